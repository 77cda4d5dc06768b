"""A refusal's reachable time-ratio range, scanned: a grid of β, then each end bisected, kept
per process as it is made (``diagnose``).

A grid is 17 reduced solves, each well under a millisecond for most parts and up to ~0.3 s
for the slowest (a crank-rocker with its rod bounded to nothing: 4.76 s for the grid, on a
300 ms budget, issue 38). So a grid is made by a thread of its own, ``scans``, for as long as
requests wait for it: a request waits until its deadline and then says its budget ran out,
and the step under way when the last waiting deadline passes is kept for the requests after
it (no other work goes on behind the requests' backs). Where that thread is on another grid,
a request makes its own steps until its deadline. Either way every step is kept as it is made,
whoever makes it, so the numbers are those of one uninterrupted scan whatever was asked
before; and a designer sweeping the time ratio past an end, or a tool checking many targets
against the same parts, pays the grid once and each end's bisection once.
"""

from __future__ import annotations

import math
import os
import queue
import threading
import time
from collections import OrderedDict
from collections.abc import Callable, Hashable
from concurrent.futures import Future
from dataclasses import dataclass, field
from typing import Protocol

from ..numerics.dense import bisect

GRID = 17  # time ratios scanned for the reachable range
TOP = math.pi * (1 - 1e-6)  # β of the largest time ratio tried, about 2e6
RANGES = 256  # grids kept per process (least recently used dropped)

Key = tuple[Hashable, ...]


class Scan(Protocol):
    """What a range depends on (``key``: not the time ratio), and whether a β has a design."""

    @property
    def key(self) -> Key: ...

    def ok(self, beta: float) -> bool: ...


class Late(Exception):
    """The deadline passed before the scan was made (what was made is kept)."""


@dataclass
class _Grid:
    """A scan's grid as far as it has been made, and its ends once it is whole."""

    flags: list[bool] = field(default_factory=list)
    ends: list[tuple[float, float]] | None = None
    whole: bool = False


@dataclass
class _Job:
    """A grid the thread makes until ``until`` (the latest deadline of the requests that wait
    for it), then ``done``."""

    scan: Scan
    until: float
    grid: _Grid  # the one its requests hold (kept though the cache drops it meanwhile)
    done: Future[None] = field(default_factory=Future)


_grids: OrderedDict[Key, _Grid] = OrderedDict()
_lock = threading.Lock()
_jobs: dict[Key, _Job] = {}  # the grids the thread is making or will make
_queue: queue.SimpleQueue[_Job] = queue.SimpleQueue()
_thread: threading.Thread | None = None
_built: Future[None] = Future()  # the thread's ``build`` (``prepare``)


def ends(scan: Scan, deadline: float) -> list[tuple[float, float]] | None:
    """The brackets (β outside, β inside) of the range's two ends on the grid of β, narrowed in
    place as queries need (``narrowed``); None if no β has a design. Raises ``Late`` if the
    deadline passes first."""
    grid = _grid(scan.key)
    if not grid.whole:
        made = _awaited(scan, grid, deadline)
        if made is None:  # the thread is on another grid
            _make(scan, grid, deadline)
        else:
            grid = made
    return grid.ends


def narrowed(
    scan: Scan, ends: list[tuple[float, float]], k: int, tol: float, deadline: float
) -> tuple[float, float]:
    """End ``k``'s bracket bisected to ``tol`` from where it is kept, each step kept in
    ``ends`` as it is made (the same midpoints whoever goes on); ``Late`` at the deadline."""
    outside, inside = ends[k]

    def ok(beta: float) -> bool:
        nonlocal inside, outside
        if time.monotonic() >= deadline:
            raise Late
        found = scan.ok(beta)
        inside, outside = (beta, outside) if found else (inside, beta)
        with _lock:
            if abs(inside - outside) < abs(ends[k][1] - ends[k][0]):
                ends[k] = (outside, inside)
        return found

    inside, outside = bisect(ok, inside, outside, tol)
    return outside, inside


def forget() -> None:
    """Drop the grids kept (a benchmark timing each refusal's whole cost)."""
    with _lock:
        _grids.clear()


