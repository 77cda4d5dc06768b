"""Design atlases: which type reaches which targets, computed exactly.

The frontier: per type and time ratio, the best minimum transmission angle any design reaches
(everything free within the default bounds; at stroke 1, as the angle does not depend on the
stroke) and that design, in stroke units. Each grid point is a synthesis (objective
``max_transmission_angle``) verified as the service verifies, recorded as ``certified`` (an
exact reduced solver's global optimum), ``local`` (IPOPT's local optimum) or ``refused``
(with the reason). From the frontier follow the selection chart (a type meets a time ratio
and a bound exactly where its best angle there is at least the bound) and, per type and
bound, the reachable time-ratio range: its ends bisected on the same syntheses, to 1e-9
relative in the time ratio.

The grid's points are cut into chunks, the tasks (a million points are not a million
tasks): run in this process, in a local process pool (the default), or, given a scheduler's
address (``--scheduler tcp://host:8786``, or ``DASK_SCHEDULER_ADDRESS``), on a Dask cluster,
whose scheduler runs again what a lost worker held. Each finished chunk is written to the
output folder at once (atomically, with the run's inputs in ``manifest.json``), so an
interrupted run resumes where it stopped: the chunks already there are read, not computed
again.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from multiprocessing import get_context
from pathlib import Path
from typing import Any

from ..mechanisms import all_types, get
from ..numerics.dense import bisect
from ..synthesis import synthesize
from ..targets import MAX_TRANSMISSION
from . import store
from .values import CHUNK, Atlas, Inputs, Point, Range

DEFAULT_RATIOS = tuple(round(1.05 + 0.05 * k, 2) for k in range(60))  # 1.05 … 4.0
DEFAULT_BOUNDS = (10.0, 20.0, 30.0, 40.0, 50.0)
BUDGET_MS = 20_000.0  # per synthesis: IPOPT's types may need it; the exact ones take ~1 ms
BISECT = 1e-9  # relative, in the time ratio: a range's ends
POOLS = 4  # local pools a run may start (one more each time a worker dies)


def point(mtype: str, time_ratio: float) -> Point:
    """The frontier at one time ratio: a synthesis, verified."""
    r = synthesize(
        time_ratio,
        1.0,
        0.0,
        [{"type": mtype}],
        objective=MAX_TRANSMISSION,
        max_candidates=1,
        time_budget_ms=BUDGET_MS,
    )
    if not r.candidates:
        why = r.infeasible[0]
        return Point(mtype, time_ratio, None, "refused", reason=f"{why.code}: {why.reason}")
    c = r.candidates[0]
    status = "certified" if c.method == "closed_form" else "local"
    return Point(mtype, time_ratio, c.min_transmission_angle_deg, status, dict(c.params))


def run_chunk(points: Sequence[tuple[str, float]]) -> list[Point]:
    """One task: its grid points, in order."""
    return [point(t, tr) for t, tr in points]


def chunks(inputs: Inputs) -> list[list[tuple[str, float]]]:
    grid = [(t, tr) for t in inputs.types for tr in inputs.ratios]
    return [grid[k : k + inputs.chunk] for k in range(0, len(grid), inputs.chunk)]


def atlas(
    types: Sequence[str] | None = None,
    ratios: Sequence[float] = DEFAULT_RATIOS,
    bounds: Sequence[float] = DEFAULT_BOUNDS,
    *,
    chunk: int = CHUNK,
    out: str | Path | None = None,
    workers: int | None = None,
    inline: bool = False,
    scheduler: str | None = None,
    progress: Callable[[int, int], Any] | None = None,
) -> Atlas:
    """The atlas over ``types`` (default: the quick-return types) × ``ratios``, with the
    time-ratio ranges at each of ``bounds``. ``out``: the folder its chunks, CSV tables and
    manifest go to, and that a run resumes from. ``inline`` runs every task in this process,
    else a local process pool of ``workers`` (default: the cores). The result does not depend
    on how it was run. ``progress(total, done)``, if given, makes an object whose ``step()`` is
    called as each further chunk finishes."""
    types = tuple(types or (t for t in all_types() if get(t).quick_return))
    for t in types:
        get(t)  # raises for an unknown type
    inputs = Inputs(types, tuple(map(float, ratios)), tuple(map(float, bounds)), chunk)
    tasks = chunks(inputs)
    folder = store.folder(out, inputs)
    found = {k: store.read(folder, k) for k in range(len(tasks))} if folder else {}
    done = {k: v for k, v in found.items() if v is not None}
    todo = [k for k in range(len(tasks)) if k not in done]
    bar = progress(len(tasks), len(done)) if progress else None
    run = _dask(tasks, todo, scheduler, inputs) if scheduler else _run(tasks, todo, inline, workers)
    for k, pts in run:
        done[k] = pts
        if folder:
            store.write(folder, k, pts)
        if bar:
            bar.step()
    frontier = [p for k in range(len(tasks)) for p in done[k]]
    result = Atlas(inputs, frontier, computed=len(todo))
    result.ranges = [reach(result, t, b) for t in types for b in inputs.bounds]
    if folder:
        store.tables(result, folder)
    return result


def _run(
    tasks: list[list[tuple[str, float]]], todo: list[int], inline: bool, workers: int | None
) -> Iterator[tuple[int, list[Point]]]:
    """(chunk index, points) as each task finishes. A pool that breaks (a worker killed) is
    replaced and the unfinished tasks run again, up to ``POOLS`` pools in all."""
    if inline or not todo:
        for k in todo:
            yield k, run_chunk(tasks[k])
        return
    left = list(todo)
    for attempt in range(POOLS):
        if not left:
            return
        with ProcessPoolExecutor(workers or os.cpu_count(), mp_context=get_context("spawn")) as ex:
            running = {ex.submit(run_chunk, tasks[k]): k for k in left}
            try:
                while running:
                    finished, _ = wait(running, return_when=FIRST_COMPLETED)
                    for f in finished:
                        k = running.pop(f)
                        pts = f.result()
                        left.remove(k)
                        yield k, pts
            except BrokenProcessPool:  # a worker died: a new pool runs what is left
                if attempt == POOLS - 1:
                    raise


def _dask(
    tasks: list[list[tuple[str, float]]], todo: list[int], scheduler: str, inputs: Inputs
) -> Iterator[tuple[int, list[Point]]]:
    """(chunk index, points) as each task finishes on a Dask cluster. A task whose worker is
    lost is run again by the scheduler, on another."""
    from dask.distributed import Client, as_completed

    with Client(scheduler) as client:
        futures = {
            client.submit(run_chunk, tasks[k], key=f"atlas-{inputs.key()}-{k}", pure=False): k
            for k in todo
        }
        for f in as_completed(futures):
            yield futures[f], f.result()


def reach(a: Atlas, mtype: str, bound: float) -> Range:
    """The time ratios at which the type meets the bound, within the grid: the first and last
    grid points that meet it, each end bisected against its neighbour outside (None: no grid
    point meets it)."""
    pts = a.best(mtype)
    ok = [i for i, (_, mu) in enumerate(pts) if mu is not None and mu >= bound]
    out: Range = {"type": mtype, "bound_deg": bound, "min": None, "max": None}
    if not ok:
        return out
    lo, hi = ok[0], ok[-1]

    def meets(tr: float) -> bool:
        best = point(mtype, tr).best_angle_deg
        return best is not None and best >= bound

    # each end between the grid point that meets the bound and its neighbour that does not
    out["min"] = pts[lo][0] if lo == 0 else bisect(meets, pts[lo][0], pts[lo - 1][0], BISECT)[0]
    last = len(pts) - 1
    out["max"] = pts[hi][0] if hi == last else bisect(meets, pts[hi][0], pts[hi + 1][0], BISECT)[0]
    return out
