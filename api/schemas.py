"""Pydantic models of the REST contract; every per-type model is generated from the registry.

Floats are finite (``allow_inf_nan=False``) and strictly typed, unknown fields are rejected,
lengths lie in [``LENGTH_MIN``, ``LENGTH_MAX``] (or are 0 where zero selects a variant; an
offset takes either sign), and every size is capped.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable
from dataclasses import MISSING
from dataclasses import fields as dataclass_fields
from typing import TYPE_CHECKING, Annotated, Any, Literal, TypedDict, Union, get_type_hints

from pydantic import (
    BaseModel,
    ConfigDict,
    Field,
    create_model,
    field_validator,
    model_validator,
)

from synth import results
from synth.analysis.quality import CUT
from synth.analysis.request import MAX_CURVE_POINTS
from synth.analysis.sweep import MAX_POINTS
from synth.drawing import FORMATS
from synth.load import GAP, LENGTH_UNITS, RANGES
from synth.mechanisms import Mechanism, Parameter, all_types, get
from synth.objectives import all_objectives
from synth.requests import ANALYSIS_INCLUDE, INCLUDE
from synth.synthesis.driver import MAX_CANDIDATES, PER_TYPE
from synth.targets import PARETO

from .body_limit import MAX_BODY_BYTES
from .config import DEFAULT_BUDGET_MS, Settings
from .errors import MAX_ERRORS

LENGTH_MIN, LENGTH_MAX = 1e-9, 1e12
STRICT = ConfigDict(extra="forbid", allow_inf_nan=False, strict=True)


def _default(setting: str) -> Any:
    """A setting's default (the texts below say what a server does unless configured)."""
    return Settings.model_fields[setting].default


def _number(x: float) -> str:
    """``x`` as the texts write it: its digits grouped by three from 10 000 on."""
    return f"{x:g}" if abs(x) < 10_000 else f"{x:,.0f}".replace(",", " ")


# what the texts say of a request's wait for a solver, and of the working stroke a tool cuts
_QUEUE = "half" if _default("queue_share") == 0.5 else f"{_default('queue_share'):.0%}"
_QUEUE_MAX = f"at most {_number(_default('max_queue_ms') / 1000)} s"
_MIDDLE = f"middle {1 - 2 * CUT:.0%} of the working stroke"


class Strict(BaseModel):
    """A request's object: finite numbers, strict types, no unknown fields. Unknown fields get
    an error each, as many as a reply lists (``errors.MAX_ERRORS``); more are one error that
    names a few: pydantic's and FastAPI's error lists cost the event loop ~5 µs an error
    (100 000 unknown fields: 0.5 s) before a reply is cut to size."""

    model_config = STRICT

    @model_validator(mode="before")
    @classmethod
    def _few_unknown(cls, data: Any) -> Any:
        if isinstance(data, dict) and len(data) > MAX_ERRORS:
            known = cls.model_fields
            unknown = data.keys() - known.keys()
            if len(unknown) > MAX_ERRORS:
                shown = ", ".join(repr(str(k)[:40]) for k in itertools.islice(unknown, 5))
                raise ValueError(
                    f"{len(unknown)} unknown fields ({shown}, …); the known "
                    f"ones: {', '.join(known)}"
                )
        return data


def _camel(name: str) -> str:
    return "".join(w.capitalize() for w in name.split("_"))


class _Limits(TypedDict):
    ge: float
    le: float


def _limits(q: Parameter) -> _Limits:
    """A length's range: ±LENGTH_MAX where it is signed, from 0 where zero is a variant."""
    lo = -LENGTH_MAX if q.signed else 0.0 if q.zero_means else LENGTH_MIN
    return {"ge": lo, "le": LENGTH_MAX}


def _length(q: Parameter, optional: bool) -> tuple[Any, Any]:
    limits = _limits(q)
    desc = f"{q.symbol}: {q.description}" + (f"; 0: {q.zero_means}" if q.zero_means else "")
    if optional:
        return float | None, Field(None, description=desc, **limits)
    return float, Field(..., description=desc, **limits)


def _params(m: Mechanism, suffix: str, all_optional: bool) -> type[BaseModel]:
    fields: dict[str, Any] = {
        q.name: _length(q, all_optional or not q.required) for q in m.parameters
    }
    return create_model(f"{_camel(m.type)}{suffix}", __base__=Strict, **fields)


