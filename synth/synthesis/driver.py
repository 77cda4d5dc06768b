"""synthesize(): time ratio, stroke and transmission bound → every good design, verified.

The designs come from ``synth.synthesis.search`` (each type's reduced solver, IPOPT where it cannot
answer), predicted by the types' closed forms. For one criterion they are ranked and
re-analysed (``synth.synthesis.candidate``) best first until ``max_candidates`` meet the targets to
1e-9; the default answer is each type's front (``synth.synthesis.front``), and the objectives on how
the slider moves run a local NLP (``synth.synthesis.motion``). A type with no design gets a
reason with numbers (``synth.synthesis.diagnose``).
"""

from __future__ import annotations

import math
import time
from collections.abc import Collection, Mapping, Sequence
from dataclasses import KW_ONLY, dataclass, field, replace
from typing import Annotated, Any

from annotated_types import Ge, Gt, Le, Lt

from .. import objectives
from ..analysis.kinematics import analyze
from ..analysis.quality import MIDDLE
from ..analysis.request import check_drawn
from ..errors import InvalidDesign, InvalidParameters
from ..load import Load
from ..mechanisms import all_types, get
from ..objectives import FLUCTUATION, REGISTRY, TORQUE
from ..requests import INCLUDE, TOLERANCE_HELP, Help, LibraryOnly, OneOf, check, included, keyword
from ..results import Candidate, Infeasible, SynthesisResult, Tolerance
from ..targets import PARETO
from .candidate import candidate, predicted_rank
from .diagnose import diagnose, unloaded
from .front import pareto
from .motion import motion
from .search import DEFAULT, Searched, Solver, Spec, Targets, search

__all__ = [
    "MAX_CANDIDATES",
    "Solver",
    "Spec",
    "SynthesisRequest",
    "checked_spec",
    "run",
    "synthesize",
]

MAX_CANDIDATES = 50
# the solvers work in the stroke's unit: a stroke within STROKES and bounds within SCALE of it
# either way keep their ratios and squares finite and non-zero (_check_scale)
STROKES, SCALE = (1e-100, 1e100), 1e24
SPEC_KEYS = ("type", "fixed", "bounds")  # what a mechanisms entry given as a mapping takes
# the types to search: each a Spec, a mapping of SPEC_KEYS, or a type's name; one name alone
Specs = Sequence[Spec | Mapping[str, Any] | str] | str | None
PER_TYPE = 5  # candidates per type when max_candidates is not given (pareto: per type's front)


