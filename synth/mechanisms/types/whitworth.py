"""Whitworth quick return — Podhorodeski et al. (2005) Fig. 1c, the textbook chapter Example 3.

The crank pin B = r2(cos θ, sin θ) slides in a lever pivoted at O4 = (−d, 0) with d < r2, so
the lever angle ψ = atan2(B_y, B_x + d) turns a full revolution. The output arm points the
other way, P = O4 − L(cos ψ, sin ψ), and drives the ram on the line x = −d through the rod PR:

    s(θ) = P_y + sqrt(l² − (P_x + d)²) = −L sin ψ + sqrt(l² − L² cos² ψ)

==============  ======  ======================================
name            symbol  meaning
==============  ======  ======================================
crank           r2      crank O2B
pivot_distance  d       lever pivot to crank pivot, O2O4
lever           L       output arm O4P
connecting_rod  l       rod PR from the arm to the ram
==============  ======  ======================================

Valid: r2 > d (the lever turns fully); l > L (the rod reaches the ram path). Closed forms
extremes where B_x = −d; quick-stroke crank angle 2 acos(d/r2);
TR = (π − acos(d/r2)) / acos(d/r2); stroke = 2L; transmission cos μ = L cos ψ / l,
μ_min = acos(L/l).
"""

from __future__ import annotations

import math
from typing import Any

import casadi as ca

from ...errors import Unreachable
from ...targets import MIN_SIZE
from ..facts import Facts
from ..geometry import ahead, leg, lever, sqrt, where
from ..reduced import STRICT, Problem, Reduced, Space
from ..registry import (
    GROUND,
    RAM,
    ROD,
    Condition,
    Frame,
    Mechanism,
    Parameter,
    Params,
    Scale,
    register,
)
from ..slotted import check, dead_centres, ratio
from ..slotted import scale as _scale


def _lever(p: Params, th: Any) -> tuple[Any, Any]:
    r2, d = p["crank"], p["pivot_distance"]
    return lever(r2, d, th)


def position(p: Params, th: Any) -> Any:
    r2, d, L, l = p["crank"], p["pivot_distance"], p["lever"], p["connecting_rod"]
    c, s = _lever(p, th)
    # sqrt(l² − L² cos² ψ) with l ∓ L cos ψ = (l − L) + L(1 ∓ cos ψ), 1 ∓ cos ψ from the
    # crank pin's offsets without cancelling: exact when the rod is barely longer than the
    # lever (its dead point at ψ = 0, π), where the plain difference loses every digit
    x = (d - r2) + 2 * r2 * ca.cos(th / 2) ** 2
    y = r2 * ca.sin(th)
    r = sqrt(x * x + y * y)
    up = ((l - L) + L * y * y / (r * (r + x))) * (l + L * c)  # cos ψ > 0
    down = ((l - L) + L * y * y / (r * (r - x))) * (l - L * c)  # cos ψ < 0
    return ahead(-L * s, sqrt(where(x > 0, up, down)), (l - L) * (l + L))


def transmission(p: Params, th: Any) -> dict[str, Any]:
    c, _ = _lever(p, th)
    return {"connecting_rod-ram": p["lever"] * c / p["connecting_rod"]}


def joints(p: Params, th: Any) -> dict[str, tuple[Any, Any]]:
    r2, d, L = p["crank"], p["pivot_distance"], p["lever"]
    c, s = _lever(p, th)
    return {
        "O2": (0.0, 0.0),
        "B": (r2 * ca.cos(th), r2 * ca.sin(th)),
        "O4": (-d, 0.0),
        "P": (-d - L * c, -L * s),
        "R": (-d, position(p, th)),
    }


def facts(p: Params) -> Facts:
    r2, d, L, l = p["crank"], p["pivot_distance"], p["lever"], p["connecting_rod"]
    q = ca.atan2(leg(r2, d), d)  # acos(d/r2)
    return Facts(
        beta=ca.pi - 2 * q,  # TR = (π − q)/q
        stroke=2 * L,
        transmission_cos=(L / l,),
    )


