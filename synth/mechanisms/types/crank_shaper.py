"""Crank and slotted lever (crank shaper): the slotted-lever lab handout, Shelare et al. (2012),
the textbook chapter (Ex. 1, 2) and Podhorodeski et al. (2005), Fig. 1b.

The crank pin B = r2(cos θ, sin θ) carries a block that slides in the lever pivoted at
O4 = (−d, 0); the lever angle ψ = atan2(B_y, B_x + d) oscillates (r2 < d) and its tip is
P = O4 + L(cos ψ, sin ψ). The ram runs on the line x = −d + h (perpendicular to the pivot line):

    ram_link l = 0 (the tip drives the ram through a block in a slot):  s = P_y
    ram_link l > 0 (a link PR):             s = P_y + sqrt(l² − (h − L cos ψ)²)

==============  ======  =============================================================
name            symbol  meaning
==============  ======  =============================================================
crank           r2      crank CB
pivot_distance  d       lever pivot to crank pivot, AC
lever           L       slotted lever AP
ram_link        l       link PR from the lever tip to the ram (0: slot drive)
ram_height      h       lever pivot to the ram path, along the pivot line
==============  ======  =============================================================

Valid: r2 < d (else it is a Whitworth); d + r2 ≤ L (the block stays on the lever);
l ≥ max |h − L cos ψ| over the swing when l > 0. Default h = L cos ψmax, the path through the
tip's extreme positions. Closed forms: sin ψmax = r2/d;
TR = (π + 2 asin(r2/d)) / (π − 2 asin(r2/d)); stroke = 2 L r2/d when s is monotonic in ψ
(``one_way``: l cos ψmax ≥ |h − L cos ψmax|);
transmission at the ram link cos μ = (h − L cos ψ)/l; the slot drive alone transmits at 90°.
"""

from __future__ import annotations

import math
from typing import Any

import casadi as ca
import numpy as np

from ... import targets
from ...errors import Unreachable
from ..facts import Facts
from ..geometry import leg, lever
from ..reduced import ONE_WAY, Problem, Reduced, Space
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
    absent,
    one_way,
    reach_condition,
    register,
)
from ..rod import rod
from ..slotted import check, dead_centres, ratio
from ..slotted import scale as _scale


def _lever(p: Params, th: Any) -> tuple[Any, Any]:
    """cos ψ, sin ψ of the lever O4→B."""
    r2, d = p["crank"], p["pivot_distance"]
    return lever(r2, d, th)


def _cos_psi_max(p: Params) -> Any:
    r2, d = p["crank"], p["pivot_distance"]
    return leg(d, r2) / d


def _offsets(p: Params) -> tuple[Any, Any]:
    """The signed distances from the lever tip to the ram path at mid-swing and at the ends:
    the largest |·| over the swing is one of them (h − L cos ψ is monotonic in cos ψ)."""
    h, L = p["ram_height"], p["lever"]
    return h - L, h - L * _cos_psi_max(p)


def position(p: Params, th: Any) -> Any:
    L, l, h = p["lever"], p["ram_link"], p["ram_height"]
    c, s = _lever(p, th)
    if absent(l):
        return L * s
    return L * s + leg(l, h - L * c)


def transmission(p: Params, th: Any) -> dict[str, Any]:
    L, l, h = p["lever"], p["ram_link"], p["ram_height"]
    if absent(l):
        return {}
    c, _ = _lever(p, th)
    return {"ram_link-ram": (h - L * c) / l}


def defaults(p: Params) -> dict[str, Any]:
    return {"ram_height": p["lever"] * _cos_psi_max(p)}


def joints(p: Params, th: Any) -> dict[str, tuple[Any, Any]]:
    r2, d, L, h = p["crank"], p["pivot_distance"], p["lever"], p["ram_height"]
    c, s = _lever(p, th)
    return {
        "O2": (0.0, 0.0),
        "B": (r2 * ca.cos(th), r2 * ca.sin(th)),
        "O4": (-d, 0.0),
        "P": (-d + L * c, L * s),
        "R": (-d + h, position(p, th)),
    }