@dataclass(frozen=True)
class SynthesisRequest:
    """``synthesize``'s arguments (``run``), checked when built: an ``InvalidParameters``
    located at the argument, e.g. ``("mechanisms", 0, "bounds", "crank")``. ``load`` takes a
    ``Load`` or a mapping of its fields; ``specs`` are the types to search, each checked."""

    time_ratio: Annotated[float, Ge(1.0), Help("slow stroke / quick stroke (crank angles), ≥ 1")]
    stroke: Annotated[float, Ge(STROKES[0]), Le(STROKES[1]), Help("in your length unit")]
    min_transmission_angle_deg: Annotated[
        float, Ge(0.0), Lt(90.0), Help("the least transmission angle allowed, degrees", "bound")
    ] = 0.0
    mechanisms: Annotated[
        Specs,
        Help(
            "the types to search, each with its parts fixed and bounded; by default every "
            "quick-return type, nothing fixed"
        ),
    ] = None
    objective: Annotated[
        str,
        OneOf(tuple(REGISTRY)),
        Help(
            "what the candidates are best at. pareto: per type, the trade-off front between "
            "the smallest design that meets the bound (min_size) and the best-transmitting one "
            "(max_transmission_angle), points spread evenly in angle, each the smallest design "
            "with at least its angle (size: the sum of link lengths; each candidate's front "
            "says where it sits); max_transmission_angle: the best minimum transmission angle, "
            "ties to the smallest design; min_size: the smallest sum of link lengths meeting "
            "the bound (which must then be > 0°); uniform_cutting_speed: the least speed "
            f"fluctuation (largest speed over mean speed) over the {MIDDLE}, where a tool cuts; "
            "min_peak_acceleration: the least peak acceleration over both strokes, in "
            "ω²·stroke; min_peak_torque: the least peak crank torque under the request's load. "
            "The last three are searched, each candidate carrying its motion, or its loads",
        ),
    ] = PARETO
    max_candidates: Annotated[
        int | None,
        Ge(1),
        Le(MAX_CANDIDATES),
        Help(
            f"in all; omitted: {PER_TYPE} (pareto: {PER_TYPE} per type of the request, at most "
            f"{MAX_CANDIDATES}, a front of one point taking one)"
        ),
    ] = None
    time_budget_ms: Annotated[
        float, Gt(0.0), Help("the search's time; past it, what was done (reported incomplete)")
    ] = 2000.0
    _: KW_ONLY
    include: Annotated[Collection[str], OneOf(INCLUDE), Help(included(INCLUDE))] = ()
    tolerance: Annotated[Tolerance | None, Help(TOLERANCE_HELP)] = None
    max_working_speed_fluctuation: Annotated[
        float | None,
        Ge(1.0),
        Help(
            f"a limit on the speed fluctuation over the {MIDDLE} (≥ 1: 1 is a uniform speed), "
            "with the objectives uniform_cutting_speed and min_peak_acceleration"
        ),
    ] = None
    load: Annotated[
        Load | None,
        Help(
            "what the design drives: adds each candidate's loads; the objective "
            "min_peak_torque minimises its peak crank torque"
        ),
    ] = None
    max_peak_torque: Annotated[
        float | None,
        Gt(0.0),
        Help("N·m: a limit on the peak crank torque, with the objective min_peak_torque"),
    ] = None
    solver: Annotated[Solver, LibraryOnly()] = DEFAULT
    specs: tuple[Spec, ...] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        load = Load.of(self.load)
        object.__setattr__(self, "load", load)
        specs = _specs(self.mechanisms)
        check(self)
        objective, bound = self.objective, self.min_transmission_angle_deg
        if REGISTRY[objective].needs_bound and bound == 0:
            raise InvalidParameters(
                f"min_transmission_angle_deg must be > 0 with the objective {objective}: "
                "without a bound the smallest designs are linkages that lock (a 0° "
                "transmission angle)",
                ("min_transmission_angle_deg",),
            )
        for i, s in enumerate(specs):
            _check_scale(s, i, self.stroke)
        _check_limit(self.max_working_speed_fluctuation, objective)
        _check_torque(objective, load, self.max_peak_torque)
        for s in specs:
            check_drawn(s.type, self.include)
            if load is not None and get(s.type).frame is None:
                raise InvalidParameters(f"load: {s.type} has no force model yet", ("load",))
        object.__setattr__(self, "specs", tuple(specs))

    @property
    def exact_only(self) -> bool:
        """Whether it takes only the types' exact reduced solvers on the default bounds
        (nothing fixed or bounded, not a searched objective, nothing added to the candidates):
        then it costs about what an analysis does, well under a millisecond for one type and
        at most ~15 ms for the six over time ratios 1.005–4.5 and bounds 0–70°
        (``docs/benchmarks.md``)."""
        if REGISTRY[self.objective].searched or self.include or self.tolerance is not None:
            return False
        if self.load is not None or not self.solver.accelerators:  # IPOPT's multistart
            return False
        return all(
            not s.fixed and not s.bounds and get(s.type).reduced is not None for s in self.specs
        )


