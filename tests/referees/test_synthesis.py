"""synth.synthesize: the project of Podhorodeski et al. (2005), textbook inversions, infeasible
requests, determinism.

Every candidate is re-checked here against the brute-force simulator (tests/support/bruteforce.py),
which shares no code with synth.
"""

import math
import re

import pytest

import synth
from synth.synthesis.solve import multistart

from ..support import reference_cases as ref
from ..support.assertions import assert_meets
from ..support.reference_cases import podhorodeski_couplers

GENERIC = synth.Solver(accelerators=False)  # the generic path: the reduced solvers off


PROJECT = {"type": "drag_link_slider", "fixed": {**ref.DRAG_LINK_FIXED, "connecting_rod": 0.3}}


def test_drag_link_project_project_gives_exactly_the_two_couplers():
    r = synth.synthesize(ref.DRAG_LINK_TR, ref.DRAG_LINK_STROKE, 0.0, mechanisms=[PROJECT])
    assert r.complete and not r.infeasible
    couplers = sorted(c.params["coupler"] for c in r.candidates)
    assert len(couplers) == 2
    # eqs. (7)–(13) written out in the reference test, against the printed 0.1544 / 0.2504
    assert couplers == pytest.approx(podhorodeski_couplers(ref.DRAG_LINK_TR), rel=1e-12)
    assert couplers == pytest.approx(ref.DRAG_LINK_COUPLERS, abs=1e-4)
    for c in r.candidates:
        assert c.params["follower_arm"] == pytest.approx(0.15, rel=1e-12)
        assert c.method == "closed_form" and c.grashof == "drag-link"
        assert_meets(c, ref.DRAG_LINK_TR, ref.DRAG_LINK_STROKE, 0.0)
    # best first: the 0.2504 coupler transmits at 27.01°, the 0.1544 one at 9.09°
    assert [round(c.min_transmission_angle_deg, 2) for c in r.candidates] == [27.01, 9.09]


def test_drag_link_project_project_with_a_20deg_bound_keeps_only_the_long_coupler():
    r = synth.synthesize(ref.DRAG_LINK_TR, ref.DRAG_LINK_STROKE, 20.0, mechanisms=[PROJECT])
    (c,) = r.candidates
    assert c.params["coupler"] == pytest.approx(0.2504, abs=1e-4)
    assert_meets(c, ref.DRAG_LINK_TR, ref.DRAG_LINK_STROKE, 20.0)


def test_textbook_crank_shaper_inversion():
    spec = {"type": "crank_shaper", "fixed": {"pivot_distance": 240.0}}
    r = synth.synthesize(2.0, 450.0, mechanisms=[spec])
    best = r.candidates[0]  # the slot drive: 90°, the smaller mechanism
    assert best.params["crank"] == pytest.approx(120.0, rel=1e-12)
    assert best.params["lever"] == pytest.approx(450.0, rel=1e-12)
    assert best.params["ram_link"] == 0.0 and best.method == "closed_form"
    for c in r.candidates:
        assert_meets(c, 2.0, 450.0, 0.0)


def test_textbook_whitworth_inversion():
    spec = {"type": "whitworth", "fixed": {"pivot_distance": 50.0}}
    r = synth.synthesize(2.73524, 300.0, mechanisms=[spec])
    best = r.candidates[0]
    assert best.params["crank"] == pytest.approx(75.0, rel=1e-6)  # TR is given to 6 digits
    assert best.params["lever"] == pytest.approx(150.0, rel=1e-12)
    assert_meets(best, 2.73524, 300.0, 0.0)


def test_every_type_by_default_and_ranked_by_angle():
    r = synth.synthesize(1.5, 0.3, 20.0, objective="max_transmission_angle", max_candidates=50)
    assert r.complete and r.candidates
    mus = [round(c.min_transmission_angle_deg, 9) for c in r.candidates]
    assert mus == sorted(mus, reverse=True)
    assert {c.type for c in r.candidates} == {
        "offset_slider_crank",
        "crank_shaper",
        "whitworth",
        "crank_rocker_slider",
        "drag_link_slider",
    }
    for c in r.candidates:
        assert_meets(c, 1.5, 0.3, 20.0)


