"""The bounds of a four-bar problem on its construction, as level sets in (ψ, u = log(λ − 1)).

A fixed link j sets the scale, k = F_j/ρ_j; each further fixed link i holds a ratio,
log ρ_i − log ρ_j = log(F_i/F_j); a free link's box lo_i ≤ k ρ_i ≤ hi_i is the band
log(lo_i/F_j) ≤ log ρ_i − log ρ_j ≤ log(hi_i/F_j) (with the scale free, the smallest the
bounds allow, each pair's room log(ρ_i/ρ_j) ≤ log(hi_i/lo_j), which is kmin ≤ kmax). Every
bound is thus a level set (``Level``) of a difference of the links' logs, smooth in (ψ, u);
so is the transmission bound, f ≤ c. The swing's range edges, and a rod's kinks and the
swings where a rod stops fitting (both set by the swing alone), are lines ψ = const
(``walls``).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ...numerics import ROUNDING
from .. import rod
from .construction import AT, BOUND_TOL, TAYLOR, Evaluation
from .search import GRID, Search

NEAR_BETA = 13  # swings added about a small β
NEAR_ZERO = 8  # swings added towards a range's start at 0
KINKS = 512  # samples of the swing where a rod's kinks are looked for
BISECT = 40  # bisections of each kink's bracket
EDGE = 1e-6  # a swing's range edge this near 0 or π is no line of its own (a degenerate design)
ROW = {n: i for i, n in enumerate(TAYLOR)}


@dataclass(frozen=True)
class Level:
    """g = Σ w·row + b over ``TAYLOR``'s rows: ≥ 0 where feasible, = 0 for a held ratio;
    ``tol``: how far below 0 still counts as on it (a rounding slack of its own)."""

    terms: tuple[tuple[int, float], ...]
    b: float
    eq: bool = False
    tol: float = BOUND_TOL

    def at(self, rows: Sequence[Any]) -> Any:
        """g from the rows' values (numbers or arrays)."""
        return sum((w * rows[r] for r, w in self.terms), self.b)

    def value(self, t: list[float]) -> float:
        """g from ``Compiled.taylor``'s list."""
        return sum((w * t[AT + 6 * r] for r, w in self.terms), self.b)

    def local(self, t: list[float]) -> tuple[float, list[float], list[list[float]]]:
        """g's value, gradient and Hessian in (ψ, u) from ``Compiled.taylor``'s list."""
        v, g0, g1, h00, h01, h11 = self.b, 0.0, 0.0, 0.0, 0.0, 0.0
        for r, w in self.terms:
            o = AT + 6 * r
            v += w * t[o]
            g0, g1 = g0 + w * t[o + 1], g1 + w * t[o + 2]
            h00, h01, h11 = h00 + w * t[o + 3], h01 + w * t[o + 4], h11 + w * t[o + 5]
        return v, [g0, g1], [[h00, h01], [h01, h11]]


def levels(s: Search, objective: str, cos_bound: float) -> list[Level]:
    """The problem's bounds and held ratios as levels: each free link's band against the
    link that sets the scale, each further fixed link's ratio to it (with the scale free,
    each pair's room, log(ρ_i/ρ_j) ≤ log(hi_i/lo_j): kmin ≤ kmax), and for the size the
    transmission bound."""
    p, names, j = s.p, s.r.links, s.set_by
    out = []
    if j is None:
        for i in range(4):
            for k in range(4):
                lo, hi = p.box(names[k])[0], p.box(names[i])[1]
                if i != k and lo > 0 and math.isfinite(hi):
                    out.append(Level(_logs((i, -1.0), (k, 1.0)), math.log(hi / lo)))
    else:
        out += _fixed_levels(s, j)
    if objective == "size":
        out.append(Level(((ROW["f"], -1.0),), cos_bound, tol=cos_bound * ROUNDING))
    return out


