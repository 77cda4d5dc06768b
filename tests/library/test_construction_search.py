"""The four-bars' searched objectives move on their dead-centre construction
(``synth.synthesis.chart``): every point whose toggles lie in one assembly circuit is a design
with the request's time ratio and stroke, judged here by the forward analysis (its dead
centres found by root finding, nothing of the construction); the coordinates' derivatives
agree with central differences; a design gives its coordinates back. And a local optimum on
a bound survives the projection that ends each run (``screen.project``)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import synth
from synth.mechanisms import get
from synth.mechanisms.fourbar.construction import circuit, crank
from synth.numerics.ops import NUMPY
from synth.synthesis import chart, screen
from synth.synthesis.formulation import formulation, kept_by
from synth.synthesis.solve import starts as halton

FOURBARS = ["crank_rocker_slider", "drag_link_slider"]


def _chart(
    mtype: str, time_ratio: float, scale: bool, fixed: dict[str, float] | None = None
) -> chart.Chart:
    m = get(mtype)
    fixed = fixed or {}
    free = tuple(n for n in m.names if n not in fixed)
    assert chart.applies(m, frozenset(), free)
    lo, hi = np.full(len(free), 0.1), np.full(len(free), 5.0)
    return chart.Chart(m, frozenset(), free, lo, hi, time_ratio, scale, fixed)


# one part of each kind fixed (stroke units): a link of the four-bar (its length then sets the
# scale), the rod
PINNED = [
    ("crank_rocker_slider", {"coupler": 2.99}),
    ("crank_rocker_slider", {"rocker": 0.6}),
    ("crank_rocker_slider", {"connecting_rod": 0.64}),
    ("drag_link_slider", {"ground": 0.4}),
    ("drag_link_slider", {"crank": 1.2}),
]


def _points(c: chart.Chart, n: int) -> list[tuple[np.ndarray, np.ndarray]]:
    """Halton points z of the coordinates' box (v within ±3) on each sheet, with their
    constants, those whose toggles lie in one circuit."""
    box = np.array(c.bounds())
    box[1] = (-3.0, 3.0)
    if "s" in c.names:
        box[2] = (-1.0, 1.0)
    out = []
    for sigma in (1, -1):
        k = c.constants(sigma, 0.3)
        for z in halton(box[:, 0], box[:, 1], np.zeros(len(box), bool), n):
            zr, zi = crank(z[0], 1 + math.exp(z[1]), k[0], k[1], NUMPY)
            if circuit(zr, zi, k[0], k[1]) < 0:
                out.append((z, k))
    return out


def _designs_judged(mtype: str, time_ratio: float, fixed: dict[str, float]) -> int:
    """How many of the chart's points meet the formulation's inequalities, each of them
    judged by the forward analysis of the whole design (fixed parts too): the target time
    ratio and stroke, and its coordinates given back."""
    c = _chart(mtype, time_ratio, scale=True, fixed=fixed)
    m = get(mtype)
    form, key = formulation(m, frozenset(), c.free), kept_by(m, frozenset(), c.free)
    pv = np.array([*fixed.values(), time_ratio, 0.999])
    inequality = form.lbg != form.ubg
    judged = 0
    for z, k in _points(c, 64):
        x = c.at(z, k)[0]
        g = screen.constraints(form, key, x[None], pv)[0][0]
        if not np.all((g >= form.lbg)[inequality] & (g <= form.ubg)[inequality]):
            continue
        a = synth.analyze(mtype, {**dict(zip(c.free, x, strict=True)), **fixed})
        assert a.time_ratio == pytest.approx(time_ratio, rel=1e-9), (z, k)
        assert a.stroke == pytest.approx(1.0, rel=1e-9), (z, k)
        back = c.starts(x)
        assert any(np.abs(c.at(zb, kb)[0] - x).max() <= 1e-9 * np.abs(x).max() for zb, kb in back)
        judged += 1
    return judged


@pytest.mark.parametrize("mtype", FOURBARS)
@pytest.mark.parametrize("time_ratio", [1.3, 2.0])
def test_every_point_in_one_circuit_is_a_design_with_the_targets(mtype, time_ratio):
    """Where the formulation's inequalities hold too (a crank-rocker whose slider turns back
    where its rocker does, Grashof's kind, the transmission to 2.56°): what the search keeps."""
    assert _designs_judged(mtype, time_ratio, {}) >= 20


