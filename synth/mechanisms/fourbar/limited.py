"""The best transmission where a connecting rod from the swinging arm transmits worse than
the best coupler: the rod then decides the angle, and how well it can transmit depends on
the swing alone.

At a swing ψ the rod transmits at best R(ψ) (its worst cos at its upper bound, placed as
well as its placement allows: ``rod.rule`` with no other joint to match), whatever the
four-bar; the coupler at best F(ψ), the least f over the designs with that swing (a search
of the line ψ = const, ``strata``). The design's worst cos is max(f, R(ψ)), so the best is
min over ψ of T(ψ) = max(F(ψ), R(ψ)), at one of

- a local minimum of the coupler alone where the rod keeps up, R(ψ) ≤ f (the strata's own
  optima of f);
- a local minimum of R, where F ≤ R: there any design with f ≤ R(ψ) ties, and the smallest
  of them is the answer (a search of the line for the size);
- a swing where F and R cross (a root of F − R, by the Illinois method on exact F);
- an end of the swing's range.

F on the grid's rows (its least over each row's feasible points) brackets the last three;
each is then solved with F exact. Where R > 1 on every row and at its least between (the rod
reaches no placement at any swing) there is no design, and the coupler is not searched.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np

from ...numerics.ops import NUMPY
from .. import rod
from ..reduced import Reduced
from .construction import Design
from .levels import levels, swings
from .search import GRID, U_HI, U_LO, Search
from .strata import Strata, minima

# a solver's least f or size over every stratum (``FourBar.stratified``)
Stratified = Callable[..., tuple[list[Design], bool]]

ROOT_STEPS = 30  # Illinois steps on F − R
GOLDEN = 60  # golden-section steps on R


def limited(fb: Search, stratified: Stratified, coupler: Design, exact: bool) -> Reduced:
    """The best design of the solver ``fb`` where the rod decides (``coupler``: the best
    coupler's, ``exact`` whether it is certified), and whether it is exact."""
    q = dict(zip(rod.PARAMS, rod.params(fb.p, fb.r.rod, fb.r.height), strict=True))
    lo, hi = fb.psi

    def best_rod(psi: Any) -> Any:
        psi = np.asarray(psi, dtype=float)
        with np.errstate(all="ignore"):
            cos = rod.rule(0.5 / np.sin(psi / 2), psi / 2, 0.0, q, NUMPY)[2]
        return np.where(np.isfinite(cos), cos, np.inf)

    def line(psi: float) -> tuple[float, Design | None, bool]:
        found, ok = stratified("f", psi=psi)
        return (found[0].evaluation.f, found[0], ok) if found else (math.inf, None, ok)

    rows = swings(lo, hi, fb.p.beta) if lo < hi else np.array([lo])
    r_rows = best_rod(rows)
    every = np.ones((len(rows), 1), dtype=bool)
    if np.all(r_rows > 1) and all(  # the rod reaches at no row, nor between: no design
        best_rod(_golden(best_rod, *_bracket(rows, i))) > 1
        for i, _ in minima(r_rows[:, None], every)
    ):
        return Reduced([], exact=exact)
    found, sure = stratified("f")
    sure = sure and exact
    options: list[tuple[float, float, Design | None]] = []  # (T, ψ, design or None: R's)
    for de in found:  # the coupler's optima where the rod keeps up
        e = de.evaluation
        if best_rod(e.at[0]) <= e.f:
            options.append((float(e.f), float(e.at[0]), de))
            break
    f_rows = _coupler_rows(fb, rows)
    t_rows = np.maximum(f_rows, r_rows)
    for i, _ in minima(t_rows[:, None], every):
        a, b = _bracket(rows, i)
        # the rod's own best swing in the bracket, if the coupler keeps up there
        psi_r = _golden(best_rod, a, b)
        f_r, at, ok = line(psi_r)
        sure = sure and ok
        if f_r <= best_rod(psi_r):
            options.append((float(best_rod(psi_r)), psi_r, None))
        # where the coupler and the rod cross, on either side
        for c, d in ((a, rows[i]), (rows[i], b)):
            with np.errstate(invalid="ignore"):  # both infinite: NaN, no crossing
                dc = f_rows[_row(rows, c)] - r_rows[_row(rows, c)]
                dd = f_rows[_row(rows, d)] - r_rows[_row(rows, d)]
            if np.isfinite(dc) and np.isfinite(dd) and dc * dd < 0:
                crossed = _cross(line, best_rod, c, d, dc, dd)
                if crossed is None:
                    sure = False
                    continue
                psi_c, design, ok = crossed
                sure = sure and ok
                options.append((float(best_rod(psi_c)), psi_c, design))
    for edge in (lo, hi):  # the range's ends
        f_e, at, ok = line(edge)
        if at is not None:
            sure = sure and ok
            options.append((max(f_e, float(best_rod(edge))), edge, at))
    if not options:
        return Reduced([coupler.params], exact=False)
    t, psi, best = min(options, key=lambda o: (o[0], o[2] is not None))
    if best is None:  # R decides and every coupler with f ≤ R ties: the smallest
        got, ok = stratified("size", cos_bound=t, psi=psi)
        if not got:
            return Reduced([coupler.params], exact=False)
        best, sure = got[0], sure and ok
    return Reduced([best.params], exact=sure)


def _coupler_rows(fb: Search, rows: np.ndarray) -> np.ndarray:
    """F on the grid's rows: each row's least f over its feasible points, both sheets."""
    bounds = levels(fb, "f", 1.0)
    u = np.linspace(U_LO, U_HI, GRID)[None, :]
    out = np.full(len(rows), np.inf)
    for sigma in (1, -1):
        st = Strata(fb, sigma, "f", bounds)
        e = fb.evaluate(sigma, rows[:, None], 1 + np.exp(u))
        ok = st.feasible_grid(e)
        out = np.minimum(out, np.min(np.where(ok, e.f, np.inf), axis=1))
    return out


def _bracket(rows: np.ndarray, i: int) -> tuple[float, float]:
    """The rows on either side of row i (its own at an end)."""
    return float(rows[max(i - 1, 0)]), float(rows[min(i + 1, len(rows) - 1)])


def _row(rows: np.ndarray, psi: float) -> int:
    return int(np.argmin(np.abs(rows - psi)))


def _golden(fn: Any, a: float, b: float) -> float:
    """The least of fn on [a, b] by golden sections (fn unimodal there)."""
    g = (math.sqrt(5) - 1) / 2
    c, d = b - g * (b - a), a + g * (b - a)
    fc, fd = float(fn(c)), float(fn(d))
    for _ in range(GOLDEN):
        if fc <= fd:
            b, d, fd = d, c, fc
            c = b - g * (b - a)
            fc = float(fn(c))
        else:
            a, c, fc = c, d, fd
            d = a + g * (b - a)
            fd = float(fn(d))
    return (a + b) / 2


def _cross(
    line: Any, best_rod: Any, a: float, b: float, da: float, db: float
) -> tuple[float, Design, bool] | None:
    """The swing between a and b where F = R (F − R is da at a, db at b: of opposite
    signs), by the Illinois method on exact F; with its design and exactness."""
    sure, design, psi, kept = True, None, a, 0
    for _ in range(ROOT_STEPS):
        psi = a - da * (b - a) / (db - da)
        f, design, ok = line(psi)
        if design is None:
            return None
        sure = sure and ok
        dp = f - float(best_rod(psi))
        if abs(dp) <= 1e-12 * abs(f) or abs(b - a) <= 1e-12:
            return psi, design, sure
        if (dp < 0) == (da < 0):  # a moves; b kept (a second time in a row: its value halved)
            a, da, db, kept = psi, dp, db / 2 if kept == 1 else db, 1
        else:
            b, db, da, kept = psi, dp, da / 2 if kept == -1 else da, -1
    return None
