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
stroke; a connecting rod follows ``rod.rule``.

Everything above is written once (``rows``), a function of a point (ψ, λ) and the variant's
numbers (``PARAMS``: every structural choice of a variant, the fixed link that sets the
scale, a swinging arm, a rod, its path's placement, the objective, is a number there, so one
function serves every variant). Built in CasADi and compiled (``synth.numerics.native``) it
evaluates a Newton step's few points and a design through preallocated buffers, and its
derivatives (``Compiled.taylor``) are CasADi's automatic differentiation of it; on numpy
arrays it evaluates a search's grid, all points at once.
"""

from __future__ import annotations

import math
import threading
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, NamedTuple, cast

import casadi as ca
import numpy as np

from ...errors import Unreachable
from ...numerics.native import Points
from ...numerics.ops import CASADI, NUMPY, Ops
from .. import rod
from ..reduced import Problem, unreachable
from ..registry import Roles
from .geometry import grashof_margins, worst_cos

BOUND_TOL = 1e-9  # relative: a link this far past its bound is on it (Newton's 1e-10 on a ratio)
# from this many points on (a search's grid) ``rows`` runs on numpy's whole arrays: ~0.1 µs a
# point and ~150 µs a call, against the compiled function's ~0.25 µs a point
WHOLE = 1024

# the parameter vector: the names of its entries, in order
PARAMS = (
    "ep_r",
    "ep_i",  # e^{iφ}, φ = π + σβ
    "lo0",
    "lo1",
    "lo2",
    "lo3",
    "hi0",
    "hi1",
    "hi2",
    "hi3",  # the links' boxes (scale 1)
    "free_scale",
    "set0",
    "set1",
    "set2",
    "set3",  # the scale free, or set by link i
    "swings",
    "arm",  # the arm swings (r5 = 1/(2 sin(ψ/2))), else its length
    "rod",
    *rod.PARAMS,  # a connecting rod (rod.rule)
)
ROWS = ("valid", "feasible", "f", "size", "k", "a2", "a3", "a4", "r5", "l", "h", "rod_cos", "slack")
# the rows of the local model (``Compiled.taylor``): the coupler's worst cos, the size and the
# logs of the links at scale 1 (the ground's is 0)
TAYLOR = ("f", "size", "log_a2", "log_a3", "log_a4")
AT = 2  # where the first row's six numbers start in ``Compiled.taylor``'s list

_local = threading.local()


@dataclass(frozen=True)
class Evaluation:
    """The designs at points (ψ, λ) of sheet ``sigma``, the rows (``ROWS``) by name: arrays
    (``Construction.evaluate``; a point that is no design is NaN or False) or one point's
    numbers (``Construction.design``; valid and feasible 1 or 0). ``valid``: a design;
    ``feasible``: within the bounds; ``f``: the coupler's worst cos; ``k``: the four-bar's
    scale; ``rho``: its links at scale 1, the crank-rocker's order; ``r5``: the arm; the rod's
    length, its path's placement and its worst cos; ``slack``: the log distance from a link's
    bound; ``at``: the point (ψ, u) a search found the design at (None: none did)."""

    valid: Any
    feasible: Any
    f: Any
    size: Any
    k: Any
    rho: tuple[Any, Any, Any, Any]
    r5: Any
    rod_length: Any
    height: Any
    rod_cos: Any
    slack: Any
    sigma: int
    at: Any = None

    def measure(self, key: str) -> Any:
        """What a search minimises, by its name: "f" (the coupler's worst cos) or "size"."""
        return self.f if key == "f" else self.size


class Design(NamedTuple):
    """A design's parameters and its evaluation."""

    params: dict[str, float]
    evaluation: Evaluation


def _evaluation(rows: Sequence[Any], sigma: int, at: Any = None) -> Evaluation:
    """The record of ``ROWS``' values."""
    valid, feasible, f, size, k, a2, a3, a4, r5, l, h, rod_cos, slack = rows
    return Evaluation(
        valid, feasible, f, size, k, (1.0, a2, a3, a4), r5, l, h, rod_cos, slack, sigma, at
    )


def crank(psi: Any, lam: Any, er: Any, ei: Any, ops: Ops = CASADI) -> tuple[Any, Any]:
    """The crank vector at the extended toggle, z1 = (1 − e^{iψ}) / ((1 − λ) e^{iφ} − (1 +
    λ) e^{iψ}), in real arithmetic (er, ei: e^{iφ})."""
    cp, sp = ops.cos(psi), ops.sin(psi)
    nr, ni = 1 - cp, -sp
    dr, di = (1 - lam) * er - (1 + lam) * cp, (1 - lam) * ei - (1 + lam) * sp
    dd = dr * dr + di * di
    return (nr * dr + ni * di) / dd, (ni * dr - nr * di) / dd


def circuit(zr: Any, zi: Any, er: Any, ei: Any) -> Any:
    """Negative where the toggles lie in one assembly circuit, sin θ sin(θ + φ) < 0 (θ = arg
    z1), up to the positive factor |z1|²."""
    return zi * (zr * ei + zi * er)


def rows(psi: Any, lam: Any, p: Any, ops: Ops = CASADI) -> tuple[Any, ...]:
    """The rows (``ROWS``) at (ψ, λ) with the parameters p (``PARAMS``): CasADi symbols, or
    numpy arrays (``ops``)."""
    q = {n: p[i] for i, n in enumerate(PARAMS)}
    er, ei = q["ep_r"], q["ep_i"]
    zr, zi = crank(psi, lam, er, ei, ops)
    a2 = ops.sqrt(zr * zr + zi * zi)
    a3 = lam * a2
    wr, wi = (1 + lam) * zr - 1, (1 + lam) * zi
    a4 = ops.sqrt(wr * wr + wi * wi)
    # one assembly circuit, and Grashof with the crank the shortest link
    valid = circuit(zr, zi, er, ei) < 0
    for margin in grashof_margins((1.0, a2, a3, a4), 1):
        valid = ops.logic_and(valid, margin >= 0)
    f = worst_cos(1.0, a2, a3, a4, ops)
    # the scale
    rho = (1.0, a2, a3, a4)
    lo = [q[f"lo{i}"] / r for i, r in enumerate(rho)]
    hi = [q[f"hi{i}"] / r for i, r in enumerate(rho)]
    kmin = ops.fmax(ops.fmax(lo[0], lo[1]), ops.fmax(lo[2], lo[3]))
    kmax = ops.fmin(ops.fmin(hi[0], hi[1]), ops.fmin(hi[2], hi[3]))
    k = ops.if_else(q["set2"], lo[2], lo[3])
    k = ops.if_else(q["set0"], lo[0], ops.if_else(q["set1"], lo[1], k))
    k = ops.if_else(q["free_scale"], kmin, k)
    feasible = ops.logic_and(valid, kmin <= kmax * (1 + BOUND_TOL))

    # how far the design is from a link's bound: the scale's room, log(kmax/kmin), when it is
    # free; else the free links' distance from their boxes, in log (one log of the least
    # ratio: log is monotonic)
    def least() -> Any:
        rest = [
            ops.if_else(q[f"set{i}"], math.inf, ops.fmin(k / a, b / k))
            for i, (a, b) in enumerate(zip(lo, hi, strict=True))
        ]
        return ops.fmin(ops.fmin(rest[0], rest[1]), ops.fmin(rest[2], rest[3]))

    slack = ops.log(ops.choose(q["free_scale"], lambda: kmax / kmin, least))
    r5 = ops.choose(q["swings"], lambda: 0.5 / ops.sin(psi / 2), lambda: q["arm"])
    # the connecting rod (none in a slot drive)
    l, h, rc, l_ok = ops.choose(
        q["rod"], lambda: rod.rule(r5, psi / 2, f, q, ops), lambda: (0.0, math.nan, 0.0, True)
    )
    l_fin = ops.logic_or(ops.logic_not(q["rod"]), l_ok)
    feasible = ops.logic_and(feasible, l_fin)
    size = k * (1 + a2 + a3 + a4) + r5 + ops.if_else(l_fin, l, 0.0)
    return valid, feasible, f, size, k, a2, a3, a4, r5, l, h, rc, slack


class Compiled:
    """This thread's compiled construction: ``points`` (the rows at many points) and
    ``taylor`` (the local model at one point, for Newton)."""

    def __init__(self) -> None:
        x, p = ca.SX.sym("x", 2), ca.SX.sym("p", len(PARAMS))
        out = ca.vertcat(*rows(x[0], x[1], p))
        self.points = Points(ca.Function("fourbar_construction", [x, p], [out], {"cse": True}))
        # at y = (ψ, u), λ = 1 + e^u (Newton's coordinates)
        y = ca.SX.sym("y", 2)
        at = ca.vertcat(*rows(y[0], 1 + ca.exp(ca.fmin(y[1], 50.0)), p))
        named = [at[ROWS.index("f")], at[ROWS.index("size")]]
        named += [ca.log(at[ROWS.index(n)]) for n in ("a2", "a3", "a4")]
        local = [at[ROWS.index("valid")], at[ROWS.index("l")]]
        for r in named:
            h, g = ca.hessian(r, y)
            local += [r, g[0], g[1], h[0, 0], h[0, 1], h[1, 1]]
        self.local = Points(
            ca.Function("fourbar_construction_taylor", [y, p], [ca.vertcat(*local)], {"cse": True})
        )

    def taylor(self, psi: float, u: float, params: Sequence[float]) -> list[float]:
        """At one point (ψ, u), λ = 1 + e^u, a list: valid, the rod's length (NaN where no rod
        fits), then for each row of ``TAYLOR`` its value, its gradient in (ψ, u) and its
        Hessian's entries ∂ψψ, ∂ψu, ∂uu (six numbers a row, from ``AT``; ``params`` as for
        ``points``)."""
        return self.local.one((psi, u), params)


def construction() -> Compiled:
    """This thread's compiled construction (CasADi functions are never shared by threads)."""
    if not hasattr(_local, "compiled"):
        _local.compiled = Compiled()
    return cast(Compiled, _local.compiled)


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
            (
                roles.links.index(n),
                cast(int, self.set_by),
                math.log(p.fixed[n] / p.fixed[cast(str, first)]),
            )
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

    def evaluate(self, sigma: int, psi: Any, lam: Any) -> Evaluation:
        """The designs at (ψ, λ), arrays broadcast together."""
        psi, lam = np.asarray(psi, dtype=float), np.asarray(lam, dtype=float)
        shape = np.broadcast_shapes(psi.shape, lam.shape)
        e: list[Any]
        if math.prod(shape) >= WHOLE:
            with np.errstate(all="ignore"):
                grid = rows(psi, lam, self._params(sigma), NUMPY)
            e = [r if np.shape(r) == shape else np.broadcast_to(r, shape) for r in grid]
        else:
            if psi.shape != shape or lam.shape != shape or psi.ndim != 1:
                psi, lam = (np.broadcast_to(a, shape).ravel() for a in (psi, lam))
            values = construction().points((psi, lam), self._params(sigma))
            e = list(values.reshape(len(ROWS), *shape))
        e[0], e[1] = e[0] > 0, e[1] > 0  # valid, feasible
        return _evaluation(e, sigma)

    def _params(self, sigma: int) -> list[float]:
        """The compiled function's parameters (``PARAMS``) for sheet σ, kept per sheet, bounds
        and rod: a copy of this construction (``copy.copy``, ``holding``)
        shares the cache but may differ in its rod or its bounds' arrays (replaced, never
        changed in place)."""
        key = (sigma, id(self.lo), id(self.hi), self.rod)
        cache: dict[tuple[int, int, int, bool], tuple[list[float], np.ndarray, np.ndarray]]
        cache = self.__dict__.setdefault("_param_cache", {})
        if key not in cache:
            cache[key] = (self._make_params(sigma), self.lo, self.hi)  # the arrays kept alive
        return cache[key][0]

    def _make_params(self, sigma: int) -> list[float]:
        p, r = self.p, self.r
        sb = sigma * p.beta
        the_rod = rod.params(p, r.rod, r.height) if self.rod else [0.0] * len(rod.PARAMS)
        return [
            -math.cos(sb),
            -math.sin(sb),
            *self.lo,
            *self.hi,
            float(self.set_by is None),
            *(float(self.set_by == i) for i in range(4)),
            float(r.swings),
            p.fixed.get(r.arm, 0.5),
            float(self.rod),
            *the_rod,
        ]

    def design(self, sigma: int, psi: float, lam: float, at: Any = None) -> Design:
        """The design at one point, and its evaluation; ``at``: the point (ψ, u) a search
        found it at."""
        values = construction().points.one((psi, lam), self._params(sigma))
        one = _evaluation(values, sigma, at)
        r = self.r
        out = {n: one.k * x for n, x in zip(r.links, one.rho, strict=True)}
        out[r.arm] = one.r5
        if self.rod:
            out[r.rod] = one.rod_length
            if r.height:
                out[r.height] = one.height
        return Design({**out, **self.p.fixed}, one)

    def found(self, sigma: int, x: Any) -> Design:
        """The design a search found at x = (ψ, u), λ = 1 + e^u."""
        return self.design(sigma, x[0], 1 + math.exp(x[1]), x)

    def residuals(self, e: Evaluation) -> list[np.ndarray]:
        """log(ρ_i/ρ_j) − c for each ratio held."""
        return [np.log(e.rho[i] / e.rho[j]) - c for i, j, c in self.ratios]
