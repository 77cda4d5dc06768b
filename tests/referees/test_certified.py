"""The certified motion optima (synth.synthesis.certify: the least peak acceleration, the most
uniform cutting speed) against designs drawn and measured from outside.

A certified candidate claims that no design of its type at the targets measures below
value × (1 − gap). Here the designs that meet the targets are drawn by their own geometry (the
offset slider-crank's textbook construction: the crank pivot on the circle that sees the stroke
under β; the Whitworth's pivot ratio and lever, each rod), within the request's box, checked
and measured by the brute-force simulation (tests/support/bruteforce.py, motion_bruteforce.py),
coarse and then twice densely about the best drawn: none that meets the bound may measure below
the claim, and the draw must come close to the certified value (else it would be too sparse to
judge). The certified design itself is measured by brute force too.
"""

from __future__ import annotations

import os
import time

import pytest

import synth
from synth.synthesis import certify

from ..support.constructions import BOX, DRAWN, least_drawn
from ..support.motion_bruteforce import brute_motion

PEAK, UNIFORM = "min_peak_acceleration", "uniform_cutting_speed"
# `make stress`: every time ratio 1.3, 1.6, 2.0, 2.5 with every bound 0, 10, 20, 30, 40° that
# the type reaches (20 targets per type and objective)
STRESS = os.environ.get("HYPOTHESIS_PROFILE") == "stress"
TARGETS = (
    [(tr, b) for tr in (1.3, 1.6, 2.0, 2.5) for b in (0.0, 10.0, 20.0, 30.0, 40.0)]
    if STRESS
    else [(1.3, 0.0), (1.6, 20.0), (2.0, 10.0), (2.5, 0.0)]
)
BEATEN = 1e-8  # relative: the brute force's own error on the measure
NEAR = 1e-3  # relative: the draw's best must come this close to the certified value


def brute(mtype, p, objective=PEAK):
    """The objective's measure by brute force."""
    _, middle, working, ret = brute_motion(mtype, p)
    return max(working, ret) if objective == PEAK else middle


def request(mtype, tr, bound, objective):
    bounds = {k: list(v) for k, v in BOX[mtype].items()}
    mechanisms = [{"type": mtype, "bounds": bounds}]
    return synth.synthesize(tr, 1.0, bound, mechanisms, objective=objective)


@pytest.mark.parametrize("objective", [PEAK, UNIFORM])
@pytest.mark.parametrize(("tr", "bound"), TARGETS)
@pytest.mark.parametrize("mtype", list(DRAWN))
def test_no_design_measures_below_the_certificate(mtype, tr, bound, objective):
    r = request(mtype, tr, bound, objective)
    if not r.candidates:  # a bound the type cannot reach at that ratio: it says so
        assert STRESS and r.infeasible[0].code == "TRANSMISSION_UNREACHABLE"
        return
    c = r.candidates[0]
    assert r.complete and c.certified and c.gap <= certify.TOL
    assert c.objective_value == pytest.approx(brute(mtype, c.params, objective), rel=1e-9)
    claim = c.objective_value * (1 - c.gap)
    # a global search of its own over the family: a coarse draw, then densely about its best
    best, drawn, tried = least_drawn(
        mtype, tr, bound, lambda p: brute(mtype, p, objective), BOX[mtype]
    )
    assert drawn > tried / 3
    assert best[0] >= claim * (1 - BEATEN), f"{best} beats the certificate {claim}"
    assert best[0] <= c.objective_value * (1 + NEAR), "the draw is too sparse to judge"


def test_every_other_candidate_of_the_type_says_how_far_it_is():
    r = synth.synthesize(
        1.6, 300.0, 20.0, [{"type": "offset_slider_crank"}], objective=PEAK, max_candidates=5
    )
    first, *rest = r.candidates
    bound = first.objective_value * (1 - first.gap)
    assert rest and all(not c.certified for c in rest)
    for c in rest:
        assert c.gap == pytest.approx((c.objective_value - bound) / c.objective_value, rel=1e-9)


def test_a_search_stopped_short_is_not_certified(monkeypatch):
    monkeypatch.setattr(certify, "LEVELS", 3)
    r = synth.synthesize(1.6, 300.0, 20.0, [{"type": "offset_slider_crank"}], objective=PEAK)
    c = r.candidates[0]
    assert not c.certified and c.gap > certify.TOL
    monkeypatch.undo()
    best = synth.synthesize(1.6, 300.0, 20.0, [{"type": "offset_slider_crank"}], objective=PEAK)
    assert best.candidates[0].certified
    # the short search's bound holds still
    assert best.candidates[0].objective_value >= c.objective_value * (1 - c.gap) * (1 - 1e-12)