def _bounds(m: Mechanism) -> type[BaseModel]:
    def pair(q: Parameter) -> Any:
        end = Annotated[float, Field(allow_inf_nan=False, **_limits(q))]
        return Annotated[list[end], Field(min_length=2, max_length=2)]

    fields: dict[str, Any] = {
        q.name: (
            pair(q),
            Field(
                None,
                description=f"[lower, upper] for {q.name}; default "
                f"[{q.bounds[0]:g}, {q.bounds[1]:g}] × the stroke",
            ),
        )
        for q in m.parameters
    }
    return create_model(f"{_camel(m.type)}Bounds", __base__=Strict, **fields)


def _tag(value: str) -> Any:
    """``Literal[value]``: a union member's ``type``, built at run time."""
    return Literal[value]


def _design(m: Mechanism) -> type[BaseModel]:
    return create_model(
        _camel(m.type),
        __base__=Strict,
        __doc__=m.title,
        type=(_tag(m.type), ...),
        params=(_params(m, "Params", all_optional=False), ...),
    )


def _spec(m: Mechanism) -> type[BaseModel]:
    fixed = _params(m, "Fixed", all_optional=True)
    return create_model(
        f"{_camel(m.type)}Spec",
        __base__=Strict,
        type=(_tag(m.type), ...),
        fixed=(fixed, Field(default_factory=fixed, description="parameters kept as they are")),
        bounds=(
            _bounds(m),
            Field(
                default_factory=_bounds(m),
                description="limits on free ones, in the stroke's unit. The defaults (each "
                "parameter's bounds in /v1/mechanisms, × the stroke; the upper × the largest "
                "fixed length where that is larger) limit a search; where a candidate rests on "
                "one (its active list), give a wider pair here to see past it",
            ),
        ),
    )


def _union(make: Callable[[Mechanism], type[BaseModel]]) -> Any:
    """One model per registered type, told apart by ``type``."""
    models = tuple(make(get(t)) for t in all_types())
    return Annotated[Union[models], Field(discriminator="type")]  # noqa: UP007


if TYPE_CHECKING:
    # static stand-ins for the unions built from the registry at run time (below): what the
    # routers use of any member

    class Design(Strict):
        type: str
        params: BaseModel

    class TypeSpec(Strict):
        type: str
        fixed: BaseModel
        bounds: BaseModel

else:
    Design = _union(_design)
    TypeSpec = _union(_spec)


# --- requests ----------------------------------------------------------------------------


class ToleranceSpec(Strict):
    """± on every parameter of the design: one of the two."""

    absolute: float | None = Field(None, ge=0.0, le=LENGTH_MAX, description="in the lengths' unit")
    relative: float | None = Field(None, ge=0.0, le=1.0, description="a fraction of each length")

    @model_validator(mode="after")
    def _one(self) -> ToleranceSpec:
        if (self.absolute is None) == (self.relative is None):
            raise ValueError("give absolute or relative, one of them")
        return self


_INCLUDES = {
    "motion": "motion (cutting-speed fluctuation over the working stroke, peak accelerations "
    "per stroke)",
    "sensitivities": "sensitivities (first-order derivatives of time ratio, stroke and minimum "
    "transmission angle to every parameter)",
    "envelope": "envelope (the box the frame must hold: every pivot and every pin's path)",
    "pins": "pins (with crank_angles_deg or samples: curves.pins, every pin of the type's "
    "drawing at the curves' angles)",
    "forces": "forces (with a load and curves: curves.forces, each joint's and the guide's "
    "force at the curves' angles)",
}


def _include(names: tuple[str, ...]) -> str:
    *most, last = (_INCLUDES[k] for k in names)
    return f"computed only when asked: {', '.join(most)} and {last}"


class Extras(Strict):
    """What an analysis adds only when asked: to the analysis, or to each candidate."""

    include: list[Literal[INCLUDE]] = Field(  # type: ignore[valid-type]
        [], max_length=len(INCLUDE), description=_include(INCLUDE)
    )
    tolerance: ToleranceSpec | None = Field(
        None,
        description="± on every parameter: adds the sensitivities and their worst-case "
        "first-order deviations",
    )


def _ranged(name: str, default: Any, description: str) -> Any:
    """A load's number as ``Load`` ranges it (``RANGES``)."""
    lo, hi = RANGES[name]
    return Field(default, ge=lo, le=hi, description=description)


