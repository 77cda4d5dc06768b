"""A server's memory is bounded by design: no request-controlled number (how many curve
points, how long a force profile, which type) makes it keep more. Against the real server:
1 000 loaded analyses and syntheses of random sizes and types, RSS of each server process
measured after the first 50 and at the end. (The searched objectives build a solver for each
structure a request reaches, once: bounded by the types, not by requests; their screens'
evaluations take the same fixed-width slots, ``tests/library/test_native.py``.)"""

from __future__ import annotations

import http.client
import json
import threading
from pathlib import Path
from typing import Any

import pytest

from benchmarks.overload import loaded_mix
from tests.support.bruteforce import TYPES
from tests.support.designs import random_designs
from tests.support.server import descendants, serving

pytestmark = pytest.mark.serial  # timing-sensitive: alone, not beside other tests (make test)

REQUESTS = 1000
FIRST = 50  # requests before the baseline: what a process builds once is in it by then
GROWTH_MB = 50.0  # the most a process's RSS may grow after them
CLIENTS = 4


def rss_mb(pid: int) -> float:
    """The resident memory of ``pid`` (MB); 0 for a process that has gone (replaced)."""
    try:
        return int(Path(f"/proc/{pid}/statm").read_text().split()[1]) * 4096 / 1e6
    except OSError:
        return 0.0


def requests(seed: int) -> list[tuple[str, dict[str, Any]]]:
    """The overload benchmark's loaded mix, of designs drawn here (every type's)."""
    designs = {t: random_designs(t, 20, seed=seed) for t in TYPES}
    mix = [
        (path, body)
        for path, body, _ in loaded_mix(REQUESTS, seed, designs=designs, budget_ms=1000.0)
    ]
    # first, on each client's connection, an analysis and a synthesis of every type: what a
    # process builds once for a type (its solvers, its loads' functions) is built by then
    tour = [
        next(r for r in mix if kind in r[0] and t in json.dumps(r[1]))
        for t in TYPES
        for kind in ("analyze", "synthesize")
    ]
    first = [r for r in tour for _ in range(CLIENTS)]
    return [*first, *mix[len(first) :]]


def send(port: int, work: list[tuple[str, dict[str, Any]]], statuses: list[int]) -> None:
    conn = http.client.HTTPConnection("127.0.0.1", port, timeout=120)
    try:
        for path, body in work:
            conn.request("POST", path, json.dumps(body), {"Content-Type": "application/json"})
            r = conn.getresponse()
            r.read()
            statuses.append(r.status)
            if r.getheader("connection") == "close":
                conn.close()
    finally:
        conn.close()


def run(port: int, work: list[tuple[str, dict[str, Any]]]) -> list[int]:
    statuses: list[int] = []
    parts = [work[i::CLIENTS] for i in range(CLIENTS)]
    threads = [threading.Thread(target=send, args=(port, part, statuses)) for part in parts]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    return statuses


@pytest.mark.long  # tens of seconds: make long (CI runs it), not make test
def test_random_loaded_requests_do_not_grow_a_process() -> None:
    work = requests(seed=38)
    with serving() as (port, proc):
        processes = sorted(descendants(proc.pid))
        first = run(port, work[:FIRST])
        before = {pid: rss_mb(pid) for pid in processes}
        rest = run(port, work[FIRST:])
        after = {pid: rss_mb(pid) for pid in processes}
    statuses = first + rest
    assert len(statuses) == REQUESTS
    counts = {s: statuses.count(s) for s in set(statuses)}
    print(counts)
    assert set(counts) <= {200, 422, 503} and counts.get(200, 0) >= 0.7 * REQUESTS, counts
    grown = {pid: round(after[pid] - before[pid], 1) for pid in processes}
    print("grown (MB):", grown)
    assert max(grown.values()) <= GROWTH_MB, f"RSS grew (MB): {grown}, from {before}"
