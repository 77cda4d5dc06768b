"""Pin positions for drawings: every link keeps its length, the slider is where the analysis
puts it, pins on a lever lie on it, and the four-bar's pin is on its circuit. An analysis's
pins (include "pins") are the same, at exactly its curves' angles, and only when asked."""

import math
from dataclasses import replace

import numpy as np
import pytest

import synth
from synth.analysis import kinematics
from synth.analysis.request import AnalysisRequest as check
from synth.mechanisms import all_types, get

from ..support.designs import random_designs
from ..support.isolation import in_a_process_of_its_own

ANGLES = np.arange(0.0, 360.0, 7.5)


def cross(u, v):
    return u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0]


# per type: (pin, pin, the parameter that is their distance) for every rigid link
LINKS = {
    "scotch_yoke": [("O2", "B", "crank")],
    "offset_slider_crank": [("O2", "B", "crank"), ("B", "C", "coupler")],
    "crank_shaper": [
        ("O2", "B", "crank"),
        ("O4", "P", "lever"),
        ("O2", "O4", "pivot_distance"),
        ("P", "R", "ram_link"),
    ],
    "whitworth": [
        ("O2", "B", "crank"),
        ("O4", "P", "lever"),
        ("O2", "O4", "pivot_distance"),
        ("P", "R", "connecting_rod"),
    ],
    "crank_rocker_slider": [
        ("O2", "A", "crank"),
        ("A", "D", "coupler"),
        ("O4", "D", "rocker"),
        ("O4", "C", "rocker_arm"),
        ("O2", "O4", "ground"),
        ("C", "R", "connecting_rod"),
    ],
    "drag_link_slider": [
        ("O2", "A", "crank"),
        ("A", "B", "coupler"),
        ("O4", "B", "follower"),
        ("O4", "C", "follower_arm"),
        ("O2", "O4", "ground"),
        ("C", "D", "connecting_rod"),
    ],
}
# the slider's pin, and how its position s is read from it
SLIDER = {
    "scotch_yoke": ("yoke", 0),
    "offset_slider_crank": ("C", 0),
    "crank_shaper": ("R", 1),
    "whitworth": ("R", 1),
    "drag_link_slider": ("D", 0),
}


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
    p = {
        "ground": 0.1,
        "crank": 0.225,
        "coupler": 0.2504,
        "follower": 0.275,
        "follower_arm": 0.15,
        "connecting_rod": 0.3,
    }
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
        synth.joints(
            "whitworth",
            {"crank": 75, "pivot_distance": 50, "lever": 150, "connecting_rod": 135},
            [0.0],
        )


# --- the analysis's pins (include "pins"): the same pins, at exactly the curves' angles -----


@pytest.mark.parametrize("mtype", [t for t in all_types() if get(t).joints is not None])
def test_an_analysis_pins_are_the_joints_at_its_angles(mtype):
    for params in random_designs(mtype, 5, seed=11):
        for angles in ({"crank_angles_deg": ANGLES}, {"samples": 7}):
            a = synth.analyze(mtype, params, include=["pins"], **angles)
            deg = a.curves.crank_angle_deg
            j = synth.joints(mtype, params, deg)
            assert list(a.curves.pins) == list(j)  # every pin, in the drawing's order
            for name, path in a.curves.pins.items():
                assert path.x.shape == path.y.shape == deg.shape
                assert np.array_equal(np.column_stack([path.x, path.y]), j[name]), name


