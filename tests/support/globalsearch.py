"""An independent global search for the synthesis optima: the referee of synth.synthesize.

Written from the model (the parameters and their meaning), sharing no formula or code with synth:
only the parameter names and default bounds are read from the registry (bounds are part of
the contract). Every design is at stroke 1 (lengths scale with the stroke; synthesise at 1).

Each quick-return type is reduced to an exact family of designs with the target time ratio and
stroke 1, so differential evolution needs no equality constraint:

- offset_slider_crank: the dead centres C1 (folded) and C2 = C1 + (1, 0) seen from O2 under the
  angle β; one angle α = ∠(x, O2C1) ∈ [β, π/2] fixes the design (|O2C1| = r3 − r2,
  |O2C2| = r3 + r2, C1 = (x1 ≥ 0, e)).
- crank_shaper: r2/d = sin(β/2), lever = 1/(2 sin(β/2)) (whatever its length: the targets
  set it alone, so the default bounds do not limit it); d free (and the ram link l, h).
- whitworth: d = r2 cos((π − β)/2), lever = 1/2; r2 and the rod free.
- crank_rocker_slider: ground 1, the rocker's toggle pins D_e, D_f on circle(O4, r4) seen from
  O2 at angles φe and φf = φe ± β (both above the ground line on the left-hand circuit):
  r3 ± r2 = |O2D_e|, |O2D_f|, each a root of a quadratic; r5 from the swing and stroke 1.
  The four-bar's scale is free within the bounds (only its ratios matter for TR and μ).
- drag_link_slider: crank 1, ground r1 and follower r4 free; the crank angles θ2a, θ2b with the
  follower on the ground line obey θ2b = θ2a ± β, and equating the coupler from both
  triangles gives A cos θ2a + B sin θ2a = C (two roots); follower_arm = 1/2.

The discrete choices (the signs, the roots, a slot drive or a link) are searched exhaustively.
Validity conditions, bounds and, for minimum size or a time-ratio extreme, the transmission
bound are inequalities: a feasibility-first penalty for the differential evolution (several
seeds), then SLSQP from each seed's best on the same functions. The overall best design is
checked by tests/support/bruteforce.py's forward simulation, so a slip in these closed forms cannot
produce a fake "better" design.
"""

from __future__ import annotations

import functools
import math
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import differential_evolution, minimize
from scipy.stats import qmc

from synth.mechanisms import get

from . import bruteforce, exact

PI = math.pi
STRICT = 1e-10  # margin kept by the strict (">") conditions: above FEASIBLE
FEASIBLE = 1e-12  # a polished design may miss a non-strict inequality by this much
PENALTY = 100.0  # above every feasible objective (|cos| ≤ 1, size ≤ 30, β < π)
TR_CAP = 20.0  # a time-ratio search stops here unless told where (its ``limit``)
PLACEMENTS = ("offset", "ram_height", "slider_height")  # not links: not in the size
GOALS = ("max_transmission_angle", "min_size", "max_time_ratio", "min_time_ratio")
TYPES = (
    "offset_slider_crank",
    "crank_shaper",
    "whitworth",
    "crank_rocker_slider",
    "drag_link_slider",
)


@dataclass(frozen=True)
class Effort:
    seeds: tuple[int, ...] = (0, 1, 2)
    popsize: int = 25  # × the dimension
    maxiter: int = 300
    polish: bool = True
    # with fixed parts, besides: the best distinct points of each branch among ``samples``
    # Sobol points, each polished (the optimum often lies on a thin sliver of the space,
    # where the evolution's population seldom goes)
    samples: int = 4096
    starts: int = 12


QUICK = Effort(seeds=(0, 1), popsize=15, maxiter=100, samples=512, starts=4)
FULL = Effort()


def beta_of(tr: float) -> float:
    """The stroke-angle excess: the slow stroke takes π + β, the quick one π − β."""
    return PI * (tr - 1) / (tr + 1)


def tr_of(beta):
    return (PI + beta) / (PI - beta)


# --------------------------------------------------------------------------- families
@dataclass
class Batch:
    """Designs at stroke 1, one per row: parameters, inequality margins (≥ 0 when valid),
    signed transmission cosines (the worst |·| is the minimum transmission angle), size."""

    params: dict[str, np.ndarray]
    margins: np.ndarray  # (n, m)
    cosines: np.ndarray  # (n, k), k = 0 for a slot drive
    size: np.ndarray


def _log(w, lo, hi):
    return lo * (hi / lo) ** w


def _lin(w, lo, hi):
    return lo + w * (hi - lo)


def _bounds(mtype: str, fx: Fix | None = None) -> dict[str, tuple[float, float]]:
    """The search space: the default bounds (stroke 1), each upper one × the largest fixed
    length where that is larger (as a request's own are)."""
    top = max([1.0, *(abs(v) for v in fx.fixed.values())]) if fx else 1.0
    return {q.name: (q.bounds[0], q.bounds[1] * top) for q in get(mtype).parameters}


