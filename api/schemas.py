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

from annotated_types import Ge, Le
from pydantic import (
    BaseModel,
    ConfigDict,
    Field,
    create_model,
    field_validator,
    model_validator,
)

import synth
from synth import results
from synth.analysis.quality import CUT
from synth.analysis.request import MAX_CURVE_POINTS
from synth.drawing.report import Goals
from synth.load import GAP, Load
from synth.mechanisms import Mechanism, Parameter, all_types, get
from synth.objectives import all_objectives
from synth.requests import Argument, argument, arguments
from synth.results import Tolerance

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


def _annotation(a: Argument, caps: tuple[Any, ...]) -> Any:
    """A field's type in a body: its kind (its choices as a ``Literal``), its limits and the
    service's ``caps`` on it (the narrower limit wins: it is given last)."""
    kind: Any = a.kind if a.choices is None else Literal[a.choices]
    if a.limits or caps:
        kind = Annotated[kind, *a.limits, *caps]
    if a.many:
        kind = list[kind]
    return kind | None if a.optional else kind


def _body(
    value: type,
    name: str,
    wire: dict[str, tuple[Any, Any]],
    caps: dict[str, tuple[Any, ...]] | None = None,
    base: type[BaseModel] = Strict,
    doc: str | None = None,
    extra: dict[str, dict[str, Any]] | None = None,
) -> type[BaseModel]:
    """The body of an operation whose request value is ``value``: its fields that the edges
    take (``synth.requests.arguments``), in order, with their words, defaults, limits and
    choices; ``wire``: the fields the body takes in a shape of its own (a model), as (type,
    ``Field``), and those it leaves out (None, folded into another); ``caps``: the service's
    narrower limits on a field; ``base``: the model it extends (with rules of its own);
    ``doc``: its words; ``extra``: what a field's schema adds for a client (``x-`` keys)."""
    fields: dict[str, Any] = {}
    for a in arguments(value):
        if not a.edge or (a.name in wire and wire[a.name] is None):
            continue
        if a.name in wire:
            fields[a.name] = wire[a.name]
            continue
        default = ... if a.default is MISSING else list(a.default) if a.many else a.default
        # a collection of choices names each once at most
        most = len(a.choices) if a.many and a.choices is not None else None
        info = Field(
            default,
            max_length=most,
            description=a.help.text if a.help else None,
            json_schema_extra=(extra or {}).get(a.name),
        )
        fields[a.name] = (_annotation(a, (caps or {}).get(a.name, ())), info)
    return create_model(name, __base__=base, __doc__=doc, **fields)


def _help(value: type, name: str) -> str | None:
    """A field's words (``synth.requests.Help``)."""
    h = argument(value, name).help
    return h.text if h else None


class _LoadRules(Strict):
    """A load's fractions checked where a body holds them, each error at its field."""

    @field_validator("cutting_zone", check_fields=False)
    @classmethod
    def _zone(cls, zone: list[float]) -> list[float]:
        if not zone[1] - zone[0] >= GAP:
            raise ValueError(
                f"start {zone[0]:g} must be less than end {zone[1]:g}, by {GAP:g} or more"
            )
        return zone

    @field_validator("force_profile", check_fields=False)
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
    def _one_force(self) -> Any:
        given = vars(self)  # the fields of the model built on this (``_load``)
        if given["force_profile"] is not None and (
            given["cutting_force"] or "cutting_zone" in self.model_fields_set
        ):
            raise ValueError("give cutting_force (and cutting_zone) or force_profile, not both")
        return self


