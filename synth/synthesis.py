"""synthesize(): time ratio, stroke and transmission bound → every good design, verified.

The designs come from ``synth.search`` (each type's reduced solver, IPOPT where it cannot
answer), predicted by the types' closed forms. They are ranked and re-analysed (``verify``)
best first until ``max_candidates`` meet the targets to 1e-9; a type with no design gets a
reason with numbers (``synth.diagnose``).
"""

from __future__ import annotations

import math
import time
from collections.abc import Collection, Mapping, Sequence
from dataclasses import dataclass, replace
from typing import Any

from .diagnose import diagnose
from .errors import InvalidParameters, SynthError
from .kinematics import check_include
from .mechanisms import Mechanism, all_types, get
from .motion_search import MOTION_OBJECTIVES, UNIFORM, fluctuation, local_optima, measure
from .reduced import MAX_TRANSMISSION, MIN_SIZE
from .results import TOL, Candidate, Family, FrontPoint, Infeasible, SynthesisResult, Tolerance
from .search import (
    Proposal,
    Searched,
    SolverNeeded,
    Spec,
    Targets,
    Variant,
    proposal,
    same,
    search,
)
from .verify import verify

__all__ = ["MAX_CANDIDATES", "OBJECTIVES", "SolverNeeded", "Spec", "synthesize"]

PARETO = "pareto"
OBJECTIVES = (PARETO, MAX_TRANSMISSION, MIN_SIZE, *MOTION_OBJECTIVES)
MAX_CANDIDATES = 50
PER_TYPE = 5  # candidates per type when max_candidates is not given (pareto: per type's front)
MEASURE = "link_length_sum"  # the size the front minimises
FLAT = 1e-9  # relative: a front whose ends are this close in angle and size is one point


def synthesize(
    time_ratio: float,
    stroke: float,
    min_transmission_angle_deg: float = 0.0,
    mechanisms: Sequence[Spec | Mapping[str, Any]] | None = None,
    objective: str = PARETO,
    max_candidates: int | None = None,
    time_budget_ms: float = 2000.0,
    *,
    include: Collection[str] = (),
    tolerance: Tolerance | None = None,
    max_working_speed_fluctuation: float | None = None,
    accelerators: bool = True,
    ipopt: bool = True,
) -> SynthesisResult:
    """Every good design for the targets, verified and ranked (POST /v1/synthesize).

    ``objective``: ``pareto`` (each type's trade-off front between its smallest design that
    meets the bound and its best-transmitting one, see ``_front``), or one criterion:
    ``max_transmission_angle`` (ties to the smaller design) or ``min_size`` (the smallest sum
    of link lengths meeting the bound); or one of how the slider moves (``motion_search``):
    ``uniform_cutting_speed`` (the least speed fluctuation over the middle 80% of the working
    stroke, where a tool cuts) or ``min_peak_acceleration`` (the least peak acceleration over
    both strokes, in ω²·stroke). ``max_working_speed_fluctuation`` (≥ 1) limits that
    fluctuation (with the motion objectives). ``max_candidates`` counts in all; by default it is
    ``PER_TYPE`` (pareto: per type of the request, at most ``MAX_CANDIDATES``).
    ``accelerators=False`` solves every type as one without a reduced solver would be, by
    cold multistart IPOPT on the formulation: the generic path, for cross-checks.
    ``ipopt=False`` answers only what the reduced solvers answer exactly (in milliseconds)
    and raises ``SolverNeeded`` for the rest.
    ``include`` and ``tolerance`` add to each candidate what they add to an analysis
    (``synth.analyze``): motion quality, sensitivities, the envelope.

    >>> r = synthesize(2.0, 450.0, mechanisms=[{"type": "crank_shaper",
    ...                "fixed": {"pivot_distance": 240.0, "ram_link": 0.0}}])
    >>> [round(r.candidates[0].params[k], 9) for k in ("crank", "lever")]
    [120.0, 450.0]
    """
    t0 = time.monotonic()
    if mechanisms is None:
        specs = [Spec(t) for t in all_types() if get(t).quick_return]
    else:
        specs = [_spec(s, i) for i, s in enumerate(mechanisms)]
    per_type = max_candidates or PER_TYPE  # the most one type's front takes
    if max_candidates is None:
        max_candidates = min(PER_TYPE * (len(specs) if objective == PARETO else 1), MAX_CANDIDATES)
    _check_targets(time_ratio, stroke, min_transmission_angle_deg, objective, max_candidates)
    _check_limit(max_working_speed_fluctuation, objective)
    check_include(include)
    if not (time_budget_ms > 0 and math.isfinite(time_budget_ms)):
        raise InvalidParameters(
            f"time_budget_ms must be > 0, got {time_budget_ms}", ("time_budget_ms",)
        )
    deadline = t0 + time_budget_ms / 1000
    targets = Targets(time_ratio, stroke, min_transmission_angle_deg, objective, deadline, ipopt)
    extras = {"include": include, "tolerance": tolerance}
    if objective == PARETO:
        cands, infeasible = _pareto(specs, targets, max_candidates, per_type, extras, accelerators)
    elif objective in MOTION_OBJECTIVES:
        extras["include"] = sorted({*include, "motion"})  # what the objective measures
        cands, infeasible = _motion(
            specs, targets, max_candidates, extras, accelerators, max_working_speed_fluctuation
        )
    else:
        cands, infeasible = _single(specs, targets, max_candidates, extras, accelerators)
    return SynthesisResult(
        candidates=tuple(cands),
        infeasible=tuple(infeasible),
        complete=time.monotonic() < targets.deadline,
        elapsed_ms=(time.monotonic() - t0) * 1000,
    )


