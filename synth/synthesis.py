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
from dataclasses import dataclass
from typing import Any

from .diagnose import diagnose
from .errors import InvalidParameters, SynthError
from .formulation import OBJECTIVES
from .kinematics import check_include
from .mechanisms import Mechanism, all_types, get
from .results import Candidate, SynthesisResult, Tolerance
from .search import Proposal, Searched, SolverNeeded, Spec, Targets, Variant, search
from .verify import verify

__all__ = ["MAX_CANDIDATES", "SolverNeeded", "Spec", "synthesize"]

MAX_CANDIDATES = 50


def synthesize(
    time_ratio: float,
    stroke: float,
    min_transmission_angle_deg: float = 0.0,
    mechanisms: Sequence[Spec | Mapping[str, Any]] | None = None,
    objective: str = "max_transmission_angle",
    max_candidates: int = 5,
    time_budget_ms: float = 2000.0,
    *,
    include: Collection[str] = (),
    tolerance: Tolerance | None = None,
    accelerators: bool = True,
    ipopt: bool = True,
) -> SynthesisResult:
    """Every good design for the targets, verified and ranked (POST /v1/synthesize).

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
    _check_targets(time_ratio, stroke, min_transmission_angle_deg, objective, max_candidates)
    check_include(include)
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
    extras = {"include": include, "tolerance": tolerance}
    found, left = _verified(searched, targets, max_candidates, extras)
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
    if objective == "min_size":
        return lambda p: (p.size, -p.angle_deg, p.type)
    return lambda p: (-round(p.angle_deg, 9), p.size, p.type)


def _rank(objective: str):
    if objective == "min_size":
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
        objective_value=size if t.objective == "min_size" else mu,
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
