"""Each type's kinematics compiled for one structural variant, once per thread.

The rows are the slider's position s(θ) and each pin joint's transmission cosine, with their
first and second θ-derivatives (automatic differentiation); ``kind="motion"`` gives the rows
s′ and s″ instead, whose stationary points are the velocity and acceleration extremes.
``Forces`` compiles a variant's Newton–Euler equations for the loads the same way. The
functions are built to machine code where a C compiler is at hand (``native``), and are never
shared between threads.
"""

from __future__ import annotations

import functools
import itertools
import threading
from typing import Any, cast

import casadi as ca
import numpy as np
import numpy.typing as npt

from ..mechanisms import Mechanism, all_types, get, kinetics, rod
from ..mechanisms.fourbar.construction import construction
from ..numerics.native import Mapped

GRID = 128  # samples per revolution that bracket the stationary points
POLISH_STEPS = 8  # safeguarded Newton steps a compiled polish takes (``Polisher``)

_local = threading.local()


KINDS = ("kinematics", "motion", "pins", "envelope")


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
        self.fn = _Batched(self.name, th, pv, ca.vertcat(g, g1, g2))
        self.polish = Polisher(f"{self.name}_polish", th, pv, g1, g2)
        self._rows = (th, pv, ca.vertcat(g, g1))
        self.dead: _Batched | None = None
        self.dead_polish: Polisher | None = None
        if kind == "kinematics" and m.dead_centres is not None:
            h = m.dead_centres(p, th)
            dh = ca.jacobian(h, th)
            self.dead = _Batched(f"{base}_dead_centres", th, pv, ca.vertcat(h, dh))
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
    def _dp(self) -> _Batched:  # built on first use: only sensitivities need it
        th, pv, g = self._rows
        return _Batched(f"{self.name}_dp", th, pv, ca.vec(ca.jacobian(g, pv)))


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


