"""The objectives a synthesis request may name, one record each: what it measures on a verified
design, which way is better, what the request must carry, how it is found, what a limit on it
means and how designs it cannot tell apart are ordered. The library, the schema, the command
line and the playground read them from here (``all_objectives``, ``get``); a new objective is a
record and, where it is searched, its terms (``synth.synthesis.aims``)."""

from __future__ import annotations

import itertools
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from typing import Literal

from .errors import InvalidParameters
from .results import TOL, Candidate
from .targets import MAX_TRANSMISSION, MIN_SIZE, PARETO, PEAK, PEAK_TORQUE, UNIFORM

# the rules that order designs, in the words a reply gives (``Candidate.ranked_by``)
OBJECTIVE, TRANSMISSION, SIZE, TYPE = "objective", "min_transmission_angle", "size", "type"
SAME_ANGLE_DEG = 1e-9  # minimum transmission angles this close are one (a slot drive's 90°)
SEARCHED_TIE = 1e-6  # relative: a searched measure's values this close are one


def fluctuation(c: Candidate) -> float:
    """The speed fluctuation over the middle 80% of the working stroke, where a tool cuts."""
    assert c.motion is not None  # the objectives that read it ask for the motion
    return c.motion.working_speed_fluctuation.middle


def peak_acceleration(c: Candidate) -> float:
    """The peak |acceleration| over both strokes (ω²·stroke)."""
    assert c.motion is not None
    p = c.motion.peak_acceleration
    return max(p.working_stroke, p.return_stroke)


def peak_torque(c: Candidate) -> float:
    """The peak crank torque under the request's load (N·m)."""
    assert c.loads is not None  # the objective's request carries a load
    return c.loads.torque.max


@dataclass(frozen=True)
class Limit:
    """A request's cap on a measure: its field, the measure it caps and the terms a search
    bounds for it (``Objective.terms``), the objective whose search finds that measure's
    least (what a refusal reports), the refusal's code and the words and unit its reason
    uses."""

    field: str
    value: Callable[[Candidate], float]
    terms: str
    least: str
    code: str
    words: str
    unit: str = ""


FLUCTUATION = Limit(
    field="max_working_speed_fluctuation",
    value=fluctuation,
    terms="speed",
    least=UNIFORM,
    code="FLUCTUATION_UNREACHABLE",
    words="speed fluctuation over the middle 80% of the working stroke",
)
TORQUE = Limit(
    field="max_peak_torque",
    value=peak_torque,
    terms="torque",
    least=PEAK_TORQUE,
    code="PEAK_TORQUE_UNREACHABLE",
    words="peak crank torque under the load",
    unit=" N·m",
)


