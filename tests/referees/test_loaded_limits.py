"""Loaded designs at their limits never give a server error (issue 38).

A design whose forces have no finite value at some crank angle (a dead point: a transmission
angle of 0° on a validity limit; the guide's friction at or past the angle where it locks the
ram) is refused with the crank angle named; the flywheel's and the motor's divisors are
range-checked (``synth.load.RANGES``) so nothing underflows.

The examples that gave a 500, each asked over HTTP (the ASGI app in-process, its shipped
engine); then random loaded analyses and syntheses at validity limits and at the friction-lock
boundary, with random loads whose crank speed and speed fluctuation reach past their ranges:
no 5xx, every 422 names a body field or a crank angle, every 200's loads are finite numbers.
`make test` runs a sample (300 analyses, 30 syntheses); `make stress` (HYPOTHESIS_PROFILE=
stress) 5 000 analyses and 500 syntheses.
"""

import math
import os
import re
from collections import Counter

import numpy as np
import pytest
from fastapi.testclient import TestClient
from hypothesis import given, settings
from hypothesis import strategies as st

import synth
from api.main import app
from synth.analysis.forces import forces
from synth.errors import InvalidDesign, InvalidParameters
from synth.load import RANGES, Load
from synth.mechanisms import all_types, get, kinetics

from ..support.strategies import design, log_uniform

STRESS = os.environ.get("HYPOTHESIS_PROFILE") == "stress"
ANALYSES, SYNTHESES = (5_000, 500) if STRESS else (300, 30)
LOADED = [t for t in all_types() if get(t).frame is not None]  # the types with a force model
QUICK_RETURN = [t for t in LOADED if get(t).quick_return]
# min_size twice as often: its designs sit on the bound
OBJECTIVES = ["min_size", "min_size", "pareto", "max_transmission_angle", "min_peak_torque"]
ANGLE = re.compile(r"crank angle (-?\d[\d.]*(?:e[-+]?\d+)?)°")
SCOTCH = {"type": "scotch_yoke", "params": {"crank": 1.0}}
# on its limit: crank + |offset| = coupler, the coupler square to the guide at 90° (offset −1)
# or 270° (offset 1), a transmission angle of 0°
LIMIT = {"type": "offset_slider_crank", "params": {"crank": 1.0, "coupler": 2.0, "offset": -1.0}}
MIRROR = {"type": "offset_slider_crank", "params": {"crank": 1.0, "coupler": 2.0, "offset": 1.0}}
SMALLEST = {
    "time_ratio": 1.2,
    "stroke": 0.4962307363062504,
    "min_transmission_angle_deg": 10,
    "objective": "min_size",
    "mechanisms": [{"type": "whitworth"}],
}
# the smallest Whitworth of SMALLEST: its connecting rod at 10° to the ram's path at 0° and 180°
WHITWORTH = {
    "crank": 0.3486851703779094,
    "pivot_distance": 0.04962307363062504,
    "lever": 0.2481153681531252,
    "connecting_rod": 0.2519429476405122,
}


@pytest.fixture(scope="module")
def client():
    with TestClient(app) as c:
        yield c


def analyze(client, mechanism, load, **extra):
    return client.post("/v1/analyze", json={"mechanism": mechanism, "load": load, **extra})


def detail(r):
    assert r.status_code == 422, (r.status_code, r.text)
    (d,) = r.json()["detail"]
    return d


# the examples that gave a 500


@pytest.mark.parametrize(
    ("field", "load", "words"),
    [
        ("crank_rpm", {"crank_rpm": 1e-200}, "crank_rpm must be ≥ 1e-06, got 1e-200"),
        (
            "speed_fluctuation",
            {"crank_rpm": 1, "speed_fluctuation": 5e-324},
            "speed_fluctuation must be ≥ 1e-06, got 5e-324",
        ),
        ("crank_rpm", {"crank_rpm": 2e6}, "crank_rpm must be ≤ 1e+06, got 2000000.0"),
        ("efficiency", {"crank_rpm": 1, "efficiency": 1e-300}, "efficiency must be ≥ 1e-06"),
    ],
)
def test_the_flywheel_and_the_motor_divide_by_nothing_out_of_range(client, field, load, words):
    load = {"length_unit": "m", **load}
    for r in (
        analyze(client, SCOTCH, load),
        client.post("/v1/synthesize", json={**SMALLEST, "load": load}),
    ):
        d = detail(r)
        assert d["loc"] == ["body", "load", field] and d["msg"].startswith(words), d
    with pytest.raises(InvalidParameters, match=rf"load.{field} must be .* at least 1e-06") as e:
        Load(**load)
    assert e.value.loc == ("load", field)


