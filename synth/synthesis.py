"""synthesize(): time ratio, stroke and transmission bound → every good design, verified.

Per type and variant (a slot drive or a link where a part may be zero):

1. the fixed parts alone are checked against the validity conditions;
2. the fast path: where the targets determine the free parameters up to a finite set (the
   type's ``inverse``: closed forms and their roots), every member is taken; parameters left
   free after it go to IPOPT with the determined ones fixed;
3. otherwise IPOPT from deterministic multistart over the bounds;
4. every design is re-analysed (``verify``) and kept only if it meets the targets to 1e-9;
5. a type with no design gets a reason with numbers, found by optimisation: the best
   transmission angle at these targets, or the time-ratio range under the bound.
"""

from __future__ import annotations

import math
import time
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .errors import InvalidParameters, SynthError
from .formulation import OBJECTIVES, relevant
from .kinematics import analyze
from .mechanisms import Mechanism, all_types, get
from .mechanisms._registry import Unreachable
from .results import Candidate, Infeasible, SynthesisResult
from .solve import built, multistart, starts
from .verify import verify

STARTS = 8  # multistart size for a whole family
STARTS_LEFTOVER = 4  # for what a closed form leaves free, and for diagnosing a refusal
MAX_CANDIDATES = 50
SAME = 1e-4  # two designs within this (× stroke) in every parameter are one local optimum


@dataclass(frozen=True)
class Spec:
    """One type to search: parameters kept (``fixed``) and limits on the free ones."""

    type: str
    fixed: Mapping[str, float] = field(default_factory=dict)
    bounds: Mapping[str, tuple[float, float]] = field(default_factory=dict)


@dataclass(frozen=True)
class Targets:
    time_ratio: float
    stroke: float
    bound_deg: float
    objective: str
    deadline: float

    @property
    def cos_bound(self) -> float:
        return math.cos(math.radians(self.bound_deg))


def synthesize(
    time_ratio: float,
    stroke: float,
    min_transmission_angle_deg: float = 0.0,
    mechanisms: Sequence[Spec | Mapping[str, Any]] | None = None,
    objective: str = "max_transmission_angle",
    max_candidates: int = 5,
    time_budget_ms: float = 2000.0,
) -> SynthesisResult:
    """Every good design for the targets, verified and ranked (POST /v1/synthesize).

    >>> r = synthesize(2.0, 450.0, mechanisms=[{"type": "crank_shaper",
    ...                "fixed": {"pivot_distance": 240.0, "ram_link": 0.0}}])
    >>> [round(r.candidates[0].params[k], 9) for k in ("crank", "lever")]
    [120.0, 450.0]
    """
    t0 = time.monotonic()
    _check_targets(time_ratio, stroke, min_transmission_angle_deg, objective, max_candidates)
    if not (time_budget_ms > 0 and math.isfinite(time_budget_ms)):
        raise InvalidParameters(
            f"time_budget_ms must be > 0, got {time_budget_ms}", ("time_budget_ms",)
        )
    if mechanisms is None:
        specs = [Spec(t) for t in all_types() if get(t).quick_return]
    else:
        specs = [_spec(s, i) for i, s in enumerate(mechanisms)]
    targets = Targets(
        time_ratio, stroke, min_transmission_angle_deg, objective, t0 + time_budget_ms / 1000
    )
    found: list[Candidate] = []
    infeasible: list[Infeasible] = []
    for spec in specs:
        cands, why = _one_type(get(spec.type), spec, targets)
        found += cands
        if not cands and why is not None:
            infeasible.append(why)
    complete = time.monotonic() < targets.deadline
    found.sort(key=_rank(objective))
    return SynthesisResult(
        candidates=tuple(found[:max_candidates]),
        infeasible=tuple(infeasible),
        complete=complete,
        elapsed_ms=(time.monotonic() - t0) * 1000,
    )


def _rank(objective: str):
    if objective == "min_size":
        return lambda c: (c.size, -c.min_transmission_angle_deg, c.type)
    # ties (e.g. slot drives, 90° for every design) go to the smaller mechanism
    return lambda c: (-round(c.min_transmission_angle_deg, 9), c.size, c.type)


