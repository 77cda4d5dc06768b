"""The compiled enclosures (synth.numerics.compiled_interval) against the functions and against
numpy's (synth.numerics.interval), on test_interval's expressions, boxes and checks: every
value CasADi computes and the exact value lie within them; they agree with numpy's, flags to
the bit and bounds to the bit where only + − × ÷ √ and comparisons are used (C rounds those
as numpy does), else within ``AGREE`` REL of the enclosure's magnitude (glibc's exp, log,
tan, … differ from numpy's by an ulp here and there; a bound moves by that ulp, REL|y| wide
alike, then by what the later steps make of it: ≤ 3 REL measured on the motion rows); the
known enclosures, shapes and orders of convergence are test_interval's own tests, run on the
compiled classes; and the checks catch a mutant of the C."""

from __future__ import annotations

import os
import shutil
from collections.abc import Callable, Iterator

import casadi as ca
import numpy as np
import pytest

from synth.numerics import compiled_interval
from synth.numerics.compiled_interval import CompiledCentred, CompiledInterval
from synth.numerics.interval import REL, Centred, Interval

from . import test_interval as reference
from .test_interval import (
    EXPRESSIONS,
    about,
    boxes,
    inexact,
    motion,
    split,
    two,
    violations,
)

AGREE = 16  # REL of the enclosure's magnitude max(|lo|, |hi|) that two bounds may differ by
EXACT = ("arithmetic", "comparisons")  # no libm function: the same bits
# where no C compiler builds a library, the classes are numpy's: nothing of their own to test
compiler = pytest.mark.skipif(
    shutil.which(os.environ.get("CC", "cc")) is None, reason="no C compiler: numpy runs"
)


@pytest.fixture(autouse=True, scope="module")
def cache(tmp_path_factory: pytest.TempPathFactory) -> Iterator[None]:
    """One cache for the module's libraries, built here (not the user's)."""
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("SYNTH_CACHE", str(tmp_path_factory.mktemp("cache")))
        mp.setenv("SYNTH_NATIVE", "1")
        yield


def disagreements(
    fn: ca.Function,
    compiled: Callable,
    numpy: Callable,
    lo: np.ndarray,
    hi: np.ndarray,
    exact: bool,
) -> list[str]:
    """Where the compiled enclosure's flags differ from numpy's, or its bounds by more than
    ``AGREE`` REL of the enclosure's magnitude (``exact``: at all)."""
    a, b = (f(split(fn, lo), split(fn, hi)) for f in (compiled, numpy))
    flags = ("partial", "branched", "jumps")
    found = [f for f in flags if not np.array_equal(getattr(a, f)[0], getattr(b, f)[0])]
    scale = np.maximum(np.abs(b.lo[0]), np.abs(b.hi[0]))
    for name in ("lo", "hi"):
        x, y = getattr(a, name)[0], getattr(b, name)[0]
        with np.errstate(invalid="ignore"):
            ok = (x == y) | (np.isnan(x) & np.isnan(y))
            if not exact:
                ok |= np.abs(x - y) <= AGREE * REL * scale
        found += [f"{name} {x[j]} vs numpy's {y[j]}" for j in zip(*np.nonzero(~ok), strict=True)]
    return found[:5]


@compiler
@pytest.mark.parametrize("name", EXPRESSIONS)
@pytest.mark.parametrize("form", ["naive", "centred"])
def test_hand_written_expressions_are_enclosed_as_numpy_encloses_them(name: str, form: str):
    expr, *region = EXPRESSIONS[name]
    fn = two(expr)
    joined = name not in ("comparisons", "if_else")
    if form == "naive":
        compiled, numpy = CompiledInterval(fn), Interval(fn)
    else:
        compiled, numpy = CompiledCentred(fn, continuous=joined), Centred(fn, continuous=joined)
    assert compiled.library is not None
    rng = np.random.default_rng(sum(map(ord, name)))
    lo, hi = boxes(region, 300, rng)
    assert not violations(fn, compiled, lo, hi, rng)
    assert not inexact(fn, compiled, lo[:40], hi[:40], rng)
    lo, hi = boxes(region, 3000, rng)
    assert not disagreements(fn, compiled, numpy, lo, hi, name in EXACT)


@compiler
@pytest.mark.parametrize("mtype", ["offset_slider_crank", "crank_rocker_slider"])
@pytest.mark.parametrize("form", ["naive", "centred"])
def test_the_motion_rows_of_two_types_are_enclosed_as_numpy_encloses_them(mtype: str, form: str):
    fn, p = motion(mtype)
    if form == "naive":
        compiled, numpy = CompiledInterval(fn), Interval(fn)
    else:
        compiled, numpy = CompiledCentred(fn, continuous=True), Centred(fn, continuous=True)
    assert compiled.library is not None
    rng = np.random.default_rng(7)
    lo, hi = about(p, 1000, rng)
    assert not violations(fn, compiled, lo[:300], hi[:300], rng, extra=30)
    assert not inexact(fn, compiled, lo[:6], hi[:6], rng, extra=1)
    assert not disagreements(fn, compiled, numpy, lo, hi, exact=False)


