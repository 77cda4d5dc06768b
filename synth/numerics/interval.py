"""Rigorous enclosures of a CasADi SX function over boxes of its inputs, many boxes at once.

``Interval(fn)`` compiles ``fn``'s instructions once into numpy steps on pairs (row 0 the lower
bounds, row 1 the upper, a column per box): N boxes cost one vectorised step per instruction.
Each step encloses the exact real result of its operation over its operands' intervals, so the
outputs hold every value the function takes over a box, and what CasADi computes at any point
of it in floating point (each of its operations is within the rounding its step allows for).

- + − × ÷ √ are correctly rounded (IEEE 754): one ulp outwards holds the exact result
  (``round_out``); a product's or quotient's bounds are its four corners' extremes.
- exp, log, sin, cos, atan2, pow, … come from numpy's libm, not correctly rounded (measured
  ≤ 1.2 ulp): the result is widened by ``REL`` |y| (≥ 64 ulp) and ``TINY`` (``widen``).
- A monotone function maps the ends; sin and cos also reach ±1 where the interval may hold a
  peak (``crosses``: its slack only ever admits one); tan is (−∞, ∞) over a pole.
- x/y with 0 in y: (−∞, ∞); x², |x| over 0: lower bound 0. atan2 over a box that may touch
  its cut (x ≤ 0, y over 0): [−π, π]; elsewhere its corners' extremes (the angles of a convex
  set that holds neither the origin nor the cut form an arc whose ends are vertices).
- sqrt, log, asin, acos and a real power clip their argument to the domain: the bounds hold
  where the function is defined; ``partial`` marks a box where it is not everywhere (NaN; or,
  for x**y with y not a constant, x < 0, where C's pow takes an integral y).
- if_else(c, a, b) (CasADi's if_else_zero(c, a) + if_else_zero(!c, b)) is one step: a or b
  where c is decided over the box, else their hull; ``branched`` marks the undecided boxes,
  ``jumps`` those where atan2 may cross its cut or sign pass 0.

Naive interval arithmetic overestimates where a variable repeats (the dependency problem), by
O(h) on boxes of width h. ``Centred`` intersects it with the mean-value form
f(P) ⊆ f(c) + J(P)(P − c), J the Jacobian's enclosure by the same evaluator: excess O(h²).
J is built by forward differentiation (``symbolic.forward``), which keeps each if_else whole.
For a continuous f that is piecewise smooth on the box (Lipschitz there where J is finite),
Lebourg's mean-value theorem gives f(p) − f(c) ∈ ∂f([c, p])(p − c), and the generalised
gradient ∂f lies in J(P): the hull of the derivatives of the branches the box may take.
"""

from __future__ import annotations

import math
import sys
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, cast

import casadi as ca
import numpy as np
import numpy.typing as npt

from .symbolic import forward, sx_function

REL = 2.0**-46  # a libm result's relative margin: ≥ 64 ulp (numpy's measured: ≤ 1.2 ulp)
TINY = 64 * 2.0**-1074  # and its absolute margin: 64 subnormal steps, for |y| near 0
SLACK = 1e-14  # ``crosses``' slack per period and unit of |u| (its rounding: < 1e-15)
PI_UP = math.nextafter(math.pi, math.inf)  # π rounded up: [−PI_UP, PI_UP] holds every angle
TAU = 2 * math.pi
INF = math.inf

Pair = npt.NDArray[np.float64]  # (2, n): lower bounds, upper bounds, a column per box
Mask = npt.NDArray[np.bool_]
Step = Callable[..., Any]  # pairs in; a pair, or (pair, flag mask) for a flagged step
OUT = np.array([[-INF], [INF]])  # each row's outward direction; also "unbounded"
SIDE = np.array([[-1.0], [1.0]])
MAX = sys.float_info.max
LOW, HIGH = np.array([[-INF], [-MAX]]), np.array([[MAX], [INF]])  # a lower bound is not +∞
ZERO, ONE = np.zeros((2, 1)), np.ones((2, 1))
# what a step's mask marks: nothing, a domain left, a comparison undecided, a jump possible
PLAIN, PARTIAL, BRANCHED, JUMP = 0, 1, 2, 3


def round_out(y: Pair) -> Pair:
    """A correctly rounded pair moved one ulp outwards: it then holds the exact result."""
    return cast(Pair, np.nextafter(y, OUT))


