"""The search on a four-bar's construction: a grid over (ψ, u = log(λ − 1)), then Newton's
method on the Lagrangian (``synth.numerics.dense.newton``) from its best points, for the
coupler's worst cos or the size, with the fixed links' ratios and the transmission bound as
equalities where they bind."""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any, cast

import numpy as np

from ...numerics import ROUNDING
from ...numerics.dense import Taylor, differences, newton
from .construction import AT, Construction, Design, Evaluation, construction

U_LO, U_HI = -9.0, 6.0  # λ = 1 + e^u: couplers from 1.0001 to 400 cranks
GRID = 48
STEP = (U_HI - U_LO) / (GRID - 1)  # the grid's spacing in u
NEAR = 0.1  # log: the links this near their bounds may be the ones that bind
CONTINUE = 8  # Newton steps a front's continuation may take (else the full search runs)
# halvings of a step a shortcut's Newton may take (a continuation, a hint; both also take
# at most CONTINUE steps): a start whose steps keep leaving the designs is at their edge,
# where the grid's search does better
SHORTCUT = 6
SLACK = 1e-6  # a design closer to a link's bound than this (log of the scale's range) may be
# held by that bound, which the Newton steps do not model: IPOPT polishes it


class Search(Construction):
    """The local optima of one variant of a four-bar type on its construction."""

    missed: Evaluation | None = None  # where Newton last ended beyond, or near, a link's bound

    def optimum(
        self,
        sigma: int,
        objective: str,
        cos_bound: float = 1.0,
        psi_fixed: float | None = None,
        limits: bool = True,
    ) -> tuple[list[Design], bool]:
        """Local optima on sheet σ of the coupler's worst cos (``objective`` "f") or of the size
        with that cos ≤ ``cos_bound`` ("size"), where the fixed links' ratios hold and the
        swing is in range (or ``psi_fixed``): a grid, then Newton from its best points; with
        the ratios fixing the point (three links fixed), every root. Returns [(design,
        evaluation)] and whether that is exact: not where Newton failed from a start (the
        start is returned instead, for IPOPT) or ends at a link's bound, which it ignores. With
        ``limits`` False the links' bounds are ignored (only a design's validity counts)."""
        lo, hi = self.psi if psi_fixed is None else (psi_fixed, psi_fixed)
        if lo == hi:
            psi_fixed = lo
        psi = np.linspace(lo, hi, 1 if psi_fixed is not None else GRID)[:, None]
        u = np.linspace(U_LO, U_HI, GRID if psi_fixed is None else 4 * GRID)[None, :]
        hinted = self.hinted(sigma, objective, psi_fixed)
        if hinted is not None:
            return [hinted], True
        starts = self._starts(sigma, psi, u, objective, cos_bound, limits)
        found: list[Design]
        found, exact = [], bool(starts)  # no start is no proof: a link's bound may cut it off
        points = len(self.ratios) >= (1 if psi_fixed is not None else 2)  # roots, not optima
        roots, least, doubts = 0, math.inf, []
        for x0, value, optional, floor in starts:
            x = self._newton(sigma, x0, objective, cos_bound, psi_fixed, optional)
            if x is None and optional:
                continue  # a near-crossing of two curves that is no intersection
            roots += x is not None
            de = self.found(sigma, x0 if x is None else x)
            e = de.evaluation
            ok = e.feasible if limits else e.valid
            within = objective == "f" or e.f <= cos_bound * (1 + ROUNDING)
            if optional:
                same = any(np.allclose(e.at, f.evaluation.at, atol=1e-8) for f in found)
                if ok and within and not same:
                    found.append(de)
                continue
            if x is None or not (ok and within) or (limits and e.slack <= SLACK):
                doubts.append(floor)  # the start is a warm start for IPOPT, if it is a design
                self.missed = e if e.valid else None
                de = self.found(sigma, x0)
                if de.evaluation.feasible if limits else de.evaluation.valid:
                    found.append(de)
                continue
            if not self.ratios and e.measure(objective) > value + 1e-9 * abs(value):
                # Newton found a worse stationary point than its start: its best is held?
                exact = False
                self.missed = self.design(sigma, x0[0], 1 + math.exp(x0[1])).evaluation
            least = min(least, e.measure(objective))
            found.append(de)
        # a start Newton failed from is no doubt if nothing near it can beat the best found
        if any(floor <= least + 1e-9 * abs(least) for floor in doubts):
            exact = False
        found.sort(key=lambda de: de.evaluation.measure(objective))
        if points and starts and not roots:
            exact = False  # crossings, but no intersection found: perhaps a tangency
        return (found if points else found[:1]), exact

    def hinted(self, sigma: int, objective: str, psi_fixed: float | None) -> Design | None:
        """The optimum from another variant's (a slot drive's, for the same crank-rocker with a
        rod): the variants differ by the rod's smooth share of the size, so Newton from there
        finds this one's in a few steps; None where it does not."""
        if sigma != 1 or objective != "size" or self.ratios or not self.p.hints:
            return None
        h = self.p.hints[0]
        if not self.r.swings or self.r.arm not in h:
            return None
        crank, coupler = (h[n] for n in self.r.links[1:3])
        x0 = np.array([2 * math.asin(min(0.5 / h[self.r.arm], 1.0)), math.log(coupler / crank - 1)])
        x = self._newton(sigma, x0, objective, self.p.cos_bound, psi_fixed, shortcut=True)
        if x is None:
            return None
        de = self.found(sigma, x)
        e = de.evaluation
        ok = e.feasible and e.f <= self.p.cos_bound * (1 + ROUNDING) and e.slack > SLACK
        return de if ok else None

    def _starts(
        self,
        sigma: int,
        psi: np.ndarray,
        u: np.ndarray,
        objective: str,
        cos_bound: float,
        limits: bool = True,
    ) -> list[tuple[np.ndarray, float, bool, float]]:
        """Grid points to start Newton from: (point, the objective there, whether it is only
        a possible root, the least the objective can be near it). The best point (no ratio
        held); the crossings of one ratio's curve that are best among their neighbours along
        it (each may be a local optimum, at least its value less the largest difference to a
        neighbour within two grid cells: a smooth function dips between samples far less)
        and, for the size, every place the curve crosses the bound (the bound may bind at
        any of them); with two ratios, or one and ψ held, every crossing of both."""
        e = self.evaluate(sigma, psi, 1 + np.exp(u))
        value = e.measure(objective)
        ok = (e.feasible if limits else e.valid) & ((objective == "f") | (e.f <= cos_bound))
        if not self.ratios:
            if objective == "size" and psi.size > 1:  # a front's later bounds may use it
                floor = np.min(np.where(e.valid, e.f, np.inf))
                self.__dict__.setdefault("floors", {})[sigma] = float(floor)
            if not np.any(ok):
                return []
            i, j = np.unravel_index(np.argmin(np.where(ok, value, np.inf)), ok.shape)
            start = np.array([psi[min(i, psi.shape[0] - 1), 0], u[0, min(j, u.shape[1] - 1)]])
            return [(start, float(value[i, j]), False, -math.inf)]
        pts = np.stack(np.broadcast_arrays(psi, u), axis=-1)  # (rows, cols, 2)
        res = self.residuals(e)
        x = _crossings(res[0], e.valid, pts)
        if len(x) == 0:
            return []
        if psi.size == 1:
            return [(y, math.nan, True, -math.inf) for y in x]
        if len(self.ratios) == 2:
            meet = _meet(x, _crossings(res[1], e.valid, pts))
            return [(y, math.nan, True, -math.inf) for y in meet]
        ev = self.evaluate(sigma, x[:, 0], 1 + np.exp(x[:, 1]))
        v = ev.measure(objective)
        good = ev.feasible & ((objective == "f") | (ev.f <= cos_bound))
        cell = np.array([np.ptp(psi) / (GRID - 1), STEP])
        least, floors = _least(x, v, good, cell)
        out = [(x[k], float(v[k]), False, fl) for k, fl in zip(least, floors, strict=True)]
        if objective == "size":
            bound = _crossings(e.f - cos_bound, e.valid, pts)
            out += [(y, math.nan, True, -math.inf) for y in _meet(x, bound)]
        return out

    def _newton(
        self,
        sigma: int,
        x0: np.ndarray,
        objective: str,
        cos_bound: float,
        psi_fixed: float | None,
        root: bool = False,
        shortcut: bool = False,
    ) -> np.ndarray | None:
        """Newton from x0 = (ψ, u) with the ratios (and, for the size, the bound where it
        binds; only the bound from a ``root`` start) as equalities; a swing that leaves its
        range is held at the nearer edge."""
        lo, hi = self.psi
        x = self._newton_at(sigma, x0, objective, cos_bound, psi_fixed, root, shortcut)
        if psi_fixed is None and (x is None or not lo <= x[0] <= hi):
            edge = lo if (x if x is not None else x0)[0] < (lo + hi) / 2 else hi
            x = self._newton_at(sigma, x0, objective, cos_bound, edge, root, shortcut)
        return x

    def _newton_at(
        self,
        sigma: int,
        x0: np.ndarray,
        objective: str,
        cos_bound: float,
        psi: float | None,
        root: bool = False,
        shortcut: bool = False,
    ) -> np.ndarray | None:
        """Newton with ψ held (or not); for the size, with the bound binding and, where ratios
        are held (it may then not bind), without it: the smaller design that keeps it."""
        both = objective == "size" and bool(self.ratios) and not root
        best: tuple[float, np.ndarray] | None = None
        y0 = x0 if psi is None else x0[1:]
        actives: tuple[bool, ...]
        if root:  # the point where the ratios meet each other, or the bound
            actives = (objective == "size" and len(self.ratios) < y0.size,)
        else:
            actives = (True, False) if objective == "size" else (False,)
        for bound_active in actives:
            rows = self._rows(sigma, objective, cos_bound, bound_active, psi)
            n_eq = len(self.ratios) + bound_active
            y0 = x0 if psi is None else x0[1:]
            if n_eq > y0.size:
                continue
            limits = (CONTINUE, None, SHORTCUT) if shortcut else (30, None, None)
            y = newton(rows, y0, n_eq, *limits)
            if y is None:
                continue
            x = y if psi is None else np.array([psi, y[0]])
            if not both:
                return x
            e = self.design(sigma, x[0], 1 + math.exp(x[1])).evaluation
            if e.f <= cos_bound * (1 + ROUNDING) and (best is None or e.size < best[0]):
                best = e.size, x
        return None if best is None else best[1]

    def _rows(
        self,
        sigma: int,
        objective: str,
        cos_bound: float,
        bound_active: bool,
        psi_fixed: float | None,
    ) -> Callable[[list[float]], Taylor | None]:
        """Newton's ``local`` for x = (ψ, u), or (u,) with ψ held: the objective (f, or the
        size), the ratios' residuals and, with the bound active, f − cos_bound. Exact (the
        compiled ``taylor``) where no ratio is held; else central differences of ``evaluate``."""
        if not self.ratios:
            return self._taylor(sigma, objective, cos_bound, bound_active, psi_fixed)

        def rows(x: np.ndarray) -> np.ndarray:
            ps = x[:, 0] if psi_fixed is None else np.full(len(x), psi_fixed)
            e = self.evaluate(sigma, ps, 1 + np.exp(np.minimum(x[:, -1], 50.0)))
            out = [e.measure(objective), *self.residuals(e)]
            if bound_active:
                out.append(e.f - cos_bound)
            # Newton may cross a bound on its way: only a design that cannot run stops it
            return np.where(e.valid & np.isfinite(e.size), np.array(out), np.nan)

        return differences(rows, 1 if psi_fixed is not None else 2)

    def _taylor(
        self,
        sigma: int,
        objective: str,
        cos_bound: float,
        bound_active: bool,
        psi_fixed: float | None,
    ) -> Callable[[list[float]], Taylor | None]:
        params, taylor = self._params(sigma), construction().taylor
        one = psi_fixed is not None  # only u moves: its entries

        def local(x: list[float]) -> Taylor | None:
            t = taylor(cast(float, psi_fixed) if one else x[0], x[-1], params)
            f, f0, f1, f00, f01, f11 = t[AT : AT + 6]
            size, s0, s1, s00, s01, s11 = t[AT + 6 : AT + 12]
            valid = t[0]
            if not (valid > 0 and math.isfinite(size)):
                return None
            fg, fh = ([f1], [[f11]]) if one else ([f0, f1], [[f00, f01], [f01, f11]])
            sg, sh = ([s1], [[s11]]) if one else ([s0, s1], [[s00, s01], [s01, s11]])
            first = (f, fg, fh) if objective == "f" else (size, sg, sh)
            if not bound_active:
                return [first[0]], [first[1]], [first[2]]
            return [first[0], f - cos_bound], [first[1], fg], [first[2], fh]

        return local