def _in_bounds(mtype: str, params: dict[str, np.ndarray], names, fx=None) -> list[np.ndarray]:
    """Margins of the parameters ``names`` in their bounds; a fixed one, or one the targets
    and fixed parts set alone (``Fix.exempt``), has none."""
    fx = fx or NOFIX
    b = _bounds(mtype, fx)
    names = [k for k in names if k not in fx.fixed and k not in fx.exempt]
    return [m for k in names for m in (params[k] - b[k][0], b[k][1] - params[k])]


# the four-bar types' links: the first fixed one sets the scale
LINKS = {
    "crank_rocker_slider": ("ground", "crank", "coupler", "rocker"),
    "drag_link_slider": ("ground", "crank", "coupler", "follower"),
}
# parameters the targets set alone: a fixed one is only checked
SET_ALONE = {
    "crank_shaper": ("lever",),
    "whitworth": ("lever",),
    "drag_link_slider": ("follower_arm",),
}
# parameters that, once one of them is fixed, the targets and it set alone: not bounded
SET_TOGETHER = {
    "offset_slider_crank": ("crank", "coupler", "offset"),
    "crank_shaper": ("crank", "pivot_distance"),
    "whitworth": ("crank", "pivot_distance"),
}


@dataclass(frozen=True)
class Fix:
    """Fixed parts (stroke 1, sorted (name, value) pairs) of one type."""

    mtype: str = ""
    values: tuple[tuple[str, float], ...] = ()

    @functools.cached_property
    def fixed(self) -> dict[str, float]:
        return dict(self.values)

    @functools.cached_property
    def scale(self) -> tuple[str, float] | None:
        """The four-bar link whose fixed length sets the scale."""
        return next(
            ((n, self.fixed[n]) for n in LINKS.get(self.mtype, ()) if n in self.fixed), None
        )

    @functools.cached_property
    def exempt(self) -> frozenset[str]:
        """The parameters the targets and the fixed parts set on their own: unbounded (as a
        request's reduced solver takes them), those the targets set alone among them."""
        together = SET_TOGETHER.get(self.mtype, ())
        out = set(SET_ALONE.get(self.mtype, ()))
        if any(n in self.fixed for n in together):
            out |= set(together)
        return frozenset(out)


NOFIX = Fix()


def _ratio(b, names, fx) -> float:
    """The largest ratio of two links the bounds (and fixed lengths) allow."""
    fixed = [v for k, v in (fx or NOFIX).fixed.items() if k in names]
    return max(b[k][1] for k in names) / min([b[k][0] for k in names] + fixed)


def _cos_law(a, b, c):
    """cos of the angle between sides a and b of the triangle with third side c."""
    return (a * a + b * b - c * c) / (2 * a * b)


def _monotone(amplitude, rod, h, arm):
    """Margins for the slider moving one way over the driving arm's swing ±amplitude (so its
    extremes are the arm's, and the closed forms for TR and stroke hold). With the arm at δ
    from the path's normal, gap = h − arm cos δ, s = arm sin δ + sqrt(rod² − gap²) and
    ds/dδ ∝ cos δ sqrt(rod² − gap²) − gap sin δ: where gap sin δ > 0 that is > 0 exactly when
    rod cos δ > |gap|, and both signs of δ occur, so the condition is rod x − |h − arm x| ≥ 0
    for x = cos δ ∈ [cos amplitude, 1]; concave in x, it holds on the interval when it holds
    at the ends (x = 1 is the rod's reach at mid-swing)."""
    x = np.cos(amplitude)
    gap = h - arm * x
    return [rod * x - gap, rod * x + gap]


def _scaled_fourbar(mtype, names, links, fx=None):
    """The smallest scale that puts all four links in their bounds (ratios fixed), and the
    margins for one to exist: hi_i / r_i ≥ lo_j / r_j for all i, j; where a link is fixed,
    the scale its length sets, and the other links' margins in their bounds."""
    fx = fx or NOFIX
    b = _bounds(mtype, fx)
    lo = [b[k][0] for k in names]
    hi = [b[k][1] for k in names]
    if fx.scale is not None:
        j = names.index(fx.scale[0])
        scale = fx.scale[1] / links[j]
        free = [i for i in range(4) if names[i] not in fx.fixed]
        margins = [m for i in free for m in (hi[i] - scale * links[i], scale * links[i] - lo[i])]
        return scale, margins
    scale = np.max([lo[j] / links[j] for j in range(4)], axis=0)
    margins = [hi[i] * links[j] - lo[j] * links[i] for i in range(4) for j in range(4) if i != j]
    return scale, margins


def _grashof(shortest, others):
    """s + x ≤ a + b for every other link x: Grashof with ``shortest`` the shortest link."""
    out = []
    for i, x in enumerate(others):
        a, c = (o for j, o in enumerate(others) if j != i)
        out.append(a + c - shortest - x)
    return out


