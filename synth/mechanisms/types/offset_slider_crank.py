"""Offset slider-crank — Podhorodeski et al. (2005), Fig. 1a.

Crank pin B = r2(cos θ, sin θ); the slider C runs on the line y = e, ahead of B along +x:

    s(θ) = B_x + sqrt(r3² − (e − B_y)²)

=======  ======  ==================================================
name     symbol  meaning
=======  ======  ==================================================
crank    r2      crank O2B
coupler  r3      connecting rod BC
offset   e       signed distance of the slider path from O2 (y = e)
=======  ======  ==================================================

Valid when r3 ≥ r2 + |e| (the crank turns fully). Transmission (coupler → slider): the angle
between BC and the path's normal, cos μ = (e − B_y)/r3. Closed forms:
stroke = sqrt((r3+r2)² − e²) − sqrt((r3−r2)² − e²); β = asin(|e|/(r3−r2)) − asin(|e|/(r3+r2));
TR = (π+β)/(π−β); μ_min = acos((r2+|e|)/r3).
"""

from __future__ import annotations

import math
import sys
from typing import Any

import casadi as ca

from ...numerics import ROUNDING
from ...results import TOL
from ...targets import MAX_TRANSMISSION
from ..facts import Facts
from ..geometry import leg, sqrt, where
from ..reduced import (
    Problem,
    Reduced,
    Space,
    clip,
    intersect,
    judge,
    unreachable,
)
from ..registry import GROUND, RAM, ROD, Condition, Frame, Mechanism, Parameter, Params, register

EPS = sys.float_info.epsilon


def position(p: Params, th: Any) -> Any:
    r2, r3, e = p["crank"], p["coupler"], p["offset"]
    # r3² − (e − B_y)² as (r3 − e + B_y)(r3 + e − B_y) with 1 ± sin θ = 2 sin²(θ/2 ± π/4):
    # exact near the coupler's upright positions, where a design on its limit has a dead point
    # (the plain difference loses every digit there)
    below = (r3 - r2 - e) + 2 * r2 * ca.sin(th / 2 + ca.pi / 4) ** 2
    above = (r3 - r2 + e) + 2 * r2 * ca.sin(th / 2 - ca.pi / 4) ** 2
    bx, root = r2 * ca.cos(th), sqrt(below * above)
    # with the crank pin well behind the pivot, B_x + root cancels when the coupler is barely
    # longer than the crank (the slider stays near O2): there use (root² − B_x²)/(root − B_x)
    # with root² − B_x² = (r3 − r2)(r3 + r2) − e(e − 2 B_y), exact for a small offset
    folded = ((r3 - r2) * (r3 + r2) - e * (e - 2 * r2 * ca.sin(th))) / (root - bx)
    return where(bx < -r2 / 2, folded, bx + root)


def transmission(p: Params, th: Any) -> dict[str, Any]:
    r2, r3, e = p["crank"], p["coupler"], p["offset"]
    return {"coupler-slider": (e - r2 * ca.sin(th)) / r3}


def joints(p: Params, th: Any) -> dict[str, tuple[Any, Any]]:
    r2 = p["crank"]
    return {
        "O2": (0.0, 0.0),
        "B": (r2 * ca.cos(th), r2 * ca.sin(th)),
        "C": (position(p, th), p["offset"]),
    }


def facts(p: Params) -> Facts:
    r2, r3, e = p["crank"], p["coupler"], p["offset"]
    # β = asin(e/(r3−r2)) − asin(e/(r3+r2)) with atan2; odd in e: TR < 1 is the mirror's 1/TR
    beta = ca.atan2(e, leg(r3 - r2, e)) - ca.atan2(e, leg(r3 + r2, e))
    return Facts(
        beta=beta,
        stroke=leg(r3 + r2, e) - leg(r3 - r2, e),
        transmission_cos=((e + r2) / r3, (e - r2) / r3),  # B_y = ∓r2
    )


