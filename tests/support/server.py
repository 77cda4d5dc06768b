"""The real server for tests that go over a socket: the benchmarks' (``benchmarks.server``:
started as `make serve` starts it, stopped with every process it started), and whether a
process is still alive."""

from __future__ import annotations

from pathlib import Path

from api.config import Settings
from benchmarks.common import descendants
from benchmarks.server import ROOT, call, free_port, serving, wait_for_health

__all__ = [
    "ROOT",
    "SHIPPED_CAP",
    "alive",
    "call",
    "descendants",
    "free_port",
    "serving",
    "wait_for_health",
]

# the budget cap as shipped, for a server whose requests ask what they need (the test
# session's is 1 s, tests/conftest.py)
SHIPPED_CAP = {"SYNTH_MAX_BUDGET_MS": str(Settings.model_fields["max_budget_ms"].default)}


def alive(pid: int) -> bool:
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False