def widen(y: Pair) -> Pair:
    """A libm pair widened by ``REL`` |y| + ``TINY``: it then holds the exact result (a
    finite one that overflowed: a lower bound of at most the largest float)."""
    return cast(Pair, np.clip(y + (np.minimum(np.abs(y), MAX) * REL + TINY) * SIDE, LOW, HIGH))


def crosses(x: Pair, phase: float, period: float) -> Mask:
    """Whether [lo, hi] may hold a point phase + k·period (NaN, ∞ or doubt: True). The
    computed u = (x − phase)/period is off by < 4 eps (|u| + 1); ``SLACK`` covers that."""
    u = (x - phase) / period
    slack = SLACK * (1.0 + np.abs(u[0]) + np.abs(u[1]))
    return cast(Mask, ~(np.floor(u[1] + slack) < u[0] - slack))


def _sane(r: Pair) -> Pair:  # NaN (0·∞, ∞/∞): unbounded on its side
    return np.where(r == r, r, OUT)


def _extremes(c: Pair) -> Pair:  # the least and greatest of (2, 2, n) corners, NaN aside
    c = c.reshape(4, -1)
    r = np.empty((2, c.shape[1]))
    np.fmin.reduce(c, 0, out=r[0])
    np.fmax.reduce(c, 0, out=r[1])
    return r


def _mul(x: Pair, y: Pair) -> Pair:
    return _sane(round_out(_extremes(x[:, None] * y[None, :])))


def _div(x: Pair, y: Pair) -> tuple[Pair, Mask]:
    zero = (y[0] <= 0) & (y[1] >= 0)
    return np.where(zero, OUT, _sane(round_out(_extremes(x[:, None] / y[None, :])))), zero


def _abs(x: Pair) -> Pair:
    a = x * -SIDE  # (x0, −x1): |x| ≥ both and ≥ 0, and ≤ −(the lesser)
    return np.stack((np.maximum(a.max(0), 0.0), -a.min(0)))


def _sq(x: Pair) -> Pair:
    m = _abs(x)
    return np.maximum(round_out(m * m), 0.0)


def _monotone(
    f: Callable[[Pair], Pair],
    exact: bool = False,
    domain: tuple[float, float] | None = None,
    span: tuple[float, float] = (-INF, INF),
    falling: bool = False,
) -> Step:
    """A monotone function's step: its argument clipped to ``domain`` (masked where it left
    it), the ends' images rounded out, within the function's ``span``."""
    lo, hi = domain or (-INF, INF)

    def step(x: Pair) -> Any:
        z = np.clip(x, lo, hi) if domain else x
        y = f(z[::-1] if falling else z)
        r = np.clip(round_out(y) if exact else widen(y), *span)
        return (r, (x[0] < lo) | (x[1] > hi)) if domain else r

    return step


def _periodic(f: Callable[[Pair], Pair], peak: float) -> Step:
    """sin or cos (1 at ``peak``, −1 half a turn on): the ends' images, ±1 over a peak."""

    def step(x: Pair) -> Pair:
        y = f(x)
        r = widen(np.stack((np.minimum(y[0], y[1]), np.maximum(y[0], y[1]))))
        over = np.stack((crosses(x, peak + math.pi, TAU), crosses(x, peak, TAU)))
        return np.clip(np.where(over, SIDE, r), -1.0, 1.0)

    return step


def _tan(x: Pair) -> Pair:
    return np.where(crosses(x, math.pi / 2, math.pi), OUT, widen(np.tan(x)))


def _atan2(y: Pair, x: Pair) -> tuple[Pair, Mask]:  # masked where it may jump at its cut
    cut = (x[0] <= 0) & (y[0] <= 0) & (y[1] >= 0)
    r = np.where(cut, OUT, widen(_extremes(np.arctan2(y[:, None], x[None, :]))))
    return np.clip(r, -PI_UP, PI_UP), cut