@dataclass(frozen=True)
class Objective:
    """An objective: its ``name`` and the ``words`` a person reads; its ``value`` on a verified
    design (the candidate's ``objective_value``) and ``sense`` (+1: the least is best, −1:
    the largest); how it is ``found`` (``front``: each type's trade-off front; ``exact``: the
    reduced solvers and IPOPT on the formulation; ``searched``: a search over each variant
    bounding its ``terms``, ``synth.synthesis.aims``); what each candidate's analysis must
    ``include`` for it; whether it ``needs_load`` or a bound above 0 (``needs_bound``); the
    ``limit`` a request may add; and the rules that order designs whose values it cannot tell
    apart (``ties``: within ``tie``, relative), in turn."""

    name: str
    words: str
    value: Callable[[Candidate], float]
    sense: Literal[1, -1]
    found: Literal["front", "exact", "searched"]
    ties: tuple[str, ...]
    tie: float = 0.0
    include: tuple[str, ...] = ()
    terms: str | None = None
    needs_load: bool = False
    needs_bound: bool = False
    limit: Limit | None = None
    proposals: Literal["size", "angle"] = "angle"  # how its exact solvers' designs are ranked

    @property
    def searched(self) -> bool:
        return self.found == "searched"

    def allows(self, c: Candidate, limit: float | None) -> bool:
        """Whether a candidate meets the request's ``limit`` on this objective's limited
        measure (to the verification's tolerance), if the request sets one."""
        return self.limit is None or limit is None or self.limit.value(c) <= limit * (1 + TOL)

    def rank(self, cands: Sequence[Candidate]) -> list[Candidate]:
        """The candidates best first (``order``), each with its ``ranked_by``."""
        return [replace(cands[i], ranked_by=rule) for i, rule in self.order(cands)]

    def order(self, cands: Sequence[Candidate]) -> list[tuple[int, str]]:
        """The candidates' places in ``cands``, best first: by value, those within ``tie`` of
        the first of their group by the ``ties`` in turn, then by type; each with the rule
        that put it after the one before it (a group's first: ``objective``)."""
        groups: list[list[int]] = []
        for i in sorted(range(len(cands)), key=lambda i: self._value_keys(cands[i])):
            if groups and self._tied(cands[groups[-1][0]], cands[i]):
                groups[-1].append(i)
            else:
                groups.append([i])
        out: list[tuple[int, str]] = []
        for g in groups:
            g.sort(key=lambda i: self._keys(cands[i]))
            rules = [OBJECTIVE] + [self._rule(cands[a], cands[b]) for a, b in itertools.pairwise(g)]
            out += zip(g, rules, strict=True)
        return out

    def _value_keys(self, c: Candidate) -> tuple[float | str, ...]:
        return (self.sense * self.value(c), *self._keys(c))

    def _tied(self, a: Candidate, b: Candidate) -> bool:
        x, y = self.value(a), self.value(b)
        return abs(x - y) <= self.tie * max(abs(x), abs(y))

    def _keys(self, c: Candidate) -> tuple[float | str, ...]:
        """The tie rules' keys (the larger angle first, to ``SAME_ANGLE_DEG``), then the type."""
        keys = {TRANSMISSION: -round(c.min_transmission_angle_deg, 9), SIZE: c.size}
        return (*(keys[r] for r in self.ties), c.type)

    def _rule(self, before: Candidate, c: Candidate) -> str:
        """The rule that orders ``c`` after ``before``, whose values are tied."""
        pairs = zip(self.ties, self._keys(before), self._keys(c), strict=False)  # type last
        return next((r for r, a, b in pairs if a != b), TYPE)


REGISTRY: dict[str, Objective] = {}


def register(o: Objective) -> Objective:
    REGISTRY[o.name] = o
    return o


def all_objectives() -> list[Objective]:
    """Every objective, the default first."""
    return list(REGISTRY.values())


def get(name: str) -> Objective:
    """The objective named ``name``; InvalidParameters naming the choices otherwise."""
    if name not in REGISTRY:
        msg = f"objective must be one of {', '.join(REGISTRY)}; got {name!r}"
        raise InvalidParameters(msg, ("objective",))
    return REGISTRY[name]


register(
    Objective(
        PARETO,
        "Trade-off front (size against transmission)",
        lambda c: c.size,
        sense=1,
        found="front",
        ties=(),
    )
)
register(
    Objective(
        MAX_TRANSMISSION,
        "Best transmission angle",
        lambda c: c.min_transmission_angle_deg,
        sense=-1,
        found="exact",
        ties=(SIZE,),
        tie=SAME_ANGLE_DEG / 90,
    )
)
register(
    Objective(
        MIN_SIZE,
        "Smallest design",
        lambda c: c.size,
        sense=1,
        found="exact",
        ties=(TRANSMISSION,),
        needs_bound=True,
        proposals="size",
    )
)
register(
    Objective(
        UNIFORM,
        "Most uniform cutting speed",
        fluctuation,
        sense=1,
        found="searched",
        ties=(TRANSMISSION, SIZE),
        tie=SEARCHED_TIE,
        include=("motion",),
        terms="speed",
        limit=FLUCTUATION,
    )
)
register(
    Objective(
        PEAK,
        "Least peak acceleration",
        peak_acceleration,
        sense=1,
        found="searched",
        ties=(TRANSMISSION, SIZE),
        tie=SEARCHED_TIE,
        include=("motion",),
        terms="acceleration",
        limit=FLUCTUATION,
    )
)
register(
    Objective(
        PEAK_TORQUE,
        "Least peak torque (with a load)",
        peak_torque,
        sense=1,
        found="searched",
        ties=(TRANSMISSION, SIZE),
        tie=SEARCHED_TIE,
        terms="torque",
        needs_load=True,
        limit=TORQUE,
    )
)