def _crossings(r: np.ndarray, valid: np.ndarray, pts: np.ndarray) -> np.ndarray:
    """Where r changes sign between neighbouring valid grid points, along either axis of the
    grid, linearly interpolated: points near the curve r = 0 whatever its direction."""
    out = []
    for axis in (0, 1):
        if r.shape[axis] < 2:
            continue
        a: Any = [slice(None), slice(None)]
        b: Any = [slice(None), slice(None)]
        a[axis], b[axis] = slice(None, -1), slice(1, None)
        a, b = tuple(a), tuple(b)
        hit = (r[a] * r[b] < 0) & valid[a] & valid[b]
        ra, rb = r[a][hit], r[b][hit]
        out.append(pts[a][hit] + (ra / (ra - rb))[:, None] * (pts[b][hit] - pts[a][hit]))
    return np.concatenate(out) if out else np.empty((0, 2))


def _meet(a: np.ndarray, b: np.ndarray) -> list[np.ndarray]:
    """The points near curve a that are nearest to points near curve b: where they meet (two
    meetings within a grid cell keep both of a's nearest points, for Newton to tell apart)."""
    if len(a) == 0 or len(b) == 0:
        return []
    gap = np.linalg.norm(a[:, None, :] - b[None, :, :], axis=-1)
    nearest = np.argmin(gap, axis=0)
    return [a[n] for n in np.unique(nearest[gap[nearest, np.arange(len(b))] <= 2 * STEP])]


def _least(
    x: np.ndarray, v: np.ndarray, good: np.ndarray, cell: np.ndarray
) -> tuple[np.ndarray, list[float]]:
    """The good points no worse than every good point within two grid cells (the local
    minima of v along a curve sampled by its crossings), and for each its value less the
    largest difference to those neighbours."""
    d = np.max(np.abs(x[:, None, :] - x[None, :, :]) / np.maximum(cell, 1e-300), axis=-1)
    near = good[None, :] & (d <= 2)
    worse = np.where(near, v[None, :], np.inf)
    k = np.flatnonzero(good & (v <= worse.min(axis=1)))
    spread = np.max(np.where(near[k], np.abs(v[None, :] - v[k, None]), 0.0), axis=1)
    return k, (v[k] - spread).tolist()
