"""Why a type gave no design, with numbers: the best minimum transmission angle any design
reaches at the targets, else the time ratios the type reaches with the bound.

Where a variant's reduced solver answered exactly, the numbers come from the same exact
reduced problem (certified: the best angle is its global optimum; the time-ratio range is the
hull of the ratios at which it has a design, its ends bisected). Elsewhere they come from
IPOPT's local optima of the diagnostic objectives (formulation.DIAGNOSTICS).
"""

from __future__ import annotations

import math
import time
from collections.abc import Hashable, Iterator
from dataclasses import dataclass, field, replace

from ..analysis.kinematics import analyze
from ..errors import InvalidDesign, SynthError, Unreachable
from ..load import Load
from ..mechanisms import Mechanism
from ..mechanisms.reduced import differ
from ..results import TOL, Infeasible
from ..targets import MAX_TRANSMISSION, time_ratio
from . import scans
from .search import Searched, Spec, Targets, Variant, bounds, ipopt, predict, scaled, whole

SCAN_TOL = 1e-6  # relative: a design at the scan's time ratio
LIFT = 10.0  # a default bound lifted this many times wider, to say what lifting it reaches
# β of the range's ends: the one the target lies beyond tighter than the verification (it tells
# how far to move), the other to the six digits a message prints
NEAR_END, FAR_END = 1e-10, 1e-6


def diagnose(m: Mechanism, spec: Spec, t: Targets, s: Searched) -> Infeasible:
    if not s.variants:
        return s.reasons[0] if s.reasons else _budget(m)
    searchable = [v for v in s.variants if v.free or v.exact]
    if not searchable:
        return Infeasible(m.type, "FIXED_PARTS_CONTRADICT_TARGETS", _fixed_design(m, spec, t))
    best, found = None, []
    if t.bound_deg > 0:
        found = [(v, _angles(m, v, spec, t)) for v in searchable]
        best = max((mu for _, (angles, _) in found for mu in angles), default=None)
    if best is not None and best < t.bound_deg:
        return Infeasible(
            m.type,
            "TRANSMISSION_UNREACHABLE",
            f"{m.type} reaches at most a minimum transmission angle of {best:.4f}° at time "
            f"ratio {t.time_ratio:g} and stroke {t.stroke:g}{_with(spec)}, below the bound "
            f"{t.bound_deg:g}°{_lifted(m, spec, t, found, best) or _defaults(m, spec, t)}",
            best_transmission_angle_deg=best,
        )
    if time.monotonic() >= t.deadline:  # then what follows would end so: not begun
        return _budget(m)
    trs = [tr for v in searchable for tr in _reach(m, v, spec, t)]
    if time.monotonic() >= t.deadline:
        return _budget(m)
    if trs and min(trs) <= t.time_ratio <= max(trs):  # designs exist, none passed the check
        return Infeasible(
            m.type,
            "NO_VALID_DESIGN",
            f"{m.type} reaches time ratios {min(trs):.6g} … {max(trs):.6g} with a transmission "
            f"angle ≥ {t.bound_deg:g}° and stroke {t.stroke:g}{_with(spec)}, yet no design its "
            f"solvers found at {t.time_ratio:.9g} met the targets to {TOL:g} (by the closed "
            f"forms and the forward analysis)",
        )
    if trs:
        lo, hi = min(trs), max(trs)
        if t.time_ratio < lo:  # the end the target lies beyond: with the digits that tell
            (lo_s, want), hi_s = differ(lo, t.time_ratio), f"{hi:.6g}"
        else:
            lo_s, (hi_s, want) = f"{lo:.6g}", differ(hi, t.time_ratio)
        return Infeasible(
            m.type,
            "TIME_RATIO_UNREACHABLE",
            f"{m.type} reaches time ratios {lo_s} … {hi_s} with a transmission angle ≥ "
            f"{t.bound_deg:g}° and stroke {t.stroke:g}{_with(spec)}, not {want}",
            time_ratio_range=(lo, hi),
        )
    return Infeasible(
        m.type,
        "NO_VALID_DESIGN",
        f"no valid {m.type} has stroke {t.stroke:g} with a transmission angle ≥ "
        f"{t.bound_deg:g}°{_with(spec)} within the bounds",
    )


Exact = list[tuple[float, dict[str, float]]]  # the exact reduced optima: (angle, design)


def _angles(m: Mechanism, v: Variant, spec: Spec, t: Targets) -> tuple[list[float], Exact | None]:
    """The minimum transmission angle of the variant's best designs at the targets (any
    angle), and those designs where they are exact (else None): exact where the reduced
    solver is, else IPOPT's local optima, verified. The reduced problem is asked even where it
    was not exact for the request: without the bound it may be (a bound no rod can meet
    leaves no start on its grid)."""
    found = _reduced(m, v, t, v.problem.beta)
    if found is not None:
        exact = list(found)
        return [mu for mu, _ in exact], exact
    return [mu for _, mu in _optima(m, v, spec, t, MAX_TRANSMISSION, 1.0)], None


