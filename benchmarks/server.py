"""The real server on loopback, for the benchmarks and for tests that go over a socket: a
configuration (``SERVERS``; ``shipped`` is the command `make serve` and the image run) started
on a free port, awaited on /health, and stopped with every process it started."""

from __future__ import annotations

import contextlib
import json
import os
import signal
import socket
import subprocess
import sys
import tempfile
import time
import urllib.error
import urllib.request
from collections.abc import Iterator
from pathlib import Path
from typing import IO, Any

from .common import descendants

ROOT = Path(__file__).resolve().parent.parent
HEALTH_S = 120  # how long a server may take to answer /health after its start
STOP_S = 30  # how long after SIGTERM its processes may take to end, before SIGKILL

# the configurations: a command (the port follows it) and its environment
_UVICORN = [sys.executable, "-m", "uvicorn", "api.main:app", "--no-access-log", "--port"]
SERVERS: dict[str, tuple[list[str], dict[str, str]]] = {
    # what ships: a server process per core, analyses in the event loop, solver threads
    "shipped": ([sys.executable, "-m", "api.serve", "--port"], {}),
    # one server process with a pool of solver processes
    "one_process_pool": (_UVICORN, {"WEB_CONCURRENCY": "1"}),
    # the shipped split, but uvicorn's own --workers: Nagle stays on (api/serve.py)
    "uvicorn_workers": ([*_UVICORN[:-1], "--workers", "2", "--port"], {"WEB_CONCURRENCY": "2"}),
    # not the service: a bare ASGI app served as `shipped` is (benchmarks/bare.py)
    "bare": ([sys.executable, "-m", "benchmarks.bare", "--port"], {}),
}


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def call(port: int, path: str, body: dict[str, Any] | None = None) -> tuple[int, Any]:
    """GET ``path`` (POST ``body`` as JSON): the status and the answer's JSON."""
    data = None if body is None else json.dumps(body).encode()
    req = urllib.request.Request(
        f"http://127.0.0.1:{port}{path}", data=data, headers={"Content-Type": "application/json"}
    )
    try:
        with urllib.request.urlopen(req, timeout=120) as r:
            return r.status, json.loads(r.read())
    except urllib.error.HTTPError as e:
        return e.code, json.loads(e.read())


def wait_for_health(port: int, proc: subprocess.Popen[bytes], timeout: float) -> Any:
    """/health's answer once the server on ``port`` gives one; an error if ``proc`` exits or
    ``timeout`` seconds pass first."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if proc.poll() is not None:
            raise RuntimeError(f"the server exited with {proc.returncode}")
        try:
            return call(port, "/health")[1]
        except OSError:
            time.sleep(0.2)
    raise RuntimeError(f"no /health on port {port} within {timeout} s")


@contextlib.contextmanager
def serving(
    server: str = "shipped", *, defaults: bool = False, **env: str
) -> Iterator[tuple[int, subprocess.Popen[bytes]]]:
    """``SERVERS[server]`` on a free port, warming up as shipped, with this process's
    environment and ``env`` added; with ``defaults``, none of this environment's settings
    (``SYNTH_*``, ``WEB_CONCURRENCY``): the configuration's own. Stopped at the end with
    SIGTERM, then SIGKILL to whatever of it is left."""
    cmd, settings = SERVERS[server]
    base = {
        k: v
        for k, v in os.environ.items()
        if not defaults or (k != "WEB_CONCURRENCY" and "SYNTH_" not in k)
    }
    port = free_port()
    environment = {**base, "SYNTH_WARM": "1", **settings, **env}
    processes = int(environment.get("WEB_CONCURRENCY") or len(os.sched_getaffinity(0)))
    with tempfile.TemporaryFile() as log:
        proc = subprocess.Popen(
            [*cmd, str(port)], cwd=ROOT, env=environment, stdout=subprocess.DEVNULL, stderr=log
        )
        started: set[int] = set()
        try:
            wait_for_health(port, proc, timeout=HEALTH_S)
            ready(log, processes, proc, timeout=HEALTH_S)
            started = descendants(proc.pid)
            yield port, proc
        finally:
            started |= descendants(proc.pid)
            proc.send_signal(signal.SIGTERM)
            try:
                proc.wait(timeout=STOP_S)
            finally:
                for pid in started | ({proc.pid} if proc.poll() is None else set()):
                    with contextlib.suppress(OSError):
                        os.kill(pid, signal.SIGKILL)


def ready(log: IO[bytes], processes: int, proc: subprocess.Popen[bytes], timeout: float) -> None:
    """Wait until each of a server's ``processes`` has said in its ``log`` (uvicorn's) that its
    start-up (the warm-up) is complete: the first /health comes from the first one ready, and
    a test that starts right after it would meet the others still warming."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline and proc.poll() is None:
        log.seek(0)
        if log.read().count(b"Application startup complete") >= processes:
            return
        time.sleep(0.05)
    raise RuntimeError(f"not every one of {processes} server processes started in {timeout} s")