def reduced(p: Problem) -> Reduced:
    """The dead-centre construction: the crank pivot sees the chord between the slider's dead
    centres, the stroke, under the angle β, so it lies on a circle through them; one number
    places it there. With s, c = sin, cos(β/2) and y the cosine of the angle between the
    pivot's line to the chord's far end and the chord's normal (0 < y < c), take
    q = c² − y² = |offset| sin β (no digits lost near time ratio 1, where y → c → 1):

        crank = sqrt(c² − q)/(2c),  coupler = sqrt(s² + q)/(2s),  |offset| = q/sin β

    (stroke units), 0 < q < c². The worst transmission cos μ = (crank + |offset|)/coupler =
    (q + s y)/(c sqrt(s² + q)) is 1 at q = c² − s² (y = s, a dead point: two branches). On the
    branch q < c² − s² (the crank longer than the other branch's) it has one minimum, at
    q* = s (sqrt(s² + 4) − 3s)/2 (y* = (sqrt(s² + 4) − s)/2: the stationary points are the
    roots of (y − s)(y² + s y − 1)), and it is 1 at q = 0 (crank = coupler: the slider folds);
    on the other branch it decreases with q. The size, crank + coupler, is greatest at
    y = s and falls away from it on both sides. So each branch's optimum is q*, an end of the
    box, or a root of cos μ = cos(bound)."""
    s, c = p.half
    if p.beta <= math.pi / 2 * TOL:  # a centred slider, time ratio 1: crank half the stroke
        lo, hi = p.box("coupler")
        coupler = hi if p.objective == MAX_TRANSMISSION else max(lo, 0.5 / p.cos_bound)
        design = {"crank": 0.5, "coupler": p.fixed.get("coupler", coupler), "offset": 0.0}
        design = {**design, **p.fixed}
        if p.fixed:  # they may be another time ratio's or stroke's
            judge(p, facts, design)
        return Reduced([design] if coupler <= hi and _allowed(p, design) else [])
    qs = _fixed_q(p, s, c)
    if qs is not None:
        design = _design(p, qs[0], qs[1], s, c)
        if len(p.fixed) > 1:  # the first fixed part sets the design; the others must agree
            judge(p, facts, design)
        return Reduced([design] if _allowed(p, design) else [])
    designs: list[dict[str, float]] = []
    seen: list[float] = []
    solved: dict[tuple[float, float], float | None] = {}  # the signs' boxes often agree
    for sign in (1, -1):
        box = _q_box(p, s, c, sign)
        if box is None:
            continue
        lo, hi = box[0], min(box[1], math.cos(p.beta))
        if (lo, hi) not in solved:
            solved[lo, hi] = _optimum(p, s, c, lo, hi) if lo < hi else None
        q = solved[lo, hi]
        if q is not None and not any(abs(q - o) <= ROUNDING * max(q, o) for o in seen):
            seen.append(q)
            designs.append(_design(p, q, sign, s, c))
    return Reduced(designs)


def space(p: Problem) -> Space | None:
    """The dead-centre construction as ``reduced`` states it: every design is one q in
    (0, cos β) = (0, c² − s²), up to the offset's sign (a mirror: the same motion), β the
    constant. The box is the q whose cos μ is within the bound (``reduced``: cos μ is 1 at
    both ends and has one minimum between) and whose parts are within theirs (``_q_box``;
    the hull of both signs' where the mirror is searched too), so that an optimum a bound
    holds lies on its face; None where no q meets them. A fixed part sets q (the box a point),
    and the offset's sign is the fixed offset's, else the one its bounds allow (the other the
    mirror's, where they allow both)."""
    if p.beta <= math.pi / 2 * TOL:
        return None
    s, c = p.half
    fixed = _fixed_q(p, s, c)
    sign = fixed[1] if fixed else (1.0 if p.box("offset")[1] > 0 else -1.0)
    e = p.box("offset")
    mirror = (p.beta, -sign) if "offset" not in p.fixed and e[0] < 0 < e[1] else None
    if fixed:
        lo, hi = fixed[0], fixed[0]
    else:
        signs = (sign, -sign) if mirror else (sign,)
        parts = [b for b in (_q_box(p, s, c, int(x)) for x in signs) if b]
        cb, star = p.cos_bound, _star(s)
        if not parts or _cos_mu(star, s, c) > cb:
            return None
        if cb < 1:
            bound = _bound_root(s, c, cb, 0.0, star), _bound_root(s, c, cb, math.cos(p.beta), star)
        else:
            bound = 0.0, math.cos(p.beta)
        hull = min(b[0] for b in parts), max(b[1] for b in parts)
        box = intersect(bound, hull)
        if box is None:
            return None
        lo, hi = box

    def design(u: Any, k: Any) -> dict[str, Any]:
        beta, q = k[0], u[0]
        s, c = ca.sin(beta / 2), ca.cos(beta / 2)
        crank, coupler = ca.sqrt(c * c - q) / (2 * c), ca.sqrt(s * s + q) / (2 * s)
        return {"crank": crank, "coupler": coupler, "offset": k[1] * q / ca.sin(beta)}

    return Space((lo,), (hi,), (p.beta, sign), design, mirror)


