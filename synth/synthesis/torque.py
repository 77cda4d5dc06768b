"""The peak crank torque as the certified search (``certify``) measures and bounds it: under a
cutting force over a zone of the working stroke, on a variant's space.

The torque T(θ, u) is the balance of power (``mechanisms.kinetics.torque``: the Newton–Euler
equations' torque from the motion alone) for the designs of the space: one CasADi expression
of the crank angle, the free numbers u and the load's numbers, with the force on the ram an
input of its own (the cut's while the tool cuts, 0 elsewhere). The measure is the largest T
over the turn (signed: the objective's ``torque.max``): on a grid, polished by Newton on T′
at its largest local maxima, and at each end of the cut from either side (the force steps
there).

For any angles θⱼ and a box U, every u in U has max_θ T ≥ maxⱼ inf_U T(θⱼ, ·), where T(θⱼ,
·) is the torque with the force u's design has at θⱼ. Over a box, the cut's ends are enclosed
in intervals proved to hold them for every u (``stroke.prove``, with the zone's fractions);
an angle between the start's interval and the end's is cut for every u, one outside both is
not, and one inside an interval takes the lesser of the two (T is one of them). The angles
are the two of the centre's peaks and the cut's ends (an end moved to its interval's side)
where the centre's torque is largest; where the proof fails each takes the lesser. Where T is
proved monotonic in a free number over the box (its derivative's enclosure), inf_U is taken
on the face where it is least, else by the centred form over the box. The space's designs
all meet the time ratio, so the working stroke runs the same way for all of them, and so
does the cut's force.

A zone that starts or ends at a dead centre (a fraction 0 or 1) ends there: its interval is
the dead centre's, and T does not step there (s′ = 0). This holds where the force is the
whole of the load's step: a cutting force over its zone, no force profile, and no guide
friction (whose work needs the guide's force, ``unsupported``).
"""

from __future__ import annotations

import math
from typing import Any

import casadi as ca
import numpy as np

from ..load import Load
from ..mechanisms import Mechanism, kinetics
from ..mechanisms.reduced import Space
from ..numerics.compiled_interval import CompiledCentred, CompiledInterval
from ..numerics.native import WIDEST, Mapped
from ..numerics.symbolic import forward
from .measures import local_peaks
from .stroke import PEAKS, TAU, Kinematics, design, newton, prove, strokes

BOUNDED = 2  # the angles a box's bound is taken at


def unsupported(load: Load, sp: Space) -> str | None:
    """Why the bound does not hold for this load on this space (the module's docstring), None
    where it does: on a space whose crank's scale is pinned (``Space.scaled``), not where the
    crank's weight counts (a crank turning evenly about its pivot takes no torque but its
    weight's); not with gravity in the machine's frame, whose direction in the drawing's
    varies by design."""
    if load.force_profile is not None or load.guide_friction != 0:
        return "a force profile or guide friction (the bound takes a cutting force over a zone)"
    if load.ram_incline_deg is not None:
        return "gravity in the machine's frame (its direction in the drawing's varies by design)"
    if sp.scaled and load.link_mass_per_length > 0 and load.gravity_deg is not None:
        return "the crank's weight on a crank of free scale"
    return None


