"""Newton's method on one stratum of a four-bar problem, as an active-set method (the
``Strata`` search's step from each start).

From a start on a stratum (the region, a curve of active bounds, a line ψ = const or a point
where they meet), ``dense.descend`` (safeguarded Newton on the Lagrangian: it only descends,
and steps along a curve are projected back onto it) runs with every other bound guarded: a
step that would cross one is halved, and where halving does not keep it, Newton stops at its
last point and the bound it crosses first (or a line ψ = const: the swing's range edge, a
rod's kink) joins the active ones, while the stratum has room; a bound that joined and whose
multiplier says the objective falls away from it leaves again. A start that leads to no
feasible minimum leaves its floor as a doubt.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ...numerics.dense import Taylor, descend
from .construction import AT, construction
from .levels import ROW, Level
from .search import U_HI, U_LO, Search

HALVINGS = 4  # halvings of a step that would leave the designs or cross a bound


@dataclass
class Found:
    """The feasible stationary points found, and the doubts left (floors of starts that led
    nowhere)."""

    points: list[tuple[float, np.ndarray]]
    floors: list[float]
    samples: float  # the least objective over the feasible samples


@dataclass
class Start:
    """Where Newton starts on a stratum (the ``active`` levels, ψ held at ``psi`` if given):
    the least the objective can be near it (``floor``), its value there and the largest
    difference to its neighbours; ``optional``: a possible meeting of curves, no doubt if it
    leads nowhere."""

    floor: float
    x: np.ndarray
    active: tuple[int, ...]
    value: float = math.nan
    spread: float = 0.0
    psi: float | None = None
    optional: bool = False


@dataclass
class _Guard:
    """What stopped a Newton run: the bound its last step would cross (a level, or the
    swing's range edge as a float), and its last point within the bounds, with its local
    model."""

    blocked: int | float | None = None
    last: list[float] | None = None
    t: list[float] | None = None


class ActiveSet:
    """The active-set steps of one sheet's search (``strata.Strata``)."""

    s: Search
    sigma: int
    key: str
    levels: list[Level]
    ineqs: list[int]
    obj: Level
    range: tuple[float, float]
    walls: list[float]
    cell: np.ndarray

    def _cell(self, psi: float) -> np.ndarray:
        raise NotImplementedError

    def _chain(self, found: Found, st: Start) -> None:
        """Newton from x0 on the stratum of the ``active`` levels (ψ held at ``psi``, if
        given), an active-set method: a step that would cross a bound is halved, and where
        halving does not keep it, Newton stops at its last point and that bound (or the
        swing's range edge) joins the active ones, while the stratum has room; a bound that
        joined and whose multiplier says the objective falls away from it leaves again. A
        start that leads to no feasible stationary point leaves its floor as a doubt (none
        for an ``optional`` one: a possible meeting of two curves)."""
        x, active, value, psi = st.x, st.active, st.value, st.psi
        base = len(active)
        for _ in range(6):
            guard = _Guard()
            local = self._local(active, psi, guard)
            cell = self.cell[1:] if psi is not None else self._cell(x[0])
            y = descend(
                local, x[1:] if psi is not None else x, len(active), cell, halvings=HALVINGS
            )
            if y is not None and guard.t is not None:
                x = np.array([psi, y[0]]) if psi is not None else y
                t = guard.t
                beyond = [(self.levels[k].value(t), k) for k in self.ineqs if k not in active]
                beyond = [(g, k) for g, k in beyond if g < -self.levels[k].tol]
                if beyond:  # a point beyond another bound (steps to it are not guarded):
                    if len(active) == base:  # that bound, not the last that joined
                        break
                    active = (*active[:-1], min(beyond)[1])
                    continue
                wrong = self._leaving(t, active, base, psi)
                if wrong is not None:
                    active = tuple(k for k in active if k != wrong)
                    continue
                v = guard.t[AT + 6 * ROW[self.key]]
                # a stationary point worse than the start's neighbourhood: not its minimum
                if not (math.isfinite(value) and v > value + st.spread + 1e-12 * abs(value)):
                    found.points.append((v, x))
                    return
                break
            if guard.blocked is None or guard.last is None:
                break
            x = np.array(guard.last)
            if isinstance(guard.blocked, float):  # the swing's range edge: its line
                if psi is not None or len(active) > 1:
                    break
                psi = guard.blocked
                x[0] = psi
                continue
            if len(active) < (1 if psi is not None else 2):
                active = (*active, guard.blocked)
            elif len(active) > base and guard.blocked not in active:
                active = (*active[:-1], guard.blocked)  # the bound that joined was not the first
            else:
                break
        if not st.optional:
            found.floors.append(st.floor)

    def _leaving(
        self, t: list[float], active: tuple[int, ...], base: int, psi: float | None
    ) -> int | None:
        """The bound among those that joined (``active[base:]``) whose multiplier has the
        wrong sign (the objective falls into the feasible side), if any."""
        if len(active) == base:
            return None
        obj = self.obj.local(t)[1]
        grads = [self.levels[k].local(t)[1] for k in active]
        if psi is not None:
            obj, grads = [obj[1]], [[g[1]] for g in grads]
        a = np.array(grads)
        nu = np.linalg.lstsq(a.T, -np.array(obj), rcond=None)[0]
        scale = float(np.linalg.norm(obj)) / max(float(np.linalg.norm(a)), 1e-300)
        for n in range(base, len(active)):
            if nu[n] > 1e-9 * scale:  # ∇obj = −Σ ν ∇g: a bound that holds has ν ≤ 0
                return active[n]
        return None

    def _local(
        self, active: tuple[int, ...], psi: float | None, guard: _Guard
    ) -> Callable[[list[float]], Taylor | None]:
        """Newton's local model: the objective and the active levels, in (ψ, u) or (u,);
        None (a step to halve) at a point that is no design or beyond a bound that is not
        active (``guard`` says which, and keeps the last point within them)."""
        params, taylor = self.s._params(self.sigma), construction().taylor
        rows = [self.obj, *(self.levels[k] for k in active)]
        others = [(k, self.levels[k]) for k in self.ineqs if k not in active]
        point = len(active) == (1 if psi is not None else 2)
        lo, hi = self.range

        def local(x: list[float]) -> Taylor | None:
            at = psi if psi is not None else x[0]
            if not lo <= at <= hi:  # the range's edge: a line, or no design beyond
                edge = lo if at < lo else hi
                guard.blocked = edge if edge in self.walls else None
                return None
            if not U_LO - 1 <= x[-1] <= U_HI + 1:  # beyond the searched couplers
                guard.blocked = None
                return None
            t = taylor(at, x[-1], params)
            last = guard.t
            # the bounds and walls (a kink of the rod's length: a line of its own) the step
            # crosses, at their fraction of the step from the last point within them
            crossed: list[tuple[float, int | float]] = []
            if not point:  # a point's equalities alone decide its steps: judged at the end
                for k, lv in others:
                    gk = lv.value(t)
                    if gk < -lv.tol:
                        crossed.append((0.0 if last is None else _fraction(lv.value(last), gk), k))
            if psi is None and guard.last is not None:
                was = guard.last[0]
                crossed += [
                    ((w - was) / (at - was), w)
                    for w in self.walls
                    if min(was, at) < w < max(was, at)
                ]
            if crossed:
                guard.blocked = min(crossed)[1]
                return None
            if not (t[0] > 0 and math.isfinite(t[1])):
                guard.blocked = None  # no design
                return None
            guard.blocked, guard.last, guard.t = None, [at, x[-1]], t
            vals, grads, hess = [], [], []
            for lv in rows:
                v, g, h = lv.local(t)
                vals.append(v)
                grads.append([g[1]] if psi is not None else g)
                hess.append([[h[1][1]]] if psi is not None else h)
            return vals, grads, hess

        return local


def _fraction(before: float, after: float) -> float:
    """Where along a step a level went from ``before`` (≥ 0) to ``after`` (< 0) crosses 0."""
    return before / (before - after) if before > after else 0.0
