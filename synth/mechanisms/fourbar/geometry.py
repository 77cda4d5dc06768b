"""Shared four-bar pieces: the output pin, Grashof conditions and class.

O2 at the origin, O4 = (ground, 0), crank pin A = crank·(cos θ, sin θ); the output pin D is the
intersection of circle(A, coupler) and circle(O4, rocker) to the left of the directed line A→O4.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import casadi as ca

from ...numerics import ROUNDING
from ...numerics.ops import CASADI, Ops
from ..geometry import cos_law, sqrt, where
from ..registry import Condition, Params, Scale


def output_pin(r1: Any, r2: Any, r3: Any, r4: Any, th: Any) -> tuple[Any, Any, Any]:
    """(v_x, v_y, cos μ): the rocker/follower vector v = D − O4 to its pin D, and the signed
    coupler–rocker transmission.

    D is the intersection of circle(A, r3) and circle(O4, r4) left of A→O4, its Heron product
    written for a four-bar: with d² = |AO4|² = (r2 − r1)² + 4 r1 r2 sin²(θ/2) = (r1 + r2)² − 4 r1 r2
    cos²(θ/2), the factors (r3 + r4)² − d² and d² − (r3 − r4)² are sums of terms that a valid
    (Grashof) linkage keeps ≥ 0, so near its folded and extended positions, where a near
    change point's follower stalls, no digit cancels. v is measured from O4, not built as
    A + (D − A), which would keep only a few ulp of |A| of a rocker much shorter than the crank.
    """
    ay, s2 = r2 * ca.sin(th), ca.sin(th / 2) ** 2
    d2, across = _triangle(r1, r2, r3, r4, th)
    ux = (r1 - r2) + 2 * r2 * s2  # u = A→O4 = (r1 − A_x, −A_y)
    # D = O4 − back·u + across·n, n = u turned left; back = (d² − r3² + r4²) / 2d², whose
    # constant part (r2 − r1)² − r3² + r4² is summed in the grouping with the smaller terms (a
    # kite's (r2 − r3 − r1)(r2 + r3 − r1) + r4²; a crank ≈ ground's (r2 − r1)² + r4² − r3²)
    kite = ((r2 - r3) - r1) * ((r2 + r3) - r1)
    near = (r4 - r3) * (r4 + r3)
    fixed = where(
        ca.fmax(ca.fabs(kite), r4 * r4) <= ca.fmax((r2 - r1) ** 2, ca.fabs(near)),
        kite + r4 * r4,
        (r2 - r1) ** 2 + near,
    )
    back = (fixed + 4 * r1 * r2 * s2) / (2 * d2)
    return -back * ux + across * ay, back * ay + across * ux, cos_law(r3, r4, sqrt(d2))


def output_pin_height(r1: Any, r2: Any, r3: Any, r4: Any, th: Any) -> Any:
    """D_y of ``output_pin``, precise to its own size where D passes near the crank pivot O2.

    There (a drag-link kite, ground ≈ follower and crank ≈ coupler, near its change point)
    D = A + (D − A) cancels to a few ulp of |A|. Measured from O2 instead, D − O2 = a u + t n
    with u = A→O4, n = u turned left, a = ((r1² − r4²) + (r3² − r2²)) / 2d² (the radical line,
    both differences exact for a kite) and t the root of d² t² − 2 r1 A_y t + K = 0 on D's side,
    taken as K / (d² t') from the other root t' where the sum would cancel.
    """
    ay = r2 * ca.sin(th)
    d2, across = _triangle(r1, r2, r3, r4, th)
    ux = (r1 - r2) + 2 * r2 * ca.sin(th / 2) ** 2
    a = ((r1 - r4) * (r1 + r4) + (r3 - r2) * (r3 + r2)) / (2 * d2)
    k = a * a * d2 - 2 * r1 * a * ux + (r1 - r4) * (r1 + r4)
    beta = r1 * ay / d2  # the foot of D on the line A→O4, along n
    t = where(beta >= 0, beta + across, k / (d2 * (beta - across)))
    return -a * ay + t * ux


def _triangle(r1: Any, r2: Any, r3: Any, r4: Any, th: Any) -> tuple[Any, Any]:
    """|AO4|² and the distance of D from the line A→O4 in units of |AO4| (Heron, see
    ``output_pin``)."""
    s2, c2 = ca.sin(th / 2) ** 2, ca.cos(th / 2) ** 2
    d2 = (r2 - r1) ** 2 + 4 * r1 * r2 * s2
    # the factors that vanish on a Grashof limit are summed as differences of pairs, each
    # exact or rounded at its own size (``_paired``), not left to right at the size of the
    # longest link
    outer = _paired(r3, r2, r4, r1) * ((r3 + r4) + (r1 + r2)) + 4 * r1 * r2 * c2
    inner = _paired(r2, r3, r4, r1) * _paired(r2, r1, r3, r4) + 4 * r1 * r2 * s2
    return d2, sqrt(outer * inner) / (2 * d2)


def _paired(a: Any, b: Any, c: Any, d: Any) -> Any:
    """a − b + c − d as (a − b) + (c − d) or (a − d) + (c − b), whichever pairs' differences
    are smaller: each difference of two near links is exact, so the sum keeps the digits of
    its size (a kite pairs one way, a crank ≈ ground with coupler ≈ follower the other; the
    wrong pairing keeps only ulps of the longest link)."""
    x, y, u, v = a - b, c - d, a - d, c - b
    return where(ca.fabs(x) + ca.fabs(y) <= ca.fabs(u) + ca.fabs(v), x + y, u + v)


def grashof_margin(shortest: Any, x: Any, a: Any, b: Any) -> Any:
    """shortest + x ≤ a + b, as a margin ≥ 0 (polymorphic). The three margins of a four-bar's
    links other than the shortest (``grashof_margins``) are Grashof with it the shortest
    link: together they say that it is the shortest and s + l ≤ p + q."""
    return a + b - shortest - x


def grashof_margins(links: Sequence[Any], shortest: int) -> tuple[Any, ...]:
    """Grashof with link ``shortest`` of the four the shortest, as three margins ≥ 0
    (``grashof_margin`` for each other link x, in order, a and b the remaining two)."""
    s = links[shortest]
    return tuple(grashof_margin(s, links[x], links[a], links[b]) for x, a, b in _OTHERS[shortest])


# for each shortest link: each other link x with the remaining two, in order
_OTHERS = {
    s: tuple((x, *(k for k in range(4) if k not in (s, x))) for x in range(4) if x != s)
    for s in range(4)
}


def grashof_conditions(
    names: tuple[str, str, str, str], shortest: str, kind: str
) -> tuple[Condition, ...]:
    """Grashof with ``shortest`` the shortest link (``grashof_margins``), as three linear
    conditions; ``names`` are the parameter names of the four links."""
    s = names.index(shortest)

    def condition(x: int) -> Condition:
        a, b = (names[k] for k in range(len(names)) if k not in (s, x))
        n = names[x]

        def margin(p: Params) -> tuple[Any, ...]:
            return (grashof_margin(p[shortest], p[n], p[a], p[b]),)

        def explain(p: Params) -> str:
            return (
                f"{shortest} {p[shortest]:g} + {n} {p[n]:g} = {p[shortest] + p[n]:g} > "
                f"{a} {p[a]:g} + {b} {p[b]:g} = {p[a] + p[b]:g}: not a {kind} (Grashof with the "
                f"{shortest} the shortest link), the crank cannot drive it through a full "
                f"revolution as one"
            )

        text = f"{shortest} + {n} ≤ {a} + {b} (Grashof with the {shortest} the shortest link: a "
        text += f"{kind})"
        return Condition(name=f"grashof_{n}", text=text, margin=margin, explain=explain)

    return tuple(condition(x) for x in range(len(names)) if x != s)


def grashof_class(ground: float, crank: float, coupler: float, rocker: float) -> str:
    """The four-bar's class by Grashof's criterion (``grashof_margins``; on its limit, to
    rounding, counts as Grashof), named by the shortest link (ground, crank, rocker, coupler
    in that order among equals)."""
    links = (ground, crank, coupler, rocker)
    s = min((0, 1, 3, 2), key=links.__getitem__)
    if min(grashof_margins(links, s)) < -ROUNDING * max(links):
        return "triple-rocker"
    return {0: "drag-link", 1: "crank-rocker", 2: "double-rocker", 3: "rocker-crank"}[s]


def worst_cos(ground: Any, crank: Any, coupler: Any, rocker: Any, ops: Ops = CASADI) -> Any:
    """The largest |cos μ| of the coupler–rocker transmission over a revolution of a Grashof
    crank-rocker: at the crank on the ground line, max(c1, −c2) with c1, c2 = (coupler² +
    rocker² − (ground ∓ crank)²)/(2 coupler rocker) (numbers or CasADi symbols; numpy arrays
    with ``ops``)."""
    base = coupler * coupler + rocker * rocker
    c1 = (base - (ground - crank) ** 2) / (2 * coupler * rocker)
    c2 = (base - (ground + crank) ** 2) / (2 * coupler * rocker)
    return ops.fmax(c1, -c2)


def fourbar_scale(output: str) -> Scale:
    """A four-bar's angles (its swing, time ratio and coupler transmission) do not change with
    its scale, and the output's arm to the slider is a length of its own."""
    return Scale(
        "crank",
        ("ground", "coupler", output),
        f"the four-bar's angles do not depend on its scale; the {output}'s arm to the slider "
        "is a length of its own",
    )
