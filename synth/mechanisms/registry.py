"""The registry: one record per mechanism type, read by analysis, synthesis, the API and the tests.

A type module defines its maths with ``casadi`` operations only and ends with
``register(Mechanism(...))``. Nothing else restates its equations.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any

import casadi as ca

from ..errors import InvalidDesign, InvalidParameters, UnknownMechanism
from ..numerics import ROUNDING

if TYPE_CHECKING:
    from .facts import Facts
    from .reduced import Problem, Reduced, Space

Params = Mapping[str, Any]  # parameter name -> float, DM, SX or MX


# Default synthesis bounds, × the stroke. A link from a tenth of the stroke (room for its pins
# and bearings) to five strokes. A rod to the slider (a connecting rod, the slider-crank's
# coupler, the crank shaper's ram link) transmits better the longer it is (its cos μ falls as
# 1/length), so its upper bound decides the best design: two strokes keep the frame within
# about three strokes and already give the Whitworth's rod 75.5° (cos μ = 1/4).
LINK = (0.1, 5.0)
ROD = (0.1, 2.0)


@dataclass(frozen=True)
class Parameter:
    """A link length or placement; a length unless ``signed``."""

    name: str
    symbol: str
    description: str
    default: float | None = None  # a constant default (makes the parameter optional)
    default_rule: str | None = None  # words for a default derived from the others (optional too)
    signed: bool = False  # may be zero or negative (an offset)
    link: bool = True  # a link length (counts in the mechanism's size); False for placements
    bounds: tuple[float, float] = LINK  # default synthesis bounds, × the stroke
    zero_means: str | None = None  # 0 is allowed and selects a variant (e.g. a slot drive)

    @property
    def required(self) -> bool:
        return self.default is None and self.default_rule is None


@dataclass(frozen=True)
class Condition:
    """A validity condition: every term of ``margin(p)`` ≥ 0 (> 0 when strict).

    ``margin`` is polymorphic and returns smooth terms (|x| ≤ y is two terms), so each is a
    constraint in the formulation; ``explain`` states a violation with its numbers, e.g.
    "coupler 2 < crank 1 + |offset| 1.5: the crank cannot turn fully". ``needs`` names the
    optional part the condition is about (it holds only in the variants that have it, e.g. a
    ram link's reach). ``params``, the parameters the margin depends on (where an error
    points, and the lengths its rounding tolerance scales with), is derived when the type is
    registered, never declared.
    """

    name: str
    text: str
    margin: Callable[[Params], tuple[Any, ...]]
    explain: Callable[[Params], str]
    strict: bool = False
    needs: str | None = None
    params: tuple[str, ...] = ()

    def applies(self, variant: frozenset[str]) -> bool:
        """Whether the condition holds in a variant (the set of optional parts left out)."""
        return self.needs is None or self.needs not in variant


@dataclass(frozen=True)
class Scale:
    """A free scale the targets leave: ``free`` and the ``tied`` lengths may grow or shrink
    together, in the ratios a design has, without changing the time ratio, the stroke or any
    transmission angle (only the size). ``reach`` is the largest ``free`` that validity allows
    with the other lengths held, ``why`` says in words why the scale is free."""

    free: str
    tied: tuple[str, ...]
    why: str
    reach: Callable[[Params], float] | None = None


GROUND, RAM = "ground", "ram"  # the frame and the slider, in a ``Frame``'s joints


@dataclass(frozen=True)
class Frame:
    """How a variant's parts carry forces, for its Newton–Euler equations (the loads).

    ``bodies``: each rigid moving body as the drawn members it is made of (``drawing``'s
    names), the crank's first; a body is named by its first member. ``pins``: each pin joint
    as (pin, body, body), a body being one of those, ``GROUND`` or ``RAM``. ``slots``: each
    block that slides in a slot, as (pin, the body carrying the block, the slotted body, the
    slot's line as two pins of it, or None for a slot across the ram's path): the block, and
    the slot's friction, are left out, so it pushes along the slot's normal only. ``path``:
    the ram's direction of travel as s grows (a unit vector, from the complete parameters).
    The ram is a body that only translates: a guide holds it to its path."""

    bodies: tuple[tuple[str, ...], ...]
    pins: tuple[tuple[str, str, str], ...]
    path: Callable[[Params], tuple[Any, Any]]
    slots: tuple[tuple[str, str, str, tuple[str, str] | None], ...] = ()


@dataclass(frozen=True)
class Roles:
    """A four-bar type's parameters in the crank-rocker's roles on its dead-centre construction
    (``synth.mechanisms.fourbar.construction``)."""

    links: tuple[str, str, str, str]  # the crank-rocker's ground, crank, coupler, rocker
    arm: str
    rod: str
    height: str | None  # the slider path's placement (crank-rocker), None: on the ground line
    swings: bool  # the arm swings with the rocker (stroke 2 r5 sin(ψ/2)); else stroke 2 r5


@dataclass(frozen=True)
class Mechanism:
    """One mechanism type: parameters, validity, and its kinematics as functions of (p, θ)."""

    type: str
    title: str
    description: str
    sources: tuple[str, ...]  # short citations (docs/references.md)
    quick_return: bool
    parameters: tuple[Parameter, ...]
    conditions: tuple[Condition, ...]
    position: Callable[[Params, Any], Any]  # s(θ) along the slider path, complete parameters
    transmission: Callable[[Params, Any], dict[str, Any]]  # signed cos μ per pin-jointed coupler
    # a function of (p, θ) whose zeros are exactly the slider's dead centres, each a simple
    # zero, for a type whose ds/dθ has a near-multiple zero there (a follower that nearly
    # stalls at its dead centre): the analysis locates the dead centres on it instead
    dead_centres: Callable[[Params, Any], Any] | None = None
    defaults: Callable[[Params], dict[str, Any]] = lambda p: {}  # derived defaults (polymorphic)
    # the four-bar's (ground, crank, coupler, rocker), for its Grashof class
    fourbar: Callable[[Params], tuple[Any, Any, Any, Any]] | None = None
    # the closed forms (``Facts``: β, the stroke, the transmission cosines, the one-way margins)
    facts: Callable[[Params], Facts] | None = None
    # the exact reduced solver (an accelerator, synth.mechanisms.reduced): Problem -> Reduced,
    # None where it cannot take the problem (IPOPT on the formulation then solves it); raises
    # Unreachable for fixed parts that contradict the targets
    reduced: Callable[[Problem], Reduced | None] | None = None
    # the designs that meet the time ratio and stroke as functions of a few free numbers
    # (synth.mechanisms.reduced.Space), None where it cannot take the problem
    space: Callable[[Problem], Space | None] | None = None
    # a four-bar type's parameters in the crank-rocker's roles on its dead-centre construction
    # (synth.mechanisms.fourbar.construction), where its searched objectives move
    construction: Roles | None = None
    # the pin positions {name: (x, y)} at crank angle θ, named as in the module docstring, the
    # slider's pin last, in CasADi maths (for drawings, and the envelope the frame must hold)
    joints: Callable[[Params, Any], dict[str, tuple[Any, Any]]] | None = None
    # how to draw it: the straight members between two of those pins, (name, pin, pin), named
    # by the parameter that is their length where one is (a part that is 0 is not drawn)
    drawing: tuple[tuple[str, str, str], ...] = ()
    # a family of equal designs the targets leave (synthesis reports it, synth.results.Family)
    scale: Scale | None = None
    # each variant's bodies and joints (its set of left-out parts -> ``Frame``), for the loads
    frame: Callable[[frozenset[str]], Frame] | None = None

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(q.name for q in self.parameters)

    def parameter(self, name: str) -> Parameter:
        for q in self.parameters:
            if q.name == name:
                return q
        raise InvalidParameters(
            f"{self.type} has no parameter {name!r}; its parameters: {', '.join(self.names)}",
            (name,),
        )

    def size(self, p: Params) -> Any:
        """The sum of the link lengths (placements, such as an offset, do not count)."""
        return sum(p[q.name] for q in self.parameters if q.link)

    def variant(self, p: Params) -> frozenset[str]:
        """The optional parts set to zero (``ram_link`` 0 = slot drive): a structural choice."""
        return frozenset(q.name for q in self.parameters if q.zero_means and p[q.name] == 0)

    def value(self, name: str, value: Any) -> float:
        """One parameter's value checked (see ``_check_value``)."""
        return _check_value(self.type, self.parameter(name), value)

    def complete(self, given: Mapping[str, float]) -> dict[str, float]:
        """Check names and values, fill the defaults, and check every validity condition.

        Raises ``InvalidParameters`` for unknown, missing, non-finite or non-positive values and
        ``InvalidDesign`` for the first failed condition, with the numbers.
        """
        for name in given:
            self.parameter(name)
        p: dict[str, float] = {}
        for q in self.parameters:
            if q.name in given and given[q.name] is not None:
                p[q.name] = self.value(q.name, given[q.name])
            elif q.required:
                raise InvalidParameters(
                    f"{self.type} needs {q.name!r} ({q.description})", (q.name,)
                )
        p = self.filled(p)
        self.check(p)
        return p

    def filled(self, given: Mapping[str, float]) -> dict[str, float]:
        """``given`` with every default filled in (the constants, then those derived from the
        others), in the parameters' order, unchecked: ``complete`` checks."""
        p: dict[str, float] = {}
        for q in self.parameters:
            if q.name in given:
                p[q.name] = given[q.name]
            elif q.default is not None:
                p[q.name] = q.default
        missing = [q.name for q in self.parameters if q.name not in p]
        if missing:
            derived = {k: float(v) for k, v in self.defaults(p).items() if k in missing}
            p.update(derived)
        return {q.name: p[q.name] for q in self.parameters}

    def check(self, p: Params) -> None:
        """Raise ``InvalidDesign`` for the first condition the complete parameters break.

        A non-strict condition holds to rounding (−1e-12 × the largest length it involves): a
        design built exactly on a limit in floating point is on it, not past it."""
        variant = self.variant(p)
        for c in self.conditions:
            if not c.applies(variant):
                continue
            tol = ROUNDING * max(abs(float(p[k])) for k in c.params)
            m = min(float(t) for t in c.margin(p))
            if not (m > 0 if c.strict else m >= -tol):  # also catches NaN
                raise InvalidDesign(c.explain(p), c.params, c.name)