@compiler
@pytest.mark.parametrize(
    "test",
    [
        "test_known_enclosures",
        "test_shapes_and_errors",
        "test_the_excess_shrinks_like_h_naive_and_h_squared_centred",
    ],
)
def test_interval_tests_pass_compiled(test: str, monkeypatch: pytest.MonkeyPatch):
    """test_interval's tests of exact enclosures, flags, shapes (θ shared by the boxes), errors
    and the orders of convergence (h naive, h² centred), with the compiled classes."""
    monkeypatch.setattr(reference, "Interval", CompiledInterval)
    monkeypatch.setattr(reference, "Centred", CompiledCentred)
    getattr(reference, test)()


@compiler
def test_outputs_inputs_and_wrt_as_numpy():
    """Two outputs, one sparse, an input of two nonzeros, bounds given once for every box or
    a lower bound shared by boxes with their own upper ones, wrt any inputs or none: the
    same bits as numpy's (+ − × ÷ √ only)."""
    x, y = ca.SX.sym("x", 2), ca.SX.sym("y")
    sparse = ca.SX(3, 2)
    sparse[0, 0], sparse[2, 1] = x[0] * y, x[1] / y + x[0] * x[0] * x[0]
    fn = ca.Function("g", [x, y], [sparse, ca.vertcat(x[0] - x[1], ca.sqrt(y))])
    boxes = [
        ([[[0.1, 0.2], [-1, 0.5]], [[-0.5], [0.3]]], [[[0.2, 0.4], [1, 0.6]], [[0.5], [0.4]]]),
        ([[[0.1, 0.2], [-1, 0.5]], [[0.3]]], [[[0.2, 0.4], [1, 0.6]], [[0.4], [0.5]]]),
        ([[0.1, 0.2], [0.3]], [[0.2, 0.4], [0.3]]),
    ]
    pairs = [(CompiledInterval(fn), Interval(fn))] + [
        (CompiledCentred(fn, wrt), Centred(fn, wrt)) for wrt in (None, [0], [1], [])
    ]
    for compiled, numpy in pairs:
        assert compiled.library is not None
        for lo, hi in boxes:
            a, b = compiled(lo, hi), numpy(lo, hi)
            for name in ("lo", "hi", "partial", "branched", "jumps"):
                for u, v in zip(getattr(a, name), getattr(b, name), strict=True):
                    assert np.array_equal(u, v), (name, u, v)


def test_without_a_library_numpy_runs(monkeypatch: pytest.MonkeyPatch, tmp_path):
    fn, p = motion("offset_slider_crank")
    lo, hi = [[[0.1]], p * 0.99], [[[0.2]], p * 1.01]
    want = Interval(fn)(lo, hi)
    monkeypatch.setenv("SYNTH_NATIVE", "0")
    off = CompiledInterval(fn)
    blocked = tmp_path / "file"
    blocked.write_text("a file where the cache folder should be")
    monkeypatch.setenv("SYNTH_NATIVE", "1")
    monkeypatch.setenv("SYNTH_CACHE", str(blocked / "synth"))
    unwritable = CompiledInterval(fn)
    for ev in (off, unwritable):
        assert ev.library is None
        got = ev(lo, hi)
        for name in ("lo", "hi", "partial", "branched", "jumps"):
            assert np.array_equal(getattr(got, name)[0], getattr(want, name)[0])


# the C's own mutants: no ulp outwards after + − × ÷ √, no margin on libm's results, no
# peaks of sin and cos
CROSSES = "S int crosses(P x, double phase, double period) {"
MUTANTS = {
    "round_out": ("return pair(dn(y.l), up(y.h));", "return y;"),
    "widen": ("S P widen(P y) {", "S P widen(P y) { return y;"),
    "crosses": (CROSSES, CROSSES + " return 0;"),
}


@compiler
@pytest.mark.parametrize("mutant", MUTANTS)
def test_the_checks_catch_a_mutant_of_the_c(mutant: str, monkeypatch: pytest.MonkeyPatch):
    old, new = MUTANTS[mutant]
    assert old in compiled_interval.PRELUDE
    monkeypatch.setattr(compiled_interval, "PRELUDE", compiled_interval.PRELUDE.replace(old, new))
    rng = np.random.default_rng(3)
    found = []
    for name in ("arithmetic", "roots and logs", "trigonometry", "atan2"):
        expr, *region = EXPRESSIONS[name]
        fn = two(expr)
        ev = CompiledInterval(fn)
        assert ev.library is not None
        lo, hi = boxes(region, 200, rng)
        found += violations(fn, ev, lo, hi, rng)
        found += inexact(fn, ev, lo[:50], hi[:50], rng)
    assert found
