"""Drag-link (crank-crank) four-bar driving a piston — Podhorodeski et al. (2005), Fig. 2b,
Fig. 3, eqs. 2–13.

O2 at the origin, O4 = (r1, 0), crank pin A = r2(cos θ, sin θ); the follower pin B is the
intersection of circle(A, r3) and circle(O4, r4) left of A→O4, and the follower turns fully.
The pin C = O4 + r5 (B − O4)/r4 drives the piston on the ground line through the rod CD:

    s(θ) = C_x + sqrt(r6² − C_y²)

==============  ======  ===============================================
name            symbol  meaning
==============  ======  ===============================================
ground          r1      crank pivot to follower pivot, O2O4
crank           r2      crank O2A
coupler         r3      coupler AB
follower        r4      follower O4B
follower_arm    r5      O4C, on the follower line, same side as B
connecting_rod  r6      rod CD to the piston
==============  ======  ===============================================

Valid: Grashof with the ground the shortest link (a drag-link); r6 > r5. Closed forms
(Podhorodeski et al. 2005):
TDC/BDC with the follower on the ground line, O2B = r4 ± r1; θ2a, θ2b from eqs. (3a)/(3b);
TR = (π − θ2a + θ2b)/(π + θ2a − θ2b); stroke = 2 r5; rod → piston μ_min = acos(r5/r6).
Coupler → follower: cos μ = (r3² + r4² − |AO4|²)/(2 r3 r4), extremes with the *crank* on the
ground line, |AO4| = r2 ∓ r1 (not at TDC/BDC, where Podhorodeski et al. evaluate it: not the
minimum).
"""

from __future__ import annotations

import math
from typing import Any

import casadi as ca
import numpy as np

from ...numerics import ROUNDING
from ..facts import Facts
from ..fourbar.geometry import (
    fourbar_scale,
    grashof_conditions,
    output_pin,
    output_pin_height,
    worst_cos,
)
from ..fourbar.solver import FourBar, Roles
from ..geometry import ahead, cos_law, leg, triangle_angle
from ..reduced import Problem, Reduced, agree, differ, unreachable
from ..registry import GROUND, RAM, ROD, Condition, Frame, Mechanism, Parameter, Params, register
from ..rod import rod

LINKS = ("ground", "crank", "coupler", "follower")


def _pin_c(p: Params, th: Any) -> tuple[Any, Any, Any]:
    r1, r2, r3, r4 = (p[n] for n in LINKS)
    vx, vy, cos_mu = output_pin(r1, r2, r3, r4, th)
    k = p["follower_arm"] / r4
    return r1 + k * vx, k * vy, cos_mu


def position(p: Params, th: Any) -> Any:
    cx, cy, _ = _pin_c(p, th)
    r1, r5, r6 = p["ground"], p["follower_arm"], p["connecting_rod"]
    return r1 + ahead(cx - r1, leg(r6, cy), (r6 - r5) * (r6 + r5))


def dead_centres(p: Params, th: Any) -> Any:
    """B_y: the piston is at a dead centre exactly when the follower lies on the ground line,
    as ds/dθ = −r5 φ' sin φ (1 + r5 cos φ/root), the last factor > 0 (r6 > r5). Near a change
    point the follower nearly stalls right there (the four-bar folds flat onto the ground
    line), so ds/dθ has a near-triple zero that double precision locates only to ~1e-5 rad,
    while B_y's zero is simple; near a kite's, B passes the crank pivot, where B_y is taken
    from O2 to keep its own digits."""
    r1, r2, r3, r4 = (p[n] for n in LINKS)
    return output_pin_height(r1, r2, r3, r4, th)


def transmission(p: Params, th: Any) -> dict[str, Any]:
    _, cy, cos_mu = _pin_c(p, th)
    return {"coupler-follower": cos_mu, "connecting_rod-slider": cy / p["connecting_rod"]}


def joints(p: Params, th: Any) -> dict[str, tuple[Any, Any]]:
    r1, r2, r4, r5 = p["ground"], p["crank"], p["follower"], p["follower_arm"]
    vx, vy, _ = output_pin(r1, r2, p["coupler"], r4, th)
    return {
        "O2": (0.0, 0.0),
        "A": (r2 * ca.cos(th), r2 * ca.sin(th)),
        "O4": (r1, 0.0),
        "B": (r1 + vx, vy),
        "C": (r1 + r5 * vx / r4, r5 * vy / r4),
        "D": (position(p, th), 0.0),
    }


def facts(p: Params) -> Facts:
    r1, r2, r3, r4 = (p[n] for n in LINKS)
    r5, r6 = p["follower_arm"], p["connecting_rod"]
    t2a = triangle_angle(r2, r4 + r1, r3)  # eq. (3a)
    t2b = triangle_angle(r2, r4 - r1, r3)  # eq. (3b)
    return Facts(
        beta=t2b - t2a,  # eq. (5): TR = (π − θ2a + θ2b)/(π + θ2a − θ2b)
        stroke=2 * r5,
        # coupler–follower with the crank on the ground line; rod with the follower upright
        transmission_cos=(cos_law(r3, r4, r2 - r1), cos_law(r3, r4, r2 + r1), r5 / r6),
        crank_at_max=t2a,
    )


