"""Stationary points of a compiled model's rows over a crank revolution, to machine precision.

Bracketed on a grid (refined where the motion is fast), then polished by a safeguarded Newton
iteration (bisection where Newton leaves the bracket). Nothing here uses a type's closed forms.
"""

from __future__ import annotations

import functools
import math
import sys
from collections.abc import Callable
from typing import Any, cast

import numpy as np

from ..errors import InvalidDesign
from .model import GRID, Model, Polisher

TWO_PI = 2 * math.pi
EPS4 = 4 * sys.float_info.epsilon
# a Newton step this short (relative to the angle, at least 1 rad) where the function is ~0
# ends the iteration: the point it reaches is as close as the function's rounding tells (from
# a simple root's quadratic convergence, ~1e-24 away); bracketing on to a few ulps only picks
# a point within that noise (near a flat root, 1e-14 to 1e-12 wide: dozens of steps)
STEP = 1e-12
BATCH = 32  # designs whose grids go through one batched evaluation

Points = tuple[np.ndarray, np.ndarray, np.ndarray]  # (row, θ, value) of each stationary point
# (rows, the brackets' lower and upper ends, g' at each end, the row's scale), and (rows, θ)
# where g' is 0 or undefined on the grid
Brackets = tuple[
    tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray],
    tuple[np.ndarray, np.ndarray],
]


def stationary_points(
    f: Model, pv: np.ndarray, n: int = GRID, reversals: int | None = None
) -> Points:
    """Every stationary point of every row that changes the sign of its derivative.

    Returns (row, θ, value) arrays. Roots are bracketed on an n-point grid, refined where the
    motion is fast (see ``refine_grid``), and polished by safeguarded Newton steps on g' with g''
    (``polish``: compiled, all roots in one call). ``reversals``: how many stationary points
    row 0 (the slider's position) must have, or InvalidDesign, raised before any is polished
    (a search's design near a change point can have a thousand at the level of rounding).
    """
    grid, widths = _grid(n)
    g, g1, g2 = f(grid, pv)
    if not np.all(np.isfinite(g)):
        bad = grid[np.nonzero(~np.all(np.isfinite(g), axis=0))[0][0]]
        msg = f"the design cannot be assembled at crank angle {math.degrees(bad):.6g}°"
        raise InvalidDesign(msg, (), "assembly")
    if f.kind == "kinematics":  # row 0 is the slider's position
        _refuse_dwell(grid, g1[0])
    grid, widths, g1 = refine_grid(f, pv, grid, widths, g1, g2)
    (rows, lo, hi, f_lo, f_hi, scale), (zr, zx) = _brackets(grid, widths, g1)
    found = np.count_nonzero(rows == 0) + np.count_nonzero(zr == 0)
    if reversals is not None and found != reversals:
        msg = f"the slider reverses {found} times a turn: not one working and one return stroke"
        raise InvalidDesign(msg, (), "stroke")
    nr = g1.shape[0]

    # g', g'' of roots i, each of its own row
    def derivatives(x: np.ndarray, i: np.ndarray) -> np.ndarray:
        return f.fn(x, pv).reshape(3, nr, -1)[1:, rows[i], np.arange(i.size)]

    x = polish(f.polish, derivatives, rows, lo, hi, f_lo, f_hi, scale, pv)
    if f.dead is not None:
        x = _dead_centres(f, pv[None, :], np.zeros(rows.size, dtype=int), rows == 0, x, TWO_PI / n)
    rows = np.concatenate([rows, zr])
    x = np.concatenate([x, zx]) % TWO_PI
    values = f.fn(x, pv)[rows, np.arange(x.size)] if x.size else np.empty(0)
    return rows, x, values


