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
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import differential_evolution, minimize

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


QUICK = Effort(seeds=(0, 1), popsize=15, maxiter=100)
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


def _bounds(mtype: str) -> dict[str, tuple[float, float]]:
    return {q.name: q.bounds for q in get(mtype).parameters}


def _in_bounds(mtype: str, params: dict[str, np.ndarray], names) -> list[np.ndarray]:
    b = _bounds(mtype)
    return [m for k in names for m in (params[k] - b[k][0], b[k][1] - params[k])]


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


def _scaled_fourbar(mtype, names, links):
    """The smallest scale that puts all four links in their bounds (ratios fixed), and the
    margins for one to exist: hi_i / r_i ≥ lo_j / r_j for all i, j."""
    b = _bounds(mtype)
    lo = [b[k][0] for k in names]
    hi = [b[k][1] for k in names]
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


def _osc(z, beta, branch):
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
    margins = [*_in_bounds(mt, p, ("crank", "coupler", "offset")), r3 - r2 - e, u - 1e-6]
    cosines = [(e + r2) / r3, (e - r2) / r3]
    return Batch(p, np.array(margins).T, np.array(cosines).T, r2 + r3)


def _shaper(z, beta, branch, link):
    mt = "crank_shaper"
    b = _bounds(mt)
    k = np.sin(beta / 2)
    lever = 1 / (2 * k)
    d = _log(z[:, 0], *b["pivot_distance"])
    r2 = k * d
    p = {"crank": r2, "pivot_distance": d, "lever": lever, "ram_link": np.zeros_like(d)}
    margins = [  # the lever is set by the targets alone: the default bounds do not limit it
        *_in_bounds(mt, p, ("crank", "pivot_distance")),
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
        margins += _in_bounds(mt, p, ("ram_link", "ram_height"))
        margins += [rod + sg * o for o in offsets for sg in (1, -1)]
        margins += _monotone(np.arcsin(k), rod, h, lever)
        cosines = [o / rod for o in offsets]
        size = size + rod
    cosines = np.array(cosines).T if cosines else np.zeros((len(d), 0))
    return Batch(p, np.array(margins).T, cosines, size)


def _whitworth(z, beta, branch):
    mt = "whitworth"
    b = _bounds(mt)
    r2 = _log(z[:, 0], *b["crank"])
    rod = _log(z[:, 1], *b["connecting_rod"])
    d = r2 * np.cos((PI - beta) / 2)  # half the quick stroke's crank angle is acos(d/r2)
    lever = np.full_like(r2, 0.5)
    p = {"crank": r2, "pivot_distance": d, "lever": lever, "connecting_rod": rod}
    margins = [*_in_bounds(mt, p, p), r2 - d - STRICT, rod - lever - STRICT]
    return Batch(p, np.array(margins).T, (lever / rod)[:, None], r2 + d + lever + rod)


def _signs(branch, n):
    return [1 - 2 * ((branch >> i) & 1) for i in range(n)]


def _toggle_distance(phi, r4, sign):
    """The distance from O2 along direction φ to circle(O4 = (1, 0), r4): a root of
    x² − 2x cos φ + 1 − r4² = 0."""
    s = np.sin(phi)
    return np.cos(phi) + sign * np.sqrt((r4 - s) * (r4 + s))


def _rocker(z, beta, branch, rod):
    mt = "crank_rocker_slider"
    b = _bounds(mt)
    sg, sv, su = _signs(branch, 3)
    ratio = max(b[k][1] / b[k][0] for k in ("ground", "crank", "coupler", "rocker"))
    r1 = np.ones(len(z))
    r4 = _log(z[:, 0], 1 / ratio, ratio)
    phi_e = z[:, 1] * PI
    phi_f = phi_e + sg * beta
    v = _toggle_distance(phi_e, r4, sv)  # r3 + r2
    u = _toggle_distance(phi_f, r4, su)  # r3 − r2
    r2, r3 = (v - u) / 2, (v + u) / 2
    names = ("ground", "crank", "coupler", "rocker")
    scale, ratios = _scaled_fourbar(mt, names, (r1, r2, r3, r4))
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
        *_in_bounds(mt, p, ("rocker_arm",)),
    ]
    cosines = [_cos_law(r3, r4, r1 - r2), _cos_law(r3, r4, r1 + r2)]
    size = scale * (r1 + r2 + r3 + r4) + arm
    if rod:
        r6 = _log(z[:, 2], *b["connecting_rod"])
        h = _lin(z[:, 3], *b["slider_height"])
        p.update(connecting_rod=r6, slider_height=h)
        half = np.abs(swing) / 2
        offsets = (h - arm, h - arm * np.cos(half))  # mid-swing, swing ends
        margins += _in_bounds(mt, p, ("connecting_rod", "slider_height"))
        margins += [r6 + s * o for o in offsets for s in (1, -1)]
        margins += _monotone(half, r6, h, arm)
        cosines += [o / r6 for o in offsets]
        size = size + r6
    return Batch(p, np.array(margins).T, np.array(cosines).T, size)


