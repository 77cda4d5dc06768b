"""Every reference case of docs/model.md, against the sources' numbers.

Values come from tests/support/reference_cases.py (with provenance). Where a source's printed
number and its own equations disagree, the equations win and the comment says so.
"""

import math

import numpy as np
import pytest

import synth
from synth.errors import InvalidDesign

from ..support import bruteforce
from ..support import reference_cases as ref
from ..support.reference_cases import podhorodeski_couplers

ANGLES = np.arange(0.0, 361.0, 10.0)


def test_slotted_lever_lab_table_theory_column():
    a = synth.analyze("crank_shaper", ref.SLOTTED_LEVER_LAB_PARAMS, crank_angles_deg=ANGLES)
    x = ref.SLOTTED_LEVER_LAB_SCALE_ZERO + a.curves.position
    np.testing.assert_allclose(x, ref.SLOTTED_LEVER_LAB_THEORY, atol=0.005 + 1e-9)


def test_slotted_lever_lab_exact_extremes_and_time_ratio():
    a = synth.analyze("crank_shaper", ref.SLOTTED_LEVER_LAB_PARAMS)
    zero = ref.SLOTTED_LEVER_LAB_SCALE_ZERO
    assert zero + a.extremes["max"].position == pytest.approx(130.0, abs=1e-9)
    assert zero + a.extremes["min"].position == pytest.approx(10.0, abs=1e-9)
    assert a.extremes["max"].crank_angle_deg == pytest.approx(104.48, abs=0.005)
    assert a.extremes["min"].crank_angle_deg == pytest.approx(255.52, abs=0.005)
    # exact: 90° + asin(40/160) and 270° − asin(40/160); TR (π + 2 asin ¼)/(π − 2 asin ¼)
    assert a.extremes["max"].crank_angle_deg == pytest.approx(
        90 + math.degrees(math.asin(0.25)), abs=1e-10
    )
    assert a.time_ratio == pytest.approx(1.38340, abs=5e-6)
    # the lab's 200°/160° = 1.25 is a 10°-sampling artefact: the sampled table itself says so
    sampled = np.array(ref.SLOTTED_LEVER_LAB_THEORY[:-1])
    k_max, k_min = int(np.argmax(sampled)), int(np.argmin(sampled))
    assert (k_max * 10, k_min * 10) == (100, 260)
    assert a.working_stroke.crank_angle_deg + a.return_stroke.crank_angle_deg == pytest.approx(360)


def test_slotted_link_lab_scotch_yoke_tables():
    r = ref.SLOTTED_LINK_LAB_CRANK
    a = synth.analyze("scotch_yoke", {"crank": r}, crank_speed=1.0, crank_angles_deg=ANGLES)
    # the handout measures x = r(1 − cos θ) = r − s from one extreme, so v_x = −v and a_x = −a
    tol = 0.005 + 1e-9
    np.testing.assert_allclose(r - a.curves.position, ref.SLOTTED_LINK_LAB_DISPLACEMENT, atol=tol)
    np.testing.assert_allclose(-a.curves.velocity, ref.SLOTTED_LINK_LAB_VELOCITY, atol=tol)
    np.testing.assert_allclose(-a.curves.acceleration, ref.SLOTTED_LINK_LAB_ACCELERATION, atol=tol)
    assert a.time_ratio == pytest.approx(1.0, abs=1e-12)
    assert a.stroke == pytest.approx(2 * r, rel=1e-14)
    assert a.transmission.min_deg == 90.0
    # simple harmonic motion: a ∝ −x about the centre
    np.testing.assert_allclose(a.curves.acceleration, -a.curves.position, atol=1e-12)


@pytest.mark.parametrize("lever", [420.0, 500.0, 1000.0])
def test_textbook_example1_time_ratio(lever):
    a = synth.analyze("crank_shaper", {"crank": 120, "pivot_distance": 300, "lever": lever})
    assert a.time_ratio == pytest.approx(1.70995, abs=5e-6)  # the book rounds to 1.72
    assert a.return_stroke.crank_angle_deg == pytest.approx(132.84, abs=0.005)


def test_textbook_example2_inclination_ratio_stroke():
    d, r2 = 240.0, 120.0
    a = synth.analyze("crank_shaper", {"crank": r2, "pivot_distance": d, "lever": 450})
    assert a.time_ratio == pytest.approx(2.0, rel=1e-12)
    assert a.stroke == pytest.approx(450.0, rel=1e-12)
    th = math.radians(a.extremes["max"].crank_angle_deg)
    lever_angle = math.degrees(math.atan2(r2 * math.sin(th), d + r2 * math.cos(th)))
    assert lever_angle == pytest.approx(30.0, abs=1e-9)  # inclination to the pivot line


def test_shelare_shaper():
    a = synth.analyze("crank_shaper", {"crank": 100, "pivot_distance": 250, "lever": 650})
    assert a.time_ratio == pytest.approx(1.70995, abs=5e-6)  # the paper prints 1.71
    assert a.stroke == pytest.approx(520.0, rel=1e-12)