def _single(specs, t: Targets, max_candidates: int, extras: dict[str, Any], accelerators: bool):
    """One criterion: the best ``max_candidates`` designs of all types, ranked."""
    searched = [search(get(spec.type), spec, i, t, accelerators) for i, spec in enumerate(specs)]
    found, left = _verified(searched, t, max_candidates, extras)
    infeasible = [
        diagnose(get(spec.type), spec, t, s)
        for i, (spec, s) in enumerate(zip(specs, searched, strict=True))
        if not any(c.spec == i for c in found) and not left[i]
    ]
    return sorted((c.candidate for c in found), key=_rank(t.objective))[:max_candidates], infeasible


def _motion(specs, t: Targets, max_candidates: int, extras: dict[str, Any], accelerators: bool,
            limit: float | None):  # fmt: skip
    """A motion objective: per type and variant, SLSQP (``motion_search``) from the designs the
    exact solvers give for the request (best-transmitting and smallest), the most promising
    first; the optima and those designs, verified, ranked by the measure (the limit met)."""
    if not t.ipopt:  # a numerical solver, as IPOPT is: not for a caller that must not block
        raise SolverNeeded(t.objective)
    found: list[Candidate] = []
    infeasible = []
    for i, spec in enumerate(specs):
        m = get(spec.type)
        best_t = replace(t, objective=MAX_TRANSMISSION)
        s = search(m, spec, i, best_t, accelerators)
        pool = list(s.proposals)
        if t.bound_deg > 0:
            pool += search(m, spec, i, replace(t, objective=MIN_SIZE), accelerators).proposals
        mine = []
        for p in pool:
            c = _candidate(m, p, t, s.variants, extras)
            if c is not None:
                mine.append(c)
        for v in s.variants:
            starts = [
                {k: x / t.stroke for k, x in c.params.items()}
                for c in sorted(mine, key=lambda c: c.objective_value)
                if m.variant(c.params) == v.parts
            ]
            if not starts or not v.free:
                continue
            cos_bound = math.cos(math.radians(t.bound_deg))
            optima = local_optima(m, v.parts, v.free, dict(v.problem.fixed), v.problem.bounds,
                                  v.problem.explicit, (t.time_ratio, cos_bound), t.objective,
                                  starts, limit, t.deadline)  # fmt: skip
            for d in optima:
                p = proposal(m, i, {k: x * t.stroke for k, x in d.items()}, "slsqp", t)
                c = None if p is None else _candidate(m, p, t, s.variants, extras)
                if c is not None:
                    mine.append(_smallest_member(m, i, c, t, s.variants, extras))
        kept = [c for c in mine if limit is None or fluctuation(c.motion) <= limit * (1 + TOL)]
        if not kept and not mine:
            infeasible.append(diagnose(m, spec, best_t, s))
        elif not kept:
            least = min(fluctuation(c.motion) for c in mine)
            if t.objective != UNIFORM:  # how uniform it can be: that objective's optimum
                alone = _motion([spec], replace(t, objective=UNIFORM), 1, extras, accelerators,
                                None)[0]  # fmt: skip
                least = min([least] + [c.objective_value for c in alone])
            infeasible.append(Infeasible(
                m.type, "FLUCTUATION_UNREACHABLE",
                f"{m.type}'s speed fluctuation over the middle 80% of the working stroke is at "
                f"least {least:.6g} (the least the search finds) at time ratio "
                f"{t.time_ratio:g}, stroke {t.stroke:g} and bound {t.bound_deg:g}°, above the "
                f"limit {limit:g}",
            ))  # fmt: skip
        found += _distinct(kept, t.stroke)
    found.sort(key=lambda c: (round(c.objective_value, 12), c.size, c.type))
    return found[:max_candidates], infeasible


