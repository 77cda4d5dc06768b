"""The two commands on a fresh checkout, and the real server over a real socket.

`make serve` must build .venv from the lock file and answer /health; the running service then
answers analyze and synthesize, and ≥ 16 parallel mixed requests each get exactly the serial
answer while the service stays up. Every command the README shows works as written, the
Dockerfile's command serves from what the Dockerfile copies, and stopping the server leaves no
process behind.
"""

import asyncio
import doctest
import json
import os
import shlex
import shutil
import signal
import socket
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

from ..support import reference_cases as ref
from ..support.server import alive, call, descendants, free_port, wait_for_health

ROOT = Path(__file__).resolve().parents[2]


def fresh_checkout(dest: Path) -> Path:
    """The tracked files as they are in the working tree, without .venv or caches."""
    files = (
        subprocess.run(
            ["git", "ls-files", "-z", "--cached", "--others", "--exclude-standard"],
            cwd=ROOT,
            capture_output=True,
            check=True,
        )
        .stdout.decode()
        .split("\0")
    )
    for f in filter(None, files):
        if (ROOT / f).is_file():
            (dest / f).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(ROOT / f, dest / f)
    return dest


def test_readme_starts_with_the_two_commands():
    head = (ROOT / "README.md").read_text().splitlines()[:8]
    assert any(line.startswith("make serve") for line in head)
    assert any(line.startswith("make test") for line in head)


def chosen_python(tmp_path: Path, versions: dict[str, str], *args: str):
    """What `make python` says with only these interpreters on the PATH: each name runs this
    Python with ``sys.version_info`` set to its version, so the Makefile's own check runs."""
    bin_dir = tmp_path / "bin"
    bin_dir.mkdir()
    for name, version in versions.items():
        fake = bin_dir / name
        info = tuple(int(x) for x in version.split("."))
        # `name -c CODE`: CODE runs as in that Python (only the version differs)
        code = f"import sys; sys.version_info = {info}; exec(sys.argv[1])"
        fake.write_text(f'#!/bin/sh\nexec {sys.executable} -c "{code}" "$2"\n')
        fake.chmod(0o755)
    (bin_dir / "echo").symlink_to(shutil.which("echo"))  # make runs `@echo …` without a shell
    make = shutil.which("make")
    env = {"PATH": str(bin_dir), "HOME": str(tmp_path)}
    return subprocess.run(
        [make, "-s", "-C", str(ROOT), "python", *args], env=env, capture_output=True, text=True
    )


@pytest.mark.parametrize(
    ("versions", "want"),
    [
        ({"python3.13": "3.13.1", "python3.12": "3.12.3", "python3.11": "3.11.7"}, "python3.13"),
        ({"python3.12": "3.12.3", "python3.11": "3.11.7"}, "python3.12"),
        ({"python3.11": "3.11.7", "python3": "3.11.7"}, "python3.11"),
        ({"python3": "3.12.8"}, "python3"),  # only the unversioned name, and it fits
        ({"python3.13": "3.10.0", "python3": "3.13.0"}, "python3"),  # a name that lies
        ({"python3": "3.10.12"}, None),  # too old
        ({"python3": "3.14.0"}, None),  # too new for the lock
        ({}, None),
    ],
)
def test_make_picks_the_newest_supported_python(tmp_path, versions, want):
    if shutil.which("make") is None:
        pytest.skip("needs make")
    r = chosen_python(tmp_path, versions)
    if want is None:
        assert r.returncode != 0 and r.stdout == ""
        assert "no Python 3.11, 3.12 or 3.13 found" in r.stderr and "PYTHON=" in r.stderr
    else:
        assert (r.returncode, r.stdout.strip()) == (0, want), r.stderr


def test_make_takes_the_python_it_is_given(tmp_path):
    if shutil.which("make") is None:
        pytest.skip("needs make")
    r = chosen_python(tmp_path, {"python3.12": "3.12.3"}, "PYTHON=/opt/py/bin/python3")
    assert (r.returncode, r.stdout.strip()) == (0, "/opt/py/bin/python3")


