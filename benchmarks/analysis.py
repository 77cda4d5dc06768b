"""What an analysis costs: the summary alone against curves (and how they grow with samples),
motion quality, sensitivities and the envelope.

    python -m benchmarks.analysis [--quick]

One reference design per type (docs/model.md, Reference cases). Each case is timed as the
median of repeated calls, in one run, interleaved with the summary-only baseline so that
machine load moves both; the report is the ratio to that baseline.

Also what a synthesis costs: the default requests (everything free, each objective, several
time ratios and bounds) and requests a type cannot meet, per type and for all five
quick-return types at once, each timed against summary analyses of the types asked, calls
alternated; and how the cost depends on the number of candidates asked for.
"""

from __future__ import annotations

import argparse
import itertools
import statistics
import time
from collections.abc import Callable
from dataclasses import replace
from functools import partial
from pathlib import Path

import numpy as np

import synth

from . import targets
from .common import RESULTS, report, table

DESIGNS = {
    "scotch_yoke": {"crank": 1.0},
    "offset_slider_crank": {"crank": 1.0, "coupler": 3.0, "offset": 0.5},
    "crank_shaper": {"crank": 120.0, "pivot_distance": 240.0, "lever": 450.0},
    "whitworth": {"crank": 75.0, "pivot_distance": 50.0, "lever": 150.0, "connecting_rod": 200.0},
    "crank_rocker_slider": {
        "ground": 5.0,
        "crank": 1.0,
        "coupler": 4.5,
        "rocker": 3.0,
        "rocker_arm": 4.0,
    },
    "drag_link_slider": {
        "ground": 0.1,
        "crank": 0.225,
        "coupler": 0.250428,
        "follower": 0.275,
        "follower_arm": 0.15,
        "connecting_rod": 0.3,
    },
}
SAMPLES = (10, 100, 1_000, 10_000, 100_000)
# a shaper's load on each reference design (the lengths read as mm): a 2 kN cut, a 60 kg ram,
# links of 8 kg/m, 40 strokes a minute
LOAD = synth.Load("mm", 40.0, cutting_force=2000.0, slider_mass=60.0, link_mass_per_length=8.0)
LIMIT = 1.5  # the fluctuation limit of motion_targets' "limit" requests
FIXED_TARGETS = 30  # motion_targets' fixed-part targets per type


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
        cases |= {
            "motion": partial(summary, include=["motion"]),
            "sensitivities": partial(summary, include=["sensitivities"]),
            "tolerance": partial(summary, tolerance=synth.Tolerance(relative=1e-3)),
            "envelope": partial(summary, include=["envelope"]),
            "load": partial(summary, load=LOAD),
            "load with friction": partial(summary, load=replace(LOAD, guide_friction=0.2)),
            "load, 1 000 samples": partial(summary, load=LOAD, samples=1_000),
        }
        for case, fn in cases.items():
            ms, ref = median_ms(fn, summary, repeats)
            rows.append({"type": mtype, "case": case, "ms": ms, "ratio": ms / ref})
    return rows


SYNTH_REQUEST = {
    "time_ratio": 1.6,
    "stroke": 1.0,
    "min_transmission_angle_deg": 20.0,
    "mechanisms": [{"type": "crank_rocker_slider"}],
}


def synthesis_costs(repeats: int) -> list[dict]:
    """A default request (crank-rocker, all free): cost against the candidates asked for (the
    verification stops once that many pass), and the generic multistart's cost beside it."""
    rows = []
    base = partial(synth.synthesize, **SYNTH_REQUEST)
    base()
    cases = {f"max_candidates {k}": partial(base, max_candidates=k) for k in (1, 5, 20, 50)}
    cases["generic multistart"] = partial(base, solver=synth.Solver(accelerators=False))
    for case, fn in cases.items():
        fn()
        ms, ref = median_ms(fn, base, repeats)
        rows.append({"case": case, "ms": ms, "ratio": ms / ref, "candidates": len(fn().candidates)})
    return rows


