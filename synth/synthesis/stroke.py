"""A variant's space compiled for the certified search (``certify``): the type's position
s(θ, u) and its θ-derivatives at many (angle, point) pairs, and enclosed over boxes of (θ, u)
(``Kinematics``); each design's working stroke (``strokes``: its dead centres, where the
slider has run given fractions of its travel), and intervals that hold those angles for every
design of a box (``prove``).

A dead centre's interval is proved by the sign of s′ at its ends, or is the space's own angle
where no design of the space moves it (``Space.dead``). A window end's is proved by the sign
of s − level at its ends (the level a fraction of the way from s at the stroke's start to s
at its end), enclosed as one function of the angle, u and the dead centres' angles over their
intervals: s and the level move alike with u, and s at a dead centre hardly moves with its
angle (s′ = 0 there), so the enclosure is as tight as s − level is. Its first width is twice the
first-order estimate of how far the end moves over the box; where that is not proved it is
widened ``GROW``-fold, up to ``REACHES`` times (a wider interval is still one that holds the
end, and the measures' bounds only lose some tightness)."""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import casadi as ca
import numpy as np

from ..analysis.quality import CUT
from ..mechanisms import Mechanism
from ..mechanisms.reduced import Space
from ..numerics.compiled_interval import CompiledCentred, CompiledInterval
from ..numerics.native import WIDEST, Mapped
from ..numerics.symbolic import forward

GRID = 128  # angles that bracket a design's dead centres, window ends and peaks
PEAKS = 3  # the largest local peaks at a box's centre at which its bound is taken
NEWTON = 6  # Newton steps that polish an angle
SLACK = 2.0  # a proved interval's half-width: this many times the first-order estimate
# and at least this (radians): at a dead centre, where s′ is ~ s″ δ and the enclosures' rounding
# ~1e-13, wide enough to tell its sign (s there moves by s″ δ²/2 only); at a window's end,
# where s − level moves by s′ δ, narrow (the window's travel loses 2 δ)
DEAD, CROSSING = 1e-7, 2e-12
GROW, REACHES = 3.0, 6
TAU = 2 * math.pi
EPS = float(np.finfo(float).eps)


class Kinematics:
    """A variant's space compiled: s and its first four θ-derivatives, and the u-derivatives
    of s and s′, at many (angle, point) pairs (``rows``, ``du``); s, s′ and s″ enclosed over
    boxes of (θ, u) (``position``, ``velocity``, ``acceleration``: centred in θ and u), s −
    level with the dead centres' angles as inputs (``past``, centred), the speed window's
    gradient (``window``: naive), and the space's dead centres where u does not move them
    (``dead``, ``Space.dead``)."""

    def __init__(self, m: Mechanism, variant: frozenset[str], sp: Space, name: str) -> None:
        th = ca.SX.sym("theta")
        u, k = ca.SX.sym("u", len(sp.lo)), ca.SX.sym("k", len(sp.constants))
        p = design(m, variant, sp, u, k)
        d = [m.position(p, th)]
        for _ in range(4):
            d.append(forward(d[-1], th))

        def fn(what: str, out: Any) -> ca.Function:
            return ca.Function(f"{name}_{what}", [th, u, k], [out], {"cse": True})

        self.rows = Mapped(fn("rows", ca.vertcat(*d)), (False, False, True), looped=(WIDEST,))
        du = ca.densify(ca.jacobian(ca.vertcat(d[0], d[1]), u))  # (2, len(u))
        self.du = Mapped(fn("du", ca.vec(du.T)), (False, False, True))
        self.dead = sp.dead  # the dead centres' angles, where u does not move them
        self.window = CompiledInterval(window(m, p, th, u, k, name, sp.dead is None))
        # s − level: s(θ) − (1 − f) s(θ0) − f s(θ1), the level f of the way from s(θ0) to s(θ1)
        ends, f = ca.SX.sym("ends", 2), ca.SX.sym("f")
        past = (
            d[0] - (1 - f) * ca.substitute(d[0], th, ends[0]) - f * ca.substitute(d[0], th, ends[1])
        )
        self.past = CompiledCentred(
            ca.Function(f"{name}_past", [th, ends, f, u, k], [past], {"cse": True}),
            wrt=[0, 1, 3],
            continuous=True,
        )
        self.position, self.velocity, self.acceleration = (
            CompiledCentred(fn(what, d[i]), wrt=[0, 1], continuous=True)
            for i, what in enumerate(("position", "velocity", "acceleration"))
        )

    def libraries(self) -> list[Any]:
        """Each enclosure's compiled library (None: not built)."""
        kept = (self.position, self.velocity, self.acceleration, self.window, self.past)
        return [f.library for f in kept]

    def at(self, theta: np.ndarray, points: np.ndarray, k: np.ndarray) -> np.ndarray:
        """The rows (s, s′, s″, s‴, s⁗) at each angle of ``theta`` (n, m), each row of
        ``points`` (n, …) its design: shape (5, n, m)."""
        n, per = theta.shape
        r = self.rows(theta.reshape(-1, 1), np.repeat(points, per, axis=0), k)
        return r.reshape(5, n, per)

    def newton(
        self, theta: np.ndarray, points: np.ndarray, k: np.ndarray, row: int, level: Any = 0.0
    ) -> np.ndarray:
        """Angles (n, m) moved towards rows[row] = level (each point's): ``newton``."""
        return newton(lambda t: self.at(t, points, k), theta, row, level)