def _drag(z, beta, branch):
    mt = "drag_link_slider"
    b = _bounds(mt)
    sg, sr = _signs(branch, 2)
    ratio = max(b[k][1] / b[k][0] for k in ("ground", "crank", "coupler", "follower"))
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
    scale, ratios = _scaled_fourbar(mt, names, (r1, r2, r3, r4))
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
        *_in_bounds(mt, p, ("follower_arm", "connecting_rod")),
        r6 - arm - STRICT,
    ]
    cosines = [_cos_law(r3, r4, r2 - r1), _cos_law(r3, r4, r2 + r1), arm / r6]
    size = scale * (r1 + r2 + r3 + r4) + arm + r6
    return Batch(p, np.array(margins).T, np.array(cosines).T, size)


@dataclass(frozen=True)
class Family:
    """One structural variant: ``dim`` unit-box variables (after β), ``branches`` choices."""

    mtype: str
    variant: str
    dim: int
    branches: int
    decode: Callable[[np.ndarray, np.ndarray, int], Batch]


FAMILIES: dict[str, tuple[Family, ...]] = {
    "offset_slider_crank": (Family("offset_slider_crank", "", 1, 1, _osc),),
    "crank_shaper": (
        Family("crank_shaper", "slot drive", 1, 1, functools.partial(_shaper, link=False)),
        Family("crank_shaper", "ram link", 3, 1, functools.partial(_shaper, link=True)),
    ),
    "whitworth": (Family("whitworth", "", 2, 1, _whitworth),),
    "crank_rocker_slider": (
        Family("crank_rocker_slider", "slot drive", 2, 8, functools.partial(_rocker, rod=False)),
        Family("crank_rocker_slider", "rod", 4, 8, functools.partial(_rocker, rod=True)),
    ),
    "drag_link_slider": (Family("drag_link_slider", "", 3, 4, _drag),),
}


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
        self, fam: Family, goal: str, tr: float | None, bound_deg: float, limit: float
    ) -> None:
        self.fam, self.goal = fam, goal
        self.cos_bound = math.cos(math.radians(bound_deg))
        self.free_beta = goal in ("max_time_ratio", "min_time_ratio")
        self.beta = None if self.free_beta else beta_of(tr)
        self.dim = fam.dim + self.free_beta
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

    def evaluate(self, z, branch):
        """(objective, total violation, batch) for the rows of z."""
        zz, beta = self.split(z)
        with np.errstate(all="ignore"):
            d = self.fam.decode(zz, beta, branch)
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

    def penalised(self, z):
        """The feasibility-first objective, best over the discrete branches; and the branch."""
        best = np.full(len(z), np.inf)
        arg = np.zeros(len(z), dtype=int)
        for br in range(self.fam.branches):
            obj, viol, _ = self.evaluate(z, br)
            f = np.where(viol > 0, PENALTY + np.minimum(viol, 1e6), obj)
            arg = np.where(f < best, br, arg)
            best = np.minimum(best, f)
        return best, arg

    def feasible(self, z, branch) -> tuple[bool, float]:
        obj, _, d = self.evaluate(z[None, :], branch)
        margins = np.nan_to_num(d.margins, nan=-1.0)
        ok = bool(np.all(margins >= -FEASIBLE) and np.isfinite(obj[0]))
        if self.goal != "max_transmission_angle":
            worst = np.max(np.abs(d.cosines), initial=0.0)
            ok = ok and worst <= self.cos_bound + FEASIBLE
        return ok, float(obj[0])

    def polish(self, z0, branch):
        """SLSQP on the same functions (an epigraph t ≥ |cos| for the transmission), from the
        DE's best; kept only where it is feasible and better."""
        epi = self.goal == "max_transmission_angle"

        def parts(x):
            obj, _, d = self.evaluate(x[None, : self.dim], branch)
            return obj[0], d

        def fun(x):
            return x[-1] if epi else parts(x)[0]

        def cons(x):
            d = parts(x)[1]
            c = d.cosines[0]
            top = x[-1] if epi else self.cos_bound
            rows = np.concatenate([d.margins[0], top - c, top + c])
            return np.nan_to_num(rows, nan=-1.0)

        ok, f0 = self.feasible(z0, branch)
        x0 = np.append(z0, f0) if epi else z0
        bounds = [(0.0, 1.0)] * self.dim + ([(0.0, 1.0)] if epi else [])
        with np.errstate(all="ignore"):
            res = minimize(
                fun,
                x0,
                method="SLSQP",
                bounds=bounds,
                constraints=[{"type": "ineq", "fun": cons}],
                options={"maxiter": 300, "ftol": 1e-15},
            )
        best = (f0, z0) if ok else (math.inf, z0)
        # SLSQP may end a hair outside an active constraint: step back towards the start
        for lam in (1.0, 1 - 1e-6, 1 - 1e-4, 1 - 1e-2, 0.5):
            z = np.clip(z0 + lam * (res.x[: self.dim] - z0), 0, 1)
            ok, f = self.feasible(z, branch)
            if ok and f < best[0]:
                return f, z
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
) -> Found:
    """The best design of ``goal`` over every variant, by DE from each seed and polishing.

    max_transmission_angle: at time ratio ``tr`` (stroke 1), the bound ignored; min_size: at
    ``tr`` with min transmission ≥ ``bound_deg``; max_time_ratio / min_time_ratio: with the
    bound, searched up to / down to ``limit`` (default TR_CAP / 1): a design at the limit shows
    that the extreme is at least / at most that."""
    if limit is None:
        limit = TR_CAP if goal == "max_time_ratio" else 1.0
    limit = min(max(limit, 1.0), TR_CAP)
    tr = None if tr is None else float(tr)
    return _search(mtype, goal, tr, float(bound_deg), effort, float(limit))


