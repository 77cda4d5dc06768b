"""Polymorphic planar-geometry primitives for the mechanism models.

Everything here is written with ``casadi`` maths only, so the same function runs on floats
(analysis), on ``SX``/``MX`` (the IPOPT formulation) and inside root finders. Formulas are chosen
to keep precision near dead points: products of sums and differences instead of differences of
squares, ``atan2`` instead of ``acos`` (the README, *Numerical stability*).
"""

from __future__ import annotations

from typing import Any, TypeVar

import casadi as ca

S = TypeVar("S", float, ca.DM, ca.SX, ca.MX)


def sqrt(x: S) -> S:
    """sqrt(max(x, 1e-300)): a root whose argument is negative only by rounding (a design
    exactly on a limit, checked by the validity conditions) is 0, not NaN, and its slope stays
    finite (0 below the floor). An optimiser's iterate that leaves the valid region between
    steps sees a flat extension and is pulled back by the validity constraints."""
    return ca.sqrt(ca.fmax(x, 1e-300))


def where(cond: Any, a: S, b: S) -> S:
    """a where cond else b, on floats (a Python branch) or symbols (``if_else``; the branch not
    taken may be inf or NaN without harm)."""
    if isinstance(cond, bool):
        return a if cond else b
    # the stubs give Any where ``cond`` leaves the overload open (float, DM)
    return ca.if_else(cond, a, b)  # type: ignore[no-any-return]


def unit(x: S, y: S) -> tuple[S, S]:
    """The unit vector along (x, y)."""
    r = sqrt(x * x + y * y)
    return x / r, y / r


def lever(r2: S, d: S, th: S) -> tuple[S, S]:
    """The unit vector from the pivot (−d, 0) to the crank pin r2(cos θ, sin θ).

    Its x-component d + r2 cos θ is written (d − r2) + 2 r2 cos²(θ/2): exact when the pin
    passes near the pivot (d ≈ r2, the largest time ratios), where the plain sum cancels."""
    return unit((d - r2) + 2 * r2 * ca.cos(th / 2) ** 2, r2 * ca.sin(th))


def ahead(a: S, root: S, gap: S) -> S:
    """a + root, the slider ahead of its pin: a is the pin's offset along the path and root the
    rod's along-path reach, sqrt(l² − b²). Where a < 0 the sum cancels (a rod barely longer
    than the arm, near its dead point), so there it is gap/(root − a) with gap = l² − a² − b²
    supplied without cancellation (e.g. (l − r)(l + r) for a pin on a circle of radius r)."""
    return where(a < 0, gap / (root - a), a + root)


def leg(hyp: S, side: S) -> S:
    """sqrt(hyp² − side²), the other leg of a right triangle, written to keep precision."""
    return sqrt((hyp - side) * (hyp + side))


def triangle_angle(a: S, b: S, c: S) -> S:
    """The angle between sides a and b of a triangle whose third side is c (law of cosines).

    Uses ``atan2(sqrt(Heron), a² + b² − c²)``: accurate also when the triangle is flat.
    """
    area16 = (a + b + c) * (-a + b + c) * (a - b + c) * (a + b - c)
    return ca.atan2(sqrt(area16), (a - b) * (a - b) + 2 * a * b - c * c)


def cos_law(a: S, b: S, c: S) -> S:
    """cos of the angle between sides a and b of a triangle with third side c."""
    return ((a - c) * (a + c) + b * b) / (2 * a * b)
