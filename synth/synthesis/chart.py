"""A four-bar type's local search on its dead-centre construction
(``synth.mechanisms.fourbar.construction``, ``Mechanism.construction``): coordinates
(``local.Coordinates``) in which every point is a design with the request's time ratio and
stroke, so SLSQP keeps only inequalities and never leaves the equalities on its way. In the
type's own parameters its iterates left them by up to 14% of the stroke and crawled back,
100–300 iterations a run (``docs/benchmarks.md``).

On a sheet σ (the crank turns φ = π + σβ between the toggles), a point is
z = (ψ, v[, s][, l][, h]): the rocker's swing ψ, λ = 1 + e^v (the coupler over the crank), the
four-bar's scale e^s (its ground link, in the request's bounds on that link: SLSQP keeps a
coordinate's bounds at every iterate, not its rows; a constant of the start where the measure
does not depend on it, the motion's; where one link is fixed, its length over its ratio to the
ground, no coordinate), the rod's length l and its path's placement h where the variant has a
rod and they are free. The links are e^s (1, a2, a3, a4)(ψ, λ) in the crank-rocker's roles,
the arm the construction's (1/(2 sin(ψ/2)) where it swings with the rocker, else half the
stroke). Its own rows: the request's bounds on the parameters that are no coordinates (where
the scale is a constant, on the links' ratios: some scale then meets them all, the smallest is
the answer), and the toggles in one assembly circuit. The search's drawn starts are points of
the construction too (``Chart.draw``)."""

from __future__ import annotations

import itertools
import math
import threading
from collections.abc import Callable
from typing import Any

import casadi as ca
import numpy as np

from ..mechanisms import Mechanism
from ..mechanisms.fourbar.construction import PARAMS, ROWS, circuit, crank, rows
from ..mechanisms.geometry import triangle_angle
from ..mechanisms.reduced import ONE_WAY
from ..mechanisms.registry import Roles
from ..numerics.native import Mapped
from ..targets import beta
from .solve import spread
from .solve import starts as halton

MATCH = 1e-9  # relative: how closely a start's coordinates give the start back
FAR = 30.0  # the logs v and s stay within ±FAR (λ − 1 and the scale within e^±30)
EDGE = 1e-9  # ψ within (EDGE, π − EDGE)
DRAWN_V = (-7.0, 4.0)  # the range of v = log(λ − 1) that ``Chart.draw`` draws from
GENERATIONS, POPULATION = 10, 10  # ``Chart.evolve``'s, on each sheet (per coordinate)
_local = threading.local()