def _fixed_levels(s: Search, j: int) -> list[Level]:
    """Each free link's band against link j, whose fixed length sets the scale, and each
    further fixed link's ratio to it."""
    p, names = s.p, s.r.links
    fj = p.fixed[names[j]]
    out = []
    for i, n in enumerate(names):
        if i == j:
            continue
        d = _logs((i, 1.0), (j, -1.0))
        neg = tuple((r, -w) for r, w in d)
        if n in p.fixed:
            out.append(Level(d, -math.log(p.fixed[n] / fj), eq=True))
            continue
        lo, hi = p.box(n)
        if lo > 0:
            out.append(Level(d, -math.log(lo / fj)))
        if math.isfinite(hi):
            out.append(Level(neg, math.log(hi / fj)))
    return out


def _logs(*links: tuple[int, float]) -> tuple[tuple[int, float], ...]:
    """Σ w·log ρ over (link, w), as ``Level`` terms over ``TAYLOR``'s rows (the ground's log,
    link 0, is 0 at scale 1: no term)."""
    return tuple((ROW["log_a2"] + m - 1, w) for m, w in links if m > 0)


def rows_of(e: Evaluation) -> list[Any]:
    """``TAYLOR``'s rows from an evaluation (``Construction.evaluate`` or ``design``)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return [e.f, e.size, *(np.log(np.asarray(r, dtype=float)) for r in e.rho[1:])]


def walls(s: Search) -> list[float]:
    """The lines ψ = const that are strata of their own: the swing's range edges within
    (0, π) and, with a rod from the swinging arm, where a rod stops fitting and (for the
    smallest design) where its length kinks (``rod.switches``' sign changes, bisected)."""
    kept: dict[bool, list[float]] = s.__dict__.setdefault("walls", {})
    if s.rod not in kept:
        kept[s.rod] = _walls(s)
    return kept[s.rod]


def _walls(s: Search) -> list[float]:
    lo, hi = s.psi
    out = [w for w in (lo, hi) if EDGE < w < math.pi - EDGE and lo < hi]
    if s.rod and s.r.swings and lo < hi:
        q = dict(zip(rod.PARAMS, rod.params(s.p, s.r.rod, s.r.height), strict=True))

        def margins(psi: np.ndarray) -> np.ndarray:
            with np.errstate(all="ignore"):
                return np.array(rod.switches(0.5 / np.sin(psi / 2), psi / 2, q))

        psi = np.linspace(lo, hi, KINKS)
        m = margins(psi)
        k, i = np.nonzero(np.isfinite(m[:, :-1]) & (m[:, :-1] * m[:, 1:] < 0))
        a, b, ma = psi[i], psi[i + 1], m[k, i]
        for _ in range(BISECT):
            mid = (a + b) / 2
            mm = margins(mid)[k, np.arange(len(k))]
            same = np.sign(mm) == np.sign(ma)
            a, ma, b = np.where(same, mid, a), np.where(same, mm, ma), np.where(same, b, mid)
        out += np.where(ma > 0, a, b).tolist()  # the end where the margin holds: a rod fits
    return sorted(set(out))


def swings(lo: float, hi: float, beta: float) -> np.ndarray:
    """The grid's swings: ``GRID`` evenly from lo to hi; where the range starts at 0,
    ``NEAR_ZERO`` more within its first step, halving towards 0 (a small swing makes long
    links of a short one: ratios change fast there); and where β is within a few steps of 0
    (a time ratio near 1, whose good designs swing about β), ``NEAR_BETA`` more, geometric
    from β/8 to 8β."""
    out = np.linspace(lo, hi, GRID)
    step = (hi - lo) / (GRID - 1)
    extra = [lo + step * 0.5 ** np.arange(1, NEAR_ZERO + 1)] if lo < EDGE else []
    if 0 < beta < 4 * step:
        extra.append(beta * 2.0 ** np.linspace(-3, 3, NEAR_BETA))
    for near in extra:
        out = np.union1d(out, near[(near > lo) & (near < hi)])
    return out
