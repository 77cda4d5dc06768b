"""The four-bar types' dead-centre construction (crank_rocker_slider, drag_link_slider).

Both are built on the crank-rocker: a drag-link (ground g, crank a, coupler b, follower c)
moves as the crank-rocker (ground a, crank g, coupler c, rocker b), with the same time ratio
(its dead centres are the crank-rocker's toggles) and the same coupler transmission angle.

Ground 1, crank a2, coupler a3 = λ a2 (λ > 1), rocker a4. At the two toggles the crank and
coupler are collinear; from the extended toggle to the folded one the crank turns φ = π + σβ
(σ = ±1: two sheets of solutions) and the rocker swings ψ. The loop closures at the toggles
(Söylemez, *Mechanisms*, §7.1),

    (1 + λ) Z1 − Z2 = 1,    (1 − λ) e^{iφ} Z1 − e^{iψ} Z2 = 1,

are linear in the crank and rocker vectors Z1, Z2 at the extended toggle, so

    Z1 = (1 − e^{iψ}) / ((1 − λ) e^{iφ} − (1 + λ) e^{iψ}),   Z2 = (1 + λ) Z1 − 1,

and every (σ, ψ, λ) is one four-bar with the time ratio and the swing: a2 = |Z1|, a4 = |Z2|.
It is a design when it is a Grashof crank-rocker whose toggles lie in one assembly circuit,
sin θ sin(θ + φ) < 0 with θ = arg Z1. The worst coupler transmission is at the crank on the
ground line: f = max(c1, −c2) with c1, c2 = (a3² + a4² − (1 ∓ a2)²)/(2 a3 a4).

The rest follows the four-bar: its scale is free (the smallest the bounds allow, to break
ties), unless a fixed link sets it (further fixed links hold ratios of the construction's
links); the crank-rocker's arm sets the stroke, 2 r5 sin(ψ/2) = 1, the drag-link's is half the
stroke; a connecting rod follows ``reduced.rod``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ...errors import Unreachable
from ..reduced import MIN_SIZE, ONE_WAY, STRICT, Problem, rod, unreachable
from .compiled import MAX_WIDTH, ROWS, compiled

BOUND_TOL = 1e-9  # relative: a link this far past its bound is on it (Newton's 1e-10 on a ratio)


def construction():
    """This thread's compiled evaluation (``_fourbar_native``)."""
    return compiled(BOUND_TOL, STRICT, ONE_WAY)


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


