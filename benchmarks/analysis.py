"""What an analysis costs: the summary alone against curves, and how it grows with samples.

    python -m benchmarks.analysis [--quick]

One reference design per type (mechanisms.md). Each case is timed as the median of repeated
calls, in one run, interleaved with the summary-only baseline so that machine load moves both;
the report is the ratio to that baseline. Also: how synthesis cost grows with the number of
candidates asked for and with the multistart size.
"""

from __future__ import annotations

import argparse
import statistics
import time
from collections.abc import Callable
from contextlib import AbstractContextManager
from functools import partial
from pathlib import Path

import numpy as np

import synth
from synth import synthesis
from synth.formulation import relevant
from synth.solve import starts as synthesis_starts

from .common import RESULTS, report, table
from .methods import patched, starts

DESIGNS = {
    "scotch_yoke": {"crank": 1.0},
    "offset_slider_crank": {"crank": 1.0, "coupler": 3.0, "offset": 0.5},
    "crank_shaper": {"crank": 120.0, "pivot_distance": 240.0, "lever": 450.0},
    "whitworth": {"crank": 75.0, "pivot_distance": 50.0, "lever": 150.0, "connecting_rod": 200.0},
    "crank_rocker_slider": {"ground": 5.0, "crank": 1.0, "coupler": 4.5, "rocker": 3.0,
                            "rocker_arm": 4.0},
    "drag_link_slider": {"ground": 0.1, "crank": 0.225, "coupler": 0.250428, "follower": 0.275,
                         "follower_arm": 0.15, "connecting_rod": 0.3},
}  # fmt: skip
SAMPLES = (10, 100, 1_000, 10_000, 100_000)


def median_ms(fn: Callable[[], object], baseline: Callable[[], object], repeats: int):
    """(median ms of fn, median ms of baseline), calls alternated."""
    a, b = [], []
    for _ in range(repeats):
        for f, out in ((fn, a), (baseline, b)):
            t0 = time.perf_counter()
            f()
            out.append((time.perf_counter() - t0) * 1e3)
    return statistics.median(a), statistics.median(b)


def analysis_costs(repeats: int, samples: tuple[int, ...]) -> list[dict]:
    rows = []
    for mtype, p in DESIGNS.items():
        summary = partial(synth.analyze, mtype, p)
        summary()  # builds the compiled model
        cases = {"summary": summary, "curves, 1 angle": partial(summary, crank_angles_deg=[60.0])}
        cases |= {f"curves, {n} samples": partial(summary, samples=n) for n in samples}
        for case, fn in cases.items():
            ms, ref = median_ms(fn, summary, repeats)
            rows.append({"type": mtype, "case": case, "ms": ms, "ratio": ms / ref})
    return rows


SYNTH_REQUEST = {"time_ratio": 1.6, "stroke": 1.0, "min_transmission_angle_deg": 20.0,
                 "mechanisms": [{"type": "crank_rocker_slider"}]}  # fmt: skip


def synthesis_costs(repeats: int) -> list[dict]:
    """A family search (crank-rocker, all free): cost against candidates and starts."""
    rows = []
    base = partial(synth.synthesize, **SYNTH_REQUEST)
    base()
    for k in (1, 5, 20, 50):
        ms, ref = median_ms(partial(base, max_candidates=k), base, repeats)
        rows.append({"case": f"max_candidates {k}", "ms": ms, "ratio": ms / ref})
    for n in (1, 2, 4, 8, 16, 32):
        fn = under(starts(n), base)  # the benchmark's "ours_starts_n"
        ms, ref = median_ms(fn, base, repeats)
        rows.append({"case": f"starts {n}", "ms": ms, "ratio": ms / ref,
                     "candidates": len(fn().candidates)})  # fmt: skip
    return rows


DEFAULT_TIME_RATIOS = (1.3, 1.6, 2.0)


def default_requests(repeats: int) -> list[dict]:
    """The default request (everything free, bound 20°) for each type and for all six at once,
    the median over DEFAULT_TIME_RATIOS; the baseline is a summary analysis of each type asked."""
    rows = []
    for mtype in (*DESIGNS, "all six"):
        kinds = None if mtype == "all six" else [{"type": mtype}]
        asked = DESIGNS if kinds is None else {mtype: DESIGNS[mtype]}

        def base(asked=asked):
            for t, p in asked.items():
                synth.analyze(t, p)

        times, refs = [], []
        for tr in DEFAULT_TIME_RATIOS:
            fn = partial(synth.synthesize, tr, 1.0, 20.0, mechanisms=kinds)
            fn()  # builds the solvers
            ms, ref = median_ms(fn, base, repeats)
            times.append(ms), refs.append(ref)
        ms = statistics.median(times)
        rows.append({"type": mtype, "ms": ms, "analyses": ms / statistics.median(refs)})
    return rows


