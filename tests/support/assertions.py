"""Assertions the test modules share: a candidate checked from outside synth."""

import pytest

from . import bruteforce


def assert_meets(c, tr, stroke, bound_deg):
    """Independent check: the brute-force simulation of the candidate meets the targets."""
    b = bruteforce.simulate(c.type, c.params)
    assert b["time_ratio"] == pytest.approx(tr, rel=1e-9)
    assert b["stroke"] == pytest.approx(stroke, rel=1e-9)
    assert b["min_transmission_deg"] >= bound_deg - 1e-7
    assert c.verified and max(c.residuals.values()) <= 1e-9
    assert c.min_transmission_angle_deg == pytest.approx(b["min_transmission_deg"], abs=1e-6)
