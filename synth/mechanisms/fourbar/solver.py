"""Reduced synthesis of the four-bar types on their dead-centre construction
(``_fourbar_construction``): the best transmission and the smallest design.

**What is known about the coupler's worst cos f** (derived where stated, otherwise
established by dense sampling and checked in the tests against an independent global
search): on σ = +1, for each ψ, f has a single minimum in λ, and that minimum is least at
ψ = β, where a2 = sin(β/2) = s for every λ and f = c1 = ((λ² − 1)s + 1)/(λ sqrt(1 − s² + λ²s²))
is least at λ² = 1 + 1/s (derived):

    cos μ* = 2√s/(1 + s),   sin μ* = (1 − s)/(1 + s),

for a unit crank: ground 1/s, coupler sqrt(1 + 1/s), rocker sqrt((1 + 1/s)/s). The sheet
σ = −1 transmits worse than σ = +1 at every swing. So the best design is this closed form when
the swing ψ = β is allowed, else at the nearest allowed swing with λ found by Newton's method.

Everything else (the smallest design, fixed links' ratios, links' bounds that cut an optimum
off) is a problem in (ψ, u = log(λ − 1)): a grid, then Newton's method on the Lagrangian
(``reduced.newton``) from its best points.
"""

from __future__ import annotations

import copy
import math

import numpy as np

from ..reduced import MAX_TRANSMISSION, MIN_SIZE, Reduced, _solve, clip, differences, newton
from .construction import Construction, Roles, construction, worst_cos

__all__ = ["FourBar", "Roles", "worst_cos"]

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