class Model:
    """A variant's space with its crank torque in closed form: T, and T, T′ and T″, at many
    (angle, point, force) triples (``value``, ``rows``), and T enclosed over boxes of (θ, u)
    (``enclosure``) with its u-derivatives (``slope``), for the load's numbers
    (``kinetics.LOAD``) and a force on the ram (N, along s)."""

    def __init__(self, m: Mechanism, variant: frozenset[str], sp: Space, name: str) -> None:
        th, force = ca.SX.sym("theta"), ca.SX.sym("force")
        u, k = ca.SX.sym("u", len(sp.lo)), ca.SX.sym("k", len(sp.constants))
        w = ca.SX.sym("w", len(kinetics.LOAD))
        numbers = {n: w[i] for i, n in enumerate(kinetics.LOAD)} | {"force": force}
        t = kinetics.torque(m, variant, design(m, variant, sp, u, k), th, numbers)
        t1 = forward(t, th)
        args, shared = [th, u, k, w, force], (False, False, True, True, False)
        value = ca.Function(f"{name}_torque", args, [t], {"cse": True})
        rows = ca.Function(f"{name}_torque_rows", args, [ca.vertcat(t, t1, forward(t1, th))])
        self.value = Mapped(value, shared, looped=(WIDEST,))
        self.rows = Mapped(rows, shared)
        self.enclosure = CompiledCentred(value, wrt=[0, 1])
        slope = ca.densify(forward(t, u))
        self.slope = CompiledInterval(
            ca.Function(f"{name}_torque_du", args, [slope], {"cse": True})
        )

    def libraries(self) -> list[Any]:
        """Each enclosure's compiled library (None: not built)."""
        return [self.enclosure.library, self.slope.library]

    def least(
        self,
        theta: np.ndarray,
        lo: np.ndarray,
        hi: np.ndarray,
        k: np.ndarray,
        w: np.ndarray,
        f: np.ndarray,
    ) -> tuple[np.ndarray, np.ndarray]:
        """inf T over each box [lo, hi] (rows) at its angle ``theta`` with its force ``f``
        (one each), −∞ where unbounded: where T is proved monotonic in a free number over the
        box, over the face where it is least (exactly: T's change there costs nothing); and
        that face's point where T is monotonic in every one (NaN elsewhere)."""
        at = theta[:, None], f[:, None]
        d = self.slope([at[0], lo, k, w, at[1]], [at[0], hi, k, w, at[1]])
        rising, falling = d.lo[0] >= 0, d.hi[0] <= 0
        lo, hi = np.where(falling, hi, lo), np.where(rising, lo, hi)
        e = self.enclosure([at[0], lo, k, w, at[1]], [at[0], hi, k, w, at[1]])
        face = np.where(np.all(rising | falling, axis=1)[:, None], lo, math.nan)
        return np.nan_to_num(e.lo[0][:, 0], nan=-math.inf), face

    def at(
        self,
        theta: np.ndarray,
        points: np.ndarray,
        k: np.ndarray,
        w: np.ndarray,
        f: np.ndarray,
        rows: bool = False,
    ) -> np.ndarray:
        """T at each angle of ``theta`` (n, m) with the force ``f`` (n, m), each row of
        ``points`` (n, …) its design, shape (n, m); with ``rows``, T, T′ and T″: (3, n, m)."""
        n, per = theta.shape
        fn = self.rows if rows else self.value
        r = fn(theta.reshape(-1, 1), np.repeat(points, per, axis=0), k, w, f.reshape(-1, 1))
        return r.reshape(3, n, per) if rows else r.reshape(n, per)