class LoadSpec(Strict):
    """What the design drives at constant crank speed: adds ``loads`` (the crank torque, power
    and flywheel, the joints' and the guide's largest forces) and, with curves, the torque
    curve. Forces and masses are SI; the design's lengths are in ``length_unit``."""

    length_unit: Literal[tuple(LENGTH_UNITS)] = Field(  # type: ignore[valid-type]
        ..., description="the unit of the design's lengths (forces and masses are SI)"
    )
    crank_rpm: float = _ranged("crank_rpm", ..., "the crank's constant speed")
    cutting_force: float = Field(
        0.0, ge=0.0, le=1e12, description="N, resisting the ram through the cutting zone"
    )
    cutting_zone: Annotated[
        list[Annotated[float, Field(ge=0.0, le=1.0)]], Field(min_length=2, max_length=2)
    ] = Field(
        [0.1, 0.9],
        description="[start, end]: the fractions of the working stroke (by position) where "
        "the tool cuts, 0 ≤ start < end ≤ 1",
    )
    slider_mass: float = Field(0.0, ge=0.0, le=1e12, description="kg: the ram and its tool")
    link_mass_per_length: float = Field(
        0.0, ge=0.0, le=1e12, description="kg/m: each drawn link a uniform slender rod (0: none)"
    )
    speed_fluctuation: float = _ranged(
        "speed_fluctuation", 0.05, "Cs = (ω_max − ω_min)/ω the flywheel keeps the crank to"
    )
    efficiency: float = _ranged("efficiency", 1.0, "the drive's, motor to crank")
    guide_friction: float = Field(
        0.0, ge=0.0, le=2.0, description="Coulomb coefficient at the ram's guide (0: none)"
    )
    flywheel_rpm: float | None = _ranged(
        "flywheel_rpm",
        None,
        "the speed of the shaft that carries the flywheel (omitted: the crank's)",
    )
    flywheel_width: float | None = _ranged(
        "flywheel_width",
        None,
        "in length_unit: adds the diameter of a solid steel disc flywheel this wide",
    )
    motor_rpm: float | None = _ranged(
        "motor_rpm", None, "the motor's speed: adds its rated torque there"
    )
    gravity_deg: float | None = Field(
        None,
        ge=-360.0,
        le=360.0,
        description="the direction gravity pulls in, in the drawing's frame (degrees from +x, "
        "counter-clockwise: -90 is down the drawing's y axis); omitted, and no "
        "ram_incline_deg: no weight",
    )
    ram_incline_deg: float | None = Field(
        None,
        ge=-90.0,
        le=90.0,
        description="instead of gravity_deg, gravity in the machine's frame, the same for "
        "every type: the mechanism in a vertical plane, its drive below the ram's path, the "
        "working stroke this many degrees above the horizontal (0: a shaper, -90: a slotter "
        "cutting downwards)",
    )
    force_profile: (
        Annotated[
            list[
                Annotated[
                    list[Annotated[float, Field(ge=0.0, le=1e12)]],
                    Field(min_length=2, max_length=2),
                ]
            ],
            Field(min_length=2, max_length=100),
        ]
        | None
    ) = Field(
        None,
        description="instead of cutting_force and cutting_zone: [fraction of the working "
        "stroke, N] points, the fractions increasing in [0, 1], the force linear between them "
        "and 0 outside them",
    )

    @field_validator("cutting_zone")
    @classmethod
    def _zone(cls, zone: list[float]) -> list[float]:
        if not zone[1] - zone[0] >= GAP:
            raise ValueError(
                f"start {zone[0]:g} must be less than end {zone[1]:g}, by {GAP:g} or more"
            )
        return zone

    @field_validator("force_profile")
    @classmethod
    def _profile(cls, profile: list[list[float]] | None) -> list[list[float]] | None:
        fractions = [u for u, _ in profile or ()]
        for i, u in enumerate(fractions):
            if u > 1:
                raise ValueError(f"[{i}]: the fraction {u:g} must be at most 1")
            if i and not u - fractions[i - 1] >= GAP:
                raise ValueError(
                    f"[{i}]: fractions must increase, each by {GAP:g} or more, got "
                    f"{u:g} after {fractions[i - 1]:g}"
                )
        return profile

    @model_validator(mode="after")
    def _one_force(self) -> LoadSpec:
        if self.force_profile is not None and (
            self.cutting_force or "cutting_zone" in self.model_fields_set
        ):
            raise ValueError("give cutting_force (and cutting_zone) or force_profile, not both")
        return self


