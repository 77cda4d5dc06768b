"""The benchmarks (`make bench`) in their quick form, so that they cannot rot: they run, and
what they report holds (ours solves every feasible target it is given and refuses every
infeasible one; the service answers every request). Timings are printed, never asserted."""

from benchmarks import analysis, service, synthesis


def test_synthesis_benchmark_quick():
    out = synthesis.main(["--quick", "--methods", "ours,ours_starts_1,scipy_slsqp"])
    ours = [r for r in out["summary"] if r["method"] == "ours"]
    assert len(ours) == 6
    for r in ours:
        assert r["success"] == 1.0 and r["refused"] == 1.0, r
        assert r["error_max"] <= 1e-12, r


def test_analysis_benchmark_quick():
    out = analysis.main(["--quick"])
    assert {r["type"] for r in out["analysis"]} == set(analysis.DESIGNS)
    assert all(r["ms"] > 0 for r in out["analysis"] + out["synthesis"])


def test_service_benchmark_quick():
    out = service.main(["--quick", "--servers", "shipped"])
    for r in out["rows"]:
        assert r["requests"] == 40, r
        bad = {c: n for c, n in r["statuses"].items() if c >= 500}
        assert not bad, r
        # the share of invalid analyses is answered 422, every synthesis 200 (with a reason)
        expected = {200: 32, 422: 8} if r["path"] == "/v1/analyze" else {200: 40}
        assert r["statuses"] == expected, r
