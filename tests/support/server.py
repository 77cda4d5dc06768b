"""The real server for tests that go over a socket: the benchmarks' (``benchmarks.server``:
started as `make serve` starts it, stopped with every process it started), and whether a
process is still alive."""

from __future__ import annotations

from pathlib import Path

from benchmarks.common import descendants
from benchmarks.server import ROOT, call, free_port, serving, wait_for_health

__all__ = ["ROOT", "alive", "call", "descendants", "free_port", "serving", "wait_for_health"]


def alive(pid: int) -> bool:
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False
