"""Named regression tests for what the numerical-stability suite (test_stress.py) found.

The referee is the 50-digit closed form (tests/support/exact.py) or the source's own equations,
never synth's code.
"""

import math
import warnings

import numpy as np
import pytest
from fastapi.testclient import TestClient

import synth
from api.main import app
from synth.analysis import roots
from synth.analysis.model import model
from synth.analysis.roots import rtsafe
from synth.synthesis.formulation import relevant
from synth.synthesis.search import Spec, Targets, build_problem, variants
from synth.targets import MAX_TRANSMISSION

from ..support import exact
from ..support.assertions import assert_meets


def assert_exact(mtype, p, rel=1e-12):
    a = synth.analyze(mtype, p)
    tr, stroke = exact.time_ratio_and_stroke(mtype, a.params)
    assert a.time_ratio == pytest.approx(tr, rel=rel)
    assert a.stroke == pytest.approx(stroke, rel=rel)
    return a


def test_offset_slider_crank_on_its_limit_keeps_every_digit():
    """r3 = r2 + e: r3² − (e − B_y)² lost every digit where the coupler stands upright."""
    a = assert_exact("offset_slider_crank", {"crank": 1.0, "coupler": 2.0, "offset": 1.0})
    assert a.stroke == pytest.approx(math.sqrt(8), rel=1e-14)


def test_offset_slider_crank_on_its_limit_with_negative_offset():
    """The kink of a design on its limit: Newton's tiny steps there once stopped 1e-8 short."""
    assert_exact("offset_slider_crank", {"crank": 10.0, "coupler": 20.0, "offset": -10.0})


def test_offset_limit_in_binary_is_not_the_decimal_limit():
    """1.01 − 1 − 0.01 ≠ 0 in binary: the design is 9e-18 inside, and its exact numbers differ
    from the decimal limit's by 1e-7 (the 50-digit form agrees with synth, not a plain sim)."""
    assert_exact("offset_slider_crank", {"crank": 1.0, "coupler": 1.01, "offset": 0.01})


def test_centred_slider_crank_with_a_coupler_barely_longer_than_the_crank():
    """B_x + root cancelled to 1e-8 behind the pivot: the time ratio read 1 + 3e-9."""
    a = synth.analyze("offset_slider_crank", {"crank": 1.0, "coupler": 1.00000001, "offset": 0})
    assert a.time_ratio == pytest.approx(1.0, abs=1e-12)


def test_a_slider_that_stands_still_is_refused():
    """coupler = crank, no offset: the slider sits at O2 for half a turn (any TR was arbitrary)."""
    with pytest.raises(synth.InvalidDesign, match="stands still") as e:
        synth.analyze("offset_slider_crank", {"crank": 1.0, "coupler": 1.0, "offset": 0.0})
    assert e.value.condition == "dwell"


def test_a_change_point_whose_circuit_switches_is_refused():
    """ground + follower = crank + coupler: at the flat position the left-hand circuit jumps,
    so both extremes fell at one crank angle (a division by zero, a 500 through the API)."""
    p = {
        "ground": 1.0,
        "crank": 1.0001,
        "coupler": 1.9999,
        "follower": 2.0,
        "follower_arm": 1.0,
        "connecting_rod": 2.0,
    }
    with pytest.raises(synth.InvalidDesign, match="change point") as e:
        synth.analyze("drag_link_slider", p)
    assert e.value.condition == "change_point"


def test_a_design_exactly_on_a_limit_is_valid_despite_rounding():
    """1.001 − 1 − 0.001 = −2e-16: the block-on-lever limit was refused by rounding."""
    a = assert_exact("crank_shaper", {"crank": 0.001, "pivot_distance": 1.0, "lever": 1.001})
    assert a.conditioning.limiting_condition == "block_on_lever"


def test_hidden_pair_of_dead_centres_is_found():
    """TR 69 with a ram link: both dead centres sat between two grid points."""
    p = {
        "crank": 0.999,
        "pivot_distance": 1.0,
        "lever": 1.999,
        "ram_link": 1.9096243545533795,
        "ram_height": 0.08937564544662047,
    }
    a = synth.analyze("crank_shaper", p)
    top = 90 + math.degrees(math.asin(0.999))  # the lever's extreme: sin ψmax = crank/pivot
    assert a.extremes["max"].crank_angle_deg == pytest.approx(top, abs=1e-10)
    assert a.extremes["min"].crank_angle_deg == pytest.approx(360 - top, abs=1e-10)


@pytest.mark.parametrize("rod", [1.00001, 1.0000001])
def test_whitworth_rod_barely_longer_than_the_lever(rod):
    """sqrt(l² − L² cos² ψ) and −L sin ψ + root both cancelled near the rod's dead point."""
    assert_exact(
        "whitworth", {"crank": 1.0, "pivot_distance": 0.999, "lever": 1.0, "connecting_rod": rod}
    )