def test_the_extreme_accepted_load_gives_finite_numbers():
    """The slowest crank, the tightest flywheel and the least efficient drive: ΔE / (Cs ω²) and
    mean·ω/η as computed by hand, every number finite."""
    lo = {k: v[0] for k, v in RANGES.items()}
    load = Load("m", slider_mass=1e12, cutting_force=1e12, **lo)
    got = synth.analyze("whitworth", WHITWORTH, load=load).loads
    om = 2 * math.pi * lo["crank_rpm"] / 60
    assert got.flywheel.inertia == pytest.approx(
        got.flywheel.energy / (lo["speed_fluctuation"] * om**2), rel=1e-12
    )
    assert got.power.rated == pytest.approx(got.torque.mean * om / lo["efficiency"], rel=1e-12)
    assert all(map(math.isfinite, _numbers(got)))


def test_a_dead_point_without_a_load_on_it_has_zero_forces(client):
    """At 90° the limit design's coupler is square to the guide (A singular): nothing loads it,
    so nothing is transmitted, as at every other angle."""
    r = analyze(client, LIMIT, {"length_unit": "m", "crank_rpm": 60}, crank_angles_deg=[90])
    assert r.status_code == 200, r.text
    assert r.json()["curves"]["torque"] == [0.0]
    assert r.json()["loads"]["torque"]["max"] == 0.0


@pytest.mark.parametrize(
    ("mechanism", "load", "at"),
    [
        (LIMIT, {"slider_mass": 1.0}, 90),
        (MIRROR, {"slider_mass": 1.0, "length_unit": "mm"}, 270),
        # on the Grashof limit: it folds flat at 0°, coupler and rocker in line
        (
            {
                "type": "crank_rocker_slider",
                "params": {
                    "ground": 0.2,
                    "crank": 0.1,
                    "coupler": 1.0,
                    "rocker": 1.1,
                    "rocker_arm": 1.1,
                    "connecting_rod": 1.1,
                },
            },
            {"link_mass_per_length": 1.0, "crank_rpm": 1e-6},
            0,
        ),
    ],
)
def test_a_loaded_dead_point_names_its_angle_and_joint(client, mechanism, load, at):
    """The ram's mass (or the links') moves at the dead point: no finite force does it (with or
    without the guide's friction), whichever angles the curves ask for."""
    load = {"length_unit": "m", "crank_rpm": 60, **load}
    for extra in ({}, {"crank_angles_deg": [at, at + 1e-9]}):
        d = detail(analyze(client, mechanism, load, **extra))
        assert d["loc"] == ["body", "mechanism"] and d["type"] == "invalid_design"
        assert d["msg"].startswith(
            f"the joint forces are indeterminate at crank angle {at}°: a dead point (the "
        ), d


@pytest.mark.parametrize("load", [{"slider_mass": 1}, {"cutting_force": 5}])
def test_friction_on_a_dead_point_locks_the_ram_there(client, load):
    """Loaded there or not (the cut stops short of it, nothing weighs: the forces are 0 at the
    dead point, and finite around it), the guide's friction locks the ram at the dead point."""
    load = {"length_unit": "mm", "crank_rpm": 40, "guide_friction": 0.3, **load}
    d = detail(analyze(client, MIRROR, load))
    assert d["loc"] == ["body", "mechanism"]
    assert d["msg"].startswith("the guide's friction 0.3 locks the ram at crank angle 270°")
    assert "any friction locks it" in d["msg"]
    if "cutting_force" in load:
        del load["guide_friction"]
        assert analyze(client, MIRROR, load).json()["loads"]["torque"]["max"] > 0


def test_a_profile_steeper_than_a_nanometre_is_refused(client):
    """Two points of a force profile 1e-308 of the stroke apart made its slope overflow."""
    load = {"length_unit": "m", "crank_rpm": 1, "force_profile": [[0.0, 1.0], [1e-308, 10.0]]}
    d = detail(analyze(client, LIMIT, load))
    assert d["loc"] == ["body", "load", "force_profile"] and "by 1e-09 or more" in d["msg"]
    load = {"length_unit": "m", "crank_rpm": 1, "cutting_force": 1, "cutting_zone": [0.5, 0.5]}
    assert detail(analyze(client, LIMIT, load))["loc"] == ["body", "load", "cutting_zone"]
    with pytest.raises(InvalidParameters, match="each by at least 1e-09"):
        Load("m", 1, force_profile=((0.0, 1.0), (1e-308, 10.0)))