@pytest.fixture(scope="module")
def served(tmp_path_factory):
    """`make serve` on a fresh checkout: (its port, the checkout with the .venv it built)."""
    if shutil.which("make") is None:
        pytest.skip("needs make")
    work = fresh_checkout(tmp_path_factory.mktemp("fresh") / "checkout")
    assert not (work / ".venv").exists()
    port = free_port()
    proc = subprocess.Popen(
        ["make", "serve", f"PORT={port}"],
        cwd=work,
        start_new_session=True,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        env={
            k: v
            for k, v in os.environ.items()
            if not k.startswith("VIRTUAL_ENV") and k != "SYNTH_WARM"
        },  # as shipped
    )
    try:
        assert wait_for_health(port, proc, timeout=600)["status"] == "ok"
        yield port, work
    finally:
        os.killpg(proc.pid, signal.SIGTERM)
        proc.wait(timeout=120)


@pytest.fixture(scope="module")
def server(served):
    return served[0]


ANALYZE = {
    "mechanism": {
        "type": "drag_link_slider",
        "params": {**ref.DRAG_LINK_PROJECT, "coupler": 0.2504},
    },
    "crank_speed": 10.0,
    "crank_angles_deg": [60.0],
}
SHAPER = {
    "mechanism": {
        "type": "crank_shaper",
        "params": {"crank": 40, "pivot_distance": 160, "lever": 240},
    },
    "samples": 360,
}
PROJECT = {
    "time_ratio": 1.5,
    "stroke": 0.3,
    "mechanisms": [
        {"type": "drag_link_slider", "fixed": {**ref.DRAG_LINK_FIXED, "connecting_rod": 0.3}}
    ],
}
TEXTBOOK = {
    "time_ratio": 2.73524,
    "stroke": 300.0,
    "time_budget_ms": 1000,
    "mechanisms": [{"type": "whitworth", "fixed": {"pivot_distance": 50}}],
}
MIXED = [
    ("/v1/analyze", ANALYZE),
    ("/v1/analyze", SHAPER),
    ("/v1/synthesize", PROJECT),
    ("/v1/synthesize", TEXTBOOK),
]


def stable(body: dict) -> dict:
    return {k: v for k, v in body.items() if k != "elapsed_ms"}


@pytest.mark.long  # tens of seconds: make long (CI runs it), not make test
def test_make_serve_on_a_fresh_checkout_answers_over_a_socket(server):
    status, out = call(server, "/v1/analyze", ANALYZE)
    assert status == 200 and out["time_ratio"] == pytest.approx(1.49995, abs=1e-5)
    status, out = call(server, "/v1/synthesize", PROJECT)
    assert status == 200
    assert [c["params"]["coupler"] for c in out["candidates"]] == pytest.approx(
        [0.2504, 0.1544], abs=1e-4
    )
    status, out = call(server, "/v1/analyze", {"mechanism": {"type": "cam", "params": {}}})
    assert status == 422


def test_parallel_mixed_requests_match_the_serial_answers(server):
    serial = [stable(call(server, path, body)[1]) for path, body in MIXED]
    jobs = [MIXED[k % len(MIXED)] for k in range(32)]
    with ThreadPoolExecutor(16) as pool:
        answers = list(pool.map(lambda job: call(server, *job), jobs))
    for k, (status, body) in enumerate(answers):
        assert status == 200
        assert stable(body) == serial[k % len(MIXED)]
    assert call(server, "/health")[1]["status"] == "ok"


def test_the_listener_gives_connections_tcp_nodelay():
    """uvicorn --workers leaves Nagle on (uvicorn #3149): ~40 ms per keep-alive request."""
    from api.serve import listener

    async def accepted() -> int:
        got = asyncio.get_running_loop().create_future()

        def made(transport):
            sock = transport.get_extra_info("socket")
            got.set_result(sock.getsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY))
            transport.close()

        sock = listener("127.0.0.1", 0)
        proto = type("P", (asyncio.Protocol,), {"connection_made": lambda self, t: made(t)})
        server = await asyncio.get_running_loop().create_server(proto, sock=sock)
        _, writer = await asyncio.open_connection(*sock.getsockname())
        try:
            return await asyncio.wait_for(got, 10)
        finally:
            writer.close()
            server.close()

    assert asyncio.run(accepted()) == 1


