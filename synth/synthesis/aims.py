"""What the search over one structural variant minimises (``local.local_optima``): a motion
measure or the peak crank torque, as the terms whose largest it is, with their exact
derivatives, and as a quick ranking of many designs at once (the starts')."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import partial
from typing import Any, cast

import numpy as np

from ..analysis.terms import motion_terms, peak_torque_terms
from ..load import Load
from ..mechanisms import Mechanism
from ..objectives import Objective
from ..results import Candidate
from . import screen
from .search import Targets

# a measure's terms and their derivatives in the type's parameters, from a design's evaluation
Pick = Callable[[Any], tuple[np.ndarray, np.ndarray]]


@dataclass(frozen=True)
class Aim:
    """What a search minimises over one variant: a design's evaluation (``evaluate``, once
    per design, stroke units; SynthError where it does not run), the terms whose largest is
    the measure (``pick``, from the evaluation, with their derivatives in the type's
    parameters), the measure of many designs at once, approximately (``rank``: the
    parameter rows of designs -> their measures, inf where one does not run), and whether the
    measure stays the same over a candidate's family (``scale_free``: the family's members
    move alike, but links that weigh load the drive differently), and how many of the box's
    best-ranked points a search runs from (``drawn``: with everything free, on a four-bar's
    construction, and with parts fixed, whichever the coordinates; of each further set the
    coordinates draw, ``further``; of the designs their evolution finds, ``evolved``, none:
    no evolution)."""

    evaluate: Callable[[dict[str, float]], Any]
    pick: Pick
    rank: Callable[[np.ndarray], np.ndarray]
    scale_free: bool
    drawn: dict[str, int]


# the box's points a search runs from: the motion measures' ranks pick their basins well; the
# torque's have more (the links' inertia against the cut: a crank-rocker's slot drive at time
# ratio 1.3 took 8 to reach its optimum, 0.8% below; on the construction, whose runs are
# shorter and stay within a sheet, 16; of the construction's second set, the rod's reach, 4
# found every answer 16 did, the torque's medians 0.79 of the time); of the evolution's designs
# on the construction (``chart.Chart.evolve``: the motion measures' ranks only, the torque's
# cost 20 times as much a design), every one
DRAWN_MOTION = {"free": 2, "fixed": 4, "construction": 2, "further": 2, "evolved": 4}
DRAWN_TORQUE = {"free": 8, "fixed": 8, "construction": 16, "further": 4, "evolved": 0}


# the motion terms an objective bounds (``Objective.terms``), from ``quality.MotionTerms`` with
# their derivatives (``gradient=True``)
PICK: dict[str, Pick] = {
    "speed": lambda t: (t.middle, cast(np.ndarray, t.middle_dp)),
    "acceleration": lambda t: (
        np.concatenate([t.working, t.returning]),
        np.vstack([cast(np.ndarray, t.working_dp), cast(np.ndarray, t.returning_dp)]),
    ),
}


def aim(
    m: Mechanism,
    variant: frozenset[str],
    o: Objective,
    t: Targets,
    extras: dict[str, Any],
    limit: float | None,
    mine: list[Candidate],
) -> tuple[Aim, tuple[Pick, float] | None]:
    """The objective's search over one variant, and its limit's terms and cap: for the peak
    torque's terms, under the request's load (``extras``), in units of the best verified
    start's peak (the search's numbers near 1), the limit the same terms'; for motion terms,
    the objective's, the limit its own (the fluctuation's: the middle's speed)."""
    assert o.terms is not None  # a searched objective
    if o.terms in PICK:
        terms = o.terms

        def rank(pvs: np.ndarray) -> np.ndarray:
            return screen.rank(m, variant, pvs, terms)

        motion = partial(motion_terms, m.type, gradient=True)
        capped = None if limit is None or o.limit is None else (PICK[o.limit.terms], limit)
        return Aim(motion, PICK[terms], rank, True, DRAWN_MOTION), capped
    load: Load = extras["load"]
    metres = load.metres * t.stroke  # the search's lengths are in strokes
    unit = min((abs(c.objective_value) for c in mine), default=1.0) or 1.0

    def pick(got: tuple[np.ndarray, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
        return got[0] / unit, got[1] / unit

    def torque(pvs: np.ndarray) -> np.ndarray:
        return screen.rank_torque(m, variant, pvs, load, metres) / unit

    peak = partial(peak_torque_terms, m.type, load=load, metres=metres)
    capped = None if limit is None else (pick, limit / unit)
    # with massless links the torque is the ram's motion's (a four-bar's scale leaves it alone)
    scale_free = load.link_mass_per_length == 0
    return Aim(peak, pick, torque, scale_free, DRAWN_TORQUE), capped
