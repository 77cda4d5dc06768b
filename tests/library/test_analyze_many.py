"""``analyze_many`` (a front's verification: several designs' dead centres and transmission
extremes in shared compiled calls) gives each design exactly what ``analyze`` gives it alone,
to the bit, and the same refusal for a design that cannot run; whatever its neighbours in the
batch, including designs whose grid needs refining and designs the analysis refuses."""

import dataclasses

import numpy as np
import pytest

import synth
from synth.analysis import roots
from synth.analysis.kinematics import analyze_many
from synth.errors import SynthError
from synth.mechanisms import all_types

from ..support.designs import random_designs

# designs that complete() accepts but the analysis refuses: a slider that stands still, a
# change point whose circuit switches (tests/referees/test_regressions.py)
REFUSED = {
    "offset_slider_crank": {"crank": 1.0, "coupler": 1.0, "offset": 0.0},
    "drag_link_slider": {
        "ground": 1.0,
        "crank": 1.0001,
        "coupler": 1.9999,
        "follower": 2.0,
        "follower_arm": 1.0,
        "connecting_rod": 2.0,
    },
}
# a design whose grid is refined: both dead centres between two grid points
REFINED = {
    "crank_shaper": {
        "crank": 0.999,
        "pivot_distance": 1.0,
        "lever": 1.999,
        "ram_link": 1.9096243545533795,
        "ram_height": 0.08937564544662047,
    },
}


def alone(mtype, params, **extras):
    try:
        return synth.analyze(mtype, params, **extras)
    except SynthError as e:
        return e


def same(a, b) -> bool:
    """Equal to the bit (every number of the analysis), or the same refusal."""
    if isinstance(a, SynthError) or isinstance(b, SynthError):
        return type(a) is type(b) and str(a) == str(b)
    return dataclasses.astuple(a) == dataclasses.astuple(b)


@pytest.mark.parametrize("mtype", all_types())
def test_each_design_as_alone(mtype, monkeypatch):
    refined = []
    original = roots.refine_grid

    def counted(f, pv, grid, *args):
        out = original(f, pv, grid, *args)
        refined.append(len(out[0]) > len(grid))
        return out

    monkeypatch.setattr(roots, "refine_grid", counted)
    designs = random_designs(mtype, 120, seed=5)
    if mtype in REFUSED:
        designs[7:7] = [REFUSED[mtype]]
    if mtype in REFINED:
        designs[3:3] = [REFINED[mtype]]
    rng = np.random.default_rng(1)
    start = 0
    while start < len(designs):  # batches of 1 to 9, as a front's or a sweep's
        batch = designs[start : start + int(rng.integers(1, 10))]
        start += len(batch)
        for p, got in zip(batch, analyze_many(mtype, batch), strict=True):
            assert same(got, alone(mtype, p)), p
    if mtype in REFINED:
        assert any(refined)  # the batch refined a grid, as the design alone does
    if mtype in REFUSED:
        got = analyze_many(mtype, [REFUSED[mtype], designs[0]])
        assert isinstance(got[0], SynthError) and not isinstance(got[1], SynthError)


@pytest.mark.parametrize("mtype", ["whitworth", "crank_rocker_slider"])
def test_what_a_candidate_adds_as_alone(mtype):
    extras = {
        "include": ["motion", "sensitivities", "envelope"],
        "tolerance": synth.Tolerance(absolute=0.01),
    }
    designs = random_designs(mtype, 12, seed=9)
    for p, got in zip(designs, analyze_many(mtype, designs, **extras), strict=True):
        assert same(got, alone(mtype, p, **extras))


def test_a_refused_completion_is_returned_not_raised():
    bad = {"crank": 1.0, "coupler": 0.5, "offset": 0.0}  # coupler shorter than the crank
    got = analyze_many("offset_slider_crank", [bad, {**bad, "coupler": 2.0}])
    assert isinstance(got[0], SynthError) and str(got[0]) == str(alone("offset_slider_crank", bad))
    assert got[1].time_ratio == pytest.approx(1.0)


def test_a_batch_beyond_the_buffers():
    """40 designs: more than one compiled call's batch (``roots.BATCH``, 32)."""
    designs = random_designs("whitworth", 40, seed=2)
    for p, got in zip(designs, analyze_many("whitworth", designs), strict=True):
        assert same(got, alone("whitworth", p))