def test_min_size_ranks_by_size():
    r = synth.synthesize(1.5, 0.3, 20.0, objective="min_size", max_candidates=50)
    sizes = [c.size for c in r.candidates]
    assert sizes == sorted(sizes) and r.candidates[0].objective_value == sizes[0]
    for c in r.candidates:
        placements = ("offset", "ram_height", "slider_height")
        assert c.size == pytest.approx(sum(v for k, v in c.params.items() if k not in placements))
        assert_meets(c, 1.5, 0.3, 20.0)


def test_time_ratio_beyond_reach_says_how_far_the_type_goes():
    r = synth.synthesize(3.0, 100.0, 30.0, mechanisms=[{"type": "offset_slider_crank"}])
    assert not r.candidates
    (why,) = r.infeasible
    assert why.code == "TIME_RATIO_UNREACHABLE"
    top = float(why.reason.split(" … ")[1].split()[0])
    assert 1.2 < top < 3.0 and "transmission angle ≥ 30°" in why.reason
    # the reported reach is real: a design at that TR with the bound exists (just below it)
    below = synth.synthesize(top * 0.999, 100.0, 30.0, mechanisms=[{"type": "offset_slider_crank"}])
    assert below.candidates


def test_a_range_end_is_exact_and_kept_ranges_answer_alike():
    """The end a refused time ratio lies beyond is bisected to 1e-10: designs 1e-8 inside it
    pass the brute-force check, and 1e-8 outside it is refused with the same end. The range is
    kept per process; the order of the questions changes no number."""
    from synth.synthesis.diagnose import forget_ranges

    def reach(tr):
        (why,) = synth.synthesize(tr, ref.DRAG_LINK_STROKE, 0.0, mechanisms=[PROJECT]).infeasible
        assert why.code == "TIME_RATIO_UNREACHABLE"
        return why.time_ratio_range

    forget_ranges()
    low, high = reach(1.2)[0], reach(10.0)[1]
    forget_ranges()
    assert (reach(10.0)[1], reach(1.2)[0]) == (high, low)
    assert 1.4298 < low < 1.4299 and 3.5381 < high < 3.5382
    inside = synth.synthesize(low * (1 + 1e-8), ref.DRAG_LINK_STROKE, 0.0, mechanisms=[PROJECT])
    assert inside.candidates
    for c in inside.candidates:
        assert_meets(c, low * (1 + 1e-8), ref.DRAG_LINK_STROKE, 0.0)
    assert reach(low * (1 - 1e-8))[0] == low


@pytest.mark.parametrize(
    ("mtype", "rod", "tr", "bound"),
    [("crank_rocker_slider", "connecting_rod", 1.6, 20.0), ("crank_shaper", "ram_link", 2.5, 10.0)],
)
def test_a_rod_from_a_swinging_arm_keeps_the_slider_moving_one_way(mtype, rod, tr, bound):
    """With the slot drive bounded out, the smallest design with a rod was one whose rod was
    so short that the slider turned back within each swing (four reversals): it failed the
    analysis and the request was refused, though designs exist."""
    spec = [{"type": mtype, "bounds": {rod: (0.05, 5.0)}}]
    r = synth.synthesize(tr, 1.0, bound, mechanisms=spec, objective="min_size")
    assert r.candidates, r.infeasible
    for c in r.candidates:
        assert c.params[rod] >= 0.05
        assert_meets(c, tr, 1.0, bound)