def _osc(z, beta, branch, fx=None):
    mt = "offset_slider_crank"
    alpha = beta + z[:, 0] * (PI / 2 - beta)
    u = np.sin(alpha - beta) / np.sin(beta)  # |O2C1| = r3 − r2
    v = np.sin(alpha) / np.sin(beta)  # |O2C2| = r3 + r2
    e = u * np.sin(alpha)
    r2, r3 = (v - u) / 2, (v + u) / 2
    p = {"crank": r2, "coupler": r3, "offset": e}
    # u > 0: with u = 0 (and so e = 0) the slider dwells at O2 for half a turn, no TR; below
    # 1e-6 (TR within ~1e-6 of 3) no double-precision analysis resolves the dead centres, so
    # the search leaves that sliver out (it can only make the referee more lenient)
    margins = [*_in_bounds(mt, p, ("crank", "coupler", "offset"), fx), r3 - r2 - e, u - 1e-6]
    cosines = [(e + r2) / r3, (e - r2) / r3]
    return Batch(p, np.array(margins).T, np.array(cosines).T, r2 + r3)


def _shaper(z, beta, branch, link, fx=None):
    mt = "crank_shaper"
    b = _bounds(mt, fx)
    k = np.sin(beta / 2)
    lever = 1 / (2 * k)
    d = _log(z[:, 0], *b["pivot_distance"])
    r2 = k * d
    p = {"crank": r2, "pivot_distance": d, "lever": lever, "ram_link": np.zeros_like(d)}
    margins = [  # the lever is set by the targets alone: the default bounds do not limit it
        *_in_bounds(mt, p, ("crank", "pivot_distance"), fx),
        d - r2 - STRICT,
        lever - d - r2,
    ]
    size = r2 + d + lever
    cosines = []
    if link:
        rod = _log(z[:, 1], *b["ram_link"])
        h = _lin(z[:, 2], *b["ram_height"])
        p.update(ram_link=rod, ram_height=h)
        offsets = (h - lever, h - lever * np.sqrt(1 - k * k))  # mid-swing, swing ends
        margins += _in_bounds(mt, p, ("ram_link", "ram_height"), fx)
        margins += [rod + sg * o for o in offsets for sg in (1, -1)]
        margins += _monotone(np.arcsin(k), rod, h, lever)
        cosines = [o / rod for o in offsets]
        size = size + rod
    cosines = np.array(cosines).T if cosines else np.zeros((len(d), 0))
    return Batch(p, np.array(margins).T, cosines, size)


def _whitworth(z, beta, branch, fx=None):
    mt = "whitworth"
    b = _bounds(mt, fx)
    r2 = _log(z[:, 0], *b["crank"])
    rod = _log(z[:, 1], *b["connecting_rod"])
    d = r2 * np.cos((PI - beta) / 2)  # half the quick stroke's crank angle is acos(d/r2)
    lever = np.full_like(r2, 0.5)
    p = {"crank": r2, "pivot_distance": d, "lever": lever, "connecting_rod": rod}
    margins = [*_in_bounds(mt, p, p, fx), r2 - d - STRICT, rod - lever - STRICT]
    return Batch(p, np.array(margins).T, (lever / rod)[:, None], r2 + d + lever + rod)


def _signs(branch, n):
    """The n signs a branch number (or an array of them, one a row) encodes."""
    return [1 - 2 * ((np.asarray(branch) >> i) & 1) for i in range(n)]


def _toggle_distance(phi, r4, sign):
    """The distance from O2 along direction φ to circle(O4 = (1, 0), r4): a root of
    x² − 2x cos φ + 1 − r4² = 0."""
    s = np.sin(phi)
    return np.cos(phi) + sign * np.sqrt((r4 - s) * (r4 + s))


def _rocker(z, beta, branch, rod, fx=None):
    mt = "crank_rocker_slider"
    b = _bounds(mt, fx)
    sg, sv, su = _signs(branch, 3)
    ratio = _ratio(b, LINKS[mt], fx)
    r1 = np.ones(len(z))
    r4 = _log(z[:, 0], 1 / ratio, ratio)
    phi_e = z[:, 1] * PI
    phi_f = phi_e + sg * beta
    v = _toggle_distance(phi_e, r4, sv)  # r3 + r2
    u = _toggle_distance(phi_f, r4, su)  # r3 − r2
    r2, r3 = (v - u) / 2, (v + u) / 2
    names = ("ground", "crank", "coupler", "rocker")
    scale, ratios = _scaled_fourbar(mt, names, (r1, r2, r3, r4), fx)
    # the rocker's swing, from the angles at O4 of the triangles (r1, r4, O2D) at the toggles
    swing = np.arccos(np.clip(_cos_law(r1, r4, v), -1, 1)) - np.arccos(
        np.clip(_cos_law(r1, r4, u), -1, 1)
    )
    arm = 1 / (2 * np.sin(np.abs(swing) / 2))
    p = dict(zip(names, (scale * r1, scale * r2, scale * r3, scale * r4), strict=True))
    p.update(rocker_arm=arm, connecting_rod=np.zeros_like(arm))
    margins = [
        phi_f,
        PI - phi_f,
        u - STRICT,
        *_grashof(r2, (r1, r3, r4)),
        *ratios,
        *_in_bounds(mt, p, ("rocker_arm",), fx),
    ]
    cosines = [_cos_law(r3, r4, r1 - r2), _cos_law(r3, r4, r1 + r2)]
    size = scale * (r1 + r2 + r3 + r4) + arm
    if rod:
        r6 = _log(z[:, 2], *b["connecting_rod"])
        h = _lin(z[:, 3], *b["slider_height"])
        p.update(connecting_rod=r6, slider_height=h)
        half = np.abs(swing) / 2
        offsets = (h - arm, h - arm * np.cos(half))  # mid-swing, swing ends
        margins += _in_bounds(mt, p, ("connecting_rod", "slider_height"), fx)
        margins += [r6 + s * o for o in offsets for s in (1, -1)]
        margins += _monotone(half, r6, h, arm)
        cosines += [o / r6 for o in offsets]
        size = size + r6
    return Batch(p, np.array(margins).T, np.array(cosines).T, size)


