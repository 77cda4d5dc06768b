"""Synthesis benchmark (issue 6): every method on the same targets, verified the same way.

    python -m benchmarks.synthesis            # all targets and methods, ~20 min on 2 cores
    python -m benchmarks.synthesis --quick    # a smoke run: a few targets, fewer methods

Targets come from ``benchmarks.targets`` (seeded; feasible or infeasible by construction),
methods from ``benchmarks.methods``. Each method first runs once, untimed, on a case of every
structure (type, fixed parts, feasibility; the swarm and evolution once per type, whose build
costs are negligible beside their runs) so that no timing includes building a solver. Then the
cases run in turn, the types interleaved, every method on a case before the next case (in an
order rotated per case), so that changes in the machine's load touch every method alike.

Every returned candidate is re-analysed by ``synth.analyze`` (root-found dead centres): its
relative time-ratio and stroke errors and its transmission-angle violation (degrees below the
bound), a candidate's error being the largest of the three. A method succeeds on a feasible
target when a candidate's error is ≤ 1e-9, and refuses an infeasible one correctly when none is.

Prints the summary as markdown tables and writes (``write``) the results to ``--out``
(default ``benchmarks/results``; ``--quick`` writes only where ``--out`` is given).
"""

from __future__ import annotations

import os

os.environ.setdefault("OMP_NUM_THREADS", "1")  # as the Makefile: one thread per process
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse
import gzip
import itertools
import json
import math
import sys
import time
import warnings
from pathlib import Path
from typing import Any

import numpy as np

from synth import SynthError, analyze, synthesis
from synth.mechanisms import all_types

from . import methods, targets
from .common import machine

TOL = 1e-9  # relative on time ratio and stroke, degrees on the transmission bound
FLOOR = 1e-17  # errors plotted no lower (exact zeros)
CAP = 1e3  # nor higher (a design that does not run counts as inf)
QUICK = {"n_feasible": 5, "n_infeasible": 2}
QUICK_BUDGETS = {  # the global searches cut to a smoke test's size
    "DE": {"maxiter": 20, "popsize": 5, "tol": 1e-8, "polish": False},
    "PSO": {"n_particles": 10, "iterations": 10},
}
WARM_PER_TYPE = {"scipy_de", "pylinkage_pso"}
ERRORS = ("time_ratio", "stroke", "transmission_deg")


def errors(case: dict[str, Any], params: dict[str, float]) -> dict[str, float]:
    """The candidate's errors against its target, by an independent forward analysis."""
    t = case["target"]
    try:
        a = analyze(case["type"], params)
    except SynthError:
        return dict.fromkeys(ERRORS, math.inf)
    return {
        "time_ratio": abs(a.time_ratio - t["time_ratio"]) / t["time_ratio"],
        "stroke": abs(a.stroke - t["stroke"]) / t["stroke"],
        "transmission_deg": max(0.0, t["min_transmission_angle_deg"] - a.transmission.min_deg),
    }


def run_one(case: dict[str, Any], name: str) -> dict[str, Any]:
    t0 = time.perf_counter()
    candidates, note = methods.METHODS[name](case["target"])
    seconds = time.perf_counter() - t0
    errs = [errors(case, p) for p in candidates]
    worst = [max(e.values()) for e in errs]
    return {
        "case": case["id"], "type": case["type"], "feasible": case["feasible"], "method": name,
        "ms": seconds * 1e3, "n": len(candidates), "valid": sum(w <= TOL for w in worst),
        "best": min(worst, default=None), "worst": max(worst, default=None),
        "errors": {k: [e[k] for e in errs] for k in ERRORS}, "note": note,
    }  # fmt: skip