def test_the_least_friction_that_locks_is_the_rods_lean():
    """The Whitworth's rod leans 10° off the ram's path at most: friction up to just below
    tan 10° gives finite (if large) forces, exactly tan 10° unbounded ones at the lean's angle,
    and more locks the ram, the message saying from which friction on."""
    lock = math.tan(math.radians(10.0))

    def load(mu):
        return Load("m", 60, slider_mass=1.0, guide_friction=mu)

    below = synth.analyze("whitworth", WHITWORTH, load=load(lock * (1 - 1e-6))).loads
    assert all(map(math.isfinite, _numbers(below)))
    with pytest.raises(InvalidDesign, match="indeterminate at crank angle 180°: the guide's fr"):
        synth.analyze("whitworth", WHITWORTH, load=load(lock))
    for mu in (lock * (1 + 1e-12), 0.2, 0.5, 2.0):
        with pytest.raises(InvalidDesign, match=r"locks the ram at crank angle (0|180)°") as e:
            synth.analyze("whitworth", WHITWORTH, load=load(mu))
        assert f"locks under a friction of {lock:.6g} or more" in e.value.msg
        assert e.value.condition == "friction"


def test_a_synthesis_whose_design_locks_says_where(client):
    """The smallest Whitworth locks under the load's friction: not a server error; the design
    is left out, and its type's reason says where and from which friction on."""
    load = {"length_unit": "m", "crank_rpm": 60, "slider_mass": 1, "guide_friction": 0.5}
    r = client.post("/v1/synthesize", json={**SMALLEST, "load": load})
    assert r.status_code == 200, r.text
    body = r.json()
    assert body["candidates"] == []
    (why,) = body["infeasible"]
    assert why["code"] == "LOAD_NOT_CARRIED", why
    assert (
        ANGLE.search(why["reason"])
        and "locks under a friction of 0.176327 or more" in why["reason"]
    )


def test_a_screen_of_many_designs_ranks_a_dead_point_last():
    """``Forces.each`` (the least peak torque's screen): NaN where A is singular, no error."""
    m = get("offset_slider_crank")
    pv = [*LIMIT["params"].values(), *np.zeros(len(kinetics.LOAD))]
    pv[len(m.parameters) + kinetics.LOAD.index("slider_mass")] = 1.0
    pv[len(m.parameters) + kinetics.LOAD.index("unit")] = 1.0
    pv[len(m.parameters) + kinetics.LOAD.index("omega")] = 1.0
    pvs = np.array([pv, pv])
    z = forces(m, frozenset()).each(np.radians([90.0, 30.0]), pvs)
    assert np.isnan(z[0]).all() and np.isfinite(z[1]).all()


# random loaded requests at the limits


@pytest.fixture(scope="module")
def tally():
    counts: Counter[str] = Counter()
    yield counts
    print("\nloaded limits:", dict(sorted(counts.items())))


@st.composite
def in_range(draw, name):
    """A number of the load's near and on the ends of its range (``RANGES``), or, one time in
    eight, past them."""
    lo, hi = RANGES[name]
    if all(draw(st.booleans()) for _ in range(3)):
        return draw(st.sampled_from([5e-324, 1e-200, 0.0, lo * (1 - 1e-15), hi * 2, 1e300]))
    return draw(st.one_of(st.sampled_from([lo, hi]), log_uniform(lo, hi)))


@st.composite
def load_spec(draw, lock: float | None):
    """A load: its unit, speed and flywheel to the ends of their ranges and past them, its
    masses and cut from nothing to the schema's largest, and the guide's friction at the
    lock (``lock``: the friction from which the design locks) to a part in 1e15 either way,
    or any."""
    out = {
        "length_unit": draw(st.sampled_from(["m", "mm", "in"])),
        "crank_rpm": draw(in_range("crank_rpm")),
    }
    for name in ("speed_fluctuation", "efficiency", "flywheel_rpm", "flywheel_width", "motor_rpm"):
        if draw(st.booleans()):
            out[name] = draw(in_range(name))
    for name in ("slider_mass", "link_mass_per_length"):
        out[name] = draw(st.one_of(st.just(0.0), log_uniform(1e-6, 1e12)))
    if draw(st.booleans()):
        out["cutting_force"] = draw(log_uniform(1e-3, 1e12))
    elif draw(st.booleans()):
        steps = st.lists(st.integers(0, 1000), min_size=2, max_size=5, unique=True)
        fractions = sorted(u / 1000 for u in draw(steps))
        out["force_profile"] = [[u, draw(log_uniform(1e-3, 1e6))] for u in fractions]
    if draw(st.booleans()):
        out["gravity_deg"] = draw(st.sampled_from([-90.0, 0.0, 90.0, 180.0, 37.5]))
    elif draw(st.booleans()):  # the machine's frame: a shaper, a slotter, a slope
        out["ram_incline_deg"] = draw(st.sampled_from([-90.0, 0.0, 37.5, 90.0]))
    if lock is not None and lock <= 2 and draw(st.integers(0, 3)) > 0:
        nudge = draw(st.sampled_from([0.0, 0.0, 1e-15, -1e-15, 1e-9, -1e-9, 1e-3, -1e-3]))
        out["guide_friction"] = lock * (1 + nudge)
    elif draw(st.booleans()):
        out["guide_friction"] = draw(st.floats(0.0, 2.0))
    return out


