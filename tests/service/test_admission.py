"""/health answers from the event loop at once, whatever the mix: on the real server, 48
clients of the heaviest work (analyses of 1 000 curve points with pins, loaded analyses, exact
syntheses of each type and of all six) for 20 s, while a prober asks /health every 20–50 ms on
its own connection. Every kind of work passes admission: a 200, or a 503 with Retry-After.

The clients run in a process of their own (asyncio, one keep-alive connection each), so that
the prober's times are the server's, not the load generator's.
"""

from __future__ import annotations

import asyncio
import http.client
import json
import random
import statistics
import time
from concurrent.futures import ProcessPoolExecutor
from itertools import cycle
from multiprocessing import get_context

import pytest

from benchmarks import analysis

from ..support.server import serving

pytestmark = pytest.mark.serial  # timing-sensitive: alone, not beside other tests (make test)

CLIENTS = 48
SECONDS = 20.0
PROBE_S = (0.02, 0.05)  # the prober's pause between two asks, drawn in this range
HEALTH_P99_MS, HEALTH_MAX_MS = 50.0, 200.0

# the reference designs (the benchmarks'), each type but the yoke's for the loaded analyses
DESIGNS = {t: p for t, p in analysis.DESIGNS.items() if t != "scotch_yoke"}
LOAD = {
    "length_unit": "mm",
    "crank_rpm": 40.0,
    "cutting_force": 2000.0,
    "slider_mass": 60.0,
    "link_mass_per_length": 8.0,
}
TYPES = tuple(analysis.DESIGNS)
KINDS = ("curves", "loaded", "exact")


def mix() -> list[tuple[str, str, dict]]:
    """(kind, path, body): what ran in the event loop before (1 000 curve points with pins;
    syntheses the exact solvers answer alone, each type and all six) and loaded analyses."""
    out = []
    for t, params in DESIGNS.items():
        design = {"type": t, "params": params}
        out.append(
            ("curves", "/v1/analyze", {"mechanism": design, "samples": 1000, "include": ["pins"]})
        )
        out.append(("loaded", "/v1/analyze", {"mechanism": design, "load": LOAD, "samples": 72}))
    for t in TYPES:
        tr = 1.0 if t == "scotch_yoke" else 1.6
        out.append(
            (
                "exact",
                "/v1/synthesize",
                {"time_ratio": tr, "stroke": 300.0, "mechanisms": [{"type": t}]},
            )
        )
    for tr, bound in ((1.6, 20.0), (2.2, 10.0), (1.3, 30.0)):
        out.append(
            (
                "exact",
                "/v1/synthesize",
                {"time_ratio": tr, "stroke": 300.0, "min_transmission_angle_deg": bound},
            )
        )
    return out


def clients(port: int, n: int, seconds: float) -> list[tuple[str, int, bool]]:
    """``n`` keep-alive clients sending the mix (each its own shuffle) for ``seconds``: each
    answer's kind, status and whether it carried Retry-After. Runs in a process of its own."""
    return asyncio.run(_clients(port, n, seconds))


async def _clients(port: int, n: int, seconds: float) -> list[tuple[str, int, bool]]:
    requests = [(kind, _raw(path, body)) for kind, path, body in mix()]
    stop = time.monotonic() + seconds
    out: list[tuple[str, int, bool]] = []

    async def client(k: int) -> None:
        reader, writer = await asyncio.open_connection("127.0.0.1", port)
        for kind, raw in cycle(random.Random(k).sample(requests, len(requests))):
            if time.monotonic() >= stop:
                break
            writer.write(raw)
            status, headers = await _head(reader)
            await reader.readexactly(int(headers["content-length"]))
            out.append((kind, status, "retry-after" in headers))
            if headers.get("connection") == "close":
                writer.close()
                reader, writer = await asyncio.open_connection("127.0.0.1", port)
        writer.close()

    await asyncio.gather(*(client(k) for k in range(n)))
    return out


def _raw(path: str, body: dict) -> bytes:
    data = json.dumps(body).encode()
    return (
        f"POST {path} HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Type: application/json\r\n"
        f"Content-Length: {len(data)}\r\n\r\n"
    ).encode() + data


async def _head(reader: asyncio.StreamReader) -> tuple[int, dict[str, str]]:
    status = int((await reader.readline()).split()[1])
    headers = {}
    while (line := await reader.readline()) not in (b"\r\n", b""):
        name, _, value = line.decode("latin-1").partition(":")
        headers[name.strip().lower()] = value.strip()
    return status, headers


def _share(xs: list[bool]) -> float:
    return sum(xs) / max(1, len(xs))


def probe(port: int, until: float) -> list[float]:
    """GET /health every 20–50 ms on one keep-alive connection until ``until``: each one's
    milliseconds, from its send to its last byte."""
    out = []
    conn = http.client.HTTPConnection("127.0.0.1", port, timeout=30)
    pause = random.Random(0)
    while time.monotonic() < until:
        t0 = time.perf_counter()
        conn.request("GET", "/health")
        r = conn.getresponse()
        r.read()
        out.append((time.perf_counter() - t0) * 1000)
        assert r.status == 200
        time.sleep(pause.uniform(*PROBE_S))
    conn.close()
    return out


@pytest.mark.long  # tens of seconds: make long (CI runs it), not make test
def test_health_answers_at_once_under_the_heaviest_mix_and_every_kind_of_work_is_admitted():
    with serving() as (port, _), ProcessPoolExecutor(1, mp_context=get_context("spawn")) as pool:
        pool.submit(clients, port, 4, 6.0).result()  # warm: every process's models and solvers
        loaded = pool.submit(clients, port, CLIENTS, SECONDS)
        health = probe(port, time.monotonic() + SECONDS)
        answers = loaded.result()
    q = statistics.quantiles(health, n=100, method="inclusive")
    got = {"p50": q[49], "p99": q[98], "max": max(health), "probes": len(health)}
    bad = [(k, s) for k, s, retry in answers if s != 200 and not (s == 503 and retry)]
    assert not bad, f"answers besides 200 and 503 with Retry-After: {bad[:10]} ({len(bad)})"
    served = {k: _share([s == 200 for kind, s, _ in answers if kind == k]) for k in KINDS}
    print(f"/health {got}; served {served}; {len(answers)} answers")
    assert got["p99"] <= HEALTH_P99_MS and got["max"] <= HEALTH_MAX_MS, (got, served)
    assert min(served.values()) >= 0.9, f"share of each kind served: {served} (/health {got})"