def test_no_math_domain_error_escapes_the_api():
    """A cos μ of 1 + 1e-16 reached math.acos: a 500."""
    body = {
        "mechanism": {
            "type": "crank_rocker_slider",
            "params": {
                "ground": 0.1,
                "crank": 0.225,
                "coupler": 0.2504,
                "rocker": 1e-9,
                "rocker_arm": 1e-9,
                "connecting_rod": 999999999999.0,
                "slider_height": 1e-9,
            },
        },
        "vary": "coupler",
        "start": 0.1,
        "stop": 0.5,
        "points": 101,
    }
    with TestClient(app) as client:
        assert client.post("/v1/sweep", json=body).status_code in (200, 422)


def test_drag_link_coupler_at_the_double_root():
    """At the time ratio's minimum over the coupler, eq. (11)'s two roots merge (A² + B² = C²);
    the double-root-safe eq. (12) still gives the coupler, whose dead centre the analysis
    locates to 1e-12 rad of eq. (3a)."""
    from mpmath import acos, mpf

    fixed = {"ground": 0.1, "crank": 0.225, "follower": 0.275, "connecting_rod": 0.3}
    s = synth.sweep(
        "drag_link_slider",
        {**fixed, "coupler": 0.2, "follower_arm": 0.15},
        "coupler",
        0.15,
        0.40,
        51,
    )
    tr_min = s.time_ratio_range["min"].time_ratio
    r = synth.synthesize(tr_min, 0.3, mechanisms=[{"type": "drag_link_slider", "fixed": fixed}])
    assert r.candidates, r.infeasible
    for c in r.candidates:
        assert c.params["coupler"] == pytest.approx(s.time_ratio_range["min"].value, abs=1e-4)
        r1, r2, r3, r4 = (mpf(c.params[k]) for k in ("ground", "crank", "coupler", "follower"))
        theta2a = acos((r2**2 + (r4 + r1) ** 2 - r3**2) / (2 * r2 * (r4 + r1)))  # eq. (3a)
        a = synth.analyze("drag_link_slider", c.params)
        assert math.radians(a.extremes["max"].crank_angle_deg) == pytest.approx(
            float(theta2a), abs=1e-12
        )


@pytest.mark.parametrize("k", [1e-3, 1.0, 7.3, 10.0])
@pytest.mark.parametrize(
    "links", [(1.0, 2.0, 2.0, 1.000001), (1.0, 1001.0, 1001.0, 1.001)], ids=["kite", "long-kite"]
)
def test_drag_link_kite_near_its_change_point(links, k):
    """ground ≈ follower, crank = coupler: at the dead centre the follower pin passes within
    1e-6 of the crank pivot, where the follower nearly stalls, so ds/dθ has a near-triple zero.
    Its root was 3e-6 rad off (time ratio 6e-5, and scale-dependent); the dead centres are now
    the simple zeros of B_y, measured from the crank pivot that B passes. The referee is seed
    002's eqs. (3a)/(3b) in 50 digits."""
    from mpmath import acos, mpf, pi

    p = dict(zip(("ground", "crank", "coupler", "follower"), (x * k for x in links), strict=True))
    p |= {"follower_arm": 0.5 * k, "connecting_rod": 2.0 * k}
    a = assert_exact("drag_link_slider", p, rel=1e-14)
    r1, r2, r3, r4 = (mpf(p[n]) for n in ("ground", "crank", "coupler", "follower"))
    t2a = acos((r2**2 + (r4 + r1) ** 2 - r3**2) / (2 * r2 * (r4 + r1)))  # eq. (3a): B right
    t2b = acos((r2**2 + (r4 - r1) ** 2 - r3**2) / (2 * r2 * (r4 - r1)))  # eq. (3b): B left of O2
    found = {k: math.radians(e.crank_angle_deg) for k, e in a.extremes.items()}
    assert found["max"] == pytest.approx(float(t2a), abs=1e-12)
    assert found["min"] == pytest.approx(float(pi + t2b), abs=1e-12)


def test_offset_slider_crank_past_its_limit_by_rounding():
    """coupler = crank + offset up to 1.5e-13 too short (accepted: on the limit to rounding):
    the linkage cannot assemble for ±3e-7 rad around its dead centre, so the time ratio is
    defined to ~sqrt(rounding) = 1e-6 there, not 1e-7 (the stress suite's rule)."""
    p = {"crank": 3.1622776601683795, "coupler": 1781.441687699091, "offset": 1778.2794100389228}
    a = assert_exact("offset_slider_crank", p, rel=1e-6)
    assert "near_validity_limit" in a.conditioning.flags


