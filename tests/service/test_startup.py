"""A quick start, and budgets that hold from the first request on.

``import synth`` loads none of the heavy libraries a command may never need (scipy.stats,
scipy.optimize, ezdxf, matplotlib, the atlas), nor does ``import api.main`` (the service
imports what its searches use while it warms up). A server started fresh answers its first
request for each structure of ``benchmarks.startup.FIRST`` (issue 38's crank-rocker, the
least peak torque, a motion objective, the default request) within the request's budget +
50 ms, measured by the client: what a first request would otherwise build is built before the
server listens (``synth.synthesis.warm``), and what the deadline cuts short says so
(``complete`` false), its work kept for the next request. So does a fresh server's first
request of each searched objective (``FIRST_SEARCHED``: every type, nothing fixed): after the
warm-up a searched request with nothing fixed builds no formulation, compiled function or
solver (issue 39).
"""

from __future__ import annotations

import json
import subprocess
import sys
import time
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from typing import Any

import pytest

import synth
from benchmarks.startup import FIRST, FIRST_SEARCHED, SEARCHED, SLACK_MS, TYPES
from synth.analysis import model
from synth.synthesis import certify, formulation, local, screen, solve, stroke, torque, warm

from ..support.server import ROOT, call, serving

pytestmark = pytest.mark.serial  # timing-sensitive: alone, not beside other tests (make test)

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


@pytest.mark.parametrize(("objective", "body"), FIRST_SEARCHED, ids=[o for o, _ in FIRST_SEARCHED])
def test_a_fresh_servers_first_searched_request_answers_within_its_budget(objective, body):
    with serving() as (port, _):
        start = time.monotonic()
        status, out = call(port, "/v1/synthesize", body)
        took_ms = (time.monotonic() - start) * 1000
    assert status == 200, out
    assert took_ms <= body["time_budget_ms"] + SLACK_MS, (objective, took_ms, out.get("complete"))


def test_after_the_warm_up_a_searched_request_with_nothing_fixed_builds_nothing(monkeypatch):
    """In a thread of its own (its structures its own), after ``warm.warm``: a request of each
    type and searched objective, nothing fixed, builds no compiled function (the analysis's,
    the motion search's constraints, the certified search's), no formulation and no solver;
    each type reaches the motion search (the certified one, or the NLP)."""
    built: list[str] = []
    searched: set[str] = set()

    def watched(module: Any, name: str, seen: Callable[..., None]) -> None:
        made = getattr(module, name)

        def make(*args: Any, **kwargs: Any) -> Any:
            seen(*args)
            return made(*args, **kwargs)

        monkeypatch.setattr(module, name, make)

    def requests() -> None:
        warm.warm()
        for module, name in [
            (model, "Mapped"),
            (screen, "Mapped"),
            (stroke, "Mapped"),
            (torque, "Mapped"),
            (formulation, "formulate"),
            (solve, "formulate"),
        ]:
            watched(module, name, lambda *_, at=f"{module.__name__}.{name}": built.append(at))
        watched(local, "formulation", lambda m, *_: searched.add(m.type))
        watched(certify, "search", lambda m, *_: searched.add(m.type))
        for objective, targets in SEARCHED.items():
            load = targets.get("load")
            for mtype in TYPES:
                synth.synthesize(
                    **{**targets, "load": load and synth.Load(**load)},
                    objective=objective,
                    mechanisms=[mtype],
                    time_budget_ms=1000.0,
                )

    with ThreadPoolExecutor(1) as thread:
        thread.submit(requests).result()
    assert searched == set(TYPES)
    assert built == []
