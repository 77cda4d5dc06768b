"""The loads a design carries at constant crank speed: the crank torque, its power and the
flywheel that evens it out, and the forces at the joints and the ram's guide.

The forces at a crank angle solve the design's Newton–Euler equations A z = b
(``synth.mechanisms.kinetics``); their derivatives in the crank angle solve the same system
differentiated (``forces.Forces``). The resisting force is linear in the ram's position between
the points of the load's profile (a cutting force over its zone: two points), and steps where
the working stroke passes them (``quality.reached``): the turn is a piece between each two and
a piece for the rest; with the guide's friction, split further where the ram turns and where
the guide's force changes sign (``_pieces``). On each piece everything is smooth:

- extremes: the stationary points of each quantity on each piece (bracketed on a grid,
  polished by the safeguarded Newton iteration that finds the dead centres, ``roots``), and
  the pieces' ends;
- the mean and the root mean square: Gauss–Legendre quadrature on each piece, its panels
  halved where the 8- and 16-point rules disagree (``Pieces.integrals``);
- the flywheel: the crank's energy E(θ) = ∫ (T − T_mean) dθ is extreme where T crosses its
  mean (roots, polished alike) or jumps across it at a piece's end: its largest swing ΔE.

Where no finite forces move the design, it is refused with the crank angle named: a loaded
dead point (``Forces.dead``), a ram the guide's friction locks (``Forces.lock``), A singular
to rounding where the extremes land (``Forces.bounded``). ``peak_terms`` gives the least peak
torque's search the torque's maxima and the pieces' ends with their derivatives in the
lengths, each end's angle moving with the design.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import cast

import numpy as np

from ..errors import InvalidParameters
from ..load import Load
from ..mechanisms import Mechanism, kinetics
from ..results import Flywheel, Force, Loads, Power, Torque
from .forces import Forces, Torques, forces, torques
from .model import Model
from .pieces import Found, Piece, Pieces, Quantity
from .quality import Strokes, reached
from .roots import TWO_PI, Points


def _torque(z: np.ndarray) -> np.ndarray:
    return z[:, :, 0]


def _magnitude(cols: list[int]) -> Quantity:
    """|z[cols]| (a pin's force, a block's push, the guide's), with its derivatives."""

    def q(z: np.ndarray) -> np.ndarray:
        v, v1, v2 = z[:, :, cols]
        mag = np.sqrt((v * v).sum(axis=1))
        with np.errstate(divide="ignore", invalid="ignore"):
            d1 = (v * v1).sum(axis=1) / mag
            d2 = ((v1 * v1).sum(axis=1) + (v * v2).sum(axis=1) - d1 * d1) / mag
        return np.array([mag, d1, d2])

    return q


def _extremes(sys: Forces, pieces: Pieces, fs: list[Quantity], k: int) -> list[Found]:
    """Where each quantity may be extreme (radians) and its values there: its stationary
    points on each piece (only its maxima for the first ``k``) and the pieces' ends (the
    value from each side); in one evaluation, where ``sys``'s forces are bounded."""
    n = len(pieces.pieces)
    ends = np.concatenate([pieces.lo, pieces.hi]), np.tile(np.arange(n), 2)
    found = [
        (np.concatenate([x, ends[0]]), np.concatenate([o, ends[1]]))
        for x, o in pieces.roots(fs, 1, k)
    ]
    x, owner = (np.concatenate(c) for c in zip(*found, strict=True))
    z = pieces(x, owner)
    sys.bounded(x, pieces.pv[owner], z[0])
    cut = np.cumsum([f[0].size for f in found])[:-1]
    return [
        (xs, f(zs)[0]) for (xs, _), zs, f in zip(found, np.split(z, cut, axis=1), fs, strict=True)
    ]


def speed(
    m: Mechanism, load: Load | None, crank_speed: float | None, crank_acceleration: float
) -> float:
    """The curves' crank speed (rad/s): the load's, which a ``crank_speed`` given too must
    equal; else ``crank_speed``, 1 by default. Raises InvalidParameters for a load the type
    cannot take, or with a crank that accelerates."""
    if load is None:
        return 1.0 if crank_speed is None else crank_speed
    if m.frame is None:
        raise InvalidParameters(f"load: {m.type} has no force model yet", ("load",))
    if crank_acceleration:
        msg = "with a load the crank turns at constant speed: crank_acceleration must be 0"
        raise InvalidParameters(msg, ("crank_acceleration",))
    if crank_speed is not None and crank_speed != load.omega:
        msg = (
            f"crank_speed {crank_speed:g} rad/s differs from the load's crank_rpm "
            f"{load.crank_rpm:g} ({load.omega:.9g} rad/s): give one of them"
        )
        raise InvalidParameters(msg, ("crank_speed",))
    return load.omega


def forces_of(m: Mechanism) -> int:
    """How many force curves an analysis with ``"forces"`` carries at most: each joint's and
    the guide's (a variant's own joints are as many or fewer)."""
    if m.frame is None:
        return 0
    fr = m.frame(frozenset())
    return len(fr.pins) + len(fr.slots) + 1


def loads(
    m: Mechanism,
    variant: frozenset[str],
    f: Model,
    pv: np.ndarray,
    points: Points,
    st: Strokes,
    load: Load,
) -> tuple[Loads, Callable[[np.ndarray], dict[str, np.ndarray]]]:
    """The loads of a design (``pv``: its parameters; ``points``: its stationary points,
    ``roots.stationary_points``; ``st``: its strokes) under ``load``, and its torque and
    forces as functions of crank angles (radians), for curves."""
    sys = forces(m, variant)
    pieces = _pieces(sys, _spans(f, pv, st, load, load.metres), st, load.guide_friction)

    def owner(theta: np.ndarray) -> np.ndarray:  # the piece each angle is in (the first)
        inside = (theta[:, None] - pieces.lo) % TWO_PI <= pieces.hi - pieces.lo
        return cast(np.ndarray, np.argmax(inside, axis=1))

    rows, at, c = points  # a joint's transmission angle 0°: a dead point
    flat = (rows > 0) & (np.abs(c) >= 1 - sys.FLAT)
    sys.dead(at[flat], pieces.pv[owner(at[flat])], [f.names[r - 1] for r in rows[flat]])
    lay = sys.layout
    pushes = [_magnitude([lay.pin(j), lay.pin(j) + 1]) for j in range(len(lay.pins))]
    pushes += [_magnitude([lay.slot(j)]) for j in range(len(lay.slots))]
    pushes.append(_magnitude([lay.size - 1]))
    *found_all, (x, v) = _extremes(sys, pieces, [*pushes, _torque], len(pushes))  # maxima
    total, squares = pieces.integrals()[1].sum(axis=1)
    mean = float(total / TWO_PI)
    k_hi, k_lo = int(np.argmax(v)), int(np.argmin(v))
    rms = math.sqrt(squares / TWO_PI)
    t = Torque(float(v[k_hi]), _deg(x[k_hi]), float(v[k_lo]), _deg(x[k_lo]), mean, rms)
    energy = _energy(pieces, mean)
    om, rated = load.omega, mean * load.omega / load.efficiency  # ω, Cs, η > 0 (``Load``)
    power = Power(mean * om, t.max * om, rated, load.motor_torque(rated))
    inertia = load.inertia(energy)
    flywheel = Flywheel(energy, inertia, load.flywheel_speed, load.disc(inertia))
    largest = [Force(float(v.max()), _deg(x[int(np.argmax(v))])) for x, v in found_all]
    joints = dict(zip((*lay.pins, *lay.slots), largest[:-1], strict=True))
    quantities = [_torque, *pushes]

    def curves(theta: np.ndarray) -> dict[str, np.ndarray]:
        """The torque and each force (``Loads``' names, the guide's last) at each crank angle,
        from the piece it lies in (the earlier piece's at a piece's end)."""
        z = pieces(theta, owner(theta))
        out = [q(z)[0] for q in quantities]
        return dict(zip(("torque", *joints, "guide"), out, strict=True))

    return Loads(t, power, flywheel, joints, largest[-1]), curves


@dataclass(frozen=True)
class _Span:
    """A span [lo, hi] of the turn (radians) where the resisting force is one linear function
    of the ram's position: between two points of the load's profile (``segment``: their
    fractions and forces), or the rest of the turn (None, no force); ``pv``: the design's
    parameters and the load's but the friction, the last (``kinetics.LOAD``)."""

    lo: float
    hi: float
    pv: np.ndarray
    segment: tuple[float, float, float, float] | None


def _spans(f: Model, pv: np.ndarray, st: Strokes, load: Load, metres: float) -> list[_Span]:
    """The turn's spans (``_Span``) for a design's parameters ``pv`` (its lengths are
    ``metres`` each) and strokes ``st``. The profile's points' crank angles are roots of
    s − level inside the working stroke, its dead centres at its ends; each segment's force
    resists the ram (against its travel in the working stroke), linear in its position:
    F = F0 + (F1 − F0)(s − s0)/(s1 − s0) between its points' positions."""
    profile = np.array(load.profile)
    fractions = profile[:, 0]
    inner = (fractions > 0) & (fractions < 1)
    at = np.where(fractions == 0, st.start, st.start + st.working)
    at[inner] = reached(f, pv, st, fractions[inner])
    sign = math.copysign(1.0, st.s1 - st.s0)
    travel = (st.s1 - st.s0) * metres  # the working stroke, m, signed
    out = []
    for (u0, f0), (u1, f1), lo, hi in zip(profile[:-1], profile[1:], at[:-1], at[1:], strict=True):
        slope = (f1 - f0) / ((u1 - u0) * travel)  # N per metre of s
        level = (st.s0 * metres) + u0 * travel  # s at the segment's start, m
        w = kinetics.numbers(load, metres, -sign * (f0 - slope * level), -sign * slope)
        out.append(_Span(float(lo), float(hi), np.concatenate([pv, w[:-1]]), (u0, f0, u1, f1)))
    rest = np.concatenate([pv, kinetics.numbers(load, metres)[:-1]])
    out.append(_Span(float(at[-1]), float(at[0]) + TWO_PI, rest, None))
    return out


def peak_terms(
    m: Mechanism,
    variant: frozenset[str],
    f: Model,
    pv: np.ndarray,
    st: Strokes,
    load: Load,
    metres: float,
) -> tuple[np.ndarray, np.ndarray]:
    """The values whose largest is the peak torque (N·m): the torque at each of its maxima on
    each span and at each span's ends (from its side), for a design whose lengths are
    ``metres`` each; and their derivatives in the type's parameters (rows: terms): at a
    maximum the partial derivative (the envelope theorem), at a piece's end the torque's
    change with its angle too (the implicit function theorem on s − level at a profile's
    point, on s′ at a dead centre, on the guide's force N where friction's sign changes);
    a segment's force depends on the stroke's dead centres' positions."""
    sys: Forces | Torques = forces(m, variant) if load.guide_friction else torques(m, variant)
    k, guide = len(m.parameters), sys.n - 1
    spans = _spans(f, pv, st, load, metres)
    # the stroke's dead centres and the profile's points inside it (their fractions): s, its
    # θ-derivatives and ∂s/∂p there, in one evaluation each
    inner = {
        a: u
        for span in spans
        for a, u in zip((span.lo, span.hi), _end_fractions(span, load), strict=True)
        if 0 < u < 1
    }
    at = np.array([st.start, st.start + st.working, *inner])
    kd, g = f.dp(at, pv), f(at, pv)  # kd: (angle, [rows; θ-derivatives], parameter)
    nr = kd.shape[1] // 2
    ds0, ds1 = kd[0, 0], kd[1, 0]
    dt_dead = -kd[:2, nr] / g[2][0][:2, None]  # s′(θ, p) = 0 there
    # s(θ, p) = s0 + u (s1 − s0) at the profile's points: each one's dθ/dp
    dt_inner = {
        a: (ds0 + u * (ds1 - ds0) - kd[i, 0]) / g[1][0][i]
        for i, (a, u) in enumerate(inner.items(), start=2)
    }
    sign = math.copysign(1.0, st.s1 - st.s0)
    force_at = k + kinetics.LOAD.index("force")
    moving = np.zeros((len(spans), 2, k))  # d(force, slope)/dp: moving with the dead centres
    for i, span in enumerate(spans):
        if span.segment is not None:
            u0, f0, u1, f1 = span.segment
            travel = (st.s1 - st.s0) * metres
            slope = (f1 - f0) / ((u1 - u0) * travel)
            level = st.s0 * metres + u0 * travel
            d_travel = metres * (ds1 - ds0)
            d_raw = -slope * d_travel / travel
            moving[i, 0] = sign * (d_raw * level + slope * (metres * ds0 + u0 * d_travel))
            moving[i, 1] = -sign * d_raw
    pieces = _pieces(sys, spans, st, load.guide_friction)
    ((x, owner),) = pieces.roots([_torque], 1, falling=1, polisher=sys.polish)
    n, found = len(pieces.pieces), x.size
    x = np.concatenate([x, pieces.lo, pieces.hi])
    owner = np.concatenate([owner, np.arange(n), np.arange(n)])
    z = pieces(x, owner, order=1)
    # d(T, N)/dp at fixed angles, the force's parameters moving too
    dz = sys.dp(x, pieces.pv[owner])[:, [0, guide]]  # (angle, T and N, pv)
    d_load = moving[[pieces.pieces[o].span for o in owner]]
    both = (
        dz[..., :k]
        + dz[..., force_at, None] * d_load[:, None, 0]
        + dz[..., force_at + 1, None] * d_load[:, None, 1]
    )
    grad, d_guide = both[:, 0], both[:, 1]
    for j in range(found, x.size):
        end, span = x[j], spans[pieces.pieces[owner[j]].span]
        turn = (end - st.start) % TWO_PI
        if end in (span.lo, span.hi):  # a profile's point
            u = _end_fractions(span, load)[0 if end == span.lo else 1]
            dt = dt_dead[int(u)] if u in (0.0, 1.0) else dt_inner[end]
        elif min(turn, TWO_PI - turn, abs(turn - st.working)) < 1e-9:  # a dead centre
            dt = dt_dead[int(abs(turn - st.working) < 1e-9)]
        else:  # where the guide's force changes sign: N(θ, p) = 0
            dt = -d_guide[j] / z[1, j, guide]
        grad[j] += z[1, j, 0] * dt
    return z[0, :, 0], grad


def _end_fractions(span: _Span, load: Load) -> tuple[float, float]:
    """The fractions of the working stroke at a span's ends: its segment's, or the profile's."""
    if span.segment is not None:
        return span.segment[0], span.segment[2]
    profile = load.profile
    return profile[-1][0], profile[0][0]


def _pieces(sys: Forces | Torques, spans: list[_Span], st: Strokes, mu: float) -> Pieces:
    """The spans as pieces on which everything is smooth: themselves, without the guide's
    friction (``mu`` 0; ``sys`` may be ``Torques``); with it (``Forces``), their parts on
    which the friction, −μ |N| sign(v), is one multiple of N (``kinetics``): split at the dead
    centres, where the ram turns, and where N changes sign (there N = 0 whichever sign is
    assumed, so the roots of N with one sign assumed are the changes), each part taking the
    sign of N that its middle is consistent with."""
    whole = [Piece(s.lo, s.hi, np.append(s.pv, 0.0), i) for i, s in enumerate(spans)]
    if mu == 0:
        return Pieces(sys, whole)
    assert isinstance(sys, Forces)
    sys.lock(np.append(spans[-1].pv, 0.0), mu)  # the design's ram leans past atan μ: refused
    turns = TWO_PI * np.arange(-1, 3)
    dead = np.concatenate([st.start + turns, st.start + st.working + turns])
    up = math.copysign(1.0, st.s1 - st.s0)  # sign(v) in the working stroke
    parts, signs = [], []  # N > 0 assumed
    for i, span in enumerate(spans):
        inner = dead[(dead > span.lo) & (dead < span.hi)]
        for a, b in itertools.pairwise(np.sort(np.concatenate([[span.lo, span.hi], inner]))):
            working = (0.5 * (a + b) - st.start) % TWO_PI < st.working
            v = up if working else -up
            parts.append(Piece(a, b, np.append(span.pv, -mu * v), i))
            signs.append(v)
    pushing = Pieces(sys, parts)
    ((changes, at),) = pushing.roots([_guide], 0)
    tiny = 1e-12 * pushing.largest(pushing.z[0])  # a guide force 0 to rounding
    cut = [
        (j, c, d)
        for j, p in enumerate(parts)
        for c, d in itertools.pairwise([p.lo, *np.sort(changes[at == j]), p.hi])
    ]
    mid = np.array([0.5 * (c + d) for _, c, d in cut])
    owner = np.array([j for j, _, _ in cut])
    pulled = _guide(pushing(mid, owner, 0))[0] < -tiny[owner]
    if not pulled.any() and len(cut) == len(parts):
        return pushing
    out = [Piece(c, d, parts[j].pv, parts[j].span) for j, c, d in cut]
    for j in np.nonzero(pulled)[0]:  # N < 0
        p = out[j]
        out[j] = Piece(p.lo, p.hi, np.append(p.pv[:-1], mu * signs[owner[j]]), p.span)
    return Pieces(sys, out)  # one sign of N consistent everywhere: the ram does not lock


def _guide(z: np.ndarray) -> np.ndarray:
    return z[:, :, -1]


def _energy(pieces: Pieces, mean: float) -> float:
    """The largest swing of E(θ) = ∫ (T − mean) dθ over a turn (J): its extremes lie where T
    crosses its mean, or steps across it at a piece's end. E at the panels' edges from the
    pieces' integrals, and on from an edge to each crossing by a short quadrature."""

    def excess(z: np.ndarray) -> np.ndarray:
        return cast(np.ndarray, _torque(z) - np.array([mean, 0.0, 0.0])[:, None])

    all_edges, sums = pieces.integrals()
    ((crossings, owner),) = pieces.roots([excess], 0)
    widths = np.concatenate([np.diff(e) for e in all_edges])
    at_edges = np.concatenate([[0.0], np.cumsum(sums[0] - mean * widths)])
    first = np.cumsum([0] + [e.size - 1 for e in all_edges])  # each piece's first panel
    edges = np.concatenate([e[:-1] for e in all_edges])
    at = [np.searchsorted(all_edges[o], x) - 1 for x, o in zip(crossings, owner, strict=True)]
    k = first[owner] + np.clip(at, 0, first[owner + 1] - first[owner] - 1).astype(int)
    partial = pieces.gauss(edges[k], crossings, owner, 1)[0, 0] - mean * (crossings - edges[k])
    values = np.concatenate([at_edges, at_edges[k] + partial])
    return float(values.max() - values.min())


def _deg(x: float) -> float:
    return float(np.degrees(x % TWO_PI))
