"""The synthesis benchmark's files: the results, the records, the tables, the plot, the targets."""

from __future__ import annotations

import gzip
import json
import math
from pathlib import Path
from typing import Any

from .. import targets
from .plot import plot


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
