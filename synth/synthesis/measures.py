"""What the certified search (``certify``) bounds, per objective's terms: a design's measure
at points of a variant's space (floats, many at once) and a rigorous lower bound of it over
boxes of the space (``numerics.interval``'s centred enclosures, compiled).

Both come from the type's position s(θ, u) and its θ-derivatives (``Kinematics``):

- ``acceleration`` (``min_peak_acceleration``): max over the turn of |s″|. For any angles
  θⱼ, every u in a box U has max_θ |s″| ≥ maxⱼ inf_U |s″(θⱼ, ·)|; the angles are the centre's
  peaks, where the bound is tight;
- ``speed`` (``uniform_cutting_speed``): max |s′| over the middle 80% of the working stroke
  (by travel) times that window's crank travel over 80% of the stroke. Over a box, each
  angle where the window starts or ends, and each dead centre, is enclosed in an interval
  proved to hold it for every u (the sign of s′ or of s − level differs, for every u, at
  its ends: the design's motion has one dead centre of each kind, so that root is the
  one); the stroke's and the levels' intervals follow from s over the dead centres'. Every
  angle θⱼ between the window's start interval and its end interval is in every window, and
  G(u) = |s′(θⱼ, u)| (θb − θa)/(0.8 S) is at most the measure. The bound is the better of
  G at the box's centre less its gradient's enclosure over the box times the half-widths
  (the angles moving by the implicit function theorem over their proved intervals: O(h²)
  at a smooth optimum), and the factors' own bounds (inf_U |s′(θⱼ, ·)|, the gap between the
  window's intervals, the top of the stroke's: O(h), better on a wide box). A box where a
  proof fails gets the bound 0 (it is cut further).

A design that is not one (no two dead centres on the grid) measures ∞.
"""

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

GRID = 128  # angles that bracket a design's dead centres, window ends and peaks
PEAKS = 3  # the largest local peaks at a box's centre at which its bound is taken
NEWTON = 6  # Newton steps that polish an angle
SLACK = 2.0  # a proved interval's half-width: this many times the first-order estimate
# and at least this (radians): at a dead centre, where s′ is ~ s″ δ and the enclosures' rounding
# ~1e-13, wide enough to tell its sign (s there moves by s″ δ²/2 only); at a window's end,
# where s − level moves by s′ δ, narrow (the window's travel loses 2 δ)
DEAD, CROSSING = 1e-7, 2e-12
TAU = 2 * math.pi


class Kinematics:
    """A variant's space compiled: s and its first four θ-derivatives, and the u-derivatives
    of s and s′, at many (angle, point) pairs (``rows``, ``du``); s, s′ and s″ enclosed over
    boxes of (θ, u) (``position``, ``velocity``, ``acceleration``: centred in θ and u), and
    the speed window's gradient (``window``: naive)."""

    def __init__(self, m: Mechanism, variant: frozenset[str], sp: Space, name: str) -> None:
        th = ca.SX.sym("theta")
        u, k = ca.SX.sym("u", len(sp.lo)), ca.SX.sym("k", len(sp.constants))
        p = design(m, variant, sp, u, k)
        d = [m.position(p, th)]
        for _ in range(4):
            d.append(ca.jacobian(d[-1], th))

        def fn(what: str, out: Any) -> ca.Function:
            return ca.Function(f"{name}_{what}", [th, u, k], [out], {"cse": True})

        self.rows = Mapped(fn("rows", ca.vertcat(*d)), (False, False, True), looped=(WIDEST,))
        du = ca.densify(ca.jacobian(ca.vertcat(d[0], d[1]), u))  # (2, len(u))
        self.du = Mapped(fn("du", ca.vec(du.T)), (False, False, True))
        self.window = CompiledInterval(window(m, p, th, u, k, name))
        self.position, self.velocity, self.acceleration = (
            CompiledCentred(fn(what, d[i]), wrt=[0, 1], continuous=True)
            for i, what in enumerate(("position", "velocity", "acceleration"))
        )

    def libraries(self) -> list[Any]:
        """Each enclosure's compiled library (None: not built)."""
        return [f.library for f in (self.position, self.velocity, self.acceleration, self.window)]

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


