"""Test-session settings, set before the app is imported; hypothesis profiles; the suite's
record of its own wall time and peak memory."""

import datetime
import json
import os
import resource
import time
from collections.abc import Generator
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, settings

from benchmarks.common import code

START = time.time()  # this file's import: the suite's start where /proc cannot say (below)

# schemathesis generates requests up to the schema's limits: keep each synthesis short here
os.environ.setdefault("SYNTH_MAX_BUDGET_MS", "1000")
# no background warm-up competing for the two cores with the test that runs meanwhile (a
# motion objective's 1 s budget ran out under it); the servers the tests start warm up
os.environ.setdefault("SYNTH_WARM", "0")

# `make test`: a bounded, reproducible subset; `make stress`: the long run (HYPOTHESIS_PROFILE)
common = {"deadline": None, "suppress_health_check": list(HealthCheck)}
settings.register_profile("default", max_examples=40, derandomize=True, database=None, **common)
settings.register_profile("few", max_examples=10, derandomize=True, database=None, **common)
settings.register_profile("medium", max_examples=1_000, **common)
settings.register_profile("stress", max_examples=10_000, **common)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "default"))

# the toy types register themselves on import: only library/test_seventh_type.py's own process,
# which names them in SYNTH_TYPES, may collect them (the doctests would import them here too)
if not os.environ.get("SYNTH_TYPES"):
    collect_ignore = ["support/toy_type.py", "support/toy_checks.py"]


# The suite's own wall time and peak resident memory, for `make bench` (benchmarks/cold.py):
# each xdist worker sends its peak (and its finished subprocesses' largest) to the controller,
# which prints one line at the end of every run and, when SYNTH_SUITE_RECORD names a file,
# appends the run's record to it as one JSON line. The variable is taken out of the
# environment at the start, so that the pytest runs the tests start do not record themselves.
RECORD_VARIABLE = "SYNTH_SUITE_RECORD"
RECORD_PATH = pytest.StashKey[Path | None]()
WORKER_PEAKS = pytest.StashKey[dict[str, tuple[int, int]]]()  # worker id: own, children (kB)
PEAK_KEY = "synth_peak_rss_kb"  # in a worker's output
# the record's counts: the terminal's outcome of each
OUTCOMES = {
    "passed": "passed",
    "failed": "failed",
    "errors": "error",
    "skipped": "skipped",
    "xfailed": "xfailed",
    "xpassed": "xpassed",
}


def peak_kb() -> tuple[int, int]:
    """This process's peak resident memory and its finished subprocesses' largest (kB)."""
    own = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return own, resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss


def process_seconds() -> float | None:
    """Seconds since this process started (from /proc; None elsewhere)."""
    try:
        started = int(Path("/proc/self/stat").read_text().rsplit(")", 1)[1].split()[19])
        uptime = float(Path("/proc/uptime").read_text().split()[0])
    except (OSError, IndexError, ValueError):
        return None
    return uptime - started / os.sysconf("SC_CLK_TCK")


def pytest_configure(config: pytest.Config) -> None:
    path = os.environ.pop(RECORD_VARIABLE, None)
    config.stash[RECORD_PATH] = config.invocation_params.dir / path if path else None
    config.stash[WORKER_PEAKS] = {}


@pytest.hookimpl(trylast=True)  # after the session's fixtures are torn down
def pytest_sessionfinish(session: pytest.Session) -> None:
    output = getattr(session.config, "workeroutput", None)
    if output is not None:  # an xdist worker: xdist sends its output on after this hook
        output[PEAK_KEY] = peak_kb()


@pytest.hookimpl(optionalhook=True)
def pytest_testnodedown(node: Any, error: object) -> None:
    peak = getattr(node, "workeroutput", {}).get(PEAK_KEY)
    if peak is not None:
        node.config.stash[WORKER_PEAKS][node.workerinput["workerid"]] = tuple(peak)


def suite_record(config: pytest.Config, stats: dict[str, list[Any]], status: int) -> dict:
    """This run's record: which run, its wall time, the peak resident memory of its largest
    process (the controller, an xdist worker, or a subprocess either had finished) and the
    sum of the workers' peaks (each at its own moment: at most what they held at once), the
    tests' outcomes, and the code."""
    workers = config.stash[WORKER_PEAKS]
    own, children = peak_kb()
    sizes = [(own, "controller")]
    sizes += [(kb, w) for w, (kb, _) in sorted(workers.items())]
    sizes += [(kb, f"a subprocess of {w}") for w, (_, kb) in sorted(workers.items())]
    # the pytest process's own subprocesses: in a parallel run, its workers too (each until
    # its exit, where a worker's own report stops at the end of its session)
    sizes.append((children, "a worker or a subprocess" if workers else "a subprocess"))
    peak, where = max(sizes, key=lambda s: s[0])
    mb = 1024 / 1e6
    root = config.rootpath
    return {
        "date_utc": datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%dT%H:%M:%SZ"),
        "run": "parallel" if config.pluginmanager.hasplugin("dsession") else "serial",
        "markers": config.option.markexpr or None,
        "paths": [os.path.relpath(a, root) if os.path.isabs(a) else a for a in config.args],
        "wall_s": round(process_seconds() or time.time() - START, 2),
        "peak_mb": round(peak * mb, 1),
        "peak_process": where,
        "controller_mb": round(own * mb, 1),
        "workers": len(workers),
        "workers_mb": {w: round(kb * mb, 1) for w, (kb, _) in sorted(workers.items())},
        "workers_sum_mb": round(sum(kb for kb, _ in workers.values()) * mb, 1),
        **{k: len(stats.get(s, [])) for k, s in OUTCOMES.items()},
        "exit_status": status,
        "cpus": len(os.sched_getaffinity(0)),
        "code": code(),
    }


@pytest.hookimpl(wrapper=True, tryfirst=True)  # around the terminal's: after its summary
def pytest_terminal_summary(
    terminalreporter: Any, exitstatus: int, config: pytest.Config
) -> Generator[None, object, object]:
    result = yield
    if not hasattr(config, "workerinput"):
        terminalreporter.write_line(recorded(config, terminalreporter.stats, int(exitstatus)))
    return result


def recorded(config: pytest.Config, stats: dict[str, list[Any]], status: int) -> str:
    """This run's record, appended to the file asked for if any; its line for the terminal."""
    record = suite_record(config, stats, status)
    path = config.stash[RECORD_PATH]
    if path is not None:
        path.parent.mkdir(parents=True, exist_ok=True)
        with path.open("a") as f:
            f.write(json.dumps(record) + "\n")
    where = f"; recorded in {path}" if path is not None else ""
    workers = record["workers"]
    summed = f", {workers} workers' peaks {record['workers_sum_mb']:.0f} MB in all"
    return (
        f"suite ({record['run']}): {record['wall_s']:.1f} s, peak resident memory "
        f"{record['peak_mb']:.0f} MB ({record['peak_process']}){summed if workers else ''}{where}"
    )
