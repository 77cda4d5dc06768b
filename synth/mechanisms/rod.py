"""The rule for a connecting rod from a pin to a straight path, shared by the types with one:
written once (``rule``), compiled on its own for the closed forms' few designs (``rod``) and
built into the four-bar construction's function."""

from __future__ import annotations

import math
import threading
from collections.abc import Mapping
from typing import Any, cast

import casadi as ca
import numpy as np

from ..numerics import ROUNDING
from ..numerics.native import Points
from ..numerics.ops import CASADI, Ops
from ..targets import MIN_SIZE
from .reduced import ONE_WAY, STRICT, Problem

_local = threading.local()

# the rule's parameters: the objective, the rod's box and its path's placement
PARAMS = (
    "min_size",
    "cos_bound",
    "rod_lo",
    "rod_hi",
    "on_line",
    "height_fixed",
    "height",
    "height_lo",
    "height_hi",
)


def rule(
    arm: Any, half: Any, cos_other: Any, q: Mapping[str, Any], ops: Ops = CASADI
) -> tuple[Any, Any, Any, Any]:
    """The connecting rod from a pin at ``arm`` from its pivot to a straight path: its
    length l, its path's placement h and its worst cos μ.

    A pin that swings ±``half`` about the path's normal (a placement h; ``on_line`` 0)
    transmits worst at mid-swing or at the swing's ends, where its offset from the path is
    g1 = |h − arm| or g2 = |h − arm x|, x = cos(half). The slider moves one way over the swing
    (so the swing's ends are its dead centres, as the closed forms take them) exactly when
    g2 ≤ x l: at the ends the rod may not lean further from the path's normal than the pin's
    own turn (kept ``ONE_WAY`` from it). The shortest rod with worst cos ≤ c is then
    max(g1/c, g2/m), m = min(c, x − ONE_WAY), least at h = arm (m + c x)/(m + c) (the
    midpoint when x > c). With max transmission, c is ``cos_other``, the other joints' worst
    cos: a rod that cannot transmit as well within its upper bound sits there, h at the
    midpoint (the least worst offset) as far as the one way allows; else the shortest rod
    that transmits no worse (ties go to the smaller design). With min size c is cos(bound).
    A pin that turns fully about a centre on the path (``on_line`` 1) needs l > arm, and
    transmits worst at w = arm.

    Returns (l, h, the rod's worst cos, l_ok), with ``q`` the entries of ``PARAMS``, in
    CasADi symbols or numpy arrays (``ops``); where the bounds allow no rod, l_ok is false and
    l, and where no h is found h, are NaN (flags, not NaN propagation: fmin and fmax drop a
    NaN).
    """
    nan, inf = math.nan, math.inf
    rlo, rhi = q["rod_lo"], q["rod_hi"]
    c = ops.if_else(q["min_size"], q["cos_bound"], cos_other)

    def along_line() -> tuple[Any, ...]:  # the pin turns fully about a centre on the path
        short = ops.fmax(ops.fmax(rlo, arm / c), arm + STRICT)
        at_most = ops.if_else(short <= rhi, short, rhi)
        length = ops.if_else(q["min_size"], short, at_most)
        return length, arm, nan, False, False  # length, w, h, no length, no h

    def swinging() -> tuple[Any, ...]:
        xc = ops.cos(half)
        m_ok = xc > ONE_WAY  # no rod moves the slider one way past ±90° (less the margin)
        m = ops.fmin(c, xc - ONE_WAY)
        pos = c > 0

        def place(h: Any) -> Any:  # the caller's placement, or one within its bounds
            within = ops.fmin(ops.fmax(h, q["height_lo"]), q["height_hi"])
            return ops.if_else(q["height_fixed"], q["height"], within)

        # the shortest rod with worst cos ≤ c; none to find where c = 0 (nothing else limits
        # the transmission: the rod sits at its upper bound)
        h = place(ops.if_else(pos, arm * (m + c * xc) / ops.if_else(pos, m + c, 1.0), arm))
        g1, g2 = ops.fabs(h - arm), ops.fabs(h - arm * xc)
        short = ops.if_else(pos, ops.fmax(rlo, ops.fmax(g1 / c, g2 / m)), inf)
        short_nan = ops.logic_and(pos, ops.logic_not(m_ok))
        h_nan = ops.logic_and(short_nan, ops.logic_not(q["height_fixed"]))

        def shortest() -> tuple[Any, ...]:  # the smallest design: the shortest rod
            return short, short_nan, h, h_nan

        def limited() -> tuple[Any, ...]:  # else the upper bound where the shortest is past it
            # at the upper bound: the midpoint, moved as little as the one way needs
            lean = (xc - ONE_WAY) * rhi  # the most the one way allows at the upper bound
            mid = place(ops.fmin(ops.fmax(arm * (1 + xc) / 2, arm * xc - lean), arm * xc + lean))
            limited_ok = ops.fabs(mid - arm * xc) <= lean * (1 + ROUNDING)
            use_short = ops.logic_and(ops.logic_not(short_nan), short <= rhi)
            neither = ops.logic_and(ops.logic_not(use_short), ops.logic_not(limited_ok))
            return (
                ops.if_else(use_short, short, rhi),
                neither,
                ops.if_else(use_short, h, mid),
                ops.logic_and(h_nan, use_short),
            )

        length, no_length, h, no_h = ops.choose(q["min_size"], shortest, limited)
        w = ops.fmax(ops.fabs(h - arm), ops.fabs(h - arm * xc))
        return length, w, ops.if_else(no_h, nan, h), no_length, no_h

    length, w, rod_h, no_length, no_h = ops.choose(q["on_line"], along_line, swinging)
    within_box = ops.logic_and(length <= rhi * (1 + ROUNDING), length < inf)
    l_ok = ops.logic_and(ops.logic_not(no_length), within_box)
    l_ok = ops.logic_and(l_ok, ops.fmin(length, rhi) < inf)
    rod_l = ops.if_else(l_ok, ops.fmin(length, rhi), nan)
    rod_cos = ops.if_else(ops.logic_and(l_ok, ops.logic_not(no_h)), w / ops.fmin(length, rhi), nan)
    return rod_l, rod_h, rod_cos, l_ok


