"""The types' closed forms (their modules' docstrings, docs/model.md) in 50-digit
arithmetic (mpmath): the referee where a design sits so near a dead point that double precision
cannot resolve its dead centres in a plain forward simulation (a coupler at its reach: s has a
square-root kink there).

Valid where the slider's extremes are the driving link's extremes, i.e. every type but the
ram-link / connecting-rod variants with a non-default path height. Written here from the
contract, sharing nothing with synth.
"""

from mpmath import acos as _acos
from mpmath import asin as _asin
from mpmath import mp, mpf, pi
from mpmath import sin as _sin
from mpmath import sqrt as _sqrt

mp.dps = 50


def _tr(beta):
    beta = abs(beta)
    return (pi + beta) / (pi - beta)


def _angle(a, b, c):
    """The angle between sides a and b of a triangle with third side c."""
    x = (a * a + b * b - c * c) / (2 * a * b)
    return _acos(max(min(x, mpf(1)), mpf(-1)))


def _leg(h, s):
    return _sqrt(max((h - s) * (h + s), mpf(0)))


def time_ratio_and_stroke(mtype: str, p: dict) -> tuple[float, float] | None:
    r = _exact(mtype, {k: mpf(v) for k, v in p.items()})
    return None if r is None else (float(r[0]), float(r[1]))


def condition(mtype: str, p: dict) -> float:
    """The relative condition number of (time ratio, stroke) in the parameters: what a
    relative rounding of 1e-16 in any input or intermediate becomes in the result. A
    double-precision computation cannot do better than about eps × this."""
    q = {k: mpf(v) for k, v in p.items()}
    base = _exact(mtype, q)
    h = mpf("1e-25")
    worst = mpf(0)
    for k in q:
        if q[k] == 0:
            continue
        moved = _exact(mtype, {**q, k: q[k] * (1 + h)})
        for b, m in zip(base, moved, strict=True):
            worst = max(worst, abs(m - b) / (abs(b) * h))
    return float(worst)


def _exact(mtype: str, q: dict):
    if mtype == "offset_slider_crank":
        r2, r3, e = q["crank"], q["coupler"], abs(q["offset"])
        beta = _asin(min(e / (r3 - r2), mpf(1))) - _asin(e / (r3 + r2))
        return _tr(beta), _leg(r3 + r2, e) - _leg(r3 - r2, e)
    if mtype == "crank_shaper" and not q.get("ram_link"):
        r2, d = q["crank"], q["pivot_distance"]
        return _tr(2 * _asin(r2 / d)), 2 * q["lever"] * r2 / d
    if mtype == "whitworth":
        qq = _acos(q["pivot_distance"] / q["crank"])
        return (pi - qq) / qq, 2 * q["lever"]
    if mtype == "crank_rocker_slider" and not q.get("connecting_rod"):
        r1, r2, r3, r4 = q["ground"], q["crank"], q["coupler"], q["rocker"]
        swing = _angle(r1, r4, r3 + r2) - _angle(r1, r4, r3 - r2)
        dphi = _angle(r1, r3 - r2, r4) - _angle(r1, r3 + r2, r4)
        return _tr(dphi), 2 * q["rocker_arm"] * _sin(swing / 2)
    if mtype == "drag_link_slider":
        r1, r2, r3, r4 = q["ground"], q["crank"], q["coupler"], q["follower"]
        beta = _angle(r2, r4 - r1, r3) - _angle(r2, r4 + r1, r3)
        return _tr(beta), 2 * q["follower_arm"]
    if mtype == "scotch_yoke":
        return mpf(1), 2 * q["crank"]
    return None
