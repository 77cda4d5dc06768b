"""Frozen result values. Angles in degrees and lengths in the caller's unit, as at the API."""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from dataclasses import asdict, dataclass
from typing import Annotated, Any, TypeVar

import numpy as np
from annotated_types import Ge

from .errors import InvalidParameters
from .requests import Help, check

TOL = 1e-9  # relative: how exactly a design must meet the targets (verification, fixed parts)


@dataclass(frozen=True)
class Extreme:
    position: float
    crank_angle_deg: float


E = TypeVar("E")


@dataclass(frozen=True)
class MinMax(Mapping[str, E]):
    """The least and the greatest of something (the slider's dead centres, a sweep's time
    ratio): as attributes, or as the mapping {"min": …, "max": …}."""

    min: E
    max: E

    def __getitem__(self, key: str) -> E:
        if key not in ("min", "max"):
            raise KeyError(key)
        return getattr(self, key)  # type: ignore[no-any-return]

    def __iter__(self) -> Iterator[str]:
        return iter(("min", "max"))

    def __len__(self) -> int:
        return 2


@dataclass(frozen=True)
class DeadCentres(MinMax[Extreme]):
    """The slider's least and greatest positions, each with its crank angle (its fields typed
    for a schema: a generic's are not)."""

    min: Extreme
    max: Extreme


@dataclass(frozen=True)
class Stroke:
    crank_angle_deg: float  # crank travel during the stroke
    direction: int  # sign of the slider's travel along its path


@dataclass(frozen=True)
class Joint:
    joint: str
    min_deg: float
    max_deg: float


@dataclass(frozen=True)
class Transmission:
    min_deg: float
    max_deg: float
    joints: tuple[Joint, ...]


@dataclass(frozen=True)
class Conditioning:
    """How close a design is to trouble, and flags where it is close.

    ``dead_point_margin_deg`` is the minimum transmission angle: the angular distance to a dead
    point (0°, where the drive locks). ``validity_margin`` is the smallest validity-condition
    margin over the design's largest length (0: on a limit, e.g. a Grashof change point), and
    ``limiting_condition`` names that condition.
    """

    dead_point_margin_deg: float
    validity_margin: float | None
    limiting_condition: str | None
    flags: tuple[str, ...]


NEAR_DEAD_POINT_DEG = 5.0
NEAR_LIMIT = 1e-3


@dataclass(frozen=True)
class PinPath:
    """One pin of the type's drawing (``synth.joints``) at each of the curves' crank angles."""

    x: np.ndarray
    y: np.ndarray


@dataclass(frozen=True)
class Curves:
    crank_angle_deg: np.ndarray
    position: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray
    transmission_deg: np.ndarray
    # only when asked (include "pins"): every pin of the drawing, named and ordered as
    # ``synth.joints`` gives them
    pins: dict[str, PinPath] | None = None
    torque: np.ndarray | None = None  # N·m, only with a load
    # with a load, when asked (include "forces"): each joint's force and the guide's (N)
    forces: dict[str, np.ndarray] | None = None


@dataclass(frozen=True)
class SpeedFluctuation:
    """The largest slider speed over the working stroke against its mean speed (1: uniform)."""

    whole: float  # over the whole working stroke
    middle: float  # over its middle 80% by position, where a tool cuts


@dataclass(frozen=True)
class PeakAcceleration:
    """The largest |slider acceleration| over each stroke, in units of ω²·stroke, and the
    crank angle (degrees) where each is reached."""

    working_stroke: float
    return_stroke: float
    working_stroke_at_deg: float
    return_stroke_at_deg: float


@dataclass(frozen=True)
class Motion:
    """How evenly the slider moves at a constant crank speed ω: dimensionless, so it holds for
    any speed and any length unit."""

    working_speed_fluctuation: SpeedFluctuation
    peak_acceleration: PeakAcceleration


@dataclass(frozen=True)
class Envelope:
    """The box the frame must hold over a revolution: every pivot, every pin's path and the
    slider's travel, in the drawing's frame (the crank pivot at the origin, x along the ground
    line). ``link_length_sum`` is the other measure of size (a candidate's ``size``)."""

    x: tuple[float, float]
    y: tuple[float, float]
    width: float
    height: float
    link_length_sum: float


