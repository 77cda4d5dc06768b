"""The default answer (objective ``pareto``): each type's trade-off front between its smallest
design that meets the bound and its best-transmitting one (docs/synthesis.md, *The front*)."""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import replace
from typing import Any, cast

from .. import objectives
from ..mechanisms import get
from ..results import Candidate, FrontPoint, Infeasible
from ..targets import MAX_TRANSMISSION, MIN_SIZE
from .candidate import firsts, predicted_rank
from .diagnose import diagnose
from .search import Proposal, Searched, Spec, Targets, search

MEASURE = "link_length_sum"  # the size the front minimises
FLAT = 1e-9  # relative: a front whose ends are this close in angle and size is one point

End = Candidate | Proposal  # a front's end: verified (a candidate) or predicted (a proposal)


def pareto(
    specs: Sequence[Spec], t: Targets, max_candidates: int, per_type: int, extras: dict[str, Any]
) -> tuple[list[Candidate], list[Infeasible]]:
    """Each type's front, ``max_candidates`` points in all shared among the types (a front of
    one point takes one, none more than ``per_type``), the types in the order of their best
    angle. The fronts are planned on their ends' predictions (the reduced solvers' exact
    closed forms), and each type's points are verified together (``firsts``)."""
    best_t, small_t = replace(t, objective=MAX_TRANSMISSION), replace(t, objective=MIN_SIZE)
    ends, infeasible = [], []
    for i, spec in enumerate(specs):
        m = get(spec.type)
        top = search(m, spec, i, best_t)
        if not top.proposals:
            infeasible.append(diagnose(m, spec, best_t, top))
            continue
        # without a bound there is no smallest design (it locks at 0°)
        low = search(m, spec, i, small_t) if t.bound_deg > 0 else None
        ends.append((i, top, low))
    # each type here has proposals, so a best one
    ends.sort(key=lambda e: predicted_rank(MAX_TRANSMISSION)(cast(Proposal, head_of(e[1], best_t))))
    flat = [_flat(head_of(low, small_t), head_of(top, best_t)) for _, top, low in ends]
    fronts = []
    for (i, top, low), n in zip(ends, _share(flat, max_candidates, per_type), strict=True):
        m = get(specs[i].type)
        front = _front(specs[i], i, top, low, max(n, 1), t, extras)
        if not front:
            infeasible.append(diagnose(m, specs[i], best_t, top))
        elif n:
            fronts.append(front)
    order = objectives.get(MAX_TRANSMISSION).order([f[0] for f in fronts])
    fronts = [fronts[i] for i, _ in order]
    return [c for f in fronts for c in f], infeasible


def _front(
    spec: Spec,
    i: int,
    top: Searched,
    low: Searched | None,
    n: int,
    t: Targets,
    extras: dict[str, Any],
) -> list[Candidate]:
    """n points of one type's front, best angle first, spread evenly in angle from its
    smallest design that meets the bound (``low``'s, the min_size optimum) to its best
    (``top``'s): the point at angle μ is the smallest design whose minimum transmission angle
    is at least μ (the min_size optimum with μ as the bound), so none beats another in both.
    Without a bound the points sit at k/n of the best angle (k = 1 … n). Points found twice (a
    front that jumps) are dropped, as are points past the budget. Each point's search starts
    from the previous one's (``near``, the low end's first): a reduced solver may continue
    from its optima. The angles are planned on the ends' predictions; where the verified ends
    differ (a proposal failed its verification), they are planned again on those. Empty where
    no best design passes."""
    m = get(spec.type)
    best_t, small_t = replace(t, objective=MAX_TRANSMISSION), replace(t, objective=MIN_SIZE)
    ends = [(top, best_t)] + ([(low, small_t)] if low is not None else [])
    # the ends: predicted, then verified
    hi: End | None = head_of(top, best_t)
    lo: End | None = head_of(low, small_t)
    assert hi is not None  # ``pareto`` asks for the front of a type with a best proposal
    for _ in range(2):
        found, near = [], low
        for mu in [] if n == 1 or _flat(lo, hi) else _angles(lo, hi, n):
            if time.monotonic() >= t.deadline:
                break
            at = replace(t, objective=MIN_SIZE, bound_deg=mu)
            near = search(m, spec, i, at, near)
            found.append((near, at))
        got = firsts(m, ends + found, t, extras)
        best, small = got[0], got[1] if low is not None else None
        if best is None:
            return []
        if _same(best, hi) and _same(small, lo):
            break
        hi, lo = best, small
    assert best is not None  # the loop returned where there was none
    if n == 1 or _flat(small, best):
        which: tuple[str, ...] = (
            (MIN_SIZE, MAX_TRANSMISSION) if _flat(small, best) else (MAX_TRANSMISSION,)
        )
        return [replace(best, front=FrontPoint(MEASURE, 0, 1, which))]
    points = [best] + ([small] if small is not None else []) + [c for c in got[len(ends) :] if c]
    kept: list[Candidate] = []  # the non-dominated, best angle first (found twice: the end)
    for c in sorted(points, key=lambda c: (-c.min_transmission_angle_deg, c.size)):
        if all(c.size < k.size * (1 - FLAT) for k in kept):
            kept.append(c)
    out = []
    for k, c in enumerate(kept):
        which = ((MIN_SIZE,) if c is small else ()) + ((MAX_TRANSMISSION,) if c is best else ())
        out.append(replace(c, front=FrontPoint(MEASURE, len(kept) - 1 - k, len(kept), which)))
    return out


def _angles(lo: End | None, hi: End, n: int) -> list[float]:
    """The inner points' angles of an n-point front between its ends (``_angle_size``; no
    small end: no bound)."""
    b = _angle_size(hi)[0]
    if lo is None:
        return [b * k / n for k in range(1, n)]
    a = _angle_size(lo)[0]
    return [a + (b - a) * k / (n - 1) for k in range(1, n - 1)]


def head_of(s: Searched | None, t: Targets) -> Proposal | None:
    """A search's best proposal by its prediction (None for none)."""
    return min(s.proposals, key=predicted_rank(t.objective), default=None) if s else None


def _same(x: End | None, y: End | None) -> bool:
    """Whether two ends (``_angle_size``) are one in angle, or both missing."""
    if x is None or y is None:
        return x is y
    a, b = _angle_size(x)[0], _angle_size(y)[0]
    return abs(a - b) <= FLAT * max(abs(b), 1.0)


def _flat(low: End | None, top: End | None) -> bool:
    """Whether a front is one point: its ends (``_angle_size``) agree in angle and size."""
    if low is None or top is None:
        return False
    (a, s_low), (b, s_top) = _angle_size(low), _angle_size(top)
    return b - a <= FLAT * b and abs(s_top - s_low) <= FLAT * s_top


def _angle_size(end: End) -> tuple[float, float]:
    """A front's end, verified (a candidate) or predicted (a proposal): angle and size."""
    if isinstance(end, Candidate):
        return end.min_transmission_angle_deg, end.size
    return end.angle_deg, end.size


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
