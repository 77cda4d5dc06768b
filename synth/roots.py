"""Stationary points of a compiled model's rows over a crank revolution, to machine precision.

Bracketed on a grid (refined where the motion is fast), then polished by a safeguarded Newton
iteration (bisection where Newton leaves the bracket). Nothing here uses a type's closed forms.
"""

from __future__ import annotations

import functools
import itertools
import math
import sys

import numpy as np

from .errors import InvalidDesign
from .model import GRID, Model

TWO_PI = 2 * math.pi
EPS4 = 4 * sys.float_info.epsilon


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
    rows, lo, hi, f_lo, f_hi, scale, zr, zx = _brackets(f, pv, grid, widths, g, g1, g2)
    nr, idx = g1.shape[0], np.arange(rows.size)

    def derivatives(x):  # g', g'' of each root's own row
        return f.fn(x, pv).reshape(3, nr, -1)[1:, rows, idx]

    x = _rtsafe(derivatives, lo, hi, f_lo, f_hi, scale)
    if f.dead is not None:
        x = _dead_centres(f, pv, rows, x, TWO_PI / n)
    rows = np.concatenate([rows, zr])
    x = np.concatenate([x, zx]) % TWO_PI
    values = f.fn(x, pv)[rows, np.arange(x.size)] if x.size else np.empty(0)
    return rows, x, values


def stationary_points_many(
    f: Model, pvs: list[np.ndarray], n: int = GRID
) -> list[tuple[np.ndarray, np.ndarray, np.ndarray] | InvalidDesign]:
    """``stationary_points`` of several designs of one model (a front's points), each in its
    place (or the InvalidDesign it raises): the same grid, brackets and iterations, the
    model evaluated for all of them in one call a stage (``Model.fn.pairs``: the same
    numbers as a call per design). Only the safeguarded Newton iteration, run for all the
    roots together, may take a root further than alone (a step within its tolerance)."""
    grid, widths = _grid(n)
    pm = np.array(pvs, dtype=float).reshape(len(pvs), -1)
    out = f.fn.pairs(np.tile(grid, len(pvs)), np.repeat(pm, n, axis=0))
    nr = out.shape[0] // 3
    g_all = out.reshape(3, nr, len(pvs), n)
    found: list = [None] * len(pvs)
    parts = []  # per design that brackets: (design, rows, lo, hi, f_lo, f_hi, scale, zr, zx)
    for d, b in enumerate(_brackets_many(f, pvs, grid, widths, *g_all)):
        if isinstance(b, InvalidDesign):
            found[d] = b
        else:
            parts.append((d, *b))
    if not parts:
        return found
    design = np.concatenate([np.full(b[1].size, b[0]) for b in parts])
    rows, lo, hi, f_lo, f_hi, scale = (np.concatenate([b[i] for b in parts]) for i in range(1, 7))
    idx, at = np.arange(rows.size), pm[design]

    def derivatives(x):  # g', g'' of each root's own row, with its own design
        return f.fn.pairs(x, at).reshape(3, nr, -1)[1:, rows, idx]

    x = _rtsafe_many(derivatives, lo, hi, f_lo, f_hi, scale, design)
    ends = np.cumsum([0] + [b[1].size for b in parts]).tolist()
    xs = [x[i:j] for i, j in itertools.pairwise(ends)]
    if f.dead is not None:
        xs = _dead_centres_many(f, pm, [(b[0], b[1]) for b in parts], xs, TWO_PI / n)
    rows_d = [np.concatenate([b[1], b[7]]) for b in parts]
    xs = [np.concatenate([x, b[8]]) % TWO_PI for x, b in zip(xs, parts, strict=True)]
    sizes = [x.size for x in xs]
    xa = np.concatenate(xs)
    va = np.empty(0)
    if xa.size:
        da = np.concatenate([np.full(s, b[0]) for s, b in zip(sizes, parts, strict=True)])
        va = f.fn.pairs(xa, pm[da])[np.concatenate(rows_d), np.arange(xa.size)]
    ends = np.cumsum([0, *sizes]).tolist()
    vs = [va[i:j] for i, j in itertools.pairwise(ends)]
    for b, r, x, v in zip(parts, rows_d, xs, vs, strict=True):
        found[b[0]] = (r, x, v)
    return found