@dataclass(frozen=True)
class Tolerance:
    """± on every length: ``absolute`` (in the lengths' unit) or ``relative`` (of each)."""

    absolute: Annotated[float | None, Ge(0.0), Help("in the lengths' unit")] = None
    relative: Annotated[float | None, Ge(0.0), Help("a fraction of each length")] = None

    def __post_init__(self) -> None:
        given = {k: v for k, v in vars(self).items() if v is not None}
        if len(given) != 1:
            msg = "tolerance: give absolute or relative, one of them"
            raise InvalidParameters(msg, ("tolerance",))
        check(self, at="tolerance")

    def of(self, value: float) -> float:
        return self.absolute if self.absolute is not None else (self.relative or 0.0) * abs(value)


@dataclass(frozen=True)
class Torque:
    """The torque the crank must receive to turn at constant speed (N·m, positive when it
    drives): its extremes, at crank angles (degrees), and its mean and root mean square."""

    max: float
    max_at_deg: float
    min: float
    min_at_deg: float
    mean: float
    rms: float


@dataclass(frozen=True)
class Power:
    """The crank's mean and peak power (W), and the motor's rated power: the mean over the
    drive's efficiency (a flywheel takes the peaks); with the load's ``motor_rpm``, the
    motor's rated torque there (N·m)."""

    mean: float
    peak: float
    rated: float
    motor_torque: float | None = None


@dataclass(frozen=True)
class Flywheel:
    """The largest swing of the crank's energy over a turn, ΔE = max E − min E with E(θ) =
    ∫ (T − T_mean) dθ (J: the turning-moment diagram's areas between its highest and lowest
    points), and the flywheel inertia (kg·m²) that holds the speed within the load's
    ``speed_fluctuation`` Cs, I = ΔE / (Cs ω²), on the shaft that carries it, turning at
    ``rpm`` (the load's ``flywheel_rpm``, else the crank's); with the load's
    ``flywheel_width``, the diameter of a solid steel disc of that inertia (``disc_diameter``,
    in the load's length unit)."""

    energy: float
    inertia: float
    rpm: float
    disc_diameter: float | None = None


@dataclass(frozen=True)
class Force:
    """A force's largest magnitude over a turn (N) and the crank angle (degrees) of it."""

    max: float
    at_deg: float


@dataclass(frozen=True)
class Loads:
    """What a design's load asks of it (``synth.analysis.loads``): the crank torque, power and
    flywheel; each joint's largest force (``joints``: the pins of the type's drawing, and the
    blocks in slots by their pins) and the ram guide's largest normal force."""

    torque: Torque
    power: Power
    flywheel: Flywheel
    joints: dict[str, Force]
    guide: Force


@dataclass(frozen=True)
class Sensitivities:
    """First-order derivatives of the time ratio, the stroke and the minimum transmission angle
    (degrees) with respect to each parameter of the design (per unit of length).

    ``min_transmission_angle_deg`` is None where that angle is not differentiable (0°: a
    locking joint). With a tolerance, ``deviation`` is the worst-case first-order change of
    each when every parameter may be off by its tolerance (the sum of |derivative| × tolerance).
    """

    time_ratio: dict[str, float]
    stroke: dict[str, float]
    min_transmission_angle_deg: dict[str, float] | None
    tolerance: Tolerance | None = None
    deviation: dict[str, float | None] | None = None


@dataclass(frozen=True)
class Analysis:
    """One design over a crank revolution (POST /v1/analyze)."""

    type: str
    params: dict[str, float]
    time_ratio: float
    stroke: float
    extremes: DeadCentres
    working_stroke: Stroke
    return_stroke: Stroke
    transmission: Transmission
    grashof: str | None
    # stationary points of s per revolution where the slider reverses: 2 for a clean quick
    # return; more means the slider dithers near a dead centre and the strokes are ill-defined
    reversals: int
    conditioning: Conditioning
    curves: Curves | None = None
    motion: Motion | None = None  # only when asked
    sensitivities: Sensitivities | None = None  # only when asked
    envelope: Envelope | None = None  # only when asked
    loads: Loads | None = None  # only with a load

    def to_dict(self) -> dict[str, Any]:
        out = asdict(self)
        for k in ("curves", "motion", "sensitivities", "envelope", "loads"):  # only when asked
            if out[k] is None:
                del out[k]
        if self.curves is not None:
            out["curves"] = {k: _lists(v) for k, v in out["curves"].items() if v is not None}
        return out


def _lists(v: Any) -> Any:
    """Arrays as lists, in mappings too (the curves' pins)."""
    if isinstance(v, dict):
        return {k: _lists(x) for k, x in v.items()}
    return np.asarray(v).tolist()