def _drag(z, beta, branch, fx=None):
    mt = "drag_link_slider"
    b = _bounds(mt, fx)
    sg, sr = _signs(branch, 2)
    ratio = _ratio(b, LINKS[mt], fx)
    r2 = np.ones(len(z))
    r1 = _log(z[:, 0], 1 / ratio, 1.0)
    r4 = _log(z[:, 1], 1 / ratio, ratio)
    big, small = r4 + r1, r4 - r1  # O2B at the two dead centres
    a_ = big - small * np.cos(beta)
    b_ = sg * small * np.sin(beta)
    c_ = 2 * r1 * r4 / r2
    reach = np.hypot(a_, b_)
    t2a = np.arctan2(b_, a_) + sr * np.arccos(np.clip(c_ / reach, -1, 1))
    t2b = t2a + sg * beta
    r3 = np.sqrt(r2 * r2 + big * big - 2 * r2 * big * np.cos(t2a))
    names = ("ground", "crank", "coupler", "follower")
    scale, ratios = _scaled_fourbar(mt, names, (r1, r2, r3, r4), fx)
    r6 = _log(z[:, 2], *b["connecting_rod"])
    arm = np.full_like(r6, 0.5)
    p = dict(zip(names, (scale * r1, scale * r2, scale * r3, scale * r4), strict=True))
    p.update(follower_arm=arm, connecting_rod=r6)
    margins = [
        reach - c_,
        t2a,
        PI - t2a,
        t2b,
        PI - t2b,
        small - STRICT,
        *_grashof(r1, (r2, r3, r4)),
        *ratios,
        *_in_bounds(mt, p, ("follower_arm", "connecting_rod"), fx),
        r6 - arm - STRICT,
    ]
    cosines = [_cos_law(r3, r4, r2 - r1), _cos_law(r3, r4, r2 + r1), arm / r6]
    size = scale * (r1 + r2 + r3 + r4) + arm + r6
    return Batch(p, np.array(margins).T, np.array(cosines).T, size)


@dataclass(frozen=True)
class Family:
    """One structural variant: ``dim`` unit-box variables (after β), ``branches`` choices.

    A fixed part is an equality on the variables, met by solving for one of them (``solve``:
    each part's variables to try, in order) over its ``spans`` entry: every root of the
    part's relative difference from its value on a scan of ``SCAN`` points, the r-th one a
    branch of its own, polished by the Illinois method. A part no free variable is left for
    is only checked."""

    mtype: str
    variant: str
    dim: int
    branches: int
    decode: Callable[..., Batch]
    solve: dict[str, tuple[int, ...]] = field(default_factory=dict)
    spans: tuple[tuple[float, float], ...] = ()


_ROCKER = {
    "ground": (1, 0),
    "crank": (1, 0),
    "coupler": (1, 0),
    "rocker": (0, 1),
    "rocker_arm": (1, 0),
    "connecting_rod": (2,),
    "slider_height": (3,),
}
FAMILIES: dict[str, tuple[Family, ...]] = {
    "offset_slider_crank": (
        Family(
            "offset_slider_crank",
            "",
            1,
            1,
            _osc,
            {"crank": (0,), "coupler": (0,), "offset": (0,)},
            ((0.0, 1.0),),
        ),
    ),
    "crank_shaper": (
        Family(
            "crank_shaper",
            "slot drive",
            1,
            1,
            functools.partial(_shaper, link=False),
            {"crank": (0,), "pivot_distance": (0,)},
            ((-1.0, 2.0),),
        ),
        Family(
            "crank_shaper",
            "ram link",
            3,
            1,
            functools.partial(_shaper, link=True),
            {"crank": (0,), "pivot_distance": (0,), "ram_link": (1,), "ram_height": (2,)},
            ((-1.0, 2.0), (0.0, 1.0), (0.0, 1.0)),
        ),
    ),
    "whitworth": (
        Family(
            "whitworth",
            "",
            2,
            1,
            _whitworth,
            {"crank": (0,), "pivot_distance": (0,), "connecting_rod": (1,)},
            ((-1.0, 2.0), (0.0, 1.0)),
        ),
    ),
    "crank_rocker_slider": (
        Family(
            "crank_rocker_slider",
            "slot drive",
            2,
            8,
            functools.partial(_rocker, rod=False),
            _ROCKER,
            ((0.0, 1.0), (0.0, 1.0)),
        ),
        Family(
            "crank_rocker_slider",
            "rod",
            4,
            8,
            functools.partial(_rocker, rod=True),
            _ROCKER,
            ((0.0, 1.0),) * 4,
        ),
    ),
    "drag_link_slider": (
        Family(
            "drag_link_slider",
            "",
            3,
            4,
            _drag,
            {
                "ground": (0, 1),
                "crank": (0, 1),
                "coupler": (1, 0),
                "follower": (1, 0),
                "connecting_rod": (2,),
            },
            ((0.0, 1.0),) * 3,
        ),
    ),
}
SCAN = 64  # points of a fixed part's scan along the variable solved for it
ROOTS = 3  # roots of a fixed part's equality searched, each a branch
CELLS = 8  # cells a side of the grid whose best points the multistart polishes
ILLINOIS = 60  # steps polishing a root (each on the rows not yet converged)


