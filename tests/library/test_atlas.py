"""The design atlas (synth.atlas): the same answers however it runs, resumed runs that compute
nothing twice, a frontier that the independent global search agrees with, and ranges that
the synthesis agrees with at their ends."""

from __future__ import annotations

import math
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest

import synth
from synth.atlas import Point, atlas

from ..support import globalsearch as gs
from ..support.server import ROOT

SMALL = {
    "types": ("offset_slider_crank", "whitworth", "drag_link_slider"),
    "ratios": (1.2, 1.6, 2.4),
    "bounds": (20.0,),
    "chunk": 2,
}


SEEDS = gs.Effort(seeds=(0, 1, 2), popsize=15, maxiter=100)  # differential evolution, 3 seeds


def same(a, b) -> None:
    assert a.frontier == b.frontier and a.ranges == b.ranges


@pytest.fixture(scope="module")
def cluster():
    """A Dask cluster of two worker processes on this machine."""
    from dask.distributed import LocalCluster

    with LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
    ) as c:
        yield c


def test_in_process_in_a_pool_and_on_dask_alike(tmp_path, cluster):
    inline = atlas(**SMALL, inline=True)
    pooled = atlas(**SMALL, workers=2, out=tmp_path)
    same(inline, pooled)
    same(inline, atlas(**SMALL, scheduler=cluster.scheduler_address))
    assert pooled.computed == 5  # 9 points in chunks of 2
    assert {p.status for p in inline.frontier} == {"certified"}
    assert (tmp_path / "frontier.csv").read_text().count("\n") == 1 + 9
    assert (tmp_path / "ranges.csv").read_text().count("\n") == 1 + 3


def test_a_resumed_run_computes_only_what_is_missing(tmp_path):
    first = atlas(**SMALL, inline=True, out=tmp_path)
    for k in (1, 3):
        (tmp_path / "chunks" / f"{k:06d}.json").unlink()
    again = atlas(**SMALL, inline=True, out=tmp_path)
    assert again.computed == 2
    same(first, again)
    with pytest.raises(ValueError, match="other inputs"):
        atlas(**{**SMALL, "ratios": (1.3,)}, inline=True, out=tmp_path)


def test_a_killed_run_resumes_to_the_same_atlas(tmp_path):
    """The command line, killed once its first chunks are written, then run again (n chunks,
    ~1 ms each: the kill comes with work left)."""
    n = 240
    args = [
        sys.executable,
        "-m",
        "synth.atlas",
        "--types",
        "offset_slider_crank",
        "whitworth",
        "--ratios",
        f"1.1:3.0:{n}",
        "--bounds",
        "20",
        "--chunk",
        "2",
        "--workers",
        "2",
        "--out",
        str(tmp_path),
    ]
    # its own process group, killed whole: its pool's workers with it (killed alone, they
    # outlived the suite, idle)
    proc = subprocess.Popen(
        args,
        cwd=ROOT,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        start_new_session=True,
    )
    chunks = tmp_path / "chunks"
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and len(list(chunks.glob("*.json"))) < 3:
        time.sleep(0.02)
    os.killpg(proc.pid, signal.SIGKILL)
    proc.wait()
    written = len(list(chunks.glob("*.json")))
    assert 3 <= written < n, written  # killed with work left
    ratios = [1.1 + 1.9 * k / (n - 1) for k in range(n)]
    inputs = {"types": ("offset_slider_crank", "whitworth"), "bounds": (20.0,), "chunk": 2}
    resumed = atlas(ratios=[round(r, 12) for r in ratios], **inputs, inline=True, out=tmp_path)
    assert resumed.computed == n - written
    same(resumed, atlas(ratios=[round(r, 12) for r in ratios], **inputs, inline=True))


def test_a_worker_killed_mid_run_changes_nothing(tmp_path, cluster):
    from dask.distributed import Client

    kw = {
        "types": ("offset_slider_crank", "whitworth"),
        "bounds": (),
        "chunk": 1,
        "ratios": tuple(round(1.05 + 0.01 * k, 4) for k in range(150)),
    }
    with Client(cluster) as client:
        victim = next(iter(client.run(os.getpid).values()))
    done = {}
    run = threading.Thread(
        target=lambda: done.update(a=atlas(**kw, scheduler=cluster.scheduler_address, out=tmp_path))
    )
    run.start()
    chunks = tmp_path / "chunks"
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and len(list(chunks.glob("*.json"))) < 20:
        time.sleep(0.005)
    os.kill(victim, signal.SIGKILL)
    at_kill = len(list(chunks.glob("*.json")))
    run.join(timeout=300)
    assert at_kill < 300 and "a" in done, at_kill  # killed with work left, and finished
    assert done["a"].computed == 300
    same(done["a"], atlas(**kw, inline=True))