def _check_value(mtype: str, q: Parameter, value: Any) -> float:
    """The value as a float, or InvalidParameters: finite, and for a length > 0 (or 0 where
    zero selects a variant)."""
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise InvalidParameters(
            f"{mtype}.{q.name} must be a number, got {value!r}", (q.name,)
        ) from None
    if not math.isfinite(x):
        raise InvalidParameters(f"{mtype}.{q.name} must be finite, got {x}", (q.name,))
    if q.signed:
        return x
    if x < 0 or (x == 0 and q.zero_means is None):
        allowed = "≥ 0 (0 means " + q.zero_means + ")" if q.zero_means else "> 0"
        raise InvalidParameters(
            f"{mtype}.{q.name} is a length and must be {allowed}, got {x:g}", (q.name,)
        )
    return x


def one_way(link: Any, cos_half: Any, end_offset: Any) -> tuple[Any, Any]:
    """Margins (≥ 0) for a slider driven through ``link`` from a pin that swings ±half about
    the path's normal to move one way over each swing, so that the swing's ends are its dead
    centres (the closed forms' time ratio and stroke hold): at the ends the link leans from
    the path no further than the pin has turned, |cos μ_end| = |end_offset|/link ≤ cos(half).
    With the reach at mid-swing (``reach_condition``) that holds over the whole swing."""
    return cos_half - end_offset / link, cos_half + end_offset / link