def facts(p: Params) -> Facts:
    r2, d, L, l = p["crank"], p["pivot_distance"], p["lever"], p["ram_link"]
    half = ca.atan2(r2, leg(d, r2))  # ψmax = asin(r2/d)
    return Facts(
        beta=2 * half,  # TR = (π + 2ψmax)/(π − 2ψmax)
        stroke=2 * L * r2 / d,
        transmission_cos=() if absent(l) else tuple(t / l for t in _offsets(p)),
        one_way=() if absent(l) else one_way(l, _cos_psi_max(p), _offsets(p)[1]),
    )


def reduced(p: Problem) -> Reduced:
    """The time ratio fixes crank/pivot_distance = sin ψmax = sin(β/2), the stroke fixes the
    lever, 1/(2 sin ψmax); the crank is a free scale (the smallest allowed: ties, and the
    size), up to the block's reach, pivot_distance + crank ≤ lever. A ram link and its path
    follow ``rod.rule`` (the lever tip swings ±ψmax); the slot drive transmits at 90°."""
    if p.beta <= 0:
        raise Unreachable("TIME_RATIO_UNREACHABLE", "crank_shaper has time ratio > 1 always")
    f = p.fixed
    k = ratio(p, "crank", "pivot_distance")  # sin ψmax

    def ratio_of(sin_half: float) -> float:  # the time ratio of crank/pivot_distance
        return targets.time_ratio(2 * math.asin(sin_half))

    check(p, ratio_of, lambda lever: 2 * lever * k)
    lever = f.get("lever", 0.5 / k)
    crank = _scale(p, 1 / k, reach=lever * k / (1 + k))
    if crank is None or not p.allows("lever", lever):
        return Reduced([])
    design = {"crank": crank, "pivot_distance": crank / k, "lever": lever}
    if "ram_link" not in p.variant:
        l, h, _ = rod(p, "ram_link", "ram_height", np.array(lever), p.beta / 2, 0.0)
        if not np.isfinite(l):
            return Reduced([])
        design.update(ram_link=float(l), ram_height=float(h))
    return Reduced([{**design, **p.fixed}])


# what the certified search takes over both free numbers in good time: the least peak
# acceleration (the peak torque's and the speed's bounds are too loose on wide boxes: 12 000
# boxes, 3 s, for a torque at time ratio 1.6; the speed not within 4 096 boxes)
TWO_FREE = frozenset({"acceleration"})


def space(p: Problem) -> Space | None:
    """As ``reduced`` states it (the crank a free scale, the smallest allowed; the pivot
    distance set by it and the time ratio; the lever by the stroke), and with a ram link two
    free numbers: b = (h − L cos ψmax)/l, the link's cos μ at the swing's ends (signed), and
    log l. The bounds on b are the transmission's and the one-way condition's, |b| ≤ cos ψmax
    − ``ONE_WAY``, and log l's the link's (fixed: a point), so that where the optimum is held
    by one of them it lies on a face of the box; the link's cos μ at mid-swing, b − L(1 −
    cos ψmax)/l, is bounded by the search's constraints. A fixed ram height leaves log l
    alone. The slot drive is one design (its box a point)."""
    if p.beta <= 0:
        return None
    f, k = p.fixed, ratio(p, "crank", "pivot_distance")
    lever = f.get("lever", 0.5 / k)
    crank = _scale(p, 1 / k, reach=lever * k / (1 + k))
    if crank is None:
        return None
    constants = (crank, crank / k, lever)
    if "ram_link" in p.variant:
        return Space((0.0,), (0.0,), constants, _slotted, scaled=True, dead=_dead)
    lo, hi = (f["ram_link"],) * 2 if "ram_link" in f else p.box("ram_link")
    span = math.log(lo), math.log(hi)
    if "ram_height" in f:

        def along(u: Any, k: Any) -> dict[str, Any]:
            return {**_slotted(u, k), "ram_link": ca.exp(u[0]), "ram_height": k[3]}

        height = (*constants, f["ram_height"])
        return Space(span[:1], span[1:], height, along, scaled=True, dead=_dead)

    def design(u: Any, k: Any) -> dict[str, Any]:
        link = ca.exp(u[1])
        height = k[2] * _cos_psi_max(_slotted(u, k)) + u[0] * link
        return {**_slotted(u, k), "ram_link": link, "ram_height": height}

    b = min(p.cos_bound, math.sqrt(1 - k * k) - ONE_WAY)
    box = (-b, span[0]), (b, span[1])
    if span[0] == span[1]:  # a fixed link: b alone
        return Space(*box, constants, design, scaled=True, dead=_dead)
    return Space(*box, constants, design, scaled=True, dead=_dead, measures=TWO_FREE)