class _Batched:
    """out(θ, p) compiled, evaluated at each θ of a vector through ``Mapped``'s slots (owned
    like the function by one thread's Model): an ordinary call's numpy <-> DM conversions
    cost ~40 µs, more than a few-angle Newton step's evaluation, and would keep a mapped
    function for every number of angles. Common subexpressions are merged (the derivatives
    repeat g's terms): the same operations on the same operands, so the same results, from
    half the instructions."""

    def __init__(self, name: str, th: ca.SX, pv: ca.SX, out: ca.SX) -> None:
        out = ca.densify(out)  # structural zeros (a fixed pivot, a constant row) as numbers
        fn = ca.Function(name, [th, pv], [out], {"cse": True})
        self.shared = Mapped(fn, (False, True))  # one design's parameters
        self.fn = self.shared.fn
        self.own = Mapped(fn, (False, False), compiled=self.fn)  # each angle its design's

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
    iteration; the caller checks convergence and finishes the others (``roots._rtsafe``)."""

    def __init__(self, name: str, th: ca.SX, pv: ca.SX, d: ca.SX, d1: ca.SX) -> None:
        w = ca.SX.sym("w", d.numel())  # the root's row, one-hot
        row = ca.Function("row", [th, pv, w], [ca.dot(w, d), ca.dot(w, d1)])
        x = x0 = ca.SX.sym("x0")
        lo, hi, rising = ca.SX.sym("lo"), ca.SX.sym("hi"), ca.SX.sym("rising")
        a, b, fx, step = lo, hi, ca.SX(0), ca.SX(0)
        for _ in range(POLISH_STEPS):
            fx, dfx = row(x, pv, w)
            on_lo = rising * fx < 0  # on lo's side of the root
            a, b = ca.if_else(on_lo, x, a), ca.if_else(on_lo, b, x)
            xn = x - fx / dfx
            nxt = ca.if_else(ca.logic_and(xn >= a, xn <= b), xn, 0.5 * (a + b))
            x, step = nxt, nxt - x
        out = ca.vertcat(x, step, fx, b - a)
        fn = ca.Function(name, [x0, lo, hi, rising, w, pv], [out], {"cse": True})
        self.mapped = Mapped(fn, (False,) * 6)  # every argument per root
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


class Forces:
    """A variant's Newton–Euler equations A z = b (``kinetics.system``) at a vector of crank
    angles, for a load given after the type's parameters (``kinetics.LOAD``), solved with
    their first two θ-derivatives: A z′ = b′ − A′ z, A z″ = b″ − 2 A′ z′ − A″ z."""

    def __init__(self, m: Mechanism, variant: frozenset[str]) -> None:
        th = ca.SX.sym("theta")
        pv = ca.SX.sym("p", len(m.parameters) + len(kinetics.LOAD))
        p = {q.name: (0.0 if q.name in variant else pv[i]) for i, q in enumerate(m.parameters)}
        w = {k: pv[len(m.parameters) + i] for i, k in enumerate(kinetics.LOAD)}
        a, b, self.layout = kinetics.system(m, variant, p, th, w)
        g = ca.vertcat(ca.vec(a), b)
        g1 = ca.jacobian(g, th)
        self.name = "_".join((m.type, *sorted(variant), "loads"))
        self.fn = _Batched(self.name, th, pv, ca.vertcat(g, g1, ca.jacobian(g1, th)))
        self.n = self.layout.size
        self._rows = (th, pv, g)

    @functools.cached_property
    def _dp(self) -> _Batched:  # built on first use: only the least peak torque needs it
        th, pv, g = self._rows
        return _Batched(f"{self.name}_dp", th, pv, ca.vec(ca.jacobian(g, pv)))

    @functools.cached_property
    def _values(self) -> _Batched:  # A and b alone: z without its derivatives
        th, pv, g = self._rows
        return _Batched(f"{self.name}_values", th, pv, g)

    def each(self, theta: np.ndarray, pvs: np.ndarray) -> np.ndarray:
        """z at each θ with its own numbers (``pvs``: one row each): shape (len(θ), unknowns)."""
        a, b = _system(_evaluate(self._values, theta, pvs), self.n)
        return cast(np.ndarray, np.linalg.solve(a, b)[..., 0])

    def dp(self, theta: np.ndarray, pv: np.ndarray) -> np.ndarray:
        """∂z/∂pv at each θ (every number of ``pv``: the type's parameters, then the load's;
        shared, or one row per angle): A ∂z/∂pv = ∂b/∂pv − ∂A/∂pv z; shape (len(θ),
        unknowns, numbers)."""
        k, p = len(theta), pv.shape[-1]
        a, b = _system(_evaluate(self._values, theta, pv), self.n)
        z = np.linalg.solve(a, b)
        da, db = _system(_evaluate(self._dp, theta, pv).reshape(k, p, -1), self.n)
        rhs = db - da @ z[:, None]
        return cast(np.ndarray, np.linalg.solve(a[:, None], rhs)[..., 0].transpose(0, 2, 1))

    def __call__(self, theta: np.ndarray, pv: np.ndarray, order: int = 2) -> np.ndarray:
        """z and its derivatives up to ``order`` (at most 2) at each θ (``pv``: the numbers,
        shared, or one row per angle): shape (order + 1, len(θ), unknowns)."""
        if len(theta) == 0:
            return np.empty((order + 1, 0, self.n))
        if order == 0:
            rows = _evaluate(self._values, theta, pv)[None]
        else:  # vec(A), b and their θ-derivatives
            rows = _evaluate(self.fn, theta, pv).reshape(len(theta), 3, -1).transpose(1, 0, 2)
        a, b = _system(rows[: order + 1], self.n)
        z = [np.linalg.solve(a[0], b[0])]
        if order > 0:
            z.append(np.linalg.solve(a[0], b[1] - a[1] @ z[0]))
        if order > 1:
            z.append(np.linalg.solve(a[0], b[2] - 2 * a[1] @ z[1] - a[2] @ z[0]))
        return np.stack(z)[..., 0]


def _evaluate(fn: _Batched, theta: np.ndarray, pv: np.ndarray) -> np.ndarray:
    """fn at each θ, one row per angle, for shared numbers ``pv`` or each angle's (a row of
    ``pv`` each)."""
    return (fn(theta, pv) if pv.ndim == 1 else fn.each(theta, pv)).T


def _system(rows: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
    """A (n × n, from its columns stacked: CasADi's vec) and b (a column) of rows of
    vec(A), b."""
    a = rows[..., : n * n].reshape(*rows.shape[:-1], n, n).swapaxes(-1, -2)
    return a, rows[..., n * n :, None]


def forces(m: Mechanism, variant: frozenset[str]) -> Forces:
    """The variant's ``Forces``, once per thread (CasADi functions are not shared)."""
    cache: dict[tuple[str, frozenset[str]], Forces] = _local.__dict__.setdefault("forces", {})
    key = (m.type, variant)
    if key not in cache:
        cache[key] = Forces(m, variant)
    return cache[key]


def model(m: Mechanism, variant: frozenset[str], kind: str = "kinematics") -> Model:
    """The compiled model, cached per thread: CasADi functions are never shared by threads."""
    cache: dict[tuple[str, frozenset[str], str], Model] = _local.__dict__.setdefault("models", {})
    key = (m.type, variant, kind)
    if key not in cache:
        cache[key] = Model(m, variant, kind)
    return cache[key]


def compile_all() -> None:
    """Every type's analysis, in every structural variant, built into the native cache: an
    image's build step (elsewhere each is built on first use). Raises where one cannot be."""
    for mtype in all_types():
        m = get(mtype)
        optional = [q.name for q in m.parameters if q.zero_means]
        for k in range(len(optional) + 1):
            for parts, kind in itertools.product(itertools.combinations(optional, k), KINDS):
                f = Model(m, frozenset(parts), kind)
                fns = [f.fn.fn, f._dp.fn, f.polish.fn, f.dead.fn if f.dead else None,
                       f.dead_polish.fn if f.dead_polish else None]  # fmt: skip
                if m.frame is not None and kind == KINDS[0]:  # the loads', once a variant
                    sys = Forces(m, frozenset(parts))
                    fns += [sys.fn.fn, sys._values.fn]
                for fn in fns:
                    if fn is not None and fn.class_name() != "External":
                        raise RuntimeError(
                            f"{fn.name()}: no C compiler or cache (synth.numerics.native)"
                        )
    # the reduced synthesis's: the four-bar construction (its points, and its chunks' loop),
    # its local model and the connecting rod (a few points at a time: no loop of theirs)
    c = construction()
    for fn in (*c.points.mapped.compiled(), c.local.fn, rod.compiled().fn):
        if fn.class_name() != "External":
            raise RuntimeError(f"{fn.name()}: no C compiler or cache (synth.numerics.native)")
