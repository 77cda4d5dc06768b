"""Synthesis benchmark: every method on the same targets, verified the same way.

    python -m benchmarks.synthesis            # all targets and methods, ~9 min on 2 cores
    python -m benchmarks.synthesis --quick    # a smoke run: a few targets, small searches

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
The best verified candidate's minimum transmission angle (every target asks for the largest)
is compared between ours and the generic multistart, target by target (``optimality``).
Ours is run once more per target, untimed, to count its fallbacks to IPOPT.

Prints the summary as markdown tables and writes (``write``) the results to ``--out``
(default ``benchmarks/results``; ``--quick`` writes only where ``--out`` is given).
"""

from __future__ import annotations

import os

os.environ.setdefault("OMP_NUM_THREADS", "1")  # as the Makefile: one thread per process
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse
import collections
import gzip
import itertools
import json
import math
import statistics
import sys
import time
import warnings
from pathlib import Path
from typing import Any

import numpy as np

from synth import SynthError, analyze
from synth.mechanisms import all_types
from synth.synthesis import search

from . import methods, targets
from .common import machine

TOL = 1e-9  # relative on time ratio and stroke, degrees on the transmission bound
SAME_ANGLE = 1e-9  # ours' best angle may be below generic's by this (× max(1, angle)), no more
FLOOR = 1e-17  # errors plotted no lower (exact zeros)
CAP = 1e3  # nor higher (a design that does not run counts as inf)
QUICK = {"n_feasible": 5, "n_infeasible": 2}
QUICK_BUDGETS = {  # the global searches cut to a smoke test's size
    "DE": {"maxiter": 20, "popsize": 5, "tol": 1e-8, "polish": False},
    "PSO": {"n_particles": 10, "iterations": 10},
}
WARM_PER_TYPE = {"scipy_de", "pylinkage_pso"}
# the global searches (about 2 s a target for evolution) run on every fourth target of each
# type and kind: 25 feasible and 6 infeasible per type, compared with ours on the same ones
SPARSE = {"scipy_de", "pylinkage_pso"}
EVERY = 4
ERRORS = ("time_ratio", "stroke", "transmission_deg")
GOALS = {  # the targets this benchmark measures ours against (medians unless said)
    "fixed_median_ms": 5.0,  # feasible targets with fixed parts
    "fixed_p99_ms": 50.0,
    "error_max": 1e-12,
    "scipy_slsqp": 30.0,  # a peer's median time at least this many times ours
    "scipy_de": 300.0,
}


def errors(case: dict[str, Any], params: dict[str, float]) -> dict[str, float]:
    """The candidate's errors against its target, by an independent forward analysis, and its
    minimum transmission angle (``angle``; None for a design that does not run)."""
    t = case["target"]
    try:
        a = analyze(case["type"], params)
    except SynthError:
        return {**dict.fromkeys(ERRORS, math.inf), "angle": None}
    return {
        "time_ratio": abs(a.time_ratio - t["time_ratio"]) / t["time_ratio"],
        "stroke": abs(a.stroke - t["stroke"]) / t["stroke"],
        "transmission_deg": max(0.0, t["min_transmission_angle_deg"] - a.transmission.min_deg),
        "angle": a.transmission.min_deg if a.reversals == 2 else None,
    }