@pytest.mark.parametrize("params", random_designs("drag_link_slider", 10, seed=5))
def test_an_analysis_pins_follow_the_drag_link_geometry(params):
    """Against geometry written here: the crank pin on its circle at each asked angle, the
    pivots where the drawing puts them, every link as long as the design says."""
    p = get("drag_link_slider").complete(params)
    deg = np.array([-30.0, 0.0, 37.5, 90.0, 200.0, 400.0])
    a = synth.analyze("drag_link_slider", p, crank_angles_deg=deg, include=["pins"])
    pins = {k: np.column_stack([v.x, v.y]) for k, v in a.curves.pins.items()}
    assert list(pins) == ["O2", "A", "O4", "B", "C", "D"]
    size = max(p.values())
    th = np.radians(deg)
    np.testing.assert_allclose(pins["O2"], 0.0, rtol=0, atol=0)
    np.testing.assert_allclose(pins["O4"], [[p["ground"], 0.0]] * deg.size, rtol=0, atol=0)
    np.testing.assert_allclose(
        pins["A"],
        p["crank"] * np.column_stack([np.cos(th), np.sin(th)]),
        rtol=0,
        atol=1e-15 * size,
    )
    for u, v, length in LINKS["drag_link_slider"]:
        d = np.hypot(*(pins[u] - pins[v]).T)
        np.testing.assert_allclose(d, p[length], rtol=1e-12, atol=0, err_msg=length)
    # the slider's pin on the x axis, where the curves put the slider
    np.testing.assert_allclose(pins["D"][:, 1], 0.0, rtol=0, atol=0)
    np.testing.assert_allclose(pins["D"][:, 0], a.curves.position, rtol=0, atol=1e-12 * size)


SHAPER = {"crank": 40.0, "pivot_distance": 160.0, "lever": 240.0}


def test_pins_need_the_curves_angles():
    for call in (synth.analyze, check):
        with pytest.raises(synth.InvalidParameters) as e:
            call("crank_shaper", SHAPER, include=["pins"])
        assert e.value.loc == ("include",)
        assert "needs crank_angles_deg or samples" in e.value.msg


def test_pins_need_a_drawing():
    in_a_process_of_its_own(pins_need_a_drawing)


def pins_need_a_drawing():
    """A type registered without a drawing (in a process of its own: it stays registered)."""
    undrawn = replace(get("scotch_yoke"), type="undrawn_yoke", joints=None)
    synth.register(undrawn)
    check("undrawn_yoke", {"crank": 1.0}, samples=4, include=["motion"])  # pins only
    for call in (synth.analyze, check):
        for what in ("pins", "envelope"):  # the envelope is the pins' box
            with pytest.raises(synth.InvalidParameters) as e:
                call("undrawn_yoke", {"crank": 1.0}, samples=4, include=[what])
            assert e.value.loc == ("include",)
            assert f"include {what!r}: undrawn_yoke has no drawing" in e.value.msg
    with pytest.raises(synth.InvalidParameters, match="undrawn_yoke has no drawing"):
        synth.synthesize(1.0, 2.0, mechanisms=[{"type": "undrawn_yoke"}], include=["envelope"])


def test_pins_only_when_asked(monkeypatch):
    def never(*_):
        raise AssertionError("pins computed without being asked")

    monkeypatch.setattr(kinematics, "_pins", never)
    a = synth.analyze("crank_shaper", SHAPER, samples=8, include=["motion", "envelope"])
    assert a.curves.pins is None
    assert "pins" not in a.to_dict()["curves"]
    with pytest.raises(AssertionError, match="without being asked"):  # the guard does guard
        synth.analyze("crank_shaper", SHAPER, samples=8, include=["pins"])


def test_pins_in_the_dict_are_lists_by_pin():
    a = synth.analyze("crank_shaper", SHAPER, crank_angles_deg=[0.0, 90.0], include=["pins"])
    out = a.to_dict()["curves"]["pins"]
    j = synth.joints("crank_shaper", SHAPER, [0.0, 90.0])
    assert out == {k: {"x": v[:, 0].tolist(), "y": v[:, 1].tolist()} for k, v in j.items()}


def test_a_candidate_has_no_pins_to_include():
    """Pins come with curves, and a candidate has none: synthesis refuses to include them."""
    with pytest.raises(synth.InvalidParameters) as e:
        synth.synthesize(1.6, 300.0, 20.0, include=["pins"])
    assert e.value.loc == ("include",) and "'pins'" in e.value.msg
