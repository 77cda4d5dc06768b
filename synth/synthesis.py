"""synthesize(): time ratio, stroke and transmission bound → every good design, verified.

Per type and structural variant (a slot drive or a link where a part may be zero):

1. the fixed parts alone are checked against the validity conditions;
2. the type's exact reduced solver (``synth.reduced``; closed forms, bracketed roots and
   Newton's method in at most two variables) gives its local optima, no search involved;
3. where it cannot take the problem, or cannot certify its answer, IPOPT solves the
   formulation, warm-started from the reduced designs and a few deterministic cold starts
   (eight cold starts for a type without a reduced solver);
4. every design is predicted by the type's closed forms (``facts``), ranked, and re-analysed
   (``verify``) best first until ``max_candidates`` meet the targets to 1e-9;
5. a type with no design gets a reason with numbers (``synth.diagnose``).
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
from .mechanisms import Mechanism, all_types, get
from .mechanisms._registry import TOL, Unreachable
from .reduced import Problem, Reduced, agree
from .results import Candidate, Infeasible, SynthesisResult
from .solve import built, multistart, starts
from .verify import verify

STARTS = 8  # cold multistart for a type without a reduced solver
STARTS_WARM = STARTS  # cold starts beside the warm ones (the generic path's: never worse than it)
MAX_CANDIDATES = 50
SAME = 1e-4  # two designs within this (× stroke) in every parameter are one local optimum


@dataclass(frozen=True)
class Spec:
    """One type to search: parameters kept (``fixed``) and limits on the free ones."""

    type: str
    fixed: Mapping[str, float] = field(default_factory=dict)
    bounds: Mapping[str, tuple[float, float]] = field(default_factory=dict)


class SolverNeeded(Exception):
    """Raised by ``synthesize(..., ipopt=False)`` where the request needs IPOPT: the reduced
    solvers could not answer it exactly (a caller that must not block runs it elsewhere)."""


@dataclass(frozen=True)
class Targets:
    time_ratio: float
    stroke: float
    bound_deg: float
    objective: str
    deadline: float
    ipopt: bool = True  # False: raise SolverNeeded rather than run IPOPT

    @property
    def cos_bound(self) -> float:
        return math.cos(math.radians(self.bound_deg))

    @property
    def beta(self) -> float:
        """The crank angle by which the slow stroke exceeds π."""
        return math.pi * (self.time_ratio - 1) / (self.time_ratio + 1)


@dataclass(frozen=True)
class Variant:
    """A structural variant the request leaves open, as the solvers saw it."""

    parts: frozenset[str]  # the optional parts left out
    names: tuple[str, ...]  # the parameters its kinematics use
    fixed: dict[str, float]
    problem: Problem
    exact: bool  # the reduced solver answered it exactly

    @property
    def free(self) -> tuple[str, ...]:
        return tuple(k for k in self.names if k not in self.fixed)


@dataclass(frozen=True)
class Proposal:
    """An unverified design and what the closed forms predict for it."""

    spec: int  # its place in the request's mechanisms
    type: str
    params: dict[str, float]
    method: str
    angle_deg: float
    size: float


@dataclass
class Searched:
    """One type of the request: its proposals, the variants left open, reasons for the rest."""

    proposals: list[Proposal] = field(default_factory=list)
    variants: list[Variant] = field(default_factory=list)
    reasons: list[Infeasible] = field(default_factory=list)


def synthesize(
    time_ratio: float,
    stroke: float,
    min_transmission_angle_deg: float = 0.0,
    mechanisms: Sequence[Spec | Mapping[str, Any]] | None = None,
    objective: str = "max_transmission_angle",
    max_candidates: int = 5,
    time_budget_ms: float = 2000.0,
    *,
    accelerators: bool = True,
    ipopt: bool = True,
) -> SynthesisResult:
    """Every good design for the targets, verified and ranked (POST /v1/synthesize).

    ``accelerators=False`` solves every type as one without a reduced solver would be, by
    cold multistart IPOPT on the formulation: the generic path, for cross-checks.
    ``ipopt=False`` answers only what the reduced solvers answer exactly (in a millisecond
    or so) and raises ``SolverNeeded`` for the rest.

    >>> r = synthesize(2.0, 450.0, mechanisms=[{"type": "crank_shaper",
    ...                "fixed": {"pivot_distance": 240.0, "ram_link": 0.0}}])
    >>> [round(r.candidates[0].params[k], 9) for k in ("crank", "lever")]
    [120.0, 450.0]
    """
    from .diagnose import diagnose  # the refusals use this module's searches

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
    deadline = t0 + time_budget_ms / 1000
    targets = Targets(time_ratio, stroke, min_transmission_angle_deg, objective, deadline, ipopt)
    searched = [
        search(get(spec.type), spec, i, targets, accelerators) for i, spec in enumerate(specs)
    ]
    found, left = _verified(searched, targets, max_candidates)
    infeasible = [
        diagnose(get(spec.type), spec, targets, s)
        for i, (spec, s) in enumerate(zip(specs, searched, strict=True))
        if not any(c.spec == i for c in found) and not left[i]
    ]
    complete = time.monotonic() < targets.deadline
    cands = sorted((c.candidate for c in found), key=_rank(objective))
    return SynthesisResult(
        candidates=tuple(cands[:max_candidates]),
        infeasible=tuple(infeasible),
        complete=complete,
        elapsed_ms=(time.monotonic() - t0) * 1000,
    )


@dataclass(frozen=True)
class _Found:
    spec: int
    candidate: Candidate


def _verified(
    searched: list[Searched], t: Targets, max_candidates: int
) -> tuple[list[_Found], list[bool]]:
    """Verify the proposals best first (predicted) until ``max_candidates`` pass: a design
    that cannot be among the answer is never analysed. Also, per spec, whether proposals were
    left unverified (its type has designs, just not among the best)."""
    pool = sorted((p for s in searched for p in s.proposals), key=_predicted_rank(t.objective))
    found: list[_Found] = []
    left = [False] * len(searched)
    for k, p in enumerate(pool):
        if len(found) >= max_candidates or time.monotonic() >= t.deadline:
            for q in pool[k:]:
                left[q.spec] = True
            break
        c = _candidate(get(p.type), p, t, searched[p.spec].variants)
        if c is not None:
            found.append(_Found(p.spec, c))
    return found, left


def _predicted_rank(objective: str):
    if objective == "min_size":
        return lambda p: (p.size, -p.angle_deg, p.type)
    return lambda p: (-round(p.angle_deg, 9), p.size, p.type)


def _rank(objective: str):
    if objective == "min_size":
        return lambda c: (c.size, -c.min_transmission_angle_deg, c.type)
    # ties (e.g. slot drives, 90° for every design) go to the smaller mechanism
    return lambda c: (-round(c.min_transmission_angle_deg, 9), c.size, c.type)


def search(m: Mechanism, spec: Spec, index: int, t: Targets, accelerators: bool = True) -> Searched:
    """Every variant's local optima (unverified, predicted), and what closed the others."""
    out = Searched()
    seen: list[dict[str, float]] = []
    hints: list[dict[str, float]] = []  # each variant's optima, stroke units: a start for the next
    for parts in _variants(m, spec):
        names = relevant(m, parts)
        fixed = {k: v for k, v in spec.fixed.items() if k in names}
        violation = _fixed_violation(m, parts, spec.fixed)
        if violation:
            out.reasons.append(Infeasible(m.type, "FIXED_PARTS_INVALID", violation))
            continue
        problem = _problem(m, parts, names, fixed, spec, t, hints=tuple(hints))
        try:
            answer = m.reduced(problem) if m.reduced and accelerators else None
        except Unreachable as u:
            out.reasons.append(Infeasible(m.type, u.code, u.reason))
            continue
        exact = answer is not None and answer.exact
        if exact:
            hints += answer.designs
        variant = Variant(parts, names, fixed, problem, exact)
        designs = [(_scaled(d, t.stroke), "closed_form") for d in (answer or Reduced()).designs]
        if not exact and not variant.free:  # nothing to solve: the fixed parts are the design
            designs = [({}, "closed_form")]
        elif not exact:  # the reduced designs are starting points, not answers
            designs = _ipopt(m, variant, spec, t, t.objective, [d for d, _ in designs])
        proposals = []
        for d, method in designs:
            params = {**d, **spec.fixed, **dict.fromkeys(parts, 0.0)}
            if any(_same(params, o, t.stroke) for o in seen):
                continue  # a local optimum found again
            seen.append(params)
            p = _proposal(m, index, params, method, t)
            if p is not None:
                proposals.append(p)
        out.proposals += proposals
        out.variants.append(variant)
    return out


