"""The loads (synth.analysis.loads) against independent computations.

- Virtual work, links massless: the crank's power is the ram's, T = (m s″ ω² + F(s)) |s′| in
  SI (F the cutting force in its zone, or a profile's, linear between its points), with s′
  by complex step and s″ by a Cauchy integral on tests/support's own geometry, the working
  stroke and the cutting zone by its brute force. 1e-9 of the turn's largest |T|.
- With link masses, the Newton–Euler torque against the energy balance T = d(KE + PE)/dθ +
  F |s′| [cutting] + μ |N| |s′| (the guide's friction), the kinetic and potential energy of
  the drawn members (uniform slender rods) and the ram from the pins' positions,
  differentiated by central differences (fourth order, two steps Richardson-combined). 1e-8.
- The guide's friction on a slider-crank with massless links, by hand. 1e-9.
- The flywheel's energy swing against Simpson's rule on 200 000 points a turn, on each
  smooth piece of the torque curve (the zone's ends from the brute force). 1e-7.
- Units: one design in m, mm and in gives the same SI numbers. 1e-12.
- The torque's extremes are never below dense sampling, and the mean equals the work a turn
  over 2π (the cut's work, F × its travel).
"""

from __future__ import annotations

import math
from dataclasses import asdict, replace

import numpy as np
import pytest
from scipy.integrate import cumulative_simpson, simpson
from scipy.optimize import brentq

import synth
from synth.errors import InvalidDesign, InvalidParameters
from synth.load import Load
from synth.mechanisms import get

from ..support import bruteforce
from ..support.designs import TYPES, random_designs
from ..support.motion_bruteforce import acceleration, velocity

N = 200  # designs per type for the identities
RPM = 45.0
OMEGA = 2 * math.pi * RPM / 60
FIXED = ("O2", "O4")  # pivots on the frame: a member between them is the ground


def _strokes(mtype, p, zone):
    """The working stroke's start and length and the cutting zone's crank angles (radians),
    by the brute force; and the fraction of the working stroke the ram has run, at angles."""
    b = bruteforce.simulate(mtype, p, n=4000)
    work = b["working_angle"]
    start = b["theta_min"] if b["working_direction"] == 1 else b["theta_max"]
    s0, s1 = (b["s_min"], b["s_max"]) if b["working_direction"] == 1 else (b["s_max"], b["s_min"])

    def at(x):
        if x in (0.0, 1.0):
            return start + x * work
        level = s0 + x * (s1 - s0)
        return brentq(
            lambda t: bruteforce.position(mtype, p, np.array([t]))[0] - level,
            start,
            start + work,
            xtol=1e-15,
            rtol=1e-15,
        )

    def run(theta):
        return (bruteforce.position(mtype, p, theta) - s0) / (s1 - s0)

    return start, work, at(zone[0]), at(zone[1]), run


def _cutting(theta, lo, hi, margin):
    """Whether each angle is in the cutting zone [lo, hi], and whether it is more than
    ``margin`` from the zone's ends (where the force steps)."""
    d = (theta - lo) % (2 * math.pi)
    span = hi - lo
    clear = (np.abs(d - span) > margin) & (d > margin) & (2 * math.pi - d > margin)
    return d <= span, clear


@pytest.mark.parametrize("mtype", TYPES)
def test_the_torque_does_the_rams_work(mtype):
    rng = np.random.default_rng(TYPES.index(mtype))
    for i, p in enumerate(random_designs(mtype, N, seed=21)):
        unit = str(rng.choice(["m", "mm", "in"]))
        mass = float(rng.uniform(0, 200))
        if i % 2:  # a force profile: 2 to 5 points, linear between them
            k = int(rng.integers(2, 6))
            fractions = np.sort(rng.choice(np.linspace(0, 1, 41), size=k, replace=False))
            profile = tuple((float(u), float(rng.uniform(0, 5000))) for u in fractions)
            load = Load(unit, RPM, slider_mass=mass, force_profile=profile)
        else:
            a = float(rng.uniform(0.0, 0.45))
            load = Load(
                unit,
                RPM,
                cutting_force=float(rng.uniform(0, 5000)),
                slider_mass=mass,
                cutting_zone=(a, float(rng.uniform(a + 0.05, 1.0))),
            )
        profile = np.array(load.profile)
        theta = rng.uniform(0, 2 * math.pi, 48)
        got = synth.analyze(mtype, p, crank_angles_deg=np.degrees(theta), load=load)
        k = load.metres
        _, _, lo, hi, run = _strokes(mtype, p, (profile[0, 0], profile[-1, 0]))
        inside, clear = _cutting(theta, lo, hi, margin=1e-9)
        force = np.where(inside, np.interp(run(theta), profile[:, 0], profile[:, 1]), 0.0)
        s1, s2 = velocity(mtype, p, theta) * k, acceleration(mtype, p, theta) * k
        expected = load.slider_mass * OMEGA**2 * s2 * s1 + force * np.abs(s1)
        scale = max(np.abs(expected).max(), abs(got.loads.torque.max), abs(got.loads.torque.min))
        err = np.abs(got.curves.torque - expected)[clear].max(initial=0.0)
        assert err <= 1e-9 * scale, (p, load.profile, err / scale)