def stationary_points_many(f: Model, pvs: np.ndarray) -> list[Points | None]:
    """``stationary_points`` of several designs of one variant (``pvs``: one row each) in
    shared compiled calls, with the same results to the bit: each step is the one design's,
    on the same numbers. None for a design that ``stationary_points`` refuses (it says why).
    At most ``BATCH`` designs go through one batched evaluation."""
    if len(pvs) > BATCH:
        return [
            found
            for i in range(0, len(pvs), BATCH)
            for found in stationary_points_many(f, pvs[i : i + BATCH])
        ]
    k, n = len(pvs), GRID
    grid, widths = _grid(n)
    out = f.fn.each(np.tile(grid, k), np.repeat(pvs, n, axis=0))  # design by design
    nr = out.shape[0] // 3
    g, g1, g2 = out.reshape(3, nr, k, n).transpose(0, 2, 1, 3).reshape(3, k * nr, n)
    bad = np.any(~np.isfinite(g).reshape(k, -1), axis=1)
    if f.kind == "kinematics":
        bad |= _dwells(g1[::nr])
    refine = np.any(_hiding(g1, g2, widths).reshape(k, -1), axis=1) & ~bad
    # the designs whose grid needs no refining at once, then each of the others on its own
    plain = np.nonzero(np.repeat(~bad & ~refine, nr))[0]
    (rows, *brackets), (zr, zx) = _brackets(grid, widths, g1[plain])
    parts, zeros = [(plain[rows], *brackets)], [(plain[zr], zx)]
    for d in np.nonzero(refine)[0]:
        own = slice(d * nr, (d + 1) * nr)
        (rows, *brackets), (zr, zx) = _brackets(
            *refine_grid(f, pvs[d], grid, widths, g1[own], g2[own])
        )
        parts.append((rows + d * nr, *brackets))
        zeros.append((zr + d * nr, zx))
    rows, lo, hi, f_lo, f_hi, scale = (np.concatenate(c) for c in zip(*parts, strict=True))
    design = rows // nr

    # g', g'' of roots i, each of its own row and design
    def derivatives(x: np.ndarray, i: np.ndarray) -> np.ndarray:
        return f.fn.each(x, pvs[design[i]]).reshape(3, nr, -1)[1:, rows[i] % nr, np.arange(i.size)]

    x = polish(f.polish, derivatives, rows % nr, lo, hi, f_lo, f_hi, scale, pvs[design])
    if f.dead is not None:
        x = _dead_centres(f, pvs, design, rows % nr == 0, x, TWO_PI / n)
    rows = np.concatenate([rows, *(z for z, _ in zeros)])
    x = np.concatenate([x, *(z for _, z in zeros)]) % TWO_PI
    design = rows // nr
    values = f.fn.each(x, pvs[design])[rows % nr, np.arange(x.size)]
    order = np.argsort(design, kind="stable")  # each design's roots in the order it finds them
    cuts = np.searchsorted(design[order], np.arange(1, k))
    return [
        None if bad[d] else (rows[o] % nr, x[o], values[o])
        for d, o in enumerate(np.split(order, cuts))
    ]


def _brackets(grid: np.ndarray, widths: np.ndarray, g1: np.ndarray) -> Brackets:
    """Where each row's g' changes sign between neighbouring grid points: (rows, the
    brackets' ends, g' there, the row's scale); and where it is 0 on the grid, or undefined
    (a change point's flat configuration, where the derivative of sqrt(0) is): (rows, θ)."""
    nxt = _next(g1)
    rows, k = np.nonzero((g1 < 0) & (nxt > 0) | (g1 > 0) & (nxt < 0))
    zr, zk = np.nonzero((g1 == 0) | ~np.isfinite(g1))
    scale = np.max(np.abs(np.where(np.isfinite(g1), g1, 0)), axis=1)[rows]
    return (rows, grid[k], grid[k] + widths[k], g1[rows, k], nxt[rows, k], scale), (zr, grid[zk])


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


