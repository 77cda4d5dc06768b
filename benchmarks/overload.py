"""The shipped server overloaded on loopback: budgets, errors, /health and memory.

    python -m benchmarks.overload [--quick]

A mixed load (analyses, default syntheses of each type, syntheses that need IPOPT, sweeps,
invalid requests; every synthesis with a 1 000 ms budget) from 16 and then 64 clients, each
on its own keep-alive connection, for a bounded time; meanwhile a prober asks /health every
50 ms on its own connection. Reported per client count:

- each synthesis's wall time against its budget (p50, p99, max; the contract: p99 ≤ budget
  + 100 ms);
- statuses, and errors: 5xx other than 503, and dropped connections (the contract: 0; a 503
  with Retry-After is a refusal, counted apart);
- /health latency (p50, p99; the contract: p99 ≤ 100 ms);

and the server's memory (RSS of all its processes) before and after 20 000 requests of the
mix. The load generator shares the machine's cores with the server: a floor.
"""

from __future__ import annotations

import argparse
import http.client
import json
import random
import statistics
import threading
import time
from pathlib import Path

from api.examples import DRAG_LINK

from .common import descendants, report, table
from .service import default_body, free_port, serve

BUDGET_MS = 1000.0
CLIENTS = (16, 64)


def mix() -> list[tuple[str, dict]]:
    """Twenty requests: analyses, syntheses (default, per type and all types; near time ratio
    1, where the four-bars need IPOPT), a sweep, and invalid ones."""
    budget = {"time_budget_ms": BUDGET_MS}
    analyze = {"mechanism": {"type": "drag_link_slider", "params": DRAG_LINK}}
    synth = [
        {**default_body(t), **budget}
        for t in ("offset_slider_crank", "crank_shaper", "whitworth", "crank_rocker_slider")
    ]
    synth += [{"time_ratio": tr, "stroke": 300.0, "min_transmission_angle_deg": b, **budget}
              for tr, b in ((1.6, 40.0), (1.02, 30.0), (1.02, 30.0))]  # fmt: skip
    sweep = {**analyze, "vary": "coupler", "start": 0.14, "stop": 0.5, "points": 101}
    bad = [{"mechanism": {"type": "crank_shaper", "params": {"crank": 300.0,
            "pivot_distance": 240.0, "lever": 450.0}}}, {"mechanism": {"type": "scotch_yoke",
            "params": {"crank": -1}}}]  # fmt: skip
    return ([("/v1/analyze", analyze)] * 8 + [("/v1/synthesize", b) for b in synth]
            + [("/v1/sweep", sweep)] * 2 + [("/v1/analyze", b) for b in bad]
            + [("/v1/synthesize", {**synth[0], "time_ratio": 3.5})])  # fmt: skip


def quantiles(xs: list[float]) -> dict:
    if not xs:
        return {"p50": None, "p99": None, "max": None}
    q = statistics.quantiles(xs, n=100, method="inclusive") if len(xs) > 1 else [xs[0]] * 99
    return {"p50": q[49], "p99": q[98], "max": max(xs)}


def drive(port: int, clients: int, seconds: float, requests: int | None = None) -> dict:
    """``clients`` keep-alive clients sending the mix (shuffled, seeded) for ``seconds`` (or
    until ``requests`` in all), and the /health prober."""
    bodies = [(path, json.dumps(b).encode()) for path, b in mix()]
    stop = time.monotonic() + seconds
    lock = threading.Lock()
    sent = 0
    statuses: dict[str, int] = {}
    walls: list[float] = []  # syntheses, ms
    health: list[float] = []

    def client(k: int) -> None:
        nonlocal sent
        order = random.Random(k).sample(bodies, len(bodies))
        conn = http.client.HTTPConnection("127.0.0.1", port, timeout=60)
        i = 0
        while time.monotonic() < stop and (requests is None or sent < requests):
            path, payload = order[i % len(order)]
            i += 1
            t0 = time.perf_counter()
            try:
                conn.request("POST", path, payload, {"Content-Type": "application/json"})
                r = conn.getresponse()
                r.read()
                key = str(r.status)
            except OSError as e:
                key = type(e).__name__
                conn.close()
                conn = http.client.HTTPConnection("127.0.0.1", port, timeout=60)
            ms = (time.perf_counter() - t0) * 1000
            with lock:
                sent += 1
                statuses[key] = statuses.get(key, 0) + 1
                if path == "/v1/synthesize" and key == "200":
                    walls.append(ms)
        conn.close()

    def prober() -> None:
        conn = http.client.HTTPConnection("127.0.0.1", port, timeout=60)
        while time.monotonic() < stop and (requests is None or sent < requests):
            t0 = time.perf_counter()
            conn.request("GET", "/health")
            conn.getresponse().read()
            health.append((time.perf_counter() - t0) * 1000)
            time.sleep(0.05)
        conn.close()

    threads = [threading.Thread(target=client, args=(k,)) for k in range(clients)]
    threads.append(threading.Thread(target=prober))
    t0 = time.perf_counter()
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    errors = sum(n for k, n in statuses.items() if not k.isdigit() or (k[0] == "5" and k != "503"))
    return {"clients": clients, "requests": sent, "seconds": time.perf_counter() - t0,
            "budget_ms": BUDGET_MS, "synthesis_wall_ms": quantiles(walls),
            "health_ms": quantiles(health), "statuses": statuses, "errors": errors}  # fmt: skip


def rss_kb(pid: int) -> int:
    """The resident memory of ``pid`` and every process below it."""
    total = 0
    for p in {pid, *descendants(pid)}:
        try:
            for line in Path(f"/proc/{p}/status").read_text().splitlines():
                if line.startswith("VmRSS:"):
                    total += int(line.split()[1])
        except OSError:
            pass
    return total


def main(argv: list[str] | None = None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--quick", action="store_true", help="a smoke run: a few seconds each")
    ap.add_argument("--seconds", type=float, default=30.0, help="per client count")
    a = ap.parse_args(argv)
    seconds, volume = (3.0, 500) if a.quick else (float(a.seconds), 20_000)
    port = free_port()
    proc = serve(port, "shipped")
    try:
        drive(port, 4, seconds / 3)  # warm-up: every process's models and solvers
        rows = [drive(port, n, seconds) for n in CLIENTS]
        before = rss_kb(proc.pid)
        memory = drive(port, 16, 600.0, requests=volume)
        after = rss_kb(proc.pid)
    finally:
        proc.terminate()
        proc.wait(120)
    flat = [{"clients": r["clients"], "requests": r["requests"], "errors": r["errors"],
             "refused_503": r["statuses"].get("503", 0),
             "synth_p99_ms": r["synthesis_wall_ms"]["p99"],
             "synth_max_ms": r["synthesis_wall_ms"]["max"],
             "health_p99_ms": r["health_ms"]["p99"]} for r in rows]  # fmt: skip
    print(table(flat, tuple(flat[0])))
    growth = {"requests": memory["requests"], "rss_before_mb": before / 1024,
              "rss_after_mb": after / 1024, "growth_mb": (after - before) / 1024,
              "errors": memory["errors"]}  # fmt: skip
    print(table([growth], tuple(growth)))
    return report("overload", {"rows": rows, "memory": growth}, quick=a.quick)


if __name__ == "__main__":
    main()