def newton(
    rows: Callable[[np.ndarray], np.ndarray], theta: np.ndarray, row: int, level: Any = 0.0
) -> np.ndarray:
    """Angles moved towards ``rows(θ)[row]`` = level by ``NEWTON`` steps on that row and the
    next (its derivative in θ); a step that does not stay small is not taken."""
    for _ in range(NEWTON):
        r = rows(theta)
        with np.errstate(all="ignore"):
            step = (r[row] - level) / r[row + 1]
        theta = np.where(np.abs(step) < 0.1, theta - step, theta)
    return theta


def design(m: Mechanism, variant: frozenset[str], sp: Space, u: Any, k: Any) -> dict[str, Any]:
    """Every parameter of the variant's design at the space's (u, k), CasADi symbols: the
    space's, 0 for the parts the variant leaves out, the type's defaults for the rest."""
    p = {**dict.fromkeys(variant, 0.0), **sp.design(u, k)}
    p.update({n: x for n, x in m.defaults(p).items() if n not in p})
    return p


def window(
    m: Mechanism, p: Any, th: Any, u: Any, k: Any, name: str, moving: bool = True
) -> ca.Function:
    """The derivative in u, along the design, of G = |s′(θⱼ)| (θb − θa) / ((1 − 2 ``CUT``)
    |s(θ1) − s(θ0)|), the speed fluctuation's bound by the speed at θⱼ (in the window
    [θa, θb] of the stroke from the dead centre θ0 to θ1), as a function of (θⱼ, θa, θb, θ0,
    θ1, u, k): θ0 and θ1 move as dead centres (s′ = 0; unless not ``moving``: the space's
    own), θa and θb as the window's ends (s = its levels), by the implicit function theorem
    (∂s0/∂u at a dead centre is ∂s/∂u there)."""
    s = m.position(p, th)
    v = forward(s, th)
    rows = ca.vertcat(s, v, forward(v, th))
    grad = forward(ca.vertcat(s, v), u)
    angles = ca.SX.sym("angles", 5)  # θⱼ, θa, θb, θ0, θ1
    at = [ca.substitute(ca.vertcat(rows, ca.vec(grad)), th, angles[i]) for i in range(5)]
    d = u.numel()

    def of(i: int) -> tuple[Any, Any, Any, Any, Any]:  # s, s′, s″, ∂s/∂u, ∂s′/∂u at angle i
        r = at[i]
        ds, dv = ([r[start + 2 * j] for j in range(d)] for start in (3, 4))
        return r[0], r[1], r[2], ca.horzcat(*ds), ca.horzcat(*dv)

    (_, vj, _, _, _), a, b, s0, s1 = (of(i) for i in range(5))
    stroke = s1[0] - s0[0]
    g = ca.fabs(vj) * (angles[2] - angles[1]) / ((1 - 2 * CUT) * ca.fabs(stroke))
    moves: list[Any] = [ca.DM.zeros(1, d)] + [None] * 4
    moves[3], moves[4] = (-x[4] / x[2] if moving else ca.DM.zeros(1, d) for x in (s0, s1))
    for i, (e, f) in ((1, (a, CUT)), (2, (b, 1 - CUT))):
        dlevel = s0[3] + f * (s1[3] - s0[3])
        moves[i] = -(e[3] - dlevel) / e[1]
    total = forward(g, u) + forward(g, angles) @ ca.vertcat(*moves)
    inputs = [ca.SX.sym(x) for x in ("j", "a", "b", "t0", "t1")]
    out = ca.substitute(total, angles, ca.vertcat(*inputs))
    return ca.Function(f"{name}_window", [*inputs, u, k], [out], {"cse": True})


