"""The exact search on a four-bar's construction where fixed links set its scale: every
stratum of the feasible set, each searched from a grid.

A fixed link j sets the scale, k = F_j/ρ_j; each further fixed link i holds a ratio,
log ρ_i − log ρ_j = log(F_i/F_j); a free link's box lo_i ≤ k ρ_i ≤ hi_i is the band
log(lo_i/F_j) ≤ log ρ_i − log ρ_j ≤ log(hi_i/F_j). Every bound is thus a level set of a
difference of the links' logs, smooth in (ψ, u); so is the transmission bound, f ≤ c, and the
swing's range is a pair of lines ψ = const. Each such set (``Level``) is a curve.

The optimum lies on a stratum: the region (no bound active), a curve (one active, or a held
ratio) or a point where two meet (or, on a line ψ = const, the line, or a point where a
curve crosses it). On each, every sample of a grid (48 × 48 in (ψ, u), 192 along a line)
that is no worse than its neighbours on the stratum starts Newton's method on the
stratum's Lagrangian; where it ends beyond a bound, that bound joins the active ones (at
most as many as the stratum has dimensions) and Newton runs again from the start. Every
meeting of two curves is solved for too. The best feasible point found is the optimum.

It is exact (``Strata.solve``'s flag) unless a start leads nowhere within the bounds and the
least its neighbourhood can hold (its value less its largest difference to a neighbour
within two cells: a smooth function dips between samples far less) is not above the best
found, or a feasible sample beats the best found (a stratum the search missed).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from .active import ActiveSet, Found, Start
from .construction import TAYLOR, Design, Evaluation
from .levels import ROW, Level, rows_of, swings, walls
from .search import GRID, STEP, U_HI, U_LO, Search

LINE = 4 * GRID  # samples along a line ψ = const
REFINE = 6  # Illinois steps that move a crossing onto its curve


class Strata(ActiveSet):
    """One sheet of one problem: minimise ``key`` ("f" or "size") over the designs that keep
    every level, with ψ held at ``psi`` or within the swing's range."""

    def __init__(
        self,
        s: Search,
        sigma: int,
        key: str,
        levels: list[Level],
        psi: float | None = None,
        seeds: Sequence[np.ndarray] = (),
    ) -> None:
        self.s, self.sigma, self.key, self.psi = s, sigma, key, psi
        self.levels = levels
        self.seeds = seeds  # points (ψ, u) to start from besides the grid's
        self.eqs = [k for k, lv in enumerate(levels) if lv.eq]
        self.ineqs = [k for k, lv in enumerate(levels) if not lv.eq]
        self.range = s.psi
        self.obj = Level(((ROW[key], 1.0),), 0.0)
        lo, hi = self.range
        self.cell = np.array([max(hi - lo, 1e-3) / (GRID - 1), STEP])
        self.rows = swings(lo, hi, s.p.beta)
        gaps = np.diff(self.rows)
        self.least_cell = np.array([float(gaps.min()) if len(gaps) else 1e-3, STEP])
        self.walls = walls(s) if psi is None else []
        # the levels as one matrix over ``TAYLOR``'s rows, and their constants
        self.weights = np.zeros((len(levels), len(TAYLOR)))
        for k, lv in enumerate(levels):
            for r, w in lv.terms:
                self.weights[k, r] += w
        self.offsets = np.array([lv.b for lv in levels])

    @property
    def dims(self) -> int:
        return 1 if self.psi is not None else 2

    def search(self) -> Found:
        """Every start of every stratum, then Newton from each, the least floor first: a
        start whose floor is above the best found by then can hold nothing better."""
        found = Found([], [], math.inf)
        starts = self._line(found, self.psi) if self.psi is not None else self._grid(found)
        for wall in self.walls:  # the swing's range edges, the rod's kinks: lines of their own
            starts += self._line(found, wall)
        # a seed (the best coupler, where the bound leaves a region too small for the grid)
        starts += [Start(-math.inf, x, (), psi=self.psi) for x in self.seeds]
        crossed = len(self.eqs) == 2 and any(st.optional for st in starts)
        best = math.inf
        for st in sorted(starts, key=lambda st: st.floor):
            if st.floor > best + 1e-9 * abs(best):
                break
            self._chain(found, st)
            best = min([best, *(v for v, _ in found.points)])
        if crossed and not found.points:
            found.floors.append(-math.inf)  # the curves cross, yet no intersection found
        return found

    def _grid(self, found: Found) -> list[Start]:
        """The starts in (ψ, u): the grid's local minima, each curve's local minima along its
        crossings of the grid, every meeting of two curves."""
        psi = self.rows[:, None]
        u = np.linspace(U_LO, U_HI, GRID)[None, :]
        e = self.s.evaluate(self.sigma, psi, 1 + np.exp(u))
        rows, valid = rows_of(e), e.valid & np.isfinite(e.rod_length)
        g = list(np.tensordot(self.weights, np.array(rows), axes=1) + self.offsets[:, None, None])
        value = self.obj.at(rows)
        pts = np.stack(np.broadcast_arrays(psi, u), axis=-1)
        starts = []
        ok = valid & self._within(g, ())
        if ok.any() and not self.eqs:  # with a ratio held, the samples on its curve only
            found.samples = float(np.min(value[ok]))
        if not self.eqs:
            for i, j in minima(np.where(valid, value, np.inf), ok):
                v, sp = float(value[i, j]), _spread(value, valid, i, j)
                starts.append(Start(v - sp, pts[i, j], (), v, sp))
        # each curve's crossings of the grid's edges (on it: ``_refine``), with every level
        # and the objective there
        on: dict[int, tuple[Any, ...]] = {}
        owner, ends_a, ends_b, ga, gb, cells = _segments(np.array(g), valid, pts)
        if len(owner):
            x, r, fine = self._refine(owner, ends_a, ends_b, ga, gb)
            gx_all = self.weights @ np.array(r) + self.offsets[:, None]
            v_all = self.obj.at(r)
            for k in np.unique(owner).tolist():
                at = owner == k
                xk, fk = x[at], fine[at]
                on[k] = xk, gx_all[:, at], v_all[at], fk, _pairs(cells[at], fk)
        # the curves that are strata of their own: a held ratio's, else each bound's
        for k in {0: self.ineqs, 1: self.eqs}.get(len(self.eqs), []):
            if k not in on:
                continue
            x, gx, v, fine, _ = on[k]
            good = fine & self._within(list(gx), (k,))
            lv = self.levels[k]  # a sample: within its own bound too (a held ratio: on it)
            inside = good & (gx[k] >= -lv.tol) & ((gx[k] <= lv.tol) | (not lv.eq))
            if inside.any():
                found.samples = min(found.samples, float(np.min(v[inside])))
            least, floors = _along(v, good, on[k][4])
            for n, fl in zip(least, floors, strict=True):
                starts.append(Start(fl, x[n], (k,), float(v[n]), float(v[n]) - fl))
        # every meeting of two curves: the problem's held ratios, else each pair of bounds
        eq, ineq = self.eqs, self.ineqs
        if len(eq) == 2:
            pairs = [(eq[0], eq[1])]
        elif eq:
            pairs = [(eq[0], k) for k in ineq]
        else:
            pairs = [(k, q) for n, k in enumerate(ineq) for q in ineq[n + 1 :]]
        for k, q in pairs:
            starts += [Start(fl, x0, (k, q), optional=True) for x0, fl in self._vertices(on, k, q)]
        return starts

    def _line(self, found: Found, psi: float) -> list[Start]:
        """The starts on the line ψ = const: local minima along it, each curve's crossings."""
        u = np.linspace(U_LO, U_HI, LINE)
        e = self.s.evaluate(self.sigma, np.full(LINE, psi), 1 + np.exp(u))
        rows, valid = rows_of(e), e.valid & np.isfinite(e.rod_length)
        g = [lv.at(rows) for lv in self.levels]
        value = self.obj.at(rows)
        ok = valid & self._within(g, ())
        if ok.any() and not self.eqs:  # with a ratio held, the samples on its curve only
            found.samples = min(found.samples, float(np.min(value[ok])))
        if len(self.eqs) > 1:
            return []
        starts = []
        if not self.eqs:
            vv = np.where(valid, value, np.inf)
            for i, _ in minima(vv[:, None], ok[:, None]):
                sp = _spread(value[:, None], valid[:, None], i, 0)
                v = float(value[i])
                starts.append(Start(v - sp, np.array([psi, u[i]]), (), v, sp, psi))
        for k in self.eqs or self.ineqs:
            gk = g[k]
            hit = np.flatnonzero(valid[:-1] & valid[1:] & (gk[:-1] * gk[1:] < 0))
            for n in hit.tolist():
                t = gk[n] / (gk[n] - gk[n + 1])
                x0 = np.array([psi, u[n] + t * (u[n + 1] - u[n])])
                va, vb = float(value[n]), float(value[n + 1])
                starts.append(Start(min(va, vb) - abs(va - vb), x0, (k,), psi=psi, optional=True))
        return starts

    def _vertices(
        self, on: dict[int, tuple[np.ndarray, ...]], a: int, b: int
    ) -> list[tuple[np.ndarray, float]]:
        """Where curves a and b meet within the other bounds: between neighbouring crossings
        of either (``_pairs``) across which the other's level changes sign, the
        interpolated point (one per half cell), with the least the objective can be there
        (the lesser neighbour's value less their difference)."""
        out: list[tuple[np.ndarray, float]] = []
        rest = [q for q in self.ineqs if q not in (a, b)]
        tol = np.array([self.levels[q].tol for q in rest])[:, None]
        for k, other in ((a, b), (b, a)):
            if k not in on or other not in on:
                continue
            x, gx, v, _, (i, j) = on[k]
            go = gx[other]
            hit = go[i] * go[j] < 0
            if rest and hit.any():
                hit &= np.all(np.maximum(gx[rest][:, i], gx[rest][:, j]) >= -tol, axis=0)
            for m, n in zip(i[hit], j[hit], strict=True):
                t = go[m] / (go[m] - go[n])
                z = x[m] + t * (x[n] - x[m])
                if all(np.max(np.abs(z - w) / self.least_cell) > 0.5 for w, _ in out):
                    out.append((z, min(v[m], v[n]) - abs(v[m] - v[n])))
        return out

    def _refine(
        self, owner: np.ndarray, a: np.ndarray, b: np.ndarray, ga: np.ndarray, gb: np.ndarray
    ) -> tuple[np.ndarray, list[Any], np.ndarray]:
        """Each crossing moved onto its curve (level ``owner``) along its grid edge a–b by the
        Illinois method (regula falsi, an end kept twice halved), at most ``REFINE`` steps,
        each on the crossings not yet within 1e-9 of their curve: the points, the rows
        there and which are designs."""
        n = len(owner)
        x = a + (ga / (ga - gb))[:, None] * (b - a)
        rows: list[Any] = [np.empty(n) for _ in TAYLOR]
        fine = np.zeros(n, dtype=bool)
        todo = np.arange(n)
        kept = np.zeros(n, dtype=int)  # which end stayed last: 1 a, −1 b
        for step in range(REFINE + 1):
            e = self.s.evaluate(self.sigma, x[todo, 0], 1 + np.exp(x[todo, 1]))
            r = rows_of(e)
            for q, v in zip(rows, r, strict=True):
                q[todo] = v
            fine[todo] = e.valid & np.isfinite(e.rod_length)
            if step == REFINE:
                break
            gx = np.einsum("ij,ji->i", self.weights[owner[todo]], np.array(r))
            gx += self.offsets[owner[todo]]
            ok = fine[todo] & np.isfinite(gx) & (np.abs(gx) > 1e-9)
            todo, gx = todo[ok], gx[ok]
            if not len(todo):
                break
            left = np.sign(gx) == np.sign(ga[todo])  # the new point replaces end a
            i, j = todo[left], todo[~left]
            a[i], ga[i] = x[i], gx[left]
            b[j], gb[j] = x[j], gx[~left]
            gb[i] = np.where(kept[i] == -1, gb[i] / 2, gb[i])
            ga[j] = np.where(kept[j] == 1, ga[j] / 2, ga[j])
            kept[i], kept[j] = -1, 1
            x[todo] = a[todo] + (ga[todo] / (ga[todo] - gb[todo]))[:, None] * (b[todo] - a[todo])
        return x, rows, fine

    def _cell(self, psi: float) -> np.ndarray:
        """The grid's spacing about swing ψ (its rows are closer near 0 and a small β)."""
        rows = self.rows
        i = int(np.clip(np.searchsorted(rows, psi), 1, len(rows) - 1))
        return np.array([max(rows[i] - rows[i - 1], 1e-6), STEP])

    def feasible_grid(self, e: Evaluation) -> Any:
        """Which points of an evaluation are designs within every bound."""
        rows = np.array(rows_of(e))
        shape = (-1, *[1] * (rows.ndim - 1))
        g = np.tensordot(self.weights, rows, axes=1) + self.offsets.reshape(shape)
        return e.valid & np.isfinite(e.rod_length) & self._within(list(g), ())

    def _within(self, g: list[Any], active: tuple[int, ...]) -> Any:
        ok: Any = True
        for k in self.ineqs:
            if k not in active:
                ok = ok & (g[k] >= -self.levels[k].tol)
        return ok