def _kinetic_energy(mtype, p, theta, load, h):
    """KE(θ) + PE(θ) (J) of the drawn members (uniform slender rods) and the ram, the members'
    velocities by fourth-order central differences (step h) of the pins' positions, the ram's
    by complex step; PE in the load's gravity (the ram at the last pin of the drawing)."""
    m = get(mtype)
    k = load.metres
    offsets = np.array([-2, -1, 1, 2]) * h
    weights = np.array([1, -8, 8, -1]) / (12 * h)
    at = (theta[:, None] + offsets[None, :]).ravel()
    pins = synth.joints(mtype, p, np.degrees(at))
    pins = {q: xy.reshape(theta.size, 4, 2) * k for q, xy in pins.items()}

    def rate(x):  # d/dθ × ω of each angle's four offsets
        return (x * weights[None, :, None]).sum(axis=1) * OMEGA

    full = m.complete(p)
    g = np.array(load.gravity)
    here = {q: xy * k for q, xy in synth.joints(mtype, p, np.degrees(theta)).items()}
    ke = np.zeros(theta.size)
    for name, a, b in m.drawing:
        if {a, b} <= set(FIXED) or full[name] == 0:
            continue
        length = full[name] * k
        mass = load.link_mass_per_length * length
        va, vb = rate(pins[a]), rate(pins[b])
        vg = (va + vb) / 2
        rel = pins[b] - pins[a]
        angle = np.unwrap(np.arctan2(rel[..., 1], rel[..., 0]), axis=1)
        spin = (angle * weights[None, :]).sum(axis=1) * OMEGA
        ke += 0.5 * mass * (vg**2).sum(axis=1) + 0.5 * mass * length**2 / 12 * spin**2
        ke -= mass * ((here[a] + here[b]) / 2) @ g
    ram = velocity(mtype, p, theta) * k * OMEGA
    lifted = -load.slider_mass * list(here.values())[-1] @ g
    return ke + 0.5 * load.slider_mass * ram**2 + lifted


def _energy_rate(mtype, p, theta, load, h):
    """dKE/dθ by central differences of ``_kinetic_energy``, steps h and h/2 combined
    (Richardson: the h⁴ error terms cancel)."""

    def at(h):
        offsets = np.array([-2, -1, 1, 2]) * h
        weights = np.array([1, -8, 8, -1]) / (12 * h)
        ke = _kinetic_energy(mtype, p, (theta[:, None] + offsets).ravel(), load, h)
        return (ke.reshape(theta.size, 4) * weights).sum(axis=1)

    return (16 * at(h / 2) - at(h)) / 15