def reduced(p: Problem) -> Reduced | None:
    """Podhorodeski, Nokleby & Wittchen (2005), eqs. (7)–(13), where ground, crank and
    follower are fixed: zero, one or two couplers give the time ratio (follower_arm =
    stroke/2, the rod by ``rod.rule``); any other problem goes to the four-bar solver
    (``fourbar.solver``)."""
    if "follower_arm" in p.fixed and not agree(2 * p.fixed["follower_arm"], 1.0):
        raise unreachable(
            "follower_arm {} gives stroke {}, not {}".format(
                p.shown(p.fixed["follower_arm"]),
                *differ(2 * p.fixed["follower_arm"] * p.stroke, p.stroke),
            )
        )
    if not {"ground", "crank", "follower"} <= p.fixed.keys() or "coupler" in p.fixed:
        return FourBar(p, ROLES).solve()
    r1, r2, r4 = p.fixed["ground"], p.fixed["crank"], p.fixed["follower"]
    f = p.beta  # eq. (7): θ2b = θ2a + f
    a = (r4 + r1) - (r4 - r1) * math.cos(f)  # eqs. (10)–(11): A cos θ2a + B sin θ2a = C
    b = (r4 - r1) * math.sin(f)
    c = 2 * r4 * r1 / r2
    rr = math.hypot(a, b)
    if rr < c * (1 - ROUNDING):
        return Reduced([])
    # eq. (12) in the double-root-safe form atan2(sqrt((R − C)(R + C)), C); at the time
    # ratio's extreme over the coupler the roots merge (R = C, up to rounding)
    half = math.atan2(math.sqrt(max(rr - c, 0.0) * (rr + c)), c)
    arm = p.fixed.get("follower_arm", 0.5)
    if not p.allows("follower_arm", arm):
        return Reduced([])
    t2a = np.array(sorted({math.atan2(b, a) - half, math.atan2(b, a) + half}))
    couplers = np.sqrt(r2**2 + (r4 + r1) ** 2 - 2 * r2 * (r4 + r1) * np.cos(t2a))  # eq. (13)
    # the crank-rocker each inverts, ground 1: crank r1/r2, coupler r4/r2, rocker r3/r2
    cos_mu = np.array([worst_cos(1.0, r1 / r2, r4 / r2, c) for c in couplers / r2])
    rods = rod(p, "connecting_rod", None, np.full(couplers.shape, arm), 0.0, cos_mu)[0]
    designs = [
        {"coupler": float(coupler), "follower_arm": arm, "connecting_rod": float(length), **p.fixed}
        for coupler, length in zip(couplers, rods, strict=True)
        if p.allows("coupler", coupler) and math.isfinite(length)
    ]
    return Reduced(designs)


# the crank-rocker's ground, crank, coupler and rocker (a drag-link is its inversion)
ROLES = Roles(
    ("crank", "ground", "follower", "coupler"), "follower_arm", "connecting_rod", None, swings=False
)

# the follower and its arm are one body
FRAME = Frame(
    bodies=(("crank",), ("coupler",), ("follower", "follower_arm"), ("connecting_rod",)),
    pins=(
        ("O2", "crank", GROUND),
        ("A", "crank", "coupler"),
        ("B", "coupler", "follower"),
        ("O4", "follower", GROUND),
        ("C", "follower", "connecting_rod"),
        ("D", "connecting_rod", RAM),
    ),
    path=lambda p: (1.0, 0.0),
)


register(
    Mechanism(
        type="drag_link_slider",
        title="Drag-link driven slider",
        description="A drag-link (crank-crank) four-bar whose follower drives a piston on the "
        "ground line; the follower's non-uniform rotation gives the quick return.",
        sources=("Podhorodeski et al. (2005)",),
        quick_return=True,
        parameters=(
            Parameter("ground", "r1", "crank pivot to follower pivot, O2O4"),
            Parameter("crank", "r2", "crank O2A"),
            Parameter("coupler", "r3", "coupler AB"),
            Parameter("follower", "r4", "follower O4B"),
            Parameter("follower_arm", "r5", "O4C: the pin on the follower line driving the rod"),
            Parameter("connecting_rod", "r6", "rod CD from C to the piston", bounds=ROD),
        ),
        conditions=(
            *grashof_conditions(LINKS, "ground", "drag-link"),
            Condition(
                name="rod_reach",
                text="connecting_rod > follower_arm (the rod reaches the piston path)",
                margin=lambda p: (p["connecting_rod"] - p["follower_arm"],),
                strict=True,
                explain=lambda p: (
                    f"connecting_rod {p['connecting_rod']:g} ≤ follower_arm "
                    f"{p['follower_arm']:g}: the rod cannot reach the piston path when the "
                    f"follower is perpendicular to it"
                ),
            ),
        ),
        position=position,
        transmission=transmission,
        dead_centres=dead_centres,
        fourbar=lambda p: tuple(p[n] for n in LINKS),
        facts=facts,
        reduced=reduced,
        construction=ROLES,
        scale=fourbar_scale("follower"),
        joints=joints,
        frame=lambda variant: FRAME,
        drawing=(
            ("ground", "O2", "O4"),
            ("crank", "O2", "A"),
            ("coupler", "A", "B"),
            ("follower", "O4", "B"),
            ("follower_arm", "O4", "C"),
            ("connecting_rod", "C", "D"),
        ),
    )
)
