"""The benchmarks (`make bench`) in their quick form, so that they cannot rot: they run, and
what they report holds (ours solves every feasible target it is given and refuses every
infeasible one, to 1e-12, never worse than the generic multistart; the service answers every
request). Timings are printed, never asserted."""

import pytest

from benchmarks import analysis, overload, searched, service, startup, synthesis
from synth.mechanisms import all_types

pytestmark = pytest.mark.long  # tens of seconds each: make long (CI runs it), not make test


def test_synthesis_benchmark_quick():
    out = synthesis.main(["--quick", "--methods", "ours,generic,scipy_slsqp"])
    ours = [r for r in out["summary"] if r["method"] == "ours"]
    assert len(ours) == len(all_types())  # every registered type
    for r in ours:
        assert r["success"] == 1.0 and r["refused"] == 1.0, r
        assert r["error_max"] <= 1e-12, r
    opt = out["optimality"]
    assert opt["compared"] == len({r["case"] for r in out["records"]})
    assert not opt["violations"], opt["violations"]
    assert {r["method"] for r in out["records"]} == {"ours", "generic", "scipy_slsqp"}


def test_analysis_benchmark_quick():
    out = analysis.main(["--quick"])
    assert {r["type"] for r in out["analysis"]} == set(analysis.DESIGNS)
    assert all(r["ms"] > 0 for r in out["analysis"] + out["synthesis"])
    cases = out["default_request_cases"]
    assert {c["type"] for c in cases} == {*analysis.DESIGNS, analysis.ALL}
    # every request a type cannot meet is refused, with a reason
    refusals = [c for c in cases if c["kind"] == "refusal"]
    assert refusals and not any(c["answered"] or not c["refusals"] for c in refusals)
    # the default requests at a 20° bound have designs for every quick-return type
    for c in cases:
        if c["kind"] == "default" and c["bound"] == 20.0 and c["type"] != "scotch_yoke":
            assert c["answered"], c
    # the motion objectives over targets: each kind for every quick-return type, answered
    motion = out["motion_targets"]
    assert {(r["type"], r["kind"]) for r in motion} == {
        (t, k) for t in analysis.QUICK_RETURN for k in ("free", "limit", "fixed")
    }
    assert all(r["answered"] == r["targets"] for r in motion if r["kind"] != "limit"), motion


def test_service_benchmark_quick():
    out = service.main(["--quick", "--servers", "shipped"])
    assert {r["workload"] for r in out["rows"]} == set(service.WORKLOADS)
    for r in out["rows"]:
        assert r["requests"] == 40, r
        bad = {c: n for c, n in r["statuses"].items() if c >= 500}
        assert not bad, r
        # the share of invalid analyses is answered 422, every synthesis 200 (with a reason)
        expected = {200: 32, 422: 8} if r["workload"] == "analyze" else {200: 40}
        assert r["statuses"] == expected, r
    for r in out["repeated_16_clients"]:
        assert r["statuses"] == {200: 40}, r
    assert {p["type"] for p in out["paired"]} == set(analysis.DESIGNS)
    for p in out["paired"]:
        assert p["statuses"] == {"synthesize": {200: 5}, "analyze": {200: 5}}, p
    # against the bare app: every request answered, on both servers
    bare = out["against_bare"]
    assert [r["request"] for r in bare["one_client"]] == list(service.AGAINST_BARE)
    for r in bare["one_client"]:
        assert r["statuses"] == {200: r["rounds"]} and r["bare_p50_ms"] > 0, r
    for r in bare["sixteen_clients"]:
        want = {200: 32, 422: 8} if r["server"] == "service" else {200: 40}
        assert r["statuses"] == want, r


def test_overload_benchmark_quick():
    """Overloaded, the server refuses (503) rather than fails: no 5xx else, no dropped
    connection, every synthesis and /health answered (their times are the benchmark's)."""
    out = overload.main(["--quick"])
    assert [r["clients"] for r in out["rows"]] == list(overload.CLIENTS)
    assert list(out["mixes"]) == ["mixed", "inline", "loaded"]
    rows = [r for rs in out["mixes"].values() for r in rs]
    for r in [*rows, out["memory"]]:
        assert r["errors"] == 0, r
    for r in rows:
        assert r["synthesis_wall_ms"]["max"] is not None and r["health_ms"]["max"] is not None
        assert r["rss_mb_before"].keys() == r["rss_mb_after"].keys() and r["rss_mb_after"], r


def test_startup_benchmark_quick():
    out = startup.main(["--quick"])
    assert [r["module"] for r in out["imports"]] == ["synth", "api.main"]
    assert {r["start"] for r in out["ready"]} == {"warm_cache", "no_warm_up"}
    assert all(r["median_s"] > 0 for r in out["imports"] + out["ready"])
    assert [r["request"] for r in out["first_requests"]] == [w for w, _ in startup.FIRST]


def test_searched_benchmark_quick():
    """The searched objectives' benchmark: every request answered, certified or saying why
    not, each best value within 1e-9 of the independent global search's or better."""
    out = searched.main(["--quick"])
    assert out["summary"] and all(r["answered"] == 1.0 for r in out["summary"]), out["summary"]
    assert all(r["said"] == 1.0 for r in out["summary"]), out["summary"]
    for r in out["referee"]:
        assert r["ours_excess"] <= 1e-9, r
