"""The crank shaper's certified optima (synth.synthesis.certify over its space: the ram link's
cos μ at the swing's ends and log of its length) checked from outside.

Designs are drawn by the type's own geometry, not by that space: the crank over the pivot
distance is sin(β/2) and the lever half the stroke over it (the lever swings ±β/2, its tip
sweeps the stroke), the ram link l and its path's height h on a grid of their own (l over the
link's default bounds, h where the path meets the tip's swing), the slot drive beside them.
Each is checked by the brute force (tests/support/bruteforce.py: time ratio, stroke, the
transmission bound) and measured by it (tests/support/motion_bruteforce.py), or by the
analysis under a load for the peak torque; a coarse grid, then twice densely about its best.
None may measure below the certificate's claim, and the draw must come close to the
certified value (else it is too sparse to judge).
"""

from __future__ import annotations

import itertools
import math
import os

import numpy as np
import pytest

import synth
from synth.errors import SynthError
from synth.load import Load
from synth.synthesis import certify

from ..support import bruteforce
from ..support.constructions import ACROSS_DEG
from ..support.motion_bruteforce import brute_motion

TYPE = "crank_shaper"
PEAK, UNIFORM, TORQUE = "min_peak_acceleration", "uniform_cutting_speed", "min_peak_torque"
STRESS = os.environ.get("HYPOTHESIS_PROFILE") == "stress"
TARGETS = (
    [(tr, b) for tr in (1.3, 1.6, 2.0, 2.5) for b in (0.0, 10.0, 20.0, 30.0, 40.0)]
    if STRESS
    else [(1.6, 20.0), (2.0, 0.0), (2.5, 0.0)]  # at 2.0 the ram link's optimum is at its longest
)
LINK = (0.1, 2.0)  # the ram link's default bounds, in strokes
BEATEN = 1e-8  # relative: the brute force's own error on the measure
NEAR = 1e-3  # relative: the draw's best must come this close to the certified value
LOAD = Load("m", 40.0, cutting_force=2000.0, slider_mass=20.0)
COARSE, FINE = 24, 9  # points a side: the first grid, each refinement's


def design(tr, link=0.0, height=None):
    """The design at stroke 1 and time ratio ``tr`` with this ram link (0: the slot drive)."""
    s = math.sin(math.pi * (tr - 1) / (tr + 1) / 2)
    p = {"crank": 0.1, "pivot_distance": 0.1 / s, "lever": 0.5 / s, "ram_link": link}
    if link:
        p["ram_height"] = height
    return p


def measure(objective):
    """The objective's measure of a design: the brute force's, or the analysis's peak torque
    under ``LOAD``; None where it does not run."""

    def of(p):
        try:
            if objective == TORQUE:
                return synth.analyze(TYPE, p, load=LOAD).loads.torque.max
            _, middle, working, ret = brute_motion(TYPE, p)
        except (SynthError, ValueError, ZeroDivisionError):
            return None
        return max(working, ret) if objective == PEAK else middle

    return of


def admitted(tr, bound, p):
    """Whether the brute force finds the design at the targets and the bound (and the least
    angle the searches keep)."""
    try:
        b = bruteforce.simulate(TYPE, p, n=4000)
    except (ValueError, ZeroDivisionError):
        return False
    # a link that leans past the lever's turn moves the slider back within a swing: its dead
    # centres are not the swing's ends, nor its time ratio and stroke the targets'
    on_target = abs(b["time_ratio"] - tr) <= 1e-9 * tr and abs(b["stroke"] - 1) <= 1e-9
    return on_target and b["min_transmission_deg"] >= max(bound, ACROSS_DEG)