def _power(c: float) -> tuple[Step, int]:
    """x**c for a constant c, and its step's mask: an integer power keeps the signs (even:
    of |x|; negative: 1/x**|c|), a real one takes x ≥ 0."""
    if not math.isfinite(c) or c != int(c):
        return _monotone(lambda x: np.power(x, c), domain=(0.0, INF), falling=c < 0), PARTIAL
    n = int(c)

    def grow(x: Pair) -> Pair:  # x**|n|, of |x| where n is even
        r = widen(np.power(_abs(x) if n % 2 == 0 else x, abs(n)))
        return np.maximum(r, 0.0) if n % 2 == 0 else r

    if n >= 0:
        return ((lambda x: ONE) if n == 0 else grow), PLAIN
    return (lambda x: _div(ONE, grow(x))), PARTIAL


def _pow(x: Pair, y: Pair) -> tuple[Pair, Mask]:
    """x**y = exp(y log x) for x ≥ 0 (masked where x < 0: C's pow takes an integral y
    there)."""
    lx, out = TABLE[ca.OP_LOG][0](x)
    return TABLE[ca.OP_EXP][0](_mul(y, lx)), out


def _nonzero(x: Pair) -> Mask:  # true over the whole box
    return cast(Mask, (x[0] > 0) | (x[1] < 0))


def _zero(x: Pair) -> Mask:
    return cast(Mask, (x[0] == 0) & (x[1] == 0))


def _truth(yes: Mask, no: Mask) -> tuple[Pair, Mask]:  # 1 decided true, 0 false, else [0, 1]
    return np.stack((yes, ~no)).astype(float), ~(yes | no)


def _equal(x: Pair, y: Pair) -> tuple[Mask, Mask]:  # x == y over the whole box; nowhere
    same = (x[0] == x[1]) & (y[0] == y[1]) & (x[0] == y[0])
    return same, (x[1] < y[0]) | (y[1] < x[0])


def _select(c: Pair, a: Pair, b: Pair) -> tuple[Pair, Mask]:
    """c ? a : b: a where c is nonzero over the box, b where it is 0, else their hull."""
    yes, no = _nonzero(c), _zero(c)
    hull = np.stack((np.minimum(a[0], b[0]), np.maximum(a[1], b[1])))
    return np.where(yes, a, np.where(no, b, hull)), ~(yes | no)


HALF_PI = PI_UP / 2
TABLE: dict[int, tuple[Step, int]] = {
    ca.OP_ADD: (lambda x, y: round_out(x + y), PLAIN),
    ca.OP_SUB: (lambda x, y: round_out(x - y[::-1]), PLAIN),
    ca.OP_MUL: (_mul, PLAIN),
    ca.OP_DIV: (_div, PARTIAL),
    ca.OP_INV: (lambda x: _div(ONE, x), PARTIAL),
    ca.OP_NEG: (lambda x: -x[::-1], PLAIN),
    ca.OP_TWICE: (lambda x: round_out(2.0 * x), PLAIN),  # out: where it overflows
    ca.OP_SQ: (_sq, PLAIN),
    ca.OP_FABS: (_abs, PLAIN),
    ca.OP_FMIN: (np.minimum, PLAIN),
    ca.OP_FMAX: (np.maximum, PLAIN),
    ca.OP_HYPOT: (lambda x, y: np.maximum(widen(np.hypot(_abs(x), _abs(y))), 0.0), PLAIN),
    ca.OP_SQRT: (_monotone(np.sqrt, True, (0.0, INF), (0.0, INF)), PARTIAL),
    ca.OP_EXP: (_monotone(np.exp, span=(0.0, INF)), PLAIN),
    ca.OP_LOG: (_monotone(np.log, domain=(0.0, INF)), PARTIAL),
    ca.OP_SIN: (_periodic(np.sin, math.pi / 2), PLAIN),
    ca.OP_COS: (_periodic(np.cos, 0.0), PLAIN),
    ca.OP_TAN: (_tan, PLAIN),
    ca.OP_ASIN: (_monotone(np.arcsin, False, (-1.0, 1.0), (-HALF_PI, HALF_PI)), PARTIAL),
    ca.OP_ACOS: (_monotone(np.arccos, False, (-1.0, 1.0), (0.0, PI_UP), True), PARTIAL),
    ca.OP_ATAN: (_monotone(np.arctan, span=(-HALF_PI, HALF_PI)), PLAIN),
    ca.OP_ATAN2: (_atan2, JUMP),
    ca.OP_POW: (_pow, PARTIAL),
    ca.OP_LT: (lambda x, y: _truth(x[1] < y[0], x[0] >= y[1]), BRANCHED),
    ca.OP_LE: (lambda x, y: _truth(x[1] <= y[0], x[0] > y[1]), BRANCHED),
    ca.OP_EQ: (lambda x, y: _truth(*_equal(x, y)), BRANCHED),
    ca.OP_NE: (lambda x, y: _truth(*_equal(x, y)[::-1]), BRANCHED),
    ca.OP_NOT: (lambda x: _truth(_zero(x), _nonzero(x)), BRANCHED),
    ca.OP_AND: (lambda x, y: _truth(_nonzero(x) & _nonzero(y), _zero(x) | _zero(y)), BRANCHED),
    ca.OP_OR: (lambda x, y: _truth(_nonzero(x) | _nonzero(y), _zero(x) & _zero(y)), BRANCHED),
    ca.OP_SIGN: (lambda x: (np.sign(x), (x[0] <= 0) & (x[1] >= 0) & (x[0] < x[1])), JUMP),
    ca.OP_IF_ELSE_ZERO: (lambda c, a: _select(c, a, ZERO), BRANCHED),
}
OP_NAMES = {getattr(ca, k): k for k in dir(ca) if k.startswith("OP_")}
SUPPORTED = frozenset({*TABLE, ca.OP_CONSTPOW, ca.OP_INPUT, ca.OP_OUTPUT, ca.OP_CONST})
Node = tuple[int, tuple[int, ...], Any]  # op, argument nodes, data (see ``graph``)