def _problem(m, parts, names, fixed, spec: Spec, t: Targets, **changes) -> Problem:
    s = t.stroke
    return Problem(
        variant=parts,
        fixed={k: v / s for k, v in fixed.items()},
        bounds={k: tuple(b / s for b in _bounds(m, k, spec, s)) for k in names if k not in fixed},
        beta=t.beta,
        cos_bound=t.cos_bound,
        objective=t.objective,
        stroke=s,
        explicit=frozenset(spec.bounds) & set(names),
        **changes,
    )


def _scaled(d: dict[str, float], s: float) -> dict[str, float]:
    return {k: v * s for k, v in d.items()}


def predict(m: Mechanism, params: dict[str, float]) -> tuple[float, float, float, float] | None:
    """(time ratio, stroke, min transmission°, size) by the type's closed forms; None for a
    design that does not run."""
    try:
        if all(k in params for k in m.names):  # a design the solvers built: check it only
            p = dict(params)
            m.check(p)
        else:
            p = m.complete(params)
    except SynthError:
        return None
    f = m.facts(p)
    beta = abs(float(f["beta"]))
    cos = [abs(float(c)) for c in f["transmission_cos"]]
    angle = math.degrees(math.acos(min(1.0, max(cos)))) if cos else 90.0
    size = sum(p[q.name] for q in m.parameters if q.link)
    return (math.pi + beta) / (math.pi - beta), float(f["stroke"]), angle, size


