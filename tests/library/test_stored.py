"""Compiled functions found by what defines them (synth.numerics.stored, as the analysis's root
polish is): loaded from the cache without being built again, one gives the numbers of the
function built on CasADi's virtual machine, to the bit; and what defines it is its key."""

from __future__ import annotations

import shutil

import casadi as ca
import numpy as np
import pytest

from synth.numerics import stored

pytestmark = pytest.mark.skipif(shutil.which("cc") is None, reason="no C compiler")


STEPS = 8


def newton(name: str, row: ca.Function, steps: int) -> ca.Function:
    """Newton's steps on the row's root, unrolled (as the analysis's polish is)."""
    x = x0 = ca.SX.sym("x0")
    pv, w = row.sx_in(1), row.sx_in(2)
    for _ in range(steps):
        fx, dfx = row(x, pv, w)
        x = x - fx / dfx
    return ca.Function(name, [x0, pv, w], [x], {"cse": True})


def row() -> ca.Function:
    th, pv, w = ca.SX.sym("theta"), ca.SX.sym("p", 2), ca.SX.sym("w", 2)
    d = ca.vertcat(ca.sin(th) - pv[0], ca.cos(2 * th) * pv[1] - 0.1)
    d1 = ca.jacobian(d, th)
    return ca.Function("row", [th, pv, w], [ca.dot(w, d), ca.dot(w, d1)])


def test_a_stored_function_is_built_once_and_gives_the_built_ones_numbers(monkeypatch, tmp_path):
    monkeypatch.setenv("SYNTH_CACHE", str(tmp_path))
    builds = []

    def counted(name: str, r: ca.Function, steps: int) -> ca.Function:
        builds.append(steps)
        return newton(name, r, steps)

    first = stored.compiled("newton_test", [row(), STEPS], counted)
    again = stored.compiled("newton_test", [row(), STEPS], counted)
    assert first.class_name() == again.class_name() == "External" and builds == [STEPS]
    vm = newton("newton_test", row(), STEPS)
    rng = np.random.default_rng(7)
    for _ in range(50):
        args = [rng.uniform(0, 1), rng.uniform(0, 1, 2), np.eye(2)[rng.integers(2)]]
        np.testing.assert_array_equal(np.asarray(again(*args)), np.asarray(vm(*args)))
    other = stored.compiled("newton_test", [row(), STEPS + 1], counted)
    assert builds == [STEPS, STEPS + 1] and other.class_name() == "External"
    assert len(list(tmp_path.glob("newton_test_*.so"))) == 2


def test_without_native_code_the_function_itself(monkeypatch):
    monkeypatch.setenv("SYNTH_NATIVE", "0")
    fn = stored.compiled("newton_test", [row(), STEPS], newton)
    assert fn.class_name() != "External"
