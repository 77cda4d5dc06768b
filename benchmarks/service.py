"""The service on loopback: latency p50/p95/p99 and throughput at 1, 4 and 16 clients.

    python -m benchmarks.service [--quick] [--servers shipped,...]

Starts each server configuration on a free port (``shipped`` is the command `make serve` and
the image run), waits for /health and a warm-up, then drives /v1/analyze and /v1/synthesize
with the bounded load generator (benchmarks/load.py). A share of the requests is infeasible or
invalid, as in real use: an analysis of a design that cannot be assembled (422), a synthesis
whose time ratio the linkage cannot reach (200 with a reason). The load generator runs on the
same cores as the service: the numbers are a floor for a separate client machine.
"""

from __future__ import annotations

import argparse
import os
import socket
import subprocess
import sys
import time
import urllib.request
from pathlib import Path

from . import load
from .analysis import DESIGNS
from .common import report, table

ROOT = Path(__file__).resolve().parent.parent
CLIENTS = (1, 4, 16)
INVALID_SHARE = 0.2  # one request in five: a design that cannot be assembled, an unreachable TR

_DRAG_FIXED = {"ground": 0.1, "crank": 0.225, "follower": 0.275, "connecting_rod": 0.3}


def bodies(path: str) -> list[dict]:
    """Ten bodies, two of them infeasible or invalid (INVALID_SHARE)."""
    if path == "/v1/analyze":
        good = [{"mechanism": {"type": t, "params": p}} for t, p in DESIGNS.items()]
        good += good[-2:]  # the four-bars twice: 8 valid bodies
        bad = {"type": "crank_shaper", "params": {"crank": 300.0, "pivot_distance": 240.0,
                                                  "lever": 450.0}}  # fmt: skip
        return good + [{"mechanism": bad}] * 2
    synth_body = {"stroke": 0.3, "mechanisms": [{"type": "drag_link_slider",
                                                  "fixed": _DRAG_FIXED}]}  # fmt: skip
    good = [{**synth_body, "time_ratio": 1.4 + 0.02 * k} for k in range(8)]
    return good + [{**synth_body, "time_ratio": 10.0}] * 2


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


# the configurations compared: a command (after the port is known) and its environment
_UVICORN = [sys.executable, "-m", "uvicorn", "api.main:app", "--no-access-log", "--port"]
SERVERS = {
    # what ships: a server process per core, analyses in the event loop, solver threads
    "shipped": ([sys.executable, "-m", "api.serve", "--port"], {}),
    # one server process with a pool of solver processes (what shipped before this benchmark)
    "one_process_pool": (_UVICORN, {"WEB_CONCURRENCY": "1"}),
    # the shipped split, but uvicorn's own --workers: Nagle stays on (api/serve.py)
    "uvicorn_workers": ([*_UVICORN[:-1], "--workers", "2", "--port"], {"WEB_CONCURRENCY": "2"}),
}


def serve(port: int, server: str) -> subprocess.Popen:
    cmd, settings = SERVERS[server]
    env = {k: v for k, v in os.environ.items() if k != "WEB_CONCURRENCY" and "SYNTH_" not in k}
    proc = subprocess.Popen([*cmd, str(port)], cwd=ROOT, env={**env, **settings},
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)  # fmt: skip
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline:
        try:
            with urllib.request.urlopen(f"http://127.0.0.1:{port}/health", timeout=1):
                return proc
        except OSError:
            time.sleep(0.1)
    proc.kill()
    raise RuntimeError("the service did not answer /health within 60 s")


def measure(server: str, requests: dict[str, int], seconds: float) -> list[dict]:
    port = free_port()
    proc = serve(port, server)
    rows = []
    try:
        for path in ("/v1/analyze", "/v1/synthesize"):
            mix = bodies(path)
            load.run(port, path, 2, 4 * len(mix), 60, mix)  # warm-up: workers, solvers
            for clients in CLIENTS:
                r = load.run(port, path, clients, requests[path], seconds, mix)
                rows.append({"server": server, **r})
    finally:
        proc.terminate()
        proc.wait(120)
    return rows


def main(argv: list[str] | None = None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--quick", action="store_true", help="a smoke run: few requests")
    ap.add_argument("--servers", default=",".join(SERVERS))
    a = ap.parse_args(argv)
    if a.quick:
        requests, seconds = {"/v1/analyze": 40, "/v1/synthesize": 40}, 60.0
    else:  # each cell stops at whichever comes first
        requests, seconds = {"/v1/analyze": 3000, "/v1/synthesize": 400}, 20.0
    rows = [r for s in a.servers.split(",") for r in measure(s, requests, seconds)]
    cols = ("server", "path", "clients", "requests", "throughput_rps", "p50_ms", "p95_ms",
            "p99_ms", "statuses")  # fmt: skip
    print(table(rows, cols))
    return report("service", {"invalid_share": INVALID_SHARE, "rows": rows}, quick=a.quick)


if __name__ == "__main__":
    main()
