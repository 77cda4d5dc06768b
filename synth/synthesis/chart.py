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

import math
import threading
from typing import Any

import casadi as ca
import numpy as np

from ..mechanisms import Mechanism
from ..mechanisms.fourbar.construction import PARAMS, ROWS, circuit, crank, rows
from ..mechanisms.geometry import triangle_angle
from ..mechanisms.registry import Roles
from ..numerics.native import Mapped
from ..targets import beta
from .solve import starts as halton

MATCH = 1e-9  # relative: how closely a start's coordinates give the start back
FAR = 30.0  # the logs v and s stay within ±FAR (λ − 1 and the scale within e^±30)
EDGE = 1e-9  # ψ within (EDGE, π − EDGE)
DRAWN_V = (-7.0, 4.0)  # the range of v = log(λ − 1) that ``Chart.draw`` draws from
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
        n, k = len(self.free), len(z)
        out = self.fn(z[None, :], c)[:, 0]
        return out[:n], out[n : n + n * k].reshape(k, n).T, out[n + n * k], out[n + n * k + 1 :]

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
        reach of C's ends (C's height there + u l, u in (−1, 1), l the rod's length, fixed or
        drawn): few of the box's placements are, and a short rod's basins lie in that sliver
        (a crank-rocker's least peak torque at time ratio 2 and 0°, 11% below the slot
        drive's)."""
        lo, hi = np.array([(EDGE, math.pi - EDGE), DRAWN_V, *self.box[2:]]).T
        logs = np.r_[[False] * (len(self.box) - len(self.own_at)), self.lo[self.own_at] > 0]
        sets = [self._at(halton(lo, hi, logs, n // 2))]
        if "h" in self.names and ("l" in self.names or self.rod is not None):
            lo[-1], hi[-1], logs[-1] = -1.0, 1.0, False
            z = halton(lo, hi, logs, n // 2)
            reach = self._at(z)
            z = np.tile(z, (2, 1))  # as the designs' rows
            rod = z[:, -2] if self.rod is None else self.rod
            arm, h = self.free.index(self.arm), self.own_at[-1]
            reach[:, h] = reach[:, arm] * np.cos(z[:, 0] / 2) + rod * z[:, -1]
            sets.append(reach)
        return [self._smallest(x) for x in sets]

    def _at(self, z: np.ndarray) -> np.ndarray:
        """The designs at the points z on each sheet (rows: every point on one sheet, then
        on the other), in one call a sheet (each its own, to the bit)."""
        nx = len(self.free)
        return np.vstack([self.fn(z, self.constants(sigma, 0.0))[:nx].T for sigma in (1, -1)])

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
    margin = circuit(*crank(z[0], lam, c[0], c[1]), c[0], c[1])
    out = ca.densify(ca.vertcat(x, ca.vec(ca.jacobian(x, z)), margin, ca.gradient(margin, z)))
    return ca.Function("chart", [z, c], [out], {"cse": True})