class Construction:
    """One variant of a four-bar type on the construction, with the problem's fixed parts and
    bounds: the designs at points (σ, ψ, λ)."""

    def __init__(self, p: Problem, roles: Roles) -> None:
        self.p, self.r = p, roles
        self.fixed_links = [n for n in roles.links if n in p.fixed]
        shortest = roles.links[1]  # the crank-rocker's crank (a drag-link's ground)
        for n in self.fixed_links:
            if shortest in p.fixed and p.fixed[n] < p.fixed[shortest]:
                raise Unreachable(
                    "FIXED_PARTS_INVALID",
                    f"{shortest} {p.shown(p.fixed[shortest])} > {n} {p.shown(p.fixed[n])}: the "
                    f"{shortest} must be the shortest link",
                )
        self.rod = roles.rod not in p.variant
        # the scale's limits from each link's box (the fixed links after the first are held by
        # their ratios instead)
        boxes = [p.box(n) if n not in self.fixed_links[1:] else (0, math.inf) for n in roles.links]
        self.lo, self.hi = np.array(boxes).T
        # the link whose fixed length sets the scale; else the smallest the bounds allow
        self.set_by = roles.links.index(self.fixed_links[0]) if self.fixed_links else None
        # the ratios the fixed links impose, log(ρ_i/ρ_j) = c: each after the first against it
        first = self.fixed_links[0] if self.fixed_links else None
        self.ratios = [
            (roles.links.index(n), self.set_by, math.log(p.fixed[n] / p.fixed[first]))
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
            self.psi = (1e-9, math.pi - 1e-9)

    def evaluate(self, sigma: int, psi, lam):
        """The designs at (ψ, λ), arrays: valid, feasible (within the bounds), f (the coupler's
        worst cos), size, k (the four-bar's scale), ρ (its links at scale 1, the crank-rocker's
        order), r5, l, h and the rod's worst cos; a point that is no design is NaN or False.
        A few points (a Newton step's, a design's) are evaluated by the compiled function
        (``_fourbar_native``), a grid by numpy."""
        psi, lam = np.asarray(psi, dtype=float), np.asarray(lam, dtype=float)
        shape = np.broadcast_shapes(psi.shape, lam.shape)
        if 0 < math.prod(shape) <= MAX_WIDTH:
            return self._compiled(sigma, psi, lam, shape)
        with np.errstate(all="ignore"):
            return self._evaluate(sigma, psi, lam)

    def _compiled(self, sigma: int, psi, lam, shape):
        flat = len(shape) == 1
        if not flat or psi.shape != shape or lam.shape != shape:
            psi, lam = (np.broadcast_to(a, shape).ravel() for a in (psi, lam))
        out = construction().at(psi, lam, self._params(sigma))
        e = dict(zip(ROWS, out if flat else out.reshape(len(ROWS), *shape), strict=True))
        e["valid"], e["feasible"] = e["valid"] > 0, e["feasible"] > 0
        e["rho"] = (1.0, e.pop("a2"), e.pop("a3"), e.pop("a4"))
        return e

    def _params(self, sigma: int) -> list[float]:
        """The compiled function's parameters (``_fourbar_native.PARAMS``) for sheet σ, kept
        per sheet, bounds and rod: a copy of this construction (``copy.copy``, ``holding``)
        shares the cache but may differ in its rod or its bounds' arrays (replaced, never
        changed in place)."""
        key = (sigma, id(self.lo), id(self.hi), self.rod)
        cache = self.__dict__.setdefault("_param_cache", {})
        if key not in cache:
            cache[key] = (self._make_params(sigma), self.lo, self.hi)  # the arrays kept alive
        return cache[key][0]

    def _make_params(self, sigma: int) -> list[float]:
        p, r = self.p, self.r
        sb = sigma * p.beta
        rod_box = p.box(r.rod) if self.rod else (0.0, 0.0)
        fixed_h = r.height is not None and r.height in p.fixed
        h_box = p.bounds.get(r.height, (0.0, 0.0)) if r.height is not None else (0.0, 0.0)
        return [-math.cos(sb), -math.sin(sb), *self.lo, *self.hi,
                float(self.set_by is None), *(float(self.set_by == i) for i in range(4)),
                float(r.swings), p.fixed.get(r.arm, 0.5),
                float(self.rod), float(p.objective == MIN_SIZE), p.cos_bound, *rod_box,
                float(r.height is None), float(fixed_h),
                p.fixed[r.height] if fixed_h else 0.0, *h_box]  # fmt: skip

    def _evaluate(self, sigma: int, psi, lam):
        a2, a3, a4, valid = shape(sigma, self.p.beta, psi, lam)
        rho = (1.0, a2, a3, a4)
        f = worst_cos(a2, a3, a4)
        lo = [b / r for b, r in zip(self.lo, rho, strict=True)]
        hi = [b / r for b, r in zip(self.hi, rho, strict=True)]
        kmin = np.maximum(np.maximum(lo[0], lo[1]), np.maximum(lo[2], lo[3]))
        kmax = np.minimum(np.minimum(hi[0], hi[1]), np.minimum(hi[2], hi[3]))
        k = kmin if self.set_by is None else lo[self.set_by]
        feasible = valid & (kmin <= kmax * (1 + BOUND_TOL))
        # how far the design is from a link's bound: the scale's room, log(kmax/kmin), when it
        # is free; else the free links' distance from their boxes (in log)
        if self.set_by is None:
            slack = np.log(kmax / kmin)
        else:
            rest = [
                np.minimum(np.log(k / a), np.log(b / k))
                for i, (a, b) in enumerate(zip(lo, hi, strict=True))
                if i != self.set_by
            ]
            slack = np.minimum(np.minimum(rest[0], rest[1]), rest[2])
        r5 = (0.5 / np.sin(psi / 2) if self.r.swings else self.p.fixed.get(self.r.arm, 0.5)) + 0 * f
        l, h, rod_cos = self._rod(r5, psi, f)
        feasible &= np.isfinite(l)
        size = k * (1 + a2 + a3 + a4) + r5 + np.where(np.isfinite(l), l, 0.0)
        return {"valid": valid, "feasible": feasible, "f": f, "size": size, "k": k, "rho": rho,
                "r5": r5, "l": l, "h": h, "rod_cos": rod_cos, "slack": slack}  # fmt: skip

    def _rod(self, r5, psi, f):
        """The connecting rod (``reduced.rod``); none in a slot drive."""
        if not self.rod:
            return 0.0 * r5, np.full(np.shape(r5), np.nan), 0.0 * r5
        return rod(self.p, self.r.rod, self.r.height, r5, psi / 2, f)

    def design(self, sigma: int, psi: float, lam: float) -> tuple[dict[str, float], dict]:
        """The design at one point, and its evaluation (numbers; valid and feasible 1 or 0)."""
        out = construction().at((psi,), (lam,), self._params(sigma))
        one = dict(zip(ROWS, out[:, 0].tolist(), strict=True))
        one["rho"] = [1.0, one.pop("a2"), one.pop("a3"), one.pop("a4")]
        r = self.r
        out = {n: one["k"] * x for n, x in zip(r.links, one["rho"], strict=True)}
        out[r.arm] = one["r5"]
        if self.rod:
            out[r.rod] = one["l"]
            if r.height:
                out[r.height] = one["h"]
        return {**out, **self.p.fixed}, one

    def residuals(self, e) -> list[np.ndarray]:
        """log(ρ_i/ρ_j) − c for each ratio held."""
        return [np.log(e["rho"][i] / e["rho"][j]) - c for i, j, c in self.ratios]