class AnalyzeRequest(Extras):
    # an analysis also has its curves' pins (a candidate has no curves)
    include: list[Literal[ANALYSIS_INCLUDE]] = Field(  # type: ignore[valid-type]
        [],
        max_length=len(ANALYSIS_INCLUDE),
        description=_include(ANALYSIS_INCLUDE),
    )
    mechanism: Design
    crank_speed: float | None = Field(
        None, ge=-1e6, le=1e6, description="ω, rad/s; omitted: 1, or a load's crank_rpm"
    )
    crank_acceleration: float = Field(0.0, ge=-1e9, le=1e9, description="α, rad/s²")
    crank_angles_deg: list[Annotated[float, Field(ge=-1e6, le=1e6)]] | None = Field(
        None,
        max_length=MAX_CURVE_POINTS,
        fail_fast=True,  # the first bad angle, not one error per angle
        description="curves at exactly these angles",
    )
    samples: int | None = Field(
        None, ge=1, le=MAX_CURVE_POINTS, description="curves at evenly spaced angles"
    )
    load: LoadSpec | None = Field(
        None, description="what the design drives: adds loads (its crank_rpm is the curves' speed)"
    )


BUDGET: Any = Field(
    None,
    gt=0.0,
    description=f"from the request's arrival; omitted: {_number(DEFAULT_BUDGET_MS)}, or the "
    "server's largest budget if that is less; at most the server's largest budget "
    f"({Settings.model_config['env_prefix']}MAX_BUDGET_MS, "
    f"{_number(_default('max_budget_ms'))} by default). A request waits for a solver at most "
    f"{_QUEUE} of it ({_QUEUE_MAX}), else 503",
)


class SynthesizeRequest(Extras):
    # the service's limit (the library takes any ratio): a quick stroke of at least 0.36°
    time_ratio: float = Field(..., ge=1.0, le=1e3, description="slow/quick crank angle, ≥ 1")
    stroke: float = Field(..., ge=LENGTH_MIN, le=LENGTH_MAX)
    min_transmission_angle_deg: float = Field(0.0, ge=0.0, lt=90.0)
    mechanisms: list[TypeSpec] | None = Field(
        None,
        min_length=1,
        max_length=24,
        description="omitted: every quick-return type, nothing fixed",
    )
    objective: Literal[tuple(o.name for o in all_objectives())] = Field(  # type: ignore[valid-type]
        PARETO,
        # the playground's words for each, and those whose value it shows beside each design
        json_schema_extra={
            "x-titles": {o.name: o.words for o in all_objectives()},
            "x-searched": [o.name for o in all_objectives() if o.searched],
        },
        description="pareto: per type, the trade-off front between the smallest design that "
        "meets the bound (min_size) and the best-transmitting one (max_transmission_angle), "
        "points spread evenly in angle, each the smallest design with at least its angle "
        "(size: the sum of link lengths; each candidate's front says where it sits); "
        "max_transmission_angle: the best minimum transmission angle, ties to the smallest "
        "design; min_size: the smallest sum of link lengths meeting the bound (which must "
        "then be > 0°); uniform_cutting_speed: the least speed fluctuation (largest speed over "
        f"mean speed) over the {_MIDDLE}, where a tool cuts; "
        "min_peak_acceleration: the least peak acceleration over both strokes, in ω²·stroke; "
        "min_peak_torque: the least peak crank torque under the request's load. "
        "The last three are local optima from many starts (method slsqp), each candidate "
        "carrying its motion, or its loads",
    )
    max_working_speed_fluctuation: float | None = Field(
        None,
        ge=1.0,
        le=1e3,
        description=f"a limit on the speed fluctuation over the {_MIDDLE} "
        "(≥ 1: 1 is a uniform speed), with the objectives uniform_cutting_speed and "
        "min_peak_acceleration",
    )
    max_candidates: int | None = Field(
        None,
        ge=1,
        le=MAX_CANDIDATES,
        description=f"in all; omitted: {PER_TYPE} (pareto: {PER_TYPE} per type of the request, "
        f"at most {MAX_CANDIDATES}, a front of one point taking one)",
    )
    time_budget_ms: float | None = BUDGET
    load: LoadSpec | None = Field(
        None,
        description="what the design drives: adds each candidate's loads; the objective "
        "min_peak_torque minimises its peak crank torque",
    )
    max_peak_torque: float | None = Field(
        None,
        gt=0.0,
        le=1e15,
        description="N·m: a limit on the peak crank torque, with the objective min_peak_torque",
    )


