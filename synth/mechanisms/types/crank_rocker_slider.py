"""Crank-rocker four-bar driving a slider (piston) — Podhorodeski et al. (2005), Fig. 2a.

O2 at the origin, O4 = (r1, 0), crank pin A = r2(cos θ, sin θ); the rocker pin D is the
intersection of circle(A, r3) and circle(O4, r4) left of A→O4, ψ the angle of O4→D. The rocker
swings between its toggles (crank and coupler collinear, O2D = r3 ± r2), at angles
ψ = π − γ(r3 ± r2) with γ(ρ) the angle at O4 of the triangle (r1, r4, ρ). The slider path is
perpendicular to the mid-swing line ψmid at distance h from O4; with δ = ψ − ψmid and C the pin
at r5 along the rocker:

    s(θ) = r5 sin δ + sqrt(r6² − (h − r5 cos δ)²)      (r6 = 0, slot drive: s = r5 sin δ)

==============  ======  =========================================================
name            symbol  meaning
==============  ======  =========================================================
ground          r1      crank pivot to rocker pivot, O2O4
crank           r2      crank O2A
coupler         r3      coupler AD
rocker          r4      rocker O4D
rocker_arm      r5      O4C, the pin on the rocker line (same side as D)
connecting_rod  r6      rod CR to the slider (0: slot drive)
slider_height   h       O4 to the slider path along the mid-swing line
==============  ======  =========================================================

Valid: Grashof with the crank the shortest link (a crank-rocker); r6 ≥ max |h − r5 cos δ| over
the swing when r6 > 0. Default h = r5 cos(Δψ/2), the path through C's extreme positions.
Transmission: coupler → rocker cos μ = (r3² + r4² − |AO4|²)/(2 r3 r4), extremes with the crank on
the ground line; rod → slider cos μ = (h − r5 cos δ)/r6. Closed forms: with φe,
φf the angles of O2D to the ground line at the toggles, TR = (π + |φf − φe|)/(π − |φf − φe|);
stroke = 2 r5 sin(Δψ/2) when s is monotonic over the swing: r6 cos(Δψ/2) ≥ |h − r5 cos(Δψ/2)|
(``one_way``).
"""

from __future__ import annotations

from typing import Any

import casadi as ca

from ..facts import Facts
from ..fourbar.geometry import fourbar_scale, grashof_conditions, output_pin
from ..fourbar.solver import FourBar, Roles
from ..geometry import cos_law, leg, triangle_angle
from ..registry import (
    GROUND,
    RAM,
    ROD,
    Frame,
    Mechanism,
    Parameter,
    Params,
    absent,
    one_way,
    reach_condition,
    register,
)

LINKS = ("ground", "crank", "coupler", "rocker")


def _swing(p: Params) -> tuple[Any, Any]:
    """(γ at the extended toggle, γ at the folded one); ψ = π − γ, Δψ = γe − γf."""
    r1, r2, r3, r4 = (p[n] for n in LINKS)
    return triangle_angle(r1, r4, r3 + r2), triangle_angle(r1, r4, r3 - r2)


def _mid(p: Params) -> tuple[Any, Any]:
    """The mid-swing line's direction from O4 (toward the slider)."""
    ge, gf = _swing(p)
    return -ca.cos((ge + gf) / 2), ca.sin((ge + gf) / 2)


def _delta(p: Params, th: Any) -> tuple[Any, Any, Any]:
    """cos δ, sin δ of the rocker relative to its mid-swing line, and cos μ at the coupler."""
    r1, r2, r3, r4 = (p[n] for n in LINKS)
    vx, vy, cos_mu = output_pin(r1, r2, r3, r4, th)
    ux, uy = vx / r4, vy / r4
    ge, gf = _swing(p)
    mx, my = -ca.cos((ge + gf) / 2), ca.sin((ge + gf) / 2)  # ψmid = π − (γe + γf)/2
    return mx * ux + my * uy, mx * uy - my * ux, cos_mu


def _offsets(p: Params) -> tuple[Any, Any]:
    """Signed distances from C to the slider path at mid-swing and at the swing's ends."""
    ge, gf = _swing(p)
    h, r5 = p["slider_height"], p["rocker_arm"]
    return h - r5, h - r5 * ca.cos((ge - gf) / 2)


def position(p: Params, th: Any) -> Any:
    r5, r6, h = p["rocker_arm"], p["connecting_rod"], p["slider_height"]
    c, s, _ = _delta(p, th)
    if absent(r6):
        return r5 * s
    return r5 * s + leg(r6, h - r5 * c)


def transmission(p: Params, th: Any) -> dict[str, Any]:
    r5, r6, h = p["rocker_arm"], p["connecting_rod"], p["slider_height"]
    c, _, cos_mu = _delta(p, th)
    joints = {"coupler-rocker": cos_mu}
    if not absent(r6):
        joints["connecting_rod-slider"] = (h - r5 * c) / r6
    return joints