def _smallest_member(m: Mechanism, i: int, c: Candidate, t: Targets, variants, extras):
    """The smallest member of a candidate's family (the same motion and angles), verified."""
    f = c.family
    if f is None:
        return c
    (free,) = f.free
    lo = f.range[free][0]
    if lo >= c.params[free]:
        return c
    params = {**c.params, free: lo, **{k: r * lo for k, (_, r) in f.tied.items()}}
    p = proposal(m, i, params, c.method, t)
    smaller = None if p is None else _candidate(m, p, t, variants, extras)
    return smaller or c


def _distinct(cands: list[Candidate], stroke: float) -> list[Candidate]:
    """One candidate per design (the first of those within ``SAME`` × stroke of each other)."""
    out: list[Candidate] = []
    for c in sorted(cands, key=lambda c: c.objective_value):
        if not any(same(c.params, o.params, stroke) for o in out):
            out.append(c)
    return out


def _pareto(specs, t: Targets, max_candidates: int, per_type: int, extras: dict[str, Any],
            accelerators: bool):  # fmt: skip
    """Each type's front, ``max_candidates`` points in all shared among the types (a front of
    one point takes one, none more than ``per_type``), the types in the order of their best
    angle."""
    best_t = replace(t, objective=MAX_TRANSMISSION)
    tops, infeasible = [], []
    for i, spec in enumerate(specs):
        m = get(spec.type)
        s = search(m, spec, i, best_t, accelerators)
        top = _first(m, s, best_t, t, extras)
        if top is None:
            infeasible.append(diagnose(m, spec, best_t, s))
        else:
            tops.append((i, top))
    tops.sort(key=lambda it: _rank(MAX_TRANSMISSION)(it[1]))
    out: list[Candidate] = []
    lows: dict[int, Candidate | None] = dict.fromkeys((i for i, _ in tops), None)
    if t.bound_deg > 0:  # without a bound there is no smallest design (it locks at 0°)
        small_t = replace(t, objective=MIN_SIZE)
        for i in lows:
            m = get(specs[i].type)
            lows[i] = _first(m, search(m, specs[i], i, small_t, accelerators), small_t, t, extras)
    share = _share([_flat(lows[i], top) for i, top in tops], max_candidates, per_type)
    for (i, top), n in zip(tops, share, strict=True):
        if n:
            out += _front(specs[i], i, top, lows[i], n, t, extras, accelerators)
    return out, infeasible