# --------------------------------------------------------------------------- the search
@dataclass
class Found:
    """The best design of one search, and what each seed and variant found (the spread)."""

    goal: str
    value: float | None  # degrees, size or time ratio; None: no valid design found
    params: dict[str, float] | None = None
    variant: str | None = None
    per_seed: list[tuple[str, int, float | None]] = field(default_factory=list)
    simulated: dict | None = None
    seconds: float = 0.0


class _Problem:
    """One family, one goal: z ∈ [0, 1]^n (with β first for a time-ratio goal) → objective."""

    def __init__(
        self,
        fam: Family,
        goal: str,
        tr: float | None,
        bound_deg: float,
        limit: float,
        fx: Fix = NOFIX,
    ) -> None:
        self.fam, self.goal, self.fx = fam, goal, fx
        self.cos_bound = math.cos(math.radians(bound_deg))
        self.free_beta = goal in ("max_time_ratio", "min_time_ratio")
        self.beta = None if self.free_beta else beta_of(tr)
        # the fixed parts this variant has, besides the link that sets the scale: each
        # solved for by a variable of its own, else checked
        with np.errstate(all="ignore"):
            names = fam.decode(np.full((1, fam.dim), 0.5), np.array([0.5]), 0, fx=fx).params
        scale = fx.scale[0] if fx.scale else None
        self.checks = [n for n in fx.fixed if n in names and n != scale]
        self.solved: list[tuple[int, str]] = []
        for n in list(self.checks):
            used = [c for c, _ in self.solved]
            free = [c for c in fam.solve.get(n, ()) if c < fam.dim and c not in used]
            if free and n not in SET_ALONE.get(fam.mtype, ()):
                self.solved.append((free[0], n))
                self.checks.remove(n)
        self.free = [c for c in range(fam.dim) if c not in (c for c, _ in self.solved)]
        self.scanned: tuple[object, np.ndarray | None] = (None, None)
        self.branches = fam.branches * ROOTS ** len(self.solved)
        self.dim = len(self.free) + self.free_beta
        # β from 0 up to the limit (max) or from the limit up to TR_CAP (min): the search
        # stops at the limit, on a plateau of designs there rather than at a degenerate
        # supremum (the offset slider-crank's TR → 3 needs the crank pivot on the path)
        span = sorted((beta_of(limit), 0.0 if goal == "max_time_ratio" else beta_of(TR_CAP)))
        self.beta_span = span

    def split(self, z):
        if not self.free_beta:
            return z, np.full(len(z), self.beta)
        lo, hi = self.beta_span
        return z[:, 1:], lo + z[:, 0] * (hi - lo)

    def residual(self, params, name):
        """A fixed part's relative difference from its value (a fixed offset: its size, the
        families' offsets being ≥ 0)."""
        want = self.fx.fixed[name]
        got = params[name]
        if name == "offset":
            want, got = abs(want), np.abs(got)
        return (got - want) / abs(want) if want else got

    def solve(self, full, beta, branch, c, name, root):
        """Variable c of each row solved for fixed part ``name``: its root-th root along the
        variable's span; and which rows have one."""
        n, (lo, hi) = len(full), self.fam.spans[c]
        grid = np.linspace(lo, hi, SCAN)
        br = np.broadcast_to(branch, (n,))
        # the scan is the same for every root: once per distinct row (a batch of branches
        # repeats each), kept for the next call
        keys = np.hstack([full, beta[:, None], br[:, None]])
        uniq, back = np.unique(keys, axis=0, return_inverse=True)
        key = (uniq.tobytes(), c)
        if self.scanned[0] != key:
            m = len(uniq)
            rows = np.repeat(uniq[:, : self.fam.dim], SCAN, axis=0)
            rows[:, c] = np.tile(grid, m)
            ub, ubr = uniq[:, -2], uniq[:, -1].astype(int)
            d = self.fam.decode(rows, np.repeat(ub, SCAN), np.repeat(ubr, SCAN), fx=self.fx)
            self.scanned = (key, self.residual(d.params, name).reshape(m, SCAN))
        r = self.scanned[1][back.ravel()]
        change = np.isfinite(r[:, :-1]) & np.isfinite(r[:, 1:]) & (r[:, :-1] * r[:, 1:] <= 0)
        pick = change & (np.cumsum(change, axis=1) == np.asarray(root + 1).reshape(-1, 1))
        has, k = pick.any(axis=1), np.argmax(pick, axis=1)
        at = np.arange(n)
        a, b, ra, rb = grid[k], grid[k + 1], r[at, k], r[at, k + 1]
        x = a.copy()
        todo = np.flatnonzero(has)
        for it in range(ILLINOIS):  # regula falsi, an end kept twice halved; every third a
            if not len(todo):  # bisection, so the bracket shrinks whatever the function
                break
            i = todo
            with np.errstate(all="ignore"):
                t = np.clip(ra[i] / (ra[i] - rb[i]), 0.0, 1.0)
            t = np.where(np.isfinite(t) & (it % 3 != 2), t, 0.5)
            x[i] = a[i] + t * (b[i] - a[i])
            row = full[i].copy()
            row[:, c] = x[i]
            rx = self.residual(self.fam.decode(row, beta[i], br[i], fx=self.fx).params, name)
            rx = np.where(np.isfinite(rx), rx, ra[i])  # no design there: as the end a
            left = np.sign(rx) == np.sign(ra[i])
            rb[i] = np.where(left, rb[i] / 2, rb[i])
            ra[i] = np.where(left, ra[i], ra[i] / 2)
            a[i], ra[i] = np.where(left, x[i], a[i]), np.where(left, rx, ra[i])
            b[i], rb[i] = np.where(left, b[i], x[i]), np.where(left, rb[i], rx)
            done = (np.abs(rx) <= 1e-15) | (
                np.abs(b[i] - a[i]) <= 1e-15 * np.maximum(1, np.abs(x[i]))
            )
            todo = i[~done]
        return x, has

    def full(self, z, branch):
        """The rows of z (the free variables, β first for a time-ratio goal) as every
        variable w (β, then the family's), the fixed parts' ones solved for (the branch
        numbers the family's branch, then each part's root); the family's branch; which rows
        have the roots."""
        zz, beta = self.split(z)
        fb, roots = branch % self.fam.branches, branch // self.fam.branches
        full = np.zeros((len(zz), self.fam.dim))
        full[:, self.free] = zz
        has = np.ones(len(zz), dtype=bool)
        with np.errstate(all="ignore"):
            for c, name in self.solved:
                full[:, c], ok = self.solve(full, beta, fb, c, name, roots % ROOTS)
                roots //= ROOTS
                has &= ok
        w = np.hstack([z[:, :1], full]) if self.free_beta else full
        return w, fb, has

    def at(self, w, fb):
        """(objective, total violation, batch) at every variable w (``full``), the fixed
        parts' equalities as margins (to 1e-10 relative)."""
        full, beta = self.split(w)
        with np.errstate(all="ignore"):
            d = self.fam.decode(full, beta, fb, fx=self.fx)
            extra = [1e-10 - np.abs(self.residual(d.params, n)) for _, n in self.solved]
            extra += [1e-10 - np.abs(self.residual(d.params, n)) for n in self.checks]
            if extra:
                d.margins = np.hstack([d.margins, np.array(extra).T])
            worst = np.max(np.abs(d.cosines), axis=1, initial=0.0)
            margins = d.margins
            if self.goal != "max_transmission_angle":
                margins = np.hstack([margins, (self.cos_bound - worst)[:, None]])
            # violations to rounding are none: designs exactly on a limit (margin ±1e-18) count
            viol = np.sum(np.clip(-np.nan_to_num(margins, nan=-1.0) - FEASIBLE, 0, None), axis=1)
            obj = {
                "max_transmission_angle": worst,
                "min_size": d.size,
                "max_time_ratio": -beta,
                "min_time_ratio": beta,
            }[self.goal]
        bad = ~np.isfinite(obj) | ~np.isfinite(viol)
        viol = np.where(bad, np.inf, viol)
        return obj, viol, d

    def evaluate(self, z, branch):
        """(objective, total violation, batch) for the rows of z (the free variables)."""
        w, fb, has = self.full(z, branch)
        obj, viol, d = self.at(w, fb)
        return obj, np.where(has, viol, np.inf), d

    def penalised(self, z):
        """The feasibility-first objective, best over the discrete branches (all evaluated
        in one batch); and the branch."""
        n, nb = len(z), self.branches
        obj, viol, _ = self.evaluate(np.tile(z, (nb, 1)), np.repeat(np.arange(nb), n))
        f = np.where(viol > 0, PENALTY + np.minimum(viol, 1e6), obj).reshape(nb, n)
        return f.min(axis=0), f.argmin(axis=0)

    def feasible(self, w, fb) -> tuple[bool, float]:
        """Whether every variable w (``full``) is a design meeting the bound, and its
        objective."""
        obj, viol, _ = self.at(w[None, :], fb)
        return bool(viol[0] == 0 and np.isfinite(obj[0])), float(obj[0])

    def polish(self, z0, branch):
        """SLSQP from the free variables z0 on every variable (``full``), the fixed parts'
        equalities as constraints of its own (an epigraph t ≥ |cos| for the transmission);
        kept only where it is feasible and better: (objective, variables w, family branch)."""
        epi = self.goal == "max_transmission_angle"
        w0s, fb, has = self.full(z0[None, :], branch)
        w0 = w0s[0]
        if not has[0]:
            return math.inf, w0, fb
        eqs = len(self.solved)

        def parts(x, memo={}):  # noqa: B006 - the last point's batch, for fun and cons
            key = x[: len(w0)].tobytes()
            if memo.get("key") != key:
                full, beta = self.split(x[None, : len(w0)])
                with np.errstate(all="ignore"):
                    d = self.fam.decode(full, beta, fb, fx=self.fx)
                    res = [self.residual(d.params, n)[0] for _, n in self.solved]
                memo.update(key=key, d=d, res=np.array(res))
            return memo["d"], memo["res"]

        def fun(x):
            return x[-1] if epi else float(parts(x)[0].size[0])

        def cons(x):
            d = parts(x)[0]
            c = d.cosines[0]
            top = x[-1] if epi else self.cos_bound
            rows = np.concatenate([d.margins[0], top - c, top + c])
            return np.nan_to_num(rows, nan=-1.0)

        def equal(x):
            return np.nan_to_num(parts(x)[1], nan=1.0)

        ok, f0 = self.feasible(w0, fb)
        x0 = np.append(w0, f0) if epi else w0
        spans = [
            self.fam.spans[c] if any(c == k for k, _ in self.solved) else (0.0, 1.0)
            for c in range(self.fam.dim)
        ]
        bounds = [(0.0, 1.0)] * self.free_beta + spans + ([(0.0, 1.0)] if epi else [])
        constraints = [{"type": "ineq", "fun": cons}]
        if eqs:
            constraints.append({"type": "eq", "fun": equal})
        with np.errstate(all="ignore"):
            res = minimize(
                fun,
                x0,
                method="SLSQP",
                bounds=bounds,
                constraints=constraints,
                options={"maxiter": 300, "ftol": 1e-15},
            )
        best = (f0, w0, fb) if ok else (math.inf, w0, fb)
        # SLSQP may end a hair outside an active constraint: step back towards the start
        lo, hi = np.array(bounds[: len(w0)]).T
        for lam in (1.0, 1 - 1e-6, 1 - 1e-4, 1 - 1e-2, 0.5):
            w = np.clip(w0 + lam * (res.x[: len(w0)] - w0), lo, hi)
            ok, f = self.feasible(w, fb)
            if ok and f < best[0]:
                return f, w, fb
        return best

    def value(self, f):
        if self.goal == "max_transmission_angle":
            return math.degrees(math.acos(min(f, 1.0)))
        if self.goal == "min_size":
            return f
        return float(tr_of(abs(f)))