def _reduced(
    m: Mechanism, v: Variant, t: Targets, beta: float, tol: float = TOL
) -> Iterator[tuple[float, dict[str, float]]] | None:
    """The predicted angles of the exact reduced optima at β (max transmission, no bound)
    that meet the time ratio and stroke to ``tol``, each with its design (stroke units), one
    by one (each costs a prediction), or None where the reduced solver is not exact there."""
    problem = replace(
        v.problem, beta=beta, cos_bound=1.0, objective=MAX_TRANSMISSION, hints=(), near=()
    )
    if m.reduced is None:
        return None
    try:
        answer = m.reduced(problem)
    except Unreachable:
        return iter(())
    if answer is None or not answer.exact:
        return None
    tr = time_ratio(beta)

    def angles() -> Iterator[tuple[float, dict[str, float]]]:
        for d in answer.designs:
            got = predict(m, {**scaled(d, t.stroke), **dict.fromkeys(v.parts, 0.0)})
            if got and abs(got[0] - tr) <= tol * tr and abs(got[1] - t.stroke) <= tol * t.stroke:
                yield got[2], d

    return angles()


def _reach(m: Mechanism, v: Variant, spec: Spec, t: Targets) -> list[float]:
    """The smallest and largest time ratio with a design meeting the bound."""
    if not v.exact:
        return [
            tr
            for objective in ("max_time_ratio", "min_time_ratio")
            for tr, mu in _optima(m, v, spec, t, objective)
            if mu >= t.bound_deg - TOL * max(t.bound_deg, 1.0)
        ]
    scan = _Scan.of(m, v, t)
    # the end the target lies beyond to NEAR_END, the other to FAR_END. Bisection from a kept
    # bracket goes on along the same midpoints, so the numbers do not depend on what was asked
    # before; threads that narrow the same end at once at most repeat each other's work. What
    # the deadline stops is kept for the next request (then this one says its budget ran out)
    try:
        ends = scans.ends(scan, t.deadline)
        if ends is None:
            return []
        below = t.beta < ends[0][1]
        out = []
        for k, tol in enumerate((NEAR_END, FAR_END) if below else (FAR_END, NEAR_END)):
            bracket = scans.narrowed(scan, ends, k, tol, t.deadline)
            out.append(time_ratio(bracket[1]))
        return out
    except scans.Late:
        return []


@dataclass(frozen=True)
class _Scan:
    """What a reachable range depends on (``key``: not the time ratio), and how to test a β."""

    key: tuple[Hashable, ...]
    m: Mechanism = field(compare=False)
    v: Variant = field(compare=False)
    t: Targets = field(compare=False)

    @classmethod
    def of(cls, m: Mechanism, v: Variant, t: Targets) -> _Scan:
        p = v.problem
        key = (
            m.type,
            v.parts,
            p.variant,
            tuple(sorted(p.fixed.items())),
            tuple(sorted(p.bounds.items())),
            p.explicit,
            t.stroke,
            t.bound_deg,
        )
        return cls(key, m, v, t)

    def ok(self, beta: float) -> bool:
        """Whether a design at β meets the bound. The closed forms lose digits where the range
        ends in a degenerate design (a time ratio → 3 for the slider-crank, → ∞ for the
        slotted levers): SCAN_TOL tells the ends."""
        bound = self.t.bound_deg - TOL * max(self.t.bound_deg, 1.0)
        angles = _reduced(self.m, self.v, self.t, beta, SCAN_TOL)
        return angles is not None and any(a >= bound for a, _ in angles)


def forget_ranges() -> None:
    """Drop the reachable ranges kept (a benchmark timing each refusal's whole cost)."""
    scans.forget()


def _optima(
    m: Mechanism,
    v: Variant,
    spec: Spec,
    t: Targets,
    objective: str,
    cos_bound: float | None = None,
) -> Iterator[tuple[float, float]]:
    """(TR, min transmission°) of each verified local optimum of ``objective`` (IPOPT)."""
    for x, _ in ipopt(m, v, spec, t, objective, cos_bound=cos_bound):
        try:
            a = analyze(m.type, whole(spec, x, v.parts))
        except SynthError:
            continue
        if a.reversals == 2 and abs(a.stroke - t.stroke) <= TOL * t.stroke:
            yield a.time_ratio, a.transmission.min_deg


def _budget(m: Mechanism) -> Infeasible:
    return Infeasible(
        m.type,
        "BUDGET_EXHAUSTED",
        f"the time budget ran out before a {m.type} design or a proof that none exists was "
        f"found; ask again with a larger time_budget_ms",
    )


def _fixed_design(m: Mechanism, spec: Spec, t: Targets) -> str:
    try:
        a = analyze(m.type, dict(spec.fixed))
    except SynthError as e:
        return f"the fixed parts do not run: {e.msg}"
    return (
        f"the fixed parts make time ratio {a.time_ratio:.9g}, stroke {a.stroke:.9g} and a "
        f"minimum transmission angle of {a.transmission.min_deg:.4f}°; the targets are "
        f"{t.time_ratio:g}, {t.stroke:g} and ≥ {t.bound_deg:g}°"
    )


