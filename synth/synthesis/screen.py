"""Where a motion objective's local search starts: many designs of one variant, built and
ranked in a few batched calls.

- ``project``: points of the box onto the time-ratio and stroke equalities, all at once
  (minimum-norm Newton steps through the formulation's compiled constraints, mapped over the
  points), kept where every other constraint holds too; ``breach``: how far points break
  those constraints;
- ``rank``: the motion measure of each, from the slider's s, s′ and s″ on a grid of crank
  angles (one compiled call for every design): a ranking of starts to ~1e-3, never an answer
  (the answers' measures are the analysis's, by root finding); ``rank_torque``: the peak
  crank torque of each under a load, from the Newton–Euler equations solved on that grid.
"""

from __future__ import annotations

import threading
from dataclasses import dataclass, replace
from typing import cast

import casadi as ca
import numpy as np

from ..analysis.forces import forces
from ..analysis.model import model
from ..analysis.quality import CUT
from ..load import Load
from ..mechanisms import Mechanism, kinetics
from ..mechanisms.kinetics import numbers
from ..numerics.native import Mapped
from .formulation import Formulation

STEPS = 12  # Newton steps a projection takes
CLOSE = 1e-12  # the equalities' residual a projected point keeps
SETTLED = 1e-15  # a residual, or a step's change of it, that ends the Newton steps
MET = 1e-9  # how far beyond its limits an inequality may be and count as met
INSIDE = 1e-12  # how far inside its limits a local optimum's inequalities are held (relative)
ANGLES = 96  # crank angles a ranking samples
_local = threading.local()


def compiled_constraints(form: Formulation, key: object) -> Mapped:
    """g and ∂g/∂x in one row per point, mapped over points with the parameters shared."""
    cache: dict[object, Mapped] = _local.__dict__.setdefault("constraints", {})
    if key not in cache:
        x, p, g = (form.nlp[k] for k in ("x", "p", "g"))
        out = ca.densify(ca.vertcat(g, ca.vec(ca.jacobian(g, x))))
        cache[key] = Mapped(ca.Function("screen_g", [x, p], [out]), (False, True))
    return cache[key]


def slot_widths() -> set[int]:
    """The widths of the slots this thread's constraint functions keep: a few fixed ones
    (``native.widths``), whatever numbers of points were screened."""
    kept: dict[object, Mapped] = _local.__dict__.get("constraints", {})
    return {w for m in kept.values() for w in m.slots}


