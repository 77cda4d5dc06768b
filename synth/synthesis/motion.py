"""The searched objectives (``synth.objectives``): how the slider moves
(``uniform_cutting_speed``, ``min_peak_acceleration``, with a limit on the fluctuation) and
what it asks of the drive (``min_peak_torque``, with a limit on it under the request's load).
What each search bounds is its ``aims.Aim``.

No closed form gives these measures: they are extremes over the crank's turn, found by root
finding (``synth.analysis.quality``, ``synth.analysis.loads``). Where a variant's designs are
a box of free numbers and the measure is one the certified search takes (``certify``), it
answers, with its certificate. Otherwise the designs come from a local search from the exact
solvers' designs and ranked points of the box (``local``: SLSQP in epigraph form). No clock
but the request's deadline decides anything: a type's search it cuts short answers the exact
solvers' designs alone, and says so.

Its answer, a local optimum, is verified like every candidate, and checked against an
independent global search by ``tests/referees/test_motion_search.py``."""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import replace
from typing import Any

from .. import objectives
from ..mechanisms import Mechanism, get
from ..results import Candidate, Infeasible
from ..targets import MAX_TRANSMISSION, MIN_SIZE
from . import aims, certify
from .candidate import candidate, distinct, smallest_member
from .diagnose import cut_short, diagnose, locked
from .local import local_optima
from .search import (
    Searched,
    Spec,
    Targets,
    proposal,
    scaled,
    search,
    whole,
)

# the least 1 − cos μ a search for motion keeps at every joint, whatever the bound: as a rod
# comes to stand across its slider's path (μ → 0) the slider's speed there grows without
# bound in a spike narrower than the analysis's grid, so a measure there is no design's
ACROSS = 1e-3
ACROSS_DEG = math.degrees(math.acos(1 - ACROSS))


def motion(
    specs: Sequence[Spec],
    t: Targets,
    max_candidates: int,
    extras: dict[str, Any],
    limit: float | None,
) -> tuple[list[Candidate], list[Infeasible]]:
    """A searched objective (a motion measure, or the peak torque): per type and variant, the
    certified search (``certify``) or the local search (``local``) from the exact solvers' designs;
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
