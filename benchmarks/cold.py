"""Cold processes: what a fresh interpreter costs before it answers, and what `make test` costs.

    python -m benchmarks.cold [--quick] [--suite] [--rounds N] [--records FILE] [--root DIR]

- ``cold``: each command of ``COMMANDS`` in a fresh process (a new interpreter each time; the
  operating system's file cache, the bytecode, written by a round untimed before, and the
  disk cache of compiled functions, ``SYNTH_CACHE`` as ``make`` builds it, are warm), run
  ``ROUNDS`` times in turn, the order rotated from round
  to round so that no command always follows the same one: the median wall time from start
  to exit, its minimum and maximum, the median of its ratio to the baseline's
  (``import casadi, numpy`` in its own process) of the same round, and the median peak
  resident memory of the process; for the imports, also the import alone, timed inside the
  process (its interpreter's start left out), and its ratio to the baseline's import. The
  targets on a quiet machine: ``import synth`` ≤ 1.5 × ``import casadi, numpy``,
  ``quickreturn --help`` ≤ 0.3 s, a one-type ``quickreturn synthesize`` ≤ 1 s;
- ``suite``: `make test`'s wall time and peak resident memory, as the suite records them
  itself (``tests/conftest.py``: one JSON line per pytest run appended to the file
  ``SYNTH_SUITE_RECORD`` names, here ``results/suite.jsonl``): the latest record of each run
  (the parallel one and the serial one). ``--suite`` runs `make test` first with the
  records asked for (about 13 minutes on 2 cores), and reports the two it wrote and the wall
  time of the whole `make test`; without it, the suite does not run.

``--root``: the checkout to measure (another commit's, e.g. unpacked by ``git archive``), with
this interpreter; the command line is then run as its console script would be, with
``python -c`` in that checkout. The machine's load moves every number: read the medians and
the ratios, which compare commands measured in turn.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from .common import RESULTS, report, table
from .server import ROOT

ROUNDS = 15
BASELINE = "import casadi, numpy"
SUITE_RECORDS = RESULTS / "suite.jsonl"
SUITE_VARIABLE = "SYNTH_SUITE_RECORD"  # the variable tests/conftest.py reads
SYNTHESIZE = ["synthesize", "--time-ratio", "1.6", "--stroke", "300", "--type"]
# what the console script `quickreturn` runs (pip writes it so), for a checkout that has none
CONSOLE = "import sys; from synth.cli import main; sys.argv[0] = 'quickreturn'; sys.exit(main())"


# The launcher of each run, a small interpreter (no site): it forks, the child runs the command,
# and it writes the command's wall seconds and peak resident memory (kB) to the file argv[1].
# A child's peak counts the memory of the process it was forked from, so the command is not
# started from the benchmark's own, larger, process; and the time to start the launcher is
# left out.
LAUNCH = """
import os, sys, time
t = time.perf_counter()
pid = os.fork()
if pid == 0:
    try:
        os.execv(sys.argv[2], sys.argv[2:])
    finally:
        os._exit(127)
_, status, usage = os.wait4(pid, 0)
wall = time.perf_counter() - t
code = os.waitstatus_to_exitcode(status)
if code == 0:
    with open(sys.argv[1], "w") as f:
        f.write(f"{wall} {usage.ru_maxrss}")
