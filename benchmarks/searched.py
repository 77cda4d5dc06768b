"""The searched objectives (issue 39): what a request costs, whether it completes and is
certified, and how far its answer is from an independent global search.

    python -m benchmarks.searched [--quick] [--budget-ms MS | --unbounded] [--busy]
                                  [--referee none|sample|all] [--types TYPE ...]

In process, warm. Per type of ``TYPES`` and searched objective of ``VARIANTS`` (the two motion
objectives, each also under the fluctuation limit ``LIMIT``; the least peak torque under
``LOADS``, massless links and links of 8 kg/m), over ``targets``: per type the 12 free targets
(time ratios 1.3–2.5 × bounds 0, 20, 40°) and 8 (40%) of ``benchmarks.targets``' feasible
targets with parts fixed (a seeded choice; their own ratios and bounds), every one at stroke
300 (mm for the loads; fixed parts scaled with it: the motion measures do not depend on
scale, the torque does).

- Each structure (type, fixed parts, variant) is asked once, untimed (same budget), first;
  then the targets in turn, the types interleaved and the variants in an order rotated per
  target. Each request is timed once, at the budget ``--budget-ms`` (default: the service's
  default, 2 000 ms; ``--unbounded``: ``UNBOUNDED_MS``), and right after it one summary
  analysis of its answer (``synth.analyze`` of the best candidate's design; median of
  ``ANALYSES`` calls), so that each time is also a multiple of an analysis in the same run.
- Per type and variant: median and p99 ms and multiples, the share of answers ``complete``,
  the share answered (a candidate), the share certified (the best candidate's
  ``certified``), the share certified or saying why not (``said``: its ``uncertified``; the
  reasons are listed below the table, counted per type), and for the limited variants the
  share where the limit binds (how many: the answer worse than the same target's without it,
  or gone).
- ``--busy``: the same while two processes spin, keeping both cores busy; ``complete`` then
  says how many requests completed within their budget.
- ``referee``: run time against error on a sample (``REFEREED``; ``all``: every type and
  objective; ``none``: skipped). At stroke 1 (the referee's scale; its loads in metres), ours
  at the budget and unbounded, and the independent global search of
  ``tests/support/motion_referee.py`` (differential evolution from several seeds per family,
  polished by Nelder–Mead), each timed; the reference is the referee's best, the error
  ours' relative excess over it (negative: the referee stopped short of ours).

Prints markdown tables; writes ``results/searched.json`` (not with ``--quick``), a record per
mode (quiet or busy, the budget; the other modes' kept), with each request as a row.
"""

from __future__ import annotations

import argparse
import collections
import itertools
import json
import os
import re
import statistics
import sys
import time
from dataclasses import replace
from typing import Any

import numpy as np

import synth
from synth.synthesis.motion import ACROSS_DEG

from . import targets as bench_targets
from .analysis import DESIGNS
from .common import RESULTS, TYPES, machine, spinning, table

