"""The synthesis benchmark's runner: every method on every target, each candidate verified
by an independent forward analysis (``errors``), the methods in turn on a case and the types
interleaved, so that changes in the machine's load touch every method alike."""

from __future__ import annotations

import itertools
import math
import sys
import time
from typing import Any

from synth import SynthError, analyze
from synth.mechanisms import all_types

from .. import methods

TOL = 1e-9  # relative on time ratio and stroke, degrees on the transmission bound
WARM_PER_TYPE = {"scipy_de", "pylinkage_pso"}
# the global searches (about 2 s a target for evolution) run on every fourth target of each
# type and kind: 25 feasible and 6 infeasible per type, compared with ours on the same ones
SPARSE = {"scipy_de", "pylinkage_pso"}
EVERY = 4
ERRORS = ("time_ratio", "stroke", "transmission_deg")


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
        "case": case["id"],
        "type": case["type"],
        "feasible": case["feasible"],
        "fixed": bool(case["target"]["mechanisms"][0]["fixed"]),
        "kind": case["kind"],
        "method": name,
        "ms": seconds * 1e3,
        "n": len(out.candidates),
        "valid": sum(w <= TOL for w in worst),
        "best": min(worst, default=None),
        "worst": max(worst, default=None),
        "best_angle": max((a for a in good if a is not None), default=None),
        "errors": {k: [e[k] for e in errs] for k in ERRORS},
        "how": list(out.how),
        "refusals": list(out.refusals),
    }


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