def _brackets_many(f: Model, pvs, grid, widths, g, g1, g2) -> list:
    """``_brackets`` of several designs, their g, g', g'' on the grid as (rows, designs, n):
    numpy's operations once for all; a design that cannot be assembled, whose slider dwells
    or whose grid needs refining (``_refine``) goes through ``_brackets`` alone."""
    out: list = [None] * g.shape[1]
    odd = ~np.isfinite(g).all(axis=(0, 2))
    if f.kind == "kinematics":  # _refuse_dwell's test
        still = g1[0] == 0
        ring = np.concatenate((still[:, -1:], still, still[:, :1]), axis=1)
        odd |= np.any(ring[:, :-2] & ring[:, 1:-1] & ring[:, 2:], axis=1)
    nxt1, nxt2 = np.roll(g1, -1, axis=2), np.roll(g2, -1, axis=2)
    with np.errstate(invalid="ignore"):  # _refine's test
        fast = (np.abs(g1) < np.abs(g2) * widths) | (np.abs(nxt1) < np.abs(nxt2) * widths)
        odd |= np.any(fast & (g1 * nxt1 > 0) & (g2 * nxt2 <= 0), axis=(0, 2))
    for d in np.nonzero(odd)[0]:
        try:
            out[d] = _brackets(f, pvs[d], grid, widths, g[:, d], g1[:, d], g2[:, d])
        except InvalidDesign as e:
            out[d] = e
    rest = np.nonzero(~odd)[0]
    if rest.size == 0:
        return out
    a, b = g1[:, rest].transpose(1, 0, 2), nxt1[:, rest].transpose(1, 0, 2)  # (designs, rows, n)
    d, rows, k = np.nonzero((a < 0) & (b > 0) | (a > 0) & (b < 0))
    zd, zr, zk = np.nonzero((a == 0) | ~np.isfinite(a))
    scale = np.max(np.abs(np.where(np.isfinite(a), a, 0)), axis=2)[d, rows]
    cut = np.searchsorted(d, np.arange(rest.size + 1)).tolist()
    zcut = np.searchsorted(zd, np.arange(rest.size + 1)).tolist()
    vals = (rows, grid[k], grid[k] + widths[k], a[d, rows, k], b[d, rows, k], scale)
    zx = grid[zk]
    for j, e in enumerate(rest.tolist()):
        i0, i1, z0, z1 = cut[j], cut[j + 1], zcut[j], zcut[j + 1]
        out[e] = (*(v[i0:i1] for v in vals), zr[z0:z1], zx[z0:z1])
    return out


def _brackets(f: Model, pv, grid, widths, g, g1, g2):
    """The brackets of the stationary points on the grid (g, g', g'' there): (rows, lo, hi,
    g' at lo and at hi, the rows' scale) and the exact ones (rows, θ); raises InvalidDesign
    for a design that cannot be assembled or whose slider dwells."""
    if not np.all(np.isfinite(g)):
        bad = grid[np.nonzero(~np.all(np.isfinite(g), axis=0))[0][0]]
        msg = f"the design cannot be assembled at crank angle {math.degrees(bad):.6g}°"
        raise InvalidDesign(msg, (), "assembly")
    if f.kind == "kinematics":  # row 0 is the slider's position
        _refuse_dwell(grid, g1[0])
    grid, widths, g1 = _refine(f, pv, grid, widths, g1, g2)
    nxt = _next(g1)
    rows, k = np.nonzero((g1 < 0) & (nxt > 0) | (g1 > 0) & (nxt < 0))
    # exact stationary points on the grid, and kinks (a change point's flat configuration,
    # where the derivative of sqrt(0) is undefined)
    zr, zk = np.nonzero((g1 == 0) | ~np.isfinite(g1))
    lo, hi = grid[k], grid[k] + widths[k]
    scale = np.max(np.abs(np.where(np.isfinite(g1), g1, 0)), axis=1)[rows]
    return rows, lo, hi, g1[rows, k], nxt[rows, k], scale, zr, grid[zk]


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