def _load() -> type[BaseModel]:
    """``Load`` as a body takes it: its fractions as lists, and the service's caps."""
    zone = argument(Load, "cutting_zone")
    fraction = Annotated[float, Field(ge=0.0, le=1.0)]
    pair = Annotated[list[fraction], Field(min_length=2, max_length=2)]
    point = Annotated[
        list[Annotated[float, Field(ge=0.0, le=1e12)]], Field(min_length=2, max_length=2)
    ]
    return _body(
        Load,
        "LoadSpec",
        {
            "cutting_zone": (pair, Field(list(zone.default), description=_help(Load, zone.name))),
            "force_profile": (
                Annotated[list[point], Field(min_length=2, max_length=100)] | None,
                Field(None, description=_help(Load, "force_profile")),
            ),
        },
        {
            "cutting_force": (Le(1e12),),
            "slider_mass": (Le(1e12),),
            "link_mass_per_length": (Le(1e12),),
            "guide_friction": (Le(2.0),),
            "gravity_deg": (Ge(-360.0), Le(360.0)),
        },
        base=_LoadRules,
        doc="What the design drives at constant crank speed: adds ``loads`` (the crank torque, "
        "power and flywheel, the joints' and the guide's largest forces) and, with curves, the "
        "torque curve. Forces and masses are SI; the design's lengths are in ``length_unit``.",
    )


def _tolerance() -> type[BaseModel]:
    """``Tolerance`` as a body takes it, within the service's caps."""
    return _body(
        Tolerance,
        "ToleranceSpec",
        {},
        {"absolute": (Le(LENGTH_MAX),), "relative": (Le(1.0),)},
        doc="± on every parameter of the design: one of the two.",
    )


if TYPE_CHECKING:
    # static stand-ins for the models built from synth's values at run time (below)

    class LoadSpec(Strict):
        pass

    class ToleranceSpec(Strict):
        pass

else:
    LoadSpec, ToleranceSpec = _load(), _tolerance()


BUDGET: Any = Field(
    None,
    gt=0.0,
    description=f"from the request's arrival; omitted: {_number(DEFAULT_BUDGET_MS)}, or the "
    "server's largest budget if that is less; at most the server's largest budget "
    f"({Settings.model_config['env_prefix']}MAX_BUDGET_MS, "
    f"{_number(_default('max_budget_ms'))} by default). A request waits for a solver at most "
    f"{_QUEUE} of it ({_QUEUE_MAX}), else 503",
)
ANGLE = (Ge(-1e6), Le(1e6))  # a crank angle's, degrees (any, in the library)


def _wired(value: type, name: str, kind: Any, default: Any = None, **more: Any) -> Any:
    """A field the body takes as ``kind`` (a model of its own), with its words."""
    return (kind, Field(default, description=_help(value, name), **more))


def _extras(value: type) -> dict[str, Any]:
    """What an analysis adds when asked, as the body takes it."""
    return {
        "tolerance": _wired(value, "tolerance", ToleranceSpec | None),
        "load": _wired(value, "load", LoadSpec | None),
    }


if TYPE_CHECKING:
    # static stand-ins for the bodies built from the request values at run time (below): the
    # fields the routers read by name, as the body holds them

    class SynthesizeRequest(Strict):
        mechanisms: list[TypeSpec] | None
        time_budget_ms: float | None
        tolerance: ToleranceSpec | None
        load: LoadSpec | None

    class AnalyzeRequest(Strict):
        mechanism: Design
        tolerance: ToleranceSpec | None
        load: LoadSpec | None

    class SweepRequest(Strict):
        mechanism: Design
        time_budget_ms: float | None

    class ExportRequest(Strict):
        mechanism: Design
        format: str

    class ReportTargets(Strict):
        pass

    class ReportRequest(Strict):
        mechanism: Design
        load: LoadSpec | None
        targets: ReportTargets | None