def search(
    mtype: str,
    goal: str,
    tr: float | None = None,
    bound_deg: float = 0.0,
    effort: Effort = FULL,
    limit: float | None = None,
    fixed: Mapping[str, float] | None = None,
) -> Found:
    """The best design of ``goal`` over every variant, by DE from each seed and polishing.

    max_transmission_angle: at time ratio ``tr`` (stroke 1), the bound ignored; min_size: at
    ``tr`` with min transmission ≥ ``bound_deg``; max_time_ratio / min_time_ratio: with the
    bound, searched up to / down to ``limit`` (default TR_CAP / 1): a design at the limit shows
    that the extreme is at least / at most that. ``fixed``: parts kept at their values (stroke
    1), the search space then as a request's (``Fix``)."""
    if limit is None:
        limit = TR_CAP if goal == "max_time_ratio" else 1.0
    limit = min(max(limit, 1.0), TR_CAP)
    tr = None if tr is None else float(tr)
    fx = Fix(mtype, tuple(sorted((k, float(v)) for k, v in (fixed or {}).items())))
    return _search(mtype, goal, tr, float(bound_deg), effort, float(limit), fx)


@functools.lru_cache(maxsize=512)
def _search(mtype, goal, tr, bound_deg, effort, limit, fx=NOFIX):
    assert goal in GOALS, goal
    t0 = time.monotonic()
    out = Found(goal, None)
    best = (math.inf, None, None, None)  # f, z, branch, problem
    for fam in FAMILIES[mtype]:
        prob = _Problem(fam, goal, tr, bound_deg, limit, fx)
        if prob.dim == 0:  # the fixed parts leave points: each branch's is the search
            for br in range(prob.branches):
                w, fb, has = prob.full(np.zeros((1, 0)), br)
                ok, f = prob.feasible(w[0], fb) if has[0] else (False, math.inf)
                out.per_seed.append((fam.variant, br, prob.value(f) if ok else None))
                if ok and f < best[0]:
                    best = (f, w[0], fb, prob)
            continue
        for seed in effort.seeds:
            res = differential_evolution(
                lambda zt, prob=prob: prob.penalised(zt.T)[0],
                [(0.0, 1.0)] * prob.dim,
                seed=seed,
                popsize=effort.popsize,
                maxiter=effort.maxiter,
                tol=1e-10,
                atol=0,
                mutation=(0.5, 1.0),
                recombination=0.9,
                init="sobol",
                polish=False,
                vectorized=True,
                updating="deferred",
            )
            z = res.x
            branch = int(prob.penalised(z[None, :])[1][0])
            w, fb, has = prob.full(z[None, :], branch)
            ok, f = prob.feasible(w[0], fb) if has[0] else (False, math.inf)
            if not ok:
                out.per_seed.append((fam.variant, seed, None))
                continue
            w = w[0]
            if effort.polish:
                f, w, fb = prob.polish(z, branch)
            out.per_seed.append((fam.variant, seed, prob.value(f)))
            if f < best[0]:
                best = (f, w, fb, prob)
        if fx.values and effort.polish:
            for f, w, fb in _multistart(prob, effort):
                out.per_seed.append((fam.variant, -1, prob.value(f)))
                if f < best[0]:
                    best = (f, w, fb, prob)
    f, w, fb, prob = best
    if prob is not None:
        _, _, d = prob.at(w[None, :], fb)
        out.value = prob.value(f)
        out.params = {k: float(v[0]) for k, v in d.params.items()}
        out.variant = prob.fam.variant
        out.simulated = _check(mtype, goal, tr, bound_deg, out, fx)
    out.seconds = time.monotonic() - t0
    return out


