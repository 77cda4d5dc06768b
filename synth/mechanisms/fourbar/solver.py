"""Reduced synthesis of the four-bar types on their dead-centre construction
(``construction``): the best transmission and the smallest design.

**What is known about the coupler's worst cos f** (derived where stated, otherwise
established by dense sampling and checked in the tests against an independent global
search): on σ = +1, for each ψ, f has a single minimum in λ, and that minimum is least at
ψ = β, where a2 = sin(β/2) = s for every λ and f = c1 = ((λ² − 1)s + 1)/(λ sqrt(1 − s² + λ²s²))
is least at λ² = 1 + 1/s (derived):

    cos μ* = 2√s/(1 + s),   sin μ* = (1 − s)/(1 + s),

for a unit crank: ground 1/s, coupler sqrt(1 + 1/s), rocker sqrt((1 + 1/s)/s). The sheet
σ = −1 transmits worse than σ = +1 at every swing. So the best design is this closed form when
the swing ψ = β is allowed, else at the nearest allowed swing with λ found by Newton's method.

Everything else (the smallest design, links' bounds that cut an optimum off) is a problem in
(ψ, u = log(λ − 1)): a grid, then Newton's method on the Lagrangian from its best points
(``search``). Where a fixed link sets the scale, and where that search is not exact, every
stratum of the feasible set is searched (``strata``); where a rod from the swinging arm
transmits worse than the best coupler, ``limited`` finds the best design.
"""

from __future__ import annotations

import copy
import math
from collections.abc import Sequence
from typing import Any, cast

import numpy as np

from ...numerics import ROUNDING
from ...numerics.dense import Taylor, newton, solve
from ...targets import MAX_TRANSMISSION, MIN_SIZE
from ..reduced import Reduced, clip
from ..registry import Roles
from . import strata
from .construction import Design, Evaluation
from .levels import levels
from .limited import limited
from .search import CONTINUE, GRID, NEAR, SHORTCUT, SLACK, U_HI, U_LO, Search
from .strata import Strata

__all__ = ["FourBar", "Roles"]