def pareto_costs(repeats: int, quick: bool = False) -> list[dict]:
    """The default answer (objective pareto, each type's front) against a max_transmission_angle
    request on the same targets (everything free, stroke 1), calls alternated; per type (and
    all five) the median and largest ratio over DEFAULT_TIME_RATIOS × DEFAULT_BOUNDS where the
    type has designs, and the points its fronts had."""
    ratios, bounds = ((1.6,), (20.0,)) if quick else (DEFAULT_TIME_RATIOS, DEFAULT_BOUNDS)
    rows = []
    for mtype in (*QUICK_RETURN, ALL):
        kinds = None if mtype == ALL else [{"type": mtype}]
        per = []
        for tr, b in itertools.product(ratios, bounds):
            front = partial(synth.synthesize, tr, 1.0, b, kinds)
            best = partial(front, objective="max_transmission_angle")
            r = front()
            best()
            if not r.candidates:
                continue
            ms, ref = median_ms(front, best, repeats)
            per.append((ms, ref, len(r.candidates)))
        if per:
            rows.append(
                {
                    "type": mtype,
                    "targets": len(per),
                    "pareto_ms": statistics.median(p[0] for p in per),
                    "max_transmission_ms": statistics.median(p[1] for p in per),
                    "ratio": statistics.median(p[0] / p[1] for p in per),
                    "ratio_max": max(p[0] / p[1] for p in per),
                    "points": statistics.median(p[2] for p in per),
                }
            )
    return rows


def motion_costs(repeats: int) -> list[dict]:
    """The motion objectives (SLSQP from many starts, ``synth.synthesis.motion``) against a
    max_transmission_angle request on the same targets (time ratio 1.6, stroke 1, bound 20°,
    everything free), per quick-return type, calls alternated; with the measure reached."""
    rows = []
    for mtype in QUICK_RETURN:
        request = partial(
            synth.synthesize, 1.6, 1.0, 20.0, [{"type": mtype}], time_budget_ms=30_000
        )
        best = partial(request, objective="max_transmission_angle")
        for objective in ("uniform_cutting_speed", "min_peak_acceleration"):
            fn = partial(request, objective=objective)
            r = fn()
            if not r.candidates:
                continue
            ms, ref = median_ms(fn, best, repeats)
            rows.append(
                {
                    "type": mtype,
                    "objective": objective,
                    "ms": ms,
                    "max_transmission_ms": ref,
                    "ratio": ms / ref,
                    "measure": r.candidates[0].objective_value,
                    "complete": r.complete,
                }
            )
    return rows


def motion_targets(quick: bool) -> list[dict]:
    """The motion objectives over targets, per quick-return type and objective, in process
    (the goals, ``docs/benchmarks.md``: everything free, median ≤ 10 ms; parts fixed, p99 ≤ 50
    ms):

    - ``free``: everything free at ``DEFAULT_TIME_RATIOS`` × ``DEFAULT_BOUNDS``, stroke 300;
    - ``limit``: the same with ``max_working_speed_fluctuation`` ``LIMIT``;
    - ``fixed``: the benchmark's feasible targets that fix parts (``benchmarks.targets``, the
      first ``FIXED_TARGETS`` of the type).

    Warm: each request asked once before it is timed (a fixed set's first request compiles
    its functions, ~150 ms). Median, p99 and max ms, and how many have a candidate."""
    ratios, bounds = ((1.6,), (20.0,)) if quick else (DEFAULT_TIME_RATIOS, DEFAULT_BOUNDS)
    per_type = 1 if quick else FIXED_TARGETS
    fixed_cases = [
        c for c in targets.cases(n_infeasible=0) if c["target"]["mechanisms"][0]["fixed"]
    ]
    rows = []
    for mtype in QUICK_RETURN:
        mine = [c["target"] for c in fixed_cases if c["type"] == mtype][:per_type]
        free = [
            {
                "time_ratio": tr,
                "stroke": 300.0,
                "min_transmission_angle_deg": b,
                "mechanisms": [{"type": mtype}],
            }
            for tr in ratios
            for b in bounds
        ]
        limited = [{**k, "max_working_speed_fluctuation": LIMIT} for k in free]
        for objective in ("uniform_cutting_speed", "min_peak_acceleration"):
            sets = {"free": free, "limit": limited, "fixed": mine}
            for kind, kwargs in sets.items():
                for k in kwargs:  # warm
                    synth.synthesize(**{**k, "objective": objective, "time_budget_ms": 30_000})
                ms, answered = [], 0
                for k in kwargs:
                    t0 = time.perf_counter()
                    r = synth.synthesize(**{**k, "objective": objective, "time_budget_ms": 30_000})
                    ms.append((time.perf_counter() - t0) * 1e3)
                    answered += bool(r.candidates)
                if ms:
                    rows.append(
                        {
                            "type": mtype,
                            "objective": objective,
                            "kind": kind,
                            "targets": len(ms),
                            "answered": answered,
                            "median_ms": statistics.median(ms),
                            "p99_ms": float(np.percentile(ms, 99)),
                            "max_ms": max(ms),
                        }
                    )
    return rows


