"""The default answer (objective ``pareto``): each type's trade-off front between its smallest
design that meets the bound and its best-transmitting one (docs/synthesis.md, *The front*)."""

from __future__ import annotations

import time
from dataclasses import replace
from typing import Any

from .candidate import first, rank
from .diagnose import diagnose
from .mechanisms import get
from .reduced import MAX_TRANSMISSION, MIN_SIZE
from .results import Candidate, FrontPoint
from .search import Searched, Spec, Targets, search

PARETO = "pareto"
MEASURE = "link_length_sum"  # the size the front minimises
FLAT = 1e-9  # relative: a front whose ends are this close in angle and size is one point


def pareto(specs, t: Targets, max_candidates: int, per_type: int, extras: dict[str, Any],
            ):  # fmt: skip
    """Each type's front, ``max_candidates`` points in all shared among the types (a front of
    one point takes one, none more than ``per_type``), the types in the order of their best
    angle."""
    best_t = replace(t, objective=MAX_TRANSMISSION)
    tops, infeasible = [], []
    for i, spec in enumerate(specs):
        m = get(spec.type)
        s = search(m, spec, i, best_t)
        top = first(m, s, best_t, t, extras)
        if top is None:
            infeasible.append(diagnose(m, spec, best_t, s))
        else:
            tops.append((i, top))
    tops.sort(key=lambda it: rank(MAX_TRANSMISSION)(it[1]))
    out: list[Candidate] = []
    lows: dict[int, Candidate | None] = dict.fromkeys((i for i, _ in tops), None)
    searched: dict[int, Searched | None] = dict.fromkeys(lows, None)
    if t.bound_deg > 0:  # without a bound there is no smallest design (it locks at 0°)
        small_t = replace(t, objective=MIN_SIZE)
        for i in lows:
            m = get(specs[i].type)
            searched[i] = search(m, specs[i], i, small_t)
            lows[i] = first(m, searched[i], small_t, t, extras)
    share = _share([_flat(lows[i], top) for i, top in tops], max_candidates, per_type)
    for (i, top), n in zip(tops, share, strict=True):
        if n:
            out += _front(specs[i], i, top, lows[i], n, t, extras, searched[i])
    return out, infeasible


def _front(spec: Spec, i: int, top: Candidate, low: Candidate | None, n: int, t: Targets,
           extras, near: Searched | None) -> list[Candidate]:  # fmt: skip
    """n points of one type's front, spread evenly in angle from its smallest design that
    meets the bound (``low``, the min_size optimum) to its best (``top``): the point at angle
    μ is the smallest design whose minimum transmission angle is at least μ (the min_size
    optimum with μ as the bound), so none beats another in both. Without a bound the points
    sit at k/n of the best angle (k = 1 … n). Points found twice (a front that jumps) are
    dropped, as are points past the budget. Each point's search starts from the previous
    one's (``near``, the low end's first): a reduced solver may continue from its optima."""
    m = get(spec.type)
    if n == 1 or _flat(low, top):
        ends = (MIN_SIZE, MAX_TRANSMISSION) if _flat(low, top) else (MAX_TRANSMISSION,)
        return [replace(top, front=FrontPoint(MEASURE, 0, 1, ends))]
    b = top.min_transmission_angle_deg
    if low is not None:
        a = low.min_transmission_angle_deg
        grid = [a + (b - a) * k / (n - 1) for k in range(1, n - 1)]
        points = [low]
    else:
        grid = [b * k / n for k in range(1, n)]
        points = []
    points.insert(0, top)  # first: a point found again is kept as the end it is
    found = []
    for mu in grid:
        if time.monotonic() >= t.deadline:
            break
        at = replace(t, objective=MIN_SIZE, bound_deg=mu)
        near = search(m, spec, i, at, near)
        found.append((near, at))
    points += [c for c in (first(m, s, at, t, extras) for s, at in found) if c is not None]
    kept: list[Candidate] = []  # the non-dominated, best angle first
    for c in sorted(points, key=lambda c: (-c.min_transmission_angle_deg, c.size)):
        if all(c.size < k.size * (1 - FLAT) for k in kept):
            kept.append(c)
    kept.reverse()
    out = []
    for k, c in enumerate(kept):
        ends = ((MIN_SIZE,) if c is low else ()) + ((MAX_TRANSMISSION,) if c is top else ())
        out.append(replace(c, front=FrontPoint(MEASURE, k, len(kept), ends)))
    return out[::-1]


def _flat(low: Candidate | None, top: Candidate) -> bool:
    """Whether a front is one point: its ends agree in angle and size."""
    return low is not None and (
        top.min_transmission_angle_deg - low.min_transmission_angle_deg
        <= FLAT * top.min_transmission_angle_deg
        and abs(top.size - low.size) <= FLAT * top.size
    )


def _share(flat: list[bool], total: int, cap: int) -> list[int]:
    """``total`` points among fronts in rank order: a front of one point (``flat``) takes
    one, the others share the rest evenly up to ``cap`` each, the better-ranked first; with
    fewer points than fronts, the better-ranked take one each."""
    out = [1 if k < total else 0 for k in range(len(flat))]
    grow = [k for k, f in enumerate(flat) if not f and out[k]]
    while grow and sum(out) < total:
        for k in grow[: total - sum(out)]:
            out[k] += 1
        grow = [k for k in grow if out[k] < cap]
    return out