def _front(spec: Spec, i: int, top: Candidate, low: Candidate | None, n: int, t: Targets,
           extras, accelerators: bool) -> list[Candidate]:  # fmt: skip
    """n points of one type's front, spread evenly in angle from its smallest design that
    meets the bound (``low``, the min_size optimum) to its best (``top``): the point at angle
    μ is the smallest design whose minimum transmission angle is at least μ (the min_size
    optimum with μ as the bound), so none beats another in both. Without a bound the points
    sit at k/n of the best angle (k = 1 … n). Points found twice (a front that jumps) are
    dropped, as are points past the budget."""
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
    for mu in grid:
        if time.monotonic() >= t.deadline:
            break
        at = replace(t, objective=MIN_SIZE, bound_deg=mu)
        c = _first(m, search(m, spec, i, at, accelerators), at, t, extras)
        if c is not None:
            points.append(c)
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


def _first(m: Mechanism, s: Searched, t: Targets, asked: Targets, extras) -> Candidate | None:
    """The best proposal of a search (by ``t``'s objective) that passes verification against
    the request (``asked``)."""
    variants = s.variants
    for p in sorted(s.proposals, key=_predicted_rank(t.objective)):
        c = _candidate(m, p, asked, variants, extras)
        if c is not None:
            return c
    return None


@dataclass(frozen=True)
class _Found:
    spec: int
    candidate: Candidate


def _verified(
    searched: list[Searched], t: Targets, max_candidates: int, extras: dict[str, Any]
) -> tuple[list[_Found], list[bool]]:
    """Verify the proposals best first (predicted) until ``max_candidates`` pass: a design
    that cannot be among the answer is never analysed. Also, per spec, whether proposals were
    left unverified (its type has designs, just not among the best). What the search found is
    verified even past the budget (an analysis each, under a millisecond): a slow type must
    not cost the others their answers."""
    pool = sorted((p for s in searched for p in s.proposals), key=_predicted_rank(t.objective))
    found: list[_Found] = []
    left = [False] * len(searched)
    for k, p in enumerate(pool):
        if len(found) >= max_candidates:
            for q in pool[k:]:
                left[q.spec] = True
            break
        c = _candidate(get(p.type), p, t, searched[p.spec].variants, extras)
        if c is not None:
            found.append(_Found(p.spec, c))
    return found, left


def _predicted_rank(objective: str):
    if objective == MIN_SIZE:
        return lambda p: (p.size, -p.angle_deg, p.type)
    return lambda p: (-round(p.angle_deg, 9), p.size, p.type)


def _rank(objective: str):
    if objective == MIN_SIZE:
        return lambda c: (c.size, -c.min_transmission_angle_deg, c.type)
    # ties (e.g. slot drives, 90° for every design) go to the smaller mechanism
    return lambda c: (-round(c.min_transmission_angle_deg, 9), c.size, c.type)


def _candidate(
    m: Mechanism, p: Proposal, t: Targets, variants: list[Variant], extras: dict[str, Any]
) -> Candidate | None:
    try:
        params = m.complete(p.params)
    except SynthError:
        return None
    checked = verify(m.type, params, t.time_ratio, t.stroke, t.bound_deg, **extras)
    if checked is None:
        return None
    a, residuals = checked
    size = m.size(params)
    mu = a.transmission.min_deg
    limits = {}
    for v in variants:
        if v.parts == m.variant(params):
            limits = {k: tuple(x * t.stroke for x in v.problem.bounds[k]) for k in v.free}
    return Candidate(
        type=m.type,
        params=params,
        time_ratio=a.time_ratio,
        stroke=a.stroke,
        min_transmission_angle_deg=mu,
        objective_value=(
            measure(a.motion, t.objective)
            if t.objective in MOTION_OBJECTIVES
            else mu
            if t.objective == MAX_TRANSMISSION
            else size
        ),
        method=p.method,
        residuals=residuals,
        verified=True,
        grashof=a.grashof,
        size=size,
        conditioning=a.conditioning,
        active=_active(params, mu, t, limits),
        motion=a.motion,
        sensitivities=a.sensitivities,
        envelope=a.envelope,
        family=_family(m, params, limits),
    )