@pytest.mark.parametrize(("mtype", "fixed"), PINNED)
@pytest.mark.parametrize("time_ratio", [1.3, 2.0])
def test_with_a_part_fixed_every_point_is_a_design_with_the_targets_and_that_part(
    mtype, fixed, time_ratio
):
    """One link fixed: the coordinates are (ψ, v[, l, h]) and the link's length sets the
    scale; the rod fixed: (ψ, v, s, h)."""
    names = _chart(mtype, time_ratio, scale=True, fixed=fixed).names
    assert "s" not in names or "connecting_rod" in fixed
    assert _designs_judged(mtype, time_ratio, fixed) >= 10


@pytest.mark.parametrize("mtype", FOURBARS)
@pytest.mark.parametrize("scale", [False, True])
@pytest.mark.parametrize("fixed", [None, "link"])
def test_the_coordinates_derivatives_agree_with_central_differences(mtype, scale, fixed):
    link = {m: f for m, f in PINNED if "connecting_rod" not in f}[mtype] if fixed else None
    c = _chart(mtype, 1.6, scale, link)
    for z, k in _points(c, 8)[:6]:
        x, dx = c.at(z, k)
        h = 1e-6
        for j in range(len(z)):
            e = np.zeros(len(z))
            e[j] = h
            central = (c.at(z + e, k)[0] - c.at(z - e, k)[0]) / (2 * h)
            assert np.allclose(dx[:, j], central, rtol=1e-6, atol=1e-7 * np.abs(x).max())


@pytest.mark.parametrize("mtype", FOURBARS)
def test_off_its_circuit_a_point_that_misses_the_targets_is_told_so(mtype):
    """A point whose toggles lie in two circuits is no design with the targets; where its
    design (judged by the forward analysis) misses the time ratio by over 10%, the circuit's
    row says so by a margin SLSQP weighs (≤ −1e-4; sin θ sin(θ + φ) ≥ 0.0014 here). With the
    factor |Z1|² the row had, a short crank's (v up to 5: λ − 1 ≈ 150) was as small as −6e-8,
    and a crank-rocker's torque runs went there and stayed, hundreds of iterations (designs
    of time ratio 1.01 and stroke 0.06 at 1.6/0°)."""
    c = _chart(mtype, 1.6, scale=False)
    row = len(c.low) + len(c.high)  # the own rows: the bounds below, above, the circuit's
    box = np.array(c.bounds())
    box[1] = (-3.0, 5.0)
    missed = []
    for sigma in (1, -1):
        k = c.constants(sigma, 0.0)
        for z in halton(box[:, 0], box[:, 1], np.zeros(len(box), bool), 400):
            x, _, (own, _) = c.point(z, k)
            if own[row] >= 0:  # one circuit
                continue
            try:
                a = synth.analyze(mtype, dict(zip(c.free, x, strict=True)))
            except synth.SynthError:
                continue
            if abs(a.time_ratio - 1.6) > 0.16:
                missed.append(own[row])
    assert len(missed) >= 100
    assert max(missed) <= -1e-4


@pytest.mark.parametrize("mtype", FOURBARS)
def test_a_design_gives_its_coordinates_back(mtype):
    c = _chart(mtype, 1.6, scale=True)
    for z, k in _points(c, 16):
        x = c.at(z, k)[0]
        if np.any(x[c.links] <= 0):
            continue
        back = c.starts(x)
        assert back, z
        assert any(np.abs(c.at(zb, kb)[0] - x).max() <= 1e-9 * np.abs(x).max() for zb, kb in back)


