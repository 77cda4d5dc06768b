"""The service on loopback: latency p50/p95/p99 and throughput at 1, 4 and 16 clients.

    python -m benchmarks.service [--quick] [--servers shipped,...]

Starts each server configuration (``benchmarks.server``: ``shipped`` is the command `make
serve` and the image run) with its own default settings, waits for a warm-up, then drives
three workloads with the load generator (``benchmarks.load``):

- ``analyze``: /v1/analyze, eight designs without curves;
- ``synthesize``: /v1/synthesize, the drag-link project of the sources (time ratio, stroke
  and four parts given, the coupler to find) at eight time ratios;
- ``synthesize_default``: /v1/synthesize, default requests (everything free, bound 20°): each
  quick-return type alone, and all five at once.

A share of each is infeasible or invalid, as in real use: an analysis of a design that cannot
be assembled (422), a synthesis no design can meet (200 with a reason). The load generator
runs on the same cores as the service: the numbers are a floor for a separate client machine.

On the shipped server it also repeats the synthesis workloads at 16 clients, alternated, for
a median throughput (``repeated``); and it times, per type, a default synthesis request for
that type alone against a summary analysis of a design of the same type, alternated on one
connection (``paired``): the ratio of their median latencies is what a synthesis costs over
HTTP, in analyses.

Then the shipped server against a bare ASGI app served the same way (``benchmarks.bare``), in
the same run (``against_bare``): at one client, /health, an analysis of a crank shaper and a
default crank-shaper synthesis, each in turn on the service and on the bare app with the same
computation run in this process between them, so that the machine's load touches all three
alike. What the service adds to a request is its p50 less the bare round trip's and the
computation's; the goal is at most ``ALLOWANCE_MS``. And the analysis workload at 16 clients on
both, alternated: throughput and the server's processor time per request.
"""

from __future__ import annotations

import argparse
import http.client
import json
import statistics
import time
from collections.abc import Callable
from functools import partial
from typing import Any

import synth

from . import load
from .analysis import DESIGNS, QUICK_RETURN
from .common import cpu_seconds, descendants, report, table
from .server import SERVERS, serving

CLIENTS = (1, 4, 16)
INVALID_SHARE = 0.2  # two requests in ten: a design that cannot be assembled, an unmet target
WORKLOADS = {
    "analyze": "/v1/analyze",
    "synthesize": "/v1/synthesize",
    "synthesize_default": "/v1/synthesize",
}

_DRAG_FIXED = {"ground": 0.1, "crank": 0.225, "follower": 0.275, "connecting_rod": 0.3}
SERVICE = [s for s in SERVERS if s != "bare"]  # the service's configurations

# against_bare: each request (a GET where its body is None) and the same computation in process
_SHAPER = DESIGNS["crank_shaper"]
_SHAPER_TARGETS = (1.6, 300.0, 20.0, [{"type": "crank_shaper"}])  # time ratio, stroke, bound
AGAINST_BARE: dict[str, tuple[str, dict | None, Callable[[], Any] | None]] = {
    "health": ("/health", None, None),
    "analyze": (
        "/v1/analyze",
        {"mechanism": {"type": "crank_shaper", "params": _SHAPER}},
        partial(synth.analyze, "crank_shaper", _SHAPER),
    ),
    "synthesize": (
        "/v1/synthesize",
        dict(
            zip(
                ("time_ratio", "stroke", "min_transmission_angle_deg", "mechanisms"),
                _SHAPER_TARGETS,
                strict=True,
            )
        ),
        partial(synth.synthesize, *_SHAPER_TARGETS),
    ),
}
ALLOWANCE_MS = 0.3  # the goal: a request costs the bare round trip + its computation + this


def bodies(workload: str) -> list[dict]:
    """Ten bodies, two of them infeasible or invalid (INVALID_SHARE)."""
    if workload == "analyze":
        good = [{"mechanism": {"type": t, "params": p}} for t, p in DESIGNS.items()]
        good += good[-2:]  # the four-bars twice: 8 valid bodies
        bad = {
            "type": "crank_shaper",
            "params": {"crank": 300.0, "pivot_distance": 240.0, "lever": 450.0},
        }
        return good + [{"mechanism": bad}] * 2
    if workload == "synthesize":
        body = {"stroke": 0.3, "mechanisms": [{"type": "drag_link_slider", "fixed": _DRAG_FIXED}]}
        good = [{**body, "time_ratio": 1.4 + 0.02 * k} for k in range(8)]
        return good + [{**body, "time_ratio": 10.0}] * 2
    alone = [
        default_body(t, tr) for t, tr in zip(QUICK_RETURN, (1.3, 1.6, 2.0, 2.5, 1.6), strict=True)
    ]
    every = [
        {"time_ratio": tr, "stroke": 1.0, "min_transmission_angle_deg": 20.0}
        for tr in (1.3, 1.6, 2.0)
    ]
    bad = [default_body("offset_slider_crank", 3.5), default_body("whitworth", 1.6, 89.9)]
    return alone + every + bad


