"""Numerical stability: property-based tests aimed at the edges of every type.

Bounded in `make test` (the default hypothesis profile), ≥ 10 000 cases per type and property
in `make stress`. Designs come from tests/support/strategies.py (limits, change points, dead points,
scales 1e-6 … 1e6, link ratios 1e-3 … 1e3). The properties:

- the analysis never returns NaN/inf and raises nothing but synth's domain errors;
- where it answers, it agrees with the independent brute-force simulation;
- it is scale invariant;
- the offset slider-crank's mirror (−offset) gives the same time ratio and stroke;
- synthesis → analysis round trips: a design's own targets give verified candidates only, the
  same twice, and a typed reason whenever it gives none.
"""

import math

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

import synth
from synth.mechanisms import all_types

from ..support import bruteforce, exact
from ..support.designs import TYPES
from ..support.strategies import design, log_uniform


def finite(*xs):
    return all(math.isfinite(x) for x in xs)


def analyzed(mtype, p):
    """The analysis, or None for a design synth calls invalid (a domain error, nothing else)."""
    try:
        return synth.analyze(mtype, p)
    except synth.SynthError:
        return None


def tolerance(mtype, a) -> float:
    """The relative accuracy a double-precision answer can have for this design.

    1e-9, unless the problem itself forbids it: where it is ill-conditioned (a time ratio of
    10⁴ moves by 5e7 × a relative change of the crank), 100 ulp of backward error, 1e-14 × the
    condition number; for a stroke far from O2, a few ulp of the positions, 1e-15 |s| / stroke;
    and on a validity limit (margin < 1e-9 of the design's size) the design sits on a
    square-root kink of its own definition: synth accepts a design past a limit by rounding
    (1e-12 of its lengths), and the kink turns that into an ambiguity of sqrt(1e-12) = 1e-6
    (where the linkage cannot assemble for a few 1e-7 rad around the dead centre).
    Only asked for when 1e-9 was missed (it costs simulations).
    """
    # the stroke is the difference of two positions in the contract's frame (from O2)
    frame = 1e-15 * max(abs(e.position) for e in a.extremes.values()) / a.stroke
    tol = max(1e-9, 1e-14 * condition(mtype, a.params), flat_dead_centres(mtype, a), frame)
    return max(tol, 1e-6) if on_limit(a) else tol


def flat_dead_centres(mtype, a) -> float:
    """The time-ratio accuracy the dead centres allow: a dead centre where d²s/dθ² is tiny (a
    follower that nearly stalls there) is located only to ~100 ulp × max|ds/dθ| / |d²s/dθ²|,
    whatever the code; each radian of it moves the time ratio by 1/working + 1/return angle.
    The derivatives are the brute force's (complex step), at the analysis's dead centres."""

    def ds(t):
        return bruteforce.d_dtheta(lambda x: bruteforce.position(mtype, a.params, x), t)

    h = 1e-6
    worst = 0.0
    try:
        scale = np.max(np.abs(ds(np.linspace(0, 2 * np.pi, 721))))
        for k in ("min", "max"):
            t = math.radians(a.extremes[k].crank_angle_deg)
            curvature = abs(ds(np.array([t + h]))[0] - ds(np.array([t - h]))[0]) / (2 * h)
            worst = max(worst, 1e-14 * scale / max(curvature, 1e-300))
    except ValueError:  # the simulation refuses a design on its limit (rounding)
        return 0.0
    slow, quick = (math.radians(s.crank_angle_deg) for s in (a.working_stroke, a.return_stroke))
    return min(worst * (1 / slow + 1 / quick), 1.0)


STEP = 1e-10


def condition(mtype, p) -> float:
    """The relative condition number of (time ratio, stroke) in the parameters, by central
    differences of the brute-force simulation (independent of synth), or of the 50-digit
    closed form where the simulation cannot run the design. The relative step,
    1e-10, is small enough to see a flat dead centre's non-linear sensitivity (its location
    moves like the cube root of a perturbation) and large against the simulation's noise."""
    worst = 0.0
    try:
        base = bruteforce.simulate(mtype, p)
        for k, v in p.items():
            if v == 0:
                continue
            up, down = (bruteforce.simulate(mtype, {**p, k: v * (1 + s)}) for s in (STEP, -STEP))
            for q in ("time_ratio", "stroke"):
                worst = max(worst, abs(up[q] - down[q]) / (2 * STEP * base[q]))
    except ValueError:  # the simulation cannot run it, or a step leaves the valid region
        if exact.time_ratio_and_stroke(mtype, p) is None:
            return math.inf  # unrefereed: the caller's exact comparison cannot happen either
        return exact.condition(mtype, p)
    return worst