def run(r: SynthesisRequest) -> SynthesisResult:
    """Every good design for the targets, verified and ranked (POST /v1/synthesize).

    ``mechanisms``: the types to search, each a type's name, a ``Spec`` or a mapping with the
    keys ``type``, ``fixed`` (lengths kept, by parameter name) and ``bounds`` (parameter name
    → (low, high)); a key it does not know is refused. By default every quick-return type.
    The types, the objectives and their names are listed at the end.

    ``objective``: ``pareto`` (each type's trade-off front between its smallest design that
    meets the bound and its best-transmitting one: ``synth.synthesis.front``), or one criterion:
    ``max_transmission_angle`` (ties to the smaller design) or ``min_size`` (the smallest sum
    of link lengths meeting the bound); or one of how the slider moves (``motion_search``):
    ``uniform_cutting_speed`` (the least speed fluctuation over the middle 80% of the working
    stroke, where a tool cuts) or ``min_peak_acceleration`` (the least peak acceleration over
    both strokes, in ω²·stroke); or ``min_peak_torque``, the least peak crank torque under the
    request's ``load`` (the same search, its measure the loads' ``torque.max``).
    ``max_working_speed_fluctuation`` (≥ 1) limits that fluctuation (with the motion
    objectives), ``max_peak_torque`` (N·m) the peak torque (with ``min_peak_torque``).
    ``max_candidates`` counts in all; by default it is
    ``PER_TYPE`` (pareto: per type of the request, at most ``MAX_CANDIDATES``).
    ``solver`` says how (``Solver``): ``Solver(accelerators=False)`` solves every type as one
    without a reduced solver would be, by cold multistart IPOPT on the formulation: the
    generic path, for cross-checks.
    ``include`` and ``tolerance`` add to each candidate what they add to an analysis
    (``synth.analyze``): motion quality, sensitivities, the envelope; a ``load`` adds each
    returned candidate's ``loads`` (crank torque, power, flywheel, joint forces).

    >>> r = synthesize(2.0, 450.0, mechanisms=[{"type": "crank_shaper",
    ...                "fixed": {"pivot_distance": 240.0, "ram_link": 0.0}}])
    >>> [round(r.candidates[0].params[k], 9) for k in ("crank", "lever")]
    [120.0, 450.0]
    """
    t0 = time.monotonic()
    o = objectives.get(r.objective)
    per_type = r.max_candidates or PER_TYPE  # the most one type's front takes
    max_candidates = r.max_candidates
    if max_candidates is None:
        max_candidates = min(PER_TYPE * (len(r.specs) if o.found == "front" else 1), MAX_CANDIDATES)
    deadline = t0 + r.time_budget_ms / 1000
    targets = Targets(
        r.time_ratio, r.stroke, r.min_transmission_angle_deg, r.objective, deadline, r.solver
    )
    # what the objective measures; with its load, every candidate's analysis has its loads
    extras: dict[str, Any] = {"include": sorted({*r.include, *o.include}), "tolerance": r.tolerance}
    specs = list(r.specs)
    if o.found == "front":
        cands, infeasible = pareto(specs, targets, max_candidates, per_type, extras)
    elif o.searched:
        limit = {FLUCTUATION: r.max_working_speed_fluctuation, TORQUE: r.max_peak_torque}
        extras |= {"load": r.load} if o.needs_load else {}
        cands, infeasible = motion(
            specs, targets, max_candidates, extras, limit.get(o.limit) if o.limit else None
        )
    else:
        cands, infeasible = _single(specs, targets, max_candidates, extras)
    if r.load is not None:  # what the returned candidates carry, theirs alone
        cands, infeasible = _loaded(cands, infeasible, r.load, targets.deadline)
    return SynthesisResult(
        candidates=tuple(cands),
        infeasible=tuple(infeasible),
        complete=time.monotonic() < targets.deadline,
        elapsed_ms=(time.monotonic() - t0) * 1000,
    )


synthesize = keyword(SynthesisRequest, run, "synthesize")