def _multistart(prob: _Problem, effort: Effort) -> list[tuple[float, np.ndarray, int]]:
    """Each branch's Sobol points (``effort.samples``), the best of each cell of a coarse grid
    over the variables (``CELLS`` a side: the basins apart; feasibility first, as the
    evolution ranks them: a sliver of feasible designs may hold no sample, yet its
    neighbours come near), the best ``effort.starts`` of those polished: (value, every
    variable, the family's branch)."""
    z = qmc.Sobol(prob.dim, seed=0).random(effort.samples)
    side = CELLS if prob.dim <= 2 else 4
    cell = np.ravel_multi_index(
        tuple(np.minimum((z * side).astype(int), side - 1).T), (side,) * prob.dim
    )
    out = []
    for br in range(prob.branches):
        obj, viol, _ = prob.evaluate(z, br)
        value = np.where(viol > 0, PENALTY + np.minimum(viol, 1e6), obj)
        best: dict[int, int] = {}
        for i in np.argsort(value):
            if not np.isfinite(value[i]):
                break
            best.setdefault(int(cell[i]), int(i))
        for i in sorted(best.values(), key=lambda i: value[i])[: effort.starts]:
            f, w, fb = prob.polish(z[i], br)
            if math.isfinite(f):
                out.append((f, w, fb))
    return out