def solve(sheets: Sequence[Strata]) -> tuple[list[Design], bool]:
    """The stationary points the sheets' searches find, best first, as (design, evaluation),
    and whether the best is certified the optimum: no doubt's floor and no feasible sample of
    any sheet is below it."""
    out: list[tuple[float, Design]] = []
    floors, samples = [], math.inf
    for st in sheets:
        found = st.search()
        floors += found.floors
        samples = min(samples, found.samples)
        for _, x in found.points:
            de = st.s.found(st.sigma, x)
            out.append((float(de.evaluation.measure(st.key)), de))
    out.sort(key=lambda ve: ve[0])
    best = out[0][0] if out else math.inf
    slack = 1e-9 * abs(best) if out else 0.0
    exact = all(fl > best + slack for fl in floors) and samples >= best - slack
    return [de for _, de in out], exact


def _segments(g: np.ndarray, valid: np.ndarray, pts: np.ndarray) -> tuple[np.ndarray, ...]:
    """The grid's edges (along either axis) between valid points where a level (g: levels ×
    grid) changes sign: each one's level, its ends a, b, g there, and the two grid cells it
    borders (numbered row-major, −1 beyond the grid): a curve runs from an edge to another
    of the same cell."""
    _, n, m = g.shape
    out = []
    for axis in (1, 2):
        sa: Any = [slice(None)] * 3
        sb: Any = [slice(None)] * 3
        sa[axis], sb[axis] = slice(None, -1), slice(1, None)
        sa, sb = tuple(sa), tuple(sb)
        hit = (g[sa] * g[sb] < 0) & valid[sa[1:]] & valid[sb[1:]]
        k, i, j = np.nonzero(hit)
        # the cells on either side: (i, j − 1) and (i, j) across an edge along ψ, (i − 1, j)
        # and (i, j) across one along u
        ci = np.stack([i, i] if axis == 1 else [i - 1, i], axis=1)
        cj = np.stack([j - 1, j] if axis == 1 else [j, j], axis=1)
        cells = np.where((ci >= 0) & (cj >= 0) & (ci < n - 1) & (cj < m - 1), ci * m + cj, -1)
        a, b = pts[sa[1:]][i, j], pts[sb[1:]][i, j]
        out.append((k, a, b, g[sa][k, i, j], g[sb][k, i, j], cells))
    return tuple(np.concatenate(x) for x in zip(*out, strict=True))