def window(m: Mechanism, p: Any, th: Any, u: Any, k: Any, name: str) -> ca.Function:
    """The derivative in u, along the design, of G = |s′(θⱼ)| (θb − θa) / ((1 − 2 ``CUT``)
    |s(θ1) − s(θ0)|), the speed fluctuation's bound by the speed at θⱼ (in the window
    [θa, θb] of the stroke from the dead centre θ0 to θ1), as a function of (θⱼ, θa, θb, θ0,
    θ1, u, k): θ0 and θ1 move as dead centres (s′ = 0), θa and θb as the window's ends (s =
    its levels), by the implicit function theorem (∂s0/∂u at a dead centre is ∂s/∂u there)."""
    s = m.position(p, th)
    v = ca.jacobian(s, th)
    rows = ca.vertcat(s, v, ca.jacobian(v, th))
    grad = ca.jacobian(ca.vertcat(s, v), u)
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
    moves[3], moves[4] = (-x[4] / x[2] for x in (s0, s1))
    for i, (e, f) in ((1, (a, CUT)), (2, (b, 1 - CUT))):
        dlevel = s0[3] + f * (s1[3] - s0[3])
        moves[i] = -(e[3] - dlevel) / e[1]
    total = ca.jacobian(g, u) + ca.jacobian(g, angles) @ ca.vertcat(*moves)
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


def least_abs(bounds: tuple[np.ndarray, np.ndarray]) -> np.ndarray:
    """inf |f| of each enclosure (0 where it may pass 0; NaN: 0)."""
    out: np.ndarray = np.fmax(np.fmax(bounds[0], -bounds[1]), 0.0)
    return out