class Chart:
    """One variant's coordinates on the construction (where it ``applies``), with the request's
    box on its free parameters (``local.Coordinates``); ``scale``: the four-bar's scale is one
    of them (the measure depends on it) unless ``fixed`` (the request's fixed parts) holds a
    link, whose length then sets it."""

    equalities = False
    drawn = "construction"

    def __init__(
        self,
        m: Mechanism,
        variant: frozenset[str],
        free: tuple[str, ...],
        lo: np.ndarray,
        hi: np.ndarray,
        time_ratio: float,
        scale: bool,
        fixed: dict[str, float],
    ) -> None:
        r = m.construction
        assert r is not None
        self.names = names(r, free, scale)
        self.scaled = "s" in self.names  # ``local.Coordinates``
        self.free, self.lo, self.hi, self.beta = free, lo, hi, beta(time_ratio)
        self.fn = function(m, variant, free, scale)
        self.roles = r.links
        self.arm, self.rod = r.arm, fixed.get(r.rod)  # the rod's length where it is fixed
        pinned = _pinned(r, free)
        # a fixed link's length, else None (its log is the constants' last)
        self.pinned = None if pinned is None else fixed[pinned]
        self.links = [free.index(n) for n in r.links if n in free]
        self.own_at = [free.index(n) for n in _own(r, free)]  # l, h
        own, sized = self.own_at, scale or pinned is not None  # the links' lengths are set
        bounded = [i for i in range(len(free)) if i not in own and (sized or i not in self.links)]
        self.low = [i for i in bounded if math.isfinite(lo[i])]
        self.high = [i for i in bounded if math.isfinite(hi[i])]
        li = [] if sized else self.links
        self.pairs = [(i, j) for i in li for j in li if i != j and lo[i] > 0 and hi[j] < math.inf]
        self.box = [(EDGE, math.pi - EDGE), (-FAR, FAR)]
        if self.scaled:  # e^s is the first link's length: its bounds, as SLSQP keeps them
            first = free.index(r.links[0])
            with np.errstate(divide="ignore"):
                a, b = np.clip(np.log([lo[first], hi[first]]), -FAR, FAR)
            self.box.append((float(a), float(b)))
        self.box += [(lo[i], hi[i]) for i in own]

    def constants(self, sigma: int, s: float) -> np.ndarray:
        """e^{iφ}, half the stroke (a fixed arm's length) and the scale's log (a fixed link's
        length's, where one is fixed)."""
        s = s if self.pinned is None else math.log(self.pinned)
        return np.array([-math.cos(sigma * self.beta), -math.sin(sigma * self.beta), 0.5, s])

    def starts(self, x: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
        """The coordinates of the design x on the sheet that gives it back (none: no sheet
        does, a design of no crank-rocker's construction)."""
        given = iter(x[self.links])
        rho = np.array([self.pinned if n not in self.free else next(given) for n in self.roles])
        k, lam = rho[0], rho[2] / rho[1]
        if not (k > 0 and lam > 1):
            return []
        swing = triangle_angle(rho[0], rho[3], rho[2] + rho[1])
        swing -= triangle_angle(rho[0], rho[3], rho[2] - rho[1])
        scale = [math.log(k)] if self.scaled else []
        z = np.array([float(swing), math.log(lam - 1), *scale, *x[self.own_at]])
        found = []
        for sigma in (1, -1):
            c = self.constants(sigma, math.log(k))
            if np.abs(self.at(z, c)[0] - x).max() <= MATCH * np.abs(x).max():
                found.append((z, c))
        return found

    def _split(self, z: np.ndarray, c: np.ndarray) -> tuple[np.ndarray, np.ndarray, Any, Any]:
        """x(z), ∂x/∂z, the circuit's margin and its gradient."""
        x, dx, margin, dm = self._parts(self.fn(z[None, :], c)[:, 0])
        return x, dx.reshape(len(z), len(x)).T, margin, dm

    def _parts(self, out: np.ndarray) -> tuple[np.ndarray, np.ndarray, Any, Any]:
        """The chart function's rows (a column a point, ``function``): x, ∂x/∂z by columns,
        the circuit's margin and its gradient."""
        n, k = len(self.free), len(self.names)
        return out[:n], out[n : n + n * k], out[n + n * k], out[n + n * k + 1 :]

    def at(self, z: np.ndarray, c: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """x(z) and ∂x/∂z."""
        return self._split(z, c)[:2]

    def point(
        self, z: np.ndarray, c: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, tuple[np.ndarray, np.ndarray]]:
        """x(z), ∂x/∂z and the own rows: the request's bounds on what is no coordinate, the
        toggles in one circuit (its margin < 0)."""
        x, dx, margin, dm = self._split(z, c)
        k = len(z)
        lo, hi, low, high = self.lo, self.hi, self.low, self.high
        values = [x[low] - lo[low], hi[high] - x[high], [-margin]]
        values += [[math.log(hi[j] / lo[i]) - math.log(x[j] / x[i]) for i, j in self.pairs]]
        rates = [dx[low], -dx[high], -dm[None]]
        rates += [np.array([dx[i] / x[i] - dx[j] / x[j] for i, j in self.pairs]).reshape(-1, k)]
        return x, dx, (np.concatenate(values), np.vstack(rates))

    def bounds(self) -> list[tuple[float, float]]:
        return self.box

    def draw(self, n: int) -> list[np.ndarray]:
        """Designs at n/2 Halton points of the construction on each sheet (ψ over its range, v
        over ``DRAWN_V``, the scale's log where it is a coordinate and the rod's numbers over
        their box; else the scale the smallest the box allows): each meets the time ratio and
        the stroke where its toggles lie in one circuit. Of 256 such points 19–90 pass the
        screen on a crank-rocker at time ratio 1.6 and 0°, of the box's own 3–7. Where the
        rod's path's placement is a coordinate, a second set with the path within the rod's
        reach of C's ends (``_placed``): few of the box's placements are, and a short rod's
        basins lie in that sliver (a crank-rocker's least peak torque at time ratio 2 and 0°,
        11% below the slot drive's)."""
        sets = [self._at(halton(*self._drawn(False), n // 2))]
        if self._reaches():
            z = halton(*self._drawn(True), n // 2)
            sets.append(self._placed(np.tile(z, (2, 1)), self._at(z)))  # z as the designs' rows
        return [self._smallest(x) for x in sets]

    def evolve(self, measure: Callable[[np.ndarray, np.ndarray], np.ndarray]) -> np.ndarray:
        """On each sheet, the design that differential evolution finds least by ``measure``
        (designs as rows, and how far each breaks the toggles' circuit, 0 where it does not
        → values) over ``draw``'s coordinates; where the rod's reach applies, also on the
        one way's edges (u = ±1, ``_placed``), where a crank-rocker's most uniform speed at a
        0° bound may have its optimum (time ratio 1.3: a basin 1e-5 of the coordinates'
        volume, which none of 4 096 drawn points reached, nor the evolution off the edge).
        ``POPULATION`` points per coordinate for ``GENERATIONS`` generations, from seed 0."""
        from scipy.optimize import differential_evolution  # ~0.4 s of an import of synth

        reach = self._reaches()
        lo, hi, logs = self._drawn(reach)
        found = []
        for sigma, edge in itertools.product((1, -1), (False, True) if reach else (False,)):

            def designs(
                u: np.ndarray, sigma: int = sigma, edge: bool = edge
            ) -> tuple[np.ndarray, np.ndarray]:
                z = spread(u, lo, hi, logs)
                if edge:
                    z[:, -1] = np.where(z[:, -1] < 0, -1.0, 1.0)
                x, margin = self._on(z, sigma)
                return self._smallest(self._placed(z, x) if reach else x), margin

            def value(u: np.ndarray, designs: Any = designs) -> np.ndarray:  # u by columns
                x, margin = designs(u.T)
                return measure(x, np.where(margin < 0, 0.0, 1.0 + margin))

            best = differential_evolution(
                value,
                [(0.0, 1.0)] * len(lo),
                popsize=POPULATION,
                maxiter=GENERATIONS,
                seed=0,
                polish=False,
                vectorized=True,
                updating="deferred",
            ).x
            found.append(designs(best[None])[0])
        return np.vstack(found)

    def _drawn(self, reach: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The box ``draw`` draws from, and where log-uniformly; with ``reach``, the path's
        placement as ``_placed``'s u, within ±1."""
        lo, hi = np.array([(EDGE, math.pi - EDGE), DRAWN_V, *self.box[2:]]).T
        logs = np.r_[[False] * (len(self.box) - len(self.own_at)), self.lo[self.own_at] > 0]
        if reach:
            lo[-1], hi[-1], logs[-1] = -1.0, 1.0, False
        return lo, hi, logs

    def _reaches(self) -> bool:
        """Whether the rod's path's placement is a coordinate and the rod's length known."""
        return "h" in self.names and ("l" in self.names or self.rod is not None)

    def _placed(self, z: np.ndarray, x: np.ndarray) -> np.ndarray:
        """The designs x at the points z (rows alike) with the rod's path within its reach of
        C's ends: at C's height there + u (c − ``ONE_WAY``) l, u the last coordinate (within
        ±1), c = cos(ψ/2), l the rod's length (fixed or drawn): the slider moves one way over
        the swing exactly where |u| ≤ 1 (``rod.rule``)."""
        rod = z[:, -2] if self.rod is None else self.rod
        arm, h = self.free.index(self.arm), self.own_at[-1]
        c = np.cos(z[:, 0] / 2)
        x[:, h] = x[:, arm] * c + rod * z[:, -1] * (c - ONE_WAY)
        return x

    def _on(self, z: np.ndarray, sigma: int) -> tuple[np.ndarray, np.ndarray]:
        """The designs at the points z on sheet σ (rows) and their circuits' margins (< 0:
        the toggles in one circuit), in one call."""
        x, _, margin, _ = self._parts(self.fn(z, self.constants(sigma, 0.0)))
        return x.T, margin

    def _at(self, z: np.ndarray) -> np.ndarray:
        """The designs at the points z on each sheet (rows: every point on one sheet, then
        on the other), in one call a sheet (each its own, to the bit)."""
        return np.vstack([self._on(z, sigma)[0] for sigma in (1, -1)])

    def end(self, x: np.ndarray) -> np.ndarray:
        """The design x(z) at a point; where the scale is free and no coordinate, the smallest
        the box allows (a copy)."""
        return self._smallest(x.copy())

    def _smallest(self, x: np.ndarray) -> np.ndarray:
        """The designs x (rows, or one) at the smallest scale the box's lower bounds allow,
        where the scale is free and no coordinate (else as they are)."""
        if self.scaled or self.pinned is not None:
            return x
        links = x[..., self.links]
        x[..., self.links] *= np.max(self.lo[self.links] / links, axis=-1, keepdims=True)
        return x


def applies(m: Mechanism, variant: frozenset[str], free: tuple[str, ...]) -> bool:
    """Whether the variant's free parameters are its construction's: the arm and every link
    free, or all but one (whose length then sets the scale); the rod's length and its path's
    placement free or fixed."""
    r = m.construction
    if r is None:
        return False
    rod = {n for n in (r.rod, r.height) if n and r.rod not in variant}
    core = {*r.links, r.arm}
    return r.arm in free and len(core - set(free)) <= 1 and set(free) <= core | rod


def _pinned(r: Roles, free: tuple[str, ...]) -> str | None:
    """The four-bar's link that is fixed (at most one where the chart ``applies``), or None."""
    return next((n for n in r.links if n not in free), None)


def function(m: Mechanism, variant: frozenset[str], free: tuple[str, ...], scale: bool) -> Mapped:
    """This thread's function of the variant's coordinates (with the scale one of them, or
    not), compiled, at points z (a row each) with shared constants: (z, constants) → x,
    ∂x/∂z (by columns), the circuit's margin (< 0: one circuit) and its gradient, a column
    a point (``warm`` builds them before a service is ready)."""
    cache: dict[Any, Mapped] = _local.__dict__.setdefault("charts", {})
    key = (m.type, variant, free, scale)
    if key not in cache:
        assert m.construction is not None
        fn = _function(m.construction, free, names(m.construction, free, scale))
        cache[key] = Mapped(fn, (False, True))
    return cache[key]


def names(r: Roles, free: tuple[str, ...], scale: bool) -> tuple[str, ...]:
    """The coordinates' names: ψ, v, the scale's log s where it is one (the measure depends
    on it and no link is fixed), the rod's length l and its path's placement h where they
    are free."""
    s = ("s",) if scale and _pinned(r, free) is None else ()
    return ("psi", "v", *s, *({r.rod: "l", r.height: "h"}[n] for n in _own(r, free)))


def _own(r: Roles, free: tuple[str, ...]) -> list[str]:
    """The rod's length and its path's placement, those of them free."""
    return [n for n in (r.rod, r.height) if n is not None and n in free]


def _function(r: Roles, free: tuple[str, ...], names: tuple[str, ...]) -> ca.Function:
    z, c = ca.SX.sym("z", len(names)), ca.SX.sym("c", 4)
    lam = 1 + ca.exp(z[1])
    q = dict.fromkeys(PARAMS, 0.0) | {"ep_r": c[0], "ep_i": c[1], "arm": c[2]}
    q |= {"swings": float(r.swings), "free_scale": 1.0} | {f"hi{i}": 1.0 for i in range(4)}
    got = dict(zip(ROWS, rows(z[0], lam, ca.vertcat(*(q[n] for n in PARAMS))), strict=True))
    ratios = dict(zip(r.links, (1, got["a2"], got["a3"], got["a4"]), strict=True))
    pinned = _pinned(r, free)
    k = ca.exp(z[names.index("s")] if "s" in names else c[3])
    if pinned is not None:  # c[3]: the fixed link's log
        k /= ratios[pinned]
    value = {n: k * a for n, a in ratios.items()}
    value[r.arm] = got["r5"]
    for name, part in (("l", r.rod), ("h", r.height)):
        if name in names and part is not None:
            value[part] = z[names.index(name)]
    x = ca.vertcat(*(value[n] for n in free))
    zr, zi = crank(z[0], lam, c[0], c[1])
    # sin θ sin(θ + φ) itself, not up to |z1|²: with a short crank that factor made the row
    # ~1e-5 far off its circuit, and SLSQP's runs went there (a design of another time ratio
    # and stroke, its measure far below any design's) and stayed, hundreds of iterations
    margin = circuit(zr, zi, c[0], c[1]) / (zr * zr + zi * zi)
    out = ca.densify(ca.vertcat(x, ca.vec(ca.jacobian(x, z)), margin, ca.gradient(margin, z)))
    return ca.Function("chart", [z, c], [out], {"cse": True})
