"""Analysis of one design over a crank revolution, generic over the registry.

Each type's position s(θ) and transmission cosines are compiled once per thread into a CasADi
function that also returns their first and second θ-derivatives (automatic differentiation),
built to machine code where a C compiler is at hand (``native``).
Dead centres and transmission extremes are the stationary points of those functions: bracketed
on a grid, then polished by a safeguarded Newton iteration (bisection where Newton leaves the
bracket) to machine precision. Nothing here uses a type's closed forms.
"""

from __future__ import annotations

import functools
import itertools
import math
import sys
import threading
from collections.abc import Mapping, Sequence

import casadi as ca
import numpy as np

from .errors import InvalidDesign, InvalidParameters
from .mechanisms import Mechanism, all_types, get
from .mechanisms._fourbar import grashof_class
from .native import native
from .results import (
    NEAR_DEAD_POINT_DEG,
    NEAR_LIMIT,
    Analysis,
    Conditioning,
    Curves,
    Extreme,
    Joint,
    Stroke,
    Transmission,
)

GRID = 128  # samples per revolution that bracket the stationary points
MAX_CURVE_POINTS = 100_000
TWO_PI = 2 * math.pi
EPS4 = 4 * sys.float_info.epsilon

_local = threading.local()


class Model:
    """A type's kinematics compiled for one variant: rows are s, then each joint's cos μ."""

    def __init__(self, m: Mechanism, variant: frozenset[str]) -> None:
        th = ca.SX.sym("theta")
        pv = ca.SX.sym("p", len(m.parameters))
        p = {q.name: (0.0 if q.name in variant else pv[i]) for i, q in enumerate(m.parameters)}
        joints = m.transmission(p, th)
        g = ca.vertcat(m.position(p, th), *joints.values())
        g1 = ca.jacobian(g, th)
        g2 = ca.jacobian(g1, th)
        self.joints = tuple(joints)
        name = "_".join((m.type, *sorted(variant)))  # one symbol per compiled library
        self.fn = _Batched(f"{name}_kinematics", th, pv, ca.vertcat(g, g1, g2))
        self.dead = None
        if m.dead_centres is not None:
            h = m.dead_centres(p, th)
            self.dead = _Batched(f"{name}_dead_centres", th, pv, ca.vertcat(h, ca.jacobian(h, th)))

    def __call__(self, theta: np.ndarray, pv: np.ndarray) -> tuple[np.ndarray, ...]:
        """g, g', g'' at each θ: arrays of shape (rows, len(θ))."""
        out = self.fn(theta, pv)
        return tuple(out.reshape(3, out.shape[0] // 3, -1))


class _Batched:
    """out(θ, p) compiled, evaluated at each θ of a vector.

    Up to GRID angles go through a buffer preallocated for their number (made on first use,
    owned like the function by one thread's Model): an ordinary call's numpy <-> DM
    conversions cost ~40 µs, more than a few-angle Newton step's evaluation. Common
    subexpressions are merged (the derivatives repeat g's terms): the same operations on the
    same operands, so the same results, from half the instructions."""

    def __init__(self, name: str, th: ca.SX, pv: ca.SX, out: ca.SX) -> None:
        self.fn = native(ca.Function(name, [th, pv], [out], {"cse": True}))
        self.buffers: dict[int, tuple] = {}

    def __call__(self, theta, pv: np.ndarray) -> np.ndarray:
        theta = np.atleast_1d(theta)
        n = theta.size
        if n > GRID:  # curves: the conversions are small against the work
            return self.fn(theta[None, :], pv).full()
        if n not in self.buffers:
            self.buffers[n] = self._buffer(n)
        x, p, out, run, _ = self.buffers[n]
        x[:], p[:] = theta, pv
        run()
        return out.T.copy()  # the buffer is reused by the next call

    def _buffer(self, width: int) -> tuple:
        f = self.fn.map(width, [False, True], [False])
        x, p = np.zeros(width), np.zeros(self.fn.nnz_in(1))
        out = np.zeros((width, self.fn.nnz_out(0)))  # column-major (rows, width)
        buf, run = f.buffer()
        buf.set_arg(0, memoryview(x))
        buf.set_arg(1, memoryview(p))
        buf.set_res(0, memoryview(out))
        return x, p, out, run, buf  # buf holds the bindings run uses


def model(m: Mechanism, variant: frozenset[str]) -> Model:
    """The compiled model, cached per thread: CasADi functions are never shared by threads."""
    cache: dict[tuple[str, frozenset[str]], Model] = _local.__dict__.setdefault("models", {})
    key = (m.type, variant)
    if key not in cache:
        cache[key] = Model(m, variant)
    return cache[key]


def compile_all() -> None:
    """Every type's analysis, in every structural variant, built into the native cache: an
    image's build step (elsewhere each is built on first use). Raises where one cannot be."""
    for mtype in all_types():
        m = get(mtype)
        optional = [q.name for q in m.parameters if q.zero_means]
        for k in range(len(optional) + 1):
            for parts in itertools.combinations(optional, k):
                f = Model(m, frozenset(parts))
                for fn in (f.fn.fn, f.dead and f.dead.fn):
                    if fn is not None and fn.class_name() != "External":
                        raise RuntimeError(f"{fn.name()}: no C compiler or cache (synth.native)")


def stationary_points(
    f: Model, pv: np.ndarray, n: int = GRID
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Every stationary point of every row that changes the sign of its derivative.

    Returns (row, θ, value) arrays. Roots are bracketed on an n-point grid, refined where the
    motion is fast (see ``_refine``), and polished by a vectorised safeguarded Newton
    iteration on g' with g''.
    """
    grid, widths = _grid(n)
    g, g1, g2 = f(grid, pv)
    if not np.all(np.isfinite(g)):
        bad = grid[np.nonzero(~np.all(np.isfinite(g), axis=0))[0][0]]
        msg = f"the design cannot be assembled at crank angle {math.degrees(bad):.6g}°"
        raise InvalidDesign(msg, (), "assembly")
    _refuse_dwell(grid, g1[0])
    grid, widths, g1 = _refine(f, pv, grid, widths, g1, g2)
    nxt = _next(g1)
    rows, k = np.nonzero((g1 < 0) & (nxt > 0) | (g1 > 0) & (nxt < 0))
    # exact stationary points on the grid, and kinks (a change point's flat configuration,
    # where the derivative of sqrt(0) is undefined)
    zr, zk = np.nonzero((g1 == 0) | ~np.isfinite(g1))
    lo, hi = grid[k], grid[k] + widths[k]
    scale = np.max(np.abs(np.where(np.isfinite(g1), g1, 0)), axis=1)[rows]

    nr, idx = g1.shape[0], np.arange(rows.size)

    def derivatives(x):  # g', g'' of each root's own row
        return f.fn(x, pv).reshape(3, nr, -1)[1:, rows, idx]

    x = _rtsafe(derivatives, lo, hi, g1[rows, k], nxt[rows, k], scale)
    if f.dead is not None:
        x = _dead_centres(f, pv, rows, x, TWO_PI / n)
    rows = np.concatenate([rows, zr])
    x = np.concatenate([x, grid[zk]]) % TWO_PI
    values = f.fn(x, pv)[rows, np.arange(x.size)] if x.size else np.empty(0)
    return rows, x, values


@functools.cache
def _grid(n: int) -> tuple[np.ndarray, np.ndarray]:
    """n angles over a revolution and the widths of their cells (read-only: shared)."""
    grid = np.linspace(0.0, TWO_PI, n, endpoint=False)
    widths = _widths(grid)
    grid.flags.writeable = widths.flags.writeable = False
    return grid, widths


def _widths(grid: np.ndarray) -> np.ndarray:
    return np.diff(np.append(grid, TWO_PI))


def _next(a: np.ndarray) -> np.ndarray:
    """Each column's successor around the revolution: np.roll(a, -1, axis=1), 4× cheaper."""
    return np.concatenate((a[:, 1:], a[:, :1]), axis=1)


def _rtsafe(fd, lo, hi, f_lo, f_hi, scale) -> np.ndarray:
    """The roots of fd (x -> (value, derivative), vectorised) in the brackets [lo, hi], where
    it changes sign from f_lo to f_hi: Newton from the secant point while it stays in the
    bracket and at least halves the step before last, else bisection (rtsafe), to machine
    precision; ``scale`` is the function's size, to tell a root from a kink."""
    # start from the secant (regula falsi) point: already close on a fine grid
    with np.errstate(divide="ignore", invalid="ignore"):
        x = lo + (hi - lo) * f_lo / (f_lo - f_hi)
    x = np.where(np.isfinite(x), x, 0.5 * (lo + hi))
    if x.size == 0:
        return x
    # one evaluation of fd for all roots per step, the steps in Python floats: numpy's
    # per-operation overhead on a handful of roots cost more than the evaluations
    x, lo, hi, dx_old = x.tolist(), lo.tolist(), hi.tolist(), (hi - lo).tolist()
    rising, tiny = (f_lo < 0).tolist(), (1e-12 * scale).tolist()
    for _ in range(100):
        done = True
        for i, (fx, dfx) in enumerate(zip(*fd(np.array(x)).tolist(), strict=True)):
            xi = x[i]
            if fx < 0 if rising[i] else fx > 0:  # on lo's side (not where fx is 0 or NaN)
                lo[i] = xi
            else:
                hi[i] = xi
            a, b = lo[i], hi[i]
            step = fx / dfx if dfx else math.nan
            newton = math.isfinite(step) and a <= xi - step <= b
            newton = newton and abs(step) <= 0.5 * abs(dx_old[i])
            dx = step if newton else xi - 0.5 * (a + b)
            if not newton:
                dx_old[i] = dx
            tol = EPS4 * max(1.0, xi)
            # a tiny Newton step is convergence only where the function is ~0 too: at a kink
            # (a change point, a rod at its reach) it jumps across 0, and bisection must finish
            small = abs(fx) <= tiny[i]
            done &= fx == 0 or b - a <= tol or (abs(dx) <= tol and newton and small)
            if fx != 0:
                x[i] = xi - dx
        if done:
            break
    return np.array(x)


def _dead_centres(f: Model, pv, rows, x, width: float) -> np.ndarray:
    """Move the slider's stationary points onto the zeros of the type's dead-centre function,
    searched within a grid cell (and a quarter of the gap to the next one) of each."""
    on_s = np.nonzero(rows == 0)[0]
    if on_s.size < 2:
        return x
    t = x[on_s]
    gap = np.abs((t[:, None] - t[None, :] + math.pi) % TWO_PI - math.pi)
    np.fill_diagonal(gap, np.inf)
    w = np.minimum(width, 0.25 * gap.min(axis=1))
    lo, hi = t - w, t + w
    h_lo, h_hi = f.dead(np.concatenate([lo, hi]), pv)[0].reshape(2, -1)
    ok = np.sign(h_lo) * np.sign(h_hi) < 0
    scale = np.maximum(np.abs(h_lo), np.abs(h_hi))[ok]
    x = x.copy()
    x[on_s[ok]] = _rtsafe(lambda y: f.dead(y, pv), lo[ok], hi[ok], h_lo[ok], h_hi[ok], scale)
    return x


def _refine(f: Model, pv, grid, widths, g1, g2, levels: int = 3, split: int = 16):
    """Subdivide the cells where a pair of roots could hide between two grid points.

    A cell whose ends have the same sign of g' can still hold two roots if g' turns inside it
    (g'' changes sign) and is small against its rate of change, |g'| < |g''| × width (a quick
    stroke squeezed into a few degrees, an extreme just inside a lever's swing): such cells are
    split ``split`` ways, up to ``levels`` times."""
    for _ in range(levels):
        nxt1, nxt2 = _next(g1), _next(g2)
        with np.errstate(invalid="ignore"):
            fast = (np.abs(g1) < np.abs(g2) * widths) | (np.abs(nxt1) < np.abs(nxt2) * widths)
            suspect = np.any(fast & (g1 * nxt1 > 0) & (g2 * nxt2 <= 0), axis=0)
        if not np.any(suspect):
            break
        k = np.nonzero(suspect)[0]
        inner = (grid[k, None] + widths[k, None] * np.arange(1, split) / split).ravel()
        _, n1, n2 = f(inner, pv)
        order = np.argsort(np.concatenate([grid, inner]), kind="stable")
        grid = np.concatenate([grid, inner])[order]
        g1 = np.concatenate([g1, n1], axis=1)[:, order]
        g2 = np.concatenate([g2, n2], axis=1)[:, order]
        widths = _widths(grid)
    return grid, widths, g1


def _refuse_dwell(grid: np.ndarray, ds: np.ndarray) -> None:
    """A slider that stands still over an interval (a linkage folded onto itself, e.g. an
    offset slider-crank with coupler = crank and no offset) has no defined strokes.

    Standing still is ds/dθ = 0 exactly at three grid points in a row: the cancellation-free
    position formulas give an exact 0 for a folded linkage, while a near-stall keeps its tiny
    but real motion (a drag-link kite 1e-9 off its change point moves its slider by ~1e-23 of
    the stroke per radian over 20° of the turn, and its strokes are well defined)."""
    still = ds == 0
    ring = np.concatenate((still[-1:], still, still[:1]))  # around the revolution
    if np.any(ring[:-2] & ring[1:-1] & ring[2:]):
        raise InvalidDesign(
            f"the slider stands still over about {360 * np.count_nonzero(still) / len(grid):.3g}°"
            " of the crank's turn: the linkage folds onto itself, so its strokes and time ratio"
            " are undefined",
            (),
            "dwell",
        )


def analyze(
    mechanism: str,
    params: Mapping[str, float],
    *,
    crank_speed: float = 1.0,
    crank_acceleration: float = 0.0,
    crank_angles_deg: Sequence[float] | None = None,
    samples: int | None = None,
) -> Analysis:
    """Analyse one design over a crank revolution (the semantics of POST /v1/analyze).

    Curves are computed only when asked: at exactly ``crank_angles_deg``, or at ``samples``
    evenly spaced angles (0° included, 360° not).

    >>> a = analyze("whitworth", {"crank": 75, "pivot_distance": 50, "lever": 150,
    ...                           "connecting_rod": 200})
    >>> round(a.time_ratio, 5), round(a.stroke, 9)
    (2.73524, 300.0)
    """
    m = get(mechanism)
    p = m.complete(params)
    f = model(m, m.variant(p))
    pv = np.array([p[n] for n in m.names], dtype=float)
    rows, theta, values = stationary_points(f, pv)
    summary = _summary(m, p, f, rows, theta, values)
    curves = None
    if crank_angles_deg is not None or samples is not None:
        curves = _curves(f, pv, crank_speed, crank_acceleration, crank_angles_deg, samples)
    return Analysis(**summary, curves=curves)


def joints(
    mechanism: str, params: Mapping[str, float], crank_angles_deg: Sequence[float]
) -> dict[str, np.ndarray]:
    """The pin positions at each crank angle, {pin: array of (x, y)}, for drawings; the pins
    and the frame are named in the type's docstring (``synth.mechanisms.get(t).description``).

    >>> j = joints("drag_link_slider", {"ground": 0.1, "crank": 0.225, "coupler": 0.2504,
    ...            "follower": 0.275, "follower_arm": 0.15, "connecting_rod": 0.3}, [90.0])
    >>> sorted(j), j["A"].round(9).tolist()
    (['A', 'B', 'C', 'D', 'O2', 'O4'], [[0.0, 0.225]])
    """
    m = get(mechanism)
    if m.joints is None:
        raise InvalidParameters(f"{mechanism} has no drawing yet", ("mechanism",))
    p = m.complete(params)
    # θ as a CasADi number: a branch not taken (a division by zero on a pivot line) is inf
    # there, as in the compiled analysis, instead of raising as on a Python float
    at = [m.joints(p, ca.DM(math.radians(a))) for a in crank_angles_deg]
    return {k: np.array([pins[k] for pins in at], dtype=float) for k in at[0]} if at else {}


def _summary(m: Mechanism, p: dict[str, float], f: Model, rows, theta, values) -> dict:
    on_s = rows == 0
    reversals = int(np.count_nonzero(on_s))
    if reversals < 2:
        raise InvalidDesign("the slider does not move: no dead centres found", (), "stroke")
    s_theta, s_val = theta[on_s], values[on_s]
    i_max, i_min = s_val.argmax(), s_val.argmin()
    t_max, t_min = float(s_theta[i_max]), float(s_theta[i_min])
    up = (t_max - t_min) % TWO_PI  # crank travel while the slider goes min -> max (+ direction)
    down = TWO_PI - up
    if min(up, down) < 1e-12:
        raise InvalidDesign(
            f"the slider's extremes fall at one crank angle ({math.degrees(t_max):.6g}°): the "
            "linkage passes a change point there and its assembly circuit switches, so the "
            "slider jumps",
            (),
            "change_point",
        )
    slow_up = up >= down
    joints = []
    for j, name in enumerate(f.joints, start=1):
        c = values[rows == j]
        lo, hi = float(c.min()), float(c.max())
        worst = min(1.0, max(abs(lo), abs(hi)))
        best = 0.0 if lo < 0 < hi else min(1.0, abs(lo), abs(hi))
        joints.append(Joint(name, math.degrees(math.acos(worst)), math.degrees(math.acos(best))))
    mu_min = min((jt.min_deg for jt in joints), default=90.0)
    return {
        "type": m.type,
        "params": p,
        "time_ratio": max(up, down) / min(up, down),
        "stroke": float(s_val[i_max] - s_val[i_min]),
        "extremes": {
            "min": Extreme(float(s_val[i_min]), math.degrees(t_min)),
            "max": Extreme(float(s_val[i_max]), math.degrees(t_max)),
        },
        "working_stroke": Stroke(math.degrees(max(up, down)), 1 if slow_up else -1),
        "return_stroke": Stroke(math.degrees(min(up, down)), -1 if slow_up else 1),
        "transmission": Transmission(
            mu_min,
            max((jt.max_deg for jt in joints), default=90.0),
            tuple(joints),
        ),
        "grashof": grashof_class(*m.fourbar(p)) if m.fourbar else None,
        "reversals": reversals,
        "conditioning": conditioning(m, p, mu_min, reversals),
    }


def conditioning(m: Mechanism, p: dict[str, float], mu_deg: float, reversals: int) -> Conditioning:
    """Distance to a dead point and to the nearest validity limit, flagged when small."""
    scale = max(abs(v) for v in p.values())
    variant = m.variant(p)
    margins = [
        (min(float(t) for t in c.margin(p)) / scale, c.name)
        for c in m.conditions
        if c.applies(variant)
    ]
    margin, name = min(margins, default=(None, None))
    flags = []
    if mu_deg < NEAR_DEAD_POINT_DEG:
        flags.append("near_dead_point")
    if margin is not None and margin < NEAR_LIMIT:
        flags.append("near_validity_limit")
    if reversals > 2:
        flags.append("dithering")
    return Conditioning(mu_deg, margin, name, tuple(flags))


def _curves(f: Model, pv, omega, alpha, angles_deg, samples) -> Curves:
    if angles_deg is not None and samples is not None:
        raise InvalidParameters("give crank_angles_deg or samples, not both", ("samples",))
    if angles_deg is not None:
        deg = np.asarray(angles_deg, dtype=float).ravel()
    else:
        if samples is None or samples < 1:
            raise InvalidParameters(f"samples must be ≥ 1, got {samples}", ("samples",))
        deg = np.arange(samples) * (360.0 / samples)
    if deg.size > MAX_CURVE_POINTS:
        raise InvalidParameters(
            f"at most {MAX_CURVE_POINTS} curve points, got {deg.size}", ("crank_angles_deg",)
        )
    if not np.all(np.isfinite(deg)):
        raise InvalidParameters("crank angles must be finite", ("crank_angles_deg",))
    if deg.size == 0:
        empty = np.empty(0)
        return Curves(deg, empty, empty, empty, empty)
    g, g1, g2 = f(np.radians(deg), pv)
    mu = np.degrees(np.arccos(np.minimum(1.0, np.abs(g[1:])))) if g.shape[0] > 1 else None
    return Curves(
        crank_angle_deg=deg,
        position=g[0],
        velocity=g1[0] * omega,
        acceleration=g2[0] * omega**2 + g1[0] * alpha,
        transmission_deg=np.min(mu, axis=0) if mu is not None else np.full(deg.size, 90.0),
    )
