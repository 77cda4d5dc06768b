"""The searched objectives (``synth.objectives``): how the slider moves
(``uniform_cutting_speed``, ``min_peak_acceleration``, with a limit on the fluctuation) and
what it asks of the drive (``min_peak_torque``, with a limit on it under the request's load).
What each search bounds is its ``aims.Aim``.

No closed form gives these measures: they are extremes over the crank's turn, found by root
finding (``synth.analysis.quality``, ``synth.analysis.loads``). Where a variant's designs are
a box of free numbers and the measure is one the certified search takes (``certify``), it
answers, with its certificate. Otherwise the designs come from a local NLP over each
variant's free parameters (stroke units), solved by SLSQP:

- the constraints are the type's formulation (``synth.synthesis.formulation``: CasADi, exact
  derivatives), the bounds the request's;
- each measure is the largest of a few terms (the speed, acceleration or torque at each place
  along the turn where it may peak), so the NLP takes it in epigraph form, with the terms'
  exact derivatives (``quality.motion_terms``, ``loads.peak_terms``: the envelope theorem at
  a peak, the implicit function theorem at a dead centre or a window's end);
- its starts are the exact solvers' designs for the request (best-transmitting and smallest,
  at ``ACROSS_DEG`` without a bound) and ``SAMPLES`` points of the box projected onto the
  equalities (with fixed parts and few such points, ``SAMPLES`` more within ``AROUND`` of
  the starts), ranked by their measure on a grid of crank angles (``screen``); it runs from
  the ``STARTS`` best of the former and as many of the latter as ``Aim.drawn`` says, at most
  ``MAX_ITER`` iterations each. No clock but the request's deadline decides anything: a
  type's search it cuts short answers the exact solvers' designs alone, and says so.

Its answer, a local optimum, is verified like every candidate, and checked against an
independent global search by ``tests/referees/test_motion_search.py``."""

from __future__ import annotations

import math
import time
import warnings
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import replace
from typing import Any

import numpy as np

from .. import objectives
from ..errors import SynthError
from ..mechanisms import Mechanism, get
from ..results import Candidate, Infeasible
from ..targets import MAX_TRANSMISSION, MIN_SIZE
from . import aims, certify, screen
from .candidate import candidate, distinct, smallest_member
from .diagnose import cut_short, diagnose, locked
from .formulation import TIE, formulation, kept_by
from .search import (
    Searched,
    Spec,
    Targets,
    proposal,
    scaled,
    search,
    whole,
)
from .solve import starts as halton