@pytest.mark.parametrize("rod", [150.0001, 200.0, 600.0])
def test_textbook_example3_whitworth(rod):
    p = {"crank": 75, "pivot_distance": 50, "lever": 150, "connecting_rod": rod}
    a = synth.analyze("whitworth", p)
    assert a.time_ratio == pytest.approx(2.73524, abs=5e-6)
    assert a.return_stroke.crank_angle_deg == pytest.approx(96.38, abs=0.005)
    assert a.stroke == pytest.approx(300.0, rel=1e-12)


def test_textbook_example3_book_rod_cannot_run():
    p = {"crank": 75, "pivot_distance": 50, "lever": 150, "connecting_rod": 135}
    with pytest.raises(InvalidDesign, match=r"connecting_rod 135 ≤ lever 150") as e:
        synth.analyze("whitworth", p)
    assert e.value.loc == ("lever", "connecting_rod")  # in the type's order


def test_podhorodeski_couplers_give_time_ratio():
    exact = podhorodeski_couplers(ref.DRAG_LINK_TR)
    # the exact roots are 0.154344 and 0.250428: the paper rounds the first up to 0.1544
    np.testing.assert_allclose(exact, ref.DRAG_LINK_COUPLERS, atol=1e-4)
    for r3, theta2a, mu in zip(
        exact, ref.DRAG_LINK_THETA2A_DEG, ref.DRAG_LINK_MIN_TRANSMISSION_DEG, strict=True
    ):
        a = synth.analyze("drag_link_slider", {**ref.DRAG_LINK_PROJECT, "coupler": r3})
        assert a.time_ratio == pytest.approx(ref.DRAG_LINK_TR, rel=1e-12)
        assert a.stroke == pytest.approx(ref.DRAG_LINK_STROKE, rel=1e-12)
        assert a.grashof == "drag-link"
        # TDC (piston farthest) is θ2a: eq. (2a) gives 7.18° / 40.39° (printed: 6.18 / 39.38)
        assert a.extremes["max"].crank_angle_deg == pytest.approx(theta2a, abs=0.005)
        follower = {j.joint: j for j in a.transmission.joints}
        assert follower["coupler-follower"].min_deg == pytest.approx(mu, abs=0.005)
        assert follower["connecting_rod-slider"].min_deg == pytest.approx(60.0, abs=1e-9)
    # the rounded couplers the paper prints give TR 1.5 to its four digits
    for r3 in ref.DRAG_LINK_COUPLERS:
        a = synth.analyze("drag_link_slider", {**ref.DRAG_LINK_PROJECT, "coupler": r3})
        assert a.time_ratio == pytest.approx(1.5, abs=1e-3)


def test_drag_link_project_fig5_feasible_range_and_time_ratios():
    lo, hi = ref.DRAG_LINK_COUPLER_RANGE
    design = {**ref.DRAG_LINK_PROJECT}
    for r3 in (lo, hi, 0.2, 0.3):
        synth.analyze("drag_link_slider", {**design, "coupler": r3})
    for r3 in (lo - 1e-9, hi + 1e-9, 0.1, 0.5):
        with pytest.raises(InvalidDesign, match="not a drag-link"):
            synth.analyze("drag_link_slider", {**design, "coupler": r3})
    top = synth.analyze("drag_link_slider", {**design, "coupler": hi})
    assert top.time_ratio == pytest.approx(ref.DRAG_LINK_TR_AT_MAX_COUPLER, abs=5e-4)  # not 5.538
    grid = np.linspace(lo, hi, 251)
    trs = [synth.analyze("drag_link_slider", {**design, "coupler": r3}).time_ratio for r3 in grid]
    k = int(np.argmin(trs))
    assert trs[k] == pytest.approx(ref.DRAG_LINK_TR_MIN[0], abs=1e-4)
    assert grid[k] == pytest.approx(ref.DRAG_LINK_TR_MIN[1], abs=2e-3)
    assert max(trs) == pytest.approx(trs[-1])


def test_drag_link_project_velocity_acceleration_at_60deg():
    """θ2 = 60°, ω2 = 10 rad/s, α2 = 0: against central differences of the brute-force s(θ)."""
    r3 = podhorodeski_couplers(ref.DRAG_LINK_TR)[1]
    p = {**ref.DRAG_LINK_PROJECT, "coupler": r3}
    w = 10.0
    a = synth.analyze("drag_link_slider", p, crank_speed=w, crank_angles_deg=[60.0])
    h = 1e-4
    s = bruteforce.position("drag_link_slider", p, math.radians(60) + np.array([-h, 0.0, h]))
    v_fd = (s[2] - s[0]) / (2 * h) * w
    a_fd = (s[2] - 2 * s[1] + s[0]) / h**2 * w**2
    assert a.curves.position[0] == pytest.approx(s[1], rel=1e-12)
    assert a.curves.velocity[0] == pytest.approx(v_fd, rel=1e-7)
    assert a.curves.acceleration[0] == pytest.approx(a_fd, rel=1e-5)
    # with an angular acceleration the tangential term adds ds/dθ·α
    b = synth.analyze(
        "drag_link_slider", p, crank_speed=w, crank_acceleration=3.0, crank_angles_deg=[60.0]
    )
    assert b.curves.acceleration[0] == pytest.approx(a_fd + v_fd / w * 3.0, rel=1e-5)
