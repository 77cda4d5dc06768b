"""Every validity condition and parameter check, broken on purpose, with its message checked."""

import math

import numpy as np
import pytest

import synth
from synth.errors import InvalidDesign, InvalidParameters, UnknownMechanism
from synth.mechanisms import all_types, get

from ..support.designs import random_designs

# (type, design that breaks exactly the named condition, condition, message pattern)
# a table: one broken design a line
# fmt: off
BROKEN = [
    ("offset_slider_crank", {"crank": 1.0, "coupler": 2.0, "offset": 1.5}, "full_rotation",
     r"coupler 2 < crank 1 \+ \|offset\| 1\.5 = 2\.5: the crank cannot turn a full revolution"),
    ("offset_slider_crank", {"crank": 1.0, "coupler": 2.0, "offset": -1.5}, "full_rotation",
     r"coupler 2 < crank 1 \+ \|offset\| 1\.5"),
    ("crank_shaper", {"crank": 2.0, "pivot_distance": 1.0, "lever": 4.0}, "oscillating_lever",
     r"crank 2 ≥ pivot_distance 1: the lever would turn a full revolution \(that is a whitworth\)"),
    ("crank_shaper", {"crank": 1.0, "pivot_distance": 1.0, "lever": 4.0}, "oscillating_lever",
     r"crank 1 ≥ pivot_distance 1"),
    ("crank_shaper", {"crank": 40.0, "pivot_distance": 160.0, "lever": 190.0}, "block_on_lever",
     r"lever 190 < pivot_distance 160 \+ crank 40 = 200: the crank-pin block runs off"),
    ("crank_shaper", {"crank": 40.0, "pivot_distance": 160.0, "lever": 240.0, "ram_link": 5.0,
                      "ram_height": 250.0}, "ram_link_reach",
     r"ram_link 5 < 17\.621\d*, the largest distance from the lever tip to the ram path"),
    ("whitworth", {"crank": 50.0, "pivot_distance": 75.0, "lever": 150.0,
                   "connecting_rod": 200.0}, "rotating_lever",
     r"crank 50 ≤ pivot_distance 75: the lever cannot turn a full revolution"),
    ("whitworth", {"crank": 75.0, "pivot_distance": 50.0, "lever": 150.0,
                   "connecting_rod": 150.0}, "rod_reach",
     r"connecting_rod 150 ≤ lever 150: the rod cannot reach the ram path"),
    ("crank_rocker_slider", {"ground": 1.0, "crank": 0.5, "coupler": 0.6, "rocker": 0.7,
                             "rocker_arm": 1.0}, "grashof_ground",
     r"crank 0\.5 \+ ground 1 = 1\.5 > coupler 0\.6 \+ rocker 0\.7 = 1\.3: not a crank-rocker"),
    ("crank_rocker_slider", {"ground": 1.0, "crank": 0.5, "coupler": 2.0, "rocker": 1.0,
                             "rocker_arm": 1.0}, "grashof_coupler",
     r"crank 0\.5 \+ coupler 2 = 2\.5 > ground 1 \+ rocker 1 = 2: not a crank-rocker"),
    ("crank_rocker_slider", {"ground": 1.0, "crank": 0.5, "coupler": 1.0, "rocker": 2.0,
                             "rocker_arm": 1.0}, "grashof_rocker",
     r"crank 0\.5 \+ rocker 2 = 2\.5 > ground 1 \+ coupler 1 = 2: not a crank-rocker"),
    ("crank_rocker_slider", {"ground": 1.0, "crank": 0.3, "coupler": 1.1, "rocker": 0.8,
                             "rocker_arm": 0.9, "connecting_rod": 0.05, "slider_height": 1.2},
     "rod_reach", r"connecting_rod 0\.05 < 0\.3\d*, the largest distance from the pin C"),
    ("drag_link_slider", {"ground": 0.1, "crank": 0.225, "coupler": 0.5, "follower": 0.275,
                          "follower_arm": 0.15, "connecting_rod": 0.3}, "grashof_coupler",
     r"ground 0\.1 \+ coupler 0\.5 = 0\.6 > crank 0\.225 \+ follower 0\.275 = 0\.5: not a "
     r"drag-link"),
    ("drag_link_slider", {"ground": 0.1, "crank": 0.225, "coupler": 0.1, "follower": 0.275,
                          "follower_arm": 0.15, "connecting_rod": 0.3}, "grashof_follower",
     r"ground 0\.1 \+ follower 0\.275 = 0\.375 > crank 0\.225 \+ coupler 0\.1 = 0\.325"),
    ("drag_link_slider", {"ground": 0.1, "crank": 0.5, "coupler": 0.3, "follower": 0.275,
                          "follower_arm": 0.15, "connecting_rod": 0.3}, "grashof_crank",
     r"ground 0\.1 \+ crank 0\.5 = 0\.6 > coupler 0\.3 \+ follower 0\.275 = 0\.575"),
    ("drag_link_slider", {"ground": 0.1, "crank": 0.225, "coupler": 0.25, "follower": 0.275,
                          "follower_arm": 0.15, "connecting_rod": 0.15}, "rod_reach",
     r"connecting_rod 0\.15 ≤ follower_arm 0\.15: the rod cannot reach the piston path"),
]
# fmt: on