def on_limit(a) -> bool:
    """Within 1e-9 of a validity limit (relative): numerically on it, at its square-root kink."""
    margin = a.conditioning.validity_margin
    return margin is not None and margin < 1e-9


def at_change_point(a) -> bool:
    """On a Grashof limit the linkage can fold flat and take either circuit out of it (a
    bifurcation): the left-hand-circuit convention then decides, and any two codes may follow
    different branches. Such designs are checked for sanity, not compared."""
    return on_limit(a) and (a.conditioning.limiting_condition or "").startswith("grashof")


@pytest.mark.parametrize("mtype", TYPES)
@given(data=st.data())
def test_analysis_agrees_with_brute_force_at_the_edges(mtype, data):
    p = data.draw(design(mtype))
    a = analyzed(mtype, p)
    if a is None:
        # refused designs sit on a limit up to rounding: the brute force must find them
        # unrunnable or degenerate too (a dead point: a rod within 1e-8 of its reach makes the
        # slider stand still over part of the turn, at a transmission angle of ~0.01°)
        try:
            b = bruteforce.simulate(mtype, p)
        except ValueError:
            return
        assert b["min_transmission_deg"] < 0.01 or b["stroke"] == 0, (p, b)
        return
    values = [
        a.time_ratio,
        a.stroke,
        a.transmission.min_deg,
        a.transmission.max_deg,
        a.extremes["min"].position,
        a.extremes["max"].position,
    ]
    assert finite(*values)
    assert a.time_ratio >= 1 and a.stroke > 0
    if at_change_point(a):
        return
    tol = 1e-9
    try:
        b = bruteforce.simulate(mtype, p)
    except ValueError:
        # the plain simulation cannot follow every design near a dead point or a limit (its
        # refinement needs a smooth extremum, and a rod 1e-8 longer than its lever has a
        # square-root kink); the 50-digit closed form still referees
        assert {"near_dead_point", "near_validity_limit"} & set(a.conditioning.flags), p
        b = None
    if b is not None:
        # flat linkage on a limit: cos μ → 1, where acos turns 1e-16 into 1e-8 rad
        mu_tol = 1e-4 if on_limit(a) else 1e-6
        assert same_angle(a.transmission.min_deg, b["min_transmission_deg"], mu_tol), p
        if close(a, b, tol):
            return
        tol = tolerance(mtype, a)
        if close(a, b, tol):
            return
    # the simulation itself loses digits at a square-root kink: the 50-digit closed form
    # referees where it applies
    tol = tolerance(mtype, a) if b is None else tol
    ref = exact.time_ratio_and_stroke(mtype, a.params)
    if ref is None:
        assert b is None, (p, a.time_ratio, a.stroke, tol, b)
        return  # on a limit, nothing to referee with: finite and sane is what can be asked
    ref = {"time_ratio": ref[0], "stroke": ref[1]}
    assert close(a, ref, tol), (p, a.time_ratio, a.stroke, ref, tol, b)


def same_angle(a_deg: float, b_deg: float, tol_deg: float) -> bool:
    """Within tol_deg, or as near as acos lets a transmission angle be: near μ = 0 a cosine
    is 1 − μ²/2, so a rounding of 1e-15 in it moves μ by up to sqrt(2e-15) rad (2.6e-6°).
    Symmetric: the slope of cos at the larger angle (one side may be exactly 0° on a limit)."""
    a, b = math.radians(a_deg), math.radians(b_deg)
    slope = max(math.sin(a), math.sin(b))
    return abs(math.cos(a) - math.cos(b)) <= 1e-15 + slope * math.radians(tol_deg)