def _rtsafe_many(fd, lo, hi, f_lo, f_hi, scale, design) -> np.ndarray:
    """``_rtsafe`` for the roots of several designs (``design``: each root's), its steps in
    numpy: the same operations root by root, and each design's roots stop where ``_rtsafe``
    on them alone would stop (the step on which all of them are done), so each root ends
    where it would alone, to the bit."""
    with np.errstate(divide="ignore", invalid="ignore"):
        x = lo + (hi - lo) * f_lo / (f_lo - f_hi)
    x = np.where(np.isfinite(x), x, 0.5 * (lo + hi))
    if x.size == 0:
        return x
    dx_old, rising, tiny = hi - lo, f_lo < 0, 1e-12 * scale
    on = np.ones(x.size, dtype=bool)  # the roots of the designs still iterating
    for _ in range(100):
        fx, dfx = fd(x)
        below = np.where(rising, fx < 0, fx > 0)  # on lo's side
        lo2, hi2 = np.where(below, x, lo), np.where(below, hi, x)
        with np.errstate(divide="ignore", invalid="ignore"):
            step = np.where(dfx != 0, fx / dfx, np.nan)
            to = x - step
            newton = np.isfinite(step) & (lo2 <= to) & (to <= hi2)
            newton &= np.abs(step) <= 0.5 * np.abs(dx_old)
        dx = np.where(newton, step, x - 0.5 * (lo2 + hi2))
        tol = EPS4 * np.where(x > 1.0, x, 1.0)
        small = np.abs(fx) <= tiny
        done = (fx == 0) | (hi2 - lo2 <= tol) | ((np.abs(dx) <= tol) & newton & small)
        lo, hi = np.where(on, lo2, lo), np.where(on, hi2, hi)
        dx_old = np.where(on & ~newton, dx, dx_old)
        x = np.where(on & (fx != 0), x - dx, x)
        on &= np.bincount(design[on & ~done], minlength=design.max() + 1)[design] > 0
        if not on.any():
            break
    return x


def _windows(rows, x, width: float):
    """The slider's stationary points (indices) and the windows searched for their dead
    centres: a grid cell, and at most a quarter of the gap to the next one; None for fewer
    than two."""
    on_s = np.nonzero(rows == 0)[0]
    if on_s.size < 2:
        return None
    t = x[on_s]
    gap = np.abs((t[:, None] - t[None, :] + math.pi) % TWO_PI - math.pi)
    np.fill_diagonal(gap, np.inf)
    w = np.minimum(width, 0.25 * gap.min(axis=1))
    return on_s, t - w, t + w


def _dead_centres_many(f: Model, pm: np.ndarray, designs, xs, width: float):
    """``_dead_centres`` for several designs ((design, rows) and their roots xs), the dead
    centre function evaluated for all in one call a stage."""
    win = [(k, _windows(d[1], x, width)) for k, (d, x) in enumerate(zip(designs, xs, strict=True))]
    win = [(k, w) for k, w in win if w is not None]
    if not win:
        return xs
    lo = np.concatenate([w[1] for _, w in win])
    hi = np.concatenate([w[2] for _, w in win])
    owner = np.concatenate([np.full(w[0].size, designs[k][0]) for k, w in win])
    at = pm[owner]
    h = f.dead.pairs(np.concatenate([lo, hi]), np.concatenate([at, at]))[0]
    h_lo, h_hi = h.reshape(2, -1)
    ok = np.sign(h_lo) * np.sign(h_hi) < 0
    scale = np.maximum(np.abs(h_lo), np.abs(h_hi))[ok]
    at_ok = at[ok]
    y = _rtsafe_many(lambda z: f.dead.pairs(z, at_ok), lo[ok], hi[ok], h_lo[ok], h_hi[ok], scale,
                     owner[ok])  # fmt: skip
    xs = [x.copy() for x in xs]
    start = done = 0
    for k, (on_s, _, _) in win:
        mine = ok[start : start + on_s.size]
        count = int(mine.sum())
        xs[k][on_s[mine]] = y[done : done + count]
        start, done = start + on_s.size, done + count
    return xs


def _dead_centres(f: Model, pv, rows, x, width: float) -> np.ndarray:
    """Move the slider's stationary points onto the zeros of the type's dead-centre function,
    searched within a grid cell (and a quarter of the gap to the next one) of each."""
    w = _windows(rows, x, width)
    if w is None:
        return x
    on_s, lo, hi = w
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
