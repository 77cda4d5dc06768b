"""Budgets hold on the real server: every reply of every objective comes within its
``time_budget_ms`` + 50 ms, measured by the client from its send to the reply's last byte, the
first request after a start included, and a request retried because its solver process died;
a request that cannot start (or start again) in time gets a 503 with Retry-After, within the
same bound.

``REQUESTS`` replies in all (``SYNTH_BUDGET_REQUESTS``; `make stress` runs more) from
``CLIENTS`` clients at once, budgets from 100 ms to 2 s in turn.
"""

from __future__ import annotations

import http.client
import json
import os
import signal
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from ..support.server import SHIPPED_CAP, alive, descendants, serving
from .test_admission import LOAD  # a shaper's: 2 kN, a 60 kg ram, links of 8 kg/m

pytestmark = pytest.mark.serial  # timing-sensitive: alone, not beside other tests (make test)

REQUESTS = int(os.environ.get("SYNTH_BUDGET_REQUESTS", "200"))
CLIENTS = 3
SLACK_MS = 50.0
BUDGETS_MS = (100.0, 200.0, 300.0, 500.0, 800.0, 1000.0, 1500.0, 2000.0)
TARGETS = {"time_ratio": 1.6, "stroke": 300.0, "min_transmission_angle_deg": 20.0}
TORQUE = {**TARGETS, "objective": "min_peak_torque", "load": LOAD}  # every type: ~3 s


def requests() -> list[tuple[str, dict]]:
    """(what it asks, its body without a budget): every objective, for every type or one,
    with its limits and extras; syntheses that need IPOPT (parts fixed or bounded, time ratios
    near 1, a bound no design reaches)."""
    drag = {"ground": 0.1, "crank": 0.225, "follower": 0.275, "connecting_rod": 0.3}
    fixed = {
        "time_ratio": 1.5,
        "stroke": 0.3,
        "min_transmission_angle_deg": 0.0,
        "mechanisms": [{"type": "drag_link_slider", "fixed": drag}],
    }
    bounded = {"mechanisms": [{"type": "crank_rocker_slider", "bounds": {"crank": [50, 200]}}]}
    shaper = [{"type": "crank_shaper", "bounds": {"ram_link": [30.0, 100.0]}}]
    uniform = {**TARGETS, "objective": "uniform_cutting_speed"}
    peak = {**TARGETS, "objective": "min_peak_acceleration"}
    best = {**TARGETS, "objective": "max_transmission_angle"}
    small = {**TARGETS, "objective": "min_size"}
    limit = "max_working_speed_fluctuation"
    strict = {**best, "min_transmission_angle_deg": 40.0, **bounded}
    sensitive = {**small, "include": ["sensitivities"], "tolerance": {"relative": 1e-3}}
    near_one = {**TARGETS, "time_ratio": 1.02, "min_transmission_angle_deg": 30.0}
    rocker = {"mechanisms": [{"type": "crank_rocker_slider"}]}
    return [
        ("min_peak_torque, every type", TORQUE),
        ("uniform_cutting_speed, every type", uniform),
        ("min_peak_acceleration, every type", peak),
        ("min_peak_torque, whitworth", {**TORQUE, "mechanisms": [{"type": "whitworth"}]}),
        ("max_peak_torque", {**TORQUE, "max_peak_torque": 1.0}),
        (limit + ", uniform", {**uniform, limit: 1.05}),
        (limit + ", peak", {**peak, limit: 1.2}),
        ("uniform_cutting_speed, crank_rocker_slider", {**uniform, **rocker}),
        ("min_peak_acceleration, parts fixed", {**peak, **fixed}),
        ("pareto", TARGETS),
        ("pareto, load and motion", {**TARGETS, "load": LOAD, "include": ["motion"]}),
        ("pareto, parts fixed", fixed),
        ("pareto, time ratio 1.02", near_one),
        ("max_transmission_angle, bounded", strict),
        ("max_transmission_angle, 50", {**best, "max_candidates": 50}),
        ("min_size, 85°", {**small, "min_transmission_angle_deg": 85.0, "mechanisms": shaper}),
        ("min_size, sensitivities", sensitive),
    ]


