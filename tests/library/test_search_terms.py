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
