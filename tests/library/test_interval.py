"""Interval enclosures (synth.numerics.interval) against the functions themselves: over random
boxes (some straddling 0, π/2, a branch cut, a domain's edge), every value CasADi computes at
the box's corners and at random points in it, and the exact value (mpmath, 120 bits) at a few
points, lie within the enclosure, for hand-written expressions that use every operation the
evaluator takes and for the analysis's motion rows of two mechanism types. The checks fail
without the outward rounding, the libm margin or the peaks of sin and cos (mutants below).
The enclosures' excess over the true range shrinks like h (naive) and h² (centred)."""

from __future__ import annotations

import math
from collections.abc import Callable

import casadi as ca
import mpmath as mp
import numpy as np
import pytest

from synth.mechanisms import get
from synth.numerics import interval
from synth.numerics.interval import OP_NAMES, PI_UP, SUPPORTED, Centred, Interval

X, Y = ca.SX.sym("x"), ca.SX.sym("y")
RANDOM = 40  # random points per box, besides its corners
# name: (expression of x and y, the region the boxes' centres are drawn from)
EXPRESSIONS: dict[str, tuple[ca.SX, tuple[float, float], tuple[float, float]]] = {
    "arithmetic": (
        (X + Y) * (X - Y) - X / (Y - 0.25) + 2 * X - 1 / (X + 0.5) + X * X * Y + ca.fmax(-X, Y),
        (-2, 2),
        (-2, 2),
    ),
    "roots and logs": (ca.sqrt(X) + ca.log(Y) + ca.exp(X * Y), (-1, 4), (-0.5, 3)),
    "trigonometry": (ca.sin(X) * ca.cos(Y) + ca.tan(X / 3) - ca.sin(2 * Y), (-7, 7), (-7, 7)),
    "inverse trigonometry": (
        ca.asin(X) + ca.acos(Y) + ca.atan(X * Y),
        (-1.3, 1.3),
        (-1.3, 1.3),
    ),
    "atan2": (ca.atan2(Y, X), (-2, 2), (-2, 2)),
    "magnitudes": (
        ca.hypot(X, Y) + ca.fabs(X - Y) - ca.fmin(X, Y) * ca.fmax(X, 2 * Y),
        (-2, 2),
        (-2, 2),
    ),
    "powers": (X**Y + X**2.5 + X**-1.5 + X**101 / 50 + X**-101 / 1e6, (-0.5, 1.1), (-2, 2)),
    "comparisons": (
        (X < Y)
        + 2 * (X <= Y)
        + 4 * (X == Y)
        + 8 * (X != Y)
        + 16 * ca.logic_not(X < Y)
        + 32 * ca.logic_and(X < Y, Y < 0.5)
        + 64 * ca.logic_or(X < 0, Y < 0)
        + ca.sign(X),
        (-1, 1),
        (-1, 1),
    ),
    "if_else": (
        ca.if_else(X < Y, ca.sin(X), ca.cos(Y)) + ca.if_else(X > 0.5, X * Y, 0),
        (-2, 2),
        (-2, 2),
    ),
}
EXACT: dict[int, Callable[..., object]] = {
    ca.OP_ADD: lambda a, b: a + b,
    ca.OP_SUB: lambda a, b: a - b,
    ca.OP_MUL: lambda a, b: a * b,
    ca.OP_DIV: lambda a, b: a / b,
    ca.OP_NEG: lambda a: -a,
    ca.OP_TWICE: lambda a: 2 * a,
    ca.OP_INV: lambda a: 1 / a,
    ca.OP_SQ: lambda a: a * a,
    ca.OP_SQRT: lambda a: mp.sqrt(a) if a >= 0 else mp.nan,
    ca.OP_EXP: mp.exp,
    ca.OP_LOG: lambda a: mp.log(a) if a > 0 else (-mp.inf if a == 0 else mp.nan),
    ca.OP_SIN: mp.sin,
    ca.OP_COS: mp.cos,
    ca.OP_TAN: mp.tan,
    ca.OP_ASIN: lambda a: mp.asin(a) if abs(a) <= 1 else mp.nan,
    ca.OP_ACOS: lambda a: mp.acos(a) if abs(a) <= 1 else mp.nan,
    ca.OP_ATAN: mp.atan,
    ca.OP_ATAN2: lambda a, b: mp.atan2(a, b),
    ca.OP_FABS: abs,
    ca.OP_FMIN: min,
    ca.OP_FMAX: max,
    ca.OP_HYPOT: mp.hypot,
    ca.OP_POW: lambda a, b: mp.power(a, b) if a > 0 or b == int(b) else mp.nan,
    ca.OP_CONSTPOW: lambda a, b: mp.power(a, b) if a > 0 or b == int(b) else mp.nan,
    ca.OP_LT: lambda a, b: mp.mpf(a < b),
    ca.OP_LE: lambda a, b: mp.mpf(a <= b),
    ca.OP_EQ: lambda a, b: mp.mpf(a == b),
    ca.OP_NE: lambda a, b: mp.mpf(a != b),
    ca.OP_NOT: lambda a: mp.mpf(a == 0),
    ca.OP_AND: lambda a, b: mp.mpf(a != 0 and b != 0),
    ca.OP_OR: lambda a, b: mp.mpf(a != 0 or b != 0),
    ca.OP_SIGN: mp.sign,
    ca.OP_IF_ELSE_ZERO: lambda c, a: a if c != 0 else mp.mpf(0),
}