@pytest.mark.parametrize(("ground", "smallest"), [(2.0, 6.1086), (4.0, 10.8649)])
def test_the_smallest_four_bar_with_a_fixed_link_is_searched_on_both_families(ground, smallest):
    """With the ground fixed the other family of the dead-centre construction holds the
    smallest design (6.1086 against 6.9075, 10.8649 against 13.1654, both also found by the
    generic multistart); only one family was searched."""
    fixed = {"ground": ground, "connecting_rod": 0.0}
    r = synth.synthesize(
        1.3, 1.0, 20.0, [{"type": "crank_rocker_slider", "fixed": fixed}], objective="min_size"
    )
    (c,) = r.candidates
    assert c.size == pytest.approx(smallest, abs=1e-4)
    assert_meets(c, 1.3, 1.0, 20.0)


@pytest.mark.parametrize(
    "tr, stroke, follower",
    [
        (1.0255889517581471, 0.6098632148922783, 0.40052145596204525),
        (1.0461947415855506, 24.278736481423202, 34.765720600521206),
    ],
)
def test_a_fixed_follower_with_two_links_at_their_bounds_is_answered_exactly(tr, stroke, follower):
    """The best drag-link with its follower fixed lies where a link's bound cuts the curve
    off at a second bound (a corner the pairs' ranking missed), or beside a grid minimum
    where Newton fails, far worse than the best: both went to IPOPT (~100 ms); benchmark
    targets drag_link_slider/f007 and f086. The answer must be the generic multistart's."""
    mechs = [{"type": "drag_link_slider", "fixed": {"follower": follower}}]
    (c,) = synth.synthesize(tr, stroke, 0.0, mechs, max_candidates=1).candidates
    (g,) = synth.synthesize(tr, stroke, 0.0, mechs, max_candidates=1, solver=GENERIC).candidates
    assert c.method == "closed_form"
    assert c.min_transmission_angle_deg >= g.min_transmission_angle_deg - 1e-9
    assert_meets(c, tr, stroke, 0.0)


@pytest.mark.parametrize("tr", [1 + 5e-9, 1 + 2e-8, 1 + 1e-6, 1 + 1e-4])
def test_offset_slider_crank_near_time_ratio_one(tr):
    """The smallest design near TR 1 lost its digits (c² − y² with y → c → 1): a division by
    zero (HTTP 500) just above TR 1 + 1e-9, refusals up to 1 + 1e-5."""
    r = synth.synthesize(tr, 1.0, 10.0, [{"type": "offset_slider_crank"}], objective="min_size")
    (c,) = r.candidates
    assert_meets(c, tr, 1.0, 10.0)


def test_transmission_bound_above_any_design():
    r = synth.synthesize(ref.DRAG_LINK_TR, ref.DRAG_LINK_STROKE, 50.0, mechanisms=[PROJECT])
    (why,) = r.infeasible
    assert why.code == "TRANSMISSION_UNREACHABLE"
    assert "27.008" in why.reason and "below the bound 50°" in why.reason