@pytest.mark.parametrize(
    "mtype", [t for t in synth.mechanisms.all_types() if synth.mechanisms.get(t).quick_return]
)
def test_the_frontier_agrees_with_a_global_search(mtype):
    ratios = tuple(np.round(np.linspace(1.1, 3.0, 10), 6))
    a = atlas([mtype], ratios, (), inline=True)
    for p in a.frontier:
        g = gs.search(mtype, "max_transmission_angle", p.time_ratio, 0.0, SEEDS)
        if p.best_angle_deg is None:
            assert g.value is None or g.value < 1e-6, (p, g.value)
            continue
        assert p.status == "certified"
        # the search is a referee: it never beats the frontier, and comes within 0.01°
        assert g.value is not None and abs(g.value - p.best_angle_deg) <= 0.01, (p, g.value)


def test_the_ranges_ends_are_the_synthesis_ends():
    a = atlas(
        ("offset_slider_crank", "crank_rocker_slider"),
        (1.1, 1.5, 2.0, 3.0),
        (20.0, 40.0),
        inline=True,
    )
    checked = 0
    for r in a.ranges:
        end = r["max"]
        if end is None or end in a.inputs.ratios:
            continue  # at the grid's end: the range goes on beyond it
        inside, outside = end * (1 - 1e-7), end * (1 + 1e-7)
        for tr, found in ((inside, True), (outside, False)):
            got = synth.synthesize(tr, 1.0, r["bound_deg"], [{"type": r["type"]}])
            assert bool(got.candidates) == found, (r, tr, got.infeasible)
        checked += 1
    assert checked == 4


def test_a_point_says_why_where_no_design_exists():
    p = synth.atlas.point("offset_slider_crank", 3.9)  # beyond its reach (just under 3)
    assert p == Point("offset_slider_crank", 3.9, None, "refused", reason=p.reason)
    assert p.reason.startswith("TIME_RATIO_UNREACHABLE") and "1 … 2.99999" in p.reason
    assert math.isfinite(synth.atlas.point("whitworth", 3.9).best_angle_deg)


def test_the_service_ships_the_atlas_this_code_computes():
    """GET /v1/atlas serves api/atlas.json (make atlas); recomputed here at a sample of its
    points, it is what the code gives now: a change that moves the frontier must rebuild it."""
    from fastapi.testclient import TestClient

    from api.main import app

    got = TestClient(app).get("/v1/atlas").json()
    inputs = got["inputs"]
    assert set(got["frontier"]) == set(inputs["types"])
    for mtype, rows in got["frontier"].items():
        assert [r[0] for r in rows] == inputs["ratios"]
        for tr, best, status in rows[:: max(1, len(rows) // 5)]:
            p = synth.atlas.point(mtype, tr)
            assert (p.best_angle_deg, p.status) == (best, status)
    assert len(got["ranges"]) == len(inputs["types"]) * len(inputs["bounds"])


def test_a_pool_worker_killed_mid_run_changes_nothing(tmp_path):
    """The local pool: a worker SIGKILLed, the pool replaced, the unfinished chunks run again."""
    from benchmarks.common import descendants

    def pool_workers(before: set[int]) -> list[int]:
        out = []
        for pid in sorted(descendants(os.getpid()) - before):
            try:
                cmd = Path(f"/proc/{pid}/cmdline").read_bytes()
            except OSError:
                continue
            if b"spawn_main" in cmd:  # not the resource tracker
                out.append(pid)
        return out

    kw = {
        "types": ("offset_slider_crank", "whitworth"),
        "bounds": (),
        "chunk": 1,
        "ratios": tuple(round(1.05 + 0.01 * k, 4) for k in range(150)),
    }
    before = descendants(os.getpid())
    done = {}
    run = threading.Thread(target=lambda: done.update(a=atlas(**kw, workers=2, out=tmp_path)))
    run.start()
    chunks = tmp_path / "chunks"
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and len(list(chunks.glob("*.json"))) < 20:
        time.sleep(0.005)
    victims = pool_workers(before)
    assert victims
    os.kill(victims[0], signal.SIGKILL)
    at_kill = len(list(chunks.glob("*.json")))
    run.join(timeout=300)
    assert at_kill < 300 and "a" in done, at_kill
    same(done["a"], atlas(**kw, inline=True))