def ram_lock(mtype, p) -> float | None:
    """The friction from which the ram locks, from the analysis without a load: the tangent of
    the least transmission angle where a link drives the ram (None: nothing leans)."""
    try:
        a = synth.analyze(mtype, p)
    except synth.SynthError:
        return None
    ram = [j.min_deg for j in a.transmission.joints if j.joint.endswith(("-ram", "-slider"))]
    return math.tan(math.radians(min(ram))) if ram else None


def check(r, tally, kind):
    """No 5xx; a 422 names a body field or a crank angle; a 200's loads are finite."""
    assert r.status_code in (200, 422), (r.status_code, r.text[:2000])
    if r.status_code == 422:
        for d in r.json()["detail"]:
            loc, msg = d["loc"], d["msg"]
            assert (loc[0] == "body" and len(loc) > 1) or ANGLE.search(msg), d
            if "indeterminate" in msg or "locks the ram" in msg:
                assert ANGLE.search(msg), d
                tally[f"{kind} 422 {'locks' if 'friction' in msg else 'dead point'}"] += 1
            else:
                tally[f"{kind} 422 {'.'.join(map(str, loc[1:3])) or d['type']}"] += 1
        return
    tally[f"{kind} 200"] += 1
    body = r.json()
    # a synthesis the budget cut before its candidates' loads were analysed says so, per type
    # (how far it got is the clock's on a shared machine)
    cut = {i["type"] for i in body.get("infeasible", ()) if i["code"] == "BUDGET_EXHAUSTED"}
    for loads in (
        [c["loads"] for c in body["candidates"] if c["type"] not in cut]
        if kind == "synthesis"
        else [body["loads"]]
    ):
        assert loads is not None
        assert all(isinstance(x, float | int) and math.isfinite(x) for x in _numbers(loads))


@settings(max_examples=ANALYSES)
@given(data=st.data())
def test_loaded_analyses_at_the_limits_never_fail(client, tally, data):
    mtype = data.draw(st.sampled_from(LOADED))
    p = data.draw(design(mtype))
    lock = ram_lock(mtype, p)
    extra = {}
    if data.draw(st.booleans()):  # curves at the dead centres (a dead point is one) and more
        try:
            a = synth.analyze(mtype, p)
            centres = [e.crank_angle_deg for e in a.extremes.values()]
        except synth.SynthError:
            centres = []
        angles = [0.0, 90.0, 180.0, 270.0, *centres, data.draw(st.floats(0, 360))]
        extra = {"crank_angles_deg": angles, "include": ["forces"]}
    load = data.draw(load_spec(lock))
    r = analyze(client, {"type": mtype, "params": p}, load, **extra)
    check(r, tally, "analysis")


@settings(max_examples=SYNTHESES)
@given(data=st.data())
def test_loaded_syntheses_at_the_limits_never_fail(client, tally, data):
    """Designs on the bound (min_size and the front's small end sit on it, their connecting
    rod at that lean where it is what transmits worst), the bound down to a millionth of a
    degree (nearly a dead point), the friction at the bound's lock."""
    bound = data.draw(st.one_of(st.sampled_from([1e-6, 0.1, 10.0]), st.floats(1e-6, 60.0)))
    objective = data.draw(st.sampled_from(OBJECTIVES))
    types = data.draw(st.lists(st.sampled_from(QUICK_RETURN), min_size=1, max_size=2, unique=True))
    lock = math.tan(math.radians(bound))
    body = {
        "time_ratio": data.draw(st.floats(1.05, 3.0)),
        "stroke": data.draw(log_uniform(1e-3, 1e3)),
        "min_transmission_angle_deg": bound,
        "objective": objective,
        "mechanisms": [{"type": t} for t in types],
        "load": data.draw(load_spec(lock)),
        "time_budget_ms": 300,
    }
    check(client.post("/v1/synthesize", json=body), tally, "synthesis")


def _numbers(loads):
    """Every number of a ``Loads`` (or its JSON), for a finiteness check (a figure not asked
    for, None, is none)."""
    if loads is None:
        return []
    if isinstance(loads, dict):
        return [x for v in loads.values() for x in _numbers(v)] if loads else []
    if isinstance(loads, list | tuple):
        return [x for v in loads for x in _numbers(v)]
    if hasattr(loads, "__dataclass_fields__"):
        return _numbers({k: getattr(loads, k) for k in loads.__dataclass_fields__})
    return [loads]