@pytest.mark.parametrize(("mtype", "params", "condition", "pattern"), BROKEN)
def test_broken_condition_is_named_with_numbers(mtype, params, condition, pattern):
    with pytest.raises(InvalidDesign, match=pattern) as e:
        synth.analyze(mtype, params)
    assert e.value.condition == condition
    cond = next(c for c in get(mtype).conditions if c.name == condition)
    assert e.value.loc == cond.params and set(e.value.loc) <= set(get(mtype).names)


def test_every_condition_has_a_breaking_case():
    covered = {(t, c) for t, _, c, _ in BROKEN}
    every = {(t, c.name) for t in all_types() for c in get(t).conditions}
    assert every == covered


def test_boundary_designs_are_valid():
    """Non-strict conditions hold at equality (the drag-link project's couplers 0.15 and 0.40
    are in range); the strict ones' equality cases are in BROKEN."""
    synth.analyze("offset_slider_crank", {"crank": 1.0, "coupler": 2.5, "offset": 1.5})
    synth.analyze("crank_shaper", {"crank": 40.0, "pivot_distance": 160.0, "lever": 200.0})
    for r3 in (0.15, 0.40):
        synth.analyze(
            "drag_link_slider",
            {
                "ground": 0.1,
                "crank": 0.225,
                "coupler": r3,
                "follower": 0.275,
                "follower_arm": 0.15,
                "connecting_rod": 0.3,
            },
        )


BAD_PARAMS = [
    (
        {"crank": 1.0, "coupler": 3.0, "offset": 0.0, "rod": 1.0},
        "rod",
        r"offset_slider_crank has no parameter 'rod'; its parameters: crank, coupler, offset",
    ),
    ({"crank": 1.0, "offset": 0.0}, "coupler", r"offset_slider_crank needs 'coupler'"),
    (
        {"crank": -1.0, "coupler": 3.0, "offset": 0.0},
        "crank",
        r"offset_slider_crank.crank is a length and must be > 0, got -1",
    ),
    ({"crank": 0.0, "coupler": 3.0, "offset": 0.0}, "crank", r"must be > 0, got 0"),
    ({"crank": math.nan, "coupler": 3.0, "offset": 0.0}, "crank", r"must be finite, got nan"),
    ({"crank": 1.0, "coupler": math.inf, "offset": 0.0}, "coupler", r"must be finite, got inf"),
    ({"crank": 1.0, "coupler": 3.0, "offset": "x"}, "offset", r"must be a number, got 'x'"),
]


@pytest.mark.parametrize(("params", "field", "pattern"), BAD_PARAMS)
def test_bad_parameters(params, field, pattern):
    with pytest.raises(InvalidParameters, match=pattern) as e:
        synth.analyze("offset_slider_crank", params)
    assert e.value.loc == (field,)


def test_zero_selects_a_variant_but_negative_does_not():
    base = {"crank": 40.0, "pivot_distance": 160.0, "lever": 240.0}
    assert synth.analyze("crank_shaper", {**base, "ram_link": 0.0}).transmission.joints == ()
    with pytest.raises(InvalidParameters, match=r"must be ≥ 0 \(0 means the lever tip drives"):
        synth.analyze("crank_shaper", {**base, "ram_link": -1.0})


def test_unknown_type_lists_the_known_ones():
    with pytest.raises(UnknownMechanism, match="known types: scotch_yoke, offset_slider_crank"):
        synth.analyze("slider_crank", {"crank": 1.0})


def test_conditioning_flags_a_change_point_and_a_dead_point():
    """The drag-link project's coupler 0.40 is on the Grashof limit: the linkage folds flat
    (μ = 0°)."""
    p = {
        "ground": 0.1,
        "crank": 0.225,
        "coupler": 0.40,
        "follower": 0.275,
        "follower_arm": 0.15,
        "connecting_rod": 0.3,
    }
    c = synth.analyze("drag_link_slider", p).conditioning
    assert c.validity_margin == 0.0 and c.limiting_condition == "grashof_coupler"
    assert c.dead_point_margin_deg == 0.0
    assert c.flags == ("near_dead_point", "near_validity_limit")
    ok = synth.analyze("drag_link_slider", {**p, "coupler": 0.2504}).conditioning
    # nearest limit: ground + follower ≤ crank + coupler, 0.1004 short of it, over 0.3
    assert ok.flags == () and ok.limiting_condition == "grashof_follower"
    assert ok.validity_margin == pytest.approx((0.225 + 0.2504 - 0.1 - 0.275) / 0.3)


@pytest.mark.parametrize("mtype", all_types())
def test_a_condition_names_every_parameter_its_margin_moves(mtype):
    """Each condition's parameters (where its 422 points) are exactly those that move its
    margin: each length nudged by 1e-6 relative on random designs, one at a time. The review's
    case: a crank-rocker's rod reach also depends on the four-bar (its swing)."""
    m = get(mtype)
    moved = {c.name: set() for c in m.conditions}
    for design in random_designs(mtype, 20, seed=7):
        p = m.complete(design)
        for c in m.conditions:
            if not c.applies(m.variant(p)):
                continue
            base = np.array([float(t) for t in c.margin(p)])
            for k in m.names:
                q = dict(p, **{k: p[k] * (1 + 1e-6) + 1e-9})
                if np.any(np.abs(np.array([float(t) for t in c.margin(q)]) - base) > 1e-13):
                    moved[c.name].add(k)
    for c in m.conditions:
        assert set(c.params) == moved[c.name], c.name
    if mtype == "crank_rocker_slider":
        (reach,) = (c for c in m.conditions if c.name == "rod_reach")
        assert {"ground", "crank", "coupler", "rocker"} <= set(reach.params)