# SLSQP runs per variant from the best ranked exact solvers' designs (STARTS) and projected
# points of the box, where the four-bars' other basins lie (``Aim.drawn``)
STARTS = 2
MAX_ITER = 300
AROUND = 3.0  # the box about the starts (each part within this factor of theirs) drawn again
STILL = 5  # iterations without a change above 1e-12 (stroke units) that end an SLSQP run
NEAR = 1e-4  # how close (stroke units, each parameter) to an earlier run's end a run ends
TERMS = 4  # the largest terms of a measure that its epigraph bounds
SAMPLES = 256  # Halton points of the box projected onto the equalities (``screen``): starts
# the least 1 − cos μ a search for motion keeps at every joint, whatever the bound: as a rod
# comes to stand across its slider's path (μ → 0) the slider's speed there grows without
# bound in a spike narrower than the analysis's grid, so a measure there is no design's
ACROSS = 1e-3
ACROSS_DEG = math.degrees(math.acos(1 - ACROSS))
FAIL = 1e3  # a design the analysis rejects, for the line search: far above every measure


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
    about the starts are drawn where the box's hold too few designs (``fixed_parts``: more). The
    deadline is looked at before each evaluation of the measure at a new design (a few ms,
    ~15 with a load): a run it cuts short ends at its last iterate."""
    if time.monotonic() >= deadline:  # nothing built for a search that cannot run
        return
    from scipy.linalg import qr  # on first use: ~0.4 s of an import of synth
    from scipy.optimize import minimize

    form = formulation(m, variant, free)
    key = kept_by(m, variant, free)
    pv = np.concatenate([[fixed[k] for k in form.fixed], targets])
    n = len(free)

    def design(y: np.ndarray) -> dict[str, float]:
        return {**fixed, **dict(zip(free, y[:n], strict=True)), **dict.fromkeys(variant, 0.0)}

    memo: dict[bytes, Any] = {}
    columns = [m.names.index(k) for k in free]  # the free parameters among the type's

    def terms(y: np.ndarray) -> Any:
        key = y[:n].tobytes()
        if key not in memo:
            if time.monotonic() >= deadline:
                raise _Late
            if len(memo) > 256:
                memo.clear()
            try:
                memo[key] = aim.evaluate(design(y))
            except SynthError:
                memo[key] = None
        return memo[key]

    def largest(y: np.ndarray, pick: aims.Pick) -> tuple[np.ndarray, np.ndarray]:
        """The ``TERMS`` largest terms (the last repeated where there are fewer), and their
        derivatives in the free parameters."""
        got = terms(y)
        if got is None:
            return np.full(TERMS, FAIL), np.zeros((TERMS, n))
        values, dp = pick(got)
        order = np.argsort(values)[::-1][:TERMS]
        order = np.concatenate([order, np.full(TERMS - order.size, order[-1])])
        return values[order], dp[order][:, columns]

    def bounded(pick: aims.Pick, cap: float | None) -> dict[str, Any]:
        """The constraint cap − each of the largest terms ≥ 0 (cap None: the epigraph's t)."""

        def fun(y: np.ndarray) -> np.ndarray:
            return (y[n] if cap is None else cap) - largest(y, pick)[0]

        def jac(y: np.ndarray) -> np.ndarray:
            out = np.zeros((TERMS, y.size))
            out[:, :n] = -largest(y, pick)[1]
            out[:, n] = 1.0 if cap is None else 0.0
            return out

        return {"type": "ineq", "fun": fun, "jac": jac}

    lbg, ubg = form.lbg, form.ubg
    eq = lbg == ubg
    below, above = np.isfinite(lbg) & ~eq, np.isfinite(ubg) & ~eq

    def rows(y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:  # y: x, or x and t
        g, jac = screen.constraints(form, key, y[None, :n], pv)
        return g[0], np.hstack([jac[0], np.zeros((jac.shape[1], 1))])  # t appears in none

    def inequalities(y: np.ndarray) -> np.ndarray:
        g = rows(y)[0]
        return np.concatenate([g[below] - lbg[below], ubg[above] - g[above]])

    def inequalities_jac(y: np.ndarray) -> np.ndarray:
        j = rows(y)[1]
        return np.vstack([j[below], -j[above]])

    # ties (a free scale that leaves the motion as it is) to the smaller design, as the
    # formulation's max_transmission_angle does: the scale is then no flat direction
    links = np.array([float(m.parameter(k).link) for k in free] + [0.0])
    pick = aim.pick
    measures = [{"type": "ineq", "fun": inequalities, "jac": inequalities_jac}, bounded(pick, None)]
    if limit is not None:
        measures.append(bounded(*limit))

    def equalities(x: np.ndarray) -> np.ndarray:
        """The equalities' rows independent at x: where the targets set one ratio twice (a
        slotted lever's fixed lever: the time ratio and the stroke both set crank /
        pivot_distance), the second is met with the first, and SLSQP's subproblems would be
        singular with both."""
        jac = rows(x)[1][eq][:, :n]
        _, r, order = qr(jac.T, pivoting=True, mode="economic")
        diag = np.abs(np.diag(r))
        rank = int(np.sum(diag > 1e-9 * diag[0])) if diag.size and diag[0] > 0 else diag.size
        kept: np.ndarray = np.flatnonzero(eq)[np.sort(order[:rank])]
        return kept

    def box_of(s: dict[str, float]) -> list[tuple[float, float]]:
        return [
            bounds[k] if k in explicit else (min(bounds[k][0], s[k]), max(bounds[k][1], s[k]))
            for k in free
        ]

    # the starts: the exact solvers' designs and projected Halton points, the best ranked first
    wide = box_of(starts[0]) if starts else [bounds[k] for k in free]
    lo, hi = (np.array([b[i] for b in wide]) for i in (0, 1))
    own = np.array([np.clip([s[k] for k in free], lo, hi) for s in starts]).reshape(-1, n)
    drawn_starts = aim.drawn[bool(fixed_parts)]
    drawn = screen.project(form, key, halton(lo, hi, lo > 0, SAMPLES), pv, lo, hi)
    near = drawn[:0]
    if len(drawn) < drawn_starts and len(own):
        # the box's points may hold few designs (a drag-link's ground is its shortest link; a
        # short fixed coupler leaves a four-bar's other links few): points about the starts too
        near_lo = np.maximum(lo, np.where(lo > 0, own.min(axis=0) / AROUND, lo))
        near_hi = np.minimum(hi, np.where(lo > 0, own.max(axis=0) * AROUND, hi))
        near = screen.project(form, key, halton(near_lo, near_hi, lo > 0, SAMPLES), pv, lo, hi)
    points = np.vstack([own, drawn, near])
    pvs = np.array([list(m.filled(design(x)).values()) for x in points])
    value = aim.rank(pvs) if len(points) else np.empty(0)
    measured = []  # the best ranked of each source that the analysis takes
    ends = np.cumsum([0, len(own), len(drawn), len(near)])
    for j, most in enumerate((STARTS, drawn_starts, drawn_starts)):
        source = np.arange(ends[j], ends[j + 1])
        taken = 0
        for k in source[np.argsort(value[source], kind="stable")]:
            try:
                got = terms(points[k]) if np.isfinite(value[k]) and taken < most else None
            except _Late:
                return
            if got is not None:
                measured.append((float(pick(got)[0].max()), points[k]))
                taken += 1
    # a start at the smallest member of its free scale (the same motion): SLSQP then has a
    # bound in that direction, where it would crawl towards the tie to the smaller design
    sc = m.scale
    scaled = [] if sc is None else [free.index(k) for k in (sc.free, *sc.tied) if k in free]
    if sc is not None and len(scaled) == 1 + len(sc.tied):
        for _, x in measured:
            x[scaled] *= max(lo[scaled] / x[scaled])
    ended: list[np.ndarray] = []  # where the runs so far ended
    for first, x0 in measured:
        if time.monotonic() >= deadline:
            break
        kept = equalities(x0)
        if kept.size == n:  # the equalities leave no freedom: the start is the optimum
            yield design(x0)
            continue
        constraints = [
            {
                "type": "eq",
                "fun": lambda y, k=kept: rows(y)[0][k] - lbg[k],
                "jac": lambda y, k=kept: rows(y)[1][k],
            },
            *measures,
        ]
        seen: list[np.ndarray] = []  # this run's iterates

        def cap(y: np.ndarray, seen: list[np.ndarray] = seen) -> None:
            """Ends SLSQP (with its last iterate, projected below) at the deadline; once its
            iterates stand still (where its line search can no longer meet ``ftol`` it may
            repeat one point for a hundred iterations); or once it comes within ``NEAR`` of an
            optimum an earlier run ended at (the rest of the way is that run's)."""
            seen.append(y.copy())
            still = len(seen) > STILL and np.ptp(seen[-STILL:], axis=0).max() <= 1e-12
            known = any(np.abs(y[:n] - x).max() <= NEAR for x in ended)
            if still or known or time.monotonic() >= deadline:
                raise StopIteration

        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")  # SLSQP's notes on clipping to the bounds
                last = minimize(
                    lambda y: y[n] + TIE * (links @ y),
                    np.append(x0, first),
                    jac=lambda y: np.eye(n + 1)[n] + TIE * links,
                    method="SLSQP",
                    bounds=[*zip(lo, hi, strict=True), (0.0, None)],
                    constraints=constraints,
                    callback=cap,
                    options={"maxiter": MAX_ITER, "ftol": 1e-12},
                ).x
        except _Late:  # within an iteration: the run ends where its last one did
            if not seen:
                break
            last = seen[-1]
        # SLSQP meets its constraints to ~1e-8, the verification asks 1e-9: projected onto
        # the equalities, the inequalities it is beyond held inside
        for x in screen.project(form, key, last[None, :n], pv, lo, hi, every=False):
            ended.append(x)
            yield design(x)


class _Late(Exception):
    """The deadline passed before an evaluation of the measure (``local_optima``)."""


def motion(
    specs: Sequence[Spec],
    t: Targets,
    max_candidates: int,
    extras: dict[str, Any],
    limit: float | None,
) -> tuple[list[Candidate], list[Infeasible]]:
    """A searched objective (a motion measure, or the peak torque): per type and variant, the
    certified search (``certify``) or SLSQP (``local_optima``) from the exact solvers' designs;
    the optima and those designs, verified, ranked by the measure (the ``limit`` met)."""
    found: list[Candidate] = []
    infeasible = []
    o = objectives.get(t.objective)
    for i, spec in enumerate(specs):
        m = get(spec.type)
        if m.facts is None:  # its constraints are the closed forms' (``formulation``)
            infeasible.append(
                Infeasible(
                    m.type,
                    "OBJECTIVE_UNSUPPORTED",
                    f"{m.type} has no closed forms, on which the motion objectives' search stands;"
                    " ask for pareto, max_transmission_angle or min_size",
                )
            )
            continue
        best_t = replace(t, objective=MAX_TRANSMISSION)
        if time.monotonic() >= t.deadline:  # not begun: its reason says the budget ran out
            infeasible.append(diagnose(m, spec, best_t, Searched()))
            continue
        s = search(m, spec, i, best_t)
        pool = list(s.proposals)
        # the smallest designs, at the bound or at the least angle these searches keep
        small = replace(t, objective=MIN_SIZE, bound_deg=max(t.bound_deg, ACROSS_DEG))
        pool += search(m, spec, i, small).proposals
        mine = []
        for p in pool:
            if time.monotonic() >= t.deadline:  # each an analysis: ~15 ms with a load
                break
            c = candidate(m, p, t, s.variants, extras)
            if c is not None:
                mine.append(c)
        if time.monotonic() >= t.deadline:  # how many were measured is the clock's: none kept
            infeasible.append(diagnose(m, spec, best_t, Searched()))
            continue
        exact = list(mine)  # the exact solvers' designs, measured: the answer if cut short
        bounds: list[float] | None = []  # each variant's certified least; None: one has none
        why = None  # why the type's answer is not certified, where that is known before it is
        for v in s.variants:
            own = [c for c in mine if m.variant(c.params) == v.parts]
            starts = [
                {k: x / t.stroke for k, x in c.params.items()}
                for c in sorted(own, key=lambda c: c.objective_value)
            ]
            if not v.free:  # one design (or none): its measure is the variant's least
                least = sorted(c.objective_value for c in own)[:1]
                bounds = None if bounds is None else bounds + least
                continue
            if not starts:  # none: proved, if the solver is exact
                if not v.exact:
                    bounds = None
                    why = why or "a variant with no exact design to start from, and none proved"
                continue
            targets = (t.time_ratio, min(t.cos_bound, 1 - ACROSS))
            load = extras.get("load")
            metres = 1.0 if load is None else load.metres * t.stroke  # the space's in strokes
            known = min(mine, key=lambda c: c.objective_value)  # the incumbent: a cutoff
            cert = certify.search(
                m, v, o.terms, targets, t.deadline, load, metres, known.objective_value
            )
            if isinstance(cert, str):  # the NLP's, below
                bounds, why = None, why or f"{cert}: SLSQP's local optimum from ranked starts"
            else:
                if not cert.complete:
                    bounds = None
                elif bounds is not None:
                    bounds.append(cert.bound)
                if cert.complete and not cert.closed:
                    why = why or (
                        f"the certified search stopped at its limit ({certify.LEVELS} levels or"
                        f" {certify.LIVE} boxes alive) before its gap closed"
                    )
                c = known  # the optimum without the limit, where it meets it; else the NLP's
                if cert.design:  # where the variant has a design better than the known one
                    d = whole(spec, scaled(cert.design, t.stroke), v.parts)
                    q = proposal(m, i, d, certify.METHOD, t)
                    c = None if q is None else candidate(m, q, t, s.variants, extras, mine)
                    mine += [c] if c is not None and c not in mine else []
                if c is not None and o.allows(c, limit):
                    continue
                why = why or "under the limit, SLSQP's local optimum (the bound is without it)"
            aim, capped = aims.aim(m, v.parts, o, t, extras, limit, mine)
            optima = local_optima(
                m,
                v.parts,
                v.free,
                dict(v.problem.fixed),
                v.problem.bounds,
                v.problem.explicit,
                targets,
                aim,
                starts,
                capped,
                t.deadline,
                bool(spec.fixed),
            )
            for d in optima:
                q = proposal(m, i, whole(spec, scaled(d, t.stroke), v.parts), "slsqp", t)
                c = None if q is None else candidate(m, q, t, s.variants, extras)
                if c is not None:  # its family's smallest member, and it where that differs
                    smallest = smallest_member(m, i, c, t, s.variants, extras)
                    mine += [smallest] if aim.scale_free else [c, smallest]
        cut = time.monotonic() >= t.deadline  # where the search stopped is the clock's
        if cut:  # not kept: its one reason is the cut
            mine, bounds = exact, None
            why = "the budget ran out before the search finished: the exact solvers' designs"
            infeasible.append(cut_short(m.type, o.name))
        # every variant's least certified (a limit only raises the optimum)
        mine = [certify.mark(c, min(bounds) if bounds else math.nan, why) for c in mine]
        kept = [c for c in mine if o.allows(c, limit)]
        if not kept and not mine and not cut:
            best = pool[0].params if pool else None
            infeasible.append(locked(m, best, extras.get("load")) or diagnose(m, spec, best_t, s))
        elif not kept and not cut:  # the limit left none
            assert o.limit is not None and limit is not None
            infeasible.append(_unreachable(m, spec, t, extras, o.limit, limit, mine))
        found += distinct(kept, t.stroke, o.tie)
    return o.rank(found)[:max_candidates], infeasible


def _unreachable(
    m: Mechanism,
    spec: Spec,
    t: Targets,
    extras: dict[str, Any],
    capped: objectives.Limit,
    limit: float,
    mine: list[Candidate],
) -> Infeasible:
    """Why no design of the type meets the limit, with the least the search finds (where the
    request's objective is not the one that finds it, that one's optimum too)."""
    least = min(capped.value(c) for c in mine)
    if t.objective != capped.least:
        alone = motion([spec], replace(t, objective=capped.least), 1, extras, None)[0]
        least = min([least] + [c.objective_value for c in alone])
    return Infeasible(
        m.type,
        capped.code,
        f"{m.type}'s {capped.words} is at least {least:.6g}{capped.unit} (the least the "
        f"search finds) at time ratio {t.time_ratio:g}, stroke {t.stroke:g} and bound "
        f"{t.bound_deg:g}°, above the limit {limit:g}{capped.unit}",
    )