def _design(p: Problem, q: float, sign: int, s: float, c: float) -> dict[str, float]:
    design = {
        "crank": math.sqrt(c * c - q) / (2 * c),
        "coupler": math.sqrt(s * s + q) / (2 * s),
        "offset": sign * q / math.sin(p.beta),
    }
    return {**design, **p.fixed}


def _allowed(p: Problem, design: dict[str, float]) -> bool:
    """The parameters the targets and fixed parts set, within any bounds the caller gave."""
    return all(p.allows(k, v) for k, v in design.items() if k in p.bounds)


def _cos_mu(q: float, s: float, c: float) -> float:
    return (q + s * math.sqrt(c * c - q)) / (c * math.sqrt(s * s + q))


def _optimum(p: Problem, s: float, c: float, lo: float, hi: float) -> float | None:
    """The best q in [lo, hi] ⊂ [0, c² − s²]: max transmission, or min size within the bound
    (the size falls with q on this branch)."""
    star = clip(_star(s), lo, hi)
    if p.objective == MAX_TRANSMISSION:
        return star
    cb = p.cos_bound
    if _cos_mu(star, s, c) > cb:
        return None
    if _cos_mu(lo, s, c) <= cb:  # as small as the bound lets it
        return lo
    return _bound_root(s, c, cb, lo, star)


def _star(s: float) -> float:
    """q*, where the worst cos μ is least on the branch q < c² − s² (``reduced``)."""
    return s * (math.sqrt(s * s + 4) - 3 * s) / 2


def _bound_root(s: float, c: float, cb: float, out: float, star: float) -> float:
    """The q between ``out`` and ``star`` where cos μ = cb (above cb at ``out``, at most cb at
    ``star``; ``out`` on either side), to machine precision: Newton's method on the closed
    form's derivative, kept within the bracket (bisection where a step would leave it or
    stall), in Python floats (scipy's brentq cost ~10 µs of call overhead here, most of a
    min_size search)."""
    a, b = out, star  # cos μ > cb at a, ≤ cb at b
    q = 0.5 * (a + b)
    for _ in range(100):
        r, w = math.sqrt(c * c - q), math.sqrt(s * s + q)
        num = q + s * r
        f = num / (c * w) - cb
        if f == 0:
            return q
        if f > 0:
            a = q
        else:
            b = q
        d = ((1 - s / (2 * r)) * w - num / (2 * w)) / (c * w * w)  # d cos μ / dq
        step = f / d if d else math.nan
        nxt = q - step
        if not (min(a, b) < nxt < max(a, b)) or not math.isfinite(nxt):
            nxt = 0.5 * (a + b)
        if abs(nxt - q) <= 2 * EPS * max(q, 1e-300) or abs(b - a) <= 2 * EPS * max(a, b):
            return nxt
        q = nxt
    return q


