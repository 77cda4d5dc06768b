"""The searched objectives' local search over one variant (``motion``): SLSQP in epigraph form,
from ranked starts, in the variant's coordinates.

- the constraints are the type's formulation (``synth.synthesis.formulation``: CasADi, exact
  derivatives), the bounds the request's;
- each measure is the largest of a few terms (the speed, acceleration or torque at each place
  along the turn where it may peak), so the NLP takes it in epigraph form, with the terms'
  exact derivatives (``quality.motion_terms``, ``loads.peak_terms``: the envelope theorem at
  a peak, the implicit function theorem at a dead centre or a window's end);
- its starts are the exact solvers' designs for the request (best-transmitting and smallest)
  and ``SAMPLES`` points its coordinates draw (the box's, or the construction's, in one set
  or more) projected onto the equalities (with few such designs, ``SAMPLES`` more within
  ``AROUND`` of the starts) and the designs the coordinates' evolution finds (a four-bar's
  construction, ``chart.Chart.evolve``), ranked by their measure on a grid of crank angles
  (``screen``); it runs from the ``STARTS`` best of the former and as many of each set of
  the latter as ``Aim.drawn`` says (of a further set, fewer), at most ``MAX_ITER``
  iterations each, but not from a start ``FAR_ABOVE`` the best (the smallest design at a
  0° bound, near locking, measures 10–5 000 times the best start: its runs went to the edge
  of the coordinates and ended infeasible).
- its coordinates (``Coordinates``): a four-bar with its arm and all its links but one free
  moves on its dead-centre construction (``chart``), where every point meets the time ratio
  and the stroke; any other variant in its free parameters, the equalities constraints.

No clock but the request's deadline decides anything: a run it cuts short ends at its last
iterate (and the caller answers the exact designs alone)."""

from __future__ import annotations

import time
import warnings
from collections.abc import Iterator, Mapping
from typing import Any, Protocol

import numpy as np

from ..errors import SynthError
from ..mechanisms import Mechanism
from . import aims, chart, screen
from .formulation import TIE, Formulation, formulation, kept_by
from .solve import starts as halton

# SLSQP runs per variant from the best ranked exact solvers' designs (STARTS) and projected
# points of the box, where the four-bars' other basins lie (``Aim.drawn``)
STARTS = 2
MAX_ITER = 300
AROUND = 3.0  # the box about the starts (each part within this factor of theirs) drawn again
STILL = 5  # iterations without a change above 1e-12 (stroke units) that end an SLSQP run
# a run ends once it comes this close (stroke units, each parameter) to where an earlier run
# ended, its epigraph's t no further below that run's measure than LEVEL (relative; 1e-3 ended
# a crank shaper's runs on their way to an optimum 6e-4 below a neighbour 1e-2 away)
NEAR, LEVEL = 1e-2, 1e-4
TERMS = 4  # the largest terms of a measure that its epigraph bounds
SAMPLES = 256  # Halton points of the box projected onto the equalities (``screen``): starts
FAIL = 1e3  # a design the analysis rejects, for the line search: far above every measure
FAR_ABOVE = 10.0  # a start measuring more than this many times the best start's: no run


class Late(Exception):
    """The deadline passed before an evaluation of the measure (``local_optima``)."""


class Known(Exception):
    """A run came to an optimum an earlier run ended at (``local_optima``)."""


Rows = tuple[np.ndarray, np.ndarray]  # values (≥ 0 where met) and their derivatives in z
Point = tuple[np.ndarray, np.ndarray | None, Rows]  # x(z), ∂x/∂z, the coordinates' own rows


class Coordinates(Protocol):
    """Where SLSQP moves: points z, each start with its constants c; ``point``: the free
    parameters x(z), ∂x/∂z (None: x is z) and the coordinates' own inequality rows at z (the
    request's bounds where they are no bounds of z), in one evaluation. ``equalities``:
    whether x(z) may leave the formulation's equalities (then constrained); ``draw``: sets
    of n points (parameters) spread over the space, which the search projects onto the
    formulation's constraints and ranks as starts, each set on its own; ``evolve``: the
    designs an evolution finds least by a measure of many designs (perhaps none); ``end``:
    the parameters a run's point stands for, from its x(z) (a free scale at its least).
    ``scaled``: whether the scale is one of the coordinates (each start keeps its own)."""

    equalities: bool
    drawn: str  # the key of ``Aim.drawn``
    scaled: bool

    def starts(self, x: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]: ...
    def point(self, z: np.ndarray, c: np.ndarray) -> Point: ...
    def bounds(self) -> list[tuple[float, float]]: ...
    def draw(self, n: int) -> list[np.ndarray]: ...
    def evolve(self, measure: Any) -> np.ndarray: ...
    def end(self, x: np.ndarray) -> np.ndarray: ...


