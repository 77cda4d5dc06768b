"""The shipped server overloaded on loopback: budgets, fairness, errors, /health and memory.

    python -m benchmarks.overload [--quick]

Three mixes, each from its own clients on their own keep-alive connections, for a bounded
time, while a prober asks /health every 50 ms on its own connection:

- ``mixed``, from 16 and then 64 clients: analyses, syntheses (default ones of each type, and
  ones that need IPOPT), sweeps, invalid requests, and heavy ones (20 000 curve points with
  pins, a 2 001-point sweep, a body of 20 000 unknown fields); every synthesis and sweep in
  each of the budget classes ``BUDGETS_MS`` in turn;
- ``inline``, from 48 clients: what once ran in the event loop, at its heaviest (analyses of
  1 000 curve points with pins, default syntheses of all six types, loaded analyses);
- ``loaded``, from 16 clients: loaded analyses and syntheses of random types, curve lengths
  and force profiles (what once grew a process by ~35 MB for each new number of points).

Reported per mix and client count: statuses and errors (5xx other than 503, and dropped
connections; the contract: 0), /health latency (p50, p99, max), and the resident memory of
each server process before and after; for ``mixed``, per budget class: the share served (200),
the share refused (503 with Retry-After), each served synthesis's wall time against the
budget, and the longest a 503 took against the documented wait, min(½ budget, 1 s). Last,
the memory of all the server's processes before and after 20 000 requests of the ``loaded``
mix. The load generator shares the machine's cores with the server: a floor.
"""

from __future__ import annotations

import argparse
import itertools
import json
import random
import statistics
from pathlib import Path
from typing import Any

import numpy as np

import synth
from api.examples import DRAG_LINK

from . import load
from .common import descendants, report, table
from .server import serving
from .service import default_body

BUDGETS_MS = (300.0, 500.0, 800.0, 1000.0, 2000.0)
CLIENTS = (16, 64)  # the mixed load's client counts
INLINE_CLIENTS = 48
LOADED_CLIENTS = 16
WAIT_SLACK_MS = 50.0  # a 503's wall time may exceed the documented wait by this much
WAIT_MAX_MS = 1000.0  # the documented wait: min(½ budget, this)


def wait_bound_ms(budget_ms: float) -> float:
    return min(0.5 * budget_ms, WAIT_MAX_MS)


def mix() -> list[tuple[str, dict, float | None]]:
    """(path, body, budget class) of one round: analyses; syntheses (default, per type and all
    types; near time ratio 1, where the four-bars need IPOPT) and sweeps, each once per budget
    class; invalid and heavy requests."""
    analyze = {"mechanism": {"type": "drag_link_slider", "params": DRAG_LINK}}
    synth = [
        default_body(t)
        for t in ("offset_slider_crank", "crank_shaper", "whitworth", "crank_rocker_slider")
    ]
    synth += [
        {"time_ratio": tr, "stroke": 300.0, "min_transmission_angle_deg": b}
        for tr, b in ((1.6, 40.0), (1.02, 30.0), (3.5, 20.0))
    ]
    sweep = {**analyze, "vary": "coupler", "start": 0.14, "stop": 0.5, "points": 101}
    bad = [
        {
            "mechanism": {
                "type": "crank_shaper",
                "params": {"crank": 300.0, "pivot_distance": 240.0, "lever": 450.0},
            }
        },
        {"mechanism": {"type": "scotch_yoke", "params": {"crank": -1}}},
    ]
    heavy = [
        ("/v1/analyze", {**analyze, "samples": 20_000, "include": ["pins"]}, None),
        ("/v1/sweep", {**sweep, "points": 2001, "time_budget_ms": 2000.0}, 2000.0),
        ("/v1/analyze", {**analyze, **{f"k{i}": 1 for i in range(20_000)}}, None),
    ]
    out = [("/v1/analyze", analyze, None)] * 4 * len(BUDGETS_MS)
    for b in BUDGETS_MS:
        out += [("/v1/synthesize", {**body, "time_budget_ms": b}, b) for body in synth]
        out += [("/v1/sweep", {**sweep, "time_budget_ms": b}, b)]
    return out + [("/v1/analyze", body, None) for body in bad] + heavy


def inline_mix() -> list[tuple[str, dict, float | None]]:
    """What once ran in the event loop, at its heaviest: 1 000 curve points with pins, the
    default synthesis of all six types, a loaded analysis."""
    analyze = {"mechanism": {"type": "drag_link_slider", "params": DRAG_LINK}}
    heavy = {**analyze, "samples": 1000, "include": ["pins"]}
    synthesize = {"time_ratio": 1.6, "stroke": 300.0, "min_transmission_angle_deg": 20.0}
    loaded = {**analyze, "load": {"length_unit": "mm", "crank_rpm": 40, "cutting_force": 2000}}
    return [
        ("/v1/analyze", heavy, None),
        ("/v1/synthesize", synthesize, 2000.0),
        ("/v1/analyze", loaded, None),
        ("/v1/analyze", analyze, None),
    ]