def _proposal(m: Mechanism, index: int, params, method: str, t: Targets) -> Proposal | None:
    """The design with its predicted angle and size, if the closed forms say it meets the
    targets (a closed form's spurious root, a design that does not run: None)."""
    got = predict(m, params)
    if got is None:
        return None
    tr, stroke, angle, size = got
    if not (agree(tr, t.time_ratio) and agree(stroke, t.stroke)):
        return None
    if angle < t.bound_deg - TOL * max(t.bound_deg, 1.0):
        return None
    return Proposal(index, m.type, params, method, angle, size)


def _ipopt(
    m: Mechanism,
    v: Variant,
    spec: Spec,
    t: Targets,
    objective: str,
    warm: list[dict[str, float]] = (),  # type: ignore[assignment]
    cos_bound: float | None = None,
) -> Iterable[tuple[dict[str, float], str]]:
    """Local optima of the formulation (caller's units) from the warm starts and valid cold
    ones, each with how it was found."""
    if not t.ipopt:
        raise SolverNeeded(m.type)
    free, fixed = v.free, v.fixed
    if not free:
        return []
    b = built(m, v.parts, free, objective)
    s = t.stroke
    lo, hi = (np.array(x) / s for x in zip(*(_bounds(m, k, spec, s) for k in free), strict=True))
    first = [np.clip([d[k] / s for k in free], lo, hi) for d in warm if all(k in d for k in free)]
    n = STARTS_WARM if warm else STARTS
    pts = []
    for x0 in starts(lo, hi, lo > 0, 40 * n):
        try:
            m.complete(
                {**fixed, **dict(zip(free, x0 * s, strict=True)), **dict.fromkeys(v.parts, 0.0)}
            )
        except SynthError:
            continue
        pts.append(x0)
        if len(pts) == n:
            break
    fx = np.array([fixed[k] / s for k in b.form.fixed])
    cb = t.cos_bound if cos_bound is None else cos_bound
    out = []
    for i, sol in multistart(b, fx, t.time_ratio, cb, lo, hi, np.array(first + pts), t.deadline):
        method = "closed_form+ipopt" if i < len(first) else "ipopt"
        out.append(({k: x * s for k, x in sol.items()}, method))
    return out


def _candidate(m: Mechanism, p: Proposal, t: Targets, variants: list[Variant]) -> Candidate | None:
    try:
        params = m.complete(p.params)
    except SynthError:
        return None
    checked = verify(m.type, params, t.time_ratio, t.stroke, t.bound_deg)
    if checked is None:
        return None
    a, residuals = checked
    size = sum(params[q.name] for q in m.parameters if q.link)
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
        objective_value=size if t.objective == "min_size" else mu,
        method=p.method,
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
    if objective == "min_size" and bound == 0:
        raise InvalidParameters(
            "min_transmission_angle_deg must be > 0 with the objective min_size: without a "
            "bound the smallest designs are linkages that lock (a 0° transmission angle)",
            ("min_transmission_angle_deg",),
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
