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

Last (``--search``: alone), the certified search these bounds serve, the product's
(``synth.synthesis.certify``), on the least peak |s″| at time ratio 1.6 and 20°: its levels,
boxes, gap and time. Not part of ``make bench``.
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
from synth.synthesis import certify
from synth.synthesis.motion import ACROSS
from synth.synthesis.search import Spec, Targets
from synth.synthesis.search import search as search_types
from synth.targets import MAX_TRANSMISSION

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


def searched() -> list[dict]:
    """The product's certified search (``synth.synthesis.certify``) on the same request: the
    least peak |s″| of the offset slider-crank at time ratio 1.6 and 20°, warm (the median of
    five runs after one that builds)."""
    m = get("offset_slider_crank")
    t = Targets(1.6, 1.0, 20.0, MAX_TRANSMISSION, math.inf)
    (v,) = search_types(m, Spec(m.type), 0, t).variants
    targets = (1.6, min(t.cos_bound, 1 - ACROSS))
    certify.search(m, v, "acceleration", targets, math.inf)
    times = []
    for _ in range(5):
        t0 = time.perf_counter()
        c = certify.search(m, v, "acceleration", targets, math.inf)
        times.append((time.perf_counter() - t0) * 1e3)
    assert not isinstance(c, str), c
    gap = (c.value - c.bound) / c.value
    row = {"levels": c.levels, "boxes": c.boxes, "gap": gap, "peak": c.value}
    row["ms"] = statistics.median(times)
    print(table([row], tuple(row)))
    return [row]


if __name__ == "__main__":
    main()