def random_load(rng: np.random.Generator) -> dict[str, Any]:
    """A random load: a cutting force or a force profile of 2–60 points, a ram, maybe links
    with mass and guide friction."""
    out: dict[str, Any] = {
        "length_unit": str(rng.choice(["m", "mm", "in"])),
        "crank_rpm": float(rng.uniform(5, 120)),
        "slider_mass": float(rng.uniform(0, 50)),
    }
    if rng.random() < 0.5:
        k = int(rng.integers(2, 61))
        u = np.linspace(0, 1, k) if rng.random() < 0.2 else np.sort(rng.uniform(0, 1, k))
        forces = rng.uniform(0, 3000, k)
        out["force_profile"] = [[float(a), float(f)] for a, f in zip(u, forces, strict=True)]
    else:
        out["cutting_force"] = float(rng.uniform(0, 3000))
    if rng.random() < 0.3:
        out["link_mass_per_length"] = float(rng.uniform(0, 10))
    if rng.random() < 0.3:
        out["guide_friction"] = float(rng.uniform(0, 0.2))
    return out


def loaded_mix(
    n: int,
    seed: int = 38,
    designs: dict[str, list[dict[str, float]]] | None = None,
    budget_ms: float = 5000.0,
) -> list[tuple[str, dict, float | None]]:
    """n loaded requests of random types and sizes: four in five analyses (1–5 000 curve
    points, or up to 300 given angles; a third with the joints' forces) of ``designs`` (by
    type; default: ones this library synthesises), the rest syntheses of one type."""
    rng = np.random.default_rng(seed)
    designs = designs or {t: synthesised(t) for t in synth.mechanisms.all_types()}
    types = [t for t in designs if designs[t]]
    out: list[tuple[str, dict, float | None]] = []
    for _ in range(n):
        t = types[int(rng.integers(len(types)))]
        if rng.random() < 0.8:
            params = designs[t][int(rng.integers(len(designs[t])))]
            body: dict[str, Any] = {
                "mechanism": {"type": t, "params": params},
                "load": random_load(rng),
            }
            if rng.random() < 0.7:
                body["samples"] = int(rng.integers(1, 5001))
            else:
                body["crank_angles_deg"] = rng.uniform(0, 360, int(rng.integers(1, 300))).tolist()
            if rng.random() < 0.3:
                body["include"] = ["forces"]
            out.append(("/v1/analyze", body, None))
        else:
            body = {
                "time_ratio": 1.0 if t == "scotch_yoke" else float(rng.uniform(1.2, 2.5)),
                "stroke": float(rng.uniform(1, 500)),
                "min_transmission_angle_deg": float(rng.uniform(0, 30)),
                "mechanisms": [{"type": t}],
                "max_candidates": int(rng.integers(1, 8)),
                "load": random_load(rng),
                "time_budget_ms": budget_ms,
            }
            out.append(("/v1/synthesize", body, budget_ms))
    return out


def synthesised(mtype: str) -> list[dict[str, float]]:
    """Up to ten designs of a type, at time ratio 1.5 (the yoke's 1), stroke 300 and 10°."""
    tr = 1.0 if mtype == "scotch_yoke" else 1.5
    r = synth.synthesize(tr, 300.0, 10.0, mechanisms=[mtype], max_candidates=10)
    return [c.params for c in r.candidates]


def quantiles(xs: list[float]) -> dict:
    if not xs:
        return {"p50": None, "p99": None, "max": None}
    q = statistics.quantiles(xs, n=100, method="inclusive") if len(xs) > 1 else [xs[0]] * 99
    return {"p50": q[49], "p99": q[98], "max": max(xs)}


