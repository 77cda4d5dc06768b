"""Settings: the only place that reads the environment (read once, overridable in tests)."""

from __future__ import annotations

import os
from functools import lru_cache
from typing import Literal

from pydantic_settings import BaseSettings, SettingsConfigDict


class Settings(BaseSettings):
    """``SYNTH_*`` environment variables."""

    model_config = SettingsConfigDict(env_prefix="SYNTH_")

    # where solves run: "process" (a pool of worker processes) or "thread" (a pool of threads,
    # each with its own CasADi solvers); see README "Concurrency" for the measurements
    executor: Literal["process", "thread"] = "process"
    workers: int = max(1, len(os.sched_getaffinity(0)))  # solver concurrency: the cores
    warm: bool = True  # build the common solvers in the workers at start, in the background
    max_budget_ms: float = 60_000.0  # the largest time_budget_ms a request may ask for


@lru_cache
def get_settings() -> Settings:
    return Settings()
