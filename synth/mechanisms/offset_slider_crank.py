"""Offset slider-crank — seed 002, Fig. 1a.

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
between BC and the path's normal, cos μ = (e − B_y)/r3. Closed forms (mechanisms.md):
stroke = sqrt((r3+r2)² − e²) − sqrt((r3−r2)² − e²); β = asin(|e|/(r3−r2)) − asin(|e|/(r3+r2));
TR = (π+β)/(π−β); μ_min = acos((r2+|e|)/r3).
"""

from __future__ import annotations

import math

import casadi as ca

from ..geometry import leg, sqrt, where
from ._registry import Condition, Mechanism, Parameter, Unreachable, register


def position(p, th):
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


def transmission(p, th):
    r2, r3, e = p["crank"], p["coupler"], p["offset"]
    return {"coupler-slider": (e - r2 * ca.sin(th)) / r3}


def joints(p, th):
    r2 = p["crank"]
    return {"O2": (0.0, 0.0), "B": (r2 * math.cos(th), r2 * math.sin(th)),
            "C": (float(position(p, th)), p["offset"])}  # fmt: skip


def facts(p):
    r2, r3, e = p["crank"], p["coupler"], p["offset"]
    # β = asin(e/(r3−r2)) − asin(e/(r3+r2)) with atan2; odd in e: TR < 1 is the mirror's 1/TR
    beta = ca.atan2(e, leg(r3 - r2, e)) - ca.atan2(e, leg(r3 + r2, e))
    return {
        "beta": beta,
        "stroke": leg(r3 + r2, e) - leg(r3 - r2, e),
        "transmission_cos": ((e + r2) / r3, (e - r2) / r3),  # B_y = ∓r2
    }


def inverse(fixed, tr, stroke):
    """With the offset fixed: the folded dead centre's x1 solves
    x1² + S x1 + e² − e S / tan β = 0 (tan β from the two dead centres' directions); then
    crank = (v − u)/2, coupler = (u + v)/2 with u = |O2C1|, v = |O2C2|."""
    if "offset" not in fixed or {"crank", "coupler"} & fixed.keys():
        return None
    e, s = abs(fixed["offset"]), stroke
    beta = math.pi * (tr - 1) / (tr + 1)
    if (beta == 0) != (e == 0):  # TR 1 if and only if the slider path is centred
        raise Unreachable(
            "FIXED_PARTS_CONTRADICT_TARGETS",
            f"offset {fixed['offset']:g} gives time ratio {'1' if e == 0 else '> 1'}, not {tr:g}",
        )
    if e == 0:
        return None  # centred: crank = stroke/2 and any longer coupler, a family
    disc = s * s - 4 * e * e + 4 * e * s / math.tan(beta)
    x1 = (-s + math.sqrt(disc)) / 2 if disc > 0 else -1.0
    if x1 <= 0:
        raise Unreachable(
            "FIXED_PARTS_CONTRADICT_TARGETS",
            f"offset {fixed['offset']:g} is too large for time ratio {tr:g} and stroke {s:g}: "
            f"needs |offset| < stroke/tan β = {s / math.tan(beta):.9g}",
        )
    u, v = math.hypot(x1, e), math.hypot(x1 + s, e)
    return [{"crank": (v - u) / 2, "coupler": (u + v) / 2}]


register(
    Mechanism(
        type="offset_slider_crank",
        title="Offset slider-crank",
        description="A slider-crank whose slider path is offset from the crank pivot; the offset "
        "makes the two strokes take different crank angles.",
        seeds=("002_9eb3d3dc2e472629.txt",),
        quick_return=True,
        parameters=(
            Parameter("crank", "r2", "crank O2B"),
            Parameter("coupler", "r3", "connecting rod BC (crank pin to slider)"),
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
                params=("coupler", "crank", "offset"),
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
        inverse=inverse,
        joints=joints,
    )
)