class Torque:
    """The peak crank torque (``min_peak_torque``) under a cutting ``force`` (N) over the
    load's zone, for the load's other numbers ``w`` (``kinetics.LOAD``), on a space's
    ``model``: ``measure`` and ``lower`` as ``measures``' motion measures."""

    def __init__(self, model: Model, load: Load, w: np.ndarray) -> None:
        self.model, self.w, self.force = model, w, load.cutting_force
        self.zone = load.cutting_zone

    def _cut(self, info: dict[str, Any]) -> np.ndarray:
        """The force on the ram while the tool cuts, per point: against the working stroke."""
        return np.where(info["slow_up"], -self.force, self.force)

    def measure(self, kin: Kinematics, points: np.ndarray, k: np.ndarray) -> tuple[Any, Any]:
        """The measure at each point, and what its bound takes (``lower``)."""
        info = strokes(kin, points, k, self.zone)
        cut = self._cut(info)[:, None]
        grid, window = info["unwrapped"], info["window"]
        force = np.where(window, cut, 0.0)
        t = self.model.at(grid, points, k, self.w, force)
        idx, real = local_peaks(t - t.min(axis=1, keepdims=True), PEAKS)
        theta = np.take_along_axis(grid, idx, axis=1)
        inside = np.take_along_axis(window, idx, axis=1)
        f = np.where(inside, cut, 0.0)
        theta = newton(lambda t: self.model.at(t, points, k, self.w, f, rows=True), theta, 1)
        a, b = info["ends"][:, :1], info["ends"][:, 1:]
        real &= inside == ((theta > a) & (theta < b))  # still on its side of the cut's ends
        # the peaks, and each end of the cut from either side (off, on; on, off)
        theta = np.hstack([theta, a, a, b, b])
        found = self.model.at(theta, points, k, self.w, np.hstack([f, 0 * cut, cut, cut, 0 * cut]))
        found[:, :PEAKS][~real] = -math.inf
        value = np.maximum(t.max(axis=1), found.max(axis=1))
        value[~(info["ok"] & np.isfinite(value))] = math.inf
        info["angles"], info["values"] = theta, found
        return value, info

    def lower(self, kin: Kinematics, lo: Any, hi: Any, info: Any, k: np.ndarray) -> np.ndarray:
        """maxⱼ inf_U T(θⱼ, ·) of each box (``bound``); where T at the first angle is monotonic
        in every free number, again at the angles of the point where it is least (measured
        there: as tight as the box's best corner)."""
        out, face = self.bound(kin, lo, hi, info, k)
        at = np.flatnonzero(np.isfinite(face[:, 0]))
        if at.size:
            _, near = self.measure(kin, face[at], k)
            out[at] = np.maximum(out[at], self.bound(kin, lo[at], hi[at], near, k)[0])
        return out

    def bound(
        self, kin: Kinematics, lo: Any, hi: Any, info: Any, k: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """maxⱼ inf_U T(θⱼ, ·) of each box, at the ``BOUNDED`` of the peaks and cut's ends of
        the point ``info`` measured where its torque is largest, an end's angle moved to the
        side of its proved interval that it stands for (the module's docstring), −∞ where
        nothing is bounded; and the point where T at the first angle is least, where it is
        proved monotonic in every free number (``Model.least``; NaN elsewhere)."""
        proved, _, (ends_lo, ends_hi), _ = prove(kin, lo, hi, info, k)
        (a_lo, b_lo), (a_hi, b_hi) = ends_lo.T[:, :, None], ends_hi.T[:, :, None]
        sides = [np.nextafter(a_lo, -math.inf), a_hi, b_lo, np.nextafter(b_hi, math.inf)]
        angles = np.hstack([info["angles"][:, :PEAKS], *sides])
        pick = np.argsort(-info["values"], axis=1, kind="stable")[:, :BOUNDED]
        angles = np.take_along_axis(angles, pick, axis=1)
        n, per = angles.shape
        with np.errstate(invalid="ignore"):
            cut = proved[:, None] & (b_lo > a_hi) & ((angles - a_hi) % TAU <= b_lo - a_hi)
            clear = proved[:, None] & ((angles - a_lo) % TAU > b_hi - a_lo)
        force = self._cut(info)[:, None] * np.ones_like(angles)
        bound = np.full((n, per), math.inf)
        face = np.full(lo.shape, math.nan)
        for rows, f in ((~clear, force), (~cut, 0 * force)):  # T with the cut's force, without
            box, j = np.nonzero(rows)
            least, point = self.model.least(angles[box, j], lo[box], hi[box], k, self.w, f[box, j])
            bound[box, j] = np.minimum(bound[box, j], least)
            first = j == 0
            face[box[first]] = point[first]
        face[~(cut[:, 0] | clear[:, 0])] = math.nan  # both forces: two faces
        return bound.max(axis=1), face
