"""Each type's kinematics compiled for one structural variant, once per thread.

The rows are the slider's position s(θ) and each pin joint's transmission cosine, with their
first and second θ-derivatives (automatic differentiation); ``kind="motion"`` gives the rows
s′ and s″ instead, whose stationary points are the velocity and acceleration extremes (the
loads' equations are ``forces``'). The functions are built to machine code where a C
compiler is at hand (``native``), and are never shared between threads.
"""

from __future__ import annotations

import functools
import threading
from typing import Any

import casadi as ca
import numpy as np
import numpy.typing as npt

from ..mechanisms import Mechanism
from ..numerics import stored
from ..numerics.native import Mapped

GRID = 128  # samples per revolution that bracket the stationary points
POLISH_STEPS = 8  # safeguarded Newton steps a compiled polish takes (``Polisher``)

_local = threading.local()


KINDS = ("kinematics", "motion", "pins", "envelope")
SENSITIVE = ("kinematics", "motion")  # the kinds whose ``dp`` anything evaluates


class Model:
    """A type's kinematics compiled for one variant, evaluated at a vector of crank angles.

    A call gives the rows and their first two θ-derivatives. The rows, by ``kind``:

    - ``kinematics``: s, then each transmission joint's cos μ (``names``);
    - ``motion``: s′ and s″ (per unit crank speed), whose stationary points are the extremes
      of the slider's velocity and acceleration;
    - ``pins``: x and y of every pin of the type's drawing (``names``, in pairs);
    - ``envelope``: those of the pins' coordinates that move (``axes``: 0 for x, 1 for y),
      whose stationary points bound the space the frame must hold.
    """

    def __init__(self, m: Mechanism, variant: frozenset[str], kind: str = "kinematics") -> None:
        th = ca.SX.sym("theta")
        pv = ca.SX.sym("p", len(m.parameters))
        p = {q.name: (0.0 if q.name in variant else pv[i]) for i, q in enumerate(m.parameters)}
        g, self.names, self.axes = _rows(m, p, th, kind)
        g1 = ca.jacobian(g, th)
        g2 = ca.jacobian(g1, th)
        self.kind = kind
        base = "_".join((m.type, *sorted(variant)))  # one symbol per compiled library
        self.name = f"{base}_{kind}"
        self.fn = Batched(self.name, th, pv, ca.vertcat(g, g1, g2))
        self.polish = Polisher(f"{self.name}_polish", th, pv, g1, g2)
        self._rows = (th, pv, ca.vertcat(g, g1))
        self.dead: Batched | None = None
        self.dead_polish: Polisher | None = None
        if kind == "kinematics" and m.dead_centres is not None:
            h = m.dead_centres(p, th)
            dh = ca.jacobian(h, th)
            self.dead = Batched(f"{base}_dead_centres", th, pv, ca.vertcat(h, dh))
            self.dead_polish = Polisher(f"{base}_dead_centres_polish", th, pv, h, dh)

    def __call__(self, theta: np.ndarray, pv: np.ndarray) -> tuple[np.ndarray, ...]:
        """g, g', g'' at each θ: arrays of shape (rows, len(θ))."""
        out = self.fn(theta, pv)
        return tuple(out.reshape(3, out.shape[0] // 3, -1))

    def dp(self, theta: np.ndarray, pv: np.ndarray) -> np.ndarray:
        """∂g/∂p and ∂g'/∂p at each θ: shape (len(θ), 2·rows, parameters)."""
        out = self._dp(theta, pv)
        return out.T.reshape(out.shape[1], len(pv), -1).transpose(0, 2, 1)

    @functools.cached_property
    def _dp(self) -> Batched:  # built on first use: only sensitivities need it
        th, pv, g = self._rows
        return Batched(f"{self.name}_dp", th, pv, ca.vec(ca.jacobian(g, pv)))


def _rows(
    m: Mechanism, p: dict[str, Any], th: ca.SX, kind: str
) -> tuple[ca.SX, tuple[str, ...], np.ndarray]:
    """A kind's rows (see ``Model``), their names and their axes."""
    none = np.zeros(0, dtype=int)
    if kind == "kinematics":
        joints = m.transmission(p, th)
        return ca.vertcat(m.position(p, th), *joints.values()), tuple(joints), none
    if kind == "motion":
        s1 = ca.jacobian(m.position(p, th), th)
        return ca.vertcat(s1, ca.jacobian(s1, th)), (), none
    assert m.joints is not None  # the pins' kinds are built for the types that have joints
    pins = m.joints(p, th)
    coords = [(axis, ca.SX(c)) for xy in pins.values() for axis, c in enumerate(xy)]
    if kind == "envelope":
        coords = [(axis, c) for axis, c in coords if ca.depends_on(c, th)]
    axes = np.array([axis for axis, _ in coords], dtype=int)
    return ca.vertcat(*(c for _, c in coords)), tuple(pins), axes


class Batched:
    """out(θ, p) compiled, evaluated at each θ of a vector through ``Mapped``'s slots (owned
    like the function by one thread's Model): an ordinary call's numpy <-> DM conversions
    cost ~40 µs, more than a few-angle Newton step's evaluation, and would keep a mapped
    function for every number of angles. Common subexpressions are merged (the derivatives
    repeat g's terms): the same operations on the same operands, so the same results, from
    half the instructions. The library is found by the plain function (``stored``), so a
    start that finds it skips the merging and the code generation (~60% of a model's build)."""

    def __init__(self, name: str, th: ca.SX, pv: ca.SX, out: ca.SX) -> None:
        out = ca.densify(out)  # structural zeros (a fixed pivot, a constant row) as numbers
        self.fn = stored.compiled(name, [ca.Function(name, [th, pv], [out])], _merged)
        self.shared = Mapped(self.fn, (False, True), compiled=self.fn)  # one design's numbers
        self.own = Mapped(self.fn, (False, False), compiled=self.fn)  # each angle its design's

    def __call__(self, theta: npt.ArrayLike, pv: np.ndarray) -> np.ndarray:
        """out at each θ, shape (rows, len(θ)), for one design's parameters ``pv``."""
        return self.shared(np.atleast_1d(theta)[:, None], pv)

    def each(self, theta: np.ndarray, pv: np.ndarray) -> np.ndarray:
        """out at each θ with its own parameters (``pv``: shape (len(θ), p)), as ``__call__``
        gives it: the same operations, so the same results, for several designs at once."""
        return self.own(theta[:, None], pv)


class Polisher:
    """Roots of one row each of d(θ) (d′ its derivative), from brackets where it changes sign:
    ``POLISH_STEPS`` safeguarded Newton steps (bisection where Newton leaves the bracket)
    unrolled into one compiled function, mapped over the roots, each with its own row and
    parameters. A call replaces the several evaluations and the Python loop of a step-by-step
    iteration; the caller checks convergence and finishes the others (``roots.rtsafe``)."""

    def __init__(self, name: str, th: ca.SX, pv: ca.SX, d: ca.SX, d1: ca.SX) -> None:
        w = ca.SX.sym("w", d.numel())  # the root's row, one-hot
        row = ca.Function("row", [th, pv, w], [ca.dot(w, d), ca.dot(w, d1)])
        # by the row and the unrolling's code: a start loads it, without unrolling it again
        fn = stored.compiled(name, [row, POLISH_STEPS], _unrolled)
        self.mapped = Mapped(fn, (False,) * 6, compiled=fn)  # every argument per root
        self.fn = self.mapped.fn

    def __call__(
        self,
        x0: np.ndarray,
        lo: np.ndarray,
        hi: np.ndarray,
        rising: np.ndarray,
        rows: np.ndarray,
        pv: np.ndarray,
    ) -> np.ndarray:
        """(x, the last step, d at the point before it, the bracket's width) per root: shape
        (4, n). ``rows``: each root's row; ``pv``: the parameters, (n, p) or shared (p,)."""
        n = len(x0)
        w = np.zeros((n, self.mapped.fn.nnz_in(4)))
        w[np.arange(n), rows] = 1.0
        pv = np.broadcast_to(pv, (n, pv.shape[-1]))
        return self.mapped(x0[:, None], lo[:, None], hi[:, None], rising[:, None], w, pv)


def _merged(name: str, plain: ca.Function) -> ca.Function:
    """``plain`` with its common subexpressions merged (the same generated code as merging
    them where its expression is made: checked for every model)."""
    x = plain.sx_in()
    return ca.Function(name, x, plain.call(x), {"cse": True})


def _unrolled(name: str, row: ca.Function, steps: int) -> ca.Function:
    """``Polisher``'s function of (x0, lo, hi, rising, w, pv): ``steps`` steps on the row
    (θ, pv, w) → (d, d′), its common subexpressions merged."""
    pv, w = row.sx_in(1), row.sx_in(2)
    x = x0 = ca.SX.sym("x0")
    lo, hi, rising = ca.SX.sym("lo"), ca.SX.sym("hi"), ca.SX.sym("rising")
    a, b, fx, step = lo, hi, ca.SX(0), ca.SX(0)
    for _ in range(steps):
        fx, dfx = row(x, pv, w)
        on_lo = rising * fx < 0  # on lo's side of the root
        a, b = ca.if_else(on_lo, x, a), ca.if_else(on_lo, b, x)
        xn = x - fx / dfx
        nxt = ca.if_else(ca.logic_and(xn >= a, xn <= b), xn, 0.5 * (a + b))
        x, step = nxt, nxt - x
    out = ca.vertcat(x, step, fx, b - a)
    return ca.Function(name, [x0, lo, hi, rising, w, pv], [out], {"cse": True})


def model(m: Mechanism, variant: frozenset[str], kind: str = "kinematics") -> Model:
    """The compiled model, cached per thread: CasADi functions are never shared by threads."""
    cache: dict[tuple[str, frozenset[str], str], Model] = _local.__dict__.setdefault("models", {})
    key = (m.type, variant, kind)
    if key not in cache:
        cache[key] = Model(m, variant, kind)
    return cache[key]


def compiled(m: Mechanism, variant: frozenset[str]) -> list[ca.Function]:
    """Every compiled function of a variant's kinematics, built in this thread's models
    (``model``): each kind's and its polish, and the sensitivities of those whose are evaluated
    (``SENSITIVE``). What a request may evaluate of it, so what the native cache holds and a
    service builds before it reports ready (``synth.synthesis.warm``; the loads' are
    ``forces.compiled``)."""
    fns = []
    for kind in KINDS:
        f = model(m, variant, kind)
        fns += [f.fn.fn, f.polish.fn, *([f._dp.fn] if kind in SENSITIVE else [])]
        fns += [g.fn for g in (f.dead, f.dead_polish) if g is not None]
    return fns
