"""Polymorphic planar-geometry primitives for the mechanism models.

Everything here is written with ``casadi`` maths only, so the same function runs on floats
(analysis), on ``SX``/``MX`` (the IPOPT formulation) and inside root finders. Formulas are chosen
to keep precision near dead points: products of sums and differences instead of differences of
squares, ``atan2`` instead of ``acos`` (see ``shared/design/numerics.md``).
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from typing import TypeVar

import casadi as ca

S = TypeVar("S", float, ca.DM, ca.SX, ca.MX)

# Inside a formulation, square roots are extended past their domain (an optimiser's iterate may
# leave the valid region between steps; the validity constraints bring it back). Analysis never
# sets this: there a negative argument is a design that cannot run, and shows as NaN.
_EXTENDED = ContextVar("extended_domain", default=False)


@contextmanager
def extended_domain() -> Iterator[None]:
    token = _EXTENDED.set(True)
    try:
        yield
    finally:
        _EXTENDED.reset(token)


def sqrt(x: S) -> S:
    """sqrt; in an extended-domain block, sqrt(max(x, 1e-300)): finite, zero slope below 0."""
    return ca.sqrt(ca.fmax(x, 1e-300)) if _EXTENDED.get() else ca.sqrt(x)


def unit(x: S, y: S) -> tuple[S, S]:
    """The unit vector along (x, y)."""
    r = sqrt(x * x + y * y)
    return x / r, y / r


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


def circle_circle_left(ax: S, ay: S, ra: S, bx: S, by: S, rb: S) -> tuple[S, S]:
    """The intersection of circle(A, ra) and circle(B, rb) to the left of the directed line A→B.

    The assembly branch is explicit: the mirror circuit is the other intersection.
    """
    dx, dy = bx - ax, by - ay
    d2 = dx * dx + dy * dy
    along = (d2 + (ra - rb) * (ra + rb)) / (2 * d2)  # distance from A along A→B, over |AB|
    d = sqrt(d2)
    # height = sqrt(Heron product)/(2 d); divided by d once more to scale the left normal (−dy, dx)
    across = sqrt((ra + rb - d) * (ra + rb + d) * (d - ra + rb) * (d + ra - rb)) / (2 * d2)
    return ax + along * dx - across * dy, ay + along * dy + across * dx