def sent(n: int) -> Iterator[tuple[str, dict, float]]:
    """The ``n`` requests in turn, each kind with every budget in turn."""
    kinds = requests()
    for i in range(n):
        name, body = kinds[i % len(kinds)]
        budget = BUDGETS_MS[(i // len(kinds) + i) % len(BUDGETS_MS)]
        yield name, {**body, "time_budget_ms": budget}, budget


def ask(conn: http.client.HTTPConnection, body: dict) -> tuple[int, bool, float]:
    """A synthesis: its status, whether it carried Retry-After, and its milliseconds from the
    send to the reply's last byte."""
    data = json.dumps(body).encode()
    t0 = time.perf_counter()
    conn.request("POST", "/v1/synthesize", data, {"Content-Type": "application/json"})
    r = conn.getresponse()
    r.read()
    return r.status, r.getheader("Retry-After") is not None, (time.perf_counter() - t0) * 1000


@pytest.fixture(scope="module")
def server() -> Iterator[int]:
    with serving(**SHIPPED_CAP) as (port, _):
        yield port


def test_the_first_request_after_a_start_keeps_its_budget(server):
    """The first request a fresh server gets (its solvers not yet used), on a short budget."""
    conn = http.client.HTTPConnection("127.0.0.1", server, timeout=60)
    _, body, _ = next(sent(1))
    status, retry, ms = ask(conn, {**body, "time_budget_ms": 500.0})
    conn.close()
    assert status == 200 or (status == 503 and retry), status
    assert ms <= 500.0 + SLACK_MS, f"the first request took {ms:.0f} ms on a 500 ms budget"


@pytest.mark.long  # tens of seconds: make long (CI runs it), not make test
def test_every_reply_comes_within_its_budget(server):
    todo = list(sent(REQUESTS))
    lock = threading.Lock()
    done: list[tuple[str, float, int, bool, float]] = []

    def client() -> None:
        conn = http.client.HTTPConnection("127.0.0.1", server, timeout=60)
        while True:
            with lock:
                if not todo:
                    break
                name, body, budget = todo.pop(0)
            status, retry, ms = ask(conn, body)
            with lock:
                done.append((name, budget, status, retry, ms))
        conn.close()

    threads = [threading.Thread(target=client) for _ in range(CLIENTS)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    worst: dict[str, float] = {}
    for name, budget, _, _, ms in done:
        worst[name] = max(worst.get(name, -1e9), ms - budget)
    print("largest overrun (ms) per request:", {k: round(v) for k, v in worst.items()})
    bad = [d for d in done if not (d[2] == 200 or (d[2] == 503 and d[3]))]
    assert not bad, f"answers besides 200 and 503 with Retry-After: {bad[:5]}"
    late = [(n, b, round(ms)) for n, b, _, _, ms in done if ms > b + SLACK_MS]
    assert not late, (
        f"{len(late)} of {len(done)} replies later than budget + {SLACK_MS:g} ms: {late}"
    )
    # three clients on two server processes: a request behind another on its solver gets a
    # 503 at half its budget (~40% of them); the rest are served
    served = sum(d[2] == 200 for d in done) / len(done)
    assert served >= 1 / 3, f"only {served:.0%} served"


def test_a_request_retried_after_its_solver_process_died_keeps_its_budget():
    """One server process with a pool of one solver process, killed a second into a 3 s
    synthesis: the request is tried again on the new pool with what is left of its budget
    (or refused with a 503 once nothing is), not with a fresh budget."""
    env = {
        "WEB_CONCURRENCY": "1",
        "SYNTH_EXECUTOR": "process",
        "SYNTH_WORKERS": "1",
        **SHIPPED_CAP,
    }
    body = {**TORQUE, "time_budget_ms": 3000.0}
    with serving(**env) as (port, proc):
        conn = http.client.HTTPConnection("127.0.0.1", port, timeout=60)
        assert ask(conn, body)[0] == 200  # the pool is up, its solvers built
        got: list[tuple[int, bool, float]] = []
        asked = threading.Thread(target=lambda: got.append(ask(conn, body)))
        asked.start()
        time.sleep(1.0)
        (worker,) = solvers(proc.pid)
        os.kill(worker, signal.SIGKILL)
        asked.join()
        conn.close()
    ((status, retry, ms),) = got
    print(f"the retried request: {status} in {ms:.0f} ms")
    assert status == 200 or (status == 503 and retry), status
    assert ms <= 3000.0 + SLACK_MS, f"the retried request took {ms:.0f} ms on a 3 s budget"


def solvers(pid: int) -> list[int]:
    """The live solver processes multiprocessing spawned below the server process ``pid``."""
    return [p for p in descendants(pid) if alive(p) and b"spawn_main" in _cmdline(p)]


def _cmdline(pid: int) -> bytes:
    try:
        return Path(f"/proc/{pid}/cmdline").read_bytes()
    except OSError:
        return b""
