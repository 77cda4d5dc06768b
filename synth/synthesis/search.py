"""The search behind synthesize(): per type and structural variant, the designs that meet the
targets, predicted but not yet verified, and what closed the variants that have none.

Per variant (a slot drive, or a link where a part may be zero):

1. the fixed parts alone are checked against the validity conditions;
2. the type's exact reduced solver (``synth.mechanisms.reduced``: closed forms, bracketed roots and
   Newton's method in at most two variables) gives its local optima, no search involved;
3. where it cannot take the problem or certify its answer, IPOPT solves the formulation,
   warm-started from the reduced designs and from the generic path's deterministic cold
   starts (those alone for a type without a reduced solver);
4. every design is predicted by the type's closed forms (``facts``; without them, by the
   analysis).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .. import targets
from ..analysis.kinematics import analyze
from ..errors import SynthError, Unreachable
from ..mechanisms import Mechanism
from ..mechanisms.reduced import Problem, Reduced, agree
from ..numerics import ROUNDING
from ..results import TOL, Infeasible
from .formulation import relevant
from .solve import built, multistart, starts

STARTS = 8  # cold multistart starts (also beside warm ones: never worse than the generic path)
SAME = 1e-4  # two designs within this (× stroke) in every parameter are one local optimum


@dataclass(frozen=True)
class Spec:
    """One type to search: parameters kept (``fixed``) and limits on the free ones."""

    type: str
    fixed: Mapping[str, float] = field(default_factory=dict)
    bounds: Mapping[str, tuple[float, float]] = field(default_factory=dict)


@dataclass(frozen=True)
class Solver:
    """How a synthesis solves (``synthesize(..., solver=...)``).

    ``accelerators``: each type's exact reduced solver (closed forms, bracketed roots, Newton
    in at most two variables) first; False solves every type as one without it would be, by
    the generic path (cold multistart on the formulation), for cross-checks. ``starts``: cold
    starts per structural variant where the generic path runs (Halton points, the valid ones;
    the reduced solvers' designs are warm starts beside them). ``local``: the local solve from
    those starts, with ``solve.multistart``'s signature (built NLP, fixed values, time ratio,
    cos of the bound, free lengths' bounds, start points, deadline) → (start index, free
    lengths in stroke units) of each solution; None is IPOPT (``solve.multistart``).
    """

    accelerators: bool = True
    starts: int = STARTS
    local: Callable[..., Iterable[tuple[int, dict[str, float]]]] | None = None


DEFAULT = Solver()  # the reduced solvers, then IPOPT from STARTS cold starts where needed


@dataclass(frozen=True)
class Targets:
    time_ratio: float
    stroke: float
    bound_deg: float
    objective: str
    deadline: float
    solver: Solver = DEFAULT

    @property
    def cos_bound(self) -> float:
        return math.cos(math.radians(self.bound_deg))

    @property
    def beta(self) -> float:
        """The crank angle by which the slow stroke exceeds π."""
        return targets.beta(self.time_ratio)


@dataclass(frozen=True)
class Variant:
    """A structural variant the request leaves open, as the solvers saw it."""

    parts: frozenset[str]  # the optional parts left out
    names: tuple[str, ...]  # the parameters its kinematics use
    fixed: dict[str, float]
    problem: Problem
    exact: bool  # the reduced solver answered it exactly
    at: tuple[tuple[float, ...], ...] = ()  # where the reduced solver found its optima

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


def search(
    m: Mechanism, spec: Spec, index: int, t: Targets, near: Searched | None = None
) -> Searched:
    """Every variant's local optima (unverified, predicted), and what closed the others;
    ``near``: the search of the same request at a nearby bound (a front's previous point),
    whose optima a reduced solver may continue from (``Problem.near``)."""
    out = Searched()
    seen: list[dict[str, float]] = []
    hints: list[dict[str, float]] = []  # each variant's optima, stroke units: a start for the next
    for parts in variants(m, spec):
        names = relevant(m, parts)
        fixed = {k: v for k, v in spec.fixed.items() if k in names}
        violation = fixed_violation(m, parts, spec.fixed)
        if violation:
            out.reasons.append(Infeasible(m.type, "FIXED_PARTS_INVALID", violation))
            continue
        prev = next((v.at for v in near.variants if v.parts == parts), ()) if near else ()
        problem = build_problem(m, parts, names, fixed, spec, t, hints=tuple(hints), near=prev)
        try:
            answer = m.reduced(problem) if m.reduced and t.solver.accelerators else None
        except Unreachable as u:
            out.reasons.append(Infeasible(m.type, u.code, u.reason))
            continue
        exact = answer is not None and answer.exact
        if exact and answer is not None:
            hints += answer.designs
        at = answer.at if exact and answer is not None else ()
        variant = Variant(parts, names, fixed, problem, exact, at)
        designs = [(scaled(d, t.stroke), "closed_form") for d in (answer or Reduced()).designs]
        if not exact and not variant.free:  # nothing to solve: the fixed parts are the design
            designs = [({}, "closed_form")]
        elif not exact:  # the reduced designs are starting points, not answers
            designs = ipopt(m, variant, spec, t, t.objective, [d for d, _ in designs])
        proposals = []
        for d, method in designs:
            params = whole(spec, d, parts)
            if any(same(params, o, t.stroke) for o in seen):
                continue  # a local optimum found again
            seen.append(params)
            p = proposal(m, index, params, method, t)
            if p is not None:
                proposals.append(p)
        out.proposals += proposals
        out.variants.append(variant)
    return out


def build_problem(
    m: Mechanism,
    parts: frozenset[str],
    names: tuple[str, ...],
    fixed: dict[str, float],
    spec: Spec,
    t: Targets,
    **changes: Any,
) -> Problem:
    s = t.stroke
    box = {k: bounds(m, k, spec, s) for k in names if k not in fixed}
    return Problem(
        variant=parts,
        fixed={k: v / s for k, v in fixed.items()},
        bounds={k: (lo / s, hi / s) for k, (lo, hi) in box.items()},
        beta=t.beta,
        cos_bound=t.cos_bound,
        objective=t.objective,
        stroke=s,
        explicit=frozenset(spec.bounds) & (set(names) - set(fixed)),
        **changes,
    )


def scaled(d: dict[str, float], s: float) -> dict[str, float]:
    return {k: v * s for k, v in d.items()}


def whole(spec: Spec, d: Mapping[str, float], parts: Iterable[str]) -> dict[str, float]:
    """A variant's design (``d``: its lengths, caller's units) as the request's: with every
    fixed part as given (those the variant leaves out too, such as a placement) and the parts
    it leaves out 0."""
    return {**d, **spec.fixed, **dict.fromkeys(parts, 0.0)}


def predict(m: Mechanism, params: dict[str, float]) -> tuple[float, float, float, float] | None:
    """(time ratio, stroke, min transmission°, size) by the type's closed forms (without them,
    by the analysis); None for a design that does not run."""
    try:
        if all(k in params for k in m.names):  # a design the solvers built: check it only
            p = dict(params)
            m.check(p)
        else:
            p = m.complete(params)
    except SynthError:
        return None
    if m.facts is None:  # no closed forms: the analysis (verification repeats it)
        try:
            a = analyze(m.type, p)
        except SynthError:
            return None
        return a.time_ratio, a.stroke, a.transmission.min_deg, m.size(p)
    f = m.facts(p)
    if any(float(t) < -ROUNDING for t in f.one_way):
        return None  # the slider turns back within a swing: the closed forms do not hold
    beta = abs(float(f.beta))
    cos = [abs(float(c)) for c in f.transmission_cos]
    angle = targets.transmission_deg(max(cos)) if cos else 90.0
    size = m.size(p)
    return targets.time_ratio(beta), float(f.stroke), angle, size


def proposal(
    m: Mechanism, index: int, params: dict[str, float], method: str, t: Targets
) -> Proposal | None:
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


def ipopt(
    m: Mechanism,
    v: Variant,
    spec: Spec,
    t: Targets,
    objective: str,
    warm: list[dict[str, float]] = (),  # type: ignore[assignment]
    cos_bound: float | None = None,
) -> list[tuple[dict[str, float], str]]:
    """Local optima of the formulation (caller's units) from the warm starts and valid cold
    ones, each with how it was found."""
    free, fixed = v.free, v.fixed
    if not free or time.monotonic() >= t.deadline:  # past it: no start would run (nor a build)
        return []
    b = built(m, v.parts, free, objective)
    s = t.stroke
    lo, hi = np.array([v.problem.bounds[k] for k in free], dtype=float).T
    first = [np.clip([d[k] / s for k in free], lo, hi) for d in warm if all(k in d for k in free)]
    pts = []
    n = t.solver.starts
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
    local = t.solver.local or multistart
    for i, sol in local(b, fx, t.time_ratio, cb, lo, hi, np.array(first + pts), t.deadline):
        method = "closed_form+ipopt" if i < len(first) else "ipopt"
        out.append(({k: x * s for k, x in sol.items()}, method))
    return out


def variants(m: Mechanism, spec: Spec) -> list[frozenset[str]]:
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


def fixed_violation(
    m: Mechanism, variant: frozenset[str], fixed: Mapping[str, float]
) -> str | None:
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


def bounds(m: Mechanism, name: str, spec: Spec, stroke: float) -> tuple[float, float]:
    """The caller's bounds, else the defaults: the parameter's (lo, hi) × the stroke, the upper
    one × the largest fixed length where that is larger (parts sized to the existing ones)."""
    if name in spec.bounds:
        return spec.bounds[name]
    lo, hi = m.parameter(name).bounds
    scale = max([stroke] + [abs(v) for v in spec.fixed.values()])
    return lo * stroke, hi * scale


def same(a: dict[str, float], b: dict[str, float], stroke: float, within: float = SAME) -> bool:
    """Whether two designs are one: each parameter within ``within`` × stroke."""
    return a.keys() == b.keys() and all(abs(a[k] - b[k]) <= within * stroke for k in a)
