"""Each operation's arguments as one value: a frozen dataclass beside the operation
(``SynthesisRequest``, ``AnalysisRequest``, ``SweepRequest``, ``ExportRequest``,
``ReportRequest``), checked when it is built, as ``Load`` is. A field says once what it is
(``Help``), its range (annotated_types' ``Ge``, ``Gt``, ``Le``, ``Lt``, ``Interval``) and its
choices (``OneOf``) in its annotation; the request checks them (``check``), the service's
schema and the command line's options are made from them (``arguments``). The library's
function takes its keyword form from the request (``keyword``): each argument list is written
once, in the request's fields, and an argument nobody knows is an error everywhere."""

from __future__ import annotations

import copy
import inspect
import math
import operator
import types
from collections.abc import Callable, Collection, Mapping
from dataclasses import MISSING, dataclass, fields
from typing import Annotated, Any, ParamSpec, TypeVar, Union, get_args, get_origin, get_type_hints

from annotated_types import Ge, GroupedMetadata, Gt, Le, Lt

from .errors import InvalidParameters

INCLUDE = ("motion", "sensitivities", "envelope")  # what an analysis or a candidate adds when asked
# an analysis also adds its curves' pins when asked (they need the curves' angles), and with a
# load its curves' forces
ANALYSIS_INCLUDE = (*INCLUDE, "pins", "forces")
_INCLUDED = {
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
TOLERANCE_HELP = (
    "± on every parameter, absolute (the lengths' unit) or relative: adds the sensitivities "
    "and their worst-case first-order deviations"
)
P = ParamSpec("P")
R = TypeVar("R")
T = TypeVar("T")
V = TypeVar("V")
# a limit's words, as the service's refusals say them too
_WORDS = {
    Ge: ("≥", "ge", operator.ge),
    Gt: (">", "gt", operator.gt),
    Le: ("≤", "le", operator.le),
    Lt: ("<", "lt", operator.lt),
}
_ARGUMENTS: dict[type, tuple[Argument, ...]] = {}  # by request type (``arguments``)
_NAMED: dict[type, dict[str, Argument]] = {}  # the same, by name (``argument``)


@dataclass(frozen=True)
class Help:
    """What a request's field is, in a few words: the command line's help and the schema's
    description; ``flag``: a shorter name the command line takes it by too."""

    text: str
    flag: str | None = None


@dataclass(frozen=True)
class OneOf:
    """A text field's choices (each item's, for a collection of texts)."""

    choices: tuple[str, ...]


@dataclass(frozen=True)
class LibraryOnly:
    """Marks a field only the library takes (not the service, not the command line)."""


@dataclass(frozen=True)
class Argument:
    """A request's field as the edges read it: its ``name``, its plain ``kind`` (float, int,
    str or bool; None for a value of its own, such as a ``Load``), whether None is allowed
    (``optional``) and whether it is a collection of its kind (``many``), its ``default``
    (``MISSING``: required), its ``help``, ``limits`` and ``choices``, and whether the edges
    take it (``edge``)."""

    name: str
    kind: type | None
    optional: bool
    many: bool
    default: Any
    help: Help | None
    limits: tuple[Any, ...]
    choices: tuple[str, ...] | None
    edge: bool

    def check(self, value: Any) -> None:
        """``InvalidParameters`` at the field where ``value`` is not of its kind, out of its
        limits or not one of its choices (of a collection of texts: each item)."""
        if value is None and self.optional:
            return
        if not self.many:
            self._one(value)
        elif self.kind is str:  # a collection of numbers is its request's to check, at once
            for v in value:
                self._one(v)

    def _one(self, v: Any) -> None:
        name = self.name
        if self.kind is float and not (
            isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)
        ):
            raise InvalidParameters(f"{name} must be a finite number, got {v!r}", (name,))
        if self.kind is int and not (isinstance(v, int) and not isinstance(v, bool)):
            raise InvalidParameters(f"{name} must be an integer, got {v!r}", (name,))
        for limit in self.limits:
            sign, key, holds = _WORDS[type(limit)]
            bound = getattr(limit, key)
            if not holds(v, bound):
                raise InvalidParameters(f"{name} must be {sign} {bound:g}, got {v!r}", (name,))
        if self.choices is not None and v not in self.choices:
            *most, last = (repr(c) for c in self.choices)
            words = f"{', '.join(most)} or {last}" if most else last
            raise InvalidParameters(f"{name} must be {words}, got {v!r}", (name,))