def _single(
    specs: list[Spec], t: Targets, max_candidates: int, extras: dict[str, Any]
) -> tuple[list[Candidate], list[Infeasible]]:
    """One criterion: the best ``max_candidates`` designs of all types, ranked."""
    searched = [search(get(spec.type), spec, i, t) for i, spec in enumerate(specs)]
    found, left = _verified(searched, t, max_candidates, extras)
    infeasible = [
        diagnose(get(spec.type), spec, t, s)
        for i, (spec, s) in enumerate(zip(specs, searched, strict=True))
        if not any(c.spec == i for c in found) and not left[i]
    ]
    ranked = objectives.get(t.objective).rank([c.candidate for c in found])
    return ranked[:max_candidates], infeasible


@dataclass(frozen=True)
class _Found:
    spec: int
    candidate: Candidate


def _verified(
    searched: list[Searched], t: Targets, max_candidates: int, extras: dict[str, Any]
) -> tuple[list[_Found], list[bool]]:
    """Verify the proposals best first (predicted) until ``max_candidates`` pass: a design
    that cannot be among the answer is never analysed. Also, per spec, whether proposals were
    left unverified (its type has designs, just not among the best). What the search found is
    verified even past the budget (an analysis each, under a millisecond): a slow type must
    not cost the others their answers."""
    pool = sorted((p for s in searched for p in s.proposals), key=predicted_rank(t.objective))
    found: list[_Found] = []
    left = [False] * len(searched)
    for k, p in enumerate(pool):
        if len(found) >= max_candidates:
            for q in pool[k:]:
                left[q.spec] = True
            break
        c = candidate(get(p.type), p, t, searched[p.spec].variants, extras)
        if c is not None:
            found.append(_Found(p.spec, c))
    return found, left


def _loaded(
    cands: list[Candidate], infeasible: list[Infeasible], load: Load, deadline: float
) -> tuple[list[Candidate], list[Infeasible]]:
    """The candidates with their loads (an analysis each where the search gave them none,
    ~15 ms). A design the load cannot be carried by (friction locks its ram, or a dead point
    meets a load) is left out; a type left with none says why. Where the deadline passes
    first, none is analysed here (how many were is the clock's): the candidates come as they
    are, and each type that lacks its loads says the budget ran out."""
    out: list[Candidate] = []
    refused: dict[str, str] = {}  # a type's first refusal
    for c in cands:
        if not c.loads:
            if time.monotonic() >= deadline:
                bare = dict.fromkeys(c.type for c in cands if not c.loads)
                return cands, infeasible + [unloaded(t, None) for t in bare]
            try:
                c = replace(c, loads=analyze(c.type, c.params, load=load).loads)
            except InvalidDesign as e:
                refused.setdefault(c.type, e.msg)
                continue
        out.append(c)
    lost = dict.fromkeys(c.type for c in cands if not any(o.type == c.type for o in out))
    return out, infeasible + [unloaded(t, refused[t]) for t in lost]


def _catalogue() -> str:
    """The types (their parameters) and the objectives, for ``synthesize``'s help."""
    types = [
        f"    {t} ({get(t).title}): {', '.join(q.name for q in get(t).parameters)}"
        for t in all_types()
        if get(t).quick_return
    ]
    named = [f"    {o.name}: {o.words}" for o in objectives.all_objectives()]
    return "\n".join(["", "    Types (parameters):", *types, "", "    Objectives:", *named])


synthesize.__doc__ = run.__doc__ = (run.__doc__ or "") + _catalogue()


def _specs(mechanisms: Specs) -> list[Spec]:
    """The request's specs, checked; every quick-return type's when ``mechanisms`` is None; a
    type's name alone is that type with nothing fixed or bounded."""
    if mechanisms is None:
        return [Spec(t) for t in all_types() if get(t).quick_return]
    if isinstance(mechanisms, str):
        mechanisms = [mechanisms]
    return [checked_spec(s, i) for i, s in enumerate(mechanisms)]


def _check_scale(s: Spec, i: int, stroke: float) -> None:
    """Bounds within ``SCALE`` of the stroke either way (0 aside): the solvers work in the
    stroke's unit, where their ratios and squares must stay finite and non-zero."""
    for k, (lo, hi) in s.bounds.items():
        if any(x != 0 and not 1 / SCALE <= abs(x) / stroke <= SCALE for x in (lo, hi)):
            raise InvalidParameters(
                f"{s.type}.{k} bounds [{lo!r}, {hi!r}]: each must lie within {1 / SCALE:g} … "
                f"{SCALE:g} × the stroke ({stroke:g}) in size",
                ("mechanisms", i, "bounds", k),
            )


