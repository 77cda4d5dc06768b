"""The real server for tests that go over a socket: started as `make serve` starts it, its
processes found from /proc (``descendants``, which the benchmarks use too)."""

from __future__ import annotations

import contextlib
import json
import os
import signal
import socket
import subprocess
import sys
import time
import urllib.request
from collections.abc import Iterator
from pathlib import Path

from benchmarks.common import descendants

ROOT = Path(__file__).resolve().parents[2]


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def call(port: int, path: str, body: dict | None = None) -> tuple[int, dict]:
    data = None if body is None else json.dumps(body).encode()
    req = urllib.request.Request(
        f"http://127.0.0.1:{port}{path}", data=data, headers={"Content-Type": "application/json"}
    )
    try:
        with urllib.request.urlopen(req, timeout=120) as r:
            return r.status, json.loads(r.read())
    except urllib.error.HTTPError as e:
        return e.code, json.loads(e.read())


def wait_for_health(port: int, proc: subprocess.Popen, timeout: float) -> dict:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if proc.poll() is not None:
            raise AssertionError(f"the server exited with {proc.returncode}")
        try:
            return call(port, "/health")[1]
        except OSError:
            time.sleep(0.2)
    raise AssertionError(f"no /health on port {port} within {timeout} s")


@contextlib.contextmanager
def serving(**env: str) -> Iterator[tuple[int, subprocess.Popen]]:
    """``python -m api.serve`` (the command `make serve` runs) on a free port, as shipped
    (warming up) with ``env`` added; stopped with SIGTERM at the end (SIGKILL to what is left)."""
    port = free_port()
    proc = subprocess.Popen(
        [sys.executable, "-m", "api.serve", "--port", str(port)], cwd=ROOT,
        env={**os.environ, "SYNTH_WARM": "1", **env},
        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
    )  # fmt: skip
    started: set[int] = set()
    try:
        wait_for_health(port, proc, timeout=120)
        started = descendants(proc.pid)
        yield port, proc
    finally:
        started |= descendants(proc.pid)
        proc.send_signal(signal.SIGTERM)
        try:
            proc.wait(timeout=30)
        finally:
            for pid in {proc.pid, *started}:
                with contextlib.suppress(OSError):
                    os.kill(pid, signal.SIGKILL)


def alive(pid: int) -> bool:
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False