def test_drawn_points_of_the_construction_pass_the_screen_where_the_boxs_seldom_do():
    """A crank-rocker at time ratio 1.6 and 0° with a rod: of 256 Halton points of the box,
    a handful project onto designs; of 256 on the construction, many more."""
    c = _chart("crank_rocker_slider", 1.6, scale=False)
    m = get("crank_rocker_slider")
    free = tuple(m.names)
    form, key = formulation(m, frozenset(), free), kept_by(m, frozenset(), free)
    pv = np.array([1.6, 0.999])
    lo, hi = c.lo, c.hi
    box = screen.project(form, key, halton(lo, hi, lo > 0, 256), pv, lo, hi)
    drawn = screen.project(form, key, c.draw(256)[0], pv, lo, hi)
    assert len(drawn) >= 3 * max(len(box), 5)
    for x in drawn[:10]:
        a = synth.analyze("crank_rocker_slider", dict(zip(free, x, strict=True)))
        assert a.time_ratio == pytest.approx(1.6, rel=1e-9)
        assert a.stroke == pytest.approx(1.0, rel=1e-9)


def test_a_local_optimum_on_its_bounds_survives_the_projection():
    """Where a run ends with parts on their lower bounds (a crank-rocker's most uniform speed
    at time ratio 1.6 and 0°, its crank and slider height at 0.1 stroke), the Newton steps
    onto the equalities hold those parts on their bounds: clipped, each step undid part of
    the next and the design was lost."""
    m = get("crank_rocker_slider")
    free = tuple(m.names)
    form, key = formulation(m, frozenset(), free), kept_by(m, frozenset(), free)
    end = np.array(
        [
            [
                0.1998058519999199,
                0.1,
                0.10025107783815104,
                0.19985598001977645,
                0.998964164200646,
                0.8998640282288428,
                0.10000000000000685,
            ]
        ]
    )
    lo, hi = np.full(7, 0.1), np.array([5.0, 5.0, 5.0, 5.0, 5.0, 2.0, 5.0])
    (x,) = screen.project(form, key, end, np.array([1.6, 0.999]), lo, hi, every=False)
    assert np.all(x >= lo) and np.all(x <= hi)
    assert np.abs(x - end[0]).max() <= 1e-9
    a = synth.analyze("crank_rocker_slider", dict(zip(free, x, strict=True)))
    assert a.time_ratio == pytest.approx(1.6, rel=1e-9)
    assert a.stroke == pytest.approx(1.0, rel=1e-9)


def test_runs_that_come_to_one_optimum_give_it_once(monkeypatch):
    """Where the scale is free and no coordinate (the motion objectives), each run moves at
    its start's scale; a run that comes to where an earlier one ended, at another scale, ends
    with nothing of its own: each local optimum of a variant is given once (compared at the
    smallest scale, as the runs' ends are). Compared at the runs' own scales, four of the
    crank-rocker's runs at time ratio 1.6 and 20° gave one optimum four times."""
    from synth.synthesis import motion

    found: dict[frozenset[str], list[np.ndarray]] = {}
    real = motion.local_optima

    def spy(m, variant, *args, **kwargs):
        for d in real(m, variant, *args, **kwargs):
            found.setdefault(variant, []).append(np.array([d[n] for n in sorted(d)]))
            yield d

    monkeypatch.setattr(motion, "local_optima", spy)
    r = synth.synthesize(
        1.6,
        1.0,
        20,
        objective="uniform_cutting_speed",
        mechanisms=["crank_rocker_slider"],
        time_budget_ms=600_000,
    )
    assert r.candidates and found
    for variant, designs in found.items():
        for i in range(len(designs)):
            for j in range(i):
                apart = np.abs(designs[i] - designs[j]).max()
                assert apart > 1e-3, (sorted(variant), i, j, apart)