def interleaved(cases: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """The cases with the types taken in turn."""
    by_type = [[c for c in cases if c["type"] == t] for t in all_types()]
    return [c for group in itertools.zip_longest(*by_type) for c in group if c is not None]


def warm_up(cases: list[dict[str, Any]], names: list[str]) -> None:
    seen: dict[tuple, dict] = {}
    for c in cases:
        fixed = tuple(sorted(c["target"]["mechanisms"][0]["fixed"]))
        seen.setdefault((c["type"], c["feasible"], fixed), c)
    per_type = {c["type"]: c for c in reversed(cases)}
    for name in names:
        for c in (per_type if name in WARM_PER_TYPE else seen).values():
            methods.METHODS[name](c["target"])


def run(cases: list[dict[str, Any]], names: list[str]) -> list[dict[str, Any]]:
    warm_up(cases, names)
    records = []
    t0 = time.monotonic()
    for i, case in enumerate(interleaved(cases)):
        k = i % len(names)
        records += [run_one(case, name) for name in names[k:] + names[:k]]
        if (i + 1) % 50 == 0:
            print(f"{i + 1}/{len(cases)} cases, {time.monotonic() - t0:.0f} s", file=sys.stderr)
    return records


def _quantile(xs: list[float], q: float) -> float | None:
    return float(np.quantile(xs, q, method="inverted_cdf")) if xs else None  # inf-safe


def summary(records: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """Per method and type: times, success and refusal rates, errors after verification."""
    out = []
    order = list(methods.METHODS)
    for (name, mtype), group in itertools.groupby(
        sorted(records, key=lambda r: (order.index(r["method"]), all_types().index(r["type"]))),
        key=lambda r: (r["method"], r["type"]),
    ):
        rs = list(group)
        feas = [r for r in rs if r["feasible"]]
        infeas = [r for r in rs if not r["feasible"]]
        ms = [r["ms"] for r in feas]
        worst = [r["worst"] for r in feas if r["worst"] is not None]
        every = [max(es) for r in feas for es in zip(*r["errors"].values(), strict=True)]
        out.append({
            "method": name, "type": mtype,
            "feasible": len(feas), "success": sum(r["valid"] > 0 for r in feas) / len(feas),
            "infeasible": len(infeas),
            "refused": sum(r["valid"] == 0 for r in infeas) / len(infeas) if infeas else None,
            "ms_median": _quantile(ms, 0.5), "ms_p90": _quantile(ms, 0.9),
            "ms_median_infeasible": _quantile([r["ms"] for r in infeas], 0.5),
            "candidates": len(every), "error_median": _quantile(every, 0.5),
            "error_max": max(every, default=None),
            "worst_error_median": _quantile(worst, 0.5), "worst_error_p90": _quantile(worst, 0.9),
            "component_max": {
                k: max((e for r in feas for e in r["errors"][k]), default=None) for k in ERRORS
            },
        })  # fmt: skip
    return out


def _num(x: float | None, fmt: str) -> str:
    return "–" if x is None else format(x, fmt)


def markdown(rows: list[dict[str, Any]]) -> str:
    lines = [
        "| method | type | feasible solved | infeasible refused | median ms | p90 ms | "
        "median ms (infeasible) | median error | max error |",
        "|---|---|" + "---:|" * 7,
    ]
    for r in rows:
        refused = "–" if r["refused"] is None else f"{r['refused']:.0%} of {r['infeasible']}"
        lines.append(
            f"| {r['method']} | {r['type']} | {r['success']:.0%} of {r['feasible']} | {refused} | "
            f"{_num(r['ms_median'], '.1f')} | {_num(r['ms_p90'], '.1f')} | "
            f"{_num(r['ms_median_infeasible'], '.1f')} | {_num(r['error_median'], '.1e')} | "
            f"{_num(r['error_max'], '.1e')} |"
        )
    return "\n".join(lines)


def ratios(rows: list[dict[str, Any]]) -> str:
    """Median time on the feasible targets relative to ours, per type."""
    ms = {(r["method"], r["type"]): r["ms_median"] for r in rows}
    names = list(dict.fromkeys(r["method"] for r in rows))
    types = [t for t in all_types() if ("ours", t) in ms]
    lines = ["| method | " + " | ".join(types) + " |", "|---|" + "---:|" * len(types)]
    for name in names:
        cells = [ms[name, t] / ms["ours", t] if ms["ours", t] else math.nan for t in types]
        lines.append(f"| {name} | " + " | ".join(f"{c:.2g}×" for c in cells) + " |")
    return "\n".join(lines)


def figure(rows: list[dict[str, Any]]):
    """The run-time-against-error plot, one point per method and type (the summary rows, also
    as read back from synthesis.json, where an infinite error is the string "inf")."""
    import matplotlib.pyplot as plt

    names = list(dict.fromkeys(r["method"] for r in rows))
    markers = dict(zip(names, itertools.cycle("o^svD<>pP*Xh"), strict=False))
    colours = dict(zip(all_types(), plt.get_cmap("tab10").colors, strict=False))
    fig, ax = plt.subplots(figsize=(9, 6))
    for r in rows:
        if r["worst_error_median"] is None or not r["ms_median"]:
            continue
        y = min(max(float(r["worst_error_median"]), FLOOR), CAP)
        ax.scatter(r["ms_median"], y, marker=markers[r["method"]], color=colours[r["type"]])
    ax.axhline(TOL, color="grey", lw=0.8, ls="--")
    ax.set(xscale="log", yscale="log", xlabel="median wall time per target (ms)",
           ylabel=f"median worst error after verification (floor {FLOOR:g}, cap {CAP:g})",
           title="Synthesis: time vs verified error (feasible targets)")  # fmt: skip
    handles = [plt.Line2D([], [], ls="", marker=markers[n], color="k", label=n) for n in names]
    handles += [plt.Line2D([], [], ls="", marker="s", color=c, label=t) for t, c in colours.items()]
    ax.legend(handles=handles, fontsize=7, loc="center left", bbox_to_anchor=(1, 0.5))
    fig.tight_layout()
    return fig


def plot(rows: list[dict[str, Any]], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig = figure(rows)
    fig.savefig(path, dpi=120)
    plt.close(fig)


def settings(names: list[str], sizes: dict[str, int]) -> dict[str, Any]:
    return {
        "methods": names, "targets": sizes, "seed": targets.SEED, "tol": TOL,
        "starts": synthesis.STARTS, "starts_leftover": synthesis.STARTS_LEFTOVER,
        "de": methods.DE, "pso": methods.PSO, "pso_penalty": methods.PENALTY, "sqp": methods.SQP,
    }  # fmt: skip


def main(argv: list[str] | None = None) -> dict[str, Any]:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="a few targets, fewer methods")
    ap.add_argument("--out", type=Path, help="where to write the results")
    ap.add_argument("--methods", help="comma-separated subset of " + ", ".join(methods.METHODS))
    a = ap.parse_args(argv)
    sizes = (
        QUICK
        if a.quick
        else {"n_feasible": targets.N_FEASIBLE, "n_infeasible": targets.N_INFEASIBLE}
    )
    names = (
        a.methods.split(",") if a.methods else list(methods.QUICK if a.quick else methods.METHODS)
    )
    out = a.out if a.out or a.quick else targets.RESULTS
    cases = targets.cases(**sizes)
    targets.check(cases)
    info = machine()
    with warnings.catch_warnings(), methods.patched(methods, **(QUICK_BUDGETS if a.quick else {})):
        warnings.simplefilter("ignore")  # scipy's and pylinkage's numerical chatter
        config = settings(names, sizes)
        records = run(cases, names)
    rows = summary(records)
    result = {"machine": info, "settings": config, "summary": rows,
              "sqpmethod_stats_raised": methods._Guarded.raised}  # fmt: skip
    text = markdown(rows)
    if "ours" in names:
        text += "\n\nMedian time on feasible targets relative to ours:\n\n" + ratios(rows)
    print(text)
    if out:
        write(out, result, records, cases, text)
    return {**result, "records": records}


def write(out: Path, result: dict, records: list[dict], cases: list[dict], text: str) -> None:
    """synthesis.json (machine, settings, summary), synthesis_records.jsonl.gz (a line per
    case and method, errors to 3 digits), synthesis.md (the tables), the plot and the targets."""
    out.mkdir(parents=True, exist_ok=True)
    (out / "synthesis.json").write_text(json.dumps(_finite(result), indent=1) + "\n")
    lines = (json.dumps(_finite(_rounded(r)), ensure_ascii=False) for r in records)
    with gzip.GzipFile(out / "synthesis_records.jsonl.gz", "wb", mtime=0) as f:
        f.write(("\n".join(lines) + "\n").encode())
    (out / "synthesis.md").write_text(text + "\n")
    plot(result["summary"], out / "synthesis_time_vs_error.png")
    targets.write(out / "targets.json.gz", cases)


def _rounded(x: Any) -> Any:
    if isinstance(x, dict):
        return {k: round(v, 3) if k == "ms" else _rounded(v) for k, v in x.items()}
    if isinstance(x, list):
        return [_rounded(v) for v in x]
    return float(f"{x:.3g}") if isinstance(x, float) else x


def _finite(x: Any) -> Any:
    """JSON has no inf: a design that does not run has error "inf"."""
    if isinstance(x, dict):
        return {k: _finite(v) for k, v in x.items()}
    if isinstance(x, list | tuple):
        return [_finite(v) for v in x]
    return "inf" if isinstance(x, float) and math.isinf(x) else x


if __name__ == "__main__":
    main(sys.argv[1:])
