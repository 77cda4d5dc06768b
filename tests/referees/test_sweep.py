"""synth.analysis.sweep: Podhorodeski et al. (2005) Fig. 5, the adjustable coupler's range."""

import pytest

import synth

from ..support import bruteforce
from ..support import reference_cases as ref

DESIGN = {**ref.DRAG_LINK_PROJECT, "coupler": 0.3}


@pytest.mark.parametrize(("start", "stop"), [(0.15, 0.40), (0.05, 0.6)])
def test_fig5_valid_interval_and_time_ratio_range(start, stop):
    r = synth.sweep("drag_link_slider", DESIGN, "coupler", start, stop, 101)
    ((lo, hi),) = r.valid_interval
    # the Grashof limits, exactly: r3 ≥ r1 + r4 − r2 and r3 ≤ r2 + r4 − r1
    assert lo == pytest.approx(0.15, rel=1e-15) and hi == pytest.approx(0.40, rel=1e-15)
    rng = r.time_ratio_range
    assert rng["min"].time_ratio == pytest.approx(ref.DRAG_LINK_TR_MIN[0], abs=5e-5)
    assert rng["min"].value == pytest.approx(ref.DRAG_LINK_TR_MIN[1], abs=5e-4)
    assert rng["max"].time_ratio == pytest.approx(ref.DRAG_LINK_TR_AT_MAX_COUPLER, abs=5e-4)
    assert rng["max"].value == pytest.approx(0.40, rel=1e-12)
    # the extremes are the brute force's too: no smaller TR near the minimum
    b = bruteforce.simulate("drag_link_slider", {**DESIGN, "coupler": rng["min"].value})
    assert b["time_ratio"] == pytest.approx(rng["min"].time_ratio, rel=1e-9)
    for dv in (-1e-4, 1e-4):
        near = {**DESIGN, "coupler": rng["min"].value + dv}
        assert bruteforce.simulate("drag_link_slider", near)["time_ratio"] > b["time_ratio"]
    inside = [v for v in r.values if lo <= v <= hi]
    assert all(r.valid[k] == (lo <= v <= hi) for k, v in enumerate(r.values))
    assert len(inside) == sum(r.valid)
    for k in range(len(r.values)):
        assert (r.time_ratio[k] is None) == (not r.valid[k])


def test_sweep_arguments_are_checked():
    with pytest.raises(synth.InvalidParameters, match="start must be > 0"):
        synth.sweep("drag_link_slider", DESIGN, "coupler", -0.1, 0.5, 11)
    with pytest.raises(synth.InvalidParameters, match="points must be"):
        synth.sweep("drag_link_slider", DESIGN, "coupler", 0.1, 0.5, 10_001)
    with pytest.raises(synth.InvalidParameters, match="has no parameter"):
        synth.sweep("drag_link_slider", DESIGN, "rod", 0.1, 0.5, 11)
