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
    # solves at once in this server process: its share of the cores (solver threads share
    # one interpreter, so more threads would only take turns: each solve slower, and a
    # budget that binds under load changes the answer); a process pool: every core
    workers: int = max(1, CORES // SERVER_PROCESSES)
    warm: bool = True  # build the common solvers in the workers at start, in the background
    max_budget_ms: float = 60_000.0  # the largest time_budget_ms a request may ask for
    # how long a request may wait for a solver slot before a 503: this share of what is left
    # of its budget (a synthesis), at most max_queue_ms (also for sweeps and long curves)
    queue_share: float = 0.5
    max_queue_ms: float = 1000.0


@lru_cache
def get_settings() -> Settings:
    return Settings()