@functools.lru_cache(maxsize=512)
def _search(mtype, goal, tr, bound_deg, effort, limit):
    assert goal in GOALS, goal
    t0 = time.monotonic()
    out = Found(goal, None)
    best = (math.inf, None, None, None)  # f, z, branch, problem
    for fam in FAMILIES[mtype]:
        prob = _Problem(fam, goal, tr, bound_deg, limit)
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
            ok, f = prob.feasible(z, branch)
            if not ok:
                out.per_seed.append((fam.variant, seed, None))
                continue
            if effort.polish:
                f, z = prob.polish(z, branch)
            out.per_seed.append((fam.variant, seed, prob.value(f)))
            if f < best[0]:
                best = (f, z, branch, prob)
    f, z, branch, prob = best
    if prob is not None:
        _, _, d = prob.evaluate(z[None, :], branch)
        out.value = prob.value(f)
        out.params = {k: float(v[0]) for k, v in d.params.items()}
        out.variant = prob.fam.variant
        out.simulated = _check(mtype, goal, tr, bound_deg, out)
    out.seconds = time.monotonic() - t0
    return out


def _check(mtype, goal, tr, bound_deg, found: Found) -> dict:
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
    if problems:
        raise AssertionError(
            f"global search ({mtype}, {goal}): the simulation disagrees with the closed forms "
            f"for {found.params}: " + "; ".join(problems)
        )
    return sim


def _links(mtype):
    return {q.name for q in get(mtype).parameters if q.name not in PLACEMENTS}