SESSION = tuple(1.50 + 0.01 * k for k in range(11))  # a designer nudging the time ratio


def warm_starts(repeats: int) -> list[dict]:
    """A session of requests whose time ratio moves 1.50 → 1.60 (crank-rocker, all free, bound
    20°): cold, the shipped 8 starts per request; warm, one start, the previous request's best
    design (the rest of the Halton sequence only where that design does not fit the variant)."""
    m = synth.mechanisms.get("crank_rocker_slider")
    frees = [relevant(m, v) for v in (frozenset(), frozenset({"connecting_rod"}))]

    def session(warm: bool) -> list[synth.SynthesisResult]:
        out, prev = [], None
        for tr in SESSION:
            request = {**SYNTH_REQUEST, "time_ratio": tr}
            if not warm or prev is None:
                out.append(synth.synthesize(**request))
            else:
                with patched(synthesis, STARTS=1, starts=partial(_from, prev, frees)):
                    out.append(synth.synthesize(**request))
            prev = out[-1].candidates[0].params if out[-1].candidates else None
        return out

    cold_ms, warm_ms = median_ms(partial(session, False), partial(session, True), repeats)
    cold, warm = session(False), session(True)
    n = len(SESSION)
    return [
        {"case": case, "ms_per_request": ms / n, "ratio": ms / cold_ms,
         "solved": sum(bool(r.candidates) for r in rs) / n,
         "candidates": statistics.mean(len(r.candidates) for r in rs),
         "best_angle_lost_deg": max(c.candidates[0].min_transmission_angle_deg
                                    - w.candidates[0].min_transmission_angle_deg
                                    if w.candidates else float("inf")
                                    for c, w in zip(cold, rs, strict=True))}
        for case, ms, rs in (("cold, 8 starts", cold_ms, cold), ("warm, 1 start", warm_ms, warm))
    ]  # fmt: skip


def _from(prev: dict[str, float], frees, lo, hi, log, n):
    """The previous design first (where it has the variant's parameters), then Halton."""
    rest = synthesis_starts(lo, hi, log, n)
    for free in frees:
        if len(free) == lo.size and all(k in prev for k in free):
            first = np.clip([prev[k] for k in free], lo, hi)
            return np.vstack([first, rest])
    return rest


def under(patch: Callable[[], AbstractContextManager[None]], fn: Callable[[], object]):
    """fn, called inside ``patch()``."""

    def call():
        with patch():
            return fn()

    return call


def main(argv: list[str] | None = None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--quick", action="store_true", help="a smoke run: few repeats and sizes")
    a = ap.parse_args(argv)
    repeats = 3 if a.quick else 25
    results = {
        "analysis": analysis_costs(repeats, SAMPLES[:3] if a.quick else SAMPLES),
        "synthesis": synthesis_costs(2 if a.quick else 7),
        "default_requests": default_requests(1 if a.quick else 5),
        "warm_starts": warm_starts(1 if a.quick else 3),
    }
    print(table(results["analysis"], ("type", "case", "ms", "ratio")))
    print(table(results["synthesis"], ("case", "ms", "ratio", "candidates")))
    print(table(results["default_requests"], ("type", "ms", "analyses")))
    print(table(results["warm_starts"], ("case", "ms_per_request", "ratio", "solved",
                                         "candidates", "best_angle_lost_deg")))  # fmt: skip
    if not a.quick:
        plot(results["analysis"], RESULTS / "analysis_cost_vs_samples.png")
    return report("analysis", results, quick=a.quick)


def plot(rows: list[dict], path: Path) -> None:
    """Cost over the summary alone against the number of curve samples, one line per type."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    for mtype in DESIGNS:
        pts = [(int(r["case"].split()[1]), r["ratio"]) for r in rows
               if r["type"] == mtype and r["case"].endswith("samples")]  # fmt: skip
        ax.loglog(*zip(*pts, strict=True), marker="o", label=mtype)
    ax.axhline(1.0, color="grey", lw=0.8, ls="--")
    ax.set(xlabel="curve samples per request", ylabel="time / summary-only time",
           title="synth.analyze: the cost of curves")  # fmt: skip
    ax.legend(fontsize=8)
    fig.tight_layout()
    RESULTS.mkdir(exist_ok=True)
    fig.savefig(path, dpi=120)
    plt.close(fig)


if __name__ == "__main__":
    main()