@pytest.mark.parametrize("mtype", TYPES)
def test_newton_euler_keeps_the_energy_balance(mtype):
    """T = d(KE + PE)/dθ + F |s′| + μ |N| |s′|: the work the ram and the links store, in
    motion and in height (gravity in any direction, half the designs), the cut's and the
    guide's friction's (with the guide's force N the analysis gives, half the designs)."""
    rng = np.random.default_rng(100 + TYPES.index(mtype))
    h = 2e-3  # with h/2: ~1e-11 on the sharpest Whitworth; rounding grows below (as 1/h²)
    for i, p in enumerate(random_designs(mtype, 40, seed=22)):
        mu = float(rng.uniform(0, 0.3)) if i % 2 else 0.0
        down = float(rng.uniform(-180, 180)) if i % 4 > 1 else None
        load = Load(
            "mm",
            RPM,
            cutting_force=float(rng.uniform(0, 5000)),
            cutting_zone=(0.0, 1.0),
            slider_mass=float(rng.uniform(0, 200)),
            guide_friction=mu,
            gravity_deg=down,
            link_mass_per_length=float(rng.uniform(0.1, 50)),
        )
        theta = rng.uniform(0, 2 * math.pi, 16)
        got = synth.analyze(
            mtype, p, crank_angles_deg=np.degrees(theta), load=load, include=["forces"]
        )
        _, _, lo, hi, _ = _strokes(mtype, p, (0.0, 1.0))
        inside, clear = _cutting(theta, lo, hi, margin=1e-9)
        s1 = np.abs(velocity(mtype, p, theta) * load.metres)
        rub = mu * got.curves.forces["guide"]
        expected = _energy_rate(mtype, p, theta, load, h) + (load.cutting_force * inside + rub) * s1
        scale = max(abs(got.loads.torque.max), abs(got.loads.torque.min))
        err = np.abs(got.curves.torque - expected)[clear].max(initial=0.0)
        assert err <= 1e-8 * scale, (p, mu, err / scale)


def test_the_guides_friction_on_a_slider_crank_by_hand():
    """Links massless, the coupler pushes along itself (P along e, from B to C): along the
    path P e_x − μ sign(v) |P e_y| = m a, across it N = −P e_y; the crank takes T = B × P e."""
    rng = np.random.default_rng(7)
    locked = 0
    for p in random_designs("offset_slider_crank", 100, seed=27):
        mu, mass = float(rng.uniform(0.01, 0.4)), float(rng.uniform(1, 200))
        load = Load("m", RPM, slider_mass=mass, guide_friction=mu)

        def coupler(theta, p=p):  # the crank pin, and the coupler's direction e
            bx, by = p["crank"] * np.cos(theta), p["crank"] * np.sin(theta)
            ex, ey = bruteforce.position("offset_slider_crank", p, theta) - bx, p["offset"] - by
            return bx, by, ex / p["coupler"], ey / p["coupler"]

        # where the coupler leans more than the friction angle off the path, no force moves
        # the ram: the analysis refuses the design
        _, _, ex, ey = coupler(np.linspace(0, 2 * math.pi, 20_001))
        if np.any(np.abs(ex) <= mu * np.abs(ey)):
            with pytest.raises(InvalidDesign, match="friction"):
                synth.analyze("offset_slider_crank", p, load=load)
            locked += 1
            continue
        theta = rng.uniform(0, 2 * math.pi, 32)
        got = synth.analyze(
            "offset_slider_crank",
            p,
            crank_angles_deg=np.degrees(theta),
            load=load,
            include=["forces"],
        )
        bx, by, ex, ey = coupler(theta)
        v = velocity("offset_slider_crank", p, theta)
        ram = mass * OMEGA**2 * acceleration("offset_slider_crank", p, theta)
        push = ram / (ex - mu * np.sign(v) * np.abs(ey))  # P, if it pushes (P > 0)
        pull = ram / (ex + mu * np.sign(v) * np.abs(ey))
        force = np.where(push > 0, push, pull)
        torque = force * (bx * ey - by * ex)
        clear = (np.abs(v) > 1e-6 * p["crank"]) & (np.abs(ey) > 1e-6)
        scale = np.abs(torque).max()
        assert np.abs(got.curves.torque - torque)[clear].max() <= 1e-9 * scale, (p, mu)
        guide = np.abs(force * ey)
        assert np.abs(got.curves.forces["guide"] - guide)[clear].max() <= 1e-9 * guide.max()
    assert 0 < locked < 20  # both kinds were met


def _dense_swing(mtype, p, load, n=200_000):
    """The largest swing of ∫ (T − mean) dθ on n points a turn, by Simpson's rule on each
    smooth piece of the torque curve (the cutting zone and the rest, split at the zone's ends,
    where the force steps), and the mean."""
    _, _, lo, hi, _ = _strokes(mtype, p, load.cutting_zone)
    pieces = []
    for a, b in ((lo, hi), (hi, lo + 2 * math.pi)):
        t = np.linspace(a, b, 2 * max(1, round(n * (b - a) / (4 * math.pi))) + 1)
        inner = np.degrees(np.clip(t, a + 1e-12, b - 1e-12))  # each end as its piece has it
        y = np.concatenate(
            [
                synth.analyze(
                    mtype, p, crank_angles_deg=inner[i : i + 50_000], load=load
                ).curves.torque
                for i in range(0, inner.size, 50_000)
            ]
        )
        pieces.append((t, y))
    mean = sum(simpson(y, x=t) for t, y in pieces) / (2 * math.pi)
    e = [np.zeros(1)]
    for t, y in pieces:
        e.append(e[-1][-1] + cumulative_simpson(y - mean, x=t))
    e = np.concatenate(e)
    return e.max() - e.min(), mean


