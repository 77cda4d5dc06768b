"""The synthesis benchmark's statistics of its records: per method and type (``summary``),
ours against the generic multistart (``optimality``), times relative to ours (``ratios``), and
ours against its goals (``goals``)."""

from __future__ import annotations

import collections
import itertools
import math
import statistics
from typing import Any

import numpy as np

from synth.mechanisms import all_types

from .. import methods
from .run import ERRORS

SAME_ANGLE = 1e-9  # ours' best angle may be below generic's by this (× max(1, angle)), no more
GOALS = {  # the targets this benchmark measures ours against (medians unless said)
    "fixed_median_ms": 5.0,  # feasible targets with fixed parts
    "fixed_p99_ms": 50.0,
    "error_max": 1e-12,
    "scipy_slsqp": 30.0,  # a peer's median time at least this many times ours
    "scipy_de": 300.0,
}


def _quantile(xs: list[float], q: float) -> float | None:
    return float(np.quantile(xs, q, method="inverted_cdf")) if xs else None  # inf-safe


def _times(rs: list[dict[str, Any]], prefix: str) -> dict[str, Any]:
    ms = [r["ms"] for r in rs]
    return {
        f"n_{prefix}": len(rs),
        f"ms_median_{prefix}": _quantile(ms, 0.5),
        f"ms_p99_{prefix}": _quantile(ms, 0.99),
    }


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
            "method": name,
            "type": mtype,
            "feasible": len(feas),
            "success": sum(r["valid"] > 0 for r in feas) / len(feas),
            "infeasible": len(infeas),
            "refused": sum(r["valid"] == 0 for r in infeas) / len(infeas) if infeas else None,
            "ms_median": _quantile(ms, 0.5),
            "ms_p90": _quantile(ms, 0.9),
            "ms_p99": _quantile(ms, 0.99),
            **_times([r for r in feas if not r["fixed"]], "free"),
            **_times([r for r in feas if r["fixed"]], "fixed"),
            **_times(infeas, "infeasible"),
            "candidates": len(every),
            "error_median": _quantile(every, 0.5),
            "error_max": max(every, default=None),
            "worst_error_median": _quantile(worst, 0.5),
            "worst_error_p90": _quantile(worst, 0.9),
            "component_max": {
                k: max((e for r in feas for e in r["errors"][k]), default=None) for k in ERRORS
            },
            "how": dict(collections.Counter(h for r in rs for h in r["how"])),
        }
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
            violations.append(
                {"case": c, "ours_deg": o, "generic_deg": g, "feasible": by[c, "ours"]["feasible"]}
            )
        elif o - g > 1e-6:
            better.append({"case": c, "ours_deg": o, "generic_deg": g})
        else:
            equal += 1
    return {
        "compared": len(cases),
        "violations": violations,
        "equal": equal,
        "ours_better_by_1e-6_deg": better,
        "only_ours_solved": generic_none,
        "neither_solved": neither,
    }


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
            (
                "fixed_median_ms",
                r["ms_median_fixed"],
                r["ms_median_fixed"] is not None
                and r["ms_median_fixed"] <= GOALS["fixed_median_ms"],
            ),
            (
                "fixed_p99_ms",
                r["ms_p99_fixed"],
                r["ms_p99_fixed"] is not None and r["ms_p99_fixed"] <= GOALS["fixed_p99_ms"],
            ),
        ]
        for peer in ("scipy_slsqp", "scipy_de"):
            x = table.get(peer, {}).get(t, {}).get("feasible")
            if x is not None:
                checks.append((f"{peer} / ours", x, x >= GOALS[peer]))
        if opt is not None:
            bad = [v for v in opt["violations"] if v["case"].startswith(t + "/")]
            checks.append(("optimality violations", len(bad), not bad))
        out += [{"type": t, "goal": g, "measured": m, "met": ok} for g, m, ok in checks]
    return out