def run_one(case: dict[str, Any], name: str) -> dict[str, Any]:
    t0 = time.perf_counter()
    out = methods.METHODS[name](case["target"])
    seconds = time.perf_counter() - t0
    errs = [errors(case, p) for p in out.candidates]
    worst = [max(e[k] for k in ERRORS) for e in errs]
    good = [e["angle"] for e, w in zip(errs, worst, strict=True) if w <= TOL]
    return {
        "case": case["id"], "type": case["type"], "feasible": case["feasible"],
        "fixed": bool(case["target"]["mechanisms"][0]["fixed"]), "kind": case["kind"],
        "method": name, "ms": seconds * 1e3, "n": len(out.candidates),
        "valid": sum(w <= TOL for w in worst),
        "best": min(worst, default=None), "worst": max(worst, default=None),
        "best_angle": max((a for a in good if a is not None), default=None),
        "errors": {k: [e[k] for e in errs] for k in ERRORS},
        "how": list(out.how), "refusals": list(out.refusals),
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


def run(cases: list[dict[str, Any]], names: list[str], every: int = EVERY) -> list[dict[str, Any]]:
    """Every method on every case, but the SPARSE ones on every ``every``-th case only."""
    warm_up(cases, names)
    records = []
    t0 = time.monotonic()
    for i, case in enumerate(interleaved(cases)):
        k = i % len(names)
        here = [
            run_one(case, name)
            for name in names[k:] + names[:k]
            if name not in SPARSE or int(case["id"][-3:]) % every == 0
        ]
        for r in here:
            if r["method"] == "ours":  # untimed: how often it fell back to IPOPT
                n = methods.ipopt_solves(case["target"])
                r.update(ipopt_calls=n.calls, ipopt_starts=n.starts, ipopt_where=n.where)
        records += here
        if (i + 1) % 50 == 0:
            print(f"{i + 1}/{len(cases)} cases, {time.monotonic() - t0:.0f} s", file=sys.stderr)
    return records


def _quantile(xs: list[float], q: float) -> float | None:
    return float(np.quantile(xs, q, method="inverted_cdf")) if xs else None  # inf-safe


def _times(rs: list[dict[str, Any]], prefix: str) -> dict[str, Any]:
    ms = [r["ms"] for r in rs]
    return {f"n_{prefix}": len(rs), f"ms_median_{prefix}": _quantile(ms, 0.5),
            f"ms_p99_{prefix}": _quantile(ms, 0.99)}  # fmt: skip


def summary(records: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """Per method and type: times (all feasible targets; those with every part free, those
    with fixed parts, the infeasible ones), success and refusal rates, errors after
    verification, and for ours the share of targets on which IPOPT ran."""
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
        row = {
            "method": name, "type": mtype,
            "feasible": len(feas), "success": sum(r["valid"] > 0 for r in feas) / len(feas),
            "infeasible": len(infeas),
            "refused": sum(r["valid"] == 0 for r in infeas) / len(infeas) if infeas else None,
            "ms_median": _quantile(ms, 0.5), "ms_p90": _quantile(ms, 0.9),
            "ms_p99": _quantile(ms, 0.99),
            **_times([r for r in feas if not r["fixed"]], "free"),
            **_times([r for r in feas if r["fixed"]], "fixed"),
            **_times(infeas, "infeasible"),
            "candidates": len(every), "error_median": _quantile(every, 0.5),
            "error_max": max(every, default=None),
            "worst_error_median": _quantile(worst, 0.5), "worst_error_p90": _quantile(worst, 0.9),
            "component_max": {
                k: max((e for r in feas for e in r["errors"][k]), default=None) for k in ERRORS
            },
            "how": dict(collections.Counter(h for r in rs for h in r["how"])),
        }  # fmt: skip
        if "ipopt_calls" in rs[0]:
            row["ipopt_share"] = {
                "feasible": sum(r["ipopt_calls"] > 0 for r in feas) / max(1, len(feas)),
                "infeasible": sum(r["ipopt_calls"] > 0 for r in infeas) / max(1, len(infeas)),
            }
        out.append(row)
    return out


def optimality(records: list[dict[str, Any]]) -> dict[str, Any]:
    """Target by target, ours' best verified minimum transmission angle against the generic
    multistart's. A violation: generic has a verified design and ours none, or a better one by
    more than SAME_ANGLE × max(1, its angle) degrees."""
    by = {(r["case"], r["method"]): r for r in records}
    cases = sorted({c for c, m in by if m == "ours" and (c, "generic") in by})
    violations, better, equal, neither, generic_none = [], [], 0, 0, 0
    for c in cases:
        o, g = by[c, "ours"]["best_angle"], by[c, "generic"]["best_angle"]
        if g is None:
            neither += o is None
            if o is not None:
                generic_none += 1
            continue
        gap = g - (o if o is not None else -math.inf)
        if gap > SAME_ANGLE * max(1.0, abs(g)):
            violations.append({"case": c, "ours_deg": o, "generic_deg": g,
                               "feasible": by[c, "ours"]["feasible"]})  # fmt: skip
        elif o - g > 1e-6:
            better.append({"case": c, "ours_deg": o, "generic_deg": g})
        else:
            equal += 1
    return {
        "compared": len(cases), "violations": violations, "equal": equal,
        "ours_better_by_1e-6_deg": better, "only_ours_solved": generic_none,
        "neither_solved": neither,
    }  # fmt: skip


def ratios(records: list[dict[str, Any]]) -> dict[str, Any]:
    """Per method and type, its time relative to ours on the targets both ran: the ratio of
    the medians on the feasible targets (``feasible``) and on the infeasible ones
    (``infeasible``), and the median of the per-target ratios on the feasible ones
    (``paired``)."""
    ms = {(r["case"], r["method"]): r["ms"] for r in records}
    out: dict[str, Any] = {}
    for name in dict.fromkeys(r["method"] for r in records):
        for mtype in all_types():
            both = [
                c for c, m in ms if m == name and c.startswith(mtype + "/") and (c, "ours") in ms
            ]
            if not both:
                continue
            cell = {}
            for kind, mark in (("feasible", "/f"), ("infeasible", "/i")):
                cs = [c for c in both if mark in c]
                if cs:
                    ours = statistics.median(ms[c, "ours"] for c in cs)
                    cell[kind] = statistics.median(ms[c, name] for c in cs) / ours if ours else None
            feas = [c for c in both if "/f" in c]
            ratio = [ms[c, name] / ms[c, "ours"] for c in feas if ms[c, "ours"]]
            cell["paired"] = statistics.median(ratio) if ratio else None
            cell["targets"] = len(both)
            out.setdefault(name, {})[mtype] = cell
    return out


def goals(rows: list[dict[str, Any]], table: dict[str, Any], opt: dict | None) -> list[dict]:
    """Each of GOALS per type, measured, and whether it is met."""
    out = []
    for r in rows:
        if r["method"] != "ours":
            continue
        t = r["type"]
        checks = [
            ("solved", r["success"], r["success"] == 1.0),
            ("refused", r["refused"], r["refused"] == 1.0),
            ("error_max", r["error_max"], r["error_max"] <= GOALS["error_max"]),
            ("fixed_median_ms", r["ms_median_fixed"],
             r["ms_median_fixed"] is not None and r["ms_median_fixed"] <= GOALS["fixed_median_ms"]),
            ("fixed_p99_ms", r["ms_p99_fixed"],
             r["ms_p99_fixed"] is not None and r["ms_p99_fixed"] <= GOALS["fixed_p99_ms"]),
        ]  # fmt: skip
        for peer in ("scipy_slsqp", "scipy_de"):
            x = table.get(peer, {}).get(t, {}).get("feasible")
            if x is not None:
                checks.append((f"{peer} / ours", x, x >= GOALS[peer]))
        if opt is not None:
            bad = [v for v in opt["violations"] if v["case"].startswith(t + "/")]
            checks.append(("optimality violations", len(bad), not bad))
        out += [{"type": t, "goal": g, "measured": m, "met": ok} for g, m, ok in checks]
    return out


def goals_table(rows: list[dict]) -> str:
    lines = ["| type | goal | measured | met |", "|---|---|---:|---|"]
    for g in rows:
        m = g["measured"]
        shown = _num(m, ".3g") if isinstance(m, float) else str(m)
        lines.append(f"| {g['type']} | {g['goal']} | {shown} | {'met' if g['met'] else 'MISSED'} |")
    return "\n".join(lines)


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


def ours_table(rows: list[dict[str, Any]]) -> str:
    """Ours per type: the targets' medians and p99s by kind, outcomes, IPOPT's share."""
    lines = [
        "| type | all free: median / p99 ms | fixed parts: median / p99 ms | "
        "infeasible: median / p99 ms | solved | refused | max error | "
        "IPOPT ran (feas. / infeas.) |",
        "|---|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for r in rows:
        if r["method"] != "ours":
            continue
        cells = [
            f"{_num(r[f'ms_median_{k}'], '.2f')} / {_num(r[f'ms_p99_{k}'], '.1f')}"
            for k in ("free", "fixed", "infeasible")
        ]
        share = r.get("ipopt_share", {})
        lines.append(
            f"| {r['type']} | " + " | ".join(cells) + f" | {r['success']:.0%} | "
            f"{_num(r['refused'], '.0%')} | {_num(r['error_max'], '.1e')} | "
            f"{share.get('feasible', 0):.0%} / {share.get('infeasible', 0):.0%} |"
        )
    return "\n".join(lines)


def ratio_table(table: dict[str, Any], key: str) -> str:
    """Median time relative to ours, per type (``key``: feasible, infeasible or paired)."""
    types = [t for t in all_types() if t in table.get("ours", {})]
    lines = ["| method | " + " | ".join(types) + " |", "|---|" + "---:|" * len(types)]
    for name, per_type in table.items():
        cells = [per_type.get(t, {}).get(key) for t in types]
        lines.append(f"| {name} | " + " | ".join(_num(c, ".3g") + "×" for c in cells) + " |")
    return "\n".join(lines)


def optimality_text(opt: dict[str, Any]) -> str:
    text = (
        f"Optimality against the generic multistart, {opt['compared']} targets: "
        f"{len(opt['violations'])} violations (generic's best verified angle above ours by more "
        f"than {SAME_ANGLE:g}° relative, or ours refused where generic solved); equal "
        f"{opt['equal']}, ours better by > 1e-6° {len(opt['ours_better_by_1e-6_deg'])}, only "
        f"ours solved {opt['only_ours_solved']}, neither {opt['neither_solved']}."
    )
    for v in opt["violations"]:
        text += f"\n- {v['case']}: ours {v['ours_deg']}, generic {v['generic_deg']}"
    return text


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
        "same_angle": SAME_ANGLE, "starts": search.STARTS,
        "de": methods.DE, "pso": methods.PSO, "pso_penalty": methods.PENALTY, "goals": GOALS,
    }  # fmt: skip


def main(argv: list[str] | None = None) -> dict[str, Any]:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="a few targets, small global searches")
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
        records = run(cases, names, 1 if a.quick else EVERY)
    rows = summary(records)
    result = {"machine": info, "settings": config, "summary": rows}
    text = markdown(rows)
    if "ours" in names:
        result["ratios"] = table = ratios(records)
        text += "\n\nOurs, by kind of target (p99 over 40–60 targets is about their maximum):\n\n"
        text += ours_table(rows)
        text += (
            f"\n\nMedian time on feasible targets relative to ours, on the same targets "
            f"({', '.join(sorted(SPARSE))}: every {EVERY}th target):\n\n"
        )
        text += ratio_table(table, "feasible")
        text += "\n\nMedian of the per-target time ratios to ours, feasible targets:\n\n"
        text += ratio_table(table, "paired")
        text += "\n\nMedian time on infeasible targets relative to ours:\n\n"
        text += ratio_table(table, "infeasible")
        if "generic" in names:
            result["optimality"] = opt = optimality(records)
            text += "\n\n" + optimality_text(opt)
        result["goals"] = met = goals(rows, table, result.get("optimality"))
        text += "\n\nThe goals (ours):\n\n" + goals_table(met)
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
        return {
            k: round(v, 3) if k == "ms" else v if k == "best_angle" else _rounded(v)
            for k, v in x.items()
        }
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
