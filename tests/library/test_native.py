"""The analysis's compiled functions (synth.numerics.native) against CasADi's virtual machine:
the same numbers to the bit, for every type and structural variant, and the virtual machine wherever
no library can be built."""

from __future__ import annotations

import itertools
import math
import shutil

import casadi as ca
import numpy as np
import pytest

import synth
from synth.analysis.model import GRID, KINDS, Model
from synth.mechanisms import all_types, get
from synth.numerics.native import FLAGS, WIDEST, Mapped
from synth.synthesis import screen

from ..support.designs import random_designs

POWERS = {1 << k for k in range(WIDEST.bit_length())}  # 1, 2, 4 … WIDEST
MODELS = [
    (mtype, frozenset(parts))
    for mtype in all_types()
    for k in range(2)
    for parts in itertools.combinations([q.name for q in get(mtype).parameters if q.zero_means], k)
]


def model(mtype, variant, kind, monkeypatch, on: bool) -> Model:
    monkeypatch.setenv("SYNTH_NATIVE", "1" if on else "0")
    return Model(get(mtype), variant, kind)


@pytest.mark.skipif(shutil.which("cc") is None, reason="no C compiler: the virtual machine runs")
@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("mtype, variant", MODELS, ids=str)
def test_compiled_kinematics_match_the_virtual_machine_to_the_bit(
    mtype, variant, kind, monkeypatch, tmp_path
):
    """Every kind (the analysis, the motion, the pins, the envelope), its parameter
    derivatives (sensitivities, the motion objectives' gradients) and the dead centres."""
    monkeypatch.setenv("SYNTH_CACHE", str(tmp_path))
    vm, compiled = (model(mtype, variant, kind, monkeypatch, on) for on in (False, True))
    assert "External" in compiled.fn.fn.class_name(), FLAGS
    assert vm.fn.fn.class_name() != compiled.fn.fn.class_name()
    rng = np.random.default_rng(len(MODELS))
    m = get(mtype)
    designs = [m.complete(p) for p in random_designs(mtype, 40)]
    designs = [p for p in designs if m.variant(p) == variant][:5]
    assert designs
    for p in designs:
        pv = np.array([p[n] for n in m.names])
        for n in (1, 3, GRID, 4 * GRID):  # a Newton step's few angles, the grid, a curve
            theta = rng.uniform(0, 2 * math.pi, n)
            a, b = vm(theta, pv), compiled(theta, pv)
            for x, y in zip(a, b, strict=True):
                np.testing.assert_array_equal(x, y)
            np.testing.assert_array_equal(vm.dp(theta, pv), compiled.dp(theta, pv))
            if vm.dead is not None:
                np.testing.assert_array_equal(vm.dead(theta, pv), compiled.dead(theta, pv))


def test_without_a_compiler_or_a_cache_the_virtual_machine_runs(monkeypatch, tmp_path):
    from synth.numerics import native

    monkeypatch.setattr(native, "_compiler", lambda: None)
    monkeypatch.setenv("SYNTH_CACHE", str(tmp_path / "empty"))
    assert model(
        "drag_link_slider", frozenset(), "kinematics", monkeypatch, True
    ).fn.fn.class_name() != ("External")
    blocked = tmp_path / "file"
    blocked.write_text("a file where the cache folder should be")
    monkeypatch.setattr(native, "_compiler", lambda: shutil.which("cc") or "cc")
    monkeypatch.setenv("SYNTH_CACHE", str(blocked / "synth"))
    assert model(
        "offset_slider_crank", frozenset(), "kinematics", monkeypatch, True
    ).fn.fn.class_name() != ("External")


def test_any_number_of_points_goes_through_the_same_few_slots():
    """A compiled function evaluated at any number of points (curves, screens, roots) keeps
    slots of the fixed widths alone (the powers of two up to 64), and each point's numbers
    are its own call's, to the bit."""
    x, p = ca.SX.sym("x", 2), ca.SX.sym("p", 3)
    out = ca.vertcat(ca.sin(x[0]) * p[0] + x[1] / p[1], ca.exp(p[2] * x[0]))
    fn = ca.Function("f", [x, p], [out])
    mapped = Mapped(fn, (False, True))
    rng = np.random.default_rng(0)
    params = rng.uniform(0.5, 2.0, 3)
    for n in [*rng.integers(1, 3000, 40), 1, 16, 17, 64, 65, 4097]:
        points = rng.uniform(-3, 3, (int(n), 2))
        got = mapped(points, params)
        one = np.hstack([fn(q, params).full() for q in points[:: max(1, int(n) // 7)]])
        assert got.shape == (2, n) and np.array_equal(got[:, :: max(1, int(n) // 7)], one)
    assert set(mapped.slots) <= POWERS


def test_a_searched_objective_screens_through_the_same_few_slots():
    """The motion search's screen projects its points in shrinking sets: through the same
    fixed-width slots too, whatever the request."""
    for tr in (1.3, 1.7, 2.2):
        types = ["offset_slider_crank", "crank_shaper"]
        synth.synthesize(tr, 300.0, 10.0, mechanisms=types, objective="uniform_cutting_speed")
    widths = screen.slot_widths()
    assert widths and widths <= POWERS