@dataclass(frozen=True)
class FrontPoint:
    """A candidate's place on its type's trade-off front (objective ``pareto``): the designs
    of the type that no other design beats in both minimum transmission angle (up) and
    ``measure`` (down, the sum of link lengths). ``index`` counts from the smallest (0) to the
    best-transmitting (``points`` − 1); ``ends`` names the single-criterion optima the point
    is (``min_size``, ``max_transmission_angle``; both for a front of one point)."""

    measure: str
    index: int
    points: int
    ends: tuple[str, ...]


@dataclass(frozen=True)
class Family:
    """Designs that are all equally good: every ``free`` parameter may take any value in its
    ``range`` (the validity conditions and the request's bounds), the ``tied`` ones follow as
    coefficient × the free one (``tied[name] = (free, coefficient)``), the rest stay as they
    are; time ratio, stroke and every transmission angle do not change. The candidate is the
    smallest member; fix the free parameter in the request to pick another."""

    free: tuple[str, ...]
    range: dict[str, tuple[float, float]]
    tied: dict[str, tuple[str, float]]
    relation: str


@dataclass(frozen=True)
class Candidate:
    """A verified design (POST /v1/synthesize): every parameter, fixed and found."""

    type: str
    params: dict[str, float]
    time_ratio: float
    stroke: float
    min_transmission_angle_deg: float
    objective_value: float
    # closed_form (an exact reduced solver), closed_form+ipopt (IPOPT from a reduced design),
    # ipopt (IPOPT from a cold start)
    method: str
    residuals: dict[str, float]  # relative: time_ratio, stroke
    verified: bool
    grashof: str | None
    size: float  # sum of the link lengths
    conditioning: Conditioning
    active: tuple[str, ...]  # constraints at (within 1e-6 of) their limit: bound, bounds
    # what the request's include (or tolerance) asked for, else None
    motion: Motion | None = None
    sensitivities: Sensitivities | None = None
    envelope: Envelope | None = None
    front: FrontPoint | None = None  # objective pareto: its place on the front
    family: Family | None = None  # where the targets leave a family of equal designs
    loads: Loads | None = None  # with a load: what it asks of the drive and the bearings
    # the rule that put it after the candidate before it: objective (its value; the first's),
    # min_transmission_angle (the value tied, the larger first), size (the smaller), type
    ranked_by: str = "objective"
    # a searched objective's certificate: the relative gap between this design's value and a
    # rigorous lower bound on every design of its type the request allows (None: no bound
    # was computed), whether that gap is within 1e-9 (the design a certified optimum), and
    # where it is not, why (None for the objectives the exact solvers answer)
    certified: bool = False
    gap: float | None = None
    uncertified: str | None = None


@dataclass(frozen=True)
class Infeasible:
    """Why a type gave no candidate: a code and a reason with numbers.

    The reason's numbers are also given as fields: ``best_transmission_angle_deg`` (code
    TRANSMISSION_UNREACHABLE: the best minimum transmission angle any design reaches at the
    requested time ratio and stroke) and ``time_ratio_range`` (TIME_RATIO_UNREACHABLE: the
    smallest and largest time ratio reachable with the transmission bound).
    """

    type: str
    code: str
    reason: str
    best_transmission_angle_deg: float | None = None
    time_ratio_range: tuple[float, float] | None = None


@dataclass(frozen=True)
class SynthesisResult:
    candidates: tuple[Candidate, ...]
    infeasible: tuple[Infeasible, ...]
    complete: bool
    elapsed_ms: float

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


@dataclass(frozen=True)
class Extremum:
    time_ratio: float
    value: float  # of the varied parameter


@dataclass(frozen=True)
class TimeRatioRange(MinMax[Extremum]):
    """A sweep's least and greatest time ratio over its valid part, each with the varied
    parameter's value there (its fields typed for a schema: a generic's are not)."""

    min: Extremum
    max: Extremum


@dataclass(frozen=True)
class SweepResult:
    """One parameter varied, the rest held (POST /v1/sweep). None where the design is invalid."""

    type: str
    vary: str
    values: list[float]
    time_ratio: list[float | None]
    stroke: list[float | None]
    min_transmission_angle_deg: list[float | None]
    valid: list[bool]
    valid_interval: list[tuple[float, float]]  # exact, within [start, stop]
    time_ratio_range: TimeRatioRange | None  # over the valid part
    # False: the budget ended the sweep before stop (values, and all above, end where it did)
    complete: bool = True

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)