def _q_box(p: Problem, s: float, c: float, sign: int) -> tuple[float, float] | None:
    """The q the bounds allow, with the offset's sign (each length is monotonic in q)."""
    lo_e, hi_e = p.box("offset")
    e_box = (max(lo_e, 0.0), hi_e) if sign > 0 else (max(-hi_e, 0.0), -lo_e)
    if e_box[0] > e_box[1]:
        return None
    sb = math.sin(p.beta)
    lo2, hi2 = p.box("crank")
    lo3, hi3 = p.box("coupler")
    return intersect(
        (_crank_q(hi2, c), _crank_q(lo2, c)),
        (_coupler_q(lo3, s), _coupler_q(hi3, s)),
        (e_box[0] * sb, e_box[1] * sb),
        (0.0, c * c),
    )


def _crank_q(r2: float, c: float) -> float:
    return c * c * (1 - 2 * r2) * (1 + 2 * r2)


def _coupler_q(r3: float, s: float) -> float:
    return s * s * (2 * r3 - 1) * (2 * r3 + 1)


def _fixed_q(p: Problem, s: float, c: float) -> tuple[float, int] | None:
    """(q, sign of the offset) set by the first fixed part, or None when nothing is fixed."""
    f, sb = p.fixed, math.sin(p.beta)
    sign = -1 if f.get("offset", 1.0) < 0 else 1
    if "crank" in f:
        if f["crank"] >= 0.5:
            raise unreachable(
                f"crank {p.shown(f['crank'])} is at least half the stroke: an offset "
                "slider-crank's stroke is more than twice its crank"
            )
        return _crank_q(f["crank"], c), sign
    if "coupler" in f:
        r3 = f["coupler"]
        if not 0.5 < r3 < 0.5 / s:
            raise unreachable(
                f"coupler {p.shown(r3)} must be longer than half the stroke and shorter than "
                f"stroke/(2 sin(β/2)) = {p.shown(0.5 / s)} at time ratio {p.ratio:.9g}"
            )
        return _coupler_q(r3, s), sign
    if "offset" in f:
        e = abs(f["offset"])
        if not 0 < e < c * c / sb:
            raise unreachable(
                f"|offset| {p.shown(e)} must be > 0 and < stroke/(2 tan(β/2)) = "
                f"{p.shown(c * c / sb)} at time ratio {p.ratio:.9g}"
            )
        return e * sb, sign
    return None


FRAME = Frame(
    bodies=(("crank",), ("coupler",)),
    pins=(("O2", "crank", GROUND), ("B", "crank", "coupler"), ("C", "coupler", RAM)),
    path=lambda p: (1.0, 0.0),
)


register(
    Mechanism(
        type="offset_slider_crank",
        title="Offset slider-crank",
        description="A slider-crank whose slider path is offset from the crank pivot; the offset "
        "makes the two strokes take different crank angles.",
        sources=("Podhorodeski et al. (2005)",),
        quick_return=True,
        parameters=(
            Parameter("crank", "r2", "crank O2B"),
            Parameter("coupler", "r3", "connecting rod BC (crank pin to slider)", bounds=ROD),
            Parameter(
                "offset",
                "e",
                "signed offset of the slider path from the crank pivot",
                signed=True,
                link=False,
                bounds=(0.0, 5.0),  # the mirror (−e) has the same TR and stroke
            ),
        ),
        conditions=(
            Condition(
                name="full_rotation",
                text="coupler ≥ crank + |offset| (the crank turns a full revolution)",
                margin=lambda p: (
                    p["coupler"] - p["crank"] - p["offset"],
                    p["coupler"] - p["crank"] + p["offset"],
                ),
                explain=lambda p: (
                    f"coupler {p['coupler']:g} < crank {p['crank']:g} + |offset| "
                    f"{abs(p['offset']):g} = {p['crank'] + abs(p['offset']):g}: the crank cannot "
                    f"turn a full revolution"
                ),
            ),
        ),
        position=position,
        transmission=transmission,
        facts=facts,
        reduced=reduced,
        space=space,
        joints=joints,
        frame=lambda variant: FRAME,
        drawing=(("crank", "O2", "B"), ("coupler", "B", "C")),
    )
)
