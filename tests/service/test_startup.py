"""A quick start, and budgets that hold from the first request on.

``import synth`` loads none of the heavy libraries a command may never need (scipy.stats,
scipy.optimize, ezdxf, matplotlib, the atlas), nor does ``import api.main`` (the service
imports what its searches use while it warms up). A server started fresh answers its first
request for each structure of ``benchmarks.startup.FIRST`` (issue 38's crank-rocker, the
least peak torque, a motion objective, the default request) within the request's budget +
50 ms, measured by the client: what a first request would otherwise build is built before the
server listens (``synth.synthesis.warm``), and what the deadline cuts short says so
(``complete`` false), its work kept for the next request.
"""

from __future__ import annotations

import json
import subprocess
import sys
import time

import pytest

from benchmarks.startup import FIRST, SLACK_MS

from ..support.server import ROOT, call, serving

HEAVY = ("scipy.stats", "scipy.optimize", "ezdxf", "matplotlib", "synth.atlas")


def loaded_by(statement: str) -> list[str]:
    """The heavy libraries in ``sys.modules`` after ``statement`` in a fresh interpreter."""
    found = f"[m for m in {HEAVY!r} if m in sys.modules]"
    code = f"import json, sys; {statement}; print(json.dumps({found}))"
    out = subprocess.run(
        [sys.executable, "-c", code],
        cwd=ROOT,
        capture_output=True,
        text=True,
        check=True,
        timeout=120,
    ).stdout
    return list(json.loads(out))


@pytest.mark.parametrize("statement", ["import synth", "import api.main"])
def test_an_import_loads_no_heavy_library(statement):
    assert loaded_by(statement) == []


@pytest.fixture(scope="module")
def fresh():
    """The shipped server, started for these tests alone (nothing asked of it before)."""
    with serving() as (port, _):
        yield port


@pytest.mark.parametrize(("what", "body"), FIRST, ids=[w for w, _ in FIRST])
def test_the_first_request_for_a_structure_answers_within_its_budget(fresh, what, body):
    start = time.monotonic()
    status, out = call(fresh, "/v1/synthesize", body)
    took_ms = (time.monotonic() - start) * 1000
    assert status == 200, out
    assert took_ms <= body["time_budget_ms"] + SLACK_MS, (what, took_ms, out.get("complete"))