def test_a_refusal_a_default_bound_set_says_so_and_what_lifting_it_reaches():
    """The best angle within the default bounds is not the type's best: the reason names the
    default bound its best design rests on, and the least limit that meets the bound. Bounded
    just above that limit, the designs come (the brute force checks them); just below, the
    refusal stays."""
    (why,) = synth.synthesize(1.6, 300.0, 80.0, mechanisms=["whitworth"]).infeasible
    assert why.code == "TRANSMISSION_UNREACHABLE" and "75.5225°" in why.reason
    rests = "default bound connecting_rod ≤ 600: with connecting_rod ≤ "
    said = re.search(rests + r"(\S+) it meets 80°", why.reason)
    assert said, why.reason
    least = float(said[1])
    above = {"type": "whitworth", "bounds": {"connecting_rod": [30.0, least * (1 + 1e-5)]}}
    c = synth.synthesize(1.6, 300.0, 80.0, mechanisms=[above]).candidates[0]
    assert_meets(c, 1.6, 300.0, 80.0)
    assert c.params["connecting_rod"] > 600.0
    below = {"type": "whitworth", "bounds": {"connecting_rod": [30.0, least * (1 - 1e-4)]}}
    (short,) = synth.synthesize(1.6, 300.0, 80.0, mechanisms=[below]).infeasible
    assert short.code == "TRANSMISSION_UNREACHABLE" and short.best_transmission_angle_deg < 80.0
    # past what lifting reaches (ten times the default), the reach itself
    (far,) = synth.synthesize(1.6, 300.0, 89.5, mechanisms=["whitworth"]).infeasible
    said = re.search(r"with connecting_rod ≤ 6000 it reaches (\S+)° ", far.reason)
    assert said, far.reason
    lifted = {"type": "whitworth", "bounds": {"connecting_rod": [30.0, 6000.0]}}
    (top,) = synth.synthesize(1.6, 300.0, 89.5, mechanisms=[lifted]).infeasible
    assert f"{top.best_transmission_angle_deg:.4f}" == said[1]


def test_the_best_angle_in_a_refusal_is_over_every_variant():
    """The reason's best angle is the best of the slot drive and the rod variant (it was the
    rod variant's alone: 0.95° where a 12.9° slot drive exists); found by the benchmarks."""
    spec = [{"type": "crank_rocker_slider"}]
    (why,) = synth.synthesize(2.5581, 0.5785, 89.9, mechanisms=spec).infeasible
    best = synth.synthesize(2.5581, 0.5785, 0.0, mechanisms=spec).candidates[0]
    assert why.code == "TRANSMISSION_UNREACHABLE"
    assert f"{best.min_transmission_angle_deg:.4f}°" in why.reason


@pytest.mark.parametrize("mtype", ["crank_rocker_slider", "drag_link_slider"])
def test_a_bound_no_rod_meets_is_refused_without_ipopt(mtype):
    """min_size at 89.9°: no rod is long enough, so the rod variant's grid had no start and
    its answer was inexact; IPOPT searched, then diagnosed (200–300 ms for a refusal). A rod
    only adds a joint: the best coupler without it already misses the bound. The angle is
    the generic path's (IPOPT's)."""
    spec = [{"type": mtype}]
    generic = synth.synthesize(1.6, 1.0, 89.9, spec, objective="min_size", solver=GENERIC)
    runs = []
    counted = synth.Solver(local=lambda *a, **k: runs.append(1) or multistart(*a, **k))
    (why,) = synth.synthesize(1.6, 1.0, 89.9, spec, objective="min_size", solver=counted).infeasible
    assert why.code == "TRANSMISSION_UNREACHABLE" and not runs
    (other,) = generic.infeasible
    assert why.best_transmission_angle_deg == pytest.approx(
        other.best_transmission_angle_deg, abs=1e-6
    )


def test_fixed_parts_that_contradict_the_targets():
    spec = {"type": "crank_shaper", "fixed": {"pivot_distance": 240.0, "lever": 400.0}}
    (why,) = synth.synthesize(2.0, 450.0, mechanisms=[spec]).infeasible
    assert why.code == "FIXED_PARTS_CONTRADICT_TARGETS"
    assert why.reason.startswith("lever 400 gives stroke 400, not 450")
    spec = {"type": "crank_shaper", "fixed": {"crank": 300.0, "pivot_distance": 240.0}}
    (why,) = synth.synthesize(2.0, 450.0, mechanisms=[spec]).infeasible
    assert why.code == "FIXED_PARTS_INVALID"
    assert "crank 300 ≥ pivot_distance 240" in why.reason
    (why,) = synth.synthesize(1.5, 10.0, mechanisms=[{"type": "scotch_yoke"}]).infeasible
    assert why.code == "TIME_RATIO_UNREACHABLE" and "time ratio 1 for every design" in why.reason


