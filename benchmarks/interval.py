"""Whether interval enclosures (synth.numerics.interval) can bound a searched objective: the
offset slider-crank's peak |slider acceleration| over the crank turn (ω = 1), around the design
the default synthesis gives at time ratio 1.6, stroke 300, bound 20°.

    python -m benchmarks.interval [--quick]

For boxes P of relative width w around the design in its three parameters, the lower bound of
min_{p∈P} max_θ |a(θ, p)| is max_k inf_{p∈P} |a(θ_k, p)| over 64 angles and the design's own
peak angle. The table gives, relative to the design's true peak: ``best_bound_gap``, the gap
of the best bound these angles allow (max_k of the sampled min_p |a(θ_k, p)|: the objective's
own variation over the box); ``*_gap``, the naive and centred bounds' gap; ``*_excess``, what
they lose to the best bound (the enclosure's overestimate). Then the cost of a box (its 65
angles) when 1, 100 or 10 000 boxes are evaluated at once, numpy's forms and the compiled ones
(synth.numerics.compiled_interval) in the same run, medians.

Last, a throwaway branch-and-bound: the least peak |s″| over the dead-centre construction's q
(``offset_slider_crank.reduced``: crank, coupler, offset of q at time ratio 1.6, stroke 300)
where μ_min ≥ 20°, certified to a relative gap of 1e-9: each level bounds every live box from
below by the centred enclosure at the peak angles at its centre (Newton from the incumbent's)
and at 0 or 32 fixed angles (``grid``), measures the peak exactly (a grid, then Newton) at
the centre of the box with the least bound (the incumbent, the upper bound), drops the boxes
whose bound is within the gap of it and halves the rest. Not part of ``make bench``.
"""

from __future__ import annotations

import argparse
import math
import statistics
import time

import casadi as ca
import numpy as np
from scipy.optimize import minimize_scalar

import synth
from synth.mechanisms import get
from synth.numerics.compiled_interval import CompiledCentred, CompiledInterval
from synth.numerics.interval import Centred, Interval
from synth.numerics.native import Mapped

from .common import report, table

ANGLES = 64
WIDTHS = (1e-1, 1e-2, 1e-3, 1e-4, 1e-5, 1e-6)
BATCHES = (1, 100, 10_000)


def acceleration() -> ca.Function:
    """a(θ, p) = s″(θ), the motion model's second row (``Model``, kind "motion")."""
    m = get("offset_slider_crank")
    th, pv = ca.SX.sym("theta"), ca.SX.sym("p", len(m.parameters))
    s = m.position({q.name: pv[i] for i, q in enumerate(m.parameters)}, th)
    a = ca.jacobian(ca.jacobian(s, th), th)
    return ca.Function("acceleration", [th, pv], [a], {"cse": True})


def values(fn: ca.Function, theta: np.ndarray, p: np.ndarray) -> np.ndarray:
    """fn at each (θ, p) pair (θ: (n,), p: (n, 3))."""
    return np.array(fn.map(len(theta))(theta[None], p.T)).ravel()


def peak(fn: ca.Function, p: np.ndarray) -> tuple[float, float]:
    """The design's peak |a| and its angle: a dense grid, then a bounded scalar search."""
    grid = np.linspace(0, 2 * np.pi, 4096, endpoint=False)
    i = int(np.argmax(np.abs(values(fn, grid, np.tile(p, (len(grid), 1))))))
    step = grid[1]
    res = minimize_scalar(
        lambda t: -abs(float(fn(t, p))),
        bounds=(grid[i] - step, grid[i] + step),
        method="bounded",
        options={"xatol": 1e-12},
    )
    return -float(res.fun), float(res.x)