class FourBar(Search):
    """The optima of one variant of a four-bar type."""

    # search every stratum (``strata``): where a fixed link sets the scale, else where the
    # free scale's search was not exact
    every = False

    def solve(self) -> Reduced:
        if self.empty:
            return Reduced([])
        answer = self.answer()
        if not answer.exact and not self.every and self.set_by is None:
            self.every = True
            again = self.answer()
            if again.exact or not answer.designs:
                return again
        return answer

    def answer(self) -> Reduced:
        if self.p.objective == MAX_TRANSMISSION:
            return self.best_transmission()
        return self.smallest(self.p.cos_bound)

    def best_transmission(self) -> Reduced:
        """σ = +1 at the allowed swing nearest β: λ in closed form there, else by Newton; with
        two or more links fixed, the best point of the curve (or points) they leave. Where the
        links' bounds cut the optimum off (too long a link for the shortest), the best design
        holds that pair of links at their bounds' ratio. A rod that transmits worse than the
        coupler decides the angle: from an arm on the path's line it transmits alike for
        every design, and the smallest design that keeps it is best; from a swinging arm,
        ``limited``."""
        found, exact = self.coupler_optimum()
        if not found:
            return Reduced([], exact=exact)
        d, e = found
        if e.rod_cos > e.f * (1 + ROUNDING):
            if self.r.swings:  # the rod's angle depends on the swing
                return limited(self, self.stratified, found, exact)
            return self.smallest(e.rod_cos, d)
        return Reduced([d], exact=exact)

    def coupler_optimum(self) -> tuple[Design | None, bool]:
        """The design whose coupler transmits best, with its evaluation, and exactness."""
        beta = self.p.beta
        psi = clip(beta, *self.psi)
        if self.set_by is not None or self.every:
            if psi == beta and beta > 0 and not self.ratios:  # the best of all, if it is allowed
                lam = math.sqrt(1 + 1 / math.sin(beta / 2))
                de = self.design(1, psi, lam, np.array([psi, math.log(lam - 1)]))
                if de.evaluation.feasible:
                    return de, True
            found, exact = self.stratified("f")
            return (found[0] if found else None), exact
        if self.ratios or psi != beta or beta == 0:
            ratios = bool(self.ratios)  # without them, the best coupler by its validity alone
            found, exact = self.optimum(1, "f", psi_fixed=None if ratios else psi, limits=ratios)
            if not found:
                return None, False
            de = found[0]
            exact = exact and bool(de.evaluation.feasible) and de.evaluation.slack > SLACK
        else:
            de = self.design(1, psi, math.sqrt(1 + 1 / math.sin(beta / 2)))
            exact = bool(de.evaluation.feasible) and de.evaluation.slack > SLACK
        e = de.evaluation
        if not e.feasible and e.valid and not self.ratios:
            return self.bounded(e)
        return de, exact

    def bounded(
        self, e: Evaluation, objective: str = "f", cos_bound: float = 1.0
    ) -> tuple[Design | None, bool]:
        """The optimum where the links' bounds cut it off (``e``: the design beyond them): the
        best of the curves where one pair of links beyond them is held at their bounds'
        ratio, ρ_i/ρ_j = hi_i/lo_j (i too long against j), else a corner of two pairs: the two
        worst, and each pair with the worst that its own optimum leaves beyond the bounds (an
        active-set step: one fixed link and two bounds, e.g.). A corner counts only if no
        feasible point of the grid beats it."""
        pairs = self._beyond(e)[:3]
        queue = [[ij] for ij in pairs] + ([pairs[:2]] if len(pairs) > 1 else [])
        best: Design | None = None
        exact = False
        for held in queue:
            if len(held) > 1 and best is not None and exact:
                break  # one pair's optimum within every bound: no corner is needed
            holding = self.holding(held)
            found, ok = holding.optimum(1, objective, cos_bound)
            if not found:
                continue
            psi, u = found[0].evaluation.at
            de = self.design(1, psi, 1 + math.exp(u))  # judged by every bound again
            e = de.evaluation
            within = objective == "f" or e.f <= cos_bound * (1 + ROUNDING)
            value = e.measure(objective)
            better = best is None or value < best.evaluation.measure(objective)
            if e.feasible and within and better:
                best = de
                corner = len(held) > 1
                beaten = corner and value > self.grid_best(objective, cos_bound) + 1e-12
                exact = ok and not beaten
            beyond = e if not e.feasible else holding.missed if not ok else None
            if len(held) == 1 and beyond is not None and beyond.valid:
                more = [[*held, ij] for ij in self._beyond(beyond) if ij != held[0]][:1]
                queue += [c for c in more if c not in queue]
        return best, exact

    def _beyond(self, e: Evaluation) -> list[tuple[int, int]]:
        """The pairs (i, j) of links of ``e``'s design, i too long against j by their bounds
        (or nearly), the worst first."""
        rho = np.array(e.rho)
        with np.errstate(divide="ignore"):  # a held pair's links: no bound (0, ∞)
            long, short = np.log(rho / self.hi), np.log(rho / self.lo)
        excess = long[:, None] - short[None, :]
        order = [np.unravel_index(k, excess.shape) for k in np.argsort(excess, axis=None)[::-1]]
        return [(int(i), int(j)) for i, j in order if excess[i, j] > -NEAR and i != j]

    def holding(self, pairs: list[tuple[int, int]]) -> FourBar:
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
        """The least ``key`` ("f" or "size") over the feasible points of the grid (cos μ ≤
        ``cos_bound``)."""
        psi = np.linspace(*self.psi, GRID)[:, None]
        e = self.evaluate(1, psi, 1 + np.exp(np.linspace(U_LO, U_HI, GRID))[None, :])
        ok = e.feasible & (e.f <= cos_bound)
        return float(np.min(np.where(ok, e.measure(key), np.inf)))

    def smallest(self, cos_bound: float, start: dict[str, float] | None = None) -> Reduced:
        """The smallest design with the coupler's worst cos ≤ ``cos_bound``, the better of
        the two sheets; with nothing fixed, no bound given and no rod that swings, σ = −1 only
        where σ = +1 has none (it was never smaller in a survey of 300 random targets, nor in
        168 drag-link targets with their rod; a swinging rod or a fixed link can make it
        smaller). None at all when the best transmission misses the
        bound. On a front (``Problem.near``: this variant's optima at the previous point's
        bound), each sheet's optimum is continued from there (``continued``), and the full
        search runs only where that fails."""
        if self.set_by is not None or self.every:
            return self.fixed_smallest(cos_bound, start)
        if start is None and self.p.near and not self.ratios and self.p.objective == MIN_SIZE:
            answer = self.continued(cos_bound)
            if answer is not None:
                return answer
        best: list[dict[str, float]] = []
        if start is None:  # does any coupler transmit well enough? A rod only adds a joint
            # (and a bound no rod meets leaves no feasible design), so ask without it
            alone = copy.copy(self)
            alone.rod = False
            coupler, exact = alone.coupler_optimum()
            if exact and coupler and coupler.evaluation.f > cos_bound * (1 + ROUNDING):
                return Reduced([])
            if self.rod:  # the start IPOPT gets has the rod
                coupler, _ = self.coupler_optimum()
            best = [coupler.params] if coupler else []
        # a rod from an arm that turns fully on the path's line (the drag-link's) is as long
        # for every design (arm / cos bound): only a swinging arm's rod can favour σ = −1
        both = (self.rod and self.r.swings) or bool(self.p.fixed) or bool(self.p.explicit)
        sheets: list[tuple[int, list[Design], bool]] = []
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
        found = sorted((de for _, f, _ in sheets for de in f), key=lambda de: de.evaluation.size)
        if found:
            exact = all(exact for _, f, exact in sheets if f)  # then the best alone is the answer
            at: tuple[Any, ...] = ()
            if exact and not self.ratios and self.p.objective == MIN_SIZE:
                at = tuple(
                    self._onward(s, f[0].evaluation.at, cos_bound, floor=self._floor(s))
                    for s, f, _ in sheets
                    if f
                )
                at = () if None in at else at
            return Reduced([d for d, _ in found[: 1 if exact else None]], exact, at)
        return Reduced([start] if start else best, exact=False)

    def stratified(
        self,
        key: str,
        cos_bound: float = 1.0,
        psi: float | None = None,
        seed: Design | None = None,
    ) -> tuple[list[Design], bool]:
        """The least ``key`` ("f", or "size" with the coupler's worst cos ≤ ``cos_bound``) on
        both sheets, every stratum of each searched (``strata``), the swing held at ``psi``
        if given, from ``seed``'s point too; the designs found, best first, and whether the
        best is the optimum."""
        bounds = levels(self, key, cos_bound)
        lo, hi = self.psi
        held = psi if psi is not None else lo if lo == hi else None
        at = [] if seed is None else [seed.evaluation.at]
        sheet = seed.evaluation.sigma if seed is not None else 0
        return strata.solve(
            [Strata(self, s, key, bounds, held, at if s == sheet else []) for s in (1, -1)]
        )

    def fixed_smallest(self, cos_bound: float, start: dict[str, float] | None) -> Reduced:
        """``smallest`` by strata (a fixed link sets the scale, or the free scale's search
        was not exact): their best; where they find none, none at all, exactly, if no coupler
        transmits well enough (a rod only adds a joint), else the search again from the best
        coupler (the bound leaves about it a region the grid does not see)."""
        found, exact = self.stratified("size", cos_bound)
        if not found and start is None:
            alone = copy.copy(self)
            alone.rod = False
            coupler, proof = alone.coupler_optimum()
            if proof and (coupler is None or coupler.evaluation.f > cos_bound * (1 + ROUNDING)):
                return Reduced([])
            if coupler is None:
                return Reduced([], exact=False)
            # the bound leaves a region about the best coupler too small for the grid: the
            # search again, from there
            found, exact = self.stratified("size", cos_bound, seed=coupler)
            exact = exact and proof
            if not found:
                return Reduced([coupler.params], exact=False)
        if found:
            return Reduced([d for d, _ in found[: 1 if exact else None]], exact)
        return Reduced([start] if start else [], exact=False)

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
            kept: list[Taylor]
            rows, kept = self._rows(sigma, "size", cos_bound, True, None), []
            x = newton(rows, _predict(at, cos_bound), 1, CONTINUE, kept, SHORTCUT)
            inside = x is not None and lo < x[0] < hi
            floor = at[-1]  # the least coupler cos on the sheet's grid (NaN: not known)
            onward = (
                self._onward(sigma, cast(np.ndarray, x), cos_bound, kept[0], at, floor)
                if inside
                else None
            )
            if onward is not None:
                assert x is not None  # inside
                d, e = self.design(sigma, x[0], 1 + math.exp(x[1]))
                if e.feasible and abs(e.f - cos_bound) <= 1e-9 and e.slack > SLACK:
                    found.append((e.size, onward, d))
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
                onward = self._onward(sigma, e.at, cos_bound, floor=self._floor(sigma))
                if onward is None:
                    return None
                found.append((e.size, onward, d))
        if not found:
            return None
        found.sort(key=lambda f: f[0])
        return Reduced([found[0][2]], True, tuple(f[1] for f in found))

    def _floor(self, sigma: int) -> float:
        """The least coupler cos f over the valid points of sheet σ's last grid (``_starts``,
        no ratios held), NaN where none was evaluated."""
        return cast(float, self.__dict__.get("floors", {}).get(sigma, math.nan))

    def _onward(
        self,
        sigma: int,
        x: Sequence[float] | np.ndarray,
        cos_bound: float,
        t: Taylor | None = None,
        before: Sequence[float] | None = None,
        floor: float = math.nan,
    ) -> tuple[float, ...] | None:
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
        dx = solve(kkt, [0.0, 0.0, 1.0])
        if dx is None:
            return None
        prev = (before[0], before[1], before[2]) if before else (math.nan,) * 3
        return (float(sigma), x[0], x[1], cos_bound, dx[0], dx[1], *prev, floor)


def _predict(at: Sequence[float], c: float) -> np.ndarray:
    """A front's next optimum (ψ, u) at the bound c, from the last one's (``_onward``): its
    tangent, and where there is a point before it, the quadratic through that point too."""
    psi, u, c1, dpsi, du, psi0, u0, c0, _ = at
    d = c - c1
    x = np.array([psi + dpsi * d, u + du * d])
    if math.isfinite(c0) and c0 != c1:
        d0 = c0 - c1  # the curvature that puts the point before on the quadratic
        x += np.array([psi0 - psi - dpsi * d0, u0 - u - du * d0]) * (d / d0) ** 2
    return x