def drive(
    port: int,
    clients: int,
    seconds: float,
    requests: int | None = None,
    bodies: list[tuple[str, dict, float | None]] | None = None,
) -> dict:
    """``clients`` keep-alive clients sending a mix (``mix()`` unless given; each client in its
    own seeded shuffle, over and over) for ``seconds`` (or until ``requests`` in all), and the
    /health prober; with the RSS of each server process before and after (MB)."""
    payloads = [
        (path, json.dumps(b).encode(), (path, budget)) for path, b, budget in (bodies or mix())
    ]
    orders = [
        itertools.cycle(random.Random(k).sample(payloads, len(payloads))) for k in range(clients)
    ]
    before = rss_mb(port)
    d = load.drive(port, orders, seconds, total=requests, probe_s=0.05)
    after = rss_mb(port)
    done = [(*s.tag, str(s.status), s.ms) for s in d.sent]  # path, budget, status, ms
    statuses = {str(k): n for k, n in load.statuses(d.sent).items()}
    errors = sum(n for k, n in statuses.items() if not k.isdigit() or (k[0] == "5" and k != "503"))
    return {
        "clients": clients,
        "requests": len(d.sent),
        "seconds": d.seconds,
        "classes": [budget_class(done, b) for b in BUDGETS_MS],
        "synthesis_wall_ms": quantiles(
            [ms for p, _, k, ms in done if p == "/v1/synthesize" and k == "200"]
        ),
        "health_ms": quantiles(d.health_ms),
        "statuses": statuses,
        "errors": errors,
        "rss_mb_before": before,
        "rss_mb_after": after,
    }


def budget_class(done: list[tuple[str, float | None, str, float]], budget: float) -> dict:
    """The syntheses and sweeps of one budget class: shares served and refused, the served
    syntheses' wall times, the refusals' against the documented wait."""
    mine = [(p, k, ms) for p, b, k, ms in done if b == budget]
    served = [ms for p, k, ms in mine if k == "200" and p == "/v1/synthesize"]
    refused = [ms for _, k, ms in mine if k == "503"]
    n, walls = max(len(mine), 1), quantiles(served)
    return {
        "budget_ms": budget,
        "requests": len(mine),
        "served": sum(k == "200" for _, k, _ in mine) / n,
        "refused": len(refused) / n,
        "synth_p99_ms": walls["p99"],
        "synth_max_ms": walls["max"],
        "wait_bound_ms": wait_bound_ms(budget),
        "refusal_max_ms": max(refused, default=None),
    }


_SERVER: dict[int, int] = {}  # port: the server's first process (``main``)


def rss_mb(port: int) -> dict[str, float]:
    """The resident memory of each process of the server on ``port`` (MB, by pid)."""
    pid = _SERVER.get(port)
    out = {}
    for p in sorted({pid, *descendants(pid)} if pid else ()):
        try:
            for line in Path(f"/proc/{p}/status").read_text().splitlines():
                if line.startswith("VmRSS:"):
                    out[str(p)] = int(line.split()[1]) / 1024
        except OSError:
            pass
    return out


def main(argv: list[str] | None = None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--quick", action="store_true", help="a smoke run: a few seconds each")
    ap.add_argument("--seconds", type=float, default=30.0, help="per mix and client count")
    a = ap.parse_args(argv)
    seconds, volume = (3.0, 500) if a.quick else (float(a.seconds), 20_000)
    loaded = loaded_mix(200 if a.quick else 2000)
    with serving("shipped", defaults=True) as (port, proc):
        _SERVER[port] = proc.pid
        drive(port, 4, seconds / 3)  # warm-up: every process's models and solvers
        rows = [drive(port, n, seconds) for n in CLIENTS]
        inline = drive(port, INLINE_CLIENTS, seconds, bodies=inline_mix())
        mixes = {
            "mixed": rows,
            "inline": [inline],
            "loaded": [drive(port, LOADED_CLIENTS, seconds, bodies=loaded)],
        }
        before = sum(rss_mb(port).values())
        memory = drive(port, 16, 600.0, requests=volume, bodies=loaded)
        after = sum(rss_mb(port).values())
    flat = [
        {
            "mix": name,
            "clients": r["clients"],
            "requests": r["requests"],
            "errors": r["errors"],
            "refused_503": r["statuses"].get("503", 0),
            "health_p50_ms": r["health_ms"]["p50"],
            "health_p99_ms": r["health_ms"]["p99"],
            "health_max_ms": r["health_ms"]["max"],
            "rss_mb_before": " ".join(f"{v:.0f}" for v in r["rss_mb_before"].values()),
            "rss_mb_after": " ".join(f"{v:.0f}" for v in r["rss_mb_after"].values()),
        }
        for name, rs in mixes.items()
        for r in rs
    ]
    print(table(flat, tuple(flat[0])))
    classes = [{"clients": r["clients"], **c} for r in rows for c in r["classes"]]
    print(table(classes, tuple(classes[0])))
    growth = {
        "requests": memory["requests"],
        "rss_before_mb": before,
        "rss_after_mb": after,
        "growth_mb": after - before,
        "errors": memory["errors"],
    }
    print(table([growth], tuple(growth)))
    return report("overload", {"rows": rows, "mixes": mixes, "memory": growth}, quick=a.quick)


if __name__ == "__main__":
    main()
