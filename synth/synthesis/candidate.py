"""A proposal made a candidate: verified by the forward analysis, with what the answer says
about it (its objective value, the constraints and bounds it rests on, its family, and that
family's smallest member), and the order in which an objective ranks the exact solvers'
proposals."""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import replace
from typing import Any

from .. import objectives
from ..analysis.verify import verify, verify_many
from ..mechanisms import Mechanism
from ..results import Analysis, Candidate, Family
from .search import Proposal, Searched, Targets, Variant, proposal, same

ONE = 1e-12  # two designs this close (stroke units, each parameter) are one
ONE_OPTIMUM = 1e-3  # two runs' ends this close (stroke units), their values tied: one optimum


def candidate(
    m: Mechanism,
    p: Proposal,
    t: Targets,
    variants: list[Variant],
    extras: dict[str, Any],
    known: Sequence[Candidate] = (),
) -> Candidate | None:
    """The proposal as a candidate if the forward analysis finds that it meets the targets;
    ``extras`` (include, tolerance) are added to its analysis. A candidate of ``known`` that
    is its design (within ``ONE`` × stroke) stands for it, not verified again."""
    for c in known:
        if same(p.params, c.params, t.stroke, ONE):
            return c
    checked = verify(m.type, p.params, t.time_ratio, t.stroke, t.bound_deg, **extras)
    return None if checked is None else made(m, p, checked, t, variants)


def made(
    m: Mechanism,
    p: Proposal,
    checked: tuple[Analysis, dict[str, float]],
    t: Targets,
    variants: list[Variant],
) -> Candidate:
    """The candidate of a proposal that passed verification (``checked``: its analysis and
    residuals)."""
    a, residuals = checked
    params = a.params  # completed and checked by the analysis
    size = m.size(params)
    mu = a.transmission.min_deg
    limits: dict[str, tuple[float, ...]] = {}
    for v in variants:
        if v.parts == m.variant(params):
            limits = {k: tuple(x * t.stroke for x in v.problem.bounds[k]) for k in v.free}
    c = Candidate(
        type=m.type,
        params=params,
        time_ratio=a.time_ratio,
        stroke=a.stroke,
        min_transmission_angle_deg=mu,
        objective_value=math.nan,  # the objective's measure of it, below
        method=p.method,
        residuals=residuals,
        verified=True,
        grashof=a.grashof,
        size=size,
        conditioning=a.conditioning,
        active=active(params, mu, t, limits),
        motion=a.motion,
        sensitivities=a.sensitivities,
        envelope=a.envelope,
        family=family(m, params, limits),
        loads=a.loads,
    )
    return replace(c, objective_value=objectives.get(t.objective).value(c))


def family(
    m: Mechanism, params: dict[str, float], limits: dict[str, tuple[float, ...]]
) -> Family | None:
    """The type's free scale (``Mechanism.scale``) where the request leaves every length of
    it free: its range within the bounds (and validity), the others tied to it."""
    sc = m.scale
    if sc is None or any(k not in limits for k in (sc.free, *sc.tied)):
        return None
    x = params[sc.free]
    ratio = {k: params[k] / x for k in sc.tied}
    lo = max([limits[sc.free][0]] + [limits[k][0] / r for k, r in ratio.items()])
    hi = min([limits[sc.free][1]] + [limits[k][1] / r for k, r in ratio.items()])
    if sc.reach is not None:
        hi = min(hi, sc.reach(params))
    ties = ", ".join(f"{k} = {r:.12g} × {sc.free}" for k, r in ratio.items())
    return Family(
        free=(sc.free,),
        range={sc.free: (min(lo, x), max(hi, x))},
        tied={k: (sc.free, r) for k, r in ratio.items()},
        relation=f"{ties}; the other lengths as given ({sc.why})",
    )


