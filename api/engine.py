"""Runs synth's solves off the event loop, bounded to the cores (short analyses stay on it).

Two executors, chosen by settings: a process pool (each worker process has its own CasADi
solvers; the GIL is not shared) or a thread pool (each thread builds its own solvers: one
``nlpsol`` is never called from two threads, that crashes). Either way at most ``workers``
solves run at once. A request waits for one of those slots only as long as its budget allows
(``queue_share`` of what is left of it, at most ``max_queue_ms``); past that it is refused at
once with ``Busy`` (HTTP 503 with Retry-After) rather than queued: a budget bounds what the
client waits, and a solve that starts runs with what is left of it.
"""

from __future__ import annotations

import asyncio
import multiprocessing
import os
import time
from concurrent.futures import BrokenExecutor, Executor, ProcessPoolExecutor, ThreadPoolExecutor
from functools import partial
from typing import Any

import synth

from .config import Settings, get_settings

# what a synthesis leaves of its budget for its reply (at most a tenth of it): verifying what
# it found by its deadline, encoding, an event loop busy with other requests; with it, a
# synthesis's wall time stays within its budget under load (benchmarks/overload.py)
REPLY_S = 0.1
_OPS = {"analyze": synth.analyze, "synthesize": synth.synthesize, "sweep": synth.sweep}


class Busy(Exception):
    """Every solver slot stayed taken for as long as the request could wait."""

    def __init__(self, waited_ms: float, retry_after_s: int) -> None:
        super().__init__(f"every solver is busy (waited {waited_ms:.0f} ms for one)")
        self.retry_after_s = retry_after_s


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
        self._slots: asyncio.Semaphore | None = None  # made in the event loop, on first use
        self._replacing: asyncio.Lock | None = None

    def _new_executor(self) -> Executor:
        n = self.settings.workers
        if self.settings.executor == "process":
            # one BLAS/OpenMP thread per worker (the pool is the parallelism): read by numpy
            # when a worker imports it, so set before the workers start
            os.environ.setdefault("OMP_NUM_THREADS", "1")
            os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
            ctx = multiprocessing.get_context("spawn")  # no fork of a threaded server
            return ProcessPoolExecutor(n, mp_context=ctx)
        return ThreadPoolExecutor(n, thread_name_prefix="solver")

    @classmethod
    def of(cls, app: Any) -> Engine:
        """The app's engine, made on first use (also when no lifespan ran)."""
        if not hasattr(app.state, "engine"):
            app.state.engine = cls(get_settings())
        return app.state.engine

    async def run(self, op: str, inline: bool = False, deadline: float | None = None,
                  **kwargs: Any) -> Any:  # fmt: skip
        """``op`` here in the event loop's thread when ``inline`` (an analysis without long
        curves, ~1 ms: less than a hand-off), else on a solver slot. ``deadline`` (monotonic
        seconds) is when the client's budget ends: a synthesis or a sweep gets what is left of
        it as its ``time_budget_ms`` once it has a slot."""
        if inline:
            return _call(op, kwargs)
        async with self._slot(deadline):
            if deadline is not None:
                left = deadline - time.monotonic()  # less what the reply takes after it
                kwargs["time_budget_ms"] = max((left - min(REPLY_S, 0.1 * left)) * 1000, 1e-3)
            executor = self.executor
            loop = asyncio.get_running_loop()
            try:
                return await loop.run_in_executor(executor, partial(_call, op, kwargs))
            except BrokenExecutor:
                # a worker died (killed, out of memory): one new pool for every request that
                # saw this one break, and each tried once more on it
                await self._replace(executor)
                return await loop.run_in_executor(self.executor, partial(_call, op, kwargs))

    def _slot(self, deadline: float | None) -> _Slot:
        if self._slots is None:
            self._slots = asyncio.Semaphore(self.settings.workers)
        s = self.settings
        wait = s.max_queue_ms / 1000
        if deadline is not None:
            wait = min(wait, s.queue_share * max(deadline - time.monotonic(), 0.0))
        return _Slot(self._slots, wait)

    async def _replace(self, broken: Executor) -> None:
        if self._replacing is None:
            self._replacing = asyncio.Lock()
        async with self._replacing:
            if self.executor is broken:
                self.executor = self._new_executor()
                broken.shutdown(wait=False, cancel_futures=True)

    def warm(self) -> None:
        """Start the workers and build their solvers in the background."""
        for _ in range(self.settings.workers):
            self.executor.submit(_warm)

    def close(self) -> None:
        """Cancel what waits and stop the worker processes at once: the server has stopped
        waiting for its requests (uvicorn's graceful-shutdown timeout, ``api.serve``), so
        nobody waits for their solves; a solve in a thread ends with the process (uvicorn
        ends it by the signal it caught)."""
        executor = self.executor
        workers = list((getattr(executor, "_processes", None) or {}).values())
        executor.shutdown(wait=False, cancel_futures=True)
        for p in workers:  # a process pool's (ProcessPoolExecutor has no way to stop them)
            p.terminate()


class _Slot:
    """One of the engine's solver slots, waited for at most ``wait`` seconds (else Busy)."""

    def __init__(self, slots: asyncio.Semaphore, wait: float) -> None:
        self.slots, self.wait = slots, wait

    async def __aenter__(self) -> None:
        if not self.slots.locked():  # free: no wait (wait_for with no time never acquires)
            await self.slots.acquire()
            return
        t0 = time.monotonic()
        try:
            await asyncio.wait_for(self.slots.acquire(), timeout=max(self.wait, 0.0))
        except TimeoutError:
            waited = time.monotonic() - t0
            raise Busy(waited * 1000, max(1, round(self.wait))) from None

    async def __aexit__(self, *exc: object) -> None:
        self.slots.release()