# The default request: everything free, each objective, these ratios and bounds (the scotch
# yoke has time ratio 1 only; min_size needs a bound > 0, synth refuses it without one); and
# per type, requests it cannot meet: a bound above the best it reaches (its slot drive gives
# the crank-shaper 90° at any ratio) or a ratio beyond reach.
DEFAULT_TIME_RATIOS = (1.3, 1.6, 2.0, 2.5)
DEFAULT_BOUNDS = (0.0, 20.0, 40.0)
OBJECTIVES = ("max_transmission_angle", "min_size")
REFUSALS = {  # (time ratio, bound°)
    "scotch_yoke": ((1.6, 20.0), (3.0, 0.0)),  # time ratio 1 for every design
    "offset_slider_crank": ((1.6, 89.9), (3.5, 20.0)),  # μ ≤ 75.52° in the default bounds; TR < 3
    "crank_shaper": ((1.0, 20.0), (1.0, 0.0)),  # TR > 1 for every design
    "whitworth": ((1.6, 89.9), (1.0, 20.0)),  # μ ≤ 75.52° (its rod ≤ 2 strokes); TR > 1
    "crank_rocker_slider": ((1.6, 89.9), (10.0, 20.0)),  # 28.5° at TR 1.6; 1.2° at TR 10
    "drag_link_slider": ((1.6, 89.9), (10.0, 20.0)),  # as the crank-rocker
}
ALL = "all five"  # mechanisms omitted: the quick-return types
QUICK_RETURN = [t for t in DESIGNS if synth.mechanisms.get(t).quick_return]


def default_cases(quick: bool = False) -> list[dict]:
    """Every default request and refusal, per type and for all five quick-return types (quick:
    time ratio 1.6 and bound 20° only)."""
    out = []
    ratios, bounds = ((1.6,), (20.0,)) if quick else (DEFAULT_TIME_RATIOS, DEFAULT_BOUNDS)
    for mtype in (*DESIGNS, ALL):
        grid = [(1.0 if mtype == "scotch_yoke" else tr, b) for tr in ratios for b in bounds]
        grid = list(dict.fromkeys(grid))
        for kind, pairs in (("default", grid), ("refusal", REFUSALS.get(mtype, ()))):
            out += [
                {"type": mtype, "kind": kind, "time_ratio": tr, "bound": b, "objective": o}
                for tr, b in pairs
                for o in OBJECTIVES
                if b > 0 or o != "min_size"
            ]
    return out


def _request(case: dict, solver: synth.Solver | None = None):
    kinds = None if case["type"] == ALL else [{"type": case["type"]}]
    return partial(
        synth.synthesize,
        case["time_ratio"],
        1.0,
        case["bound"],
        mechanisms=kinds,
        objective=case["objective"],
        solver=solver or synth.Solver(),
    )


def _best(r: synth.SynthesisResult, objective: str) -> float | None:
    if not r.candidates:
        return None
    c = r.candidates[0]
    return c.size if objective == "min_size" else c.min_transmission_angle_deg


def default_requests(repeats: int, quick: bool = False) -> list[dict]:
    """Each default request and refusal timed against a summary analysis of each type asked
    (DESIGNS), calls alternated; with its outcome, and (untimed, not when ``quick``) the
    generic multistart's outcome on the same request."""
    out = []
    for case in default_cases(quick):
        asked = QUICK_RETURN if case["type"] == ALL else [case["type"]]

        def base(asked=asked):
            for t in asked:
                synth.analyze(t, DESIGNS[t])

        fn = _request(case)
        r = fn()  # builds what it needs
        ms, ref = median_ms(fn, base, repeats)
        row = {
            **case,
            "ms": ms,
            "analyses_ms": ref,
            "answered": bool(r.candidates),
            "best": _best(r, case["objective"]),
            "methods": sorted({c.method for c in r.candidates}),
            "refusals": sorted({i.code for i in r.infeasible}),
        }
        if not quick:
            g = _request(case, synth.Solver(accelerators=False))()
            row["generic_answered"] = bool(g.candidates)
            row["generic_best"] = _best(g, case["objective"])
        out.append(row)
    return out