def test_a_deadline_inside_a_level_stops_the_search_there(monkeypatch):
    """The clock passes the deadline after the certified search's fifth look, one box a
    chunk (and the box not cut before the first level): the search stops inside its second
    level, measures nothing more, and says so (the answer is not certified); the bound it
    gives (the boxes bounded so far, the others their parents') holds."""
    looks, real = [], time.monotonic

    class Clock:
        @staticmethod
        def monotonic():
            looks.append(1)
            return real() + (1e9 if len(looks) > 5 else 0.0)

    measured = []
    acceleration = certify.MEASURES["acceleration"]

    class Counted(acceleration):
        @staticmethod
        def measure(kin, points, k):
            measured.append(len(looks))
            return acceleration.measure(kin, points, k)

    found, search = [], certify.search

    def recorded(*args, **kwargs):
        found.append(search(*args, **kwargs))
        return found[-1]

    monkeypatch.setattr(certify, "time", Clock)
    monkeypatch.setattr(certify, "CHUNK", 1)
    monkeypatch.setattr(certify, "FIRST", {})
    monkeypatch.setattr(certify, "MEASURES", {**certify.MEASURES, "acceleration": Counted})
    monkeypatch.setattr(certify, "search", recorded)
    r = synth.synthesize(1.6, 300.0, 20.0, [{"type": "offset_slider_crank"}], objective=PEAK)
    (cert,) = found
    assert not cert.complete and cert.levels == 2 and not r.candidates[0].certified
    assert max(measured) <= 5  # nothing measured after the clock passed the deadline
    monkeypatch.undo()
    best = synth.synthesize(1.6, 300.0, 20.0, [{"type": "offset_slider_crank"}], objective=PEAK)
    assert best.candidates[0].certified
    assert best.candidates[0].objective_value >= cert.bound * (1 - 1e-12)


@pytest.mark.parametrize(
    ("mtype", "fixed"),
    [
        ("offset_slider_crank", {"coupler": 0.9}),
        ("whitworth", {"crank": 0.3}),
        ("whitworth", {"connecting_rod": 1.5}),
    ],
)
def test_with_a_part_fixed_the_answer_is_certified_too(mtype, fixed):
    """One part fixed: the slider-crank's design is then the one its coupler sets, the
    Whitworth's family the same motion as with nothing fixed (its crank a free scale) or its
    rod's one design: the certified value is the brute force's of that design, and no less
    than the best of the type with nothing fixed."""
    r = synth.synthesize(1.6, 1.0, 20.0, [{"type": mtype, "fixed": fixed}], objective=PEAK)
    c = r.candidates[0]
    assert c.certified and c.gap <= certify.TOL
    assert all(c.params[k] == v for k, v in fixed.items())
    assert c.objective_value == pytest.approx(brute(mtype, c.params), rel=1e-9)
    free = synth.synthesize(1.6, 1.0, 20.0, [{"type": mtype}], objective=PEAK).candidates[0]
    assert c.objective_value >= free.objective_value * (1 - 1e-12)
    if "crank" in fixed:  # a scale: the same optimum
        assert c.objective_value == pytest.approx(free.objective_value, rel=1e-12)


def test_an_answer_not_certified_says_why(monkeypatch):
    """Every searched answer is certified or says why not: the four-bars (no certified
    search), the crank shaper's most uniform speed (its two free numbers), a guide's friction
    (the torque's bound does not hold), a search stopped at its level limit; the scotch
    yoke's one design is certified, its measure the brute force's."""
    for mtype, objective, why in (
        ("drag_link_slider", PEAK, "drag_link_slider's designs are no box of free numbers"),
        ("crank_rocker_slider", PEAK, "crank_rocker_slider's designs are no box"),
        ("crank_shaper", UNIFORM, "over crank_shaper's 2 free numbers"),
    ):
        r = synth.synthesize(1.6, 300.0, 20.0, [{"type": mtype}], objective=objective)
        assert r.candidates and r.complete
        for c in r.candidates:
            assert not c.certified and c.gap is None
            assert c.uncertified.startswith(why)
            assert c.uncertified.endswith("SLSQP's local optimum from ranked starts")
    rubbing = synth.Load(
        length_unit="mm", crank_rpm=40, cutting_force=2000, slider_mass=20, guide_friction=0.1
    )
    r = synth.synthesize(
        1.6, 300.0, 20.0, [{"type": "offset_slider_crank"}], "min_peak_torque", load=rubbing
    )
    assert r.candidates and not any(c.certified for c in r.candidates)
    assert r.candidates[0].uncertified.startswith(
        "the certified bound on the peak torque does not hold with a force profile or guide"
    )
    yoke = synth.synthesize(1.0, 300.0, 20.0, [{"type": "scotch_yoke"}], objective=UNIFORM)
    (c,) = yoke.candidates
    assert c.certified and c.uncertified is None
    assert c.objective_value == pytest.approx(brute("scotch_yoke", c.params, UNIFORM), rel=1e-9)
    monkeypatch.setattr(certify, "LEVELS", 3)
    r = synth.synthesize(1.6, 300.0, 20.0, [{"type": "offset_slider_crank"}], objective=PEAK)
    c = r.candidates[0]
    assert r.complete and not c.certified and c.gap > certify.TOL
    assert c.uncertified.startswith("the certified search stopped at its limit (3 levels")