def _check(mtype, goal, tr, bound_deg, found: Found, fx: Fix = NOFIX) -> dict:
    """The independent forward simulation must confirm the design: its time ratio, stroke 1 and
    the objective's value (else these closed forms are wrong and the "optimum" is fake).

    Where a double-precision simulation cannot follow a design next to a validity limit (a
    time-ratio extreme at the bound 0 sits on a dead point), the 50-digit closed forms of
    tests/support/exact.py referee, as in the rest of the suite; the simulation must still agree to
    1e-4 there. A time-ratio search reports the referee's value of its design."""
    params = dict(found.params)
    if params.get("ram_link", 1) == 0:
        params.pop("ram_height", None)  # a slot drive: the default placement
    if params.get("connecting_rod", 1) == 0 and mtype == "crank_rocker_slider":
        params.pop("slider_height", None)
    sim = bruteforce.simulate(mtype, params)
    ref = exact.time_ratio_and_stroke(mtype, params)
    if goal in ("max_time_ratio", "min_time_ratio") and ref is not None:
        found.value = ref[0]  # this design's own time ratio, past the float closed forms' kinks
    want = tr if goal in ("max_transmission_angle", "min_size") else found.value
    off = max(abs(sim["time_ratio"] / want - 1), abs(sim["stroke"] - 1))
    refereed = ref is not None and max(abs(ref[0] / want - 1), abs(ref[1] - 1)) <= 1e-9
    problems = []
    if not (off <= 1e-7 or (refereed and off <= 1e-4)):
        problems.append(f"time ratio {sim['time_ratio']!r} and stroke {sim['stroke']!r}")
    mu = sim["min_transmission_deg"]
    if goal == "max_transmission_angle" and abs(mu - found.value) > 1e-6:
        problems.append(f"min transmission {mu!r}°, not {found.value!r}")
    if goal != "max_transmission_angle" and mu < bound_deg - 1e-6:
        problems.append(f"min transmission {mu!r}° < {bound_deg!r}°")
    if goal == "min_size":
        size = sum(v for k, v in found.params.items() if k in _links(mtype))
        if abs(size - found.value) > 1e-12 * size:
            problems.append(f"size {size!r}, not {found.value!r}")
    for k, v in fx.fixed.items():
        got = found.params.get(k)
        if got is not None and abs(abs(got) - abs(v)) > 1e-9 * max(abs(v), 1e-3):
            problems.append(f"{k} {got!r}, fixed at {v!r}")
    if problems:
        raise AssertionError(
            f"global search ({mtype}, {goal}): the simulation disagrees with the closed forms "
            f"for {found.params}: " + "; ".join(problems)
        )
    return sim


def _links(mtype):
    return {q.name for q in get(mtype).parameters if q.name not in PLACEMENTS}