def default_summary(cases: list[dict]) -> list[dict]:
    """Per type (and all five): medians over the default requests and over the refusals, in ms
    and in summary analyses; how many were answered; and the checks: a refusal where generic
    answers, a worse best design than generic's, and min_size refused where the same targets
    with max_transmission_angle have a design (the two objectives share their feasible set)."""
    rows = []
    answered = {
        (c["type"], c["time_ratio"], c["bound"], c["objective"]): c["answered"] for c in cases
    }
    for mtype in dict.fromkeys(c["type"] for c in cases):
        row: dict = {"type": mtype}
        for kind in ("default", "refusal"):
            cs = [c for c in cases if c["type"] == mtype and c["kind"] == kind]
            if not cs:
                continue
            ms = [c["ms"] for c in cs]
            row |= {
                f"{kind}_n": len(cs),
                f"{kind}_answered": sum(c["answered"] for c in cs),
                f"{kind}_ms": statistics.median(ms),
                f"{kind}_ms_p90": float(np.quantile(ms, 0.9, method="inverted_cdf")),
                f"{kind}_ms_max": max(ms),
                f"{kind}_analyses": statistics.median(c["ms"] / c["analyses_ms"] for c in cs),
                f"{kind}_ipopt": sum(any("ipopt" in m for m in c["methods"]) for c in cs),
            }
        checked = [c for c in cases if c["type"] == mtype and "generic_answered" in c]
        row["worse_than_generic"] = [_label(c) for c in checked if _worse(c)]
        row["min_size_refused_but_feasible"] = [
            _label(c)
            for c in cases
            if c["type"] == mtype
            and c["objective"] == "min_size"
            and not c["answered"]
            and answered.get((mtype, c["time_ratio"], c["bound"], "max_transmission_angle"))
        ]
        rows.append(row)
    return rows


def _worse(c: dict) -> bool:
    """Generic answered and ours did not, or generic's best design is better by > 1e-9."""
    if not c["generic_answered"]:
        return False
    if not c["answered"]:
        return True
    o, g = c["best"], c["generic_best"]
    if c["objective"] == "min_size":
        return o > g * (1 + 1e-9)
    return o < g - 1e-9 * max(1.0, g)


def _label(c: dict) -> str:
    return f"TR {c['time_ratio']:g}, {c['bound']:g}°, {c['objective']}"


def main(argv: list[str] | None = None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--quick", action="store_true", help="a smoke run: few repeats and sizes")
    a = ap.parse_args(argv)
    repeats = 3 if a.quick else 25
    cases = default_requests(1 if a.quick else 7, a.quick)
    results = {
        "analysis": analysis_costs(repeats, SAMPLES[:3] if a.quick else SAMPLES),
        "synthesis": synthesis_costs(2 if a.quick else 7),
        "default_requests": default_summary(cases),
        "pareto": pareto_costs(3 if a.quick else 9, a.quick),
        "motion_objectives": motion_costs(1 if a.quick else 3),
        "motion_targets": motion_targets(a.quick),
        "default_request_cases": cases,
    }
    print(table(results["analysis"], ("type", "case", "ms", "ratio")))
    print(table(results["synthesis"], ("case", "ms", "ratio", "candidates")))
    columns = (
        "type",
        "default_n",
        "default_answered",
        "default_ms",
        "default_ms_p90",
        "default_ms_max",
        "default_analyses",
        "refusal_n",
        "refusal_answered",
        "refusal_ms",
        "refusal_ms_max",
        "refusal_analyses",
    )
    print(table(results["default_requests"], columns))
    print(
        table(
            results["pareto"],
            ("type", "targets", "pareto_ms", "max_transmission_ms", "ratio", "ratio_max", "points"),
        )
    )
    print(
        table(
            results["motion_objectives"],
            ("type", "objective", "ms", "max_transmission_ms", "ratio", "measure", "complete"),
        )
    )
    print(
        table(
            results["motion_targets"],
            ("type", "objective", "kind", "targets", "answered", "median_ms", "p99_ms", "max_ms"),
        )
    )
    for r in results["default_requests"]:
        for key in ("worse_than_generic", "min_size_refused_but_feasible"):
            if r[key]:
                print(f"{r['type']}: {key}: {'; '.join(r[key])}")
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
        pts = [
            (int(r["case"].split()[1]), r["ratio"])
            for r in rows
            if r["type"] == mtype and r["case"].endswith("samples")
        ]
        ax.loglog(*zip(*pts, strict=True), marker="o", label=mtype)
    ax.axhline(1.0, color="grey", lw=0.8, ls="--")
    ax.set(
        xlabel="curve samples per request",
        ylabel="time / summary-only time",
        title="synth.analyze: the cost of curves",
    )
    ax.legend(fontsize=8)
    fig.tight_layout()
    RESULTS.mkdir(exist_ok=True)
    fig.savefig(path, dpi=120)
    plt.close(fig)


if __name__ == "__main__":
    main()