class SweepRequest(Strict):
    mechanism: Design
    vary: str = Field(..., description="the parameter to vary")
    start: float = Field(..., ge=-LENGTH_MAX, le=LENGTH_MAX)
    stop: float = Field(..., ge=-LENGTH_MAX, le=LENGTH_MAX)
    points: int = Field(101, ge=1, le=MAX_POINTS)
    time_budget_ms: float | None = BUDGET


class ExportRequest(Strict):
    mechanism: Design
    format: Literal[FORMATS] = Field(  # type: ignore[valid-type]
        "svg",
        description="svg: true size; dxf: each link on its own layer; json: the drawing and "
        "its symbols' shapes, for a page that draws them; gif: a turn of the crank from "
        "crank_angle_deg, animated",
    )
    crank_angle_deg: float | None = Field(
        None,
        ge=-1e6,
        le=1e6,
        description="where the crank is drawn; omitted: a third of the way through the working "
        "stroke, where the mechanism stands open",
    )
    length_unit: Literal[tuple(LENGTH_UNITS)] = Field(  # type: ignore[valid-type]
        "mm", description="the unit of the design's lengths: the SVG's size, the DXF's units"
    )
    paths: bool = Field(False, description="each moving pin's path over a turn")


class ReportTargets(Strict):
    """What the report compares the design with (each optional)."""

    time_ratio: float | None = Field(None, ge=1.0, le=1e3, description="slow/quick crank angle")
    stroke: float | None = Field(
        None, ge=LENGTH_MIN, le=LENGTH_MAX, description="in the design's length unit"
    )
    bound_deg: float | None = Field(
        None, ge=0.0, le=90.0, description="the least transmission angle, degrees"
    )


class ReportRequest(Strict):
    mechanism: Design
    load: LoadSpec | None = Field(
        None,
        description="what the design drives: adds the loads, the torque diagram, the "
        "flywheel and the joint forces",
    )
    targets: ReportTargets | None = Field(
        None, description="compared with what the design achieves"
    )
    crank_angle_deg: float | None = Field(
        None, ge=-1e6, le=1e6, description="the drawing's; omitted: where the mechanism stands open"
    )
    length_unit: Literal[tuple(LENGTH_UNITS)] | None = Field(  # type: ignore[valid-type]
        None, description="the design's lengths; omitted: the load's, else mm"
    )


# --- responses ---------------------------------------------------------------------------


class ErrorItem(BaseModel):
    loc: list[str | int]
    msg: str
    type: str


class NotFound(BaseModel):
    detail: list[ErrorItem]


class Refused(BaseModel):
    """A request the service would not take: its body too large, or no solver free in time."""

    detail: list[ErrorItem]


# what every POST may answer besides 200 and 422 (README, "What a client can rely on")
REFUSALS: dict[int | str, dict[str, Any]] = {
    413: {
        "model": Refused,
        "description": f"the body is over {MAX_BODY_BYTES / 2**20:g} MiB (the connection is "
        "closed)",
    },
    503: {
        "model": Refused,
        "description": f"no solver was free within the wait the budget allows ({_QUEUE} of it, "
        f"{_QUEUE_MAX}): try again after Retry-After seconds",
        "headers": {"Retry-After": {"description": "seconds", "schema": {"type": "integer"}}},
    },
}


class Health(BaseModel):
    status: str = "ok"
    version: str


def _declared(model: type[BaseModel], record: Any) -> dict[str, Any]:
    """The attributes of ``record`` that ``model`` declares as fields."""
    return {name: getattr(record, name) for name in model.model_fields if hasattr(record, name)}


class ParameterInfo(BaseModel):
    model_config = ConfigDict(from_attributes=True)  # as in the registry (``MechanismInfo.of``)

    name: str
    symbol: str = Field(description="the textbook symbol")
    description: str
    required: bool
    default: float | None = Field(None, description="constant default, if any")
    default_rule: str | None = Field(None, description="a default derived from the others")
    signed: bool = Field(False, description="may be zero or negative")
    zero_means: str | None = Field(None, description="0 is allowed and selects this variant")
    bounds: tuple[float, float] = Field(description="default synthesis bounds, × the stroke")


