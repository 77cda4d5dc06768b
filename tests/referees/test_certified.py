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

import math
import os

import numpy as np
import pytest

import synth
from synth.synthesis import certify

from ..support import bruteforce
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


def slider_crank_designs(tr, angles):
    """Designs at stroke 1 and time ratio ``tr`` by the textbook construction: the dead centres
    C1 = (0, 0) and C2 = (1, 0), the crank pivot O on the circle through them where C1 O C2 = β
    = π(TR − 1)/(TR + 1), at each angle φ about its centre; |O C1| and |O C2| are l − r and
    l + r (the dead centres on one side of O's foot), O's height the offset. Those whose crank
    turns fully."""
    beta = math.pi * (tr - 1) / (tr + 1)
    radius, cy = 0.5 / math.sin(beta), 0.5 / math.tan(beta)
    out = []
    for phi in angles:
        ox, oy = 0.5 + radius * math.cos(phi), cy + radius * math.sin(phi)
        a, b = math.hypot(ox - 1, oy), math.hypot(ox, oy)
        seen = math.acos(max(-1.0, min(1.0, (ox * (ox - 1) + oy * oy) / (a * b))))
        crank, rod = abs(a - b) / 2, (a + b) / 2
        beside = ox <= 0 or ox >= 1  # both dead centres on one side of O's foot, as they are
        if oy > 0 and beside and abs(seen - beta) < 1e-9 and rod > crank + oy:
            out.append({"crank": crank, "coupler": rod, "offset": oy})
    return out


def whitworth_designs(tr, rods):
    """Designs at stroke 1 and time ratio ``tr``: pivot_distance/crank = sin(β/2) (the quick
    stroke's half angle is acos(d/r2) = π/(1 + TR)), lever 1/2, one per rod."""
    d = math.cos(math.pi / (1 + tr))
    return [{"crank": 1.0, "pivot_distance": d, "lever": 0.5, "connecting_rod": x} for x in rods]


# each type's designs at the targets, by the number that places them, over its range (the
# Whitworth's rod: its default bounds, up to 2 strokes), and its worst transmission cosine by
# the textbook's formula, to draw where the bound holds
DRAWN = {
    "offset_slider_crank": (
        slider_crank_designs,
        (0.0, 2 * math.pi),
        lambda p: (p["crank"] + p["offset"]) / p["coupler"],
    ),
    "whitworth": (whitworth_designs, (0.5, 2.0), lambda p: p["lever"] / p["connecting_rod"]),
}
COARSE, FINE = 60, 41
ACROSS_DEG = math.degrees(math.acos(1 - 1e-3))  # the least angle the motion searches keep
# the box of every request here (the types' default bounds, stroke units), which the draw keeps
BOX = {
    "offset_slider_crank": {"crank": (0.1, 5.0), "coupler": (0.1, 2.0), "offset": (0.0, 5.0)},
    "whitworth": {"connecting_rod": (0.1, 2.0)},
}


def within(mtype, p):
    return all(lo <= p[k] <= hi for k, (lo, hi) in BOX[mtype].items())


def request(mtype, tr, bound, objective):
    bounds = {k: list(v) for k, v in BOX[mtype].items()}
    mechanisms = [{"type": mtype, "bounds": bounds}]
    return synth.synthesize(tr, 1.0, bound, mechanisms, objective=objective)


def feasible(mtype, tr, bound):
    """The numbers, on a grid of 4 000, whose designs meet the bound (the cosine's formula),
    and the grid's step."""
    designs, (lo, hi), cos_mu = DRAWN[mtype]
    grid = np.linspace(lo, hi, 4001)[1:]
    ok = [x for x in grid for p in designs(tr, [x]) if cos_mu(p) <= math.cos(math.radians(bound))]
    return np.array(ok), grid[1] - grid[0]


def measured(mtype, tr, bound, values, objective):
    """(measure, value) of each drawn design that meets the targets and the bound, by brute
    force."""
    designs = DRAWN[mtype][0]
    out = []
    for x in values:
        for p in designs(tr, [x]):
            try:
                b = bruteforce.simulate(mtype, p, n=4000)
            except (ValueError, ZeroDivisionError):  # a degenerate end of the family
                continue
            if b["min_transmission_deg"] >= max(bound, ACROSS_DEG) and within(mtype, p):
                assert b["time_ratio"] == pytest.approx(tr, rel=1e-9)
                assert b["stroke"] == pytest.approx(1.0, rel=1e-9)
                out.append((brute(mtype, p, objective), x))
    return out


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
    ok, step = feasible(mtype, tr, bound)
    coarse = measured(mtype, tr, bound, ok[:: max(1, len(ok) // COARSE)], objective)
    assert len(coarse) > min(COARSE, len(ok)) / 3
    step *= max(1, len(ok) // COARSE)
    best = min(coarse)
    lo, hi = DRAWN[mtype][1]
    for _ in range(2):  # twice, densely about the best so far
        near = np.linspace(max(lo, best[1] - step), min(hi, best[1] + step), FINE)
        best = min([best, *measured(mtype, tr, bound, near, objective)])
        step /= FINE / 2
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