class Parameters:
    """The variant's free parameters themselves, within the request's box."""

    equalities = True
    drawn = "free"
    scaled = False

    def __init__(self, lo: np.ndarray, hi: np.ndarray) -> None:
        self.lo, self.hi = lo, hi

    def starts(self, x: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
        return [(x, np.empty(0))]

    def point(self, z: np.ndarray, c: np.ndarray) -> Point:
        return z, None, (np.empty(0), np.empty((0, len(z))))

    def bounds(self) -> list[tuple[float, float]]:
        return list(zip(self.lo, self.hi, strict=True))

    def draw(self, n: int) -> list[np.ndarray]:
        """Halton points of the box (log-uniform where its bounds are positive)."""
        return [halton(self.lo, self.hi, self.lo > 0, n)]

    def evolve(self, measure: Any) -> np.ndarray:
        """None: only a four-bar's construction evolves (its basins are narrow)."""
        return np.empty((0, len(self.lo)))

    def end(self, x: np.ndarray) -> np.ndarray:
        return x


def local_optima(
    m: Mechanism,
    variant: frozenset[str],
    free: tuple[str, ...],
    fixed: dict[str, float],
    bounds: Mapping[str, tuple[float, float]],
    explicit: frozenset[str],
    targets: tuple[float, float],
    aim: aims.Aim,
    starts: list[dict[str, float]],
    limit: tuple[aims.Pick, float] | None,
    deadline: float,
    fixed_parts: bool = False,
) -> Iterator[dict[str, float]]:
    """Local optima of the ``aim``'s measure over one variant, each as its run ends (verified
    by the caller before the next), from ``starts`` (designs, stroke units); ``targets`` is
    (time ratio, cos of the transmission bound). The measure, a maximum of terms, is minimised
    in epigraph form: t ≥ each of the ``TERMS`` largest terms (a peak moving along the turn is
    one constraint handing over to another, not a kink); a ``limit`` (terms, cap) bounds its
    terms alike. A default bound (not in ``explicit``) gives way to a start beyond it. Points
    about the starts are drawn where the box's hold too few designs; ``fixed_parts`` (the
    request fixes parts): more drawn starts are run from, whichever the coordinates. The
    deadline is looked at before each evaluation of the measure at a new design (a few ms,
    ~15 with a load): a run it cuts short ends at its last iterate."""
    if time.monotonic() >= deadline:  # nothing built for a search that cannot run
        return
    from scipy.optimize import minimize  # on first use: ~0.4 s of an import of synth

    form = formulation(m, variant, free)
    key = kept_by(m, variant, free)
    pv = np.concatenate([[fixed[k] for k in form.fixed], targets])
    n = len(free)

    def design(x: np.ndarray) -> dict[str, float]:
        return {**fixed, **dict(zip(free, x, strict=True)), **dict.fromkeys(variant, 0.0)}

    memo: dict[bytes, Any] = {}
    columns = [m.names.index(k) for k in free]  # the free parameters among the type's

    def terms(x: np.ndarray) -> Any:
        key = x.tobytes()
        if key not in memo:
            if time.monotonic() >= deadline:
                raise Late
            if len(memo) > 256:
                memo.clear()
            try:
                memo[key] = aim.evaluate(design(x))
            except SynthError:
                memo[key] = None
        return memo[key]

    def box_of(s: dict[str, float]) -> list[tuple[float, float]]:
        return [
            bounds[k] if k in explicit else (min(bounds[k][0], s[k]), max(bounds[k][1], s[k]))
            for k in free
        ]

    # the starts: the exact solvers' designs and projected Halton points, the best ranked first
    wide = box_of(starts[0]) if starts else [bounds[k] for k in free]
    lo, hi = (np.array([b[i] for b in wide]) for i in (0, 1))
    coords: Coordinates = (
        chart.Chart(m, variant, free, lo, hi, targets[0], not aim.scale_free, fixed)
        if chart.applies(m, variant, free)
        else Parameters(lo, hi)
    )
    drawn = aim.drawn["fixed" if fixed_parts else coords.drawn]  # whichever the coordinates
    measured = _ranked(m, form, key, pv, lo, hi, starts, free, drawn, coords, aim, terms, design)
    # a start at the smallest member of its free scale (the same motion): SLSQP then has a
    # bound in that direction, where it would crawl towards the tie to the smaller design;
    # where the scale is a coordinate (the measure depends on it), each start keeps its own
    sc = m.scale
    scaled = [] if sc is None else [free.index(k) for k in (sc.free, *sc.tied) if k in free]
    if not coords.scaled and sc is not None and len(scaled) == 1 + len(sc.tied):
        for _, x in measured:
            x[scaled] *= max(lo[scaled] / x[scaled])
    links = np.array([float(m.parameter(k).link) for k in free])
    ended: list[tuple[np.ndarray, float]] = []  # where the runs so far ended, their t
    best = min((first for first, _ in measured), default=0.0)
    for first, x0 in measured:
        if first > FAR_ABOVE * best > 0:  # a design near locking (the smallest at a 0° bound)
            continue
        for z0, c in coords.starts(x0):
            if time.monotonic() >= deadline:
                return
            kept = _independent(form, key, pv, x0) if coords.equalities else np.empty(0, int)
            if kept.size == n:  # the equalities leave no freedom: the start is the optimum
                yield design(x0)
                continue
            run = _Run(coords, c, len(z0), form, key, pv, kept, terms, columns, aim, limit)
            seen: list[np.ndarray] = []  # this run's iterates

            def cap(y: np.ndarray, seen: list[np.ndarray] = seen, run: _Run = run) -> None:
                """Ends SLSQP (with its last iterate, projected below) at the deadline; once
                its iterates stand still (where its line search can no longer meet ``ftol``
                it may repeat one point for a hundred iterations). Once it comes within
                ``NEAR`` of an optimum an earlier run ended at, no lower than it by ``LEVEL``,
                the run ends with nothing of its own (``Known``: the rest is that run's)."""
                seen.append(y.copy())
                still = len(seen) > STILL and np.ptp(seen[-STILL:], axis=0).max() <= 1e-12
                x = coords.end(run.x(y)[0])  # as the ends are kept (a free scale its least)
                known = any(
                    np.abs(x - e).max() <= NEAR and y[-1] >= t - LEVEL * abs(t) for e, t in ended
                )
                if known:
                    raise Known
                if still or time.monotonic() >= deadline:
                    raise StopIteration

            try:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")  # SLSQP's notes on clipping to the bounds
                    last = minimize(
                        lambda y, run=run: y[-1] + TIE * (links @ run.x(y)[0]),
                        np.append(z0, first),
                        jac=lambda y, run=run: np.append(TIE * _chained(links, run.x(y)[1]), 1.0),
                        method="SLSQP",
                        bounds=[*coords.bounds(), (0.0, None)],
                        constraints=run.constraints,
                        callback=cap,
                        options={"maxiter": MAX_ITER, "ftol": 1e-12},
                    ).x
            except Known:  # the rest is an earlier run's: nothing of its own to answer
                continue
            except Late:  # within an iteration: the run ends where its last one did
                if not seen:
                    return
                last = seen[-1]
            # SLSQP meets its constraints to ~1e-8, the verification asks 1e-9: projected onto
            # the equalities, the inequalities it is beyond held inside
            end = coords.end(run.x(last)[0])
            for x in screen.project(form, key, end[None], pv, lo, hi, every=False):
                ended.append((x, float(last[-1])))
                yield design(x)


class _Run:
    """One SLSQP run's functions of y = (z, t): the parameters x(z), the terms, and the
    constraints: the kept equalities, the formulation's inequalities, the coordinates' own
    rows, t ≥ each of the largest terms, the limit's cap on its terms."""

    def __init__(
        self,
        coords: Coordinates,
        c: np.ndarray,
        k: int,
        form: Formulation,
        key: object,
        pv: np.ndarray,
        kept: np.ndarray,
        terms: Any,
        columns: list[int],
        aim: aims.Aim,
        limit: tuple[aims.Pick, float] | None,
    ) -> None:
        self.coords, self.c, self.k = coords, c, k
        self.form, self.key, self.pv, self.terms, self.columns = form, key, pv, terms, columns
        self.memo: dict[bytes, dict[str, Any]] = {}  # per point z: what was found there
        lbg, ubg = form.lbg, form.ubg
        eq = lbg == ubg
        self.below, self.above = np.isfinite(lbg) & ~eq, np.isfinite(ubg) & ~eq
        self.constraints: list[dict[str, Any]] = []
        if kept.size:
            self.constraints.append(
                {
                    "type": "eq",
                    "fun": lambda y: self.rows(y)[0][kept] - lbg[kept],
                    "jac": lambda y: self.rows(y)[1][kept],
                }
            )
        self.constraints += [
            {"type": "ineq", "fun": lambda y: self.inequalities(y)[0], "jac": self._jac},
            self.bounded(aim.pick, None),
        ]
        if limit is not None:
            self.constraints.append(self.bounded(*limit))

    def _at(self, y: np.ndarray) -> dict[str, Any]:
        """What was found at the point z of y = (z, t): SLSQP asks each function and its
        derivatives there in turn, each found once."""
        z = y[: self.k]
        key = z.tobytes()
        if key not in self.memo:
            if len(self.memo) > 64:
                self.memo.clear()
            self.memo[key] = {"point": self.coords.point(z, self.c)}
        return self.memo[key]

    def x(self, y: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
        """x(z) and ∂x/∂z."""
        x, dx, _ = self._at(y)["point"]
        return x, dx

    def rows(self, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The formulation's rows at x(z) and their derivatives in y (t appears in none)."""
        at = self._at(y)
        if "rows" not in at:
            x, dx = self.x(y)
            g, jac = screen.constraints(self.form, self.key, x[None], self.pv)
            at["rows"] = g[0], np.hstack([_chained(jac[0], dx), np.zeros((g.shape[1], 1))])
        rows: tuple[np.ndarray, np.ndarray] = at["rows"]
        return rows

    def inequalities(self, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The formulation's inequalities and the coordinates' own rows, with derivatives."""
        at = self._at(y)
        if "inequalities" not in at:
            g, j = self.rows(y)
            lbg, ubg, below, above = self.form.lbg, self.form.ubg, self.below, self.above
            own, own_j = at["point"][2]
            values = np.concatenate([g[below] - lbg[below], ubg[above] - g[above], own])
            own_j = np.hstack([own_j, np.zeros((len(own), 1))])
            at["inequalities"] = values, np.vstack([j[below], -j[above], own_j])
        ineq: tuple[np.ndarray, np.ndarray] = at["inequalities"]
        return ineq

    def _jac(self, y: np.ndarray) -> np.ndarray:
        return self.inequalities(y)[1]

    def largest(self, y: np.ndarray, pick: aims.Pick) -> tuple[np.ndarray, np.ndarray]:
        """The ``TERMS`` largest terms (the last repeated where there are fewer), and their
        derivatives in z."""
        x, dx = self.x(y)
        got = self.terms(x)
        if got is None:
            return np.full(TERMS, FAIL), np.zeros((TERMS, self.k))
        values, dp = pick(got)
        order = np.argsort(values)[::-1][:TERMS]
        order = np.concatenate([order, np.full(TERMS - order.size, order[-1])])
        return values[order], _chained(dp[order][:, self.columns], dx)

    def bounded(self, pick: aims.Pick, cap: float | None) -> dict[str, Any]:
        """The constraint cap − each of the largest terms ≥ 0 (cap None: the epigraph's t)."""

        def fun(y: np.ndarray) -> np.ndarray:
            return (y[-1] if cap is None else cap) - self.largest(y, pick)[0]

        def jac(y: np.ndarray) -> np.ndarray:
            out = np.zeros((TERMS, y.size))
            out[:, :-1] = -self.largest(y, pick)[1]
            out[:, -1] = 1.0 if cap is None else 0.0
            return out

        return {"type": "ineq", "fun": fun, "jac": jac}


def _chained(d: np.ndarray, dx: np.ndarray | None) -> np.ndarray:
    """Derivatives in x as derivatives in z."""
    return d if dx is None else d @ dx


def _independent(form: Formulation, key: object, pv: np.ndarray, x: np.ndarray) -> np.ndarray:
    """The equalities' rows independent at x: where the targets set one ratio twice (a
    slotted lever's fixed lever: the time ratio and the stroke both set crank /
    pivot_distance), the second is met with the first, and SLSQP's subproblems would be
    singular with both."""
    from scipy.linalg import qr

    eq = form.lbg == form.ubg
    jac = screen.constraints(form, key, x[None], pv)[1][0][eq]
    _, r, order = qr(jac.T, pivoting=True, mode="economic")
    diag = np.abs(np.diag(r))
    rank = int(np.sum(diag > 1e-9 * diag[0])) if diag.size and diag[0] > 0 else diag.size
    kept: np.ndarray = np.flatnonzero(eq)[np.sort(order[:rank])]
    return kept


def _ranked(
    m: Mechanism,
    form: Formulation,
    key: object,
    pv: np.ndarray,
    lo: np.ndarray,
    hi: np.ndarray,
    starts: list[dict[str, float]],
    free: tuple[str, ...],
    drawn_starts: int,
    coords: Coordinates,
    aim: aims.Aim,
    terms: Any,
    design: Any,
) -> list[tuple[float, np.ndarray]]:
    """The runs' starts, measured, with their measures: the best ranked of the exact designs
    (``STARTS``), of the coordinates' projected points (``drawn_starts``) and of points about
    the starts where those hold too few designs, then of each further set the coordinates
    draw and of the designs their evolution finds (``Aim.drawn``'s "further", "evolved").
    Empty where the deadline passed."""
    n = len(free)
    own = np.array([np.clip([s[k] for k in free], lo, hi) for s in starts]).reshape(-1, n)
    drawn, *more = (screen.project(form, key, d, pv, lo, hi) for d in coords.draw(SAMPLES))
    near = drawn[:0]
    if len(drawn) < drawn_starts and len(own):
        # the box's points may hold few designs (a drag-link's ground is its shortest link; a
        # short fixed coupler leaves a four-bar's other links few): points about the starts too
        near_lo = np.maximum(lo, np.where(lo > 0, own.min(axis=0) / AROUND, lo))
        near_hi = np.minimum(hi, np.where(lo > 0, own.max(axis=0) * AROUND, hi))
        near = screen.project(form, key, halton(near_lo, near_hi, lo > 0, SAMPLES), pv, lo, hi)

    def filled(points: np.ndarray) -> np.ndarray:
        return np.array([list(m.filled(design(x)).values()) for x in points])

    def valued(x: np.ndarray, circuit: np.ndarray) -> np.ndarray:
        """The evolution's measure: the rank, or FAIL + how far x breaks a row or the box."""
        out: np.ndarray = FAIL + (broken := circuit + screen.breach(form, key, x, pv, lo, hi))
        if (met := broken == 0).any():  # only these are ranked
            out[met] = np.minimum(aim.rank(filled(x[met])), FAIL)
        return out

    evolved = coords.evolve(valued) if aim.drawn["evolved"] else near[:0]
    sets = [own, drawn, near, *more, screen.project(form, key, evolved, pv, lo, hi)]
    points = np.vstack(sets)
    value = aim.rank(filled(points)) if len(points) else np.empty(0)
    measured = []  # the best ranked of each source that the analysis takes
    ends = np.cumsum([0, *map(len, sets)])
    further = [aim.drawn["further"]] * len(more)
    for j, most in enumerate([STARTS, drawn_starts, drawn_starts, *further, aim.drawn["evolved"]]):
        source = np.arange(ends[j], ends[j + 1])
        taken = 0
        for k in source[np.argsort(value[source], kind="stable")]:
            try:
                got = terms(points[k]) if np.isfinite(value[k]) and taken < most else None
            except Late:
                return []
            if got is not None:
                measured.append((float(aim.pick(got)[0].max()), points[k]))
                taken += 1
    return measured
