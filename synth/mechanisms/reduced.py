"""Exact reduced synthesis: the targets turn most of a design into closed forms.

The time ratio and the stroke are two equalities. A type's ``reduced`` solver (an optional
accelerator in its registry record) parametrises the designs that meet them exactly, by the
classical dead-centre construction, and solves what is left, a problem in at most two
variables, by closed forms, bracketed roots and Newton's method on its optimality conditions.
It returns every local optimum it finds (one per branch or structural choice), in stroke
units, and says whether the answer is ``exact``: the best design is the global optimum of the
stated problem, and an empty answer proves that no design exists. Anything it cannot take
(``None``, or not ``exact``) goes to IPOPT, warm-started from the designs it did find.

This module is that contract: the problem a solver takes, the answer it gives, and the
helpers its checks share. The rule for a connecting rod is ``rod``; Newton's method and the
other small numerics are ``synth.numerics.dense``.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from ..errors import Unreachable
from ..numerics import ROUNDING
from ..results import TOL
from ..targets import time_ratio

if TYPE_CHECKING:
    from .facts import Facts

STRICT = 1e-7  # the margin kept by a strict condition, in stroke units (the NLP's too)
# the cos margin kept from the one-way limit (``Facts.one_way``): at the limit the slider dwells
# at its dead centre, a multiple root that the analysis locates only to ~1e-6 in the time
# ratio; the error falls as 1/margin (worst of 300 designs: 3e-12 at 1e-4, 2e-13 at 1e-3)
ONE_WAY = 1e-3


@dataclass(frozen=True)
class Problem:
    """One structural variant of one type, in stroke units (the stroke is 1).

    ``fixed`` holds the variant's fixed parameters, ``bounds`` the box of every free one (the
    caller's, else the defaults); ``beta`` = π(TR − 1)/(TR + 1) is the crank angle by which
    the slow stroke exceeds π; ``cos_bound`` is cos of the transmission bound (1: none).
    ``stroke`` is the caller's stroke, for messages in the caller's unit.

    Default bounds limit a search: a parameter that the targets and the fixed parts set on
    their own is taken as it comes unless the caller bounded it (``allows``).
    """

    variant: frozenset[str]
    fixed: Mapping[str, float]
    bounds: Mapping[str, tuple[float, float]]
    beta: float
    cos_bound: float
    objective: str
    stroke: float = 1.0
    explicit: frozenset[str] = frozenset()  # parameters whose bounds the caller gave
    hints: tuple[Mapping[str, float], ...] = ()  # the optima of the type's other variants
    # where this variant's optima were at a nearby bound (a front's previous point), in the
    # solver's own coordinates (``Reduced.at``): a solver may continue from there
    near: tuple[tuple[float, ...], ...] = ()

    @property
    def ratio(self) -> float:
        """The time ratio."""
        return time_ratio(self.beta)

    @property
    def half(self) -> tuple[float, float]:
        """sin and cos of β/2."""
        return math.sin(self.beta / 2), math.cos(self.beta / 2)

    def box(self, name: str) -> tuple[float, float]:
        """The interval a parameter may take: its fixed value, or its bounds."""
        if name in self.fixed:
            return self.fixed[name], self.fixed[name]
        return self.bounds[name]

    def allows(self, name: str, x: float) -> bool:
        """Whether a parameter set by the targets and fixed parts may take the value x: any
        value, unless the caller bounded it."""
        return name not in self.explicit or within(x, self.bounds[name])

    def shown(self, x: float) -> str:
        """A length in stroke units, in the caller's unit, for a message."""
        return f"{x * self.stroke:g}"


@dataclass(frozen=True)
class Reduced:
    """A reduced solver's answer: local optima (stroke units, every relevant parameter of the
    variant, fixed ones included), best first or not, and whether it is exact."""

    designs: list[dict[str, float]] = field(default_factory=list)
    exact: bool = True
    at: tuple[tuple[float, ...], ...] = ()  # where the solver found them, its coordinates


@dataclass(frozen=True)
class Space:
    """Every design of a variant that meets the time ratio and stroke, as a function of a few
    free numbers u over the box [``lo``, ``hi``]: ``design(u, c)`` (CasADi symbols: u, and
    ``constants`` the request sets, such as β) gives each relevant parameter in stroke units;
    its form is the same for every space of a variant with as many free numbers and
    constants (what is built from it is kept and reused by them).
    The designs of the box that meet the other constraints (transmission, validity, the
    request's bounds) are then all the variant's feasible designs, up to a free scale and a
    mirror that leave the motion as it is: a global search over the box is one over the
    variant (``synth.synthesis.certify``). The loads a design carries may tell the mirror
    image from the design, and one scale from another: ``mirror`` gives the constants of the
    mirror image's space (None: the mirror is not free), ``scaled`` says that the crank's
    scale is free and pinned (its weight loads a longer crank more). ``dead`` gives the
    crank angles of the slider's dead centres from the constants where they are the same for
    every design of the space that meets its conditions (None: they move with u).
    ``measures`` names the searched measures whose certified search over it finishes in good
    time (None: all it takes); the others are left to the local search."""

    lo: tuple[float, ...]
    hi: tuple[float, ...]
    constants: tuple[float, ...]
    design: Callable[[Any, Any], dict[str, Any]]
    mirror: tuple[float, ...] | None = None
    scaled: bool = False
    dead: Callable[[Any], tuple[float, float]] | None = None
    measures: frozenset[str] | None = None


def unreachable(what: str) -> Unreachable:
    """Fixed parts that no design with the targets can have, with the reason."""
    return Unreachable("FIXED_PARTS_CONTRADICT_TARGETS", what)


def judge(p: Problem, facts: Callable[[dict[str, Any]], Facts], design: dict[str, float]) -> None:
    """Raise when fixed parts that over-determine a design (more fixed than the targets leave
    free) miss the targets: by the type's closed forms, to the verification's tolerance."""
    f = facts(design)
    beta = abs(float(f.beta))
    got = {
        "time ratio": (time_ratio(beta), p.ratio),
        "stroke": (float(f.stroke) * p.stroke, p.stroke),
    }
    missed = [
        "{} {}, not {}".format(what, *differ(value, want))
        for what, (value, want) in got.items()
        if not agree(value, want)
    ]
    if missed:
        raise unreachable(f"the fixed parts give {' and '.join(missed)} (to a relative {TOL:g})")


def within(x: float, box: tuple[float, float]) -> bool:
    """lo ≤ x ≤ hi, to rounding (a value built on its bound)."""
    return box[0] * (1 - ROUNDING) <= x <= box[1] * (1 + ROUNDING)


def differ(a: float, b: float) -> tuple[str, str]:
    """a and b printed with the fewest significant digits, at least 9, that tell them apart."""
    for digits in range(9, 18):
        x, y = f"{a:.{digits}g}", f"{b:.{digits}g}"
        if x != y or a == b:
            return x, y
    return repr(a), repr(b)


def agree(got: float, want: float) -> bool:
    """Whether a value the fixed parts give meets its target, to the verification's tolerance."""
    return abs(got - want) <= TOL * abs(want)


def clip(x: float, lo: float, hi: float) -> float:
    return min(max(x, lo), hi)


def intersect(*intervals: tuple[float, float]) -> tuple[float, float] | None:
    lo = max(a for a, _ in intervals)
    hi = min(b for _, b in intervals)
    return (lo, hi) if lo <= hi else None
