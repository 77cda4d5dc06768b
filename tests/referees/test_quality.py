"""Motion quality and sensitivities (synth.analysis.quality) against independent computations.

- Speed fluctuation and peak accelerations against a brute force on tests/support/bruteforce.py's
  geometry (which shares no code with synth): the slider's velocity by complex step, its
  acceleration by a Cauchy contour integral of the position, both sampled densely over each
  stroke and the largest refined by a bounded scalar maximiser. 1e-9 relative.
- The scotch yoke's exact values: fluctuation π/2 over the whole stroke, peak acceleration
  ω²·r, i.e. 0.5 in units of ω²·stroke.
- Sensitivities against central differences of the analysis, Richardson-extrapolated, the
  step shrunk until two agree (the step-size control): 1e-6 relative to each quantity's scale.
- The envelope against every pin's path sampled by synth.joints at 100 000 crank angles.
"""

from __future__ import annotations

import math
import os

import numpy as np
import pytest

import synth
from synth.errors import InvalidParameters
from synth.mechanisms import all_types
from synth.results import Tolerance

from ..support.designs import TYPES, random_designs
from ..support.motion_bruteforce import acceleration, brute_motion

N = 200
STRESS = os.environ.get("HYPOTHESIS_PROFILE") == "stress"  # make stress: more envelopes


@pytest.mark.parametrize("mtype", TYPES)
def test_motion_matches_a_brute_force(mtype):
    for p in random_designs(mtype, N, seed=13):
        m = synth.analyze(mtype, p, include=["motion"]).motion
        whole, middle, working, ret = brute_motion(mtype, p)
        ours = m.working_speed_fluctuation
        assert ours.whole == pytest.approx(whole, rel=1e-9), p
        assert ours.middle == pytest.approx(middle, rel=1e-9), p
        assert m.peak_acceleration.working_stroke == pytest.approx(working, rel=1e-9), p
        assert m.peak_acceleration.return_stroke == pytest.approx(ret, rel=1e-9), p
        assert ours.middle >= 1 and ours.whole >= 1  # a peak is never below the mean


@pytest.mark.parametrize("mtype", TYPES)
def test_the_peak_accelerations_are_where_they_say(mtype):
    """The brute force's acceleration at each reported crank angle is that stroke's peak."""
    for p in random_designs(mtype, 40, seed=17):
        a = synth.analyze(mtype, p, include=["motion"])
        peak = a.motion.peak_acceleration
        at = np.radians([peak.working_stroke_at_deg, peak.return_stroke_at_deg])
        there = np.abs(acceleration(mtype, p, at)) / a.stroke
        assert there[0] == pytest.approx(peak.working_stroke, rel=1e-9), p
        assert there[1] == pytest.approx(peak.return_stroke, rel=1e-9), p


def test_the_scotch_yoke_moves_harmonically():
    for r in (1e-3, 1.0, 37.5, 1e4):
        m = synth.analyze("scotch_yoke", {"crank": r}, include=["motion"]).motion
        assert m.working_speed_fluctuation.whole == pytest.approx(math.pi / 2, rel=1e-12)
        # over the middle 80%: from cos θ = 0.8 to −0.8, speed sin θ peaks at 1 at 90°
        arc = math.pi - 2 * math.acos(0.8)
        assert m.working_speed_fluctuation.middle == pytest.approx(arc / 1.6, rel=1e-12)
        assert m.peak_acceleration.working_stroke == pytest.approx(0.5, rel=1e-12)
        assert m.peak_acceleration.return_stroke == pytest.approx(0.5, rel=1e-12)


QUANTITIES = ("time_ratio", "stroke", "min_transmission_angle_deg")


def values(mtype, p):
    a = synth.analyze(mtype, p)
    return np.array([a.time_ratio, a.stroke, a.transmission.min_deg])


def central(mtype, p, name, h):
    up, down = dict(p, **{name: p[name] + h}), dict(p, **{name: p[name] - h})
    return (values(mtype, up) - values(mtype, down)) / (2 * h)


def derivative(mtype, p, name, scale):
    """d(values)/d(name) by Richardson-extrapolated central differences, the step shrunk by
    tens until two steps agree to 1e-8 (None if they never do: a kink or a limit in reach)."""
    prev, floor = None, np.abs(values(mtype, p)) / scale  # each quantity's own size
    for k in range(3, 10):
        h = 10.0**-k * scale
        try:
            r = (4 * central(mtype, p, name, h / 2) - central(mtype, p, name, h)) / 3
        except synth.SynthError:  # the step crosses a validity limit: a smaller one
            continue
        if prev is not None and np.all(np.abs(r - prev) <= 1e-8 * (np.abs(r) + floor)):
            return r
        prev = r
    return None


