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
import threading
from typing import Any, cast

import casadi as ca
import numpy as np
import numpy.typing as npt

from ..errors import InvalidDesign
from ..mechanisms import Mechanism, kinetics
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
    iteration; the caller checks convergence and finishes the others (``roots._rtsafe``)."""

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


class Forces:
    """A variant's Newton–Euler equations A z = b (``kinetics.system``) at a vector of crank
    angles, for a load given after the type's parameters (``kinetics.LOAD``), solved with
    their first two θ-derivatives: A z′ = b′ − A′ z, A z″ = b″ − 2 A′ z′ − A″ z.

    Where A is singular (a dead point, or where the guide's friction locks the ram) no finite
    forces move the design: the solutions refuse it, naming the crank angle (``singular``),
    unless nothing loads it there (b = 0: z = 0)."""

    RCOND = 1e-12  # A's reciprocal condition number (``conditioning``) where z is rounding
    FLAT = 4 * np.finfo(float).eps  # |1 − |cos μ|| that is a transmission angle 0 (< 3e-8 rad)

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
        self.friction = len(m.parameters) + kinetics.LOAD.index("friction")  # its place in pv
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
        """z at each θ with its own numbers (``pvs``: one row each): shape (len(θ), unknowns);
        NaN where A is singular (a screen of many designs ranks that one last)."""
        a, b = _system(_evaluate(self._values, theta, pvs), self.n)
        return self._solve(a, b, theta, pvs, strict=False)[..., 0]

    def dp(self, theta: np.ndarray, pv: np.ndarray) -> np.ndarray:
        """∂z/∂pv at each θ (every number of ``pv``: the type's parameters, then the load's;
        shared, or one row per angle): A ∂z/∂pv = ∂b/∂pv − ∂A/∂pv z; shape (len(θ),
        unknowns, numbers)."""
        k, p = len(theta), pv.shape[-1]
        a, b = _system(_evaluate(self._values, theta, pv), self.n)
        z = self._solve(a, b, theta, pv)
        da, db = _system(_evaluate(self._dp, theta, pv).reshape(k, p, -1), self.n)
        rhs = db - da @ z[:, None]
        return self._solve(a[:, None], rhs, theta, pv)[..., 0].transpose(0, 2, 1)

    def __call__(self, theta: np.ndarray, pv: np.ndarray, order: int = 2) -> np.ndarray:
        """z and its derivatives up to ``order`` (at most 2) at each θ (``pv``: the numbers,
        shared, or one row per angle): shape (order + 1, len(θ), unknowns)."""
        if len(theta) == 0:
            return np.empty((order + 1, 0, self.n))
        a, b = self._equations(theta, pv, order)
        return self._solved(a, b, theta, pv)[..., 0]

    def lean(self, theta: np.ndarray, pv: np.ndarray, order: int = 2) -> np.ndarray:
        """q = (A⁻¹)[guide, ram], the guide's normal force per newton along the ram's path
        with the guide frictionless (``pv``'s friction 0), and its θ-derivatives up to
        ``order``: shape (order + 1, len(θ)). A friction μ locks the ram where μ |q| ≥ 1: A
        with the friction is A + μ e_ram e_guideᵀ, whose determinant is det A (1 ± μ q)."""
        a, _ = self._equations(theta, pv, order)
        e = np.zeros((order + 1, len(theta), self.n, 1))
        e[0, :, self.n - 2] = 1.0  # a unit force along the path, constant in θ
        return self._solved(a, e, theta, pv)[..., self.n - 1, 0]

    def lock(self, pv: np.ndarray, mu: float) -> None:
        """Refuse a design (``pv``: its numbers, the friction 0) whose ram the guide's friction
        ``mu`` locks: where μ |q| ≥ 1 (``lean``) one of the signs the guide's force may take
        makes A singular, and neither sign or both are consistent: the force that drives the
        ram leans further off its path than the friction angle. |q| is largest on a grid or
        where q′ changes sign (bisection: |q|, flat there, to rounding; a pole: a dead point)."""
        x = np.linspace(0.0, 2 * np.pi, GRID + 1)
        q = self.lean(x, pv, 1)
        c = np.nonzero(q[1, :-1] * q[1, 1:] < 0)[0]
        lean = np.abs(q[0])
        if c.size:
            lo, hi, rising = x[c], x[c + 1], q[1, c] > 0
            for _ in range(30):  # the brackets to 5e-11 rad
                mid = 0.5 * (lo + hi)
                ahead = (self.lean(mid, pv, 1)[1] > 0) == rising  # the root beyond mid
                lo, hi = np.where(ahead, mid, lo), np.where(ahead, hi, mid)
            x = np.concatenate([x, lo])
            lean = np.concatenate([lean, np.abs(self.lean(lo, pv, 0)[0])])
        lean = np.where(np.isfinite(lean), lean, np.inf)  # NaN: A singular there (a pole)
        k = int(np.argmax(lean))
        if mu * lean[k] >= 1:
            least = 1 / lean[k]
            why = (
                f"it locks under a friction of {least:.6g} or more"
                if least > 1e-8
                else "a dead point: any friction locks it"
            )
            deg = round(float(np.degrees(x[k])), 9) % 360
            raise InvalidDesign(
                f"the guide's friction {mu:g} locks the ram at crank angle {deg:.6g}°: the force "
                f"that drives it leans further off its path than the friction angle there ({why})",
                (),
                "friction",
            )

    def bounded(self, theta: np.ndarray, pv: np.ndarray, z: np.ndarray) -> None:
        """Refuse a design whose forces ``z`` (at each θ, its numbers ``pv``) are unbounded
        there: A singular to rounding (``RCOND``) where z is not 0 (a force's maximum brackets
        such a pole, and the root finding lands on it: a dead point, the friction at the lock)."""
        rc = self.conditioning(theta, pv)
        bad = (rc < self.RCOND) & z.any(axis=1)  # NaN where A is not finite: rc 0, z NaN
        if bad.any():
            k = int(np.argmin(np.where(bad, rc, np.inf)))
            raise self.singular(float(theta[k]), pv if pv.ndim == 1 else pv[k])

    def conditioning(self, theta: np.ndarray, pv: np.ndarray) -> np.ndarray:
        """A's reciprocal condition number at each θ, its rows and then its columns scaled to a
        largest entry of 1 (so whatever the units): ~1e-16 or less where A is singular to
        rounding, 0 where it is not finite."""
        a, _ = _system(_evaluate(self._values, theta, pv), self.n)
        fine = np.isfinite(a).all(axis=(1, 2))
        a = a[fine]
        for axis in (2, 1):  # rows, then columns
            big = np.abs(a).max(axis=axis, keepdims=True)
            a = a / np.where(big > 0, big, 1.0)
        out = np.zeros(len(theta))
        if a.size:
            s = np.linalg.svd(a, compute_uv=False)
            out[fine] = s[:, -1] / s[:, 0]
        return out

    def dead(self, theta: np.ndarray, pvs: np.ndarray, joints: list[str]) -> None:
        """Refuse a design with a dead point at an angle of ``theta`` (with its numbers ``pvs``
        and the joint whose transmission angle is 0° there) that anything loads there (b ≠ 0:
        a mass that moves or weighs, a force on the ram); where b = 0, z = 0 whatever A."""
        if len(theta) == 0:
            return
        _, b = _system(_evaluate(self._values, theta, pvs), self.n)
        loaded = b[..., 0].any(axis=-1)
        if loaded.any():
            k = int(np.argmax(loaded))
            raise self.singular(float(theta[k]), pvs[k], joints[k])

    def singular(self, theta: float, pv: np.ndarray, joint: str | None = None) -> InvalidDesign:
        """The refusal of a design whose forces are unbounded at crank angle ``theta``
        (radians; ``pv``: its numbers there): where the guide's friction locks the ram, or at
        a dead point (of ``joint``, where it is known)."""
        deg = round(float(np.degrees(theta)), 9) % 360  # 0, not 360 or 1e-14, at a turn's end
        at = f"the joint forces are indeterminate at crank angle {deg:.6g}°"
        mu = abs(float(pv[self.friction]))
        if mu:
            return InvalidDesign(
                f"{at}: the guide's friction {mu:g} locks the ram there (the force that drives "
                f"it leans off its path by the friction angle, atan {mu:g}), and the forces "
                "the load needs grow without bound",
                (),
                "friction",
            )
        where = f"the {joint} joint's transmission angle 0°" if joint else "a transmission angle 0°"
        return InvalidDesign(
            f"{at}: a dead point ({where}), where the crank cannot move the ram and the forces "
            "the load needs grow without bound",
            (),
            "dead_point",
        )

    def _equations(
        self, theta: np.ndarray, pv: np.ndarray, order: int
    ) -> tuple[np.ndarray, np.ndarray]:
        """A and b at each θ and their θ-derivatives up to ``order`` (the first axis)."""
        if order == 0:
            rows = _evaluate(self._values, theta, pv)[None]
        else:  # vec(A), b and their θ-derivatives
            rows = _evaluate(self.fn, theta, pv).reshape(len(theta), 3, -1).transpose(1, 0, 2)
        return _system(rows[: order + 1], self.n)

    def _solved(
        self, a: np.ndarray, b: np.ndarray, theta: np.ndarray, pv: np.ndarray
    ) -> np.ndarray:
        """z and its θ-derivatives from A's and b's (the first axis: the orders, at most 2)."""
        z = [self._solve(a[0], b[0], theta, pv)]
        if len(a) > 1:
            z.append(self._solve(a[0], b[1] - a[1] @ z[0], theta, pv))
        if len(a) > 2:
            z.append(self._solve(a[0], b[2] - 2 * a[1] @ z[1] - a[2] @ z[0], theta, pv))
        return np.stack(z)

    def _solve(
        self, a: np.ndarray, b: np.ndarray, theta: np.ndarray, pv: np.ndarray, strict: bool = True
    ) -> np.ndarray:
        """A⁻¹ b, an angle a row of the first axis. Where A is singular to the last bit: 0
        where b is 0 there, else the refusal (``singular``), or NaN unless ``strict``."""
        try:
            return cast(np.ndarray, np.linalg.solve(a, b))
        except np.linalg.LinAlgError:
            pass
        shape = np.broadcast_shapes(a.shape[:-2], b.shape[:-2]) + b.shape[-2:]
        out = np.empty(shape)
        for i in range(shape[0]):
            try:
                out[i] = np.linalg.solve(a[i], b[i])
            except np.linalg.LinAlgError:
                if b[i].any() and strict:
                    raise self.singular(theta[i], pv if pv.ndim == 1 else pv[i]) from None
                out[i] = np.nan if b[i].any() else 0.0
        return out


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


def compiled(m: Mechanism, variant: frozenset[str]) -> list[ca.Function]:
    """Every compiled function of a variant's analysis, built in this thread's models
    (``model``, ``forces``): each kind's and its polish, the sensitivities of those whose are
    evaluated (``SENSITIVE``), and the loads' where the type has a frame. What a request may
    evaluate of it, so what the native cache holds and a service builds before it reports
    ready (``synth.synthesis.warm``)."""
    fns = []
    for kind in KINDS:
        f = model(m, variant, kind)
        fns += [f.fn.fn, f.polish.fn, *([f._dp.fn] if kind in SENSITIVE else [])]
        fns += [g.fn for g in (f.dead, f.dead_polish) if g is not None]
    if m.frame is not None:
        sys = forces(m, variant)
        fns += [sys.fn.fn, sys._values.fn, sys._dp.fn]
    return fns