@dataclass(frozen=True)
class Enclosure:
    """Bounds per output, (boxes, nonzeros) each: every value over a box lies in [lo, hi]
    where the function is defined; ``partial``: an argument left its function's domain
    somewhere in the box; ``branched``: a comparison was undecided over it; ``jumps``: atan2
    may cross its cut there, or sign pass through 0."""

    lo: list[np.ndarray]
    hi: list[np.ndarray]
    partial: list[np.ndarray]
    branched: list[np.ndarray]
    jumps: list[np.ndarray]


class Interval:
    """``fn`` (built from SX, or MX that expands to SX) over boxes: a call takes each input's
    lower and upper bounds, (boxes, nonzeros) or broadcastable to it, and gives an
    ``Enclosure``. ``NotImplementedError`` at construction for an operation not enclosed."""

    def __init__(self, fn: ca.Function) -> None:
        self.fn = fn = sx_function(fn)
        self.nnz_in = [fn.nnz_in(i) for i in range(fn.n_in())]
        self.nnz_out = [fn.nnz_out(i) for i in range(fn.n_out())]
        nodes, outputs = graph(fn)
        live, kept = set(outputs.values()), set(outputs.values())
        for k in reversed(range(len(nodes))):
            if k in live:
                live.update(nodes[k][1])
        order = [k for k in range(len(nodes)) if k in live]
        self.inputs = [(k, nodes[k][2]) for k in order if nodes[k][0] == ca.OP_INPUT]
        const = [k for k in order if nodes[k][0] == ca.OP_CONST]
        self.constants = [(k, np.full((2, 1), float(nodes[k][2]))) for k in const]
        ops = [k for k in order if nodes[k][0] not in (ca.OP_INPUT, ca.OP_CONST)]
        last = {a: i for i, k in enumerate(ops) for a in nodes[k][1] if a not in kept}
        self.steps = [
            (k, *nodes[k][2], nodes[k][1], tuple(a for a in nodes[k][1] if last.get(a) == i))
            for i, k in enumerate(ops)
        ]
        flags = {k: f for k, _, f, _, _ in self.steps if f}
        flagged: dict[int, frozenset[int]] = {}  # each node's flagged ancestors, itself too
        for k in order:
            own = {k} if k in flags else set()
            flagged[k] = frozenset(own.union(*(flagged[a] for a in nodes[k][1])))

        def of(k: int) -> list[list[int]]:  # k's flagged ancestors of each kind
            return [[f for f in flagged[k] if flags[f] == kind] for kind in (1, 2, 3)]

        self.outputs = [(*o, k, of(k)) for o, k in outputs.items()]
        self.size = len(nodes)

    def __call__(self, lo: Sequence[npt.ArrayLike], hi: Sequence[npt.ArrayLike]) -> Enclosure:
        """The enclosure over each box: input i's bounds ``lo[i]``, ``hi[i]``."""
        boxes, n = bounds(lo, hi, self.nnz_in)
        w: list[Any] = [None] * self.size
        masks: dict[int, Mask] = {}
        for k, (i, nz) in self.inputs:
            w[k] = np.stack((boxes[i][0][:, nz], boxes[i][1][:, nz]))
        for k, c in self.constants:
            w[k] = c
        with np.errstate(all="ignore"):
            for k, f, flag, args, free in self.steps:
                r = f(*[w[a] for a in args])
                if flag:
                    r, masks[k] = r
                w[k] = r
                for a in free:
                    w[a] = None
        out = Enclosure(*([np.zeros((n, m), t) for m in self.nnz_out] for t in "dd???"))
        for i, nz, k, kinds in self.outputs:
            out.lo[i][:, nz], out.hi[i][:, nz] = w[k]
            for fl, into in zip(kinds, (out.partial, out.branched, out.jumps), strict=True):
                for f in fl:
                    into[i][:, nz] |= masks[f]
        return out


