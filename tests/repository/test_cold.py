"""`make bench`'s cold processes (benchmarks/cold.py) in their quick form, and the suite's record
of its own wall time and peak memory (tests/conftest.py), which that benchmark reports: asked
for, a pytest run appends one well-formed record, with the peaks of its xdist workers and of
their subprocesses; not asked for, none. Timings are printed, never asserted."""

import json
import os
import subprocess
import sys
from pathlib import Path

from benchmarks import cold

RECORD_VARIABLE = cold.SUITE_VARIABLE  # the one tests/conftest.py reads

ROOT = Path(__file__).resolve().parents[2]
MIB = 2**20 / 1e6  # MB in a MiB
# a tiny suite: one test holds 64 MiB in its worker, one starts a subprocess that holds 400
# MiB, one fails, and none sees the variable that asked for the record
TINY = f"""
import os
import subprocess
import sys


def test_holds_memory():
    block = b"x" * (64 * 2**20)
    assert len(block) == 64 * 2**20


def test_a_subprocess_holds_more():
    subprocess.run([sys.executable, "-c", "b = b'x' * (400 * 2**20)"], check=True)


def test_the_variable_is_not_passed_on():
    assert {RECORD_VARIABLE!r} not in os.environ


def test_fails():
    assert False
"""


def run_tiny(tmp: Path, *args: str, record: Path | None) -> subprocess.CompletedProcess[str]:
    """pytest on the tiny suite in ``tmp``, with this repository's conftest as a plugin."""
    (tmp / "pytest.ini").write_text("[pytest]\n")
    (tmp / "test_tiny.py").write_text(TINY)
    env = {k: v for k, v in os.environ.items() if k != RECORD_VARIABLE}
    env["PYTHONPATH"] = str(ROOT)
    if record is not None:
        env[RECORD_VARIABLE] = str(record)
    return subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-p", "tests.conftest", *args, "test_tiny.py"],
        cwd=tmp,
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
    )


def test_the_suite_records_itself_when_asked(tmp_path):
    record = tmp_path / "results" / "suite.jsonl"
    parallel = run_tiny(tmp_path, "-n", "2", record=record)
    assert parallel.returncode == 1, parallel.stdout + parallel.stderr  # the one failure
    assert "suite (parallel): " in parallel.stdout, parallel.stdout
    serial = run_tiny(tmp_path, record=record)
    assert serial.returncode == 1, serial.stdout + serial.stderr
    lines = record.read_text().splitlines()
    assert len(lines) == 2, lines
    said = parallel.stdout[-3000:] + serial.stdout[-3000:]  # for a failure's message
    first, second = (json.loads(line) for line in lines)
    commit = subprocess.run(
        ["git", "rev-parse", "HEAD"], cwd=ROOT, capture_output=True, text=True, check=True
    ).stdout.strip()
    for r, run, workers in ((first, "parallel", 2), (second, "serial", 0)):
        assert r["run"] == run and r["workers"] == workers, (r, said)
        assert (r["passed"], r["failed"], r["errors"]) == (3, 1, 0), (r, said)
        assert r["exit_status"] == 1 and r["paths"] == ["test_tiny.py"], r
        assert r["wall_s"] > 0 and r["code"]["commit"] == commit, r
        # the largest process: the subprocess with its 400 MiB (of a worker, when in parallel)
        assert r["peak_mb"] >= 400 * MIB, r
        assert r["controller_mb"] > 0 and r["controller_mb"] <= r["peak_mb"], r
    # which process: a subprocess, unless the tiny suite's controller was forked from a larger
    # process (a worker of this suite), whose high-water mark Linux counts as the child's own
    largest = ("a subprocess of gw0", "a subprocess of gw1", "controller")
    assert first["peak_process"] in largest, first
    assert second["peak_process"] in ("a subprocess", "controller"), second
    # the worker that ran the 64 MiB test held it, and the sum holds both workers
    assert set(first["workers_mb"]) == {"gw0", "gw1"}, first
    assert max(first["workers_mb"].values()) >= 64 * MIB, first
    summed = sum(first["workers_mb"].values())
    assert abs(first["workers_sum_mb"] - summed) < 0.2, first  # each rounded to 0.1 MB
    assert first["workers_sum_mb"] > max(first["workers_mb"].values()), first
    # the benchmark reads them: the latest of each run
    assert cold.latest(cold.records(record)) == [first, second]


def test_the_suite_does_not_record_unless_asked(tmp_path):
    out = run_tiny(tmp_path, record=None)
    assert out.returncode == 1, out.stdout + out.stderr
    assert "suite (serial): " in out.stdout and "recorded in" not in out.stdout, out.stdout
    assert not list(tmp_path.rglob("*.jsonl"))


def test_cold_benchmark_quick():
    out = cold.main(["--quick"])
    assert [r["command"] for r in out["cold"]] == [what for what, _, _ in cold.COMMANDS]
    for r in out["cold"]:
        assert r["runs"] == 1 and r["median_s"] > 0 and r["peak_mb"] > 0, r
        assert ("import_s" in r) == r["command"].startswith("import "), r
        assert ("met" in r) == (r["command"] in cold.TARGETS), r
    baseline = next(r for r in out["cold"] if r["command"] == cold.BASELINE)
    assert baseline["times_baseline"] == 1.0 and baseline["import_times_baseline"] == 1.0
    assert not out["suite"]["ran"]
