"""Settings: the only place the service reads the environment (read once, overridable in tests),
``api.serve``'s host, port and processes included.

The library reads its own two, for the compiled analysis, in ``synth.numerics.native``."""

from __future__ import annotations

import os
from functools import lru_cache
from typing import Literal

from pydantic import Field, model_validator
from pydantic_settings import BaseSettings, SettingsConfigDict

CORES = max(1, len(os.sched_getaffinity(0)))
DEFAULT_BUDGET_MS = 2000.0  # a request's time_budget_ms where it gives none (``default_budget_ms``)


class Settings(BaseSettings):
    """``SYNTH_*`` environment variables, and the server's own (README "Serving" has the
    measurements behind the defaults)."""

    # a variable set but empty (HOST=) is as good as unset: the default, never "every interface"
    model_config = SettingsConfigDict(env_prefix="SYNTH_", env_ignore_empty=True)

    host: str = Field("127.0.0.1", validation_alias="HOST")  # where `api.serve` listens
    port: int = Field(8000, ge=0, le=65535, validation_alias="PORT")
    # server processes: uvicorn's variable (`api.serve`: one per core unless it is set, and it
    # sets it for its processes; plain uvicorn: its --workers default)
    web_concurrency: int | None = Field(None, ge=1, validation_alias="WEB_CONCURRENCY")
    # where solves run: "thread" (solver threads in this process, each with its own CasADi
    # solvers) or "process" (a pool of worker processes). Default: threads when several server
    # processes already use the cores; a process pool when one server process must.
    executor: Literal["process", "thread"] | None = None
    # solves at once in this server process. Default: its share of the cores (solver threads
    # share one interpreter, so more threads would only take turns: each solve slower, and a
    # budget that binds under load changes the answer); a process pool: every core
    workers: int | None = Field(None, ge=1)
    # threads of this server process for short work (analyses of up to 1 000 curve points,
    # exports, syntheses the exact solvers answer alone), beside the solvers: short work never
    # waits behind a long solve, and none runs in the event loop (api.engine)
    short_workers: int = Field(1, ge=1)
    # a request must arrive whole (headers and body) this soon after the connection, or after
    # its first byte on a kept-alive one, else 408 and the connection is closed (api.connection)
    request_timeout_s: float = Field(5.0, gt=0)
    # a connection whose client takes no byte of its reply for this long is closed, the reply
    # dropped (api.connection)
    write_timeout_s: float = Field(5.0, gt=0)
    # replies written but not yet taken by their clients, per server process: one that would
    # take them past this gets a 503 with Retry-After instead (api.connection)
    max_unsent_mb: float = Field(64.0, gt=0)
    # the names a request's Host may give (comma-separated, any port; "*": any). Unset: the
    # loopback names on a connection made to a loopback address, any name on others (api.gate)
    allowed_hosts: str | None = Field(None, validation_alias="ALLOWED_HOSTS")
    # the proxies whose X-Forwarded-For and -Proto `api.serve` trusts (uvicorn's list of
    # addresses and networks, "*": any). Unset: none (uvicorn's own default trusts 127.0.0.1)
    forwarded_allow_ips: str | None = Field(None, validation_alias="FORWARDED_ALLOW_IPS")
    warm: bool = True  # build what requests reach before the service listens (api.engine)
    # a line per request on stdout (uvicorn's access log): ~40 µs of a server process's time a
    # request, a tenth of a short analysis's (docs/benchmarks.md), so off unless asked for
    access_log: bool = False
    max_budget_ms: float = 60_000.0  # the largest time_budget_ms a request may ask for
    # how long after its arrival a request may wait for a solver slot before a 503: this share
    # of its budget (a synthesis, a sweep), at most max_queue_ms (all that long curves get)
    queue_share: float = 0.5
    max_queue_ms: float = 1000.0

    @model_validator(mode="after")
    def _defaults(self) -> Settings:
        processes = self.web_concurrency or 1
        if self.executor is None:
            self.executor = "thread" if processes > 1 else "process"
        if self.workers is None:
            self.workers = max(1, CORES // processes)
        return self

    @property
    def default_budget_ms(self) -> float:
        """A synthesis's budget when its request gives none."""
        return min(DEFAULT_BUDGET_MS, self.max_budget_ms)


@lru_cache
def get_settings() -> Settings:
    return Settings()