def exact(fn: ca.Function, point: np.ndarray) -> list[mp.mpf]:
    """fn's output nonzeros at a point (its inputs' nonzeros, concatenated), in 120-bit
    arithmetic from its instruction list (NaN where an argument leaves a domain)."""
    offsets = np.cumsum([0] + [fn.nnz_in(i) for i in range(fn.n_in())])
    w: dict[int, object] = {}
    out = [mp.nan] * fn.nnz_out(0)
    with mp.workprec(120):
        for k in range(fn.n_instructions()):
            op, ins, o = fn.instruction_id(k), fn.instruction_input(k), fn.instruction_output(k)
            if op == ca.OP_INPUT:
                w[o[0]] = mp.mpf(float(point[offsets[ins[0]] + ins[1]]))
            elif op == ca.OP_CONST:
                w[o[0]] = mp.mpf(fn.instruction_constant(k))
            elif op == ca.OP_OUTPUT:
                out[o[1]] = w[ins[0]]
            else:
                args = [w[i] for i in ins]
                nan = any(mp.isnan(a) for a in args) and op != ca.OP_IF_ELSE_ZERO
                try:
                    w[o[0]] = mp.nan if nan else EXACT[op](*args)
                except ZeroDivisionError:
                    w[o[0]] = mp.nan
    return out


def two(expr: ca.SX) -> ca.Function:
    return ca.Function("f", [X, Y], [expr])


def motion(mtype: str) -> tuple[ca.Function, np.ndarray]:
    """The motion model's rows, s′ and s″ (``Model``, kind "motion"), and s, as a function
    of (θ, parameters), with a design of the type."""
    m = get(mtype)
    th, pv = ca.SX.sym("theta"), ca.SX.sym("p", len(m.parameters))
    s = m.position({q.name: pv[i] for i, q in enumerate(m.parameters)}, th)
    s1 = ca.jacobian(s, th)
    rows = ca.vertcat(s, s1, ca.jacobian(s1, th))
    design = {
        "offset_slider_crank": {"crank": 134.5, "coupler": 230.6, "offset": 77.6},
        "crank_rocker_slider": {
            "ground": 5.0,
            "crank": 1.0,
            "coupler": 4.5,
            "rocker": 3.0,
            "rocker_arm": 4.0,
            "connecting_rod": 6.0,
        },
    }[mtype]
    p = m.complete(design)
    return ca.Function(mtype, [th, pv], [rows], {"cse": True}), np.array(list(p.values()))


def split(fn: ca.Function, a: np.ndarray) -> list[np.ndarray]:
    """Columns of ``a`` (boxes, all inputs' nonzeros) as each input's (boxes, nonzeros)."""
    cuts = np.cumsum([fn.nnz_in(i) for i in range(fn.n_in())])[:-1]
    return np.split(a, cuts, axis=1)


def points(lo: np.ndarray, hi: np.ndarray, rng: np.random.Generator, extra: int) -> np.ndarray:
    """Each box's corners and ``extra`` random points in it: (boxes, points, dimensions)."""
    d = lo.shape[1]
    corners = np.array(np.meshgrid(*[[0.0, 1.0]] * d, indexing="ij")).reshape(d, -1).T
    u = np.concatenate(
        [
            np.broadcast_to(corners, (len(lo), *corners.shape)),
            rng.uniform(0, 1, (len(lo), extra, d)),
        ],
        axis=1,
    )
    return np.clip(lo[:, None] + (hi - lo)[:, None] * u, lo[:, None], hi[:, None])