def test_same_request_same_answer():
    def run():
        r = synth.synthesize(1.5, 0.3, 20.0).to_dict()
        r.pop("elapsed_ms")
        return r

    assert run() == run()


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"time_ratio": 0.9}, "time_ratio"),
        ({"time_ratio": math.nan}, "time_ratio"),
        ({"stroke": 0.0}, "stroke"),
        ({"min_transmission_angle_deg": 90.0}, "min_transmission_angle_deg"),
        ({"objective": "cheapest"}, "objective"),
        ({"max_candidates": 0}, "max_candidates"),
        ({"time_budget_ms": -1.0}, "time_budget_ms"),
    ],
)
def test_bad_targets_name_the_field(kwargs, field):
    args = {"time_ratio": 1.5, "stroke": 1.0, **kwargs}
    with pytest.raises(synth.InvalidParameters) as e:
        synth.synthesize(**args)
    assert e.value.loc == (field,)


def test_bad_specs_name_the_field():
    both = {"type": "whitworth", "fixed": {"lever": 1.0}, "bounds": {"lever": (1, 2)}}
    with pytest.raises(synth.InvalidParameters, match="both fixed and bounded"):
        synth.synthesize(1.5, 1.0, mechanisms=[both])
    with pytest.raises(synth.InvalidParameters, match=r"bounds \[2, 1\]"):
        synth.synthesize(1.5, 1.0, mechanisms=[{"type": "whitworth", "bounds": {"lever": (2, 1)}}])
    with pytest.raises(synth.InvalidParameters, match="has no parameter 'rod'"):
        synth.synthesize(1.5, 1.0, mechanisms=[{"type": "whitworth", "fixed": {"rod": 1.0}}])
    with pytest.raises(synth.UnknownMechanism):
        synth.synthesize(1.5, 1.0, mechanisms=[{"type": "cam"}])


def test_time_budget_gives_a_partial_answer():
    r = synth.synthesize(1.5, 0.3, 20.0, time_budget_ms=0.01)
    assert r.complete is False
    for c in r.candidates:  # what was found is still verified
        assert_meets(c, 1.5, 0.3, 20.0)


def test_fixed_parts_are_judged_to_the_verification_tolerance():
    """Fixed parts that meet the targets to 1e-12 (not exactly) are accepted, as the
    verification accepts 1e-9; both were refused when they had to meet them to 1e-12."""
    shaper = "crank_shaper"
    fixed = {"crank": 73.40735881448646, "pivot_distance": 156.49970186740697}
    r = synth.synthesize(1.9019683255535618, 300.0, mechanisms=[{"type": shaper, "fixed": fixed}])
    assert r.candidates and not r.infeasible
    for c in r.candidates:
        assert_meets(c, 1.9019683255535618, 300.0, 0.0)
    fixed = {"lever": 0.0258864340902721, "pivot_distance": 0.013148507569858659}
    tr, stroke = 1.2239479903544184, 0.008155153404085756
    r = synth.synthesize(tr, stroke, mechanisms=[{"type": shaper, "fixed": fixed}])
    assert r.candidates and not r.infeasible
    for c in r.candidates:
        assert_meets(c, tr, stroke, 0.0)


def test_a_contradiction_beyond_the_tolerance_shows_the_difference():
    """Just past the tolerance the two numbers agree to 9 digits: the message prints enough
    digits to tell them apart."""
    fixed = {"lever": 0.0258864340902721, "pivot_distance": 0.013148507569858659}
    spec = {"type": "crank_shaper", "fixed": fixed}
    (why,) = synth.synthesize(
        1.2239479903544184, 0.008155153404085756 * (1 + 2e-9), mechanisms=[spec]
    ).infeasible
    assert why.code == "FIXED_PARTS_CONTRADICT_TARGETS"
    got, want = why.reason.split(" gives stroke ")[1].split(" (")[0].split(", not ")
    assert got != want and float(got) != float(want)
