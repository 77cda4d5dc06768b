"""The analysis's compiled functions (synth.numerics.native) against CasADi's virtual machine:
the same numbers to the bit, for every type and structural variant, and the virtual machine wherever
no library can be built."""

from __future__ import annotations

import itertools
import math
import shutil

import numpy as np
import pytest

from synth.analysis.model import GRID, KINDS, Model
from synth.mechanisms import all_types, get
from synth.numerics.native import FLAGS

from ..support.designs import random_designs

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