RATIOS, BOUNDS = (1.3, 1.6, 2.0, 2.5), (0.0, 20.0, 40.0)
STROKE = 300.0
SEED = 39  # the subset's
FULL = (12, 8)  # targets per type: free (all of RATIOS × BOUNDS), with parts fixed (40%)
QUICK = (1, 0)
DEFAULT_BUDGET_MS = 2000.0  # the service's default time_budget_ms
UNBOUNDED_MS = 60_000.0
ANALYSES = 5  # summary analyses per request, their median its unit
# the fluctuation limit: it binds sometimes (min_peak_acceleration's optimum breaks it on some
# targets, and a few have no design that meets it), most targets keep their answers
LIMIT = 1.3
UNIFORM, PEAK, TORQUE = "uniform_cutting_speed", "min_peak_acceleration", "min_peak_torque"
LOADS = {
    "massless": synth.Load("mm", 40.0, cutting_force=2000.0, slider_mass=20.0),
    "8 kg/m": synth.Load(
        "mm", 40.0, cutting_force=2000.0, slider_mass=20.0, link_mass_per_length=8.0
    ),
}
VARIANTS: dict[str, dict[str, Any]] = {
    "uniform": {"objective": UNIFORM},
    "uniform, limit": {"objective": UNIFORM, "max_working_speed_fluctuation": LIMIT},
    "peak": {"objective": PEAK},
    "peak, limit": {"objective": PEAK, "max_working_speed_fluctuation": LIMIT},
    "torque, massless": {"objective": TORQUE, "load": LOADS["massless"]},
    "torque, 8 kg/m": {"objective": TORQUE, "load": LOADS["8 kg/m"]},
}
LIMITED = {"uniform, limit": "uniform", "peak, limit": "peak"}
# the referee's sample: time ratio 1.6, bound 20°, everything free (the issue's) for the
# motion objectives of every type; the torque where the referee takes seconds, not minutes
REFEREE_TARGET = (1.6, 20.0)
REFEREED = [(t, v) for t in TYPES for v in ("uniform", "peak")] + [
    (t, v)
    for t in ("offset_slider_crank", "whitworth")
    for v in ("torque, massless", "torque, 8 kg/m")
]
SAMPLES = {
    "none": [],
    "quick": REFEREED[:1],
    "sample": REFEREED,
    "all": [(t, v) for t in TYPES for v in VARIANTS if v not in LIMITED],
}
# the referee's loads at stroke 1: lengths in metres, the benchmark's forces and masses
REFEREE_LOADS = {
    "torque, massless": replace(LOADS["massless"], length_unit="m"),
    "torque, 8 kg/m": replace(LOADS["8 kg/m"], length_unit="m"),
}
# the crank-rocker's many local optima need more effort (tests/referees/test_motion_search.py)
EFFORT = {"crank_rocker_slider": {"seeds": (0, 1, 2), "popsize": 20, "maxiter": 120}}


def targets(quick: bool) -> list[dict[str, Any]]:
    """Per type, the seeded subset: ``FULL`` (or ``QUICK``) free and fixed-part targets, each
    as ``synthesize``'s arguments at stroke ``STROKE``, with an id and its type."""
    n_free, n_fixed = QUICK if quick else FULL
    cases = [
        c for c in bench_targets.cases(n_infeasible=0) if c["target"]["mechanisms"][0]["fixed"]
    ]
    out = []
    for k, mtype in enumerate(TYPES):
        rng = np.random.default_rng([SEED, k])
        grid = [(1.6, 20.0)] if quick else list(itertools.product(RATIOS, BOUNDS))
        for j in sorted(rng.choice(len(grid), size=n_free, replace=False)):
            tr, b = grid[j]
            out.append(target(f"{mtype}/tr{tr:g}-{b:g}deg", mtype, tr, b, {}))
        mine = [c for c in cases if c["type"] == mtype]
        for j in sorted(rng.choice(len(mine), size=n_fixed, replace=False)):
            t = mine[j]["target"]
            scale = STROKE / t["stroke"]
            fixed = {p: v * scale for p, v in t["mechanisms"][0]["fixed"].items()}
            tr, b = t["time_ratio"], t["min_transmission_angle_deg"]
            out.append(target(mine[j]["id"], mtype, tr, b, fixed))
    return out


def target(tid: str, mtype: str, tr: float, bound: float, fixed: dict) -> dict[str, Any]:
    spec = {"type": mtype, "fixed": fixed} if fixed else {"type": mtype}
    return {
        "id": tid,
        "type": mtype,
        "time_ratio": tr,
        "stroke": STROKE,
        "min_transmission_angle_deg": bound,
        "mechanisms": [spec],
    }


def request(target: dict[str, Any], variant: str, budget_ms: float) -> dict[str, Any]:
    """``synthesize``'s arguments for a target and variant."""
    args = {k: v for k, v in target.items() if k not in ("id", "type")}
    return {**args, **VARIANTS[variant], "time_budget_ms": budget_ms}


