"""A variant's loads compiled, at a vector of crank angles, once per thread: its Newton–Euler
equations A z = b solved for the forces (``Forces``), and where the guide does not rub the
crank torque alone by the balance of power (``Torques``); built to machine code where a C
compiler is at hand (``native``), as the kinematics' models are (``model``)."""

from __future__ import annotations

import functools
import threading
from typing import Any, TypeVar, cast

import casadi as ca
import numpy as np

from ..errors import InvalidDesign
from ..mechanisms import Mechanism, kinetics
from .model import GRID, Batched, Polisher

_local = threading.local()
S = TypeVar("S", "Forces", "Torques")  # a compiled system, cached per thread and variant


class Forces:
    """A variant's Newton–Euler equations A z = b (``kinetics.system``) at a vector of crank
    angles, for a load given after the type's parameters (``kinetics.LOAD``), solved with
    their first two θ-derivatives: A z′ = b′ − A′ z, A z″ = b″ − 2 A′ z′ − A″ z.

    Where A is singular (a dead point, or where the guide's friction locks the ram) no finite
    forces move the design: the solutions refuse it, naming the crank angle (``singular``),
    unless nothing loads it there (b = 0: z = 0)."""

    RCOND = 1e-12  # A's reciprocal condition number (``conditioning``) where z is rounding
    FLAT = 4 * np.finfo(float).eps  # |1 − |cos μ|| that is a transmission angle 0 (< 3e-8 rad)
    # compiled steps to the torque's extremes (``Torques.polish``): none, the torque is one
    # unknown of a linear solve, polished step by step
    polish: Polisher | None = None

    def __init__(self, m: Mechanism, variant: frozenset[str]) -> None:
        th, pv, p, w = _loaded(m, variant)
        a, b, self.layout = kinetics.system(m, variant, p, th, w)
        g = ca.vertcat(ca.vec(a), b)
        g1 = ca.jacobian(g, th)
        self.name = "_".join((m.type, *sorted(variant), "loads"))
        self.fn = Batched(self.name, th, pv, ca.vertcat(g, g1, ca.jacobian(g1, th)))
        self.n = self.layout.size
        self.friction = len(m.parameters) + kinetics.LOAD.index("friction")  # its place in pv
        self._rows = (th, pv, g)

    @functools.cached_property
    def _dp(self) -> Batched:  # built on first use: only the least peak torque needs it
        th, pv, g = self._rows
        return Batched(f"{self.name}_dp", th, pv, ca.vec(ca.jacobian(g, pv)))

    @functools.cached_property
    def _values(self) -> Batched:  # A and b alone: z without its derivatives
        th, pv, g = self._rows
        return Batched(f"{self.name}_values", th, pv, g)

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


class Torques:
    """The crank torque alone where the guide does not rub, by the balance of power
    (``kinetics.torque``): ``Forces``' interface for one unknown, without a linear solve (the
    least peak torque's search evaluates it many times: ``loads.peak_terms``)."""

    n = 1

    def __init__(self, m: Mechanism, variant: frozenset[str]) -> None:
        th, pv, p, w = _loaded(m, variant)
        t = kinetics.torque(m, variant, p, th, w)
        t1 = ca.jacobian(t, th)
        self.name = "_".join((m.type, *sorted(variant), "power"))
        t2 = ca.jacobian(t1, th)
        self.fn = Batched(self.name, th, pv, ca.vertcat(t, t1, t2))
        self.gradient = Batched(f"{self.name}_dp", th, pv, ca.jacobian(t, pv).T)
        self.polish = Polisher(f"{self.name}_polish", th, pv, t1, t2)  # T's extremes

    def __call__(self, theta: np.ndarray, pv: np.ndarray, order: int = 2) -> np.ndarray:
        """T and its θ-derivatives up to ``order`` at each θ (``pv``: the numbers, shared, or
        one row per angle): shape (order + 1, len(θ), 1)."""
        if len(theta) == 0:
            return np.empty((order + 1, 0, 1))
        return _evaluate(self.fn, theta, pv).T[: order + 1, :, None]

    def dp(self, theta: np.ndarray, pv: np.ndarray) -> np.ndarray:
        """∂T/∂pv at each θ: shape (len(θ), 1, numbers)."""
        return _evaluate(self.gradient, theta, pv)[:, None, :]


def _loaded(
    m: Mechanism, variant: frozenset[str]
) -> tuple[Any, Any, dict[str, Any], dict[str, Any]]:
    """θ, the numbers (the type's parameters, then the load's: ``kinetics.LOAD``), and the
    variant's parameters and the load's among them, CasADi symbols."""
    th = ca.SX.sym("theta")
    pv = ca.SX.sym("p", len(m.parameters) + len(kinetics.LOAD))
    p = {q.name: (0.0 if q.name in variant else pv[i]) for i, q in enumerate(m.parameters)}
    return th, pv, p, {k: pv[len(m.parameters) + i] for i, k in enumerate(kinetics.LOAD)}


def _evaluate(fn: Batched, theta: np.ndarray, pv: np.ndarray) -> np.ndarray:
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
    return _cached(Forces, m, variant)


def torques(m: Mechanism, variant: frozenset[str]) -> Torques:
    """The variant's ``Torques``, once per thread."""
    return _cached(Torques, m, variant)


def _cached(build: type[S], m: Mechanism, variant: frozenset[str]) -> S:
    cache: dict[tuple[str, frozenset[str]], S] = _local.__dict__.setdefault(build.__name__, {})
    if (m.type, variant) not in cache:
        cache[m.type, variant] = build(m, variant)
    return cache[m.type, variant]


def compiled(m: Mechanism, variant: frozenset[str]) -> list[ca.Function]:
    """Every compiled function of a variant's loads (none without a frame), built in this
    thread: what the native cache holds beside the kinematics' (``model.compiled``)."""
    if m.frame is None:
        return []
    sys, t = forces(m, variant), torques(m, variant)
    return [sys.fn.fn, sys._values.fn, sys._dp.fn, t.fn.fn, t.gradient.fn, t.polish.fn]