def enclose(
    f: CompiledCentred,
    theta: tuple[np.ndarray, np.ndarray],
    lo: np.ndarray,
    hi: np.ndarray,
    k: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """f over each (angle interval, box): ``theta`` (lower, upper), each (n, m), the boxes'
    (n, …); the enclosures' lower and upper bounds, (n, m) each (NaN: unbounded)."""
    n, per = theta[0].shape
    e = f(
        [theta[0].reshape(-1, 1), np.repeat(lo, per, axis=0), k],
        [theta[1].reshape(-1, 1), np.repeat(hi, per, axis=0), k],
    )
    return e.lo[0][:, 0].reshape(n, per), e.hi[0][:, 0].reshape(n, per)


def _side(
    ends: np.ndarray,
    reach: np.ndarray,
    positive: np.ndarray,
    enclosed: Callable[[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]],
    edge: np.ndarray,
) -> np.ndarray:
    """The offset from each window end (n, 2) to an angle on one side of it where s − level
    is proved of one sign for every u in the box (``positive``: > 0, per box; ``enclosed``:
    s − level over the boxes of some rows, at their angles): ``reach``, grown ``GROW``-fold
    up to ``REACHES`` times where it is not proved (NaN: never); an ``edge`` end's is its
    ``reach``."""
    out = np.where(edge, reach, np.nan)
    todo = ~np.broadcast_to(edge, reach.shape).copy()
    r = reach.copy()
    for _ in range(REACHES):
        rows = np.flatnonzero(todo.any(axis=1))
        if not rows.size:
            break
        e = enclosed(rows, ends[rows] + r[rows])
        good = np.where(positive[rows], e[0] > 0, e[1] < 0) & todo[rows]
        out[rows] = np.where(good, r[rows], out[rows])
        todo[rows] &= ~good
        r = r * GROW
    return out


def past(
    kin: Kinematics,
    theta: np.ndarray,
    dead: tuple[np.ndarray, np.ndarray],
    fractions: tuple[float, ...],
    lo: np.ndarray,
    hi: np.ndarray,
    k: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """s − level over each box at the angles ``theta`` (n, m), the level ``fractions[j]`` of
    the way from s at the stroke's start to s at its end, their angles within ``dead`` (lower,
    upper: (n, 2), start and end); the enclosures' lower and upper bounds, (n, m) each."""
    n, per = theta.shape
    f = np.tile(np.array(fractions, dtype=float)[:per], n)[:, None]
    e = kin.past(
        [theta.reshape(-1, 1), np.repeat(dead[0], per, 0), f, np.repeat(lo, per, 0), k],
        [theta.reshape(-1, 1), np.repeat(dead[1], per, 0), f, np.repeat(hi, per, 0), k],
    )
    return e.lo[0][:, 0].reshape(n, per), e.hi[0][:, 0].reshape(n, per)


def strokes(
    kin: Kinematics, points: np.ndarray, k: np.ndarray, fractions: tuple[float, float]
) -> dict[str, Any]:
    """Each point's working stroke, on a grid of ``GRID`` angles polished by Newton: its dead
    centres (``dead``: the least s, the greatest), where it starts and how long it lasts
    (``start``, ``working``: crank angles), whether s grows in it (``slow_up``), s at its
    ends (``s0``, ``s1``) and where the slider has run the ``fractions`` of its travel
    (``ends``: unwrapped from ``start``); the grid's angles unwrapped from ``start``, the
    rows there (``rows``), which of them lie between ``ends`` (``window``), and whether the
    point's motion has one dead centre of each kind and both ends (``ok``)."""
    n = len(points)
    grid = np.tile(np.arange(GRID) * (TAU / GRID), (n, 1))
    r = kin.at(grid, points, k)
    s, v = r[0], r[1]
    after = np.roll(v, -1, axis=1)
    up, down = (v < 0) & (after >= 0), (v > 0) & (after <= 0)  # a least s, a greatest
    ok = (up.sum(axis=1) == 1) & (down.sum(axis=1) == 1)
    half = 0.5 * TAU / GRID
    guess = np.stack([grid[0, np.argmax(up, axis=1)], grid[0, np.argmax(down, axis=1)]], 1)
    if kin.dead is None:
        dead = kin.newton(guess + half, points, k, 1)
        sd = kin.at(dead, points, k)[0]
    else:  # the space's, the least s first
        dead = np.tile(np.asarray(kin.dead(k), dtype=float), (n, 1))
        sd = kin.at(dead, points, k)[0]
        first = sd[:, :1] <= sd[:, 1:]
        dead, sd = np.where(first, dead, dead[:, ::-1]), np.where(first, sd, sd[:, ::-1])
    travel = (dead[:, 1] - dead[:, 0]) % TAU  # the crank's, while s goes up
    slow_up = travel >= math.pi
    start = np.where(slow_up, dead[:, 0], dead[:, 1])
    working = np.where(slow_up, travel, TAU - travel)
    s0, s1 = np.where(slow_up, sd[:, 0], sd[:, 1]), np.where(slow_up, sd[:, 1], sd[:, 0])
    levels = s0[:, None] + np.array(fractions) * (s1 - s0)[:, None]
    offset = (grid - start[:, None]) % TAU  # each grid angle's place in the working stroke
    inside = offset < working[:, None]
    with np.errstate(all="ignore"):
        run = (s - s0[:, None]) / (s1 - s0)[:, None]  # the travel run at each grid angle
    first = [
        f * working if f in (0.0, 1.0) else np.min(np.where(inside & (run >= f), offset, np.inf), 1)
        for f in fractions
    ]  # a fraction 0 or 1: the dead centre
    ok &= np.isfinite(first[0]) & np.isfinite(first[1])
    ends = kin.newton(start[:, None] + np.nan_to_num(np.stack(first, 1)), points, k, 0, levels)
    edge = np.array([f in (0.0, 1.0) for f in fractions])
    ends = np.where(edge, start[:, None] + np.stack(first, 1), ends)
    unwrapped = start[:, None] + offset
    window = inside & (unwrapped > ends[:, :1]) & (unwrapped < ends[:, 1:])
    return {
        "dead": dead,
        "ends": ends,
        "slow_up": slow_up,
        "start": start,
        "working": working,
        "s0": s0,
        "s1": s1,
        "rows": r,
        "unwrapped": unwrapped,
        "window": window,
        "ok": ok,
        "fractions": fractions,
    }


def prove(kin: Kinematics, lo: Any, hi: Any, info: Any, k: np.ndarray) -> tuple[Any, Any, Any, Any]:
    """Intervals about the centre's dead centres and window ends (``info``, from ``strokes``:
    the window's ends where the working stroke has run its ``fractions``) that hold each
    box's own for every u in it, and whether each box's are proved: the dead centres' where
    s′ has opposite signs at their ends (its half-width ``SLACK`` times the first-order
    estimate |dθ/du|·half-width, plus ``DEAD`` and the box's half-widths), the window ends'
    where s − level does (``past``, at least ``CROSSING``).
    Returns (proved, (dead lower, dead upper), (ends lower, ends upper)), (n, 2) each, and
    the stroke's greatest (n)."""
    n, d = lo.shape
    c, half = 0.5 * (lo + hi), 0.5 * (hi - lo)
    dead, ends, slow_up = info["dead"], info["ends"], info["slow_up"]
    sign = np.where(slow_up, 1.0, -1.0)[:, None]
    du = kin.du(dead.reshape(-1, 1), np.repeat(c, 2, axis=0), k).reshape(2 * d, n, 2)
    ds, dv = du[:d], du[d:]
    if kin.dead is not None:  # the space's own: a few ulps about them
        wide = np.full((n, 2), 8 * EPS * TAU)
        proved = np.ones(n, dtype=bool)
    else:
        at = kin.at(dead, c, k)
        with np.errstate(all="ignore"):
            move = np.sum(np.abs(dv / at[2]) * half.T[:, :, None], axis=0)
            # s is stationary there: a wider interval costs its enclosure only ~ s″ wide²,
            # and the sign of s′ at its ends must outgrow the enclosure's excess, O(half²)
            wide = SLACK * move + DEAD + half.sum(axis=1)[:, None]
        v0 = enclose(kin.velocity, (dead - wide,) * 2, lo, hi, k)
        v1 = enclose(kin.velocity, (dead + wide,) * 2, lo, hi, k)
        # the least s: s′ from − to +; the greatest: from + to −
        proved = (v0[1][:, 0] < 0) & (v1[0][:, 0] > 0)
        proved &= (v0[0][:, 1] > 0) & (v1[1][:, 1] < 0)
    s_lo, s_hi = enclose(kin.position, (dead - wide, dead + wide), lo, hi, k)
    pick = np.where(slow_up[:, None], [[0, 1]], [[1, 0]])  # the stroke's start, end
    fractions = info["fractions"]
    # the window's ends: dθ/du = −(∂s/∂u − ∂level/∂u)/s′ (∂s0/∂u: ∂s/∂u at its dead centre)
    ae = kin.at(ends, c, k)
    de = kin.du(ends.reshape(-1, 1), np.repeat(c, 2, axis=0), k).reshape(2 * d, n, 2)[:d]
    d0 = np.take_along_axis(ds, pick[None].repeat(d, 0), 2)
    dlevel = np.stack([(1 - f) * d0[:, :, 0] + f * d0[:, :, 1] for f in fractions], 2)
    with np.errstate(all="ignore"):
        slope = np.abs(ae[1])
        move = np.sum(np.abs(de - dlevel) * half.T[:, :, None], axis=0) / slope

    ordered = [np.take_along_axis(x, pick, 1) for x in (dead - wide, dead + wide)]  # start, end

    def enclosed(rows: np.ndarray, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        at = ordered[0][rows], ordered[1][rows]
        return past(kin, theta, at, fractions, lo[rows], hi[rows], k)

    reach = SLACK * move + CROSSING
    # an end at a fraction 0 or 1 is that dead centre: its interval is the dead centre's
    edge = np.array([f in (0.0, 1.0) for f in fractions])
    start_wide = np.where(slow_up, wide[:, 0], wide[:, 1])
    end_wide = np.where(slow_up, wide[:, 1], wide[:, 0])
    reach = np.where(edge, np.stack([end_wide if f else start_wide for f in fractions], 1), reach)
    before = _side(ends, -reach, sign < 0, enclosed, edge)
    after = _side(ends, reach, sign > 0, enclosed, edge)
    proved &= np.all(np.isfinite(before) & np.isfinite(after), axis=1)
    before = np.where(np.isfinite(before), before, -reach)
    after = np.where(np.isfinite(after), after, reach)
    # both inside the working stroke, clear of its dead centres' intervals (but an edge's own)
    first, last = ends[:, 0] + before[:, 0], ends[:, 1] + after[:, 1]
    proved &= edge[0] | (info["start"] + start_wide < first)
    proved &= (first < last) & (edge[1] | (last < info["start"] + info["working"] - end_wide))
    stroke = np.nextafter(s_hi[:, 1] - s_lo[:, 0], np.inf)
    return proved, (dead - wide, dead + wide), (ends + before, ends + after), stroke