def _dead(k: Any) -> tuple[float, float]:
    """The lever's swing ends, cos θ = −crank/pivot_distance: the slider's dead centres
    wherever it moves one way over each swing (``one_way``)."""
    return dead_centres(-k[0] / k[1])


def _slotted(u: Any, k: Any) -> dict[str, Any]:
    """The slot drive's design: its constants alone."""
    return {"crank": k[0], "pivot_distance": k[1], "lever": k[2]}


def frame(variant: frozenset[str]) -> Frame:
    """The crank pin's block slides in the lever's slot (on O4P); the tip P drives the ram
    through the ram link, or through a block in the ram's slot across its path."""
    bodies = (("crank",), ("lever",))
    pins = (("O2", "crank", GROUND), ("O4", "lever", GROUND))
    slots = (("B", "crank", "lever", ("O4", "P")),)
    if "ram_link" in variant:
        return Frame(bodies, pins, _path, slots=(*slots, ("P", "lever", RAM, None)))
    link = (("P", "lever", "ram_link"), ("R", "ram_link", RAM))
    return Frame((*bodies, ("ram_link",)), (*pins, *link), _path, slots)


def _path(p: Params) -> tuple[Any, Any]:
    """The ram's path, x = −d + h, as s grows."""
    return 0.0, 1.0


register(
    Mechanism(
        type="crank_shaper",
        title="Crank and slotted lever (crank shaper)",
        description="A crank drives a block in an oscillating slotted lever whose tip drives the "
        "ram, directly through a block in a slot or through a short ram link: the classic "
        "shaper drive.",
        sources=(
            "the slotted-lever lab handout",
            "Shelare et al. (2012)",
            "Podhorodeski et al. (2005)",
            "the textbook chapter",
        ),
        quick_return=True,
        parameters=(
            Parameter("crank", "r2", "crank CB"),
            Parameter("pivot_distance", "d", "lever pivot to crank pivot, AC"),
            Parameter("lever", "L", "slotted lever AP, pivot to tip"),
            Parameter(
                "ram_link",
                "l",
                "link PR from the lever tip to the ram",
                default=0.0,
                zero_means="the lever tip drives the ram through a block in a slot",
                bounds=ROD,
            ),
            Parameter(
                "ram_height",
                "h",
                "lever pivot to the ram path, along the pivot line",
                default_rule="lever·cos ψmax (sin ψmax = crank/pivot_distance): the path "
                "through the tip's extreme positions",
                link=False,
            ),
        ),
        conditions=(
            Condition(
                name="oscillating_lever",
                text="crank < pivot_distance (the lever oscillates; otherwise a Whitworth)",
                margin=lambda p: (p["pivot_distance"] - p["crank"],),
                strict=True,
                explain=lambda p: (
                    f"crank {p['crank']:g} ≥ pivot_distance {p['pivot_distance']:g}: the lever "
                    f"would turn a full revolution (that is a whitworth), not oscillate"
                ),
            ),
            Condition(
                name="block_on_lever",
                text="pivot_distance + crank ≤ lever (the crank-pin block stays on the lever)",
                margin=lambda p: (p["lever"] - p["pivot_distance"] - p["crank"],),
                explain=lambda p: (
                    f"lever {p['lever']:g} < pivot_distance {p['pivot_distance']:g} + crank "
                    f"{p['crank']:g} = {p['pivot_distance'] + p['crank']:g}: the crank-pin block "
                    f"runs off the slotted lever"
                ),
            ),
            reach_condition(
                "ram_link_reach",
                "ram_link",
                "ram_height",
                "lever",
                _offsets,
                "the lever tip",
                "ram",
            ),
        ),
        position=position,
        transmission=transmission,
        defaults=defaults,
        facts=facts,
        reduced=reduced,
        space=space,
        scale=Scale(
            "crank",
            ("pivot_distance",),
            "the time ratio sets crank/pivot_distance and the stroke sets the lever alone",
            reach=lambda p: p["lever"] / (1 + p["pivot_distance"] / p["crank"]),  # block on lever
        ),
        joints=joints,
        frame=frame,
        drawing=(
            ("pivot_distance", "O2", "O4"),
            ("crank", "O2", "B"),
            ("lever", "O4", "P"),
            ("ram_link", "P", "R"),
        ),
    )
)
