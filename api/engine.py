"""Runs synth's solves off the event loop, bounded to the cores (short work stays on it).

Two executors, chosen by settings: a process pool (each worker process has its own CasADi
solvers; the GIL is not shared) or a thread pool (each thread builds its own solvers: one
``nlpsol`` is never called from two threads, numerics.md). Either way at most ``workers``
solves run at once and the rest queue.
"""

from __future__ import annotations

import asyncio
import contextlib
import multiprocessing
import os
import time
from concurrent.futures import BrokenExecutor, Executor, ProcessPoolExecutor, ThreadPoolExecutor
from functools import partial
from typing import Any

import synth
from synth.formulation import OBJECTIVES

from .config import Settings, get_settings

_OPS = {"analyze": synth.analyze, "synthesize": synth.synthesize, "sweep": synth.sweep}


def _init_worker() -> None:
    # one BLAS/OpenMP thread per worker: the pool is the parallelism
    os.environ.setdefault("OMP_NUM_THREADS", "1")
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")


def _call(op: str, kwargs: dict[str, Any]) -> Any:
    return _OPS[op](**kwargs)


def _warm() -> None:
    """Build the solvers and kinematics a default request needs (in the worker)."""
    synth.synthesize(1.5, 1.0, 10.0, time_budget_ms=5000)
    for t in synth.mechanisms.all_types():
        m = synth.mechanisms.get(t)
        synth.model.model(m, frozenset())


class Engine:
    def __init__(self, settings: Settings) -> None:
        self.settings = settings
        self.executor = self._new_executor()

    def _new_executor(self) -> Executor:
        n = self.settings.workers
        if self.settings.executor == "process":
            ctx = multiprocessing.get_context("spawn")  # no fork of a threaded server
            return ProcessPoolExecutor(n, mp_context=ctx, initializer=_init_worker)
        return ThreadPoolExecutor(n, thread_name_prefix="solver")

    @classmethod
    def of(cls, app: Any) -> Engine:
        """The app's engine, made on first use (also when no lifespan ran)."""
        if not hasattr(app.state, "engine"):
            app.state.engine = cls(get_settings())
        return app.state.engine

    async def run(self, op: str, inline: bool = False, **kwargs: Any) -> Any:
        """``op`` in the pool, or here in the event loop's thread when ``inline``: for work
        that costs less than handing it to a worker (an analysis without long curves, ~1 ms;
        the loop thread has its own compiled models, as every thread does).

        A synthesis runs here too as far as the reduced solvers take it (no IPOPT: 1–5 ms for
        most requests, up to ~15 ms for a four-bar near time ratio 1); where it needs IPOPT
        (or SLSQP: the motion objectives) the whole request goes to the pool with what is
        left of its budget."""
        if inline:
            return _call(op, kwargs)
        if op == "synthesize":
            t0 = time.monotonic()
            try:
                return _call(op, {**kwargs, "ipopt": False})
            except synth.SolverNeeded:
                spent = (time.monotonic() - t0) * 1000
                kwargs["time_budget_ms"] = max(kwargs["time_budget_ms"] - spent, 1e-3)
        loop = asyncio.get_running_loop()
        try:
            return await loop.run_in_executor(self.executor, partial(_call, op, kwargs))
        except BrokenExecutor:
            # a worker died (killed, out of memory): replace the pool, and try once more
            self.executor = self._new_executor()
            return await loop.run_in_executor(self.executor, partial(_call, op, kwargs))

    def warm(self) -> None:
        """Start the workers and build their solvers in the background; build the models a
        synthesis in the event loop's thread needs here (~0.1 s, before the first request)."""
        for _ in range(self.settings.workers):
            self.executor.submit(_warm)
        for objective in OBJECTIVES:
            with contextlib.suppress(synth.SolverNeeded):
                synth.synthesize(1.5, 1.0, 10.0, objective=objective, ipopt=False)

    def close(self) -> None:
        self.executor.shutdown(wait=True, cancel_futures=True)