def active(
    params: dict[str, float], mu: float, t: Targets, bounds: dict[str, tuple[float, ...]]
) -> tuple[str, ...]:
    """The constraints at their limit (within 1e-6, relative): the bound, the variables' bounds."""
    out = []
    if t.bound_deg > 0 and mu - t.bound_deg <= 1e-6 * max(t.bound_deg, 1.0):
        out.append("min_transmission_angle")
    for name, (lo, hi) in bounds.items():
        v = params[name]
        if abs(v - lo) <= 1e-6 * max(abs(lo), t.stroke):
            out.append(f"{name} ≥ {lo:g}")
        elif abs(v - hi) <= 1e-6 * max(abs(hi), t.stroke):
            out.append(f"{name} ≤ {hi:g}")
    return tuple(out)


def first(
    m: Mechanism, s: Searched, t: Targets, asked: Targets, extras: dict[str, Any]
) -> Candidate | None:
    """The best proposal of a search (by ``t``'s objective) that passes verification against
    the request (``asked``)."""
    variants = s.variants
    for p in sorted(s.proposals, key=predicted_rank(t.objective)):
        c = candidate(m, p, asked, variants, extras)
        if c is not None:
            return c
    return None


def firsts(
    m: Mechanism, found: list[tuple[Searched, Targets]], asked: Targets, extras: dict[str, Any]
) -> list[Candidate | None]:
    """``first`` of each search (with the targets it ranks by), the best proposals of all of
    them verified together (``verify_many``); where one fails, its search's next proposals
    are verified one by one."""
    ranked = [sorted(s.proposals, key=predicted_rank(t.objective)) for s, t in found]
    heads = [r[0].params for r in ranked if r]
    checked = iter(
        verify_many(m.type, heads, asked.time_ratio, asked.stroke, asked.bound_deg, **extras)
    )
    out: list[Candidate | None] = []
    for (s, _), r in zip(found, ranked, strict=True):
        c = None
        if r:
            head = next(checked)
            c = made(m, r[0], head, asked, s.variants) if head is not None else None
        for p in r[1:] if c is None else ():
            c = candidate(m, p, asked, s.variants, extras)
            if c is not None:
                break
        out.append(c)
    return out


def predicted_rank(objective: str) -> Callable[[Proposal], tuple[float, float, str]]:
    """How the objective ranks the exact solvers' designs before they are verified."""
    if objectives.get(objective).proposals == "size":
        return lambda p: (p.size, -p.angle_deg, p.type)
    return lambda p: (-round(p.angle_deg, 9), p.size, p.type)


def distinct(cands: list[Candidate], stroke: float, tie: float) -> list[Candidate]:
    """One candidate per design, the better of two that are one: within ``SAME`` × stroke, or
    within ``ONE_OPTIMUM`` × stroke with values within ``tie`` (one optimum two runs ended
    short of, not two designs the objective cannot tell apart)."""
    out: list[Candidate] = []
    for c in sorted(cands, key=lambda c: c.objective_value):
        if not any(same(c.params, o.params, stroke) or _one(c, o, stroke, tie) for o in out):
            out.append(c)
    return out


def _one(a: Candidate, b: Candidate, stroke: float, tie: float) -> bool:
    x, y = a.objective_value, b.objective_value
    return abs(x - y) <= tie * max(x, y) and same(a.params, b.params, stroke, ONE_OPTIMUM)


def smallest_member(
    m: Mechanism,
    i: int,
    c: Candidate,
    t: Targets,
    variants: list[Variant],
    extras: dict[str, Any],
) -> Candidate:
    """The smallest member of a candidate's family (the same motion and angles), verified."""
    f = c.family
    if f is None or time.monotonic() >= t.deadline:  # past it: one analysis (~15 ms) saved
        return c
    (free,) = f.free
    lo = f.range[free][0]
    if lo >= c.params[free]:
        return c
    params = {**c.params, free: lo, **{k: r * lo for k, (_, r) in f.tied.items()}}
    p = proposal(m, i, params, c.method, t)
    smaller = None if p is None else candidate(m, p, t, variants, extras)
    return smaller or c