@pytest.mark.parametrize("mtype", all_types())
def test_sensitivities_match_central_differences(mtype):
    checked = 0
    for p in random_designs(mtype, N, seed=17):
        a = synth.analyze(mtype, p, include=["sensitivities"])
        sens = a.sensitivities
        scale = max(abs(v) for v in a.params.values())
        fd = {name: derivative(mtype, a.params, name, scale) for name in sens.stroke}
        if any(d is None for d in fd.values()):
            continue
        checked += 1
        for q, quantity in enumerate(QUANTITIES):
            ours = getattr(sens, quantity)
            if ours is None:
                continue
            value = values(mtype, a.params)[q]
            size = max(max(abs(v) for v in ours.values()), abs(value) / scale)
            for name, v in ours.items():
                assert v == pytest.approx(fd[name][q], rel=1e-6, abs=1e-6 * size), (
                    quantity,
                    name,
                    p,
                )
    assert checked >= 0.9 * N


def test_a_tolerance_gives_the_worst_first_order_deviation():
    p = {"crank": 75, "pivot_distance": 50, "lever": 150, "connecting_rod": 200}
    s = synth.analyze("whitworth", p, tolerance=Tolerance(absolute=0.1)).sensitivities
    assert s.deviation["stroke"] == pytest.approx(0.1 * sum(map(abs, s.stroke.values())))
    r = synth.analyze("whitworth", p, tolerance=Tolerance(relative=1e-3)).sensitivities
    want = sum(abs(v) * 1e-3 * p[k] for k, v in r.time_ratio.items())
    assert r.deviation["time_ratio"] == pytest.approx(want, rel=1e-12)
    # here the lever's end swings through a half turn: the stroke is twice the lever
    assert s.stroke["lever"] == pytest.approx(2.0, rel=1e-12)


@pytest.mark.parametrize(
    "bad", [dict(absolute=-1.0), dict(relative=math.nan), dict(), dict(absolute=1, relative=1)]
)
def test_a_bad_tolerance_is_refused_with_its_field(bad):
    with pytest.raises(InvalidParameters) as e:
        Tolerance(**bad)
    assert e.value.loc[0] == "tolerance"


def test_unknown_inclusions_are_refused():
    with pytest.raises(InvalidParameters, match="include"):
        synth.analyze("scotch_yoke", {"crank": 1.0}, include=["curvature"])


@pytest.mark.parametrize("mtype", all_types())
def test_the_envelope_holds_every_pin_path_sampled_densely(mtype):
    angles = np.arange(100_000) * (360 / 100_000)
    for p in random_designs(mtype, 40 if STRESS else 8, seed=19):
        a = synth.analyze(mtype, p, include=["envelope"])
        e = a.envelope
        pins = np.concatenate(list(synth.joints(mtype, a.params, angles).values()))
        scale = max(abs(v) for v in a.params.values())
        sampled = [(pins[:, k].min(), pins[:, k].max()) for k in (0, 1)]
        for (lo, hi), (slo, shi) in zip((e.x, e.y), sampled, strict=True):
            assert lo <= slo + 1e-12 * scale and shi <= hi + 1e-12 * scale, p  # holds them all
            assert slo - lo <= 1e-7 * scale and hi - shi <= 1e-7 * scale, p  # and no more
        assert e.width == pytest.approx(e.x[1] - e.x[0]) and e.height == pytest.approx(
            e.y[1] - e.y[0]
        )
        links = [q.name for q in synth.mechanisms.get(mtype).parameters if q.link]
        assert e.link_length_sum == pytest.approx(sum(a.params[n] for n in links), rel=1e-15)


def test_candidates_carry_what_the_request_includes():
    asked = synth.synthesize(
        1.6, 300.0, 20.0, include=["motion", "envelope"], tolerance=Tolerance(relative=1e-3)
    )
    plain = synth.synthesize(1.6, 300.0, 20.0)
    assert [c.params for c in asked.candidates] == [c.params for c in plain.candidates]
    for c, bare in zip(asked.candidates, plain.candidates, strict=True):
        a = synth.analyze(
            c.type, c.params, include=["motion", "envelope"], tolerance=Tolerance(relative=1e-3)
        )
        assert (c.motion, c.envelope, c.sensitivities) == (a.motion, a.envelope, a.sensitivities)
        assert c.sensitivities.deviation is not None
        assert (bare.motion, bare.envelope, bare.sensitivities) == (None, None, None)
    with pytest.raises(InvalidParameters, match="include"):
        synth.synthesize(1.6, 300.0, 20.0, include=["colour"])