class Centred:
    """``Interval``'s enclosure intersected with the mean-value form in the inputs ``wrt``
    (all by default): f(P) ⊆ f(P', c) + J(P)(P − c), c the centre of those inputs' boxes, P'
    the others'. It needs f continuous on the box: it is used where every function is defined
    over the box, nothing jumps and no comparison is undecided, or also where one is if the
    caller vouches that each if_else of ``fn`` joins its branches continuously
    (``continuous``: as two formulas of one quantity do)."""

    def __init__(
        self, fn: ca.Function, wrt: Sequence[int] | None = None, continuous: bool = False
    ) -> None:
        fn = sx_function(fn)
        x, self.continuous = fn.sx_in(), continuous
        self.wrt = tuple(range(fn.n_in())) if wrt is None else tuple(wrt)
        y = fn.call(x)
        rows = ca.vertcat(*(e.nz[:] for e in y))
        cols = ca.vertcat(*(x[i].nz[:] for i in self.wrt))
        jac = ca.densify(forward(rows, cols))
        self.naive = Interval(fn)
        self.joint = Interval(ca.Function(f"{fn.name()}_centred", x, [*y, jac], {"cse": True}))
        self.m, self.k = rows.numel(), cols.numel()

    def __call__(self, lo: Sequence[npt.ArrayLike], hi: Sequence[npt.ArrayLike]) -> Enclosure:
        """The intersected enclosure over each box (as ``Interval``'s call)."""
        boxes, n = bounds(lo, hi, self.naive.nnz_in)
        mid = {i: np.clip(0.5 * boxes[i][0] + 0.5 * boxes[i][1], *boxes[i]) for i in self.wrt}
        both = self.joint([a for a, _ in boxes], [b for _, b in boxes])
        flags = (both.partial[:-1], both.branched[:-1], both.jumps[:-1])
        if self.k == 0:
            return Enclosure(both.lo[:-1], both.hi[:-1], *flags)
        at = self.naive(
            *zip(*((mid[i],) * 2 if i in mid else b for i, b in enumerate(boxes)), strict=True)
        )
        # P − c per differentiated nonzero, (2, n, 1, k): exact where 0, else rounded out
        d = np.concatenate([np.stack(boxes[i]) - mid[i] + np.zeros((n, 1)) for i in self.wrt], 2)
        jac = np.stack((both.lo[-1], both.hi[-1])).reshape(2, n, self.k, self.m).swapaxes(2, 3)
        form = np.stack([np.concatenate(v, axis=1) for v in (at.lo, at.hi)])  # f(P', c)
        with np.errstate(all="ignore"):
            d = np.where(d == 0, 0.0, np.nextafter(d, OUT[:, :, None]))[:, :, None]
            t = (jac[:, None] * d[None, :]).reshape(4, n, self.m, self.k)
            t = np.where(t == t, t, 0.0)  # 0·∞: a fixed input's term is 0
            terms = np.nextafter(np.stack((t.min(0), t.max(0))), OUT[:, :, None, None])
            for j in range(self.k):
                form = np.nextafter(form + terms[..., j], OUT[:, :, None])
        naive = [np.concatenate(v[:-1], 1) for v in (both.lo, both.hi, both.partial, both.jumps)]
        bad = naive[2] | naive[3] | np.any(both.partial[-1].reshape(n, self.k, self.m), axis=1)
        if not self.continuous:
            bad |= np.concatenate(both.branched[:-1], axis=1)
        bad |= ~np.isfinite(form).all(0)
        low = np.where(bad, naive[0], np.maximum(naive[0], form[0]))
        high = np.where(bad, naive[1], np.minimum(naive[1], form[1]))
        cuts = np.cumsum(self.naive.nnz_out)[:-1]
        return Enclosure(np.split(low, cuts, axis=1), np.split(high, cuts, axis=1), *flags)