def close(a, ref, tol: float) -> bool:
    """Stroke and time ratio to ``tol``, relative; the time ratio only where it is defined
    (two reversals: with more, two equal extremes make it ambiguous)."""
    ok = abs(a.stroke - ref["stroke"]) <= tol * ref["stroke"]
    if a.reversals == 2:
        ok &= abs(a.time_ratio - ref["time_ratio"]) <= tol * ref["time_ratio"]
    return ok


@pytest.mark.parametrize("mtype", all_types())
@given(data=st.data())
def test_scale_invariance(mtype, data):
    p = data.draw(design(mtype))
    k = data.draw(log_uniform(1e-6, 1e6))
    a, b = analyzed(mtype, p), analyzed(mtype, {n: v * k for n, v in p.items()})
    assume(a is not None and b is not None and not at_change_point(a))
    # scaling rounds every input by up to an ulp: the answer moves within its own accuracy
    # near a dead point μ = acos(1 − ε) turns a rounding of ε into 1e-16/μ rad
    mu = math.radians(a.transmission.min_deg)
    deg = 1e-4 if on_limit(a) else 1e-8 + math.degrees(1e-14 / max(mu, 1e-12))
    assert b.transmission.min_deg == pytest.approx(a.transmission.min_deg, abs=deg)
    same = {"time_ratio": a.time_ratio, "stroke": a.stroke * k}
    if not close(b, same, 1e-10):
        assert close(b, same, tolerance(mtype, a)), (p, k, a.time_ratio, b.time_ratio)


@given(data=st.data())
def test_offset_mirror_invariance(data):
    p = data.draw(design("offset_slider_crank"))
    a = analyzed("offset_slider_crank", p)
    b = analyzed("offset_slider_crank", {**p, "offset": -p["offset"]})
    assert (a is None) == (b is None)
    if a is not None:
        mirrored = {"time_ratio": a.time_ratio, "stroke": a.stroke}
        if not close(b, mirrored, 1e-12):  # the same design: as exact as it can be
            assert close(b, mirrored, tolerance("offset_slider_crank", a)), p
        assert b.transmission.min_deg == pytest.approx(a.transmission.min_deg, abs=1e-9)


@pytest.mark.parametrize("mtype", all_types())
@given(p=st.lists(log_uniform(1e-6, 1e6), min_size=7, max_size=7), zero=st.booleans())
def test_any_numbers_give_an_answer_or_a_domain_error(mtype, p, zero):
    names = synth.mechanisms.get(mtype).names
    params = dict(zip(names, p, strict=False))
    if zero and "connecting_rod" in params and mtype == "crank_rocker_slider":
        params["connecting_rod"] = 0.0
    a = analyzed(mtype, params)
    if a is not None:
        assert finite(a.time_ratio, a.stroke, a.transmission.min_deg, a.transmission.max_deg)
        c = synth.analyze(mtype, params, samples=16).curves
        for arr in (c.position, c.velocity, c.acceleration, c.transmission_deg):
            assert np.all(np.isfinite(arr))


@pytest.mark.parametrize("mtype", all_types())
@settings(max_examples=min(settings().max_examples, 200))
@given(data=st.data())
def test_synthesis_round_trip_at_the_edges(mtype, data):
    p = data.draw(design(mtype))
    a = analyzed(mtype, p)
    assume(a is not None and a.reversals == 2)
    names = sorted(p)
    fixed = {
        k: a.params[k] for k in data.draw(st.lists(st.sampled_from(names), max_size=2, unique=True))
    }
    bound = max(0.0, a.transmission.min_deg - 1.0)
    request = dict(
        time_ratio=a.time_ratio,
        stroke=a.stroke,
        min_transmission_angle_deg=bound,
        mechanisms=[{"type": mtype, "fixed": fixed}],
        time_budget_ms=20_000,
    )
    r = synth.synthesize(**request)
    for c in r.candidates:
        assert c.verified and max(c.residuals.values()) <= 1e-9
        assert finite(*c.params.values(), c.min_transmission_angle_deg)
        assert c.min_transmission_angle_deg >= bound - 1e-9 * max(bound, 1.0)
        assert all(c.params[k] == v for k, v in fixed.items())
    if not r.candidates:
        (why,) = r.infeasible
        assert why.code and why.reason and why.type == mtype
    again = synth.synthesize(**request)
    assert again.candidates == r.candidates and again.infeasible == r.infeasible
