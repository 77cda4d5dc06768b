"""The load generator for the service on loopback: clients, each on its own keep-alive
connection, sending their requests in turn; only 127.0.0.1 is targeted.

    python -m benchmarks.load --port 8000 --clients 16 --requests 2000 --path /v1/analyze

prints throughput and p50/p95/p99 (JSON with --json). ``drive`` is the generator the service
and overload benchmarks share: ``run`` (N clients, a bounded count of requests), ``alternate``
(one client, requests in turn) and ``benchmarks.overload`` are ways of driving it.
"""

from __future__ import annotations

import argparse
import http.client
import json
import statistics
import threading
import time
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from typing import Any

BODIES = {
    "/v1/analyze": {
        "mechanism": {
            "type": "drag_link_slider",
            "params": {
                "ground": 0.1,
                "crank": 0.225,
                "coupler": 0.2504,
                "follower": 0.275,
                "follower_arm": 0.15,
                "connecting_rod": 0.3,
            },
        }
    },
    "/v1/synthesize": {
        "time_ratio": 1.5,
        "stroke": 0.3,
        "mechanisms": [
            {
                "type": "drag_link_slider",
                "fixed": {"ground": 0.1, "crank": 0.225, "follower": 0.275, "connecting_rod": 0.3},
            }
        ],
    },
}
JSON = {"Content-Type": "application/json"}
# a request a client sends: the path it is POSTed to, its body (None: a GET), and what its
# answer counts under
Request = tuple[str, bytes | None, Any]


@dataclass(frozen=True)
class Sent:
    """A request's answer: its tag, its status (the error's name where the connection
    failed: the client connects again), and how long it took."""

    tag: Any
    status: int | str
    ms: float


@dataclass
class Driven:
    sent: list[Sent] = field(default_factory=list)
    health_ms: list[float] = field(default_factory=list)  # the /health prober's answers
    seconds: float = 0.0


def drive(
    port: int,
    clients: Sequence[Iterable[Request]],
    seconds: float,
    total: int | None = None,
    probe_s: float | None = None,
) -> Driven:
    """Each of ``clients`` (its requests, in order) on its own keep-alive connection at once,
    each until its requests end, ``seconds`` have passed or ``total`` requests in all are
    answered; with ``probe_s``, meanwhile a GET /health every ``probe_s`` seconds on another
    connection."""
    stop = time.monotonic() + seconds
    lock = threading.Lock()
    out = Driven()

    def going() -> bool:
        return time.monotonic() < stop and (total is None or len(out.sent) < total)

    def client(requests: Iterable[Request]) -> None:
        conn = http.client.HTTPConnection("127.0.0.1", port, timeout=60)
        for path, body, tag in requests:
            if not going():
                break
            status, ms = ask(conn, path, body)
            if isinstance(status, str):
                conn = http.client.HTTPConnection("127.0.0.1", port, timeout=60)
            with lock:
                out.sent.append(Sent(tag, status, ms))
        conn.close()

    def prober(every: float) -> None:
        conn = http.client.HTTPConnection("127.0.0.1", port, timeout=60)
        while going():
            t0 = time.perf_counter()
            conn.request("GET", "/health")
            conn.getresponse().read()
            out.health_ms.append((time.perf_counter() - t0) * 1000)
            time.sleep(every)
        conn.close()

    threads = [threading.Thread(target=client, args=(c,)) for c in clients]
    if probe_s is not None:
        threads.append(threading.Thread(target=prober, args=(probe_s,)))
    t0 = time.perf_counter()
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    out.seconds = time.perf_counter() - t0
    return out


def ask(conn: http.client.HTTPConnection, path: str, body: bytes | None) -> tuple[int | str, float]:
    """One request on ``conn``, POSTed (a GET where ``body`` is None): its status (the error's
    name where the connection failed, and then ``conn`` is closed) and its milliseconds."""
    t0 = time.perf_counter()
    status: int | str
    try:
        conn.request("GET" if body is None else "POST", path, body, JSON)
        r = conn.getresponse()
        r.read()
        status = r.status
    except OSError as e:
        status = type(e).__name__
        conn.close()
    return status, (time.perf_counter() - t0) * 1000


def statuses(sent: Iterable[Sent]) -> dict[int | str, int]:
    """How many answers had each status."""
    counts: dict[int | str, int] = {}
    for s in sent:
        counts[s.status] = counts.get(s.status, 0) + 1
    return counts


def run(
    port: int,
    path: str,
    clients: int,
    requests: int,
    seconds: float,
    bodies: Sequence[dict[str, Any]] | None = None,
) -> dict[str, Any]:
    """``clients`` clients sending ``requests`` in all to ``path`` (request i: ``bodies[i %
    len(bodies)]``, by client i % clients), for at most ``seconds``: throughput, latency
    quantiles, statuses."""
    payloads = [json.dumps(b).encode() for b in bodies or [BODIES[path]]]
    shares = [
        [(path, payloads[i % len(payloads)], None) for i in range(k, requests, clients)]
        for k in range(clients)
    ]
    d = drive(port, shares, seconds)
    latencies = [s.ms / 1e3 for s in d.sent]
    q = statistics.quantiles(latencies, n=100) if len(latencies) > 1 else [latencies[0]] * 99
    return {
        "path": path,
        "clients": clients,
        "requests": len(latencies),
        "seconds": d.seconds,
        "throughput_rps": len(latencies) / d.seconds,
        "p50_ms": q[49] * 1e3,
        "p95_ms": q[94] * 1e3,
        "p99_ms": q[98] * 1e3,
        "statuses": statuses(d.sent),
    }


def alternate(port: int, requests: list[tuple[str, dict[str, Any]]], rounds: int) -> list[dict]:
    """One client, one keep-alive connection: the requests in turn, ``rounds`` times, so that
    the machine's load touches each alike. Per request: median and p90 latency, statuses."""
    payloads = [(path, json.dumps(b).encode()) for path, b in requests]
    turns = [(path, body, k) for _ in range(rounds) for k, (path, body) in enumerate(payloads)]
    sent = drive(port, [turns], float("inf")).sent
    out = []
    for k, (path, _) in enumerate(requests):
        mine = [s for s in sent if s.tag == k]
        ts = [s.ms / 1e3 for s in mine]
        q = statistics.quantiles(ts, n=10) if len(ts) > 1 else [ts[0]] * 9
        out.append(
            {
                "path": path,
                "requests": len(ts),
                "p50_ms": statistics.median(ts) * 1e3,
                "p90_ms": q[8] * 1e3,
                "statuses": statuses(mine),
            }
        )
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--port", type=int, default=8000)
    ap.add_argument("--path", default="/v1/analyze", choices=sorted(BODIES))
    ap.add_argument("--clients", type=int, default=16)
    ap.add_argument("--requests", type=int, default=1000)
    ap.add_argument("--seconds", type=float, default=60.0)
    ap.add_argument("--json", action="store_true")
    a = ap.parse_args()
    out = run(a.port, a.path, a.clients, a.requests, a.seconds)
    print(
        json.dumps(out)
        if a.json
        else f"{out['path']} {out['clients']} clients: {out['throughput_rps']:.0f} req/s, "
        f"p50 {out['p50_ms']:.1f} ms, p95 {out['p95_ms']:.1f} ms, p99 {out['p99_ms']:.1f} ms, "
        f"{out['statuses']}"
    )


if __name__ == "__main__":
    main()