def _one_type(m: Mechanism, spec: Spec, t: Targets) -> tuple[list[Candidate], Infeasible | None]:
    found: list[Candidate] = []
    seen: list[dict[str, float]] = []  # every design verified (or refused) once
    reasons: list[Infeasible] = []
    open_variants = []
    for variant in _variants(m, spec):
        names = relevant(m, variant)
        fixed = {k: v for k, v in spec.fixed.items() if k in names}
        violation = _fixed_violation(m, variant, spec.fixed)
        if violation:
            reasons.append(Infeasible(m.type, "FIXED_PARTS_INVALID", violation))
            continue
        try:
            sets = m.inverse(fixed, t.time_ratio, t.stroke) if m.inverse else None
        except Unreachable as u:
            reasons.append(Infeasible(m.type, u.code, u.reason))
            continue
        open_variants.append((variant, names, fixed))
        tasks = [({}, "ipopt")] if sets is None else [(s, "closed_form") for s in sets]
        for determined, method in tasks:
            if not _within(determined, spec.bounds):
                continue
            left = tuple(k for k in names if k not in fixed and k not in determined)
            designs: Iterable[dict[str, float]] = [{}]
            if left:
                method = "ipopt" if method == "ipopt" else "closed_form+ipopt"
                n = STARTS if sets is None else STARTS_LEFTOVER
                designs = _ipopt(m, variant, left, {**fixed, **determined}, spec, t, n, t.objective)
            limits = {k: _bounds(m, k, spec, t.stroke) for k in left}
            limits.update({k: b for k, b in spec.bounds.items() if k in determined})
            for x in designs:
                params = {**spec.fixed, **determined, **x, **{k: 0.0 for k in variant}}
                if any(_same(params, o, t.stroke) for o in seen):
                    continue  # a local optimum found again from another start
                seen.append(params)
                c = _candidate(m, params, method, t, limits)
                if c is not None:
                    found.append(c)
    if found:
        return found, None
    if open_variants and time.monotonic() < t.deadline:
        return [], _diagnose(m, spec, t, open_variants)
    if reasons:
        return [], reasons[0]
    return [], Infeasible(m.type, "BUDGET_EXHAUSTED", _budget_reason(m, t))


def _budget_reason(m: Mechanism, t: Targets) -> str:
    return (
        f"the time budget ran out before a {m.type} design or a proof that none exists was "
        f"found; ask again with a larger time_budget_ms"
    )


def _ipopt(
    m: Mechanism,
    variant: frozenset[str],
    free: tuple[str, ...],
    fixed: dict[str, float],
    spec: Spec,
    t: Targets,
    n: int,
    objective: str,
    cos_bound: float | None = None,
) -> Iterable[dict[str, float]]:
    """Local optima of the formulation from n valid starts, in the caller's units."""
    b = built(m, variant, free, objective)
    s = t.stroke
    lo, hi = (np.array(v) / s for v in zip(*(_bounds(m, k, spec, s) for k in free), strict=True))
    pts = []
    for x0 in starts(lo, hi, lo > 0, 40 * n):
        try:
            m.complete(
                {**fixed, **dict(zip(free, x0 * s, strict=True)), **dict.fromkeys(variant, 0.0)}
            )
        except SynthError:
            continue
        pts.append(x0)
        if len(pts) == n:
            break
    fx = np.array([fixed[k] / s for k in b.form.fixed])
    cb = t.cos_bound if cos_bound is None else cos_bound
    for sol in multistart(b, fx, t.time_ratio, cb, lo, hi, np.array(pts), t.deadline):
        yield {k: v * s for k, v in sol.items()}


