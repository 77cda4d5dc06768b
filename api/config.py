"""Settings: the only place the service reads the environment (read once, overridable in tests).

The library reads its own two, for the compiled analysis, in ``synth.native``."""

from __future__ import annotations

import os
from functools import lru_cache
from typing import Literal

from pydantic_settings import BaseSettings, SettingsConfigDict

CORES = max(1, len(os.sched_getaffinity(0)))
# server processes on this machine: uvicorn's variable, which `python -m api.serve` sets
SERVER_PROCESSES = int(os.environ.get("WEB_CONCURRENCY", 1))


class Settings(BaseSettings):
    """``SYNTH_*`` environment variables (README "Serving" has the measurements behind the
    defaults)."""

    model_config = SettingsConfigDict(env_prefix="SYNTH_")

    # where solves run: "thread" (solver threads in this process, each with its own CasADi
    # solvers) or "process" (a pool of worker processes). Threads when several server
    # processes already use the cores; a process pool when one server process must.
    executor: Literal["process", "thread"] = "thread" if SERVER_PROCESSES > 1 else "process"
    # solves at once in this server process: every core, also with several server processes,
    # since keep-alive connections need not spread evenly over them (63 against 42 req/s)
    workers: int = CORES
    warm: bool = True  # build the common solvers in the workers at start, in the background
    max_budget_ms: float = 60_000.0  # the largest time_budget_ms a request may ask for


@lru_cache
def get_settings() -> Settings:
    return Settings()
