"""An atlas's folder: the manifest of its inputs, a file per finished chunk (written
atomically, so an interrupted run resumes from them) and the tables (CSV, and ``atlas.json``,
what the service serves at GET /v1/atlas)."""

from __future__ import annotations

import csv
import json
import os
import tempfile
from dataclasses import asdict
from pathlib import Path

from .values import Atlas, Inputs, Point


def folder(out: str | Path | None, inputs: Inputs) -> Path | None:
    if out is None:
        return None
    folder = Path(out)
    (folder / "chunks").mkdir(parents=True, exist_ok=True)
    manifest = folder / "manifest.json"
    mine = {"key": inputs.key(), "inputs": asdict(inputs)}
    if manifest.exists():
        theirs = json.loads(manifest.read_text())
        if theirs.get("key") != mine["key"]:
            raise ValueError(
                f"{folder} holds an atlas of other inputs ({theirs.get('inputs')}); "
                "choose another folder"
            )
    else:
        _atomic(manifest, json.dumps(mine, indent=1))
    return folder


def read(folder: Path, k: int) -> list[Point] | None:
    path = folder / "chunks" / f"{k:06d}.json"
    if not path.exists():
        return None
    return [Point(**p) for p in json.loads(path.read_text())]


def write(folder: Path, k: int, pts: list[Point]) -> None:
    _atomic(folder / "chunks" / f"{k:06d}.json", json.dumps([asdict(p) for p in pts]))


def _atomic(path: Path, text: str) -> None:
    with tempfile.NamedTemporaryFile("w", dir=path.parent, delete=False, suffix=".tmp") as f:
        f.write(text)
    os.replace(f.name, path)  # whole or not at all


def tables(a: Atlas, folder: Path) -> None:
    """frontier.csv and ranges.csv, with the inputs in manifest.json beside them, and all of
    it in atlas.json (what the service serves at GET /v1/atlas)."""
    summary = {
        "inputs": asdict(a.inputs),
        "frontier": {
            t: [[p.time_ratio, p.best_angle_deg, p.status] for p in a.frontier if p.type == t]
            for t in a.inputs.types
        },
        "ranges": a.ranges,
    }
    _atomic(folder / "atlas.json", json.dumps(summary, indent=1))

    def text(x: object) -> str:  # every digit kept; empty for none
        return "" if x is None else repr(x)

    with open(folder / "frontier.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["type", "time_ratio", "best_angle_deg", "status", "design", "reason"])
        for p in a.frontier:
            design = json.dumps(p.design) if p.design else ""
            w.writerow(
                [
                    p.type,
                    text(p.time_ratio),
                    text(p.best_angle_deg),
                    p.status,
                    design,
                    p.reason or "",
                ]
            )
    with open(folder / "ranges.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["type", "bound_deg", "min_time_ratio", "max_time_ratio"])
        for r in a.ranges:
            w.writerow([r["type"], text(r["bound_deg"]), text(r["min"]), text(r["max"])])
