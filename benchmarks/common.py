"""What every benchmark shares: the machine and versions it ran on, JSON results, tables."""

from __future__ import annotations

import contextlib
import datetime
import hashlib
import json
import os
import platform
import subprocess
import sys
from collections.abc import Iterator
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

RESULTS = Path(__file__).parent / "results"
PACKAGES = ("casadi", "numpy", "scipy", "fastapi", "uvicorn", "pydantic", "pylinkage", "matplotlib")
# the quick-return types, in the order the benchmarks' tables give them
TYPES = (
    "offset_slider_crank",
    "whitworth",
    "crank_shaper",
    "drag_link_slider",
    "crank_rocker_slider",
)
SPIN = "while True:\n    pass\n"


@contextlib.contextmanager
def spinning(n: int = 2) -> Iterator[None]:
    """``n`` processes keeping the cores busy meanwhile, ended by their ids after."""
    procs = [subprocess.Popen([sys.executable, "-c", SPIN]) for _ in range(n)]
    try:
        yield
    finally:
        for p in procs:
            p.kill()
            p.wait()


def machine() -> dict:
    def ver(name: str) -> str | None:
        try:
            return version(name)
        except PackageNotFoundError:
            return None

    return {
        "date_utc": datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%dT%H:%M:%SZ"),
        "platform": platform.platform(),
        "processor": platform.processor() or platform.machine(),
        "cpus": len(os.sched_getaffinity(0)),
        "load_average_at_start": os.getloadavg(),
        "python": platform.python_version(),
        "versions": {p: v for p in PACKAGES if (v := ver(p))},
        "code": code(),
    }


def code() -> dict:
    """The commit measured, and a digest of uncommitted changes to the library and service (a
    run on a working tree that differs from it says so)."""

    def git(*args: str) -> str:
        try:
            return subprocess.run(
                ["git", *args],
                cwd=RESULTS.parent.parent,
                capture_output=True,
                text=True,
                check=True,
            ).stdout
        except (OSError, subprocess.CalledProcessError):
            return ""

    diff = git("diff", "HEAD", "--", "synth", "api")
    return {
        "commit": git("rev-parse", "HEAD").strip() or None,
        "synth_api_changes": hashlib.sha256(diff.encode()).hexdigest()[:12] if diff else None,
        "changed_files": git("diff", "HEAD", "--name-only", "--", "synth", "api").split(),
    }


def report(name: str, results: dict, quick: bool = False) -> dict:
    """The results with the machine; written to results/<name>.json unless a quick run."""
    out = {"machine": machine(), "quick": quick, **results}
    if not quick:
        RESULTS.mkdir(exist_ok=True)
        (RESULTS / f"{name}.json").write_text(json.dumps(out, indent=1) + "\n")
    return out


def table(rows: list[dict], columns: tuple[str, ...]) -> str:
    """A markdown table; floats to 4 significant digits, missing cells empty."""

    def cell(v) -> str:
        return "" if v is None else f"{v:.4g}" if isinstance(v, float) else str(v)

    lines = ["| " + " | ".join(columns) + " |", "|" + "---|" * len(columns)]
    lines += ["| " + " | ".join(cell(r.get(c)) for c in columns) + " |" for r in rows]
    return "\n".join(lines) + "\n"


def descendants(pid: int) -> set[int]:
    """Every process below ``pid`` (from /proc)."""
    children: dict[int, set[int]] = {}
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        children.setdefault(int(fields[1]), set()).add(int(stat.parent.name))
    found, todo = set(), [pid]
    while todo:
        for child in children.get(todo.pop(), ()):
            found.add(child)
            todo.append(child)
    return found


def cpu_seconds(pids: set[int]) -> float:
    """The processor time (user and system) the processes ``pids`` have used so far (from
    /proc; a process gone counts nothing)."""
    ticks = 0
    for pid in pids:
        try:
            fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        ticks += int(fields[11]) + int(fields[12])  # utime, stime
    return ticks / os.sysconf("SC_CLK_TCK")