sys.exit(code)
"""


def import_code(modules: str) -> str:
    """A program that imports ``modules`` and prints the seconds the import took."""
    return f"import time; t = time.perf_counter(); import {modules}; print(time.perf_counter() - t)"


# (what is run, whether it prints its import's seconds, the quickreturn arguments or the
# program for `python -c`)
COMMANDS: list[tuple[str, bool, list[str] | str]] = [
    ("python -c pass", False, "pass"),
    (BASELINE, True, import_code("casadi, numpy")),
    ("import synth", True, import_code("synth")),
    ("quickreturn --help", False, ["--help"]),
    ("quickreturn synthesize --type whitworth", False, [*SYNTHESIZE, "whitworth"]),
    (
        "quickreturn synthesize --type crank_rocker_slider",
        False,
        [*SYNTHESIZE, "crank_rocker_slider"],
    ),
]
TARGETS = {
    "import synth": ("≤ 1.5 × baseline", lambda r: r["times_baseline"] <= 1.5),
    "quickreturn --help": ("≤ 0.3 s", lambda r: r["median_s"] <= 0.3),
    "quickreturn synthesize --type whitworth": ("≤ 1 s", lambda r: r["median_s"] <= 1.0),
    "quickreturn synthesize --type crank_rocker_slider": ("≤ 1 s", lambda r: r["median_s"] <= 1.0),
}


def argv_of(command: list[str] | str, root: Path) -> list[str]:
    """The process to start: ``python -c`` for a program, else the console script
    `quickreturn` beside this interpreter (what a user runs), or for another checkout its
    equivalent."""
    if isinstance(command, str):
        return [sys.executable, "-c", command]
    script = Path(sys.executable).parent / "quickreturn"
    if root == ROOT and script.is_file():
        return [str(script), *command]
    return [sys.executable, "-c", CONSOLE, *command]


def run_once(argv: list[str], root: Path, env: dict[str, str]) -> tuple[float, float, str]:
    """One cold run of ``argv`` in ``root`` with the environment ``env``, started by
    ``LAUNCH``: its wall seconds from start to exit, its peak resident memory (MB) and what it
    printed; an exit status other than 0 raises."""
    with tempfile.TemporaryDirectory() as tmp:
        out, err, got = (Path(tmp) / name for name in ("out", "err", "got"))
        with out.open("wb") as o, err.open("wb") as e:
            launch = [sys.executable, "-I", "-S", "-c", LAUNCH, str(got), *argv]
            status = subprocess.run(launch, cwd=root, env=env, stdout=o, stderr=e).returncode
        if status != 0 or not got.is_file():
            raise RuntimeError(f"{argv} exited with {status}: {err.read_text()[-2000:]}")
        wall, kb = got.read_text().split()
        return float(wall), int(kb) * 1024 / 1e6, out.read_text()


def cold(root: Path, rounds: int) -> list[dict]:
    """Every command of ``COMMANDS`` ``rounds`` times in turn, in a fresh process each, after
    a round untimed that writes their bytecode (to a folder of this run's: a first run's
    state, whether or not the environment says not to write it) and reads their files."""
    walls: dict[str, list[float]] = {what: [] for what, _, _ in COMMANDS}
    imports: dict[str, list[float]] = {what: [] for what, timed, _ in COMMANDS if timed}
    peaks: dict[str, list[float]] = {what: [] for what, _, _ in COMMANDS}
    with tempfile.TemporaryDirectory() as bytecode:
        env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
        env["PYTHONPYCACHEPREFIX"] = bytecode
        for _, _, command in COMMANDS:
            run_once(argv_of(command, root), root, env)
        for i in range(rounds):
            turn = COMMANDS[i % len(COMMANDS) :] + COMMANDS[: i % len(COMMANDS)]
            for what, timed, command in turn:
                wall, peak, printed = run_once(argv_of(command, root), root, env)
                walls[what].append(wall)
                peaks[what].append(peak)
                if timed:
                    imports[what].append(float(printed))
    rows = []
    for what, _, _ in COMMANDS:
        row = {
            "command": what,
            "median_s": statistics.median(walls[what]),
            "min_s": min(walls[what]),
            "max_s": max(walls[what]),
            # per round, against the baseline of the same round
            "times_baseline": statistics.median(
                w / b for w, b in zip(walls[what], walls[BASELINE], strict=True)
            ),
            "peak_mb": statistics.median(peaks[what]),
            "runs": len(walls[what]),
        }
        if what in imports:
            row["import_s"] = statistics.median(imports[what])
            row["import_times_baseline"] = statistics.median(
                t / b for t, b in zip(imports[what], imports[BASELINE], strict=True)
            )
        if what in TARGETS:
            target, met = TARGETS[what]
            row["target"], row["met"] = target, met(row)
        rows.append(row)
    return rows


def records(path: Path) -> list[dict]:
    """The suite's records in ``path``, oldest first (none if it does not exist)."""
    if not path.is_file():
        return []
    return [json.loads(line) for line in path.read_text().splitlines() if line.strip()]


def latest(found: list[dict]) -> list[dict]:
    """The latest record of each run (parallel, serial), in that order."""
    last = {r["run"]: r for r in found}
    return [last[run] for run in ("parallel", "serial") if run in last]


def make_test(root: Path, path: Path) -> float:
    """`make test` in ``root`` with the suite's records asked for into ``path``: its wall
    seconds (its exit status is the suite's: failures are in the records)."""
    t0 = time.monotonic()
    subprocess.run(
        ["make", "--no-print-directory", "test"],
        cwd=root,
        env={**os.environ, SUITE_VARIABLE: str(path)},
    )
    return time.monotonic() - t0


def suite_rows(found: list[dict]) -> list[dict]:
    """The records as the table shows them."""
    return [
        {
            "run": r["run"],
            "date_utc": r["date_utc"],
            "commit": (r["code"]["commit"] or "")[:7] + ("+" if r["code"]["changed_files"] else ""),
            "paths": " ".join(r["paths"]),
            "markers": r["markers"],
            "wall_s": r["wall_s"],
            "peak_mb": r["peak_mb"],
            "peak_process": r["peak_process"],
            "workers": r["workers"],
            "workers_sum_mb": r["workers_sum_mb"],
            "passed": r["passed"],
            "failed": r["failed"],
            "errors": r["errors"],
        }
        for r in found
    ]


def main(argv: list[str] | None = None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--quick", action="store_true", help="a smoke run: one round")
    ap.add_argument("--rounds", type=int, help=f"runs of each command (default {ROUNDS})")
    ap.add_argument(
        "--suite",
        action="store_true",
        help="run `make test` first (about 13 minutes on 2 cores), its records asked for",
    )
    ap.add_argument(
        "--records",
        type=Path,
        default=SUITE_RECORDS,
        help="the suite's records to read and append to (default results/suite.jsonl)",
    )
    ap.add_argument("--root", type=Path, default=ROOT, help="the checkout to measure")
    a = ap.parse_args(argv)
    rounds = a.rounds or (1 if a.quick else ROUNDS)
    rows = cold(a.root.resolve(), rounds)
    columns = ("command", "median_s", "min_s", "max_s", "times_baseline", "import_s")
    print(table(rows, (*columns, "import_times_baseline", "peak_mb", "runs", "target", "met")))
    make_test_s = None
    if a.suite:
        before = len(records(a.records))
        make_test_s = make_test(a.root.resolve(), a.records.resolve())
        found = records(a.records)[before:]
    else:
        found = latest(records(a.records))
    if found:
        print(table(suite_rows(found), tuple(suite_rows(found)[0])))
        if make_test_s is not None:
            print(f"make test: {make_test_s:.1f} s in all\n")
    else:
        print(
            f"the suite: no records in {a.records} (`python -m benchmarks.cold --suite`, or "
            f"{SUITE_VARIABLE}=<file> make test)\n"
        )
    results = {
        "rounds": rounds,
        "baseline": BASELINE,
        "cold": rows,
        "suite": {"ran": a.suite, "make_test_s": make_test_s, "records": found},
    }
    return report("cold", results, quick=a.quick or a.root.resolve() != ROOT)


if __name__ == "__main__":
    main()
