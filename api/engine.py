"""Runs synth's solves off the event loop, bounded to the cores (short analyses stay on it).

Two executors, chosen by settings: a process pool (each worker process has its own CasADi
solvers; the GIL is not shared) or a thread pool (each thread builds its own solvers: one
``nlpsol`` is never called from two threads, that crashes). Either way at most ``workers``
solves run at once (``Slots``). A request waits for one of those slots only until its start-by
time: ``queue_share`` of its budget after its arrival, at most ``max_queue_ms`` (1 s without a
budget); then it is refused with ``Busy`` (HTTP 503 with Retry-After): a budget bounds what
the client waits, and a solve that starts runs with what is left of it. A freed slot goes to
the waiter whose start-by time comes first, so a short budget is not starved by long ones.
"""

from __future__ import annotations

import asyncio
import heapq
import itertools
import multiprocessing
import os
import time
from collections.abc import AsyncIterator
from concurrent.futures import BrokenExecutor, Executor, ProcessPoolExecutor, ThreadPoolExecutor
from contextlib import asynccontextmanager
from functools import partial
from multiprocessing.context import BaseContext
from multiprocessing.process import BaseProcess
from typing import Any, cast

import synth

from .config import Settings, get_settings
from .operations import OPERATIONS

# what a synthesis leaves of its budget for its reply (at most a tenth of it): verifying what
# it found by its deadline, encoding, an event loop busy with other requests; with it, a
# synthesis's wall time stays within its budget under load (benchmarks/overload.py)
REPLY_S = 0.1


class Busy(Exception):
    """Every solver slot stayed taken for as long as the request could wait."""

    def __init__(self, waited_ms: float, retry_after_s: int) -> None:
        super().__init__(f"every solver is busy (waited {waited_ms:.0f} ms for one since the "
                         "request arrived)")  # fmt: skip
        self.retry_after_s = retry_after_s


def _call(op: str, kwargs: dict[str, Any]) -> Any:
    return OPERATIONS[op].run(**kwargs)


def _warm() -> None:
    """Build the solvers and kinematics a default request needs (in the worker)."""
    synth.synthesize(1.5, 1.0, 10.0, time_budget_ms=5000)
    for t in synth.mechanisms.all_types():
        m = synth.mechanisms.get(t)
        synth.analysis.model.model(m, frozenset())


class _Spawn:
    """The "spawn" start method's context, keeping each process it starts (``started``): the
    context a process pool launches its workers with (``mp_context``)."""

    def __init__(self) -> None:
        self.context = multiprocessing.get_context("spawn")
        self.started: list[BaseProcess] = []

    def __getattr__(self, name: str) -> Any:
        return getattr(self.context, name)

    def Process(self, *args: Any, **kwargs: Any) -> BaseProcess:
        process = self.context.Process(*args, **kwargs)
        self.started.append(process)
        return process