@pytest.mark.parametrize("mtype", TYPES)
def test_the_flywheel_matches_a_dense_integration(mtype):
    rng = np.random.default_rng(200 + TYPES.index(mtype))
    for p in random_designs(mtype, 3, seed=23):
        for zone in ((0.1, 0.9), (0.0, 1.0)):
            load = Load(
                "mm",
                RPM,
                cutting_force=float(rng.uniform(100, 5000)),
                cutting_zone=zone,
                slider_mass=float(rng.uniform(0, 200)),
                link_mass_per_length=float(rng.uniform(0, 20)),
            )
            got = synth.analyze(mtype, p, load=load).loads
            swing, mean = _dense_swing(mtype, p, load)
            assert got.flywheel.energy == pytest.approx(swing, rel=1e-7), (p, zone)
            assert got.torque.mean == pytest.approx(mean, rel=1e-7, abs=1e-9 * got.torque.rms)
            om = load.omega
            assert got.flywheel.inertia == pytest.approx(swing / (0.05 * om**2), rel=1e-7)
            _shafts(mtype, p, load, got, swing, mean)


def _shafts(mtype, p, load, crank, swing, mean):
    """The flywheel and the motor where a designer puts them: on a shaft turning at
    flywheel_rpm the inertia is ΔE / (Cs ω_f²), ΔE the dense integration's, and (crank rpm /
    flywheel rpm)² of the crank shaft's; a solid steel disc of the width given, with the
    diameter given, has it (I = m D² / 8); the motor's torque at motor_rpm is the mean power
    over the efficiency, over the motor's speed."""
    shafts = {"flywheel_rpm": 1450.0, "flywheel_width": 80.0, "motor_rpm": 960.0}
    shafted = replace(load, speed_fluctuation=0.02, efficiency=0.85, **shafts)
    got = synth.analyze(mtype, p, load=shafted).loads
    fly = got.flywheel
    assert fly.rpm == 1450.0 and crank.flywheel.rpm == RPM
    assert fly.inertia == pytest.approx(swing / (0.02 * (1450 * math.pi / 30) ** 2), rel=1e-7)
    scaled = crank.flywheel.inertia * (0.05 / 0.02) * (RPM / 1450) ** 2
    assert fly.inertia == pytest.approx(scaled, rel=1e-12)
    diameter, width = fly.disc_diameter * 1e-3, 0.080  # m
    mass = 7850.0 * math.pi * diameter**2 / 4 * width
    assert mass * diameter**2 / 8 == pytest.approx(fly.inertia, rel=1e-12)
    motor = mean * (RPM * math.pi / 30) / 0.85 / (960 * math.pi / 30)
    assert got.power.motor_torque == pytest.approx(motor, rel=1e-7)
    assert crank.flywheel.disc_diameter is None and crank.power.motor_torque is None


@pytest.mark.parametrize("mtype", TYPES)
def test_gravity_in_the_machines_frame_means_the_same_for_every_type(mtype):
    """The ram's weight alone (massless links, a crank at a millionth of a rpm: no inertia),
    its working stroke α above the horizontal: the crank's torque is m g sin α ds_w/dθ, s_w
    the ram's travel along its working stroke (the brute force's, differentiated by complex
    step), whichever way the type draws its path; across the path the guide takes it."""
    theta = np.linspace(0.0, 2 * math.pi, 20_001)
    for p in random_designs(mtype, 3, seed=27):
        way = bruteforce.simulate(mtype, p, n=4000)["working_direction"]
        ds = way * bruteforce.d_dtheta(lambda t, p=p: bruteforce.position(mtype, p, t), theta)
        weight = 50.0 * 9.80665 * 1e-3 * ds  # N·m per unit of sin α: the lengths in mm
        for alpha in (-90.0, 0.0, 30.0):
            load = Load("mm", 1e-6, slider_mass=50.0, ram_incline_deg=alpha)
            got = synth.analyze(mtype, p, load=load).loads.torque
            want = math.sin(math.radians(alpha)) * weight
            tol = 1e-6 * np.abs(weight).max()
            assert got.max == pytest.approx(want.max(), abs=tol), (p, alpha)
            assert got.min == pytest.approx(want.min(), abs=tol), (p, alpha)