def graph(fn: ca.Function) -> tuple[list[Node], dict[tuple[int, int], int]]:
    """``fn``'s instructions as single-assignment nodes (op, argument nodes, data: an input's
    (index, nonzero), a constant's value, else (step, mask kind)), patterns rewritten (x·x as
    x², if_else as one selection, a constant power), and each output nonzero's node."""
    nodes: list[Node] = []
    work: dict[int, int] = {}  # CasADi's work slot -> the node last written there
    outputs: dict[tuple[int, int], int] = {}
    for j in range(fn.n_instructions()):
        op, ins = fn.instruction_id(j), fn.instruction_input(j)
        if op == ca.OP_OUTPUT:
            i, nz = fn.instruction_output(j)
            outputs[(i, nz)] = work[ins[0]]
            continue
        if op == ca.OP_INPUT:
            node: Node = (op, (), tuple(ins))
        elif op == ca.OP_CONST:
            node = (op, (), fn.instruction_constant(j))
        elif op in SUPPORTED:
            node = _rewrite(nodes, op, tuple(work[w] for w in ins))
        else:
            raise NotImplementedError(
                f"interval: {fn.name()} uses {OP_NAMES.get(op, op)}, which has no enclosure "
                f"here; supported: {', '.join(sorted(OP_NAMES[o] for o in SUPPORTED))}"
            )
        nodes.append(node)
        work[fn.instruction_output(j)[0]] = len(nodes) - 1
    return nodes, outputs


def _rewrite(nodes: list[Node], op: int, args: tuple[int, ...]) -> Node:
    """One operation's node: its table step, or a tighter one for a pattern."""
    if op == ca.OP_MUL and args[0] == args[1]:
        return op, args[:1], (_sq, PLAIN)
    if op in (ca.OP_POW, ca.OP_CONSTPOW):
        if nodes[args[1]][0] == ca.OP_CONST:  # the exponent's node kept: compiled_interval reads it
            step, kind = _power(nodes[args[1]][2])
            return op, args, (lambda x, _: step(x), kind)
        return op, args, TABLE[ca.OP_POW]
    if op == ca.OP_ADD and nodes[args[0]][0] == nodes[args[1]][0] == ca.OP_IF_ELSE_ZERO:
        (c, a), (e, b) = nodes[args[0]][1], nodes[args[1]][1]
        if nodes[e][:2] == (ca.OP_NOT, (c,)):  # c ? a : b
            return op, (c, a, b), (_select, BRANCHED)
        if nodes[c][:2] == (ca.OP_NOT, (e,)):
            return op, (e, b, a), (_select, BRANCHED)
    return op, args, TABLE[op]


def bounds(
    lo: Sequence[npt.ArrayLike], hi: Sequence[npt.ArrayLike], nnz: list[int]
) -> tuple[list[tuple[np.ndarray, np.ndarray]], int]:
    """Each input's bounds as (boxes or 1, nonzeros) arrays, checked, and the boxes' number."""
    if len(lo) != len(nnz) or len(hi) != len(nnz):
        raise ValueError(f"interval: the bounds of {len(nnz)} inputs expected")
    out = []
    for i, (a, b) in enumerate(zip(lo, hi, strict=True)):
        a, b = np.broadcast_arrays(np.atleast_2d(np.asarray(a, float)), np.atleast_2d(b))
        if a.ndim != 2 or a.shape[1] != nnz[i]:
            raise ValueError(f"interval: input {i}'s bounds: shape (boxes, {nnz[i]}) expected")
        if not np.all(a <= b):
            raise ValueError(f"interval: input {i} has a lower bound above its upper, or NaN")
        out.append((a, b.astype(float)))
    n = np.broadcast_shapes(*((len(a),) for a, _ in out)) if out else (1,)
    return out, n[0]