def polish(
    polisher: Polisher,
    fd: Callable[[np.ndarray, np.ndarray], np.ndarray],
    rows: np.ndarray,
    lo: np.ndarray,
    hi: np.ndarray,
    f_lo: np.ndarray,
    f_hi: np.ndarray,
    scale: np.ndarray,
    pv: np.ndarray,
) -> np.ndarray:
    """The roots of each one's row of fd (x, rows -> (value, derivative), vectorised) in the
    brackets [lo, hi], where it changes sign from f_lo to f_hi, to machine precision: the
    compiled Newton steps (``model.Polisher``) from the secant point, and ``rtsafe`` for
    any they leave unfinished (a kink, a slow start)."""
    if rows.size == 0:
        return np.empty(0)
    x, done = _compiled(polisher, rows, lo, hi, f_lo, f_hi, scale, pv)
    if not done.all():
        left = np.nonzero(~done)[0]
        x[left] = rtsafe(
            lambda y: fd(y, left), lo[left], hi[left], f_lo[left], f_hi[left], scale[left]
        )
    return x


def _compiled(
    polisher: Polisher,
    rows: np.ndarray,
    lo: np.ndarray,
    hi: np.ndarray,
    f_lo: np.ndarray,
    f_hi: np.ndarray,
    scale: np.ndarray,
    pv: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """The compiled Newton steps of ``polish`` from the secant point: the points they reach,
    and which of them are roots (``pv``: the parameters, shared (p,) or each root's (n, p))."""
    with np.errstate(divide="ignore", invalid="ignore"):
        x0 = lo + (hi - lo) * f_lo / (f_lo - f_hi)
    x0 = np.where(np.isfinite(x0), x0, 0.5 * (lo + hi))
    x, step, fx, width = polisher(x0, lo, hi, np.where(f_lo < 0, 1.0, -1.0), rows, pv)
    size = np.maximum(1.0, np.abs(x))
    return x, _finished(size, fx, width, step, np.abs(fx) <= 1e-12 * scale)


def _finished(size: Any, fx: Any, width: Any, step: Any, small: Any) -> Any:
    """Whether a root's iteration (floats, or arrays of many) is done where the angle's
    size is ``size`` (|x|, at least 1): on a root, a bracket closed to ``EPS4``, or a step
    within ``STEP`` where the function is ~0 too (``small``: at a kink, a change point or a
    rod at its reach, it jumps across 0, and bisection must finish)."""
    return (fx == 0) | (width <= EPS4 * size) | ((abs(step) <= STEP * size) & small)


def rtsafe(
    fd: Callable[[np.ndarray], np.ndarray],
    lo: np.ndarray,
    hi: np.ndarray,
    f_lo: np.ndarray,
    f_hi: np.ndarray,
    scale: np.ndarray,
) -> np.ndarray:
    """The roots of fd (x -> (value, derivative), vectorised) in the brackets [lo, hi], where
    it changes sign from f_lo to f_hi: Newton from the secant point while it stays in the
    bracket and is at most half the last bisection's step (the bracket's width before any),
    else bisection (rtsafe), to machine precision; ``scale`` is the function's size, to tell a
    root from a kink."""
    # start from the secant (regula falsi) point: already close on a fine grid
    with np.errstate(divide="ignore", invalid="ignore"):
        x = lo + (hi - lo) * f_lo / (f_lo - f_hi)
    x = np.where(np.isfinite(x), x, 0.5 * (lo + hi))
    if x.size == 0:
        return cast(np.ndarray, x)
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
            size = max(1.0, abs(xi))
            done &= _finished(size, fx, b - a, dx, newton and abs(fx) <= tiny[i])
            if fx != 0:
                x[i] = xi - dx
        if done:
            break
    return np.array(x)


def _dead_centres(
    f: Model, pvs: np.ndarray, design: np.ndarray, on_s: np.ndarray, x: np.ndarray, width: float
) -> np.ndarray:
    """Move the slider's stationary points (``on_s``) onto the zeros of the type's dead-centre
    function, searched within a grid cell (and a quarter of the gap to the next one) of
    each; the roots of several designs (``design``: each root's row of ``pvs``), each
    design's on their own."""
    dead, polisher = f.dead, f.dead_polish
    assert dead is not None and polisher is not None  # a type with a dead-centre function
    count = np.bincount(design[on_s], minlength=len(pvs))
    on_s = np.nonzero(on_s & (count[design] >= 2))[0]
    if on_s.size == 0:
        return x
    t, d = x[on_s], design[on_s]
    gap = np.abs((t[:, None] - t[None, :] + math.pi) % TWO_PI - math.pi)
    gap[d[:, None] != d[None, :]] = np.inf
    np.fill_diagonal(gap, np.inf)
    w = np.minimum(width, 0.25 * gap.min(axis=1))
    lo, hi, pv = t - w, t + w, pvs[d]
    h_lo, h_hi = dead.each(np.concatenate([lo, hi]), np.concatenate([pv, pv]))[0].reshape(2, -1)
    ok = np.sign(h_lo) * np.sign(h_hi) < 0
    scale = np.maximum(np.abs(h_lo), np.abs(h_hi))[ok]
    pv = pv[ok]
    x = x.copy()
    x[on_s[ok]] = polish(
        polisher,
        lambda y, i: dead.each(y, pv[i]),
        np.zeros(pv.shape[0], dtype=int),
        lo[ok],
        hi[ok],
        h_lo[ok],
        h_hi[ok],
        scale,
        pv,
    )
    return x


def refine_grid(
    f: Model,
    pv: np.ndarray,
    grid: np.ndarray,
    widths: np.ndarray,
    g1: np.ndarray,
    g2: np.ndarray,
    levels: int = 3,
    split: int = 16,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Subdivide the cells where a pair of roots could hide between two grid points.

    A cell whose ends have the same sign of g' can still hold two roots if g' turns inside it
    (g'' changes sign) and is small against its rate of change, |g'| < |g''| × width (a quick
    stroke squeezed into a few degrees, an extreme just inside a lever's swing): such cells are
    split ``split`` ways, up to ``levels`` times."""
    for _ in range(levels):
        suspect = np.any(_hiding(g1, g2, widths), axis=0)
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


def _hiding(g1: np.ndarray, g2: np.ndarray, widths: np.ndarray) -> np.ndarray:
    """Per row and cell (``refine_grid``): whether a pair of roots of the row's g' could hide in
    the cell."""
    nxt1, nxt2 = _next(g1), _next(g2)
    with np.errstate(invalid="ignore"):
        fast = (np.abs(g1) < np.abs(g2) * widths) | (np.abs(nxt1) < np.abs(nxt2) * widths)
        return cast(np.ndarray, fast & (g1 * nxt1 > 0) & (g2 * nxt2 <= 0))


def _dwells(ds: np.ndarray) -> np.ndarray:
    """Per row of ds/dθ on the grid: whether the slider stands still (``_refuse_dwell``)."""
    still = ds == 0
    ring = np.concatenate((still[:, -1:], still, still[:, :1]), axis=1)  # around the revolution
    return cast(np.ndarray, np.any(ring[:, :-2] & ring[:, 1:-1] & ring[:, 2:], axis=1))


def _refuse_dwell(grid: np.ndarray, ds: np.ndarray) -> None:
    """A slider that stands still over an interval (a linkage folded onto itself, e.g. an
    offset slider-crank with coupler = crank and no offset) has no defined strokes.

    Standing still is ds/dθ = 0 exactly at three grid points in a row: the cancellation-free
    position formulas give an exact 0 for a folded linkage, while a near-stall keeps its tiny
    but real motion (a drag-link kite 1e-9 off its change point moves its slider by ~1e-23 of
    the stroke per radian over 20° of the turn, and its strokes are well defined)."""
    if _dwells(ds[None, :])[0]:
        still = ds == 0
        raise InvalidDesign(
            f"the slider stands still over about {360 * np.count_nonzero(still) / len(grid):.3g}°"
            " of the crank's turn: the linkage folds onto itself, so its strokes and time ratio"
            " are undefined",
            (),
            "dwell",
        )