def _grid(key: Key) -> _Grid:
    with _lock:
        grid = _grids.setdefault(key, _Grid())
        _grids.move_to_end(key)
        if len(_grids) > RANGES:
            _grids.popitem(last=False)
    return grid


def _awaited(scan: Scan, grid: _Grid, deadline: float) -> _Grid | None:
    """The grid the thread made (``grid``, or the one it was making for the same key), waited
    for until the deadline (then ``Late``); None if it is on another key's."""
    with _lock:
        job = _jobs.get(scan.key)
        if job is None:
            if _jobs:
                return None
            job = _jobs[scan.key] = _Job(scan, deadline, grid)
            _queue.put(job)
            _start(None)
        job.until = max(job.until, deadline)
    wait = None if math.isinf(deadline) else max(deadline - time.monotonic(), 0.0)
    try:
        job.done.result(timeout=wait)
    except TimeoutError:
        raise Late from None
    return job.grid


def prepare(build: Callable[[], object]) -> Future[None]:
    """Start the thread that makes grids, with ``build`` (what its scans use: its CasADi
    functions are its own) run in it first: done when it has. A service's warm-up waits for
    it, so that no request waits for those builds."""
    with _lock:
        return _start(build)


def _start(build: Callable[[], object] | None) -> Future[None]:
    """The thread, started with ``build`` if it has not been (the lock held); its build's."""
    global _thread, _built
    if _thread is None:
        _built = Future()
        _thread = threading.Thread(target=_scans, args=(build, _built), name="scans", daemon=True)
        _thread.start()
    return _built


def _scans(build: Callable[[], object] | None, built: Future[None]) -> None:
    """The thread that makes grids, one at a time (its CasADi functions its own), each while
    a request waits for it; ``build`` first."""
    global _thread
    try:
        if build is not None:
            build()
    finally:
        built.set_result(None)
    try:
        _serve()
    finally:  # (a thread that dies: the next request starts another)
        with _lock:
            _thread = None


def _serve() -> None:
    while True:
        job = _queue.get()
        try:
            _make(job.scan, job.grid, job)
            job.done.set_result(None)
        except Exception as e:  # the waiting request's, as if it had made the steps itself
            job.done.set_exception(e)
        finally:
            with _lock:
                if _jobs.get(job.scan.key) is job:  # (not a new one for the same grid)
                    del _jobs[job.scan.key]


def _make(scan: Scan, grid: _Grid, until: float | _Job) -> None:
    """The grid's steps from where it is, until it is whole; ``Late`` once ``until`` (a
    deadline, or a job's, which waiting requests move on) has passed."""
    betas = [TOP * k / (GRID - 1) for k in range(GRID)]
    while not grid.whole:
        with _lock:  # (a job's deadline moves under the lock: none is missed)
            if time.monotonic() >= (until.until if isinstance(until, _Job) else until):
                if isinstance(until, _Job) and _jobs.get(scan.key) is until:
                    del _jobs[scan.key]  # a request from now on starts a new one
                raise Late
        k = len(grid.flags)
        ok = scan.ok(betas[k]) if k < GRID else False
        with _lock:
            if len(grid.flags) == k < GRID:  # (another thread may have made it meanwhile)
                grid.flags.append(ok)
            if len(grid.flags) == GRID and not grid.whole:
                grid.ends, grid.whole = _brackets(grid.flags, betas), True


def _forked() -> None:
    """A child process's: no thread makes its grids yet (the parent's did not come along)."""
    global _lock, _queue, _thread
    _lock, _queue, _thread = threading.Lock(), queue.SimpleQueue(), None
    _jobs.clear()


os.register_at_fork(after_in_child=_forked)


def _brackets(flags: list[bool], betas: list[float]) -> list[tuple[float, float]] | None:
    if not any(flags):
        return None
    i = flags.index(True)
    j = len(flags) - 1 - flags[::-1].index(True)
    low = (betas[i], betas[i]) if i == 0 else (betas[i - 1], betas[i])
    high = (betas[j], betas[j]) if j == GRID - 1 else (betas[j + 1], betas[j])
    return [low, high]