def least(tr, bound, of, links, heights):
    """The least measure of the drawn designs on the grid ``links`` × ``heights`` (each a
    function of the other's refinement: (lo, hi) spans), coarse and then twice densely about
    the best: (value, (l, h)) and how many designs the coarse grid admitted."""
    lever = design(tr)["lever"]
    low = lever * math.cos(math.pi * (tr - 1) / (tr + 1) / 2)  # the tip's lowest
    span_l, span_h = links, heights
    best, admitted_first = (math.inf, None), None
    for n in (COARSE, FINE, FINE):
        found = []
        for link, height in itertools.product(points(span_l, n), points(span_h, n)):
            p = design(tr, float(link), float(height))
            if link > 0 and admitted(tr, bound, p):
                value = of(p)
                if value is not None:
                    found.append((value, (float(link), float(height))))
        admitted_first = len(found) if admitted_first is None else admitted_first
        best = min([best, *found], key=lambda x: x[0])
        if best[1] is None:
            break
        step = ((span_l[1] - span_l[0]) / (n - 1), (span_h[1] - span_h[0]) / (n - 1))
        (l0, h0) = best[1]
        span_l = (max(links[0], l0 - step[0]), min(links[1], l0 + step[0]))
        span_h = (max(low - links[1], h0 - step[1]), h0 + step[1])
    return best, admitted_first


def points(span, n):
    """n points over ``span``, or its one point."""
    return [span[0]] if span[0] == span[1] else np.linspace(*span, n)


def request(tr, bound, objective, fixed=None, slot=True):
    """The request at stroke 1: the type's default bounds (the slot drive allowed), or the
    link's bounds given (which leave it out)."""
    part: dict = {"type": TYPE}
    if fixed:
        part["fixed"] = fixed
    if not slot:
        part["bounds"] = {"ram_link": list(LINK)}
    load = LOAD if objective == TORQUE else None
    return synth.synthesize(
        tr, 1.0, bound, [part], objective=objective, load=load, time_budget_ms=60_000
    )


def judged(r, objective, best):
    """The answer certified, its value the brute force's, and the draw's ``best`` neither
    below its claim nor far above its value."""
    assert r.complete and r.candidates
    c = r.candidates[0]
    assert c.certified and c.gap <= certify.TOL, c
    if objective != TORQUE:
        assert c.objective_value == pytest.approx(measure(objective)(c.params), rel=1e-9)
    claim = c.objective_value * (1 - c.gap)
    assert best[0] >= claim * (1 - BEATEN), f"{best} beats the certificate {claim}"
    assert best[0] <= c.objective_value * (1 + NEAR), "the draw is too sparse to judge"


@pytest.mark.parametrize("slot", [True, False])
@pytest.mark.parametrize(("tr", "bound"), TARGETS)
def test_no_design_accelerates_less_than_the_certificate(tr, bound, slot):
    """Both free numbers: the least peak acceleration over the ram-link designs, and the slot
    drive where the request allows it (its ram link's bounds not given)."""
    r = request(tr, bound, PEAK, slot=slot)
    if not r.candidates:
        assert STRESS and r.infeasible[0].code == "TRANSMISSION_UNREACHABLE"
        return
    lever = design(tr)["lever"]
    low = lever * math.cos(math.pi * (tr - 1) / (tr + 1) / 2)
    of = measure(PEAK)
    best, drawn = least(tr, bound, of, LINK, (low - LINK[1], lever + LINK[1]))
    assert drawn > COARSE  # a grid that admits designs
    if slot:
        best = min(best, (of(design(tr)), None), key=lambda x: x[0])
    judged(r, PEAK, best)


@pytest.mark.parametrize("objective", [PEAK, UNIFORM, TORQUE])
@pytest.mark.parametrize("fixed", [{"ram_link": 0.15}, {"ram_height": 1.45}])
def test_with_a_part_of_the_ram_link_fixed_every_measure_is_certified(fixed, objective):
    """One free number left (the link's length or its path's height): every searched
    measure is certified, and no design drawn with the same part (or the slot drive, which a
    fixed height leaves in) beats it."""
    tr, bound = 1.6, 20.0
    r = request(tr, bound, objective, fixed)
    lever = design(tr)["lever"]
    low = lever * math.cos(math.pi * (tr - 1) / (tr + 1) / 2)
    if "ram_link" in fixed:
        links, heights = (fixed["ram_link"],) * 2, (low - 0.15, lever + 0.15)
    else:
        links, heights = LINK, (fixed["ram_height"],) * 2
    of = measure(objective)
    best, drawn = least(tr, bound, of, links, heights)
    assert drawn > COARSE / 3
    if "ram_link" not in fixed:  # the slot drive has no height to fix: it is one too
        best = min(best, (of({**design(tr), **fixed}), None), key=lambda x: x[0])
    judged(r, objective, best)
    assert all(r.candidates[0].params[k] == v for k, v in fixed.items())