@pytest.mark.parametrize(
    ("mtype", "params", "down_deg"),
    [  # the path above the crank's pivot (y = offset > 0): down is −y; below it: +y
        ("offset_slider_crank", {"crank": 100.0, "coupler": 300.0, "offset": 60.0}, -90.0),
        ("offset_slider_crank", {"crank": 100.0, "coupler": 300.0, "offset": -60.0}, 90.0),
        # the ram's path x = h − d to the right of the crank's pivot (h = 390 > d = 240)
        ("crank_shaper", {"crank": 120.0, "pivot_distance": 240.0, "lever": 450.0}, 180.0),
    ],
)
def test_a_horizontal_ram_hangs_its_drive_below(mtype, params, down_deg):
    """A shaper (ram_incline_deg 0): gravity across the ram's path, from it towards the
    crank's pivot; with the links' weights, the same loads as that direction in the
    drawing's frame, worked out here by hand from the type's geometry."""
    base = {"slider_mass": 40.0, "link_mass_per_length": 12.0, "cutting_force": 500.0}
    machine = synth.analyze(mtype, params, load=Load("mm", RPM, **base, ram_incline_deg=0.0))
    drawn = synth.analyze(mtype, params, load=Load("mm", RPM, **base, gravity_deg=down_deg))
    for part in ("torque", "guide"):
        got, want = (asdict(getattr(a.loads, part)) for a in (machine, drawn))
        assert got == pytest.approx(want, rel=1e-12, abs=1e-9), part


PROFILE = ((0.0, 500.0), (0.1, 3000.0), (0.6, 2000.0), (0.95, 2000.0))


@pytest.mark.parametrize("mtype", TYPES)
def test_the_mean_torque_is_the_cuts_work(mtype):
    for p in random_designs(mtype, 20, seed=24):
        for load, per_stroke in (
            (
                Load(
                    "mm",
                    RPM,
                    cutting_force=1500.0,
                    cutting_zone=(0.2, 0.7),
                    slider_mass=80.0,
                    link_mass_per_length=5.0,
                ),
                1500.0 * 0.5,
            ),
            (
                Load("mm", RPM, force_profile=PROFILE, slider_mass=80.0),
                np.trapezoid([f for _, f in PROFILE], [u for u, _ in PROFILE]),
            ),
        ):
            a = synth.analyze(mtype, p, load=load)
            work = per_stroke * a.stroke * 1e-3  # J a turn: the inertia's is 0 over a turn
            assert a.loads.torque.mean == pytest.approx(work / (2 * math.pi), rel=1e-10)
            assert a.loads.power.mean == pytest.approx(work * RPM / 60, rel=1e-10)


@pytest.mark.parametrize("mtype", TYPES)
def test_the_extremes_are_never_below_sampling(mtype):
    for p in random_designs(mtype, 10, seed=25):
        load = Load("m", RPM, cutting_force=3000.0, slider_mass=60.0, link_mass_per_length=8.0)
        a = synth.analyze(mtype, p, samples=20_000, load=load)
        t, sampled = a.loads.torque, a.curves.torque
        scale = max(abs(t.max), abs(t.min))
        assert t.max >= sampled.max() - 1e-12 * scale
        assert t.min <= sampled.min() + 1e-12 * scale
        assert t.max - sampled.max() <= 1e-3 * scale  # the grid's points are near
        # where the analysis says each extreme is, the curve has it (from one side, at a
        # cutting zone's end, where the force steps)
        for value, deg in ((t.max, t.max_at_deg), (t.min, t.min_at_deg)):
            near = deg + np.array([-1e-9, 0.0, 1e-9])
            curve = synth.analyze(mtype, p, crank_angles_deg=near, load=load).curves.torque
            assert np.abs(curve - value).min() <= 1e-7 * scale
        assert t.rms >= abs(t.mean)


