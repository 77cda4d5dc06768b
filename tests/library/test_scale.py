"""Scale: the same design in mm and in m gives the same ratio and angles, lengths scaled."""

import numpy as np
import pytest

import synth

from ..support.designs import TYPES, random_designs

ANGLES = np.linspace(0.0, 350.0, 36)


def close(a, b):
    np.testing.assert_allclose(a, b, rtol=1e-12, atol=0)


@pytest.mark.parametrize("mtype", TYPES)
def test_mm_and_m_agree(mtype):
    for p_mm in random_designs(mtype, 50, seed=2):
        p_m = {k: v / 1000 for k, v in p_mm.items()}
        mm = synth.analyze(mtype, p_mm, crank_speed=3.0, crank_angles_deg=ANGLES)
        m = synth.analyze(mtype, p_m, crank_speed=3.0, crank_angles_deg=ANGLES)
        close(m.time_ratio, mm.time_ratio)
        close(m.stroke * 1000, mm.stroke)
        for k in ("min", "max"):
            close(m.extremes[k].position * 1000, mm.extremes[k].position)
            close(m.extremes[k].crank_angle_deg, mm.extremes[k].crank_angle_deg)
        close(m.working_stroke.crank_angle_deg, mm.working_stroke.crank_angle_deg)
        assert m.working_stroke.direction == mm.working_stroke.direction
        close(m.transmission.min_deg, mm.transmission.min_deg)
        close(m.transmission.max_deg, mm.transmission.max_deg)
        for name in ("position", "velocity", "acceleration"):
            # values that vanish (e.g. at a dead centre) are compared against the curve's scale
            got, want = getattr(m.curves, name) * 1000, getattr(mm.curves, name)
            np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-12 * np.max(np.abs(want)))
        close(m.curves.transmission_deg, mm.curves.transmission_deg)
        close([v * 1000 for v in m.params.values()], list(mm.params.values()))
