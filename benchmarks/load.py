"""A bounded load generator for the service on loopback: N clients, keep-alive connections.

    python benchmarks/load.py --port 8000 --clients 16 --requests 2000 --path /v1/analyze

Each client sends its share of requests (bounded in count and in --seconds) and records
latencies; prints throughput and p50/p95/p99 (JSON with --json). Only 127.0.0.1 is targeted.
"""

from __future__ import annotations

import argparse
import http.client
import json
import statistics
import threading
import time

BODIES = {
    "/v1/analyze": {"mechanism": {"type": "drag_link_slider", "params": {
        "ground": 0.1, "crank": 0.225, "coupler": 0.2504, "follower": 0.275,
        "follower_arm": 0.15, "connecting_rod": 0.3}}},
    "/v1/synthesize": {"time_ratio": 1.5, "stroke": 0.3, "mechanisms": [{
        "type": "drag_link_slider", "fixed": {"ground": 0.1, "crank": 0.225, "follower": 0.275,
                                              "connecting_rod": 0.3}}]},
}  # fmt: skip


def run(port: int, path: str, clients: int, requests: int, seconds: float, bodies=None) -> dict:
    bodies = bodies or [BODIES[path]]
    payloads = [json.dumps(b).encode() for b in bodies]
    latencies: list[float] = []
    statuses: dict[int, int] = {}
    lock = threading.Lock()
    deadline = time.monotonic() + seconds

    def client(k: int) -> None:
        conn = http.client.HTTPConnection("127.0.0.1", port, timeout=60)
        mine, codes = [], {}
        for i in range(k, requests, clients):
            if time.monotonic() > deadline:
                break
            t0 = time.perf_counter()
            conn.request("POST", path, payloads[i % len(payloads)],
                         {"Content-Type": "application/json"})  # fmt: skip
            r = conn.getresponse()
            r.read()
            mine.append(time.perf_counter() - t0)
            codes[r.status] = codes.get(r.status, 0) + 1
        conn.close()
        with lock:
            latencies.extend(mine)
            for c, n in codes.items():
                statuses[c] = statuses.get(c, 0) + n

    t0 = time.perf_counter()
    threads = [threading.Thread(target=client, args=(k,)) for k in range(clients)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    wall = time.perf_counter() - t0
    q = statistics.quantiles(latencies, n=100) if len(latencies) > 1 else [latencies[0]] * 99
    return {
        "path": path, "clients": clients, "requests": len(latencies), "seconds": wall,
        "throughput_rps": len(latencies) / wall, "p50_ms": q[49] * 1e3, "p95_ms": q[94] * 1e3,
        "p99_ms": q[98] * 1e3, "statuses": statuses,
    }  # fmt: skip


def alternate(port: int, requests: list[tuple[str, dict]], rounds: int) -> list[dict]:
    """One client, one keep-alive connection: the requests in turn, ``rounds`` times, so that
    the machine's load touches each alike. Per request: median and p90 latency, statuses."""
    conn = http.client.HTTPConnection("127.0.0.1", port, timeout=60)
    payloads = [(path, json.dumps(b).encode()) for path, b in requests]
    latencies: list[list[float]] = [[] for _ in requests]
    statuses: list[dict[int, int]] = [{} for _ in requests]
    try:
        for _ in range(rounds):
            for k, (path, payload) in enumerate(payloads):
                t0 = time.perf_counter()
                conn.request("POST", path, payload, {"Content-Type": "application/json"})
                r = conn.getresponse()
                r.read()
                latencies[k].append(time.perf_counter() - t0)
                statuses[k][r.status] = statuses[k].get(r.status, 0) + 1
    finally:
        conn.close()
    out = []
    for (path, _), ts, codes in zip(requests, latencies, statuses, strict=True):
        q = statistics.quantiles(ts, n=10) if len(ts) > 1 else [ts[0]] * 9
        out.append({"path": path, "requests": len(ts), "p50_ms": statistics.median(ts) * 1e3,
                    "p90_ms": q[8] * 1e3, "statuses": codes})  # fmt: skip
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
    print(json.dumps(out) if a.json else
          f"{out['path']} {out['clients']} clients: {out['throughput_rps']:.0f} req/s, "
          f"p50 {out['p50_ms']:.1f} ms, p95 {out['p95_ms']:.1f} ms, p99 {out['p99_ms']:.1f} ms, "
          f"{out['statuses']}")  # fmt: skip


if __name__ == "__main__":
    main()
