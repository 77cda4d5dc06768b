"""Runs synth's work off the event loop, each kind on its own lane, every kind admitted.

Two lanes, each an executor and its slots: the short lane (threads in this process: what the
library says costs about what an analysis does, at most some tens of milliseconds: analyses of
up to ``SHORT_CURVE_POINTS``, exports, syntheses the exact solvers answer alone) and the
solvers' (syntheses, sweeps, long curves), on a process pool (each worker process has its own
CasADi solvers; the GIL is not shared) or a thread pool (each thread builds its own solvers:
one ``nlpsol`` is never called from two threads, that crashes), as the settings say. So short
work never waits behind a 2-second synthesis, and the event loop only parses, checks and
answers: /health answers from it at once whatever the mix. A hand-off to a thread and back
costs ~50 µs, ~0.1 ms of processor time (README, "Serving").

Either lane runs at most as much at once as it has slots (``Slots``). A request waits for one
only until its start-by time: ``queue_share`` of its budget after its arrival, at most
``max_queue_ms`` (1 s without a budget); then it is refused with ``Busy`` (HTTP 503 with
Retry-After): a budget bounds what the client waits, and work that starts runs with what is
left of it. A freed slot goes to the waiter whose start-by time comes first, so a short budget
is not starved by long ones.
"""

from __future__ import annotations

import asyncio
import heapq
import itertools
import multiprocessing
import os
import threading
import time
from collections.abc import AsyncIterator, Awaitable, Callable
from concurrent.futures import BrokenExecutor, Executor, ProcessPoolExecutor, ThreadPoolExecutor
from contextlib import asynccontextmanager, suppress
from functools import partial
from multiprocessing.context import BaseContext
from multiprocessing.process import BaseProcess
from typing import Any, cast

from synth.requests import rebudgeted
from synth.synthesis import scans, warm

from .config import Settings, get_settings
from .operations import OPERATIONS

# what a synthesis leaves of its budget for its reply (at most a tenth of it): verifying what
# it found by its deadline, encoding, an event loop busy with other requests; with it, a
# synthesis's wall time stays within its budget under load (benchmarks/overload.py)
REPLY_S = 0.1
MIN_WAIT_S = 0.01  # the least a request may wait for a slot, whatever its budget
WARM_WAIT_S = 60  # how long a lane's thread waits for the others before it warms (``_warm``)


class Busy(Exception):
    """Every slot of the request's lane stayed taken for as long as the request could wait;
    or, ``why``, something else kept it from starting in time."""

    def __init__(
        self, waited_ms: float, retry_after_s: int, why: str = "every solver is busy"
    ) -> None:
        super().__init__(f"{why} (waited {waited_ms:.0f} ms since the request arrived)")
        self.retry_after_s = retry_after_s


def _call(op: str, request: Any, then: Callable[[Any], Any] | None = None) -> Any:
    """The operation, and ``then`` of its result (its reply's encoding: off the loop too)."""
    result = OPERATIONS[op].run(request)
    return result if then is None else then(result)