def constraints(
    form: Formulation, key: object, x: np.ndarray, pv: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """g and ∂g/∂x at each point x (rows), the formulation's parameters ``pv`` shared: shapes
    (points, g) and (points, g, x)."""
    out = compiled_constraints(form, key)(x, pv).T
    ng = form.lbg.size
    return out[:, :ng], out[:, ng:].reshape(len(x), x.shape[1], ng).transpose(0, 2, 1)


def project(
    form: Formulation,
    key: object,
    x: np.ndarray,
    pv: np.ndarray,
    lo: np.ndarray,
    hi: np.ndarray,
    every: bool = True,
) -> np.ndarray:
    """The points x (rows) moved onto the equalities by minimum-norm Newton steps within the
    box, those that get there (to ``CLOSE``): with ``every``, those that meet every other
    constraint too; without, each inequality a point is beyond (or within ``INSIDE`` of) is
    held that far inside its limit as it moves (a local optimiser's answer, which meets its
    active inequalities only to its own tolerance: the verification then judges it)."""
    if len(x) == 0:
        return x
    lbg, ubg = form.lbg, form.ubg
    eq = lbg == ubg
    x = np.array(x, dtype=float)
    g = np.empty((len(x), lbg.size))
    finite = np.ones(len(x), dtype=bool)
    todo = np.arange(len(x))  # the points Newton still moves
    last = None  # their residuals before the last step
    for step in range(STEPS + 1):
        g[todo], jac = constraints(form, key, x[todo], pv)
        if every:
            res, jac = g[todo][:, eq] - lbg[eq], jac[:, eq]
        else:
            res, jac = _held(g[todo], jac, lbg, ubg, eq)
        fine = np.all(np.isfinite(jac), axis=(1, 2)) & np.all(np.isfinite(res), axis=1)
        finite[todo[~fine]] = False
        todo, res, jac = todo[fine], res[fine], jac[fine]
        # a point Newton has no more to do: met to rounding, or unchanged by the last step
        # (held at the box's edge)
        done = np.abs(res).max(axis=1, initial=0.0) <= SETTLED
        if last is not None:
            done |= np.abs(res - last[fine]).max(axis=1, initial=0.0) <= SETTLED
        todo, res, jac = todo[~done], res[~done], jac[~done]
        if step == STEPS or todo.size == 0:
            break
        last = res
        dx = (np.linalg.pinv(jac) @ res[..., None])[..., 0]
        # a part on a bound that the step would take beyond it stays there, and the step is
        # taken again without it (else each clipped step undoes part of the next)
        at = x[todo]
        out = ((at <= lo) & (dx > 0)) | ((at >= hi) & (dx < 0))
        if out.any():
            dx = (np.linalg.pinv(jac * ~out[:, None, :]) @ res[..., None])[..., 0]
        x[todo] = np.clip(at - dx, lo, hi)
    x, g = x[finite], g[finite]
    ok = np.all(np.abs(g[:, eq] - lbg[eq]) <= CLOSE, axis=1)
    if every:
        ok &= np.all(g[:, ~eq] >= lbg[~eq] - MET, axis=1)
        ok &= np.all(g[:, ~eq] <= ubg[~eq] + MET, axis=1)
    return cast(np.ndarray, x[ok & np.all(np.isfinite(x), axis=1)])


def breach(
    form: Formulation, key: object, x: np.ndarray, pv: np.ndarray, lo: np.ndarray, hi: np.ndarray
) -> np.ndarray:
    """How far each point x (rows) breaks the formulation's rows and the box, summed: 0
    where it meets them (to ``MET``), inf where a row is NaN."""
    g = constraints(form, key, x, pv)[0]
    rows = np.maximum(form.lbg - MET - g, 0) + np.maximum(g - form.ubg - MET, 0)
    box = np.maximum(lo - MET - x, 0) + np.maximum(x - hi - MET, 0)
    return cast(np.ndarray, np.nan_to_num(np.sum(rows, axis=1) + np.sum(box, axis=1), nan=np.inf))


def _held(
    g: np.ndarray, jac: np.ndarray, lbg: np.ndarray, ubg: np.ndarray, eq: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Each point's residuals and their rows of ∂g/∂x for a Newton step: the equalities', and
    those of the inequalities beyond or within ``INSIDE`` of a limit, to ``INSIDE`` inside it
    (the other rows 0)."""
    with np.errstate(invalid="ignore"):  # an infinite limit: never held
        low = lbg + INSIDE * np.maximum(1.0, np.abs(lbg))
        high = ubg - INSIDE * np.maximum(1.0, np.abs(ubg))
        below, above = ~eq & (g < low), ~eq & (g > high)
        target = np.where(eq, lbg, np.where(below, low, np.where(above, high, g)))
    held = eq | below | above
    res = np.where(held, g - target, 0.0)
    return res, np.where(held[..., None], jac, 0.0)


def rank(m: Mechanism, variant: frozenset[str], pvs: np.ndarray, terms: str) -> np.ndarray:
    """Each design's motion measure (``terms``: the middle's speed, or the acceleration),
    approximately, from a grid of crank angles; inf for a design whose slider does not run
    one stroke each way on it."""
    g = _sampled(m, variant, pvs)
    with np.errstate(all="ignore"):  # a design that does not run: inf below
        measure = _measure(terms, g.s, g.v, g.a, g.working, g.stroke)
    return np.where(g.fine & np.isfinite(measure), measure, np.inf)


def rank_torque(
    m: Mechanism, variant: frozenset[str], pvs: np.ndarray, load: Load, metres: float
) -> np.ndarray:
    """Each design's peak crank torque under ``load`` (its lengths ``metres`` each),
    approximately: the Newton–Euler equations solved at a grid of crank angles, the load's
    force from its profile at the ram's place on the grid, without the weights where gravity
    is given in the machine's frame; inf where the slider does not run one stroke each way on
    it."""
    load = replace(load, ram_incline_deg=None)
    g = _sampled(m, variant, pvs)
    profile = np.array(load.profile)
    with np.errstate(all="ignore"):
        travel = np.abs(g.s - g.s[:, :1]) / g.stroke[:, None]  # from the working stroke's start
        inside = g.working & (travel >= profile[0, 0]) & (travel <= profile[-1, 0])
        force = np.where(inside, np.interp(travel, profile[:, 0], profile[:, 1]), 0.0)
    push = -force * np.where(g.up, 1.0, -1.0)[:, None]  # against the working stroke's travel
    k = len(pvs)
    rows = np.column_stack(
        [np.repeat(pvs, ANGLES, axis=0), np.tile(numbers(load, metres), (k * ANGLES, 1))]
    )
    rows[:, pvs.shape[1] + kinetics.LOAD.index("force")] = push.ravel()
    with np.errstate(all="ignore"):
        torque = forces(m, variant).each(g.angles.ravel(), rows)[:, 0].reshape(k, ANGLES)
    peak = np.max(torque, axis=1)
    return np.where(g.fine & np.isfinite(peak), peak, np.inf)


@dataclass(frozen=True)
class _Grid:
    """Designs sampled at ``ANGLES`` crank angles, from each one's working stroke's start:
    the angles, s, s′, s″, which samples are in the working stroke, its travel (``stroke``),
    whether s grows in it (``up``), and which designs run one stroke each way (``fine``)."""

    angles: np.ndarray
    s: np.ndarray
    v: np.ndarray
    a: np.ndarray
    working: np.ndarray
    stroke: np.ndarray
    up: np.ndarray
    fine: np.ndarray


def _sampled(m: Mechanism, variant: frozenset[str], pvs: np.ndarray) -> _Grid:
    k = len(pvs)
    grid = np.linspace(0.0, 2 * np.pi, ANGLES, endpoint=False)
    out = model(m, variant).fn.each(np.tile(grid, k), np.repeat(pvs, ANGLES, axis=0))
    nr = out.shape[0] // 3
    s, v, a = (out[i * nr].reshape(k, ANGLES) for i in range(3))
    lo, hi = np.argmin(s, axis=1), np.argmax(s, axis=1)
    up = (hi - lo) % ANGLES  # samples while the slider goes from its least to its largest s
    slow_up = 2 * up >= ANGLES
    first = np.where(slow_up, lo, hi)  # the working stroke starts here
    length = np.where(slow_up, up, ANGLES - up)
    index = (first[:, None] + np.arange(ANGLES)[None, :]) % ANGLES
    rows = np.arange(k)[:, None]
    s, v, a = s[rows, index], v[rows, index], a[rows, index]  # from the working stroke's start
    working = np.arange(ANGLES)[None, :] < length[:, None]
    stroke = np.abs(s[:, 0] - s[rows[:, 0], length % ANGLES])
    fine = (stroke > 0) & (length > 1) & (length < ANGLES - 1)
    return _Grid(grid[index], s, v, a, working, stroke, slow_up, fine)


def _measure(
    terms: str,
    s: np.ndarray,
    v: np.ndarray,
    a: np.ndarray,
    working: np.ndarray,
    stroke: np.ndarray,
) -> np.ndarray:
    """The measure from s, s′ and s″ sampled from the working stroke's start."""
    rows = np.arange(len(s))
    if terms == "acceleration":
        measure = np.maximum(_peak(a, working), _peak(a, ~working)) / stroke
    else:  # the middle of the working stroke: its share of the travel, and of the crank's turn
        travel = np.where(working, np.abs(s - s[:, :1]) / stroke[:, None], 2.0)
        ends = []
        for level in (CUT, 1 - CUT):  # where the travel reaches it, interpolated
            i = np.clip(np.argmax(travel >= level, axis=1), 1, ANGLES - 1)
            t0, t1 = travel[rows, i - 1], travel[rows, i]
            ends.append(i - 1 + (level - t0) / (t1 - t0))
        middle = working & (travel >= CUT) & (travel <= 1 - CUT)
        turn = (ends[1] - ends[0]) * (2 * np.pi / ANGLES)
        speed = _peak(v, middle)
        measure = speed * turn / ((1 - 2 * CUT) * stroke)
    return cast(np.ndarray, measure)


def _peak(y: np.ndarray, where: np.ndarray) -> np.ndarray:
    """The largest |y| of each row where ``where`` holds, by the parabola through its largest
    sample and that sample's neighbours."""
    y = np.abs(y)
    i = np.argmax(np.where(where, y, -1.0), axis=1)
    rows = np.arange(len(y))
    y0, y1, y2 = (y[rows, (i + d) % y.shape[1]] for d in (-1, 0, 1))
    curve = 2 * y1 - y0 - y2
    top = y1 + np.where(curve > 0, (y0 - y2) ** 2 / (8 * curve), 0.0)
    return np.where(np.any(where, axis=1), top, 0.0)