class MechanismInfo(BaseModel):
    type: str
    title: str
    description: str
    parameters: list[ParameterInfo]
    validity: list[str] = Field(description="the validity conditions, in words")
    quick_return: bool
    sources: list[str] = Field(
        description="where the type comes from: short citations, in full "
        "in the project's docs/references.md"
    )
    drawing: list[tuple[str, str, str]] = Field(
        default_factory=list,
        description="how to draw a design: the straight members as [name, pin, pin], between "
        "the pins /v1/analyze gives with include pins; named by the parameter that is their "
        "length where one is (a part that is 0 is not drawn)",
    )

    @classmethod
    def of(cls, m: Mechanism) -> MechanismInfo:
        """The registry's record as served: its fields of the names declared here, and its
        conditions' words."""
        return cls.model_validate({**_declared(cls, m), "validity": [c.text for c in m.conditions]})


class PinPath(BaseModel):
    """One pin at each of the curves' crank angles."""

    x: list[float]
    y: list[float]


class Curves(BaseModel):
    """Analysis curves as lists (synth keeps them as arrays)."""

    crank_angle_deg: list[float]
    position: list[float]
    velocity: list[float]
    acceleration: list[float]
    transmission_deg: list[float]
    pins: dict[str, PinPath] | None = Field(
        None,
        description="when include has pins: every pin of the type's drawing (the crank pivot "
        "at the origin, x along the ground line), by name in the drawing's order, x and y at "
        "each crank_angle_deg",
    )
    torque: list[float] | None = Field(
        None, description="with a load: the crank torque (N·m) at each crank_angle_deg"
    )
    forces: dict[str, list[float]] | None = Field(
        None,
        description="with a load, when include has forces: each joint's force (by pin, the "
        "blocks in slots too) and the ram guide's normal force, N, at each crank_angle_deg",
    )


# what an analysis answers only when asked, and a field's meaning where its name needs one
_ANALYSIS_NOTES = {
    "reversals": "slider reversals per revolution (2: a clean design)",
    "curves": "with crank_angles_deg or samples (their pins when include has pins)",
    "motion": "when include has motion",
    "sensitivities": "when include has sensitivities, or with a tolerance",
    "envelope": "when include has envelope",
    "loads": "with a load",
}


def _analysis_response() -> type[BaseModel]:
    """synth.Analysis field for field (a field added there is served), its curves as lists;
    the nested values are synth's own dataclasses."""
    hints = get_type_hints(results.Analysis) | {"curves": Curves | None}
    fields: dict[str, Any] = {
        f.name: (
            hints[f.name],
            Field(
                ... if f.default is MISSING else f.default, description=_ANALYSIS_NOTES.get(f.name)
            ),
        )
        for f in dataclass_fields(results.Analysis)
    }
    return create_model("AnalyzeResponse", __doc__=results.Analysis.__doc__, **fields)


if TYPE_CHECKING:

    class AnalyzeResponse(BaseModel):
        """Static stand-in for the model built at run time (below): synth.Analysis's fields."""

else:
    AnalyzeResponse = _analysis_response()


# synthesize and sweep answer with synth's result dataclasses as they are
SynthesizeResponse = results.SynthesisResult
SweepResponse = results.SweepResult


class AtlasInputs(BaseModel):
    types: list[str]
    ratios: list[float]
    bounds: list[float]
    chunk: int
    version: str


class AtlasRange(BaseModel):
    type: str
    bound_deg: float
    min: float | None = Field(
        description="the least time ratio at which the type meets the "
        "bound (the grid's first: perhaps less); None: nowhere on the grid"
    )
    max: float | None = Field(description="the largest (the grid's last: perhaps more)")


class AtlasInfo(BaseModel):
    inputs: AtlasInputs = Field(description="what reproduces it: python -m synth.atlas")
    frontier: dict[str, list[tuple[float, float | None, str]]] = Field(
        description="per type, [time ratio, best minimum transmission angle in degrees (None: "
        "no design), status]: certified (an exact solver's global optimum), local (IPOPT's) or "
        "refused"
    )
    ranges: list[AtlasRange]
