"""The searches' evaluation of a design (synth.analysis.terms) refuses a slider that does not
reverse twice a turn before it polishes its stationary points, and counts them as the
analysis does."""

import re

import numpy as np
import pytest

import synth
from synth.analysis.kinematics import prepared
from synth.analysis.terms import motion_terms, peak_torque_terms
from synth.errors import InvalidDesign

# a drag-link 3e-11 from its change point (its four links equal), where a least peak torque
# search stepped: its slider's s' changes sign about a thousand times at the level of rounding
NEAR_CHANGE_POINT = {
    "ground": 0.09999999999680168,
    "crank": 0.10000000000000006,
    "coupler": 0.09999999999693993,
    "follower": 0.10000000000013802,
    "follower_arm": 0.5,
    "connecting_rod": 1.9249544987278595,
}
LOAD = synth.Load("m", 40.0, cutting_force=2.0, slider_mass=0.05)


@pytest.mark.parametrize(
    "evaluate",
    [
        lambda p: motion_terms("drag_link_slider", p, gradient=True),
        lambda p: peak_torque_terms("drag_link_slider", p, LOAD, 1.0),
    ],
    ids=["motion", "torque"],
)
def test_a_slider_reversing_more_than_twice_is_refused_with_the_analysis_count(evaluate):
    with pytest.raises(InvalidDesign, match="reverses") as refused:
        evaluate(NEAR_CHANGE_POINT)
    count = int(re.search(r"reverses (\d+) times", str(refused.value)).group(1))
    rows = prepared("drag_link_slider", NEAR_CHANGE_POINT).points[0]
    assert count == np.count_nonzero(rows == 0) > 2


# the crank shaper's most uniform speed at 1.6 and 20° (stroke 1): two optima 6e-4 apart and
# 1e-2 from each other; the independent global search's best (docs/benchmarks.md's referee)
SHAPER_BEST = 1.095346228


@pytest.mark.parametrize("moved", [0.0, 1e-14, -1e-14, 2e-14])
def test_an_optimum_near_a_worse_one_does_not_depend_on_rounding(monkeypatch, moved):
    """Where the worse optimum's run ends first, the runs on their way to the better one pass
    near its end: they must not be ended there as known (starts moved by 1e-14 did it)."""
    from synth.synthesis import local

    ranked = local._ranked
    monkeypatch.setattr(local, "_ranked", lambda *a: [(f, x * (1 + moved)) for f, x in ranked(*a)])
    r = synth.synthesize(
        1.6,
        1.0,
        20.0,
        [{"type": "crank_shaper"}],
        objective="uniform_cutting_speed",
        time_budget_ms=60_000,
    )
    assert r.complete
    assert r.candidates[0].objective_value == pytest.approx(SHAPER_BEST, rel=1e-9)