def structure(target: dict[str, Any], variant: str) -> tuple:
    return (target["type"], tuple(sorted(target["mechanisms"][0].get("fixed", {}))), variant)


def best(r: synth.SynthesisResult) -> float | None:
    return r.candidates[0].objective_value if r.candidates else None


def certified(r: synth.SynthesisResult) -> tuple[bool, float | None, str | None]:
    """Whether the best candidate is a certified optimum, its gap (None: not bounded), and
    where it is not, why (``uncertified``)."""
    if not r.candidates:
        return False, None, None
    c = r.candidates[0]
    return c.certified, c.gap, c.uncertified


def analysis_ms(r: synth.SynthesisResult, mtype: str) -> float:
    """A summary analysis of the answer (of a reference design where there is none): the
    median of ``ANALYSES`` calls, ms."""
    params = r.candidates[0].params if r.candidates else DESIGNS[mtype]
    out = []
    for _ in range(ANALYSES):
        t0 = time.perf_counter()
        synth.analyze(mtype, params)
        out.append((time.perf_counter() - t0) * 1e3)
    return statistics.median(out)


def one(target: dict[str, Any], variant: str, budget_ms: float) -> dict[str, Any]:
    """One request, timed, with the analysis of its answer timed right after it."""
    t0, c0 = time.perf_counter(), time.process_time()
    r = synth.synthesize(**request(target, variant, budget_ms))
    ms, cpu = (time.perf_counter() - t0) * 1e3, (time.process_time() - c0) * 1e3
    unit = analysis_ms(r, target["type"])
    cert, gap, why = certified(r)
    return {
        "id": target["id"],
        "type": target["type"],
        "variant": variant,
        "fixed": bool(target["mechanisms"][0].get("fixed")),
        "ms": ms,
        "cpu_ms": cpu,
        "analysis_ms": unit,
        "analyses": ms / unit,
        "complete": r.complete,
        "candidates": len(r.candidates),
        "best": best(r),
        "certified": cert,
        "gap": gap,
        "uncertified": why,
        "within_budget": r.complete and ms <= budget_ms,
        "refusals": " ".join(sorted({i.code for i in r.infeasible})),
    }


def interleaved(items: list[dict[str, Any]]) -> list[dict[str, Any]]:
    by_type = [[c for c in items if c["type"] == t] for t in TYPES]
    return [c for group in itertools.zip_longest(*by_type) for c in group if c is not None]


def run(items: list[dict[str, Any]], budget_ms: float) -> list[dict[str, Any]]:
    """Every target and variant: each structure once untimed, then each request timed."""
    names = list(VARIANTS)
    seen: dict[tuple, tuple[dict[str, Any], str]] = {}
    for t in items:
        for v in names:
            seen.setdefault(structure(t, v), (t, v))
    t0 = time.monotonic()
    for t, v in seen.values():
        synth.synthesize(**request(t, v, budget_ms))
    print(f"warm: {len(seen)} structures, {time.monotonic() - t0:.0f} s", file=sys.stderr)
    records = []
    for i, t in enumerate(interleaved(items)):
        k = i % len(names)
        records += [one(t, v, budget_ms) for v in names[k:] + names[:k]]
        if (i + 1) % 10 == 0:
            print(f"{i + 1}/{len(items)} targets, {time.monotonic() - t0:.0f} s", file=sys.stderr)
    return records


def quantile(xs: list[float], q: float) -> float | None:
    return float(np.quantile(xs, q, method="inverted_cdf")) if xs else None


def binds(records: list[dict[str, Any]], r: dict[str, Any]) -> bool | None:
    """Whether a limited request's limit binds: its answer worse (by 1e-9) than the same
    target's without the limit, or gone where that one has one. None: neither answered."""
    free = next(x for x in records if x["id"] == r["id"] and x["variant"] == LIMITED[r["variant"]])
    if free["best"] is None:
        return None
    return r["best"] is None or r["best"] > free["best"] * (1 + 1e-9)