class FourBar(Construction):
    """The optima of one variant of a four-bar type."""

    missed: dict | None = None  # where Newton last ended beyond, or near, a link's bound

    def solve(self) -> Reduced:
        if self.empty:
            return Reduced([])
        if self.p.objective == MAX_TRANSMISSION:
            return self.best_transmission()
        return self.smallest(self.p.cos_bound)

    def best_transmission(self) -> Reduced:
        """σ = +1 at the allowed swing nearest β: λ in closed form there, else by Newton; with
        two or more links fixed, the best point of the curve (or points) they leave. Where the
        links' bounds cut the optimum off (too long a link for the shortest), the best design
        holds that pair of links at their bounds' ratio. A rod that transmits worse than the
        coupler decides the angle; then the smallest design that keeps it is best."""
        found, exact = self.coupler_optimum()
        if not found:
            return Reduced([], exact=exact)
        d, e = found
        if e["rod_cos"] > e["f"] * (1 + 1e-12):
            if self.r.swings:  # the rod's angle depends on the swing: not modelled here
                return Reduced([d], exact=False)
            return self.smallest(e["rod_cos"], d)
        return Reduced([d], exact=exact)

    def coupler_optimum(self) -> tuple[tuple[dict, dict] | None, bool]:
        """The design whose coupler transmits best, with its evaluation, and exactness."""
        beta = self.p.beta
        psi = clip(beta, *self.psi)
        if self.ratios or psi != beta or beta == 0:
            ratios = bool(self.ratios)  # without them, the best coupler by its validity alone
            found, exact = self.optimum(1, "f", psi_fixed=None if ratios else psi, limits=ratios)
            if not found:
                return None, False
            d, e = found[0]
            exact = exact and bool(e["feasible"]) and e["slack"] > SLACK
        else:
            d, e = self.design(1, psi, math.sqrt(1 + 1 / math.sin(beta / 2)))
            exact = bool(e["feasible"]) and e["slack"] > SLACK
        if not e["feasible"] and e["valid"] and not self.ratios:
            return self.bounded(e)
        return (d, e), exact

    def bounded(
        self, e: dict, objective: str = "f", cos_bound: float = 1.0
    ) -> tuple[tuple[dict, dict] | None, bool]:
        """The optimum where the links' bounds cut it off (``e``: the design beyond them): the
        best of the curves where one pair of links beyond them is held at their bounds'
        ratio, ρ_i/ρ_j = hi_i/lo_j (i too long against j), else a corner of two pairs: the two
        worst, and each pair with the worst that its own optimum leaves beyond the bounds (an
        active-set step: one fixed link and two bounds, e.g.). A corner counts only if no
        feasible point of the grid beats it."""
        pairs = self._beyond(e)[:3]
        queue = [[ij] for ij in pairs] + ([pairs[:2]] if len(pairs) > 1 else [])
        key = "f" if objective == "f" else "size"
        best, exact = None, False
        for held in queue:
            if len(held) > 1 and best is not None and exact:
                break  # one pair's optimum within every bound: no corner is needed
            holding = self.holding(held)
            found, ok = holding.optimum(1, objective, cos_bound)
            if not found:
                continue
            psi, u = found[0][1]["at"]
            d, e = self.design(1, psi, 1 + math.exp(u))  # judged by every bound again
            within = objective == "f" or e["f"] <= cos_bound * (1 + 1e-12)
            if e["feasible"] and within and (best is None or e[key] < best[1][key]):
                best = d, e
                corner = len(held) > 1
                beaten = corner and e[key] > self.grid_best(key, cos_bound) + 1e-12
                exact = ok and not beaten
            beyond = e if not e["feasible"] else holding.missed if not ok else None
            if len(held) == 1 and beyond is not None and beyond["valid"]:
                more = [[*held, ij] for ij in self._beyond(beyond) if ij != held[0]][:1]
                queue += [c for c in more if c not in queue]
        return best, exact

    def _beyond(self, e: dict) -> list[tuple[int, int]]:
        """The pairs (i, j) of links of ``e``'s design, i too long against j by their bounds
        (or nearly), the worst first."""
        rho = np.array(e["rho"])
        with np.errstate(divide="ignore"):  # a held pair's links: no bound (0, ∞)
            long, short = np.log(rho / self.hi), np.log(rho / self.lo)
        excess = long[:, None] - short[None, :]
        order = [np.unravel_index(k, excess.shape) for k in np.argsort(excess, axis=None)[::-1]]
        return [(int(i), int(j)) for i, j in order if excess[i, j] > -NEAR and i != j]

    def holding(self, pairs) -> FourBar:
        """This problem with each pair (i, j) held at ρ_i/ρ_j = hi_i/lo_j (the pair's own two
        bounds then hold by the ratio; a fixed link's box still sets the scale)."""
        held = FourBar.__new__(FourBar)
        held.__dict__.update(self.__dict__)
        held.ratios = [(int(i), int(j), math.log(self.hi[i] / self.lo[j])) for i, j in pairs]
        held.lo, held.hi = self.lo.copy(), self.hi.copy()
        for i, j in pairs:
            if i != self.set_by:
                held.hi[i] = math.inf
            if j != self.set_by:
                held.lo[j] = 0.0
        return held

    def grid_best(self, key: str, cos_bound: float = 1.0) -> float:
        """The least ``key`` over the feasible points of the grid (cos μ ≤ ``cos_bound``)."""
        psi = np.linspace(*self.psi, GRID)[:, None]
        e = self.evaluate(1, psi, 1 + np.exp(np.linspace(U_LO, U_HI, GRID))[None, :])
        ok = e["feasible"] & (e["f"] <= cos_bound)
        return float(np.min(np.where(ok, e[key], np.inf)))

    def smallest(self, cos_bound: float, start: dict | None = None) -> Reduced:
        """The smallest design with the coupler's worst cos ≤ ``cos_bound``, the better of
        the two sheets; with nothing fixed, no bound given and no rod that swings, σ = −1 only
        where σ = +1 has none (it was never smaller in a survey of 300 random targets, nor in
        168 drag-link targets with their rod; a swinging rod or a fixed link can make it
        smaller). None at all when the best transmission misses the
        bound. On a front (``Problem.near``: this variant's optima at the previous point's
        bound), each sheet's optimum is continued from there (``continued``), and the full
        search runs only where that fails."""
        if start is None and self.p.near and not self.ratios and self.p.objective == MIN_SIZE:
            answer = self.continued(cos_bound)
            if answer is not None:
                return answer
        best: list[dict] = []
        if start is None:  # does any coupler transmit well enough? A rod only adds a joint
            # (and a bound no rod meets leaves no feasible design), so ask without it
            alone = copy.copy(self)
            alone.rod = False
            found, exact = alone.coupler_optimum()
            if exact and found and found[1]["f"] > cos_bound * (1 + 1e-12):
                return Reduced([])
            if self.rod:  # the start IPOPT gets has the rod
                found, _ = self.coupler_optimum()
            best = [found[0]] if found else []
        # a rod from an arm that turns fully on the path's line (the drag-link's) is as long
        # for every design (arm / cos bound): only a swinging arm's rod can favour σ = −1
        both = (self.rod and self.r.swings) or bool(self.p.fixed) or bool(self.p.explicit)
        sheets: list[tuple[int, list, bool]] = []
        for sigma in (1, -1):
            self.missed = None
            found, exact = self.optimum(sigma, "size", cos_bound)
            if found and not exact and self.missed is not None and not self.ratios:
                # a link's bound binds: its curve meets the transmission bound at places that
                # can be closer than the grid tells apart, so this is a start for IPOPT only
                held, _ = self.bounded(self.missed, "size", cos_bound)
                found = [held] if held else found
            sheets.append((sigma, found, exact))
            if found and not both:
                break
        found = sorted((de for _, f, _ in sheets for de in f), key=lambda de: de[1]["size"])
        if found:
            exact = all(exact for _, f, exact in sheets if f)  # then the best alone is the answer
            at = ()
            if exact and not self.ratios and self.p.objective == MIN_SIZE:
                at = tuple(self._onward(s, f[0][1]["at"], cos_bound, floor=self._floor(s))
                           for s, f, _ in sheets if f)  # fmt: skip
                at = () if None in at else at
            return Reduced([d for d, _ in found[: 1 if exact else None]], exact, at)
        return Reduced([start] if start else best, exact=False)

    def continued(self, cos_bound: float) -> Reduced | None:
        """The smallest design at this bound from each sheet's optimum at a nearby one
        (``Problem.near``): Newton's method with the bound active, from there. Accepted only
        where each ends within the swing's range and the links' bounds, on the bound, at a
        strict local minimum of the size along it (``_binding_minimum``): a front point
        (the smallest design that transmits at least at its angle) holds its bound, as the
        full search finds it. None (the full search then runs) where any does not."""
        lo, hi = self.psi
        found = []
        for sigma, *at in self.p.near:
            sigma = int(sigma)  # Newton from the prediction, the bound active
            rows, kept = self._rows(sigma, "size", cos_bound, True, None), []
            x = newton(rows, _predict(at, cos_bound), 1, CONTINUE, kept, SHORTCUT)
            inside = x is not None and lo < x[0] < hi
            floor = at[-1]  # the least coupler cos on the sheet's grid (NaN: not known)
            onward = self._onward(sigma, x, cos_bound, kept[0], at, floor) if inside else None
            if onward is not None:
                d, e = self.design(sigma, x[0], 1 + math.exp(x[1]))
                if e["feasible"] and abs(e["f"] - cos_bound) <= 1e-9 and e["slack"] > SLACK:
                    found.append((e["size"], onward, d))
                    continue
            # this sheet's optimum moved off its branch (out of the swing's range, onto a
            # link's bound): its full search, as ``smallest`` runs it. Where no point of its
            # grid transmits that well (the grid's f, valid points, does not depend on the
            # bound) and no hint starts it (``hinted``), that search has no start and finds
            # nothing: it need not run
            if floor > cos_bound and (sigma != 1 or not self.p.hints):
                continue
            self.missed = None
            got, exact = self.optimum(sigma, "size", cos_bound)
            if got and not (exact and self.missed is None):
                return None
            for d, e in got[:1]:
                onward = self._onward(sigma, e["at"], cos_bound, floor=self._floor(sigma))
                if onward is None:
                    return None
                found.append((e["size"], onward, d))
        if not found:
            return None
        found.sort(key=lambda f: f[0])
        return Reduced([found[0][2]], True, tuple(f[1] for f in found))

    def _floor(self, sigma: int) -> float:
        """The least coupler cos f over the valid points of sheet σ's last grid (``_starts``,
        no ratios held), NaN where none was evaluated."""
        return self.__dict__.get("floors", {}).get(sigma, math.nan)

    def _onward(self, sigma: int, x, cos_bound: float, t=None, before=None, floor=math.nan):
        """Where a front continues from x, a local minimum of the size on the bound
        (f = cos_bound): (σ, ψ, u, cos_bound, dψ/dc, du/dc, the point before: ψ, u,
        cos_bound, NaN for none, and the sheet's ``_floor``), with the optimum's tangent in
        the bound c (the KKT system differentiated: H dx + ∇f dν = 0, ∇f·dx = 1). None where
        x is not a strict local minimum that holds the bound: the bound's multiplier
        ν = −∇size·∇f/|∇f|² is positive (a worse transmission would allow a smaller design)
        and the Lagrangian size + ν f curves upward along the bound's curve (second-order
        sufficiency), from the local model at x (``t``: Newton's there, if it kept it)."""
        x = [float(a) for a in x]
        if t is None:
            t = self._rows(sigma, "size", cos_bound, True, None)(x)
        if t is None:
            return None
        _, (gs, gf), (hs, hf) = t
        ff = gf[0] ** 2 + gf[1] ** 2
        nu = -(gs[0] * gf[0] + gs[1] * gf[1]) / ff if ff > 0 else math.nan
        if not nu > 0:
            return None
        hess = [[hs[i][j] + nu * hf[i][j] for j in range(2)] for i in range(2)]
        t0, t1 = -gf[1], gf[0]  # the bound's tangent
        along = t0 * t0 * hess[0][0] + 2 * t0 * t1 * hess[0][1] + t1 * t1 * hess[1][1]
        scale = (abs(hess[0][0]) + 2 * abs(hess[0][1]) + abs(hess[1][1])) * ff
        if not along > 1e-6 * scale:
            return None
        kkt = [[hess[0][0], hess[0][1], gf[0]], [hess[0][1], hess[1][1], gf[1]], [*gf, 0.0]]
        dx = _solve(kkt, [0.0, 0.0, 1.0])
        if dx is None:
            return None
        prev = (before[0], before[1], before[2]) if before else (math.nan,) * 3
        return (float(sigma), x[0], x[1], cos_bound, dx[0], dx[1], *prev, floor)

    def optimum(
        self, sigma: int, objective: str, cos_bound: float = 1.0, psi_fixed=None, limits=True
    ):
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
        ok = "feasible" if limits else "valid"
        found, exact = [], bool(starts)  # no start is no proof: a link's bound may cut it off
        key = "f" if objective == "f" else "size"
        points = len(self.ratios) >= (1 if psi_fixed is not None else 2)  # roots, not optima
        roots, least, doubts = 0, math.inf, []
        for x0, value, optional, floor in starts:
            x = self._newton(sigma, x0, objective, cos_bound, psi_fixed, optional)
            if x is None and optional:
                continue  # a near-crossing of two curves that is no intersection
            roots += x is not None
            at = x0 if x is None else x
            d, e = self.design(sigma, at[0], 1 + math.exp(at[1]))
            e["at"] = at
            within = objective == "f" or e["f"] <= cos_bound * (1 + 1e-12)
            if optional:
                same = any(np.allclose(at, f[1]["at"], atol=1e-8) for f in found)
                if e[ok] and within and not same:
                    found.append((d, e))
                continue
            if x is None or not (e[ok] and within) or (limits and e["slack"] <= SLACK):
                doubts.append(floor)  # the start is a warm start for IPOPT, if it is a design
                self.missed = e if e["valid"] else None
                d, e = self.design(sigma, x0[0], 1 + math.exp(x0[1]))
                e["at"] = x0
                if e[ok]:
                    found.append((d, e))
                continue
            if not self.ratios and e[key] > value + 1e-9 * abs(value):
                exact = False  # Newton found a worse stationary point than its start: its
                self.missed = self.design(sigma, x0[0], 1 + math.exp(x0[1]))[1]  # best is held?
            least = min(least, e[key])
            found.append((d, e))
        # a start Newton failed from is no doubt if nothing near it can beat the best found
        if any(floor <= least + 1e-9 * abs(least) for floor in doubts):
            exact = False
        found.sort(key=lambda de: de[1][key])
        if points and starts and not roots:
            exact = False  # crossings, but no intersection found: perhaps a tangency
        return (found if points else found[:1]), exact

    def hinted(self, sigma: int, objective: str, psi_fixed) -> tuple[dict, dict] | None:
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
        d, e = self.design(sigma, x[0], 1 + math.exp(x[1]))
        e["at"] = x
        ok = e["feasible"] and e["f"] <= self.p.cos_bound * (1 + 1e-12) and e["slack"] > SLACK
        return (d, e) if ok else None

    def _starts(
        self, sigma, psi, u, objective, cos_bound, limits=True
    ) -> list[tuple[np.ndarray, float, bool, float]]:
        """Grid points to start Newton from: (point, the objective there, whether it is only
        a possible root, the least the objective can be near it). The best point (no ratio
        held); the crossings of one ratio's curve that are best among their neighbours along
        it (each may be a local optimum, at least its value less the largest difference to a
        neighbour within two grid cells: a smooth function dips between samples far less)
        and, for the size, every place the curve crosses the bound (the bound may bind at
        any of them); with two ratios, or one and ψ held, every crossing of both."""
        e = self.evaluate(sigma, psi, 1 + np.exp(u))
        value = e["f"] if objective == "f" else e["size"]
        ok = e["feasible" if limits else "valid"] & ((objective == "f") | (e["f"] <= cos_bound))
        if not self.ratios:
            if objective == "size" and psi.size > 1:  # a front's later bounds may use it
                floor = np.min(np.where(e["valid"], e["f"], np.inf))
                self.__dict__.setdefault("floors", {})[sigma] = float(floor)
            if not np.any(ok):
                return []
            i, j = np.unravel_index(np.argmin(np.where(ok, value, np.inf)), ok.shape)
            start = np.array([psi[min(i, psi.shape[0] - 1), 0], u[0, min(j, u.shape[1] - 1)]])
            return [(start, float(value[i, j]), False, -math.inf)]
        pts = np.stack(np.broadcast_arrays(psi, u), axis=-1)  # (rows, cols, 2)
        res = self.residuals(e)
        x = _crossings(res[0], e["valid"], pts)
        if len(x) == 0:
            return []
        if psi.size == 1:
            return [(y, math.nan, True, -math.inf) for y in x]
        if len(self.ratios) == 2:
            meet = _meet(x, _crossings(res[1], e["valid"], pts))
            return [(y, math.nan, True, -math.inf) for y in meet]
        ev = self.evaluate(sigma, x[:, 0], 1 + np.exp(x[:, 1]))
        v = ev["f"] if objective == "f" else ev["size"]
        good = ev["feasible"] & ((objective == "f") | (ev["f"] <= cos_bound))
        cell = np.array([np.ptp(psi) / (GRID - 1), STEP])
        least, floors = _least(x, v, good, cell)
        out = [(x[k], float(v[k]), False, fl) for k, fl in zip(least, floors, strict=True)]
        if objective == "size":
            bound = _crossings(e["f"] - cos_bound, e["valid"], pts)
            out += [(y, math.nan, True, -math.inf) for y in _meet(x, bound)]
        return out

    def _newton(self, sigma, x0, objective, cos_bound, psi_fixed, root=False, shortcut=False):
        """Newton from x0 = (ψ, u) with the ratios (and, for the size, the bound where it
        binds; only the bound from a ``root`` start) as equalities; a swing that leaves its
        range is held at the nearer edge."""
        lo, hi = self.psi
        x = self._newton_at(sigma, x0, objective, cos_bound, psi_fixed, root, shortcut)
        if psi_fixed is None and (x is None or not lo <= x[0] <= hi):
            edge = lo if (x if x is not None else x0)[0] < (lo + hi) / 2 else hi
            x = self._newton_at(sigma, x0, objective, cos_bound, edge, root, shortcut)
        return x

    def _newton_at(self, sigma, x0, objective, cos_bound, psi, root=False, shortcut=False):
        """Newton with ψ held (or not); for the size, with the bound binding and, where ratios
        are held (it may then not bind), without it: the smaller design that keeps it."""
        both = objective == "size" and bool(self.ratios) and not root
        best = None
        y0 = x0 if psi is None else x0[1:]
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
            _, e = self.design(sigma, x[0], 1 + math.exp(x[1]))
            if e["f"] <= cos_bound * (1 + 1e-12) and (best is None or e["size"] < best[0]):
                best = e["size"], x
        return None if best is None else best[1]

    def _rows(self, sigma, objective, cos_bound, bound_active, psi_fixed):
        """Newton's ``local`` for x = (ψ, u), or (u,) with ψ held: the objective (f, or the
        size), the ratios' residuals and, with the bound active, f − cos_bound. Exact (the
        compiled ``taylor``) where no ratio is held; else central differences of ``evaluate``."""
        if not self.ratios:
            return self._taylor(sigma, objective, cos_bound, bound_active, psi_fixed)

        def rows(x):
            ps = x[:, 0] if psi_fixed is None else np.full(len(x), psi_fixed)
            e = self.evaluate(sigma, ps, 1 + np.exp(np.minimum(x[:, -1], 50.0)))
            out = [e["f"] if objective == "f" else e["size"], *self.residuals(e)]
            if bound_active:
                out.append(e["f"] - cos_bound)
            # Newton may cross a bound on its way: only a design that cannot run stops it
            return np.where(e["valid"] & np.isfinite(e["size"]), np.array(out), np.nan)

        return differences(rows, 1 if psi_fixed is not None else 2)

    def _taylor(self, sigma, objective, cos_bound, bound_active, psi_fixed):
        params, taylor = self._params(sigma), construction().taylor
        one = psi_fixed is not None  # only u moves: its entries

        def local(x):
            valid, f, size, f0, f1, s0, s1, f00, f01, f11, s00, s01, s11 = taylor(
                psi_fixed if one else x[0], x[-1], params
            )
            if not (valid > 0 and math.isfinite(size)):
                return None
            fg, fh = ([f1], [[f11]]) if one else ([f0, f1], [[f00, f01], [f01, f11]])
            sg, sh = ([s1], [[s11]]) if one else ([s0, s1], [[s00, s01], [s01, s11]])
            first = (f, fg, fh) if objective == "f" else (size, sg, sh)
            if not bound_active:
                return [first[0]], [first[1]], [first[2]]
            return [first[0], f - cos_bound], [first[1], fg], [first[2], fh]

        return local