def reach_condition(
    name: str,
    link: str,
    height: str,
    arm: str,
    offsets: Callable[[Params], tuple[Any, ...]],
    pin: str,
    output: str,
) -> Condition:
    """A link from a swinging pin to a straight path must reach it at every position: link ≥
    the largest |offset| of the pin from the path, where ``offsets`` gives the signed offsets
    at which it is largest (mid-swing and the swing's ends)."""
    return Condition(
        name=name,
        text=f"{link} ≥ the largest distance from {pin} to the {output} path over the swing "
        f"(when {link} > 0)",
        margin=lambda p: tuple(p[link] + sg * t for t in offsets(p) for sg in (1, -1)),
        needs=link,
        explain=lambda p: (
            f"{link} {p[link]:g} < {max(abs(float(t)) for t in offsets(p)):g}, the largest "
            f"distance from {pin} to the {output} path ({height} {p[height]:g}): the {link} "
            f"cannot reach the {output} over the whole swing"
        ),
    )


_REGISTRY: dict[str, Mechanism] = {}


def register(m: Mechanism) -> Mechanism:
    """Add a type, each condition's ``params`` derived from what its margin depends on (its
    full variant: every optional part present)."""
    sym = {k: ca.SX.sym(k) for k in m.names}

    def params(c: Condition) -> tuple[str, ...]:
        out = ca.vertcat(*(ca.SX(t) for t in c.margin(sym)))
        return tuple(k for k in m.names if ca.depends_on(out, sym[k]))

    m = replace(m, conditions=tuple(replace(c, params=params(c)) for c in m.conditions))
    _REGISTRY[m.type] = m
    return m


def get(name: str) -> Mechanism:
    try:
        return _REGISTRY[name]
    except KeyError:
        raise UnknownMechanism(name, tuple(_REGISTRY)) from None


def all_types() -> tuple[str, ...]:
    return tuple(_REGISTRY)


def absent(x: Any) -> bool:
    """True when an optional part is numerically zero (a structural variant, e.g. a slot drive).

    Model code branches on this in Python; formulations build one graph per variant.
    """
    return isinstance(x, int | float) and x == 0
