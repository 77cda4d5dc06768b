"""The same request gives the same answer under load.

- The shipped server, default budget: 32 copies of one synthesis that needs IPOPT (~0.5 s of
  solving each: 8 s of work for 2 s of budget on two cores) arrive at once. Each gets either
  the answer the request gets alone, or a 503 with Retry-After, never another answer; retried
  as told, every one gets that answer.
- The searched objectives (issue 39): 20 requests, each in a fresh process, give the same reply
  on a quiet machine and while two other processes keep both cores busy.
"""

from __future__ import annotations

import json
import subprocess
import sys
import threading
import time
import urllib.error
import urllib.request

import pytest

from benchmarks.common import spinning

from ..support.server import SHIPPED_CAP, serving

pytestmark = pytest.mark.serial  # timing-sensitive: alone, not beside other tests (make test)

REQUEST = {"time_ratio": 1.02, "stroke": 300.0, "min_transmission_angle_deg": 30.0}
COPIES = 32


def ask(port: int) -> tuple[int, dict, str | None]:
    req = urllib.request.Request(
        f"http://127.0.0.1:{port}/v1/synthesize",
        json.dumps(REQUEST).encode(),
        {"Content-Type": "application/json"},
    )
    try:
        with urllib.request.urlopen(req, timeout=60) as r:
            return r.status, json.loads(r.read()), None
    except urllib.error.HTTPError as e:
        return e.code, json.loads(e.read()), e.headers.get("Retry-After")


def answer(body: dict) -> dict:
    return {k: v for k, v in body.items() if k != "elapsed_ms"}


def test_32_concurrent_copies_get_the_answer_the_request_gets_alone():
    # the cap as shipped, so the default 2 s budget applies
    with serving(**SHIPPED_CAP) as (port, _):
        status, alone, _ = ask(port)
        assert status == 200 and alone["complete"]
        first: list = [None] * COPIES
        final: list = [None] * COPIES

        def client(k: int) -> None:
            while True:
                status, body, retry = ask(port)
                if first[k] is None:
                    first[k] = (status, retry)
                if status != 503:
                    final[k] = (status, body)
                    return
                time.sleep(float(retry))

        threads = [threading.Thread(target=client, args=(k,)) for k in range(COPIES)]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
    assert all(s in (200, 503) for s, _ in first), first
    assert all(retry is not None for s, retry in first if s == 503)
    assert all(s == 200 for s, _ in final), [b for s, b in final if s != 200][:1]
    differ = [b for _, b in final if answer(b) != answer(alone)]
    assert not differ, f"{len(differ)} of {COPIES} differ from the answer alone: {differ[0]}"


# Issue 39: a searched request (uniform_cutting_speed, min_peak_acceleration, min_peak_torque)
# gives the same reply in a fresh process, on a quiet machine and on one whose two cores two
# other processes keep busy. Each request runs in a process of its own (its first request: the
# compiled functions loaded there), with a budget it finishes well within; the reply compared
# is ``SynthesisResult.to_dict()`` without ``elapsed_ms``, its one field that is a time.
TIMED = ("elapsed_ms",)
ENOUGH_MS = 60_000.0
LOAD = {"length_unit": "mm", "crank_rpm": 40.0, "cutting_force": 2000.0, "slider_mass": 20.0}
HEAVY = {**LOAD, "link_mass_per_length": 8.0}
# the tie case of the issue: five crank-shaper designs within 1e-6 of each other
SHAPER = {"length_unit": "mm", "crank_rpm": 30.0, "cutting_force": 3000.0, "slider_mass": 40.0}
UNIFORM, PEAK, TORQUE = "uniform_cutting_speed", "min_peak_acceleration", "min_peak_torque"
SEARCHED = [  # (type or types, objective, time ratio, stroke, bound°, more arguments)
    ("offset_slider_crank", UNIFORM, 1.6, 300.0, 20.0, {}),
    ("offset_slider_crank", PEAK, 2.0, 300.0, 0.0, {}),
    ("offset_slider_crank", PEAK, 1.6, 300.0, 20.0, {"max_working_speed_fluctuation": 1.25}),
    ("whitworth", UNIFORM, 1.4, 300.0, 10.0, {}),
    ("whitworth", PEAK, 2.5, 300.0, 30.0, {}),
    ("crank_shaper", UNIFORM, 1.6, 300.0, 20.0, {}),
    ("crank_shaper", PEAK, 1.8, 250.0, 35.0, {}),
    ("drag_link_slider", UNIFORM, 1.6, 300.0, 20.0, {}),
    ("drag_link_slider", PEAK, 2.0, 300.0, 0.0, {}),
    ("crank_rocker_slider", PEAK, 1.6, 300.0, 20.0, {}),
    ("whitworth", UNIFORM, 1.8, 300.0, 20.0, {"fixed": {"connecting_rod": 360.0}}),
    ("offset_slider_crank", PEAK, 1.5, 300.0, 10.0, {"fixed": {"coupler": 420.0}}),
    (("offset_slider_crank", "whitworth"), PEAK, 1.6, 300.0, 20.0, {}),
    ("offset_slider_crank", TORQUE, 1.4, 300.0, 10.0, {"load": LOAD}),
    ("offset_slider_crank", TORQUE, 1.6, 300.0, 20.0, {"load": {**LOAD, "guide_friction": 0.2}}),
    ("whitworth", TORQUE, 1.4, 300.0, 10.0, {"load": HEAVY}),
    ("whitworth", TORQUE, 1.6, 300.0, 20.0, {"load": LOAD, "max_peak_torque": 400.0}),
    ("crank_shaper", TORQUE, 1.7, 250.0, 35.0, {"load": SHAPER}),
    ("crank_shaper", TORQUE, 1.4, 300.0, 10.0, {"load": HEAVY}),
    ("drag_link_slider", TORQUE, 1.6, 300.0, 20.0, {"load": LOAD}),
]
# a request of one type that needs about twice the default budget (3.9 s alone with enough,
# warm, on a quiet two-core machine, at 3070287; the one before, at time ratio 1.6 and 20°,
# came to 1.1 s): cut short at 2 s, quiet or loaded
CUT_SHORT = ("crank_rocker_slider", TORQUE, 2.0, 300.0, 0.0, {"load": HEAVY})
# a fresh interpreter: the request (JSON) in, its reply out (JSON, keys sorted, no time)
FRESH = """
import json, sys
import synth

kw = json.loads(sys.argv[1])
if kw.get("load"):
    kw["load"] = synth.Load(**kw["load"])
reply = synth.synthesize(**kw).to_dict()
for k in json.loads(sys.argv[2]):
    del reply[k]
print(json.dumps(reply, sort_keys=True))
"""