def _check_limit(limit: float | None, objective: str) -> None:
    if limit is None:
        return
    if REGISTRY[objective].limit is not FLUCTUATION:
        takers = [o.name for o in objectives.all_objectives() if o.limit is FLUCTUATION]
        raise InvalidParameters(
            f"max_working_speed_fluctuation is taken with the objectives "
            f"{' and '.join(takers)}, not {objective}",
            ("max_working_speed_fluctuation",),
        )


def _check_torque(objective: str, load: Load | None, limit: float | None) -> None:
    """The least peak torque needs a load; a limit on the peak torque goes with it."""
    if REGISTRY[objective].needs_load and load is None:
        msg = f"objective {objective} needs a load (the torque it minimises is the load's)"
        raise InvalidParameters(msg, ("load",))
    if limit is None:
        return
    if REGISTRY[objective].limit is not TORQUE:
        (taker,) = (o.name for o in objectives.all_objectives() if o.limit is TORQUE)
        msg = f"max_peak_torque is taken with the objective {taker}, not {objective}"
        raise InvalidParameters(msg, ("max_peak_torque",))


def checked_spec(s: Spec | Mapping[str, Any] | str, i: int) -> Spec:
    """``s`` (the request's ``mechanisms[i]``) as a ``Spec``, its fixed parts and bounds
    checked; raises ``InvalidParameters`` located in ``("mechanisms", i, ...)``."""
    if isinstance(s, str):
        s = Spec(s)
    elif not isinstance(s, Spec):
        if not isinstance(s, Mapping):
            msg = (
                f"mechanisms[{i}] must be a type's name, a Spec or a mapping with keys "
                f"{', '.join(SPEC_KEYS)}; got {type(s).__name__}"
            )
            raise InvalidParameters(msg, ("mechanisms", i))
        unknown = sorted(set(s) - set(SPEC_KEYS), key=str)
        if unknown or "type" not in s:
            what = f"unknown key {unknown[0]!r}" if unknown else "no type"
            msg = f"mechanisms[{i}]: {what}; a spec takes {', '.join(SPEC_KEYS)} (type required)"
            raise InvalidParameters(msg, ("mechanisms", i, unknown[0] if unknown else "type"))
        s = Spec(s["type"], dict(s.get("fixed") or {}), dict(s.get("bounds") or {}))
    m = get(s.type)
    both = set(s.fixed) & set(s.bounds)
    if both:
        raise InvalidParameters(
            f"{s.type} {', '.join(sorted(both))}: both fixed and bounded; give one",
            ("mechanisms", i, "bounds", sorted(both)[0]),
        )
    for k, v in s.fixed.items():
        try:
            m.value(k, v)
        except InvalidParameters as e:
            raise InvalidParameters(e.msg, ("mechanisms", i, "fixed", k)) from None
    for k, (lo, hi) in s.bounds.items():
        q = m.parameter(k)
        why = (
            "need finite bounds"
            if not (math.isfinite(lo) and math.isfinite(hi))
            else f"lower bound {lo:g} > upper bound {hi:g}"
            if lo > hi
            else None
            if q.signed or lo > 0 or (lo == 0 and q.zero_means)
            else f"a length's bounds must be ≥ 0 (0 means {q.zero_means})"
            if q.zero_means
            else "a length's bounds must be > 0"
        )
        if why:
            raise InvalidParameters(
                f"{s.type}.{k} bounds [{lo!r}, {hi!r}]: {why}", ("mechanisms", i, "bounds", k)
            )
    return Spec(s.type, dict(s.fixed), {k: (float(a), float(b)) for k, (a, b) in s.bounds.items()})
