"""Pin positions for drawings: every link keeps its length, the piston is where the analysis
puts it, and the follower pin is on the assembly's circuit (left of A→O4)."""

import math

import numpy as np
import pytest

import synth

from .designs import random_designs

ANGLES = np.arange(0.0, 360.0, 7.5)


def cross(u, v):
    return u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0]


@pytest.mark.parametrize("params", random_designs("drag_link_slider", 30, seed=7))
def test_drag_link_pins_close_every_loop(params):
    j = synth.joints("drag_link_slider", params, ANGLES)
    a = synth.analyze("drag_link_slider", params, crank_angles_deg=ANGLES)
    size = max(params.values())

    def dist(p, q):
        return np.hypot(*(j[p] - j[q]).T)

    for (p, q), length in {("O2", "A"): "crank", ("A", "B"): "coupler", ("O4", "B"): "follower",
                           ("O4", "C"): "follower_arm", ("C", "D"): "connecting_rod",
                           ("O2", "O4"): "ground"}.items():  # fmt: skip
        np.testing.assert_allclose(dist(p, q), params[length], rtol=0, atol=1e-12 * size)
    np.testing.assert_allclose(j["D"][:, 0], a.curves.position, rtol=0, atol=1e-12 * size)
    assert np.all(j["D"][:, 1] == 0)
    # C on the follower line, beyond O4 on B's side
    ob, oc = j["B"] - j["O4"], j["C"] - j["O4"]
    np.testing.assert_allclose(cross(ob, oc), 0, atol=1e-12 * size**2)
    assert np.all(np.einsum("ij,ij->i", ob, oc) > 0)
    # B left of A→O4 (the circuit named in the module docstring)
    ao4, ab = j["O4"] - j["A"], j["B"] - j["A"]
    assert np.all(cross(ao4, ab) >= -1e-12 * size**2)


def test_seed002_drawing_at_90_degrees():
    p = {"ground": 0.1, "crank": 0.225, "coupler": 0.2504, "follower": 0.275,
         "follower_arm": 0.15, "connecting_rod": 0.3}  # fmt: skip
    j = synth.joints("drag_link_slider", p, [90.0])
    assert j["A"][0] == pytest.approx([0.0, 0.225], abs=1e-15)
    # B by hand: circle(A, r3) ∩ circle(O4, r4), left of A→O4
    ax, ay, ox = 0.0, 0.225, 0.1
    d = math.hypot(ox - ax, ay)
    a = (0.2504**2 - 0.275**2 + d * d) / (2 * d)
    h = math.sqrt(0.2504**2 - a * a)
    ux, uy = (ox - ax) / d, (0 - ay) / d
    assert j["B"][0] == pytest.approx([ax + a * ux - h * uy, ay + a * uy + h * ux], abs=1e-12)


def test_types_without_a_drawing_say_so():
    with pytest.raises(synth.InvalidParameters, match="no drawing"):
        synth.joints("scotch_yoke", {"crank": 1.0}, [0.0])