def _predict(at, c: float) -> np.ndarray:
    """A front's next optimum (ψ, u) at the bound c, from the last one's (``_onward``): its
    tangent, and where there is a point before it, the quadratic through that point too."""
    psi, u, c1, dpsi, du, psi0, u0, c0, _ = at
    d = c - c1
    x = np.array([psi + dpsi * d, u + du * d])
    if math.isfinite(c0) and c0 != c1:
        d0 = c0 - c1  # the curvature that puts the point before on the quadratic
        x += np.array([psi0 - psi - dpsi * d0, u0 - u - du * d0]) * (d / d0) ** 2
    return x


def _crossings(r: np.ndarray, valid: np.ndarray, pts: np.ndarray) -> np.ndarray:
    """Where r changes sign between neighbouring valid grid points, along either axis of the
    grid, linearly interpolated: points near the curve r = 0 whatever its direction."""
    out = []
    for axis in (0, 1):
        if r.shape[axis] < 2:
            continue
        a = [slice(None), slice(None)]
        b = [slice(None), slice(None)]
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


def _least(x: np.ndarray, v: np.ndarray, good: np.ndarray, cell: np.ndarray):
    """The good points no worse than every good point within two grid cells (the local
    minima of v along a curve sampled by its crossings), and for each its value less the
    largest difference to those neighbours."""
    d = np.max(np.abs(x[:, None, :] - x[None, :, :]) / np.maximum(cell, 1e-300), axis=-1)
    near = good[None, :] & (d <= 2)
    worse = np.where(near, v[None, :], np.inf)
    k = np.flatnonzero(good & (v <= worse.min(axis=1)))
    spread = np.max(np.where(near[k], np.abs(v[None, :] - v[k, None]), 0.0), axis=1)
    return k, (v[k] - spread).tolist()
