"""Pin positions for drawings: every link keeps its length, the slider is where the analysis
puts it, pins on a lever lie on it, and the four-bar's pin is on its circuit."""

import math

import numpy as np
import pytest

import synth

from .designs import random_designs

ANGLES = np.arange(0.0, 360.0, 7.5)


def cross(u, v):
    return u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0]


# per type: (pin, pin, the parameter that is their distance) for every rigid link
LINKS = {
    "scotch_yoke": [("O2", "B", "crank")],
    "offset_slider_crank": [("O2", "B", "crank"), ("B", "C", "coupler")],
    "crank_shaper": [("O2", "B", "crank"), ("O4", "P", "lever"), ("O2", "O4", "pivot_distance"),
                     ("P", "R", "ram_link")],
    "whitworth": [("O2", "B", "crank"), ("O4", "P", "lever"), ("O2", "O4", "pivot_distance"),
                  ("P", "R", "connecting_rod")],
    "crank_rocker_slider": [("O2", "A", "crank"), ("A", "D", "coupler"), ("O4", "D", "rocker"),
                            ("O4", "C", "rocker_arm"), ("O2", "O4", "ground"),
                            ("C", "R", "connecting_rod")],
    "drag_link_slider": [("O2", "A", "crank"), ("A", "B", "coupler"), ("O4", "B", "follower"),
                         ("O4", "C", "follower_arm"), ("O2", "O4", "ground"),
                         ("C", "D", "connecting_rod")],
}  # fmt: skip
# the slider's pin, and how its position s is read from it
SLIDER = {"scotch_yoke": ("yoke", 0), "offset_slider_crank": ("C", 0), "crank_shaper": ("R", 1),
          "whitworth": ("R", 1), "drag_link_slider": ("D", 0)}  # fmt: skip


@pytest.mark.parametrize("mtype", list(LINKS))
def test_pins_keep_every_link_length(mtype):
    for params in random_designs(mtype, 20, seed=7):
        p = synth.mechanisms.get(mtype).complete(params)
        j = synth.joints(mtype, p, ANGLES)
        size = max(abs(v) for v in p.values())
        for a, b, length in LINKS[mtype]:
            if p[length] == 0:  # a slot drive: the pins share the slider's line instead
                continue
            d = np.hypot(*(j[a] - j[b]).T)
            np.testing.assert_allclose(d, p[length], rtol=0, atol=1e-11 * size, err_msg=length)
        if mtype in SLIDER:
            pin, axis = SLIDER[mtype]
            s = synth.analyze(mtype, p, crank_angles_deg=ANGLES).curves.position
            np.testing.assert_allclose(j[pin][:, axis], s, rtol=0, atol=1e-11 * size)


def test_the_lever_pins_lie_on_the_lever():
    for mtype, sign in (("crank_shaper", 1), ("whitworth", -1)):
        for p in random_designs(mtype, 20, seed=3):
            j = synth.joints(mtype, p, ANGLES)
            ob, op = j["B"] - j["O4"], j["P"] - j["O4"]
            size = max(p.values())
            np.testing.assert_allclose(cross(ob, op), 0, atol=1e-11 * size**2)
            assert np.all(sign * np.einsum("ij,ij->i", ob, op) > 0)  # Whitworth: the other way


def test_the_crank_rocker_slider_runs_on_its_path():
    for p in random_designs("crank_rocker_slider", 20, seed=3):
        p = synth.mechanisms.get("crank_rocker_slider").complete(p)
        j = synth.joints("crank_rocker_slider", p, ANGLES)
        r = j["R"] - j["O4"]
        # the path is a straight line: R minus its mean is along one direction only
        d = r - r.mean(axis=0)
        assert np.linalg.matrix_rank(d, tol=1e-9 * max(p.values())) == 1
        # at distance slider_height from O4
        n = np.array([-d[np.argmax(np.hypot(*d.T))][1], d[np.argmax(np.hypot(*d.T))][0]])
        n /= np.hypot(*n)
        np.testing.assert_allclose(np.abs(r @ n), p["slider_height"], rtol=1e-9)


@pytest.mark.parametrize("params", random_designs("drag_link_slider", 30, seed=7))
def test_drag_link_pins_are_on_its_circuit(params):
    j = synth.joints("drag_link_slider", params, ANGLES)
    size = max(params.values())
    assert np.all(j["D"][:, 1] == 0)
    # C on the follower line, beyond O4 on B's side
    ob, oc = j["B"] - j["O4"], j["C"] - j["O4"]
    np.testing.assert_allclose(cross(ob, oc), 0, atol=1e-12 * size**2)
    assert np.all(np.einsum("ij,ij->i", ob, oc) > 0)
    # B left of A→O4 (the circuit named in the module docstring)
    ao4, ab = j["O4"] - j["A"], j["B"] - j["A"]
    assert np.all(cross(ao4, ab) >= -1e-12 * size**2)


def test_drag_link_project_drawing_at_90_degrees():
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


def test_an_invalid_design_has_no_drawing():
    with pytest.raises(synth.InvalidDesign):
        synth.joints("whitworth", {"crank": 75, "pivot_distance": 50, "lever": 150,
                                   "connecting_rod": 135}, [0.0])  # fmt: skip
