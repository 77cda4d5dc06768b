"""Scotch yoke (slotted link) — the slotted-link lab handout.

The crank pin B = r(cos θ, sin θ) slides in a slot of the yoke, which moves along x:

    s(θ) = r cos θ        (measured from one extreme, x = r(1 − cos θ): the same curve)

=====  ==========  =========================
name   symbol      meaning
=====  ==========  =========================
crank  r           crank radius O2B
=====  ==========  =========================

Time ratio 1 (simple harmonic motion: the baseline, not a quick return), stroke 2r; the slot
drives along the slot's normal, so the transmission angle is 90° throughout.
"""

from __future__ import annotations

import math
from typing import Any

import casadi as ca

from ...errors import Unreachable
from ...results import TOL
from ..facts import Facts
from ..reduced import Problem, Reduced, Space, judge
from ..registry import GROUND, RAM, Frame, Mechanism, Parameter, Params, register


def position(p: Params, th: Any) -> Any:
    return p["crank"] * ca.cos(th)


def transmission(p: Params, th: Any) -> dict[str, Any]:
    return {}


def joints(p: Params, th: Any) -> dict[str, tuple[Any, Any]]:
    r = p["crank"]
    return {"O2": (0.0, 0.0), "B": (r * ca.cos(th), r * ca.sin(th)), "yoke": (position(p, th), 0.0)}


def facts(p: Params) -> Facts:
    return Facts(beta=0.0, stroke=2 * p["crank"], transmission_cos=())


def reduced(p: Problem) -> Reduced:
    """crank = stroke/2; the time ratio is 1 for every design."""
    if p.beta > math.pi / 2 * TOL:  # time ratio 1 to the verification's tolerance
        raise Unreachable(
            "TIME_RATIO_UNREACHABLE",
            f"scotch_yoke has time ratio 1 for every design, not {p.ratio:.9g}",
        )
    if "crank" in p.fixed:
        judge(p, facts, dict(p.fixed))  # stroke = 2 crank
    elif not p.allows("crank", 0.5):
        return Reduced([])
    return Reduced([{"crank": p.fixed.get("crank", 0.5)}])


def space(p: Problem) -> Space | None:
    """One design, ``reduced``'s (its box a point): the certified search measures it, and its
    measure is the least; the dead centres at θ = 0 and π."""
    if p.beta > math.pi / 2 * TOL:
        return None
    crank = p.fixed.get("crank", 0.5)
    return Space((0.0,), (0.0,), (crank,), lambda u, k: {"crank": k[0]}, dead=_dead)


def _dead(k: Any) -> tuple[float, float]:
    return 0.0, math.pi


# the crank pin's block slides in the yoke's slot, across the yoke's path
FRAME = Frame(
    bodies=(("crank",),),
    pins=(("O2", "crank", GROUND),),
    path=lambda p: (1.0, 0.0),
    slots=(("B", "crank", RAM, None),),
)


register(
    Mechanism(
        type="scotch_yoke",
        title="Scotch yoke (slotted link)",
        description="A crank pin sliding in a slotted yoke: simple harmonic motion, time ratio 1. "
        "The baseline every quick-return mechanism is compared with.",
        sources=("the slotted-link lab handout",),
        quick_return=False,
        parameters=(Parameter("crank", "r", "crank radius O2B"),),
        conditions=(),
        position=position,
        transmission=transmission,
        facts=facts,
        reduced=reduced,
        space=space,
        joints=joints,
        frame=lambda variant: FRAME,
        drawing=(("crank", "O2", "B"),),
    )
)