class Engine:
    def __init__(self, settings: Settings) -> None:
        self.settings = settings
        self._workers: list[BaseProcess] = []  # the process pool's, as it starts them
        self.executor = self._new_executor()
        self.slots = Slots(self.workers)
        self._replacing: asyncio.Lock | None = None

    @property
    def workers(self) -> int:
        """Solves at once: ``settings.workers``, which ``Settings`` fills in where not given."""
        workers = self.settings.workers
        assert workers is not None
        return workers

    def _new_executor(self) -> Executor:
        n = self.workers
        if self.settings.executor == "process":
            # one BLAS/OpenMP thread per worker (the pool is the parallelism): read by numpy
            # when a worker imports it, so set before the workers start
            os.environ.setdefault("OMP_NUM_THREADS", "1")
            os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
            context = _Spawn()  # no fork of a threaded server
            self._workers = context.started
            return ProcessPoolExecutor(n, mp_context=cast(BaseContext, context))
        return ThreadPoolExecutor(n, thread_name_prefix="solver")

    @classmethod
    def of(cls, app: Any) -> Engine:
        """The app's engine, made on first use (also when no lifespan ran)."""
        if not hasattr(app.state, "engine"):
            app.state.engine = cls(get_settings())
        engine: Engine = app.state.engine
        return engine

    async def run(self, op: str, inline: bool = False, arrival: float | None = None,
                  **kwargs: Any) -> Any:  # fmt: skip
        """``op`` here in the event loop's thread when ``inline`` (an analysis without long
        curves, a synthesis on the exact solvers alone: about a millisecond, less than a
        hand-off costs), else on a solver slot, waited for from ``arrival`` (monotonic
        seconds; None: now) until the start-by time. With a ``time_budget_ms`` (a synthesis, a
        sweep) the budget counts from ``arrival`` too: the operation gets what is left of it
        when it starts."""
        s = self.settings
        arrival = time.monotonic() if arrival is None else arrival
        budget_s = kwargs.get("time_budget_ms", 0) / 1000
        wait = s.max_queue_ms / 1000
        if budget_s:
            wait = min(wait, s.queue_share * budget_s)

        def left() -> None:
            if budget_s:  # less what the reply takes after it
                rest = arrival + budget_s - time.monotonic()
                kwargs["time_budget_ms"] = max((rest - min(REPLY_S, 0.1 * rest)) * 1000, 1e-3)

        if inline:
            waited = time.monotonic() - arrival
            if budget_s and waited > wait:  # behind other requests in the loop, as a slot's
                raise Busy(waited * 1000, max(1, round(wait)))  # waiter would have been
            left()
            return _call(op, kwargs)
        async with self.slots.held(arrival, arrival + wait):
            left()
            executor = self.executor
            loop = asyncio.get_running_loop()
            try:
                return await loop.run_in_executor(executor, partial(_call, op, kwargs))
            except BrokenExecutor:
                # a worker died (killed, out of memory): one new pool for every request that
                # saw this one break, and each tried once more on it
                await self._replace(executor)
                return await loop.run_in_executor(self.executor, partial(_call, op, kwargs))

    async def _replace(self, broken: Executor) -> None:
        if self._replacing is None:
            self._replacing = asyncio.Lock()
        async with self._replacing:
            if self.executor is broken:
                self.executor = self._new_executor()
                broken.shutdown(wait=False, cancel_futures=True)

    def warm(self) -> None:
        """Start the workers and build their solvers in the background; and the event loop
        thread's (where inline requests run) once the loop has answered what waits."""
        for _ in range(self.workers):
            self.executor.submit(_warm)
        asyncio.get_running_loop().call_soon(_warm)

    def close(self) -> None:
        """Cancel what waits and stop the worker processes at once: the server has stopped
        waiting for its requests (uvicorn's graceful-shutdown timeout, ``api.serve``), so
        nobody waits for their solves; a solve in a thread ends with the process (uvicorn
        ends it by the signal it caught)."""
        self.executor.shutdown(wait=False, cancel_futures=True)
        for p in self._workers:  # a process pool's: ProcessPoolExecutor has no way to stop them
            p.terminate()


class Slots:
    """The engine's solver slots. A request waits for one until its start-by time, then gets
    ``Busy``; a slot that comes free goes to the waiter whose start-by time comes first
    (earliest deadline first), not to the one that came first: a request whose budget allows
    a short wait is served ahead of longer ones that can wait longer, and under overload
    each budget class is served in about the same share (benchmarks/overload.py)."""

    def __init__(self, n: int) -> None:
        self.free = n
        self.waiting: list[tuple[float, int, asyncio.Future[None]]] = []  # a heap by start-by
        self._order = itertools.count()  # ties: first come, first served

    @asynccontextmanager
    async def held(self, arrival: float, start_by: float) -> AsyncIterator[None]:
        await self._acquire(arrival, start_by)
        try:
            yield
        finally:
            self._release()

    async def _acquire(self, arrival: float, start_by: float) -> None:
        if self.free:  # then nobody waits: a freed slot goes to a waiter first
            self.free -= 1
            return
        loop = asyncio.get_running_loop()
        slot: asyncio.Future[None] = loop.create_future()
        heapq.heappush(self.waiting, (start_by, next(self._order), slot))

        def expire() -> None:
            if not slot.done():
                waited = time.monotonic() - arrival
                slot.set_exception(Busy(waited * 1000, max(1, round(start_by - arrival))))

        timer = loop.call_later(max(start_by - time.monotonic(), 0.0), expire)
        try:
            await slot
        except asyncio.CancelledError:
            if slot.done() and not slot.cancelled() and slot.exception() is None:
                self._release()  # handed a slot as the request was cancelled: pass it on
            raise
        finally:
            timer.cancel()

    def _release(self) -> None:
        while self.waiting:
            slot = heapq.heappop(self.waiting)[2]
            if not slot.done():  # not expired: the slot passes to it
                slot.set_result(None)
                return
        self.free += 1