FOUR_BAR_CANCELLATIONS = {
    # the follower pin built as A + (D − A): a few ulp of |A| = 958 of a 2-long follower
    "crank-500x-follower": {
        "ground": 1.0,
        "crank": 958.3021617097721,
        "coupler": 958.4740367097721,
        "follower": 2.0,
    },
    # Heron factors summed left to right, (r2 − r1 − r3 + r4) rounded at the crank's size
    "kite-crank-1000x-ground": {
        "ground": 31.622776601683793,
        "crank": 31654.399378285478,
        "coupler": 31654.399378285478,
        "follower": 31.93900436770063,
    },
    # back = (d² − r3² + r4²)/2d² with −r3² + r4² summed as −4.0003 + 4 (crank ≈ ground)
    "crank-near-ground": {
        "ground": 1.0,
        "crank": 1.000316227766017,
        "coupler": 2.0000790569415043,
        "follower": 2.0,
    },
}


@pytest.mark.parametrize("links", FOUR_BAR_CANCELLATIONS.values(), ids=FOUR_BAR_CANCELLATIONS)
def test_four_bar_follower_keeps_its_digits(links):
    """A rod 1e-8 longer than its arm puts the piston near a dead point (μ ≈ 0.008°), where
    acos magnifies any error of the follower pin: each design moved μ by ~3e-10 rad under
    scaling (found by make stress). The follower vector is now measured from O4, its sums
    grouped so that nothing cancels; the referee is acos(r5/r6) in 50 digits."""
    from mpmath import acos, degrees, mpf

    p = {**links, "follower_arm": 1.0, "connecting_rod": 1.00000001}
    mu = float(degrees(acos(mpf(p["follower_arm"]) / mpf(p["connecting_rod"]))))
    for k in (1.0, 10.0, 100.0, 1e-3):
        a = synth.analyze("drag_link_slider", {n: v * k for n, v in p.items()})
        assert a.transmission.min_deg == pytest.approx(mu, abs=2e-10)  # a few ulp of cos μ


def test_drag_link_with_crank_near_ground_keeps_its_digits():
    """crank ≈ ground, coupler = follower: Heron's factor r2 − r3 + r4 − r1, summed as
    (1.01 − 101) + (101 − 1), kept the 0.01 to an ulp of the coupler, and μ of a piston near
    its dead point moved by 1e-4 relative under scaling (found by make stress). Now each
    factor pairs the links whose differences are smallest; the referee is acos(r5/r6) in 50
    digits, where the follower stands upright."""
    from mpmath import acos, degrees, mpf

    p = {"ground": 1.0, "crank": 1.01, "coupler": 101.0, "follower": 101.0}
    p |= {"follower_arm": 100.0, "connecting_rod": 100.00000031622776}
    mu = float(degrees(acos(mpf(p["follower_arm"]) / mpf(p["connecting_rod"]))))
    for k in (1.0, 10.0, 100.0, 0.1):
        a = synth.analyze("drag_link_slider", {n: v * k for n, v in p.items()})
        rod = next(j for j in a.transmission.joints if j.joint == "connecting_rod-slider")
        assert rod.min_deg == pytest.approx(mu, abs=5e-10)  # a few ulp of cos μ


def test_a_motion_search_past_a_design_without_stroke_still_answers():
    """The API contract check sent time ratio 240 with the least peak acceleration: the search
    passed a design whose slider does not move, and its motion measures divided by the stroke
    0. Such a design is no design to the search: every answer is verified, none raises."""
    r = synth.synthesize(240.0, 0.046875, 0.0, None, objective="min_peak_acceleration")
    assert r.candidates or r.infeasible
    for c in r.candidates:
        assert c.time_ratio == pytest.approx(240.0, rel=1e-9)
        assert c.stroke == pytest.approx(0.046875, rel=1e-9)


def test_drag_link_with_its_crank_fixed_takes_the_better_end_of_its_segment():
    """min_size for a drag-link with its crank fixed returned 324.385345 through IPOPT: its
    designs with the ground at its lower bound form one segment between the transmission
    bound's two crossings, a local minimum at each end, and it took the worse. The other end
    (the issue's design, to its ten digits: the 50-digit forms give its time ratio and
    stroke) is 323.876125: the reduced solver finds it and certifies it."""
    design = {
        "ground": 10.0,
        "crank": 100.0,
        "coupler": 98.2414934787,
        "follower": 12.4257432278,
        "follower_arm": 50.0,
        "connecting_rod": 53.2088886576,
    }
    tr, stroke = exact.time_ratio_and_stroke("drag_link_slider", design)
    assert tr == pytest.approx(1.5, rel=1e-9) and stroke == pytest.approx(100.0, rel=1e-12)
    spec = {"type": "drag_link_slider", "fixed": {"crank": 100.0}}
    r = synth.synthesize(1.5, 100.0, 20.0, objective="min_size", mechanisms=[spec])
    best = min(r.candidates, key=lambda c: c.size)
    assert [c.method for c in r.candidates] == ["closed_form"] * len(r.candidates)
    assert best.size == pytest.approx(sum(design.values()), rel=1e-9)
    for k, v in design.items():  # the digits, a few 1e-9 off the exact optimum
        assert best.params[k] == pytest.approx(v, rel=1e-8), k


