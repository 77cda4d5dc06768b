"""The synthesis benchmark's results as markdown: the summary, ours by kind of target, times
relative to ours, optimality and the goals (``text``: all of them, as printed)."""

from __future__ import annotations

from typing import Any

from synth.mechanisms import all_types

from .run import EVERY, SPARSE
from .stats import SAME_ANGLE


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


def text(result: dict[str, Any]) -> str:
    """Every table of the results: the summary; where ours ran, ours by kind of target, the
    times relative to ours, the optimality (where generic ran too) and the goals."""
    rows = result["summary"]
    out = markdown(rows)
    if "ratios" not in result:
        return out
    table = result["ratios"]
    out += "\n\nOurs, by kind of target (p99 over 40–60 targets is about their maximum):\n\n"
    out += ours_table(rows)
    out += (
        f"\n\nMedian time on feasible targets relative to ours, on the same targets "
        f"({', '.join(sorted(SPARSE))}: every {EVERY}th target):\n\n"
    )
    out += ratio_table(table, "feasible")
    out += "\n\nMedian of the per-target time ratios to ours, feasible targets:\n\n"
    out += ratio_table(table, "paired")
    out += "\n\nMedian time on infeasible targets relative to ours:\n\n"
    out += ratio_table(table, "infeasible")
    if "optimality" in result:
        out += "\n\n" + optimality_text(result["optimality"])
    return out + "\n\nThe goals (ours):\n\n" + goals_table(result["goals"])