def _pairs(cells: np.ndarray, fine: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The pairs (i < j) of a curve's crossings, both designs, on edges of one cell: where
    the curve runs between them."""
    ids = cells.ravel()
    idx = np.repeat(np.arange(len(cells)), 2)
    keep = ids >= 0
    order = np.argsort(ids[keep], kind="stable")
    ids, idx = ids[keep][order], idx[keep][order]
    i, j = [], []
    for d in (1, 2, 3):  # a cell has four edges
        same = np.flatnonzero(ids[:-d] == ids[d:])
        i.append(idx[same])
        j.append(idx[same + d])
    a, b = np.concatenate(i), np.concatenate(j)
    a, b = np.minimum(a, b), np.maximum(a, b)
    keep = (a != b) & fine[a] & fine[b]
    n = len(cells)
    pairs = np.unique(a[keep] * n + b[keep])
    return pairs // n, pairs % n


def _along(
    v: np.ndarray, good: np.ndarray, pairs: tuple[np.ndarray, np.ndarray]
) -> tuple[list[int], list[float]]:
    """The good crossings no worse than every good one within two steps along the curve (its
    local minima), and for each its value less the largest difference to those."""
    near: list[set[int]] = [set() for _ in range(len(v))]
    for a, b in zip(*pairs, strict=True):
        near[a].add(int(b))
        near[b].add(int(a))
    least, floors = [], []
    for k in np.flatnonzero(good):
        two = set(near[k]).union(*(near[n] for n in near[k])) - {k}
        around = [n for n in two if good[n]]
        if all(v[k] <= v[n] for n in around):
            least.append(int(k))
            floors.append(float(v[k] - max((abs(v[n] - v[k]) for n in around), default=0.0)))
    return least, floors


def minima(value: np.ndarray, ok: np.ndarray) -> list[tuple[int, int]]:
    """The ``ok`` grid points no worse than any of their (up to eight) neighbours, and finite
    (a column: its entries no worse than the two beside them)."""
    pad = np.pad(value, 1, constant_values=np.inf)
    n, m = value.shape
    least = np.full(value.shape, np.inf)
    for di in (-1, 0, 1):
        for dj in (-1, 0, 1):
            if di or dj:
                least = np.minimum(least, pad[1 + di : 1 + di + n, 1 + dj : 1 + dj + m])
    idx = np.argwhere(ok & (value <= least) & np.isfinite(value))
    return [(int(i), int(j)) for i, j in idx]


def _spread(value: np.ndarray, valid: np.ndarray, i: int, j: int) -> float:
    """The largest difference of a grid point's value to its valid neighbours within two
    cells."""
    a = value[max(i - 2, 0) : i + 3, max(j - 2, 0) : j + 3]
    v = valid[max(i - 2, 0) : i + 3, max(j - 2, 0) : j + 3]
    diffs = np.abs(a[v] - value[i, j])
    return float(diffs.max()) if diffs.size else 0.0