def defaults(p: Params) -> dict[str, Any]:
    ge, gf = _swing(p)
    return {"slider_height": p["rocker_arm"] * ca.cos((ge - gf) / 2)}


def joints(p: Params, th: Any) -> dict[str, tuple[Any, Any]]:
    r1, r2, r4, r5 = p["ground"], p["crank"], p["rocker"], p["rocker_arm"]
    vx, vy, _ = output_pin(r1, r2, p["coupler"], r4, th)
    mx, my = _mid(p)
    h, s = p["slider_height"], position(p, th)  # R = O4 + h m + s m⊥, m⊥ = (−my, mx)
    return {
        "O2": (0.0, 0.0),
        "A": (r2 * ca.cos(th), r2 * ca.sin(th)),
        "O4": (r1, 0.0),
        "D": (r1 + vx, vy),
        "C": (r1 + r5 * vx / r4, r5 * vy / r4),
        "R": (r1 + h * mx - s * my, h * my + s * mx),
    }


def facts(p: Params) -> Facts:
    r1, r2, r3, r4 = (p[n] for n in LINKS)
    r5, r6 = p["rocker_arm"], p["connecting_rod"]
    # the folded toggle's O2D is shorter, so its angle to the ground line is the larger one
    dphi = triangle_angle(r1, r3 - r2, r4) - triangle_angle(r1, r3 + r2, r4)
    ge, gf = _swing(p)
    offsets = _offsets(p)
    rod = () if absent(r6) else tuple(t / r6 for t in offsets)
    return Facts(
        beta=dphi,
        stroke=2 * r5 * ca.sin((ge - gf) / 2),
        # coupler–rocker with the crank on the ground line; rod at mid-swing and swing ends
        transmission_cos=(cos_law(r3, r4, r1 - r2), cos_law(r3, r4, r1 + r2), *rod),
        one_way=() if absent(r6) else one_way(r6, ca.cos((ge - gf) / 2), offsets[1]),
    )


# the crank-rocker's ground, crank, coupler and rocker (a drag-link is its inversion)
ROLES = Roles(LINKS, "rocker_arm", "connecting_rod", "slider_height", swings=True)


def frame(variant: frozenset[str]) -> Frame:
    """The rocker and its arm are one body; C drives the slider through the rod, or through
    a block in the slider's slot across its path."""
    bodies = (("crank",), ("coupler",), ("rocker", "rocker_arm"))
    pins = (
        ("O2", "crank", GROUND),
        ("A", "crank", "coupler"),
        ("D", "coupler", "rocker"),
        ("O4", "rocker", GROUND),
    )
    if "connecting_rod" in variant:
        return Frame(bodies, pins, _path, slots=(("C", "rocker", RAM, None),))
    rod = (("C", "rocker", "connecting_rod"), ("R", "connecting_rod", RAM))
    return Frame((*bodies, ("connecting_rod",)), (*pins, *rod), _path)


def _path(p: Params) -> tuple[Any, Any]:
    """The slider's path, m⊥ (``joints``)."""
    mx, my = _mid(p)
    return -my, mx


register(
    Mechanism(
        type="crank_rocker_slider",
        title="Crank-rocker driven slider",
        description="A crank-rocker four-bar whose rocker drives a slider (piston) through a "
        "connecting rod or a slot; the rocker's unequal swing times give the quick return.",
        sources=("Podhorodeski et al. (2005)",),
        quick_return=True,
        parameters=(
            Parameter("ground", "r1", "crank pivot to rocker pivot, O2O4"),
            Parameter("crank", "r2", "crank O2A"),
            Parameter("coupler", "r3", "coupler AD"),
            Parameter("rocker", "r4", "rocker O4D"),
            Parameter("rocker_arm", "r5", "O4C: the pin on the rocker line driving the slider"),
            Parameter(
                "connecting_rod",
                "r6",
                "rod from C to the slider",
                default=0.0,
                zero_means="C drives the slider through a slot",
                bounds=ROD,
            ),
            Parameter(
                "slider_height",
                "h",
                "O4 to the slider path along the mid-swing line",
                default_rule="rocker_arm·cos(Δψ/2): the path through C's extreme positions",
                link=False,
            ),
        ),
        conditions=(
            *grashof_conditions(LINKS, "crank", "crank-rocker"),
            reach_condition(
                "rod_reach",
                "connecting_rod",
                "slider_height",
                "rocker_arm",
                _offsets,
                "the pin C",
                "slider",
            ),
        ),
        position=position,
        transmission=transmission,
        defaults=defaults,
        fourbar=lambda p: tuple(p[n] for n in LINKS),
        facts=facts,
        reduced=lambda p: FourBar(p, ROLES).solve(),
        construction=ROLES,
        scale=fourbar_scale("rocker"),
        joints=joints,
        frame=frame,
        drawing=(
            ("ground", "O2", "O4"),
            ("crank", "O2", "A"),
            ("coupler", "A", "D"),
            ("rocker", "O4", "D"),
            ("rocker_arm", "O4", "C"),
            ("connecting_rod", "C", "R"),
        ),
    )
)