def default_body(mtype: str, time_ratio: float = 1.6, bound: float = 20.0) -> dict:
    """A default request for one type: everything free (the scotch yoke's ratio is 1)."""
    tr = 1.0 if mtype == "scotch_yoke" else time_ratio
    return {
        "time_ratio": tr,
        "stroke": 1.0,
        "min_transmission_angle_deg": bound,
        "mechanisms": [{"type": mtype}],
    }


def paired(port: int, rounds: int) -> list[dict]:
    """Per type: a default synthesis request for it alone against a summary analysis of a
    design of it, alternated on one connection; their median latencies and the ratio."""
    rows = []
    for mtype, params in DESIGNS.items():
        pair = [
            ("/v1/synthesize", default_body(mtype)),
            ("/v1/analyze", {"mechanism": {"type": mtype, "params": params}}),
        ]
        load.alternate(port, pair, 3)  # warm: this type's models in the serving process
        s, a = load.alternate(port, pair, rounds)
        statuses = {"synthesize": s["statuses"], "analyze": a["statuses"]}
        rows.append(
            {
                "type": mtype,
                "rounds": rounds,
                "synthesize_p50_ms": s["p50_ms"],
                "synthesize_p90_ms": s["p90_ms"],
                "analyze_p50_ms": a["p50_ms"],
                "analyze_p90_ms": a["p90_ms"],
                "ratio": s["p50_ms"] / a["p50_ms"],
                "statuses": statuses,
            }
        )
    return rows


def repeated(port: int, repeats: int, requests: int, seconds: float) -> list[dict]:
    """Synthesis throughput at 16 clients, each synthesis workload ``repeats`` times, the two
    alternated (a single cell moves by ±30% on this machine from one run to the next)."""
    rows = []
    for k in range(repeats):
        for workload in ("synthesize", "synthesize_default"):
            r = load.run(port, WORKLOADS[workload], 16, requests, seconds, bodies(workload))
            rows.append({"workload": workload, "repeat": k, **r})
    return rows


def against_bare(rounds: int, repeats: int, requests: int, seconds: float) -> tuple[list, list]:
    """The shipped server against the bare app, both started here: per request of
    ``AGAINST_BARE`` at one client, the p50s (``rounds`` in turn, after a warm-up) and what the
    service adds; and the analysis workload at 16 clients, ``repeats`` times alternated, with
    each server's processor time per request."""
    with (
        serving("shipped", defaults=True) as (port, proc),
        serving("bare", defaults=True) as (bare, bare_proc),
    ):
        ports = {"service": port, "bare": bare}
        load.run(port, "/v1/analyze", 2, 200, 60, bodies("analyze"))  # warm-up
        one = _one_client(ports, rounds)
        pids = {
            "service": descendants(proc.pid) | {proc.pid},
            "bare": descendants(bare_proc.pid) | {bare_proc.pid},
        }
        many = []
        for k in range(repeats):
            for server in ("service", "bare") if k % 2 == 0 else ("bare", "service"):
                cpu = cpu_seconds(pids[server])
                r = load.run(ports[server], "/v1/analyze", 16, requests, seconds, bodies("analyze"))
                cpu_us = (cpu_seconds(pids[server]) - cpu) / r["requests"] * 1e6
                many.append({"server": server, "repeat": k, "cpu_us_per_request": cpu_us, **r})
    return one, many