def summary(records: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """Per type and variant: times and multiples of an analysis, and the outcomes."""
    rows = []
    for mtype, variant in itertools.product(TYPES, VARIANTS):
        rs = [r for r in records if r["type"] == mtype and r["variant"] == variant]
        if not rs:
            continue
        ms, x = [r["ms"] for r in rs], [r["analyses"] for r in rs]
        answered = [r for r in rs if r["candidates"]]
        row = {
            "type": mtype,
            "variant": variant,
            "n": len(rs),
            "median_ms": quantile(ms, 0.5),
            "p99_ms": quantile(ms, 0.99),
            "max_ms": max(ms),
            "median_cpu_ms": quantile([r["cpu_ms"] for r in rs], 0.5),
            "median_x": quantile(x, 0.5),
            "p99_x": quantile(x, 0.99),
            "analysis_ms": statistics.median(r["analysis_ms"] for r in rs),
            "complete": sum(r["complete"] for r in rs) / len(rs),
            "within_budget": sum(r["within_budget"] for r in rs),
            "answered": len(answered) / len(rs),
            "certified": sum(r["certified"] for r in answered) / len(answered)
            if answered
            else None,
            # the answers certified or saying why not
            "said": sum(r["certified"] or bool(r["uncertified"]) for r in answered) / len(answered)
            if answered
            else None,
        }
        if variant in LIMITED:
            b = [binds(records, r) for r in rs]
            row["binds"] = sum(x is True for x in b)
        rows.append(row)
    return rows


def referee_sample(pairs: list[tuple[str, str]], budget_ms: float) -> list[dict[str, Any]]:
    """Ours (at the budget and unbounded) and the referee on the sample (type, variant) pairs,
    at stroke 1: times, values and ours' relative excess over the referee's best."""
    if not pairs:
        return []
    try:  # the repository's referee, as the tests run it (in a checkout, from its root)
        from tests.support import motion_referee
    except ImportError:
        print("no referee: run from the repository's root", file=sys.stderr)
        return []

    tr, bound = REFEREE_TARGET
    rows = []
    for mtype, variant in sorted(pairs, key=lambda p: (TYPES.index(p[0]), p[1])):
        load = REFEREE_LOADS.get(variant)
        objective = VARIANTS[variant]["objective"]
        row: dict[str, Any] = {"type": mtype, "variant": variant, "time_ratio": tr, "bound": bound}
        for name, budget in (("ours", budget_ms), ("unbounded", UNBOUNDED_MS)):
            t0 = time.perf_counter()
            r = synth.synthesize(
                tr, 1.0, bound, [mtype], objective=objective, load=load, time_budget_ms=budget
            )
            row[f"{name}_ms"] = (time.perf_counter() - t0) * 1e3
            row[name], row[f"{name}_complete"] = best(r), r.complete
        t0 = time.perf_counter()
        ref = motion_referee.search(
            mtype, objective, tr, max(bound, ACROSS_DEG), load=load, **EFFORT.get(mtype, {})
        )
        row["referee_ms"] = (time.perf_counter() - t0) * 1e3
        row["referee"] = ref.value if ref.params is not None else None
        for name in ("ours", "unbounded"):
            v, r0 = row[name], row["referee"]
            row[f"{name}_excess"] = None if v is None or r0 is None else (v - r0) / r0
        rows.append(row)
        print(f"referee {mtype} {variant}: {row['referee_ms'] / 1e3:.0f} s", file=sys.stderr)
    return rows


def mode(budget_ms: float, is_busy: bool) -> str:
    return f"{'busy' if is_busy else 'quiet'}, budget {budget_ms:g} ms"


KEPT = "id variant ms cpu_ms analysis_ms complete candidates best certified gap refusals"


def write(key: str, result: dict[str, Any]) -> None:
    """results/searched.json: this mode's record beside the other modes' already there; its
    requests as columns (``KEPT``: the rest follow from them) and rows, times to 4 digits."""
    path = RESULTS / "searched.json"
    old = json.loads(path.read_text()) if path.exists() else {}
    rows = [[_short(k, r[k]) for k in KEPT.split()] for r in result["requests"]]
    rounded = {
        k: [{c: _short(c, v) for c, v in r.items()} for r in result[k]]
        for k in ("summary", "referee")
    }
    record = {**result, **rounded, "requests": {"columns": KEPT.split(), "rows": rows}}
    RESULTS.mkdir(exist_ok=True)
    path.write_text(dumps({"runs": {**old.get("runs", {}), key: record}}))


def dumps(x: Any) -> str:
    """JSON, indented, but each list or mapping of plain values on one line."""
    text = json.dumps(x, indent=1, ensure_ascii=False)
    flat = r"([\[{])\s*([^\[\]{}]*?)\s*([\]}])"
    return re.sub(flat, lambda m: m[1] + " ".join(m[2].split()) + m[3], text) + "\n"


def _short(key: str, v: Any) -> Any:
    """A time (ms, or as a multiple: _x) to 4 digits."""
    return float(f"{v:.4g}") if key.endswith(("ms", "_x")) and isinstance(v, float) else v


SUMMARY = "type variant n median_ms p99_ms median_cpu_ms median_x p99_x complete within_budget"
SUMMARY += " answered certified said binds"
REFEREE = "type variant ours_ms ours_excess unbounded_ms unbounded_excess referee_ms referee"


def text(result: dict[str, Any]) -> str:
    out = table(result["summary"], tuple(SUMMARY.split()))
    reasons = collections.Counter(
        (r["type"], r["uncertified"]) for r in result["requests"] if r["uncertified"]
    )
    out += "".join(f"\n{t}, {n}×: {why}" for (t, why), n in sorted(reasons.items()))
    return out + (
        "\n" + table(result["referee"], tuple(REFEREE.split())) if result["referee"] else ""
    )


def main(argv: list[str] | None = None) -> dict[str, Any]:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="one target per type, a small sample")
    ap.add_argument(
        "--budget-ms",
        type=float,
        default=DEFAULT_BUDGET_MS,
        help="each request's time_budget_ms (default: the service's, 2000)",
    )
    ap.add_argument("--unbounded", action="store_true", help=f"a budget of {UNBOUNDED_MS:g} ms")
    ap.add_argument("--busy", action="store_true", help="two processes spin meanwhile")
    ap.add_argument(
        "--types", nargs="+", choices=TYPES, help="these types only (printed, not recorded)"
    )
    ap.add_argument(
        "--referee",
        choices=("none", "sample", "all"),
        default=None,
        help="run time against error (default: sample; --quick: one pair)",
    )
    a = ap.parse_args(argv)
    budget = UNBOUNDED_MS if a.unbounded else a.budget_ms
    items = [x for x in targets(a.quick) if a.types is None or x["type"] in a.types]
    info = machine()
    with spinning(2 if a.busy else 0):
        records = run(items, budget)
    which = a.referee or ("quick" if a.quick else "sample")
    pairs = [p for p in SAMPLES[which] if a.types is None or p[0] in a.types]
    referee = referee_sample(pairs, budget)
    info["load_average_at_end"] = os.getloadavg()
    result = {
        "machine": info,
        "quick": a.quick,
        "settings": {
            "budget_ms": budget,
            "busy": a.busy,
            "seed": SEED,
            "targets_per_type": dict(
                zip(("free", "fixed"), QUICK if a.quick else FULL, strict=True)
            ),
            "limit": LIMIT,
            "stroke": STROKE,
            "analyses": ANALYSES,
            "loads": {k: vars(v) for k, v in LOADS.items()},
            "referee": {"target": REFEREE_TARGET, "effort": EFFORT},
        },
        "summary": summary(records),
        "referee": referee,
        "requests": records,
    }
    print(f"{mode(budget, a.busy)}\n\n{text(result)}")
    if not (a.quick or a.types):
        write(mode(budget, a.busy), result)
    return result


if __name__ == "__main__":
    main()