def arguments(case: tuple, budget_ms: float) -> dict:
    types, objective, tr, stroke, bound, more = case
    more = dict(more)
    fixed = more.pop("fixed", None)
    kinds = [types] if isinstance(types, str) else list(types)
    mechanisms = [{"type": kinds[0], "fixed": fixed}] if fixed else kinds
    return {
        "time_ratio": tr,
        "stroke": stroke,
        "min_transmission_angle_deg": bound,
        "mechanisms": mechanisms,
        "objective": objective,
        "time_budget_ms": budget_ms,
        **more,
    }


def replies(requests: list[dict], at_once: int = 2) -> list[dict]:
    """Each request's reply, each in a fresh process, ``at_once`` processes at a time."""
    out: list = [None] * len(requests)
    running: list[tuple[int, subprocess.Popen]] = []
    todo = list(enumerate(requests))
    while todo or running:
        while todo and len(running) < at_once:
            k, kw = todo.pop(0)
            cmd = [sys.executable, "-c", FRESH, json.dumps(kw), json.dumps(TIMED)]
            running.append((k, subprocess.Popen(cmd, stdout=subprocess.PIPE, text=True)))
        k, p = running.pop(0)
        try:
            text, _ = p.communicate(timeout=600)
        except subprocess.TimeoutExpired:
            p.kill()
            raise
        assert p.returncode == 0, f"request {requests[k]} failed"
        out[k] = json.loads(text)
    return out


def quiet_and_loaded(requests: list[dict]) -> tuple[list[dict], list[dict]]:
    quiet = replies(requests)
    with spinning():
        loaded = replies(requests)
    return quiet, loaded


def label(kw: dict) -> str:
    kinds = "+".join(m if isinstance(m, str) else m["type"] for m in kw["mechanisms"])
    return (
        f"{kinds} {kw['objective']} TR {kw['time_ratio']:g} {kw['min_transmission_angle_deg']:g}°"
    )


@pytest.mark.long  # tens of seconds: make long (CI runs it), not make test
def test_20_searched_requests_give_the_same_reply_in_fresh_processes_quiet_and_loaded():
    requests = [arguments(c, ENOUGH_MS) for c in SEARCHED]
    assert len(requests) == 20
    assert {r["objective"] for r in requests} == {UNIFORM, PEAK, TORQUE}
    quiet, loaded = quiet_and_loaded(requests)
    for kw, q, ld in zip(requests, quiet, loaded, strict=True):
        assert q["complete"] and ld["complete"], label(kw)
        assert q["candidates"], label(kw)  # each has an answer to compare
        assert q == ld, f"{label(kw)}: the reply under load differs"


def test_a_searched_request_cut_short_by_the_default_budget_gives_the_same_reply():
    """Cut short, the search's answer is its exact solvers' designs, whatever the load: the
    budget decides only that the answer is not complete."""
    kw = arguments(CUT_SHORT, 2000.0)
    quiet, loaded = quiet_and_loaded([kw, kw])
    assert not any(r["complete"] for r in quiet + loaded), label(kw)
    assert quiet[0] == quiet[1] == loaded[0] == loaded[1], label(kw)
    assert quiet[0]["candidates"] and [i["code"] for i in quiet[0]["infeasible"]] == [
        "BUDGET_EXHAUSTED"
    ]