def _one_client(ports: dict[str, int], rounds: int) -> list[dict]:
    """Each of ``AGAINST_BARE`` in turn on each server, then in process, ``rounds`` times on
    one keep-alive connection per server (a warm-up of a tenth first): their p50s."""
    conns = {s: http.client.HTTPConnection("127.0.0.1", p, timeout=60) for s, p in ports.items()}
    requests = {
        name: (path, None if body is None else json.dumps(body).encode(), compute)
        for name, (path, body, compute) in AGAINST_BARE.items()
    }
    ms: dict[tuple[str, str], list[float]] = {}
    seen: dict[str, dict[int | str, int]] = {name: {} for name in requests}
    warm = max(rounds // 10, 3)
    for k in range(warm + rounds):
        for name, (path, body, compute) in requests.items():
            for server, conn in conns.items():
                status, t = load.ask(conn, path, body)
                if isinstance(status, str):  # the connection failed: a new one
                    conns[server] = http.client.HTTPConnection(
                        "127.0.0.1", ports[server], timeout=60
                    )
                if k >= warm:
                    ms.setdefault((name, server), []).append(t)
                    if server == "service":
                        seen[name][status] = seen[name].get(status, 0) + 1
            if compute is not None:
                t0 = time.perf_counter()
                compute()
                if k >= warm:
                    ms.setdefault((name, "in_process"), []).append((time.perf_counter() - t0) * 1e3)
    for conn in conns.values():
        conn.close()
    rows = []
    for name in requests:
        p50 = {
            s: statistics.median(ms[(name, s)]) if (name, s) in ms else 0.0
            for s in ("service", "bare", "in_process")
        }
        ours = p50["service"] - p50["bare"] - p50["in_process"]
        rows.append(
            {
                "request": name,
                "rounds": rounds,
                "service_p50_ms": p50["service"],
                "bare_p50_ms": p50["bare"],
                "in_process_p50_ms": p50["in_process"],
                "ours_ms": ours,
                "goal_ms": p50["bare"] + p50["in_process"] + ALLOWANCE_MS,
                "met": ours <= ALLOWANCE_MS,
                "statuses": seen[name],
            }
        )
    return rows


def measure(server: str, requests: int, seconds: float, rounds: int) -> tuple[list, list, list]:
    rows, pairs, again = [], [], []
    with serving(server, defaults=True) as (port, _):
        for workload, path in WORKLOADS.items():
            mix = bodies(workload)
            load.run(port, path, 2, 4 * len(mix), 60, mix)  # warm-up: workers, solvers
            for clients in CLIENTS:
                r = load.run(port, path, clients, requests, seconds, mix)
                rows.append({"server": server, "workload": workload, **r})
        if server == "shipped":
            pairs = paired(port, rounds)
            again = repeated(port, 5 if rounds > 10 else 1, requests, seconds / 2)
    return rows, pairs, again


def main(argv: list[str] | None = None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--quick", action="store_true", help="a smoke run: few requests")
    ap.add_argument("--servers", default=",".join(SERVICE))
    a = ap.parse_args(argv)
    # each cell stops at whichever comes first
    requests, seconds, rounds = (40, 60.0, 5) if a.quick else (3000, 10.0, 200)
    rows, pairs, again = [], [], []
    for s in a.servers.split(","):
        r, p, g = measure(s, requests, seconds, rounds)
        rows += r
        pairs += p
        again += g
    one, many = against_bare(*((10, 1, 40, 60.0) if a.quick else (1000, 6, 6000, 10.0)))
    cols = (
        "server",
        "workload",
        "clients",
        "requests",
        "throughput_rps",
        "p50_ms",
        "p95_ms",
        "p99_ms",
        "statuses",
    )
    print(table(rows, cols))
    print(table(pairs, ("type", "synthesize_p50_ms", "analyze_p50_ms", "ratio", "statuses")))
    summary = [
        {"workload": w, "median_rps": statistics.median(rs), "min_rps": min(rs), "max_rps": max(rs)}
        for w in ("synthesize", "synthesize_default")
        if (rs := [r["throughput_rps"] for r in again if r["workload"] == w])
    ]
    print(table(summary, ("workload", "median_rps", "min_rps", "max_rps")))
    print(
        table(
            one,
            (
                "request",
                "service_p50_ms",
                "bare_p50_ms",
                "in_process_p50_ms",
                "ours_ms",
                "goal_ms",
                "met",
                "statuses",
            ),
        )
    )
    sixteen = [
        {
            "server": s,
            "median_rps": statistics.median(r["throughput_rps"] for r in rs),
            "median_cpu_us_per_request": statistics.median(r["cpu_us_per_request"] for r in rs),
            "median_p50_ms": statistics.median(r["p50_ms"] for r in rs),
        }
        for s in ("service", "bare")
        if (rs := [r for r in many if r["server"] == s])
    ]
    print(table(sixteen, ("server", "median_rps", "median_cpu_us_per_request", "median_p50_ms")))
    results = {
        "invalid_share": INVALID_SHARE,
        "rows": rows,
        "paired": pairs,
        "repeated_16_clients": again,
        "repeated_summary": summary,
        "against_bare": {
            "allowance_ms": ALLOWANCE_MS,
            "one_client": one,
            "sixteen_clients": many,
            "sixteen_summary": sixteen,
        },
    }
    return report("service", results, quick=a.quick)


if __name__ == "__main__":
    main()