def reduced(p: Problem) -> Reduced:
    """The time ratio fixes pivot_distance/crank = cos(π/(1 + TR)) = sin(β/2) (the quick
    stroke's half angle), the stroke fixes the lever at half of it; the crank is a free scale
    (the smallest allowed, to break ties) and the rod takes the longest (max transmission,
    cos μ = lever/rod) or the shortest length the bound allows (min size)."""
    if p.beta <= 0:
        raise Unreachable("TIME_RATIO_UNREACHABLE", "whitworth has time ratio > 1 always")
    per_crank = ratio(p, "pivot_distance", "crank")

    def time_ratio(crank_per_pivot: float) -> float:
        q = math.acos(min(1 / crank_per_pivot, 1.0))  # half the quick stroke
        return (math.pi - q) / q

    check(p, time_ratio, lambda lever: 2 * lever)
    crank = _scale(p, per_crank)
    if crank is None:
        return Reduced([])
    lever = p.fixed.get("lever", 0.5)
    lo, hi = p.box("connecting_rod")
    if "connecting_rod" in p.fixed:
        rod = p.fixed["connecting_rod"]
    elif p.objective == MIN_SIZE:
        rod = max(lo, lever / p.cos_bound, lever + STRICT)
    else:
        rod = hi
    if rod > hi or ("lever" in p.bounds and not p.allows("lever", lever)):
        return Reduced([])
    design = {
        "crank": crank,
        "pivot_distance": crank * per_crank,
        "lever": lever,
        "connecting_rod": rod,
    }
    return Reduced([{**design, **p.fixed}])


def space(p: Problem) -> Space | None:
    """As ``reduced`` states it: the crank, a free scale (the smallest allowed, or as a fixed
    crank or pivot distance sets it), the pivot distance set by it and the time ratio, the
    lever half the stroke; the rod is the free number, over its bounds (fixed: a point)."""
    f, per_crank = p.fixed, ratio(p, "pivot_distance", "crank")
    crank = None if p.beta <= 0 else _scale(p, per_crank)
    if crank is None:
        return None

    def design(u: Any, k: Any) -> dict[str, Any]:
        return {"crank": k[0], "pivot_distance": k[1], "lever": k[2], "connecting_rod": u[0]}

    lo, hi = (f["connecting_rod"],) * 2 if "connecting_rod" in f else p.box("connecting_rod")
    constants = (crank, crank * per_crank, f.get("lever", 0.5))
    return Space((lo,), (hi,), constants, design, scaled=True, dead=_dead)


def _dead(k: Any) -> tuple[float, float]:
    """Where the crank pin is over the lever's pivot, cos θ = −pivot_distance/crank: the
    arm is across the ram's path, the slider's dead centres for every rod (l > L)."""
    return dead_centres(-k[1] / k[0])


# the crank pin's block slides in the lever's slot, on the line from O4 through B; the lever's
# arm O4P points the other way (the slot's own length is left out of the lever's mass)
FRAME = Frame(
    bodies=(("crank",), ("lever",), ("connecting_rod",)),
    pins=(
        ("O2", "crank", GROUND),
        ("O4", "lever", GROUND),
        ("P", "lever", "connecting_rod"),
        ("R", "connecting_rod", RAM),
    ),
    path=lambda p: (0.0, 1.0),
    slots=(("B", "crank", "lever", ("O4", "B")),),
)


register(
    Mechanism(
        type="whitworth",
        title="Whitworth quick return",
        description="The inversion of the crank shaper with the crank longer than the pivot "
        "distance: the slotted lever turns fully and drives the ram through a connecting rod.",
        sources=("Podhorodeski et al. (2005)", "the textbook chapter"),
        quick_return=True,
        parameters=(
            Parameter("crank", "r2", "crank O2B"),
            Parameter("pivot_distance", "d", "lever pivot to crank pivot, O2O4"),
            Parameter("lever", "L", "output arm O4P of the slotted lever"),
            Parameter("connecting_rod", "l", "rod PR from the arm to the ram", bounds=ROD),
        ),
        conditions=(
            Condition(
                name="rotating_lever",
                text="crank > pivot_distance (the lever turns fully; otherwise a crank shaper)",
                margin=lambda p: (p["crank"] - p["pivot_distance"],),
                strict=True,
                explain=lambda p: (
                    f"crank {p['crank']:g} ≤ pivot_distance {p['pivot_distance']:g}: the lever "
                    f"cannot turn a full revolution (that is a crank_shaper)"
                ),
            ),
            Condition(
                name="rod_reach",
                text="connecting_rod > lever (the rod reaches the ram path in every position)",
                margin=lambda p: (p["connecting_rod"] - p["lever"],),
                strict=True,
                explain=lambda p: (
                    f"connecting_rod {p['connecting_rod']:g} ≤ lever {p['lever']:g}: the rod "
                    f"cannot reach the ram path when the lever lies along the pivot line"
                ),
            ),
        ),
        position=position,
        transmission=transmission,
        facts=facts,
        reduced=reduced,
        space=space,
        scale=Scale(
            "crank",
            ("pivot_distance",),
            "the time ratio sets pivot_distance/crank and the stroke sets the lever alone",
        ),
        joints=joints,
        frame=lambda variant: FRAME,
        drawing=(
            ("pivot_distance", "O2", "O4"),
            ("crank", "O2", "B"),
            ("lever", "O4", "P"),
            ("connecting_rod", "P", "R"),
        ),
    )
)