def _defaulted(m: Mechanism, spec: Spec) -> list[str]:
    """The free parameters the request leaves to their default bounds."""
    return [q.name for q in m.parameters if q.name not in spec.fixed and q.name not in spec.bounds]


def _defaults(m: Mechanism, spec: Spec, t: Targets) -> str:
    """Where the search kept free lengths within their default bounds: those bounds, which a
    request's ``bounds`` widen."""
    free = _defaulted(m, spec)
    if not free:
        return ""
    ranges = ", ".join(
        f"{k} {lo:g} to {hi:g}" for k in free for lo, hi in [bounds(m, k, spec, t.stroke)]
    )
    return f", with its free lengths within their default bounds ({ranges}; bounds widen them)"


def _lifted(
    m: Mechanism,
    spec: Spec,
    t: Targets,
    found: list[tuple[Variant, tuple[list[float], Exact | None]]],
    best: float,
) -> str:
    """Where the best design (``found``: each variant's angles and exact optima, ``_angles``)
    rests on a default bound: that bound, and what lifting it reaches: the least limit that
    meets the request's bound (bisected), else the angle with it ``LIFT`` times wider; ''
    where a variant's optima are not exact, or none rests on one."""

    def reach(k: str, end: int, limit: float) -> float:  # the best angle with k's end there
        out = [-math.inf]
        for v, _ in found:
            if k in v.problem.bounds:
                box = list(v.problem.bounds[k])
                box[end] = limit / t.stroke
                wider = {**v.problem.bounds, k: (box[0], box[1])}
                lifted = replace(v.problem, bounds=wider, explicit=v.problem.explicit | {k})
                out += [
                    mu for mu, _ in _reduced(m, replace(v, problem=lifted), t, lifted.beta) or ()
                ]
        return max(out)

    if any(exact is None for _, (_, exact) in found):
        return ""
    tops = [(mu, v, d) for v, (_, exact) in found for mu, d in exact or ()]
    if not tops:
        return ""
    _, v, d = max(tops, key=lambda o: o[0])
    near_end = [(k, end) for k in _defaulted(m, spec) if k in v.problem.bounds for end in (0, 1)]
    resting = [
        (k, end)
        for k, end in near_end
        if abs(d[k] - v.problem.bounds[k][end]) <= 1e-9 * max(abs(d[k]), 1.0)
    ]
    lifts = []
    for k, end in resting:
        limit = bounds(m, k, spec, t.stroke)[end]
        wider = limit * LIFT if end else limit / LIFT
        lifts.append((reach(k, end, wider), k, end, limit, wider))
    top, k, end, limit, wider = max(lifts, default=(best, "", 0, 0.0, 0.0))
    if top <= best + 1e-9:
        return ""
    word = "≤" if end else "≥"
    said = f"; its best design rests on the default bound {k} {word} {limit:g}: with {k} {word}"
    if top < t.bound_deg:
        return f"{said} {wider:g} it reaches {top:.4f}° (a request's bounds lift it)"
    near, far = limit, wider  # the least limit that meets the bound lies between
    while abs(far - near) > 1e-6 * abs(far):
        mid = (near + far) / 2
        near, far = (near, mid) if reach(k, end, mid) >= t.bound_deg else (mid, far)
    return f"{said} {far:.6g} it meets {t.bound_deg:g}° (a request's bounds lift it)"


def _with(spec: Spec) -> str:
    if not spec.fixed:
        return ""
    return " with " + ", ".join(f"{k} {v:g}" for k, v in spec.fixed.items()) + " fixed"


def unloaded(mtype: str, refusal: str | None) -> Infeasible:
    """Why a type's designs came back without their loads: the load's refusal of the first
    design analysed (each one was refused, none is returned), else the budget (they are
    returned without)."""
    if refusal is not None:
        why = f"no {mtype} design found carries this load: the first is refused ({refusal})"
        return Infeasible(mtype, "LOAD_NOT_CARRIED", why)
    why = (
        f"the time budget ran out before the loads of the {mtype} designs found were "
        "analysed: they come without them; ask again with a larger time_budget_ms"
    )
    return Infeasible(mtype, "BUDGET_EXHAUSTED", why)


def cut_short(mtype: str, objective: str) -> Infeasible:
    """Why a type's candidates are its exact solvers' designs alone: the budget ran out within
    its search (what that had found depends on when; the designs before it do not)."""
    why = (
        f"the time budget ran out during the {mtype} search for {objective}: its candidates "
        "are the exact solvers' designs, not searched; ask again with a larger time_budget_ms"
    )
    return Infeasible(mtype, "BUDGET_EXHAUSTED", why)


def locked(m: Mechanism, best: dict[str, float] | None, load: Load | None) -> Infeasible | None:
    """Why the ``load`` cannot be carried by the best-transmitting design the solvers found
    (``best``: friction locks its ram, or a dead point meets the load), or None."""
    try:
        if best is not None and load is not None:
            analyze(m.type, best, load=load)
    except InvalidDesign as e:
        return unloaded(m.type, e.msg) if e.condition in ("friction", "dead_point") else None
    return None