def violations(
    fn: ca.Function,
    enclose: Callable,
    lo: np.ndarray,
    hi: np.ndarray,
    rng: np.random.Generator,
    extra: int = RANDOM,
) -> list[str]:
    """Where CasADi's values at the boxes' sample points leave their enclosures (a NaN: where
    the box is not marked ``partial``)."""
    e = enclose(split(fn, lo), split(fn, hi))
    pts = points(lo, hi, rng, extra)
    n, k, d = pts.shape
    flat = pts.reshape(-1, d)
    vals = np.array(fn.map(n * k)(*[c.T for c in split(fn, flat)])).T.reshape(n, k, -1)
    low, high, partial = e.lo[0][:, None], e.hi[0][:, None], e.partial[0][:, None]
    bad = np.where(np.isnan(vals), ~partial, ~((low <= vals) & (vals <= high)))
    return [
        f"box {lo[b]}..{hi[b]}: {vals[b, j]} outside {e.lo[0][b]}..{e.hi[0][b]}"
        for b, j in zip(*np.nonzero(bad.any(axis=2)), strict=True)
    ][:5]


def inexact(
    fn: ca.Function,
    enclose: Callable,
    lo: np.ndarray,
    hi: np.ndarray,
    rng: np.random.Generator,
    extra: int = 2,
) -> list[str]:
    """Where the exact value at a box's sample point leaves its enclosure."""
    e = enclose(split(fn, lo), split(fn, hi))
    found = []
    for b, pts in enumerate(points(lo, hi, rng, extra)):
        for p in pts[:: max(1, len(pts) // 6)]:
            for j, v in enumerate(exact(fn, p)):
                if not mp.isnan(v) and not e.lo[0][b, j] <= v <= e.hi[0][b, j]:
                    found.append(f"at {p}: {v} outside {e.lo[0][b, j]}..{e.hi[0][b, j]}")
    return found[:5]


def boxes(region: list[tuple[float, float]], n: int, rng: np.random.Generator) -> tuple:
    """Boxes with centres in the region and half-widths from 1e-9 to 1, a quarter of them
    points; in a fifth of the coordinates a landmark (0, ±π/2, π, ±1: a peak, a branch cut, a
    domain's edge) on an edge of the box or inside it."""
    a, b = np.array(region).T
    c = rng.uniform(a, b, (n, len(a)))
    r = 10 ** rng.uniform(-9, 0, (n, len(a)))
    r[: n // 4] = 0.0
    marks = np.array([0.0, math.pi / 2, -math.pi / 2, math.pi, 1.0, -1.0])
    near = rng.choice(marks, (n, len(a))) + r * rng.choice([-1.0, 1.0, 0.3], (n, len(a)))
    c = np.where(rng.uniform(size=(n, len(a))) < 0.2, near, c)
    return c - r, c + r


@pytest.mark.parametrize("name", EXPRESSIONS)
@pytest.mark.parametrize("form", ["naive", "centred"])
def test_hand_written_expressions_are_enclosed(name: str, form: str) -> None:
    expr, *region = EXPRESSIONS[name]
    fn = two(expr)
    # the caller's word that if_else joins its branches holds where there is none; atan2 and
    # sign still jump
    joined = name not in ("comparisons", "if_else")
    enclose = Interval(fn) if form == "naive" else Centred(fn, continuous=joined)
    rng = np.random.default_rng(sum(map(ord, name)))
    lo, hi = boxes(region, 300, rng)
    assert not violations(fn, enclose, lo, hi, rng)
    assert not inexact(fn, enclose, lo[:40], hi[:40], rng)


def test_the_expressions_use_every_supported_operation() -> None:
    fns = [two(e) for e, *_ in EXPRESSIONS.values()]
    used = {f.instruction_id(k) for f in fns for k in range(f.n_instructions())}
    assert not {OP_NAMES[o] for o in SUPPORTED - used}


@pytest.mark.parametrize("mtype", ["offset_slider_crank", "crank_rocker_slider"])
@pytest.mark.parametrize("form", ["naive", "centred"])
def test_the_motion_rows_of_two_types_are_enclosed(mtype: str, form: str) -> None:
    fn, p = motion(mtype)
    enclose = Interval(fn) if form == "naive" else Centred(fn, continuous=True)
    rng = np.random.default_rng(7)
    lo, hi = about(p, 300, rng)
    assert not violations(fn, enclose, lo, hi, rng, extra=30)
    assert not inexact(fn, enclose, lo[:6], hi[:6], rng, extra=1)


def about(p: np.ndarray, n: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """n boxes of (θ, parameters) about a design ``p``: θ anywhere on the turn, within
    1e-8 to 0.3 rad; each parameter within 1% of the design's, within 1e-8 to 1e-2 of it."""
    c = np.concatenate(
        [rng.uniform(0, 2 * np.pi, (n, 1)), p * (1 + 0.01 * rng.normal(size=(n, len(p))))], 1
    )
    r = np.concatenate(
        [10 ** rng.uniform(-8, -0.5, (n, 1)), np.abs(c[:, 1:]) * 10 ** rng.uniform(-8, -2, (n, 1))],
        1,
    )
    return c - r, c + r


def test_known_enclosures() -> None:
    cases = [
        (ca.sin(X), (1.0, 2.0), lambda lo, hi: hi == 1.0 and lo <= math.sin(1.0)),
        (ca.cos(X), (-0.1, 3.5), lambda lo, hi: lo == -1.0 and hi == 1.0),
        (X * X, (-1.0, 2.0), lambda lo, hi: lo == 0.0 and 4.0 <= hi <= 4.0 + 1e-15),
        (ca.fabs(X), (-3.0, 2.0), lambda lo, hi: lo == 0.0 and hi == 3.0),
        (1 / X, (-1.0, 2.0), lambda lo, hi: lo == -math.inf and hi == math.inf),
        (ca.atan2(X, -1.0), (-1e-9, 1e-9), lambda lo, hi: lo == -PI_UP and hi == PI_UP),
        (ca.sqrt(X), (-1.0, 4.0), lambda lo, hi: lo == 0.0 and 2.0 <= hi <= 2.0 + 1e-15),
        (ca.tan(X), (1.0, 2.0), lambda lo, hi: lo == -math.inf and hi == math.inf),
        # the float just below the pole π/2 + 22π, where (x − π/2)/π rounds to above 22
        (ca.tan(X), (70.68583470577035, 71.0), lambda lo, hi: lo == -math.inf and hi == math.inf),
        (1 / X, (-0.0, 1.0), lambda lo, hi: lo == -math.inf and hi == math.inf),  # 1/−0 = −∞
    ]
    for expr, (a, b), ok in cases:
        e = Interval(two(expr))([[a], [0.0]], [[b], [0.0]])
        assert ok(e.lo[0][0, 0], e.hi[0][0, 0]), (expr, e)
    e = Interval(two(ca.sqrt(X) + ca.acos(Y)))([[-1.0], [0.5]], [[1.0], [2.0]])
    assert e.partial[0][0, 0] and np.isfinite([e.lo[0], e.hi[0]]).all()
    e = Interval(two(ca.if_else(X < Y, X, Y)))([[0.0], [2.0]], [[1.0], [3.0]])
    assert (e.lo[0][0, 0], e.hi[0][0, 0], e.branched[0][0, 0]) == (0.0, 1.0, False)
    e = Interval(two(ca.vertcat(X == Y, X != Y, X < Y)))([[1.0], [1.0]], [[1.0], [1.5]])
    assert e.lo[0].tolist() == [[0.0, 0.0, 0.0]] and e.hi[0].tolist() == [[1.0, 1.0, 1.0]]
    assert e.branched[0].all()
    e = Interval(two(ca.vertcat(ca.atan2(Y, X), ca.sign(X))))([[-1.0], [0.0]], [[1.0], [1.0]])
    assert e.jumps[0].tolist() == [[True, True]] and not e.branched[0].any()
    e = Interval(two(ca.vertcat(X == Y, X != Y)))([[2.0], [2.0]], [[2.0], [2.0]])
    assert e.lo[0].tolist() == e.hi[0].tolist() == [[1.0, 0.0]] and not e.branched[0].any()


def test_shapes_and_errors() -> None:
    fn, p = motion("offset_slider_crank")
    e = Interval(fn)([[[0.1]], p * 0.99], [[[0.2]], np.stack([p * 1.01] * 5)])  # θ shared
    assert e.lo[0].shape == (5, 3) and (e.lo[0] <= e.hi[0]).all()
    with pytest.raises(ValueError, match="lower bound above"):
        Interval(fn)([[0.2], p], [[0.1], p])
    with pytest.raises(NotImplementedError, match="OP_FMOD"):
        Interval(two(ca.fmod(X, Y)))


def convergence(
    enclose: Callable, fn: ca.Function, centre: np.ndarray, scale: np.ndarray, fixed: int = 0
) -> list[float]:
    """The measured orders of the enclosure's excess over the true range (the corners' and a
    grid's, exact for a box on which the function is monotone) as h: 1e-2 → 1e-3 → 1e-4."""
    excess = []
    for h in (1e-2, 1e-3, 1e-4):
        r = scale * h
        r[:fixed] = 0.0
        lo, hi = centre - r, centre + r
        e = enclose(split(fn, lo[None]), split(fn, hi[None]))
        grid = points(lo[None], hi[None], np.random.default_rng(0), 400)[0]
        vals = np.array(fn.map(len(grid))(*[c.T for c in split(fn, grid)]))[-1]
        excess.append(float(e.hi[0][0, -1] - e.lo[0][0, -1] - np.ptp(vals)))
    return [math.log10(excess[i] / excess[i + 1]) for i in range(2)]


def test_the_excess_shrinks_like_h_naive_and_h_squared_centred() -> None:
    fn = two(X * Y - X * X + ca.sin(X) * ca.cos(Y) + Y / (1 + X * X))
    centre, scale = np.array([0.7, -0.4]), np.ones(2)
    assert all(0.8 < q < 1.2 for q in convergence(Interval(fn), fn, centre, scale))
    assert all(1.8 < q < 2.2 for q in convergence(Centred(fn), fn, centre, scale))
    # the slider's acceleration at a fixed crank angle over boxes of the parameters
    acc, p = motion("offset_slider_crank")
    centre, scale = np.concatenate([[2.0], p]), np.concatenate([[0.0], p])
    assert all(0.8 < q < 1.2 for q in convergence(Interval(acc), acc, centre, scale, 1))
    centred = Centred(acc, wrt=[1], continuous=True)
    assert all(1.8 < q < 2.2 for q in convergence(centred, acc, centre, scale, 1))


MUTANTS = {
    "round_out": lambda y: y,  # no ulp outwards after + − × ÷ √
    "widen": lambda y: y,  # no margin on libm's results
    "crosses": lambda x, phase, period: np.zeros(x.shape[1:], bool),  # no peaks of sin, cos
}


@pytest.mark.parametrize("mutant", MUTANTS)
def test_the_checks_catch_a_mutant(mutant: str, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(interval, mutant, MUTANTS[mutant])
    rng = np.random.default_rng(3)
    found = []
    for name in ("arithmetic", "roots and logs", "trigonometry", "atan2"):
        expr, *region = EXPRESSIONS[name]
        fn = two(expr)
        lo, hi = boxes(region, 200, rng)
        found += violations(fn, Interval(fn), lo, hi, rng)
        found += inexact(fn, Interval(fn), lo[:50], hi[:50], rng)
    assert found


@pytest.mark.parametrize("compiled", [False, True])
def test_a_branch_undecided_over_the_box_keeps_the_centred_form_tight(compiled: bool) -> None:
    """f = (1 − w)(x > 0 ? u (1 + x) : u + u x) − u (1 − x), two formulas of one quantity
    weighed, less a third (as s − level is): over x ∈ ±1e-9 (the branch undecided), u ∈ [1,
    2] and w = 0, f = 2 u x is within ±4e-9. The naive enclosure is [−1, 1] (u repeats); the
    centred form is as tight as f where the Jacobian's branches stay paired (reverse mode
    sends the weight down each branch over [0, 1] apart: ∂f/∂u ∈ [−1, 1], f within ±0.5)."""
    x, u, w = ca.SX.sym("x"), ca.SX.sym("u"), ca.SX.sym("w")
    f = (1 - w) * ca.if_else(x > 0, u * (1 + x), u + u * x) - u * (1 - x)
    fn = ca.Function("branched", [x, u, w], [f])
    if compiled:
        from synth.numerics.compiled_interval import CompiledCentred

        e = CompiledCentred(fn, continuous=True)([-1e-9, 1.0, 0.0], [1e-9, 2.0, 0.0])
    else:
        e = Centred(fn, continuous=True)([-1e-9, 1.0, 0.0], [1e-9, 2.0, 0.0])
    assert e.lo[0][0, 0] <= -2e-9 and e.hi[0][0, 0] >= 2e-9  # it holds f (x = ±1e-9, u = 1)
    assert e.hi[0][0, 0] - e.lo[0][0, 0] < 1e-7