def lower_bound(enclose, theta: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """max_k inf_{p∈P} |a(θ_k, p)| for each box (lo, hi: (boxes, 3))."""
    n, k = len(lo), len(theta)
    t = np.tile(theta, n)[:, None]
    e = enclose([t, np.repeat(lo, k, axis=0)], [t, np.repeat(hi, k, axis=0)])
    a_lo, a_hi = e.lo[0][:, 0], e.hi[0][:, 0]
    least = np.maximum(np.maximum(a_lo, -a_hi), 0.0)  # inf |a| over the box
    return least.reshape(n, k).max(axis=1)


def gaps(fn, forms, theta, p, top, samples: int) -> list[dict]:
    rng = np.random.default_rng(0)
    rows = []
    for w in WIDTHS:
        lo, hi = p * (1 - w / 2), p * (1 + w / 2)
        corners = np.array(np.meshgrid(*[[0.0, 1.0]] * 3, indexing="ij")).reshape(3, -1).T
        u = np.concatenate([corners, rng.uniform(0, 1, (samples, 3))])
        designs = lo + (hi - lo) * u
        a = np.abs(values(fn, np.tile(theta, len(designs)), np.repeat(designs, len(theta), 0)))
        best = a.reshape(len(designs), -1).min(axis=0).max()  # max_k of the sampled min_p
        row = {"width": w, "best_bound_gap": (top - best) / top}
        for name, enclose in forms.items():
            bound = float(lower_bound(enclose, theta, lo[None], hi[None])[0])
            row[f"{name}_gap"] = (top - bound) / top
            row[f"{name}_excess"] = (best - bound) / top
        rows.append(row)
    return rows


def costs(forms, theta, p, batches, repeats: int) -> list[dict]:
    rng = np.random.default_rng(1)
    rows = []
    for n in batches:
        w = 10 ** rng.uniform(-6, -1, (n, 1))
        lo, hi = p * (1 - w / 2), p * (1 + w / 2)
        row: dict = {"boxes": n}
        for name, enclose in forms.items():
            times = []
            for _ in range(repeats):
                t0 = time.perf_counter()
                lower_bound(enclose, theta, lo, hi)
                times.append(time.perf_counter() - t0)
            row[f"{name}_us_per_box"] = statistics.median(times) / n * 1e6
            row[f"{name}_us_per_angle"] = row[f"{name}_us_per_box"] / len(theta)
        rows.append(row)
    return rows


def main(argv: list[str] | None = None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--quick", action="store_true", help="fewer samples, batches to 1 000")
    ap.add_argument("--search", action="store_true", help="the branch-and-bound only")
    a = ap.parse_args(argv)
    if a.search:
        return {"search": searched()}
    design = synth.synthesize(1.6, 300.0, 20.0, mechanisms=["offset_slider_crank"])
    params = design.candidates[0].params
    p = np.array([params[q.name] for q in get("offset_slider_crank").parameters])
    fn = acceleration()
    top, at = peak(fn, p)
    theta = np.append(np.linspace(0, 2 * np.pi, ANGLES, endpoint=False), at)
    forms = {
        "naive": Interval(fn),
        "centred": Centred(fn, wrt=[1], continuous=True),
        "compiled_naive": CompiledInterval(fn),
        "compiled_centred": CompiledCentred(fn, wrt=[1], continuous=True),
    }
    gap_rows = gaps(fn, forms, theta, p, top, 200 if a.quick else 5000)
    batches = (1, 100, 1_000) if a.quick else BATCHES
    cost_rows = costs(forms, theta, p, batches, 3 if a.quick else 9)
    print(
        f"design {params}, peak |a| {top:.12g} at θ = {at:.12g} rad ({fn.n_instructions()} "
        "instructions)\n"
    )
    cols = ("width", "best_bound_gap", "naive_gap", "naive_excess", "centred_gap")
    print(table(gap_rows, (*cols, "centred_excess", "compiled_centred_excess")))
    cols = ("boxes", "naive_us_per_box", "compiled_naive_us_per_box", "centred_us_per_box")
    print(table(cost_rows, (*cols, "compiled_centred_us_per_box")))
    cols = ("boxes", "naive_us_per_angle", "compiled_naive_us_per_angle", "centred_us_per_angle")
    print(table(cost_rows, (*cols, "compiled_centred_us_per_angle")))
    searches = searched()
    return report(
        "interval",
        {
            "design": params,
            "peak": top,
            "peak_angle": at,
            "gaps": gap_rows,
            "costs": cost_rows,
            "search": searches,
        },
        a.quick,
    )


TOL = 1e-9  # the relative gap certified
# the enclosures, and how many fixed angles besides the peaks' each box's bound takes
SEARCHES = [(e, g) for g in (0, 32) for e in (("compiled", CompiledCentred), ("numpy", Centred))]


def construction(ratio: float, stroke: float) -> tuple[ca.Function, ca.Function, float, float]:
    """a(θ, q) (the slider's acceleration, stroke units × ``stroke``), (a, a′, a″) in θ, and
    the q where μ_min ≥ 20° on the synthesis's branch (0 < q < cos β: ``reduced``)."""
    beta = math.pi * (ratio - 1) / (ratio + 1)
    s, c = math.sin(beta / 2), math.cos(beta / 2)
    th, q = ca.SX.sym("theta"), ca.SX.sym("q")
    p = {
        "crank": stroke * ca.sqrt(c * c - q) / (2 * c),
        "coupler": stroke * ca.sqrt(s * s + q) / (2 * s),
        "offset": stroke * q / math.sin(beta),
    }
    acc = ca.jacobian(ca.jacobian(get("offset_slider_crank").position(p, th), th), th)
    a1 = ca.jacobian(acc, th)
    fn = ca.Function("acc_q", [th, q], [acc], {"cse": True})
    rows = ca.Function("acc_q_rows", [th, q], [ca.vertcat(acc, a1, ca.jacobian(a1, th))])

    def cos_mu(x: float) -> float:
        return (x + s * math.sqrt(c * c - x)) / (c * math.sqrt(s * s + x))

    star, bound = s * (math.sqrt(s * s + 4) - 3 * s) / 2, math.cos(math.radians(20))

    def edge(inside: float, outside: float) -> float:  # bisection to the last float
        while True:
            mid = 0.5 * (inside + outside)
            if mid in (inside, outside):
                return inside
            inside, outside = (mid, outside) if cos_mu(mid) <= bound else (inside, mid)

    return fn, rows, edge(star, 0.0), edge(star, math.cos(beta))


class Peaks:
    """The peak |a| over the crank's turn at given q, in floats (the compiled function)."""

    def __init__(self, rows: ca.Function) -> None:
        self.mapped = Mapped(rows, (False, False))

    def rows(self, theta: np.ndarray, q: np.ndarray) -> np.ndarray:
        return self.mapped(theta.reshape(-1, 1), q.reshape(-1, 1))  # (3, n)

    def newton(self, theta: np.ndarray, q: np.ndarray, steps: int) -> np.ndarray:
        """Angles moved towards a′ = 0 (a step that does not stay small is not taken)."""
        for _ in range(steps):
            a = self.rows(theta, q)
            step = a[1] / a[2]
            theta = np.where(np.abs(step) < 0.1, theta - step, theta)
        return theta

    def measure(self, q: float) -> tuple[float, np.ndarray]:
        """The peak |a| at q and its local peaks' angles (those above half of it)."""
        grid = np.linspace(0, 2 * np.pi, 256, endpoint=False)
        v = np.abs(self.rows(grid, np.full_like(grid, q))[0])
        local = (v >= np.roll(v, 1)) & (v >= np.roll(v, -1)) & (v >= 0.5 * v.max())
        theta = self.newton(grid[local], np.full(local.sum(), q), 8)
        w = np.abs(self.rows(theta, np.full_like(theta, q))[0])
        return float(max(w.max(), v.max())), theta


def searched() -> list[dict]:
    """The search with each enclosure, warm (the second of two runs: the first builds)."""
    rows = [[search(*form, grid) for _ in range(2)][-1] for form, grid in SEARCHES]
    cols = ("enclosure", "grid", "levels", "boxes", "angles_bounded", "gap", "peak", "q")
    print(table(rows, (*cols, "ms", "enclosure_ms", "calls")))
    return rows


def search(name: str, form: type, grid: int) -> dict:
    """The branch-and-bound to ``TOL`` (see the module's docstring), with one enclosure."""
    fn, rows, qa, qb = construction(1.6, 300.0)
    enclose, peaks = form(fn, wrt=[1], continuous=True), Peaks(rows)
    t0 = time.perf_counter()
    top, angles = peaks.measure(0.5 * (qa + qb))
    live, least = np.array([[qa, qb]]), math.inf
    levels = count = bounded = calls = 0
    spent = 0.0
    best_q = 0.5 * (qa + qb)
    while len(live):
        levels += 1
        n, centres = len(live), live.mean(axis=1)
        at = peaks.newton(np.tile(angles, n), np.repeat(centres, len(angles)), 3)
        fixed = np.linspace(0, 2 * np.pi, grid, endpoint=False)
        theta = np.concatenate([np.tile(fixed, (n, 1)), at.reshape(n, -1)], axis=1)
        k = theta.shape[1]
        t = theta.reshape(-1, 1)
        t1 = time.perf_counter()
        e = enclose([t, np.repeat(live[:, :1], k, 0)], [t, np.repeat(live[:, 1:], k, 0)])
        spent += time.perf_counter() - t1
        calls += 1
        lows = np.fmax(np.fmax(e.lo[0][:, 0], -e.hi[0][:, 0]), 0.0)  # inf |a| (NaN: 0)
        lower = lows.reshape(n, k).max(axis=1)
        count, bounded = count + n, bounded + n * k
        j = int(np.argmin(lower))
        value, found = peaks.measure(float(centres[j]))
        if value < top:
            top, angles, best_q = value, found, float(centres[j])
        keep = lower < top * (1 - TOL)
        least = min(least, *lower[~keep]) if (~keep).any() else least
        mids = centres[keep]
        live = np.concatenate(
            [np.stack([live[keep, 0], mids], 1), np.stack([mids, live[keep, 1]], 1)]
        )
    ms = (time.perf_counter() - t0) * 1e3
    return {
        "enclosure": name,
        "grid": grid,
        "levels": levels,
        "boxes": count,
        "angles_bounded": bounded,
        "gap": (top - least) / top,
        "peak": top,
        "q": best_q,
        "ms": ms,
        "enclosure_ms": spent * 1e3,
        "calls": calls,
    }


if __name__ == "__main__":
    main()
