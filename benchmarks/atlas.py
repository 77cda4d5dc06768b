"""What a design atlas costs (synth.atlas): grid points per second per core, how a local pool
scales from one worker to two, what the pool and a Dask cluster (two local worker processes)
cost against running in-process, and what a 10⁶-point atlas would take on 64 cores
(extrapolated from this machine, and said to be).

    python -m benchmarks.atlas [--quick]

Every run is in one process tree, in one sitting, its grid fresh (no folder to resume from);
each configuration is run ``repeats`` times, alternated, and the median kept.
"""

from __future__ import annotations

import argparse
import statistics
import time

from synth.atlas import atlas

from .common import report, table

TYPES = (
    "offset_slider_crank",
    "crank_shaper",
    "whitworth",
    "crank_rocker_slider",
    "drag_link_slider",
)


def grid(n: int) -> tuple[float, ...]:
    return tuple(round(1.05 + 2.95 * k / (n - 1), 9) for k in range(n))


def timed(**kw) -> float:
    t0 = time.perf_counter()
    atlas(TYPES, bounds=(), **kw)
    return time.perf_counter() - t0


def main(argv: list[str] | None = None) -> dict:
    from dask.distributed import LocalCluster

    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--quick", action="store_true", help="a smoke run: a small grid")
    a = ap.parse_args(argv)
    ratios = grid(20 if a.quick else 2000)
    points = len(TYPES) * len(ratios)
    runs = {"inline": [], "pool, 1 worker": [], "pool, 2 workers": [], "dask, 2 workers": []}
    with LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
    ) as cluster:
        for _ in range(1 if a.quick else 3):
            runs["inline"].append(timed(ratios=ratios, inline=True))
            runs["pool, 1 worker"].append(timed(ratios=ratios, workers=1))
            runs["pool, 2 workers"].append(timed(ratios=ratios, workers=2))
            runs["dask, 2 workers"].append(
                timed(ratios=ratios, scheduler=cluster.scheduler_address)
            )
    s = {k: statistics.median(v) for k, v in runs.items()}
    rows = [
        {"run": k, "points": points, "seconds": t, "points_per_s": points / t} for k, t in s.items()
    ]
    per_core = points / s["inline"]
    speedup = s["pool, 1 worker"] / s["pool, 2 workers"]
    efficiency = speedup / 2
    results = {
        "runs": rows,
        "points_per_s_per_core": per_core,
        "pool_overhead": s["pool, 1 worker"] / s["inline"],
        "dask_against_pool": s["dask, 2 workers"] / s["pool, 2 workers"],
        "speedup_1_to_2_workers": speedup,
        "extrapolated_1e6_points_64_cores_s": 1e6 / (per_core * 64 * efficiency),
        "extrapolation": "10⁶ points / (this machine's points per second per core × 64 cores × "
        "the 2-worker efficiency measured here): an estimate, not a measurement",
    }
    print(table(rows, ("run", "points", "seconds", "points_per_s")))
    print(
        f"{per_core:.0f} points/s per core; pool overhead ×{results['pool_overhead']:.2f}; "
        f"1 → 2 workers ×{speedup:.2f}; Dask against the pool "
        f"×{results['dask_against_pool']:.2f}; 10⁶ points on 64 cores ≈ "
        f"{results['extrapolated_1e6_points_64_cores_s']:.0f} s (extrapolated)"
    )
    return report("atlas", results, quick=a.quick)


if __name__ == "__main__":
    main()