def _plain(hint: Any) -> tuple[Any, tuple[Any, ...], bool]:
    """The type under ``Annotated`` and ``| None``, the metadata, and whether None is allowed."""
    meta: list[Any] = []
    if get_origin(hint) is Annotated:
        hint, *extra = get_args(hint)
        meta += extra
    optional = False
    if get_origin(hint) in (Union, types.UnionType) and type(None) in get_args(hint):
        rest = [a for a in get_args(hint) if a is not type(None)]
        hint, optional = (rest[0] if len(rest) == 1 else hint), True
        if get_origin(hint) is Annotated:
            hint, *extra = get_args(hint)
            meta += extra
    # a range given as one (annotated_types' Interval) is its limits
    flat = [m for g in meta for m in (g if isinstance(g, GroupedMetadata) else (g,))]
    return hint, tuple(flat), optional


def arguments(request: type) -> tuple[Argument, ...]:
    """The fields a request is built from, in order."""
    if request not in _ARGUMENTS:
        _ARGUMENTS[request] = _arguments(request)
        _NAMED[request] = {a.name: a for a in _ARGUMENTS[request]}
    return _ARGUMENTS[request]


def _arguments(request: type) -> tuple[Argument, ...]:
    hints = get_type_hints(request, include_extras=True)
    out = []
    for f in fields(request):
        if not f.init:
            continue
        hint = hints[f.name]
        plain, meta, optional = _plain(hint)
        origin = get_origin(plain)
        many = origin is not None and issubclass(origin, Collection)
        many = many and not issubclass(origin, Mapping)
        item = get_args(plain)[0] if many and get_args(plain) else plain
        kind = item if item in (float, int, str, bool) else None
        default = f.default if f.default is not MISSING else MISSING
        if f.default_factory is not MISSING:
            default = f.default_factory()
        out.append(
            Argument(
                name=f.name,
                kind=kind,
                optional=optional,
                many=many and kind is not None,
                default=default,
                help=next((m for m in meta if isinstance(m, Help)), None),
                limits=tuple(m for m in meta if type(m) in _WORDS),
                choices=next((m.choices for m in meta if isinstance(m, OneOf)), None),
                edge=not any(isinstance(m, LibraryOnly) for m in meta),
            )
        )
    return tuple(out)


def argument(request: type, name: str) -> Argument:
    """The field ``name`` of a request."""
    arguments(request)
    return _NAMED[request][name]


def check(value: object, at: str | None = None) -> None:
    """Each field of ``value`` (a request, or a value one holds in its field ``at``, where its
    errors are then located) of its kind, within its limits, one of its choices."""
    try:
        for a in arguments(type(value)):
            a.check(getattr(value, a.name))
    except InvalidParameters as e:
        if at is None:
            raise
        raise InvalidParameters(f"{at}.{e.msg}", (at, *e.loc)) from None


def held(kind: type[V], value: V | Mapping[str, Any] | None, at: str) -> V | None:
    """A value a request holds in its field ``at`` (a ``Load``, the report's targets): None,
    one already, or a mapping of its fields; InvalidParameters at ``at`` naming a key that is
    not one of them, or one it needs that is missing."""
    if value is None or isinstance(value, kind):
        return value
    if not isinstance(value, Mapping):
        name = kind.__name__
        msg = f"{at} must be a {name} or a mapping of its fields, got {type(value).__name__}"
        raise InvalidParameters(msg, (at,))
    known = {f.name: f for f in fields(kind)}  # type: ignore[arg-type]
    for k in value:
        if k not in known:
            msg = f"{at} has no field {k!r}; its fields are {', '.join(known)}"
            raise InvalidParameters(msg, (at, str(k)))
    for k, f in known.items():
        if k not in value and f.default is MISSING:
            raise InvalidParameters(f"{at} needs {k}", (at, k))
    return kind(**value)


def included(names: tuple[str, ...]) -> str:
    """What ``include`` may name, in words."""
    *most, last = (_INCLUDED[k] for k in names)
    return f"computed only when asked: {', '.join(most)} and {last}"


def keyword(request: Callable[P, R], run: Callable[[R], T], name: str) -> Callable[P, T]:
    """``run`` called with its request's arguments: the request is built (checked: an unknown
    keyword is a TypeError, a wrong value an ``InvalidParameters``) and run. The function is
    ``name``, in ``run``'s module, with ``run``'s words and the request's signature."""

    def call(*args: P.args, **kwargs: P.kwargs) -> T:
        return run(request(*args, **kwargs))

    returns = inspect.signature(run).return_annotation
    call.__signature__ = inspect.signature(request).replace(return_annotation=returns)  # type: ignore[attr-defined]
    call.__name__ = call.__qualname__ = name
    call.__module__, call.__doc__ = run.__module__, run.__doc__
    return call


def rebudgeted(request: R, time_budget_ms: float) -> R:
    """``request`` (checked when built) with another time budget, not checked again: a
    budget is the one field a service changes, and a valid one keeps the request valid."""
    argument(type(request), "time_budget_ms").check(time_budget_ms)
    out = copy.copy(request)
    object.__setattr__(out, "time_budget_ms", time_budget_ms)
    return out