def _family(m: Mechanism, params: dict[str, float], limits: dict) -> Family | None:
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


def _active(params: dict[str, float], mu: float, t: Targets, bounds: dict) -> tuple[str, ...]:
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


def _check_targets(tr, stroke, bound, objective, max_candidates) -> None:
    checks = [
        ("time_ratio", tr, math.isfinite(tr) and tr >= 1, "a finite number ≥ 1"),
        ("stroke", stroke, math.isfinite(stroke) and stroke > 0, "a finite length > 0"),
        (
            "min_transmission_angle_deg",
            bound,
            math.isfinite(bound) and 0 <= bound < 90,
            "an angle in [0°, 90°)",
        ),
        ("objective", objective, objective in OBJECTIVES, "one of " + ", ".join(OBJECTIVES)),
        (
            "max_candidates",
            max_candidates,
            isinstance(max_candidates, int) and 1 <= max_candidates <= MAX_CANDIDATES,
            f"an integer from 1 to {MAX_CANDIDATES}",
        ),
    ]
    for name, value, ok, what in checks:
        if not ok:
            raise InvalidParameters(f"{name} must be {what}, got {value!r}", (name,))
    if objective == MIN_SIZE and bound == 0:
        raise InvalidParameters(
            "min_transmission_angle_deg must be > 0 with the objective min_size: without a "
            "bound the smallest designs are linkages that lock (a 0° transmission angle)",
            ("min_transmission_angle_deg",),
        )


def _check_limit(limit: float | None, objective: str) -> None:
    if limit is None:
        return
    if not (math.isfinite(limit) and limit >= 1):
        raise InvalidParameters(
            f"max_working_speed_fluctuation must be a finite number ≥ 1 (the largest speed "
            f"against the mean: 1 is a uniform speed), got {limit!r}",
            ("max_working_speed_fluctuation",),
        )
    if objective not in MOTION_OBJECTIVES:
        raise InvalidParameters(
            f"max_working_speed_fluctuation is taken with the objectives "
            f"{' and '.join(MOTION_OBJECTIVES)}, not {objective}",
            ("max_working_speed_fluctuation",),
        )


def _spec(s: Spec | Mapping[str, Any], i: int) -> Spec:
    if not isinstance(s, Spec):
        s = Spec(s["type"], dict(s.get("fixed") or {}), dict(s.get("bounds") or {}))
    m = get(s.type)
    both = set(s.fixed) & set(s.bounds)
    if both:
        raise InvalidParameters(
            f"{s.type}: {', '.join(sorted(both))} both fixed and bounded; give one",
            ("mechanisms", str(i), "bounds", sorted(both)[0]),
        )
    for k, v in s.fixed.items():
        try:
            m.value(k, v)
        except InvalidParameters as e:
            raise InvalidParameters(e.msg, ("mechanisms", str(i), "fixed", k)) from None
    for k, (lo, hi) in s.bounds.items():
        q = m.parameter(k)
        if not (math.isfinite(lo) and math.isfinite(hi) and lo <= hi and (q.signed or lo >= 0)):
            raise InvalidParameters(
                f"{s.type}.{k} bounds [{lo!r}, {hi!r}]: need finite lower ≤ upper"
                + ("" if q.signed else ", lower ≥ 0"),
                ("mechanisms", str(i), "bounds", k),
            )
    return Spec(s.type, dict(s.fixed), {k: (float(a), float(b)) for k, (a, b) in s.bounds.items()})