def test_a_crank_rocker_with_its_rod_and_path_fixed_warns_of_nothing():
    """Its best-transmitting design: where the limited four-bar's search looks for the
    coupler's and the rod's transmission crossing, both were out of reach at a row (inf −
    inf: NaN, rightly no crossing), and numpy warned of an invalid subtraction (the rod
    and path fixed at the referee's most uniform design at time ratio 1.3 and 0°)."""
    fixed = {"connecting_rod": 0.12281872723421797, "slider_height": 1.1654569550776321}
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        r = synth.synthesize(
            1.6,
            1.0,
            0.0,
            [{"type": "crank_rocker_slider", "fixed": fixed}],
            objective="max_transmission_angle",
        )
    assert [str(w.message) for w in seen if issubclass(w.category, RuntimeWarning)] == []
    (c,) = r.candidates
    assert_meets(c, 1.6, 1.0, 0.0)
    assert all(c.params[k] == v for k, v in fixed.items())


def test_a_crank_rocker_whose_rod_reaches_nowhere_has_no_design_exactly():
    """A connecting rod bounded to 1e-9 strokes cannot follow the arm's tip, which rises and
    falls along its arc while the slider keeps to its line: no design. The rod-limited
    search ran the coupler's whole search first, then weighed rod placements 10⁷ times out
    of reach, and answered one of them, not exact: the request went on to the diagnosis,
    12.7 s to refuse on a slow machine (the default budget ran out first; 60 ms warm now).
    The rod is now asked first: no design, exactly, and the refusal says why."""
    m = synth.mechanisms.get("crank_rocker_slider")
    spec = Spec(m.type, {}, {"connecting_rod": (1e-9, 1e-9)})
    targets = Targets(1.5, 1.0, 0.0, MAX_TRANSMISSION, math.inf)
    for parts in variants(m, spec):
        problem = build_problem(m, parts, relevant(m, parts), {}, spec, targets)
        answer = m.reduced(problem)
        assert answer.designs == [] and answer.exact
    r = synth.synthesize(
        1.5,
        1.0,
        0.0,
        [{"type": "crank_rocker_slider", "bounds": {"connecting_rod": [1e-9, 1e-9]}}],
        time_budget_ms=60_000,
    )
    assert r.complete and r.candidates == ()
    assert [i.code for i in r.infeasible] == ["NO_VALID_DESIGN"]


def test_a_crank_rockers_flat_roots_end_at_their_rounding(monkeypatch):
    """A design a crank-rocker's search met on its way (1.6, 0°, most uniform speed): one of
    its kinematic stationary points and three of its speed's and acceleration's peaks lie
    where their rows are flat, and their Newton steps bounced at 1e-14 to 1e-12 rad, the
    rows' rounding, never down to the 4 ulps the polish asked; each went on to Python's
    bracketed iteration from the start (10 to 100 evaluations). Now a short Newton step
    where the row is ~0 ends them: no root is left to that iteration, and each still has
    its row's sign change within 1e-12 rad."""
    p = {
        "ground": 33.52078557916508,
        "crank": 30.0,
        "coupler": 30.2170546103525,
        "rocker": 33.438099370206835,
        "rocker_arm": 167.0380485025099,
        "connecting_rod": 65.04999093999962,
        "slider_height": 102.05310755345026,
    }
    m = synth.mechanisms.get("crank_rocker_slider")
    full = m.complete(p)
    pv = np.array([full[n] for n in m.names])
    finished_later = []
    monkeypatch.setattr(roots, "rtsafe", lambda *a: finished_later.append(a) or rtsafe(*a))
    for kind, count in (("kinematics", 8), ("motion", 10)):  # dead centres; speed, accel peaks
        f = model(m, m.variant(full), kind)
        rows, theta, _ = roots.stationary_points(f, pv)
        assert len(theta) == count and finished_later == []
        for r, x in zip(rows, theta, strict=True):
            step = 1e-12 * max(1.0, abs(x))
            g1 = f(np.array([x - step, x + step]), pv)[1][r]
            assert g1[0] * g1[1] <= 0, (kind, r, x)