def switches(arm: np.ndarray, half: np.ndarray, q: Mapping[str, float]) -> list[np.ndarray]:
    """Where ``rule``'s rod from a swinging pin changes formula or stops fitting: margins,
    each smooth in the swing, that change sign exactly there. The smallest design's
    (shortest) rod, c = cos(bound): the one-way limit taking over from c; the placement
    reaching its bounds, or a fixed one crossing the pin's end positions or handing the
    worst offset from one to the other; the lower bound taking over; the upper one passed.
    With max transmission, where a rod fits at all: a rod at its upper bound, placed
    within the one-way limit."""
    xc = np.cos(half)
    if not q["min_size"]:
        lean = (xc - ONE_WAY) * q["rod_hi"]
        mid = np.clip(arm * (1 + xc) / 2, arm * xc - lean, arm * xc + lean)
        mid = (
            np.full_like(arm, q["height"])
            if q["height_fixed"]
            else np.clip(mid, q["height_lo"], q["height_hi"])
        )
        return [lean * (1 + ROUNDING) - np.abs(mid - arm * xc)]
    c = q["cos_bound"]
    m = np.minimum(c, xc - ONE_WAY)
    out = [c - (xc - ONE_WAY)]
    if q["height_fixed"]:
        h: np.ndarray = np.full_like(arm, q["height"])
    else:
        raw = arm * (m + c * xc) / (m + c)
        out += [raw - q["height_lo"], q["height_hi"] - raw]
        h = np.clip(raw, q["height_lo"], q["height_hi"])
    g1, g2 = np.abs(h - arm), np.abs(h - arm * xc)
    out += [h - arm, h - arm * xc]
    if q["height_fixed"]:
        out.append(g1 / c - g2 / m)
    short = np.maximum(g1 / c, g2 / m)
    return [*out, short - q["rod_lo"], q["rod_hi"] - short]


def params(p: Problem, name: str, height: str | None) -> list[float]:
    """``PARAMS`` for the rod ``name`` of a problem (``height``: its path's placement, None for a
    path through the pivot)."""
    lo, hi = p.box(name)
    fixed = height is not None and height in p.fixed
    h_box = p.bounds.get(height, (0.0, 0.0)) if height is not None else (0.0, 0.0)
    return [
        float(p.objective == MIN_SIZE),
        p.cos_bound,
        lo,
        hi,
        float(height is None),
        float(fixed),
        p.fixed[height] if height is not None and fixed else 0.0,
        *h_box,
    ]


def rod(
    p: Problem, name: str, height: str | None, arm: Any, half: Any, cos_other: Any
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``rule`` at the points (arm, half, cos_other), arrays broadcast together: (l, h, the rod's
    worst cos); l is NaN where the bounds allow no rod."""
    x = [np.asarray(a, dtype=float) for a in (arm, half, cos_other)]
    shape = np.broadcast_shapes(*(a.shape for a in x))
    columns = [(a if a.shape == shape else np.broadcast_to(a, shape)).ravel() for a in x]
    out = compiled()(columns, params(p, name, height))
    return out[0].reshape(shape), out[1].reshape(shape), out[2].reshape(shape)


def compiled() -> Points:
    """This thread's ``rule`` compiled: at x = (arm, half, cos_other) with the parameters p
    (``PARAMS``), the rows l, h and the rod's worst cos (a closed form's few designs)."""
    if not hasattr(_local, "points"):
        x, q = ca.SX.sym("x", 3), ca.SX.sym("p", len(PARAMS))
        l, h, c, _ = rule(x[0], x[1], x[2], {n: q[i] for i, n in enumerate(PARAMS)})
        fn = ca.Function("connecting_rod", [x, q], [ca.vertcat(l, h, c)], {"cse": True})
        _local.points = Points(fn)
    return cast(Points, _local.points)