def test_sigterm_to_the_server_stops_every_process_it_started():
    """Only the parent gets the signal (as from an orchestrator): its server processes and
    their solver processes must not be left running."""
    port = free_port()
    env = {**os.environ, "WEB_CONCURRENCY": "2", "SYNTH_EXECUTOR": "process"}
    proc = subprocess.Popen(
        [sys.executable, "-m", "api.serve", "--port", str(port)],
        cwd=ROOT,
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    try:
        wait_for_health(port, proc, timeout=120)
        assert call(port, "/v1/synthesize", PROJECT)[0] == 200  # the pools have started
        started = descendants(proc.pid)
        assert len(started) >= 4  # two server processes, each with its solver processes
    finally:
        proc.send_signal(signal.SIGTERM)
        proc.wait(timeout=120)
    deadline = time.monotonic() + 30
    while any(map(alive, started)) and time.monotonic() < deadline:
        time.sleep(0.2)
    assert not [p for p in started if alive(p)]


# --- the README: every command in it works as written ---------------------------------------


def readme_console_commands() -> list[tuple[str, str]]:
    """(command, shown output) for each ``$ `` line of the README's console blocks."""
    out, block = [], None
    for line in (ROOT / "README.md").read_text().splitlines():
        if line.startswith("```"):
            block = [] if line == "```console" and block is None else None
            continue
        if block is None:
            continue
        if line.startswith("$ "):
            out.append([line[2:], []])
        elif out:
            out[-1][1].append(line)
    return [(cmd, "\n".join(shown)) for cmd, shown in out]


def same(shown, got, path="") -> None:
    """JSON equal to 1e-9 relative on floats; elapsed_ms (wall time) is not compared."""
    if isinstance(shown, dict):
        keys = set(shown) - {"elapsed_ms"}
        assert keys == set(got) - {"elapsed_ms"}, path
        for k in keys:
            same(shown[k], got[k], f"{path}.{k}")
    elif isinstance(shown, list):
        assert len(shown) == len(got), path
        for i, (a, b) in enumerate(zip(shown, got, strict=True)):
            same(a, b, f"{path}[{i}]")
    elif isinstance(shown, float) and isinstance(got, float):
        assert got == pytest.approx(shown, rel=1e-9, abs=1e-12), path
    else:
        assert shown == got, path


def test_the_readme_shows_a_curl_for_every_endpoint():
    commands = " ".join(cmd for cmd, _ in readme_console_commands())
    for path in (
        "/health",
        "/v1/mechanisms",
        "/v1/mechanisms/",
        "/v1/analyze",
        "/v1/synthesize",
        "/v1/sweep",
        "/v1/export",
    ):
        assert f"localhost:8000{path}" in commands, path


def test_every_readme_command_gives_the_output_shown(server):
    """Run as written, against `make serve` on a fresh checkout (its port for 8000)."""
    assert shutil.which("curl"), "the README's commands use curl"
    for cmd, shown in readme_console_commands():
        got = subprocess.run(
            ["bash", "-c", cmd.replace("localhost:8000", f"localhost:{server}")],
            capture_output=True,
            text=True,
            timeout=120,
            check=True,
        ).stdout.strip()
        try:
            expected = json.loads(shown)
        except json.JSONDecodeError:
            assert got == shown, cmd
        else:
            same(expected, json.loads(got))


def test_the_readme_python_examples_run():
    failed, tried = doctest.testfile(
        str(ROOT / "README.md"),
        module_relative=False,
        optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE,
    )
    assert tried >= 5 and failed == 0


# --- the Dockerfile, without a Docker engine ------------------------------------------------


def dockerfile() -> dict[str, dict[str, list[str]]]:
    """Stage name -> instruction -> its arguments, in order (continuation lines joined); the
    last stage is the image, under the name ""."""
    text = (ROOT / "Dockerfile").read_text().replace("\\\n", " ")
    stages: list[tuple[str, dict[str, list[str]]]] = []
    for line in text.splitlines():
        if line.strip() and not line.lstrip().startswith("#"):
            word, _, rest = line.strip().partition(" ")
            if word.upper() == "FROM":
                base, _, name = rest.partition(" AS ")
                stages.append((name.strip(), {"FROM": [base.strip()]}))
            elif stages:  # (an ARG before the first FROM is the build's, for the FROMs)
                stages[-1][1].setdefault(word.upper(), []).append(rest.strip())
    *built, (_, image) = stages
    return dict(built) | {"": image}


@pytest.mark.long  # tens of seconds: make long (CI runs it), not make test
def test_the_dockerfile_runs_the_service_from_what_it_copies(served, tmp_path):
    """The image's stages played out on this machine: the base's files and install, the
    compiled analysis built in the native stage, then the image (no compiler) serving."""
    work = served[1]
    d = dockerfile()
    base, native, image = d["base"], d["native"], d[""]
    assert base["FROM"] == ["${BASE}"]  # the build argument: the tag, or a digest given
    assert "BASE=python:3.11-slim" in (ROOT / "Dockerfile").read_text()
    assert native["FROM"] == image["FROM"] == ["base"]
    # the install step is the lock make serve installed into the fresh checkout's .venv
    installs = [r for stage in d.values() for r in stage.get("RUN", []) if "pip install" in r]
    assert installs == [r for r in base["RUN"] if "pip install" in r] and len(installs) == 2
    assert "--require-hashes -r requirements.lock" in installs[0]
    assert installs[1].endswith("--no-deps --no-build-isolation .")  # the project, nothing else
    assert image["USER"] and image["USER"][-1] not in ("root", "0")
    assert image["EXPOSE"] == ["8000"]
    # the build context leaves out the checkout's environment and history (a 1 GB .venv)
    ignored = (ROOT / ".dockerignore").read_text().split()
    assert {".venv", ".git", "build"} <= set(ignored)
    root = tmp_path / "root"  # the image's file system: absolute paths land under it

    def at(path: str) -> str:
        return str(root / path.lstrip("/")) if path.startswith("/") else path

    # the base's /app: only what its COPYs bring
    app = Path(at(base["WORKDIR"][0]))
    for args in base["COPY"]:
        src, dest = args.split()
        target = app / dest if dest not in (".", "./") else app / src
        if (work / src).is_dir():
            shutil.copytree(work / src, target)
        else:
            target.parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(work / src, target)

    # the project's install from what the base copied (into a folder here, not the venv)
    project = installs[1].split("pip install ", 1)[1].split()
    site = tmp_path / "site"
    subprocess.run(
        [
            str(work / ".venv/bin/python"),
            "-m",
            "pip",
            "install",
            "--quiet",
            *project[:-1],
            "--target",
            str(site),
            project[-1],
        ],
        cwd=app,
        check=True,
        timeout=300,
    )
    assert (site / "bin" / "quickreturn").exists() and (site / "api" / "static").is_dir()

    def environment(stage) -> dict[str, str]:
        pairs = [shlex.split(e) for e in stage["ENV"]]
        env = dict(pair.split("=", 1) for p in pairs for pair in p)
        return {k: at(v) for k, v in env.items()} | {
            "PATH": f"{work / '.venv/bin'}:{os.environ['PATH']}",
            "HOME": str(tmp_path),
        }

    # the native stage: its compiler is this machine's; its build writes the libraries
    (build,) = [r for r in native["RUN"] if "apt-get" not in r]
    subprocess.run(["sh", "-c", build], cwd=app, env=environment(base), check=True, timeout=300)
    (copy,) = image["COPY"]
    src, dest = copy.removeprefix("--from=native ").split()
    assert Path(at(src)).is_dir() and at(src) == at(dest)  # the same folder, now in the image
    # the image: no compiler, and every type's analysis compiled from the libraries it carries
    env = environment(base) | {"CC": str(tmp_path / "no-compiler")}
    probe = (
        "from synth.analysis.model import model; from synth.mechanisms import all_types, get; "
        "print({model(get(t), frozenset()).fn.fn.class_name() for t in all_types()})"
    )
    out = subprocess.run(
        ["python", "-c", probe],
        cwd=app,
        env=env,
        check=True,
        capture_output=True,
        text=True,
        timeout=120,
    ).stdout
    assert out.strip() == "{'External'}", out
    cmd = json.loads(image["CMD"][0])
    assert cmd[:3] == ["python", "-m", "api.serve"] and "--port" not in cmd  # PORT's
    image_port = free_port()
    env |= {"PORT": str(image_port)}  # docker run -e PORT=…
    proc = subprocess.Popen(
        cmd, cwd=app, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL
    )
    try:
        wait_for_health(image_port, proc, timeout=120)
        health = image["HEALTHCHECK"][0].split(" CMD ", 1)[1]
        assert subprocess.run(["sh", "-c", health], cwd=app, env=env, timeout=30).returncode == 0
        status, out = call(image_port, "/v1/synthesize", PROJECT)
        assert status == 200 and len(out["candidates"]) == 2
    finally:
        proc.send_signal(signal.SIGTERM)
        proc.wait(timeout=120)
