"""Reduced synthesis of the four-bar types (crank_rocker_slider, drag_link_slider).

Both are solved on the crank-rocker: a drag-link (ground g, crank a, coupler b, follower c)
moves as the crank-rocker (ground a, crank g, coupler c, rocker b), with the same time ratio
(its dead centres are the crank-rocker's toggles) and the same coupler transmission angle.

**The dead-centre construction.** Ground 1, crank a2, coupler a3 = λ a2 (λ > 1), rocker a4.
At the two toggles the crank and coupler are collinear; from the extended toggle to the
folded one the crank turns φ = π + σβ (σ = ±1: two sheets of solutions) and the rocker
swings ψ. The loop closures at the toggles (Söylemez 2002),

    (1 + λ) Z1 − Z2 = 1,    (1 − λ) e^{iφ} Z1 − e^{iψ} Z2 = 1,

are linear in the crank and rocker vectors Z1, Z2 at the extended toggle, so

    Z1 = (1 − e^{iψ}) / ((1 − λ) e^{iφ} − (1 + λ) e^{iψ}),   Z2 = (1 + λ) Z1 − 1,

and every (σ, ψ, λ) is one four-bar with the time ratio and the swing: a2 = |Z1|, a4 = |Z2|.
It is a design when it is a Grashof crank-rocker whose toggles lie in one assembly circuit,
sin θ sin(θ + φ) < 0 with θ = arg Z1. The worst coupler transmission is at the crank on the
ground line: f = max(c1, −c2) with c1, c2 = (a3² + a4² − (1 ∓ a2)²)/(2 a3 a4).

**What is known about f** (derived where stated, otherwise established by dense sampling and
checked in the tests against an independent global search): on σ = +1, for each ψ, f has a
single minimum in λ, and that minimum is least at ψ = β, where a2 = sin(β/2) = s for every λ
and f = c1 = ((λ² − 1)s + 1)/(λ sqrt(1 − s² + λ²s²)) is least at λ² = 1 + 1/s (derived):

    cos μ* = 2√s/(1 + s),   sin μ* = (1 − s)/(1 + s),

with links (1, s, sqrt(s(1 + s)), sqrt(1 + s)) / s... (ground 1/s, crank 1, coupler
sqrt(1 + 1/s), rocker sqrt((1 + 1/s)/s) for a unit crank). The sheet σ = −1 transmits worse
than σ = +1 at every swing. So the best design is this closed form when the swing ψ = β is
allowed, else at the nearest allowed swing with λ found by Newton's method.

The rest follows the four-bar: its scale is free (the smallest the bounds allow, to break
ties), the crank-rocker's arm sets the stroke, 2 r5 sin(ψ/2) = 1, the drag-link's is half the
stroke, and a connecting rod takes the rule of ``_rod``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..reduced import MAX_TRANSMISSION, Problem, Reduced, clip, newton, rod, unreachable

U_LO, U_HI = -9.0, 6.0  # λ = 1 + e^u: couplers from 1.0001 to 400 cranks
GRID = 48
STEP = (U_HI - U_LO) / (GRID - 1)  # the grid's spacing in u


@dataclass(frozen=True)
class Roles:
    """A type's parameters in the crank-rocker's roles."""

    links: tuple[str, str, str, str]  # the crank-rocker's ground, crank, coupler, rocker
    arm: str
    rod: str
    height: str | None  # the slider path's placement (crank-rocker), None: on the ground line
    swings: bool  # the arm swings with the rocker (stroke 2 r5 sin(ψ/2)); else stroke 2 r5


def shape(sigma: int, beta: float, psi, lam):
    """(a2, a3, a4, valid) of the construction, vectorised over ψ and λ."""
    e_phi = -complex(math.cos(sigma * beta), math.sin(sigma * beta))  # e^{iφ}, φ = π + σβ
    e_psi = np.exp(1j * psi)
    z1 = (1 - e_psi) / ((1 - lam) * e_phi - (1 + lam) * e_psi)
    a2 = np.abs(z1)
    a3, a4 = lam * a2, np.abs((1 + lam) * z1 - 1)
    longest = np.maximum(np.maximum(1.0, a3), a4)
    valid = (
        (z1.imag * (z1 * e_phi).imag < 0)  # sin θ sin(θ + φ) < 0: one assembly circuit
        & (a2 <= np.minimum(1.0, a4))
        & (a2 + longest <= 1 + a3 + a4 - longest)
    )
    return a2, a3, a4, valid


def worst_cos(a2, a3, a4):
    """The largest |cos μ| of the coupler transmission over a revolution."""
    base = a3 * a3 + a4 * a4
    c1 = (base - (1 - a2) ** 2) / (2 * a3 * a4)
    c2 = (base - (1 + a2) ** 2) / (2 * a3 * a4)
    return np.maximum(c1, -c2)


class FourBar:
    """One variant of a four-bar type, with the problem's fixed parts and bounds."""

    def __init__(self, p: Problem, roles: Roles) -> None:
        self.p, self.r = p, roles
        self.fixed_links = [n for n in roles.links if n in p.fixed]
        self.rod = roles.rod not in p.variant
        # the scale's limits from each link's box (the fixed links after the first are held by
        # their ratios instead)
        boxes = [p.box(n) if n not in self.fixed_links[1:] else (0, math.inf) for n in roles.links]
        self.lo, self.hi = np.array(boxes).T
        # the link whose fixed length sets the scale; else the smallest the bounds allow
        self.set_by = roles.links.index(self.fixed_links[0]) if self.fixed_links else None
        # the ratios the other fixed links impose: log(ρ_j/ρ_first) = log(F_j/F_first)
        first = self.fixed_links[0] if self.fixed_links else None
        self.ratios = [
            (roles.links.index(n), math.log(p.fixed[n] / p.fixed[first]))
            for n in self.fixed_links[1:]
        ]
        lo, hi = p.box(roles.arm)
        self.empty = False  # the bounds leave no arm for the stroke
        if roles.swings:  # the stroke is 2 r5 sin(ψ/2): ψ from the arm's box
            if roles.arm in p.fixed and hi < 0.5:
                raise unreachable(
                    f"{roles.arm} {p.shown(hi)} gives at most stroke {p.shown(2 * hi)}"
                )
            self.empty = hi < 0.5
            self.psi = (2 * math.asin(0.5 / max(hi, 0.5)), 2 * math.asin(0.5 / max(lo, 0.5)))
        else:  # the arm is half the stroke (a fixed one is judged by the driver)
            self.empty = roles.arm not in p.fixed and not lo <= 0.5 <= hi
            self.psi = (1e-3, math.pi - 1e-3)

    # --- the design at points (σ, ψ, λ) -----------------------------------------------------

    def evaluate(self, sigma: int, psi, lam):
        """The designs at (ψ, λ), arrays: valid, feasible (within the bounds), f (the coupler's
        worst cos), size, k (the four-bar's scale), ρ (its links at scale 1, the crank-rocker's
        order), r5, l, h and the rod's worst cos."""
        a2, a3, a4, valid = shape(sigma, self.p.beta, psi, lam)
        rho = (1.0, a2, a3, a4)
        f = worst_cos(a2, a3, a4)
        lo = [b / r for b, r in zip(self.lo, rho, strict=True)]
        hi = [b / r for b, r in zip(self.hi, rho, strict=True)]
        kmin = np.maximum(np.maximum(lo[0], lo[1]), np.maximum(lo[2], lo[3]))
        kmax = np.minimum(np.minimum(hi[0], hi[1]), np.minimum(hi[2], hi[3]))
        k = kmin if self.set_by is None else lo[self.set_by]
        feasible = valid & (kmin <= kmax * (1 + 1e-12))
        r5 = (0.5 / np.sin(psi / 2) if self.r.swings else self.p.fixed.get(self.r.arm, 0.5)) + 0 * f
        l, h, rod_cos = self._rod(r5, psi, f)
        feasible &= np.isfinite(l)
        size = k * (1 + a2 + a3 + a4) + r5 + np.where(np.isfinite(l), l, 0.0)
        return {"valid": valid, "feasible": feasible, "f": f, "size": size, "k": k, "rho": rho,
                "r5": r5, "l": l, "h": h, "rod_cos": rod_cos}  # fmt: skip

    def _rod(self, r5, psi, f):
        """The connecting rod (``reduced.rod``); none in a slot drive."""
        if not self.rod:
            return 0.0 * r5, np.full(np.shape(r5), np.nan), 0.0 * r5
        return rod(self.p, self.r.rod, self.r.height, r5, psi / 2, f)

    def design(self, sigma: int, psi: float, lam: float) -> tuple[dict[str, float], dict]:
        """The design at one point, and its evaluation."""
        e = self.evaluate(sigma, np.array([psi]), np.array([lam]))
        one = {k: float(np.ravel(v)[0]) for k, v in e.items() if k != "rho"}
        r = self.r
        out = {n: one["k"] * float(np.ravel(x)[0]) for n, x in zip(r.links, e["rho"], strict=True)}
        out[r.arm] = one["r5"]
        if self.rod:
            out[r.rod] = one["l"]
            if r.height:
                out[r.height] = one["h"]
        return {**out, **self.p.fixed}, one

    # --- the optima ----------------------------------------------------------------------------

    def solve(self) -> Reduced:
        if self.empty:
            return Reduced([])
        if self.p.objective == MAX_TRANSMISSION:
            return self.best_transmission()
        return self.smallest(self.p.cos_bound)

    def best_transmission(self) -> Reduced:
        """σ = +1 at the allowed swing nearest β: λ in closed form there, else by Newton; with
        two or more links fixed, the best point of the curve (or points) they leave."""
        beta = self.p.beta
        lo, hi = self.psi
        psi = clip(beta, lo, hi)
        if self.ratios:
            found = self.optimum(1, "f")
            if not found:
                return Reduced([], exact=not self.fixed_links or len(self.ratios) < 2)
            d, e = found[0]
        else:
            if psi == beta and beta > 0:
                lam = math.sqrt(1 + 1 / math.sin(beta / 2))
            else:
                found = self.optimum(1, "f", psi_fixed=psi)
                if not found:
                    return Reduced([], exact=False)
                lam = found[0][1]["lam"]
            d, e = self.design(1, psi, lam)
        if not e["valid"]:
            return Reduced([], exact=False)
        if e["rod_cos"] > e["f"] * (1 + 1e-12):  # the rod limits: ties are the smallest design
            if self.r.swings:
                return Reduced([d], exact=False)
            return self.smallest(e["rod_cos"], d)
        return Reduced([d], exact=bool(e["feasible"]))

    def smallest(self, cos_bound: float, start: dict | None = None) -> Reduced:
        """The smallest design with the coupler's worst cos ≤ ``cos_bound``: on σ = +1, and
        on σ = −1 only where σ = +1 has none (it was never smaller in a survey of 300 random
        targets)."""
        for sigma in (1, -1):
            found = self.optimum(sigma, "size", cos_bound)
            if found:
                return Reduced([d for d, _ in found])
        return Reduced([start] if start else [], exact=start is None)

    def optimum(self, sigma: int, objective: str, cos_bound: float = 1.0, psi_fixed=None):
        """Local optima on sheet σ of the coupler's worst cos (``objective`` "f") or of the size
        with that cos ≤ ``cos_bound`` ("size"), where the fixed links' ratios hold and the
        swing is in range (or ``psi_fixed``): a grid, then Newton from its best points. With
        the ratios fixing the point (three links fixed), every root. [(design, evaluation)]"""
        lo, hi = self.psi if psi_fixed is None else (psi_fixed, psi_fixed)
        if lo == hi:
            psi_fixed = lo
        psi = np.linspace(lo, hi, 1 if psi_fixed is not None else GRID)[:, None]
        u = np.linspace(U_LO, U_HI, GRID if psi_fixed is None else 4 * GRID)[None, :]
        starts = self._starts(sigma, psi, u, objective, cos_bound)
        found = []
        for x0 in starts:
            x = self._newton(sigma, x0, objective, cos_bound, psi_fixed)
            if x is None:
                continue
            d, e = self.design(sigma, x[0], 1 + math.exp(x[1]))
            e["lam"] = 1 + math.exp(x[1])
            if e["feasible"] and (objective == "f" or e["f"] <= cos_bound * (1 + 1e-12)):
                found.append((d, e))
        key = "f" if objective == "f" else "size"
        found.sort(key=lambda de: de[1][key])
        return found if len(self.ratios) >= (1 if psi_fixed is not None else 2) else found[:1]

    def _starts(self, sigma, psi, u, objective, cos_bound) -> list[np.ndarray]:
        """Grid points to start Newton from: the best one (no ratio fixed), the best crossing
        of the ratio's curve (one), or the crossings of both curves (two)."""
        e = self.evaluate(sigma, psi, 1 + np.exp(u))
        value = e["f"] if objective == "f" else e["size"]
        ok = e["feasible"] & ((objective == "f") | (e["f"] <= cos_bound))
        pts = np.stack(np.broadcast_arrays(psi, u), axis=-1)  # (rows, cols, 2)
        if not self.ratios:
            if not np.any(ok):
                return []
            i, j = np.unravel_index(np.argmin(np.where(ok, value, np.inf)), ok.shape)
            return [pts[i, j]]
        res = self.residuals(e)
        x = _crossings(res[0], e["valid"], pts)
        if len(x) == 0:
            return []
        if len(self.ratios) == 1 and psi.size > 1:
            ev = self.evaluate(sigma, x[:, 0], 1 + np.exp(x[:, 1]))
            v = ev["f"] if objective == "f" else ev["size"]
            good = ev["feasible"] & ((objective == "f") | (ev["f"] <= cos_bound))
            if objective == "size" and not np.any(good):
                good = ev["feasible"]  # the bound may hold only between the crossings
            return [x[int(np.argmin(np.where(good, v, np.inf)))]] if np.any(good) else []
        if psi.size == 1:
            return list(x)
        # two ratios: the first one's crossings nearest to the second's
        second = _crossings(res[1], e["valid"], pts)
        if len(second) == 0:
            return []
        gap = np.linalg.norm(x[:, None, :] - second[None, :, :], axis=-1)
        near = [x[n] for n in np.unique(np.argmin(gap, axis=0)) if gap[n].min() <= 2 * STEP]
        starts: list[np.ndarray] = []
        for y in near:  # one start per intersection
            if all(np.linalg.norm(y - z) > 2 * STEP for z in starts):
                starts.append(y)
        return starts

    def residuals(self, e) -> list[np.ndarray]:
        """log(ρ_j/ρ_first) − log(F_j/F_first) for each fixed link after the first."""
        return [np.log(e["rho"][j] / e["rho"][self.set_by]) - c for j, c in self.ratios]

    def _newton(self, sigma, x0, objective, cos_bound, psi_fixed):
        """Newton from x0 = (ψ, u) with the ratios (and, for the size, the bound where it
        binds) as equalities; a swing that leaves its range is held at the nearer edge."""
        lo, hi = self.psi
        x = self._newton_at(sigma, x0, objective, cos_bound, psi_fixed)
        if psi_fixed is None and (x is None or not lo <= x[0] <= hi):
            edge = lo if (x if x is not None else x0)[0] < (lo + hi) / 2 else hi
            x = self._newton_at(sigma, x0, objective, cos_bound, edge)
        return x

    def _newton_at(self, sigma, x0, objective, cos_bound, psi):
        for bound_active in (True, False) if objective == "size" else (False,):
            rows = self._rows(sigma, objective, cos_bound, bound_active, psi)
            n_eq = len(self.ratios) + bound_active
            y0 = x0 if psi is None else x0[1:]
            if n_eq > y0.size:
                continue
            y = newton(rows, y0, n_eq, np.ones(y0.size))
            if y is not None:
                return y if psi is None else np.array([psi, y[0]])
        return None

    def _rows(self, sigma, objective, cos_bound, bound_active, psi_fixed):
        def rows(x):
            ps = x[:, 0] if psi_fixed is None else np.full(len(x), psi_fixed)
            e = self.evaluate(sigma, ps, 1 + np.exp(x[:, -1]))
            out = [e["f"] if objective == "f" else e["size"], *self.residuals(e)]
            if bound_active:
                out.append(e["f"] - cos_bound)
            return np.where(e["feasible"], np.array(out), np.nan)

        return rows


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
