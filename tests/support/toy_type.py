"""Two more types, registered where ``SYNTH_TYPES=tests.support.toy_type`` names this module: what a
newcomer's seventh type looks like, and proof that the registry is the only list
(tests/library/test_seventh_type.py).

Centred slider-crank: the crank pin A = r(cos θ, sin θ) drives a slider on the x axis through
the crank pivot O2 by a coupler AB:

    s(θ) = r cos θ + sqrt(l² − r² sin² θ),    cos μ = r sin θ / l (at the slider's pin B)

=======  ======  ======================
name     symbol  meaning
=======  ======  ======================
crank    r       crank radius O2A
coupler  l       coupler AB to the slider
=======  ======  ======================

Time ratio 1, stroke 2r, the worst transmission cos μ = r/l at θ = ±90°; the crank turns fully
when l > r. No closed forms, no reduced solver: the synthesis formulates it from these
kinematics alone.

``offset_slider_crank_generic`` is the offset slider-crank without its closed forms and its
reduced solver: the same kinematics, synthesised by the generic path, for comparison with the
exact solver.
"""

from __future__ import annotations

from dataclasses import replace

import casadi as ca

import synth
from synth.mechanisms import Condition, Mechanism, Parameter, get
from synth.mechanisms.registry import ROD

TOY = "centred_slider_crank"
GENERIC = "offset_slider_crank_generic"


def position(p, th):
    r, rod = p["crank"], p["coupler"]
    return r * ca.cos(th) + ca.sqrt(rod * rod - (r * ca.sin(th)) ** 2)


def transmission(p, th):
    return {"B": p["crank"] * ca.sin(th) / p["coupler"]}


def joints(p, th):
    r = p["crank"]
    return {"O2": (0.0, 0.0), "A": (r * ca.cos(th), r * ca.sin(th)), "B": (position(p, th), 0.0)}


synth.register(
    Mechanism(
        type=TOY,
        title="Centred slider-crank",
        description="A crank driving a slider through a coupler, the slider's path through the "
        "crank pivot: time ratio 1.",
        sources=("the textbook chapter",),
        quick_return=False,
        parameters=(
            Parameter("crank", "r", "crank radius O2A"),
            Parameter("coupler", "l", "coupler AB to the slider", bounds=ROD),
        ),
        conditions=(
            Condition(
                name="crank_turns",
                text="coupler > crank",
                margin=lambda p: (p["coupler"] - p["crank"],),
                explain=lambda p: (
                    f"coupler {p['coupler']:g} ≤ crank {p['crank']:g}: the crank cannot turn fully"
                ),
                strict=True,
            ),
        ),
        position=position,
        transmission=transmission,
        joints=joints,
    )
)
synth.register(replace(get("offset_slider_crank"), type=GENERIC, facts=None, reduced=None))
