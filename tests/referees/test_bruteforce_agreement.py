"""synth.analyze agrees with the independent brute-force simulation on random valid designs.

tests/support/bruteforce.py shares no code with synth: circle/line intersections over 20 000 crank
angles, refined by complex-step derivatives and bracketing. Required: time ratio and stroke to
1e-9 relative, minimum transmission angle to 1e-6°.
"""

import math

import numpy as np
import pytest

import synth

from ..support import bruteforce
from ..support.designs import TYPES, random_designs

N = 200


@pytest.mark.parametrize("mtype", TYPES)
def test_analysis_matches_brute_force(mtype):
    for p in random_designs(mtype, N, seed=3):
        a = synth.analyze(mtype, p)
        b = bruteforce.simulate(mtype, p)
        assert a.time_ratio == pytest.approx(b["time_ratio"], rel=1e-9), p
        assert a.stroke == pytest.approx(b["stroke"], rel=1e-9), p
        tol = {"rel": 1e-9, "abs": 1e-9 * a.stroke}
        assert a.extremes["max"].position == pytest.approx(b["s_max"], **tol)
        assert a.extremes["min"].position == pytest.approx(b["s_min"], **tol)
        assert a.transmission.min_deg == pytest.approx(b["min_transmission_deg"], abs=1e-6), p
        assert a.transmission.max_deg == pytest.approx(b["max_transmission_deg"], abs=1e-6), p
        if a.time_ratio > 1 + 1e-6:  # the working stroke is defined by the slow crank travel
            assert a.working_stroke.direction == b["working_direction"], p
            assert math.radians(a.working_stroke.crank_angle_deg) == pytest.approx(
                b["working_angle"], rel=1e-9
            )


def grid_reversals(mtype, p, n=20000):
    s = bruteforce.position(mtype, p, np.linspace(0, 2 * np.pi, n, endpoint=False))
    ds = np.diff(np.append(s, s[0]))
    return int(np.count_nonzero(np.sign(ds) != np.sign(np.roll(ds, 1))))


@pytest.mark.parametrize("mtype", TYPES)
def test_reversals_match_brute_force(mtype):
    for p in random_designs(mtype, 20, seed=5):
        assert synth.analyze(mtype, p).reversals == grid_reversals(mtype, p) == 2


def test_dithering_slider_is_reported():
    """A ram link barely longer than its reach: the ram dips between two equal maxima."""
    p = {
        "crank": 0.1048,
        "pivot_distance": 1.0,
        "lever": 2.134,
        "ram_link": 0.1531,
        "ram_height": 2.2753,
    }
    assert synth.analyze("crank_shaper", p).reversals == grid_reversals("crank_shaper", p) == 4