else:
    # the design of a request on one: ``mechanism`` a ``Design``, holding its ``params``
    ON_DESIGN = {"mechanism": (Design, ...), "params": None}
    SynthesizeRequest = _body(
        synth.SynthesisRequest,
        "SynthesizeRequest",
        {
            **_extras(synth.SynthesisRequest),
            "mechanisms": _wired(
                synth.SynthesisRequest,
                "mechanisms",
                list[TypeSpec] | None,
                min_length=1,
                max_length=24,
            ),
            "time_budget_ms": (float | None, BUDGET),
        },
        {
            # the service's limit (the library takes any ratio): a quick stroke of at least 0.36°
            "time_ratio": (Le(1e3),),
            "stroke": (Ge(LENGTH_MIN), Le(LENGTH_MAX)),
            "max_working_speed_fluctuation": (Le(1e3),),
            "max_peak_torque": (Le(1e15),),
        },
        # the playground's words for each objective, and those whose value it shows beside
        # each design
        extra={
            "objective": {
                "x-titles": {o.name: o.words for o in all_objectives()},
                "x-searched": [o.name for o in all_objectives() if o.searched],
            }
        },
    )
    AnalyzeRequest = _body(
        synth.AnalysisRequest,
        "AnalyzeRequest",
        {
            **ON_DESIGN,
            **_extras(synth.AnalysisRequest),
            "crank_angles_deg": _wired(
                synth.AnalysisRequest,
                "crank_angles_deg",
                list[Annotated[float, *ANGLE]] | None,
                max_length=MAX_CURVE_POINTS,
                fail_fast=True,  # the first bad angle, not one error per angle
            ),
        },
        {"crank_speed": (Ge(-1e6), Le(1e6)), "crank_acceleration": (Ge(-1e9), Le(1e9))},
    )
    SweepRequest = _body(
        synth.SweepRequest,
        "SweepRequest",
        {**ON_DESIGN, "time_budget_ms": (float | None, BUDGET)},
        {"start": (Ge(-LENGTH_MAX), Le(LENGTH_MAX)), "stop": (Ge(-LENGTH_MAX), Le(LENGTH_MAX))},
    )
    ExportRequest = _body(
        synth.ExportRequest,
        "ExportRequest",
        ON_DESIGN,
        {"crank_angle_deg": ANGLE},
    )
    ReportTargets = _body(
        Goals,
        "ReportTargets",
        {},
        {"time_ratio": (Le(1e3),), "stroke": (Ge(LENGTH_MIN), Le(LENGTH_MAX))},
        doc=Goals.__doc__,
    )
    ReportRequest = _body(
        synth.ReportRequest,
        "ReportRequest",
        {
            **ON_DESIGN,
            "load": _wired(synth.ReportRequest, "load", LoadSpec | None),
            "targets": _wired(synth.ReportRequest, "targets", ReportTargets | None),
        },
        {"crank_angle_deg": ANGLE},
    )


# --- responses ---------------------------------------------------------------------------


class ErrorItem(BaseModel):
    loc: list[str | int]
    msg: str
    type: str


class NotFound(BaseModel):
    detail: list[ErrorItem]


# what a 422 echoes of a request's input: JSON at most three levels deep (api.errors.safe)
Echoed = str | float | bool | None
_Echoed2 = Echoed | list[Echoed] | dict[str, Echoed]
_Echoed1 = Echoed | list[_Echoed2] | dict[str, _Echoed2]


class InvalidItem(ErrorItem):
    """One place of a request that is wrong: where (``loc``), why (``msg``, ``type``), what
    was given when short (``input``) and the rule's numbers (``ctx``)."""

    input: Echoed | list[_Echoed1] | dict[str, _Echoed1] = None
    ctx: dict[str, Any] | None = None


class Invalid(BaseModel):
    """A request the service does not take as it is: each place that is wrong."""

    detail: list[InvalidItem]


class Refused(BaseModel):
    """A request the service would not take: its body too large, or no solver free in time."""

    detail: list[ErrorItem]


# what every POST may answer besides 200 and 422 (README, "What a client can rely on")
REFUSALS: dict[int | str, dict[str, Any]] = {
    422: {"model": Invalid, "description": "the request, refused: each place that is wrong"},
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