def local_peaks(
    v: np.ndarray, count: int, where: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """The grid indices of each row's ``count`` largest local maxima of v ≥ 0 (rows), among
    ``where``'s (cyclic neighbours), and whether each is one (a row may have fewer)."""
    local = (v >= np.roll(v, 1, axis=1)) & (v >= np.roll(v, -1, axis=1))
    if where is not None:
        local &= where
    order = np.argsort(-np.where(local, v, -1.0), axis=1, kind="stable")[:, :count]
    return order, np.take_along_axis(local, order, axis=1)


class Acceleration:
    """The peak |s″| over the turn (``min_peak_acceleration``)."""

    @staticmethod
    def measure(kin: Kinematics, points: np.ndarray, k: np.ndarray) -> tuple[Any, Any]:
        """The measure at each point, and its ``PEAKS`` largest peaks' angles (rows)."""
        grid = np.tile(np.arange(GRID) * (TAU / GRID), (len(points), 1))
        v = np.abs(kin.at(grid, points, k)[2])
        theta = np.take_along_axis(grid, local_peaks(v, PEAKS)[0], axis=1)
        theta = kin.newton(theta, points, k, 3)
        w = np.abs(kin.at(theta, points, k)[2])
        return np.maximum(w.max(axis=1), v.max(axis=1)), theta

    @staticmethod
    def lower(kin: Kinematics, lo: Any, hi: Any, angles: Any, k: np.ndarray) -> np.ndarray:
        """maxⱼ inf_U |s″(θⱼ, ·)| of each box, at its centre's peak angles."""
        out: np.ndarray = least_abs(enclose(kin.acceleration, (angles, angles), lo, hi, k))
        return out.max(axis=1)  # type: ignore[no-any-return]


class Speed:
    """The speed fluctuation over the middle of the working stroke (``uniform_cutting_speed``):
    max |s′| over the window where the slider has run ``CUT`` to 1 − ``CUT`` of the working
    stroke's travel, times the window's crank travel over (1 − 2 ``CUT``) × the stroke."""

    @staticmethod
    def measure(kin: Kinematics, points: np.ndarray, k: np.ndarray) -> tuple[Any, Any]:
        """The measure at each point, and what its bound takes (``lower``)."""
        info = strokes(kin, points, k, (CUT, 1 - CUT))
        v, unwrapped, window = info["rows"][1], info["unwrapped"], info["window"]
        a, b, s0, s1 = info["ends"][:, :1], info["ends"][:, 1:], info["s0"], info["s1"]
        speed = np.abs(v)
        idx, real = local_peaks(speed, PEAKS, window)
        peaks = kin.newton(np.take_along_axis(unwrapped, idx, axis=1), points, k, 2)
        real &= (peaks > a) & (peaks < b)
        vp = np.where(real, np.abs(kin.at(peaks, points, k)[1]), 0.0)
        ve = np.abs(kin.at(info["ends"], points, k)[1])
        with np.errstate(all="ignore"):
            value = np.maximum(vp.max(axis=1), ve.max(axis=1)) * (b - a)[:, 0]
            value /= (1 - 2 * CUT) * np.abs(s1 - s0)
        value[~(info["ok"] & np.isfinite(value))] = math.inf
        info["peaks"] = np.where(real, peaks, np.nan)
        return value, info

    @staticmethod
    def lower(kin: Kinematics, lo: Any, hi: Any, info: Any, k: np.ndarray) -> np.ndarray:
        """The bound of each box from its centre's dead centres, window ends and peaks (see
        the module's docstring); 0 where a proof fails."""
        c, half = 0.5 * (lo + hi), 0.5 * (hi - lo)
        proved, dead, ends, stroke = prove(kin, lo, hi, info, k)
        at_c, _, ends_c, stroke_c = prove(kin, c, c, info, k)  # tight, about the centre's own
        core = ends[1][:, :1], ends[0][:, 1:]  # in every window of the box
        peaks = info["peaks"]
        inner = np.where((peaks > core[0]) & (peaks < core[1]), peaks, core[0])
        angles = np.hstack([core[0], core[1], inner])
        n, per = angles.shape
        order = np.where(info["slow_up"][:, None], [[0, 1]], [[1, 0]])  # start, end

        def enclosed(ivals: list[tuple[np.ndarray, np.ndarray]], a: Any, b: Any) -> Any:
            """The gradient of the window's bound over the angles' intervals and the box."""
            lo_in = [angles.reshape(-1, 1)] + [np.repeat(x[0], per, axis=0) for x in ivals]
            hi_in = [angles.reshape(-1, 1)] + [np.repeat(x[1], per, axis=0) for x in ivals]
            return kin.window([*lo_in, np.repeat(a, per, 0), k], [*hi_in, np.repeat(b, per, 0), k])

        def parts(d: Any, e: Any) -> list[tuple[np.ndarray, np.ndarray]]:
            start = [np.take_along_axis(x, order, 1) for x in d]
            return [(e[0][:, i : i + 1], e[1][:, i : i + 1]) for i in (0, 1)] + [
                (start[0][:, i : i + 1], start[1][:, i : i + 1]) for i in (0, 1)
            ]

        slope = enclosed(parts(dead, ends), lo, hi)
        # G at the centre, from intervals about its own angles (a few 1e-12 wide)
        speed = least_abs(enclose(kin.velocity, (angles, angles), c, c, k))
        travel = ends_c[0][:, 1:] - ends_c[1][:, :1]
        with np.errstate(all="ignore"):
            g = speed * travel / ((1 - 2 * CUT) * stroke_c[:, None]) * (1 - 1e-14)
        steep = np.maximum(np.abs(slope.lo[0]), np.abs(slope.hi[0])).reshape(n, per, -1)
        with np.errstate(all="ignore"):
            out = g - np.sum(steep * half[:, None, :], axis=2)
        out = np.where(np.isfinite(out), out, 0.0).max(axis=1)
        # on a wide box the gradient's enclosure is loose: each factor's own bound may do
        # better (the least speed, the least travel, the greatest stroke; first order)
        least = least_abs(enclose(kin.velocity, (angles, angles), lo, hi, k)).max(axis=1)
        with np.errstate(all="ignore"):
            plain = least * (core[1] - core[0])[:, 0] / ((1 - 2 * CUT) * stroke) * (1 - 1e-14)
        out = np.maximum(out, np.where(np.isfinite(plain), plain, 0.0))
        return np.where(proved & at_c & (core[1][:, 0] > core[0][:, 0]), np.maximum(out, 0), 0.0)


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
    dead = kin.newton(guess + half, points, k, 1)
    sd = kin.at(dead, points, k)[0]
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
    where s − level does, the levels enclosed from s over the dead centres' intervals (at
    least ``CROSSING``).
    Returns (proved, (dead lower, dead upper), (ends lower, ends upper)), (n, 2) each, and
    the stroke's greatest (n)."""
    n, d = lo.shape
    c, half = 0.5 * (lo + hi), 0.5 * (hi - lo)
    dead, ends, slow_up = info["dead"], info["ends"], info["slow_up"]
    sign = np.where(slow_up, 1.0, -1.0)[:, None]
    at = kin.at(dead, c, k)
    du = kin.du(dead.reshape(-1, 1), np.repeat(c, 2, axis=0), k).reshape(2 * d, n, 2)
    ds, dv = du[:d], du[d:]
    with np.errstate(all="ignore"):
        move = np.sum(np.abs(dv / at[2]) * half.T[:, :, None], axis=0)
        # s is stationary there: a wider interval costs its enclosure only ~ s″ wide², and
        # the sign of s′ at its ends must outgrow the enclosure's excess, O(half-width²)
        wide = SLACK * move + DEAD + half.sum(axis=1)[:, None]
    before = enclose(kin.velocity, (dead - wide,) * 2, lo, hi, k)
    after = enclose(kin.velocity, (dead + wide,) * 2, lo, hi, k)
    # the least s: s′ from − to +; the greatest: from + to −
    proved = (before[1][:, 0] < 0) & (after[0][:, 0] > 0)
    proved &= (before[0][:, 1] > 0) & (after[1][:, 1] < 0)
    s_lo, s_hi = enclose(kin.position, (dead - wide, dead + wide), lo, hi, k)
    pick = np.where(slow_up[:, None], [[0, 1]], [[1, 0]])  # the stroke's start, end
    s0 = np.take_along_axis(s_lo, pick, 1)[:, 0], np.take_along_axis(s_hi, pick, 1)[:, 0]
    s1 = np.take_along_axis(s_lo, pick, 1)[:, 1], np.take_along_axis(s_hi, pick, 1)[:, 1]
    fractions = info["fractions"]
    with np.errstate(invalid="ignore"):  # 0 × an unbounded end's ∞, at a fraction 0 or 1
        low = [(1 - f) * s0[0] + f * s1[0] for f in fractions]
        high = [(1 - f) * s0[1] + f * s1[1] for f in fractions]
    level = np.nextafter(np.stack(low, 1), -np.inf), np.nextafter(np.stack(high, 1), np.inf)
    # the window's ends: dθ/du = −(∂s/∂u − ∂level/∂u)/s′ (∂s0/∂u: ∂s/∂u at its dead centre),
    # and the levels' own width
    ae = kin.at(ends, c, k)
    de = kin.du(ends.reshape(-1, 1), np.repeat(c, 2, axis=0), k).reshape(2 * d, n, 2)[:d]
    d0 = np.take_along_axis(ds, pick[None].repeat(d, 0), 2)
    dlevel = np.stack([(1 - f) * d0[:, :, 0] + f * d0[:, :, 1] for f in fractions], 2)
    with np.errstate(all="ignore"):
        slope = np.abs(ae[1])
        move = np.sum(np.abs(de - dlevel) * half.T[:, :, None], axis=0) / slope
        reach = SLACK * (move + (level[1] - level[0]) / slope) + CROSSING
    # an end at a fraction 0 or 1 is that dead centre: its interval is the dead centre's
    edge = np.array([f in (0.0, 1.0) for f in fractions])
    start_wide = np.where(slow_up, wide[:, 0], wide[:, 1])
    end_wide = np.where(slow_up, wide[:, 1], wide[:, 0])
    reach = np.where(edge, np.stack([end_wide if f else start_wide for f in fractions], 1), reach)
    p_before = enclose(kin.position, (ends - reach,) * 2, lo, hi, k)
    p_after = enclose(kin.position, (ends + reach,) * 2, lo, hi, k)
    below = np.where(sign > 0, p_before[1] < level[0], p_before[0] > level[1])
    above = np.where(sign > 0, p_after[0] > level[1], p_after[1] < level[0])
    proved &= np.all(below & above | edge, axis=1)
    # both inside the working stroke, clear of its dead centres' intervals (but an edge's own)
    first, last = ends[:, 0] - reach[:, 0], ends[:, 1] + reach[:, 1]
    proved &= edge[0] | (info["start"] + start_wide < first)
    proved &= (first < last) & (edge[1] | (last < info["start"] + info["working"] - end_wide))
    stroke = np.nextafter(s_hi[:, 1] - s_lo[:, 0], np.inf)
    return proved, (dead - wide, dead + wide), (ends - reach, ends + reach), stroke
