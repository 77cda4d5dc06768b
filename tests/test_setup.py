"""The two commands on a fresh checkout: `make serve` builds .venv from the lock and answers."""

import json
import os
import shutil
import signal
import socket
import subprocess
import time
import urllib.request
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def fresh_checkout(dest: Path) -> Path:
    """The tracked files as they are in the working tree, without .venv or caches."""
    files = subprocess.run(
        ["git", "ls-files", "-z", "--cached", "--others", "--exclude-standard"],
        cwd=ROOT, capture_output=True, check=True,
    ).stdout.decode().split("\0")  # fmt: skip
    for f in filter(None, files):
        if (ROOT / f).is_file():
            (dest / f).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(ROOT / f, dest / f)
    return dest


def wait_for_health(port: int, proc: subprocess.Popen, timeout: float) -> dict:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if proc.poll() is not None:
            raise AssertionError(f"make serve exited with {proc.returncode}")
        try:
            with urllib.request.urlopen(f"http://127.0.0.1:{port}/health", timeout=1) as r:
                return json.loads(r.read())
        except OSError:
            time.sleep(0.2)
    raise AssertionError(f"no /health on port {port} within {timeout} s")


def test_readme_starts_with_the_two_commands():
    head = (ROOT / "README.md").read_text().splitlines()[:8]
    assert any(line.startswith("make serve") for line in head)
    assert any(line.startswith("make test") for line in head)


@pytest.mark.skipif(shutil.which("make") is None, reason="needs make")
def test_make_serve_on_a_fresh_checkout(tmp_path):
    work = fresh_checkout(tmp_path / "checkout")
    assert not (work / ".venv").exists()
    port = free_port()
    proc = subprocess.Popen(
        ["make", "serve", f"PORT={port}"], cwd=work, start_new_session=True,
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
        env={k: v for k, v in os.environ.items() if not k.startswith("VIRTUAL_ENV")},
    )  # fmt: skip
    try:
        assert wait_for_health(port, proc, timeout=600)["status"] == "ok"
        with urllib.request.urlopen(f"http://127.0.0.1:{port}/v1/mechanisms", timeout=5) as r:
            assert len(json.loads(r.read())) == 6
    finally:
        os.killpg(proc.pid, signal.SIGTERM)
        proc.wait(timeout=30)