@pytest.mark.parametrize("mtype", TYPES)
def test_units_give_the_same_si_numbers(mtype):
    for p in random_designs(mtype, 5, seed=26):
        out = []
        for unit, per_metre in (("m", 1.0), ("mm", 1000.0), ("in", 1 / 0.0254)):
            load = Load(
                unit, RPM, cutting_force=2000.0, slider_mass=50.0, link_mass_per_length=10.0
            )
            q = {k: v * per_metre for k, v in p.items()}
            out.append(synth.analyze(mtype, q, load=load).loads)
        first = out[0]
        # each number to 1e-12 of its kind's scale: the mean is a small difference of large
        # inertia torques where the links are large and heavy
        torque = max(abs(first.torque.max), abs(first.torque.min))
        scales = {"torque": torque, "power": torque * OMEGA, "flywheel": torque * 2 * math.pi}
        for other in out[1:]:
            for kind, scale in scales.items():
                a, b = getattr(first, kind), getattr(other, kind)
                for k, v in vars(a).items():
                    if k.endswith("_deg"):
                        assert getattr(b, k) == pytest.approx(v, abs=1e-7), k
                    else:
                        size = scale / (0.05 * OMEGA**2) if k == "inertia" else scale
                        assert getattr(b, k) == pytest.approx(v, abs=1e-12 * size), (kind, k)
            for pin, f in first.joints.items():
                assert other.joints[pin].max == pytest.approx(f.max, rel=1e-12)
            assert other.guide.max == pytest.approx(first.guide.max, rel=1e-12)


@pytest.mark.parametrize(
    ("change", "field", "words"),
    [
        ({"length_unit": "ft"}, "length_unit", "one of m, mm, in"),
        ({"crank_rpm": 0.0}, "crank_rpm", "> 0"),
        ({"crank_rpm": math.inf}, "crank_rpm", "finite"),
        ({"cutting_force": -1.0}, "cutting_force", "≥ 0"),
        ({"slider_mass": math.nan}, "slider_mass", "finite"),
        ({"link_mass_per_length": -2.0}, "link_mass_per_length", "≥ 0"),
        ({"cutting_zone": (0.9, 0.1)}, "cutting_zone", "start < end"),
        ({"cutting_zone": (-0.1, 0.5)}, "cutting_zone", "0 ≤ start"),
        ({"cutting_zone": (0.1, 1.5)}, "cutting_zone", "end ≤ 1"),
        ({"speed_fluctuation": 0.0}, "speed_fluctuation", "> 0"),
        ({"efficiency": 1.2}, "efficiency", "(0, 1]"),
        ({"gravity_deg": math.inf}, "gravity_deg", "finite"),
        ({"guide_friction": -0.1}, "guide_friction", "≥ 0"),
        ({"force_profile": ((0.0, 10.0),)}, "force_profile", "at least two"),
        ({"force_profile": ((0.0, 10.0), (0.5, math.nan))}, "force_profile", "finite"),
        ({"force_profile": ((0.5, 10.0), (0.5, 20.0))}, "force_profile", "must increase"),
        ({"force_profile": ((0.0, 10.0), (1.5, 20.0))}, "force_profile", "in [0, 1]"),
        ({"force_profile": ((0.0, -1.0), (1.0, 20.0))}, "force_profile", "≥ 0"),
        ({"force_profile": PROFILE, "cutting_force": 5.0}, "force_profile", "not both"),
    ],
)
def test_a_bad_load_names_its_field(change, field, words):
    with pytest.raises(InvalidParameters) as e:
        Load(**{"length_unit": "mm", "crank_rpm": 40.0, **change})
    assert e.value.loc[:2] == ("load", field)
    assert words in str(e.value)


def test_a_synthesis_with_a_load_gives_each_candidate_its_loads():
    """Each returned candidate carries its loads, and only with a load: the mean torque is the
    cut's work over 2π at the request's stroke, whatever the design."""
    load = Load("mm", RPM, cutting_force=2000.0, slider_mass=60.0, link_mass_per_length=5.0)
    r = synth.synthesize(1.6, 300.0, 35.0, load=load)
    assert r.candidates
    for c in r.candidates:
        assert c.loads.torque.mean == pytest.approx(2000.0 * 0.8 * 0.3 / (2 * math.pi), rel=1e-9)
        assert c.loads.flywheel.inertia > 0 and c.loads.torque.max > c.loads.torque.mean
    assert all(c.loads is None for c in synth.synthesize(1.6, 300.0, 35.0).candidates)
