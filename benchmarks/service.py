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
"""

from __future__ import annotations

import argparse
import statistics

from . import load
from .analysis import DESIGNS, QUICK_RETURN
from .common import report, table
from .server import SERVERS, serving

CLIENTS = (1, 4, 16)
INVALID_SHARE = 0.2  # two requests in ten: a design that cannot be assembled, an unmet target
WORKLOADS = {"analyze": "/v1/analyze", "synthesize": "/v1/synthesize",
             "synthesize_default": "/v1/synthesize"}  # fmt: skip

_DRAG_FIXED = {"ground": 0.1, "crank": 0.225, "follower": 0.275, "connecting_rod": 0.3}


def bodies(workload: str) -> list[dict]:
    """Ten bodies, two of them infeasible or invalid (INVALID_SHARE)."""
    if workload == "analyze":
        good = [{"mechanism": {"type": t, "params": p}} for t, p in DESIGNS.items()]
        good += good[-2:]  # the four-bars twice: 8 valid bodies
        bad = {"type": "crank_shaper", "params": {"crank": 300.0, "pivot_distance": 240.0,
                                                  "lever": 450.0}}  # fmt: skip
        return good + [{"mechanism": bad}] * 2
    if workload == "synthesize":
        body = {"stroke": 0.3, "mechanisms": [{"type": "drag_link_slider",
                                               "fixed": _DRAG_FIXED}]}  # fmt: skip
        good = [{**body, "time_ratio": 1.4 + 0.02 * k} for k in range(8)]
        return good + [{**body, "time_ratio": 10.0}] * 2
    alone = [default_body(t, tr) for t, tr in zip(QUICK_RETURN, (1.3, 1.6, 2.0, 2.5, 1.6),
                                                  strict=True)]  # fmt: skip
    every = [{"time_ratio": tr, "stroke": 1.0, "min_transmission_angle_deg": 20.0}
             for tr in (1.3, 1.6, 2.0)]  # fmt: skip
    bad = [default_body("offset_slider_crank", 3.5), default_body("whitworth", 1.6, 89.9)]
    return alone + every + bad


def default_body(mtype: str, time_ratio: float = 1.6, bound: float = 20.0) -> dict:
    """A default request for one type: everything free (the scotch yoke's ratio is 1)."""
    tr = 1.0 if mtype == "scotch_yoke" else time_ratio
    return {"time_ratio": tr, "stroke": 1.0, "min_transmission_angle_deg": bound,
            "mechanisms": [{"type": mtype}]}  # fmt: skip


def paired(port: int, rounds: int) -> list[dict]:
    """Per type: a default synthesis request for it alone against a summary analysis of a
    design of it, alternated on one connection; their median latencies and the ratio."""
    rows = []
    for mtype, params in DESIGNS.items():
        pair = [("/v1/synthesize", default_body(mtype)),
                ("/v1/analyze", {"mechanism": {"type": mtype, "params": params}})]  # fmt: skip
        load.alternate(port, pair, 3)  # warm: this type's models in the serving process
        s, a = load.alternate(port, pair, rounds)
        statuses = {"synthesize": s["statuses"], "analyze": a["statuses"]}
        rows.append({"type": mtype, "rounds": rounds, "synthesize_p50_ms": s["p50_ms"],
                     "synthesize_p90_ms": s["p90_ms"], "analyze_p50_ms": a["p50_ms"],
                     "analyze_p90_ms": a["p90_ms"], "ratio": s["p50_ms"] / a["p50_ms"],
                     "statuses": statuses})  # fmt: skip
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
    ap.add_argument("--servers", default=",".join(SERVERS))
    a = ap.parse_args(argv)
    # each cell stops at whichever comes first
    requests, seconds, rounds = (40, 60.0, 5) if a.quick else (3000, 10.0, 200)
    rows, pairs, again = [], [], []
    for s in a.servers.split(","):
        r, p, g = measure(s, requests, seconds, rounds)
        rows += r
        pairs += p
        again += g
    cols = ("server", "workload", "clients", "requests", "throughput_rps", "p50_ms", "p95_ms",
            "p99_ms", "statuses")  # fmt: skip
    print(table(rows, cols))
    print(table(pairs, ("type", "synthesize_p50_ms", "analyze_p50_ms", "ratio", "statuses")))
    summary = [
        {"workload": w, "median_rps": statistics.median(rs), "min_rps": min(rs), "max_rps": max(rs)}
        for w in ("synthesize", "synthesize_default")
        if (rs := [r["throughput_rps"] for r in again if r["workload"] == w])
    ]
    print(table(summary, ("workload", "median_rps", "min_rps", "max_rps")))
    results = {"invalid_share": INVALID_SHARE, "rows": rows, "paired": pairs,
               "repeated_16_clients": again, "repeated_summary": summary}  # fmt: skip
    return report("service", results, quick=a.quick)


if __name__ == "__main__":
    main()