def _candidate(
    m: Mechanism, params: dict[str, float], method: str, t: Targets, limits: dict
) -> Candidate | None:
    try:
        params = m.complete(params)
    except SynthError:
        return None
    checked = verify(m.type, params, t.time_ratio, t.stroke, t.bound_deg)
    if checked is None:
        return None
    a, residuals = checked
    size = sum(params[q.name] for q in m.parameters if q.link)
    mu = a.transmission.min_deg
    return Candidate(
        type=m.type,
        params=params,
        time_ratio=a.time_ratio,
        stroke=a.stroke,
        min_transmission_angle_deg=mu,
        objective_value=size if t.objective == "min_size" else mu,
        method=method,
        residuals=residuals,
        verified=True,
        grashof=a.grashof,
        size=size,
        conditioning=a.conditioning,
        active=_active(params, mu, t, limits),
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


def _diagnose(m: Mechanism, spec: Spec, t: Targets, open_variants) -> Infeasible:
    """Why no design, over every variant the request allows: the best transmission at these
    targets, else the reachable TR range."""
    searchable = [(v, f, tuple(k for k in names if k not in f)) for v, names, f in open_variants]
    searchable = [(v, f, free) for v, f, free in searchable if free]
    if not searchable:
        return Infeasible(
            m.type, "FIXED_PARTS_CONTRADICT_TARGETS", _fixed_design_reason(m, spec, t)
        )

    def optima(objective: str, cos_bound: float | None = None):
        """(TR, min transmission°) of each verified local optimum of ``objective``."""
        for variant, fixed, free in searchable:
            n = STARTS_LEFTOVER
            for x in _ipopt(m, variant, free, fixed, spec, t, n, objective, cos_bound):
                r = _analysed(m, {**spec.fixed, **x, **dict.fromkeys(variant, 0.0)}, t)
                if r is not None:
                    yield r

    best = None
    if t.bound_deg > 0:
        best = max((mu for _, mu in optima("max_transmission_angle", 1.0)), default=None)
    if best is not None and best < t.bound_deg:
        return Infeasible(
            m.type,
            "TRANSMISSION_UNREACHABLE",
            f"{m.type} reaches at most a minimum transmission angle of {best:.4f}° at time "
            f"ratio {t.time_ratio:g} and stroke {t.stroke:g}{_with(spec)}, below the bound "
            f"{t.bound_deg:g}°",
            best_transmission_angle_deg=best,
        )
    trs = [
        tr
        for objective in ("max_time_ratio", "min_time_ratio")
        for tr, mu in optima(objective)
        if mu >= t.bound_deg - 1e-9
    ]
    if time.monotonic() >= t.deadline:
        return Infeasible(m.type, "BUDGET_EXHAUSTED", _budget_reason(m, t))
    if trs:
        return Infeasible(
            m.type,
            "TIME_RATIO_UNREACHABLE",
            f"{m.type} reaches time ratios {min(trs):.6g} … {max(trs):.6g} with a transmission "
            f"angle ≥ {t.bound_deg:g}° and stroke {t.stroke:g}{_with(spec)}, not "
            f"{t.time_ratio:g}",
            time_ratio_range=(min(trs), max(trs)),
        )
    return Infeasible(
        m.type,
        "NO_VALID_DESIGN",
        f"no valid {m.type} has stroke {t.stroke:g} with a transmission angle ≥ "
        f"{t.bound_deg:g}°{_with(spec)} within the bounds",
    )


def _analysed(m: Mechanism, params: dict[str, float], t: Targets) -> tuple[float, float] | None:
    """(TR, min transmission°) of a valid design with the target stroke, else None."""
    try:
        a = analyze(m.type, params)
    except SynthError:
        return None
    if a.reversals != 2 or abs(a.stroke - t.stroke) > 1e-9 * t.stroke:
        return None
    return a.time_ratio, a.transmission.min_deg


def _fixed_design_reason(m: Mechanism, spec: Spec, t: Targets) -> str:
    try:
        a = analyze(m.type, dict(spec.fixed))
    except SynthError as e:
        return f"the fixed parts do not run: {e.msg}"
    return (
        f"the fixed parts make time ratio {a.time_ratio:.9g}, stroke {a.stroke:.9g} and a "
        f"minimum transmission angle of {a.transmission.min_deg:.4f}°; the targets are "
        f"{t.time_ratio:g}, {t.stroke:g} and ≥ {t.bound_deg:g}°"
    )


def _with(spec: Spec) -> str:
    if not spec.fixed:
        return ""
    return " with " + ", ".join(f"{k} {v:g}" for k, v in spec.fixed.items()) + " fixed"


def _variants(m: Mechanism, spec: Spec) -> list[frozenset[str]]:
    """The structural variants the request allows: each optional part zero (first) or not."""
    out: list[frozenset[str]] = [frozenset()]
    for q in m.parameters:
        if q.zero_means is None:
            continue
        if q.name in spec.fixed:
            zero = [spec.fixed[q.name] == 0]
        elif q.name in spec.bounds:
            zero = [False] if spec.bounds[q.name][0] > 0 else [True, False]
        else:
            zero = [True, False]
        out = [v | {q.name} if z else v for z in zero for v in out]
    return out


def _fixed_violation(m: Mechanism, variant: frozenset[str], fixed: Mapping[str, float]):
    """The message of a validity condition broken by the fixed parts alone, if any."""
    p = {**fixed, **dict.fromkeys(variant, 0.0)}
    for c in m.conditions:
        if not c.applies(variant):
            continue
        try:
            terms = [float(x) for x in c.margin(p)]
        except KeyError:  # the condition involves a free part
            continue
        if min(terms) < 0 or (c.strict and min(terms) <= 0):
            return c.explain(p)
    return None


def _bounds(m: Mechanism, name: str, spec: Spec, stroke: float) -> tuple[float, float]:
    """The caller's bounds, else the defaults: the parameter's (lo, hi) × the stroke, the upper
    one × the largest fixed length where that is larger (parts sized to the existing ones)."""
    if name in spec.bounds:
        return spec.bounds[name]
    lo, hi = m.parameter(name).bounds
    scale = max([stroke] + [abs(v) for v in spec.fixed.values()])
    return lo * stroke, hi * scale


def _within(values: dict[str, float], bounds: Mapping[str, tuple[float, float]]) -> bool:
    """Closed-form values must be positive and inside the caller's explicit bounds."""
    return all(
        v > 0 and (k not in bounds or bounds[k][0] <= v <= bounds[k][1]) for k, v in values.items()
    )


def _same(a: dict[str, float], b: dict[str, float], stroke: float) -> bool:
    return a.keys() == b.keys() and all(abs(a[k] - b[k]) <= SAME * stroke for k in a)


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