def _warm(lane: str, barrier: threading.Barrier | None = None) -> int:
    """Build in this thread (a worker process's) what requests on its ``lane`` reach and would
    otherwise build at their first use, ~25 ms each (``synth.synthesis.warm``): on the
    solvers' lane the compiled analysis of every type, variant and kind and what a searched
    objective's request with nothing fixed builds (~1 s), on the short lane what its budgeted
    work (a synthesis the exact solvers answer alone) uses. ``barrier``: a lane's threads
    each take one of these calls (none starts before every thread has its own), so each
    builds its own. The process."""
    if barrier is not None:  # (a thread that does not come: each warms after WARM_WAIT_S)
        with suppress(threading.BrokenBarrierError):
            barrier.wait(WARM_WAIT_S)
    if lane == "short":
        warm.warm(("kinematics",), searches=False)
    else:
        warm.warm()  # and the thread that makes a refusal's scans, for the syntheses here
        scans.prepare(partial(warm.warm, ("kinematics",), searches=False)).result()
    return os.getpid()


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
        n = settings.short_workers  # the short lane: threads of this process, and their slots
        self.short_executor = ThreadPoolExecutor(n, thread_name_prefix="short")
        self.short_slots = Slots(n)
        self._replacing: asyncio.Lock | None = None
        self._started: asyncio.Future[int] | None = None  # a new pool's warm-up

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

    async def run(
        self,
        op: str,
        request: Any,
        arrival: float | None = None,
        then: Callable[[Any], Any] | None = None,
    ) -> Any:
        """``op`` on its ``request`` (``operations``: its value, checked), on a slot of the
        short lane where the operation says it is short or else the solvers', waited for from
        ``arrival`` (monotonic seconds; None: now) until the start-by time; ``then`` of its
        result, in the lane too. With a ``time_budget_ms`` (a synthesis, a sweep) the budget
        counts from ``arrival``: the operation gets what is left of it when it starts, and
        again if it is retried (a worker process died under it)."""
        s = self.settings
        short = OPERATIONS[op].short(request)
        arrival = time.monotonic() if arrival is None else arrival
        budget_s = (getattr(request, "time_budget_ms", None) or 0) / 1000
        wait = s.max_queue_ms / 1000
        if budget_s:  # not under MIN_WAIT_S: what reading and checking it took is no wait
            wait = max(min(wait, s.queue_share * budget_s), MIN_WAIT_S)
        deadline = arrival + budget_s if budget_s else None
        slots = self.short_slots if short else self.slots
        loop = asyncio.get_running_loop()
        async with slots.held(arrival, arrival + wait):
            executor = self.short_executor if short else self.executor
            call = partial(_call, op, _left(request, deadline), then)
            try:
                return await loop.run_in_executor(executor, call)
            except BrokenExecutor:
                if short:
                    raise
                # a worker died (killed, out of memory): one new pool for every request that
                # saw this one break, and each tried once more on it, with what is left of
                # its budget once the new pool has warmed up (a 503 if that is too little)
                await self._replace(executor, arrival, deadline)
                call = partial(_call, op, _left(request, deadline, arrival), then)
                return await loop.run_in_executor(self.executor, call)

    async def _replace(self, broken: Executor, arrival: float, deadline: float | None) -> None:
        """A new pool in place of ``broken`` (once, whoever sees it break first), awaited until
        a worker of it has warmed up (a retry on cold solvers would build them past its
        budget), at most until ``deadline``: then ``Busy``."""
        if self._replacing is None:
            self._replacing = asyncio.Lock()
        async with self._replacing:
            if self.executor is broken:
                self.executor = self._new_executor()
                broken.shutdown(wait=False, cancel_futures=True)
                loop = asyncio.get_running_loop()
                self._started = loop.run_in_executor(self.executor, _warm, "solvers")
        assert self._started is not None
        timeout = None if deadline is None else max(deadline - time.monotonic() - REPLY_S, 0.0)
        try:
            await asyncio.wait_for(asyncio.shield(self._started), timeout)
        except (TimeoutError, BrokenExecutor):
            waited = (time.monotonic() - arrival) * 1000
            raise Busy(
                waited,
                1,
                "a solver process died, and its replacement had not warmed up "
                "within the request's budget",
            ) from None

    async def warm(self) -> None:
        """Build in every thread of both lanes (every worker process of a pool) what their
        requests reach (``_warm``): the solvers' lane every kind of the analysis, the short
        lane what its budgeted work (a synthesis the exact solvers answer alone) uses. The
        lifespan awaits it, so the service listens once a budget holds from the first request
        on; an analysis's other kinds in the short lane (no budget) are built at first use."""
        loop = asyncio.get_running_loop()

        def each(executor: Executor, n: int, lane: str) -> list[Awaitable[int]]:
            barrier = threading.Barrier(n)
            return [loop.run_in_executor(executor, _warm, lane, barrier) for _ in range(n)]

        short = each(self.short_executor, self.settings.short_workers, "short")
        if self.settings.executor == "thread":
            await asyncio.gather(*short, *each(self.executor, self.workers, "solvers"))
            return
        warmed: set[int] = set()  # worker processes: calls until each has taken one
        try:
            while len(warmed) < self.workers:
                calls = [
                    loop.run_in_executor(self.executor, _warm, "solvers")
                    for _ in range(self.workers - len(warmed))
                ]
                new = set(await asyncio.gather(*calls)) - warmed
                warmed |= new
                if not new:  # an idle warm process took them: the others are still starting
                    await asyncio.sleep(0.1)
        except BrokenExecutor:  # a worker died: its replacement pool warms on first use
            pass
        await asyncio.gather(*short)

    def close(self) -> None:
        """Cancel what waits and stop the worker processes at once: the server has stopped
        waiting for its requests (uvicorn's graceful-shutdown timeout, ``api.serve``), so
        nobody waits for their solves; a solve in a thread ends with the process (uvicorn
        ends it by the signal it caught)."""
        self.executor.shutdown(wait=False, cancel_futures=True)
        self.short_executor.shutdown(wait=False, cancel_futures=True)
        for p in self._workers:  # a process pool's: ProcessPoolExecutor has no way to stop them
            p.terminate()


def _left(request: Any, deadline: float | None, retried: float | None = None) -> Any:
    """``request`` with what is left of its budget until ``deadline`` (None: no budget), less
    what the reply takes after it; ``retried`` (the arrival): a retry, refused with ``Busy``
    where less than ``REPLY_S`` is left (its own work could not end by the deadline)."""
    if deadline is None:
        return request
    rest = deadline - time.monotonic()
    rest -= min(REPLY_S, 0.1 * rest)
    if retried is not None and rest < REPLY_S:
        waited = (time.monotonic() - retried) * 1000
        raise Busy(waited, 1, "a solver process died, and the request's budget ran out")
    return rebudgeted(request, max(rest * 1000, 1e-3))


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
        now = time.monotonic()
        if now >= start_by:  # it waited that long before it came here (behind the loop)
            raise Busy((now - arrival) * 1000, max(1, round(start_by - arrival)))
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
