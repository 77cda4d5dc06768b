"""The operations a formula written once needs, for CasADi symbols (``CASADI``: built into a
compiled function, differentiated) and for numpy arrays (``NUMPY``: evaluated at a grid of
points at once). Both take NaN the way C's fmin and fmax do (the other operand).

``choose(condition, then, otherwise)`` takes its branches as functions: CasADi builds both
and selects per point; numpy, given a plain number (a variant's switch), computes only the
branch it takes. A branch may give a tuple of values."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np


@dataclass(frozen=True)
class Ops:
    cos: Callable[[Any], Any]
    sin: Callable[[Any], Any]
    sqrt: Callable[[Any], Any]
    log: Callable[[Any], Any]
    fabs: Callable[[Any], Any]
    fmin: Callable[[Any, Any], Any]
    fmax: Callable[[Any, Any], Any]
    if_else: Callable[[Any, Any, Any], Any]
    logic_and: Callable[[Any, Any], Any]
    logic_or: Callable[[Any, Any], Any]
    logic_not: Callable[[Any], Any]
    choose: Callable[[Any, Callable[[], Any], Callable[[], Any]], Any]


def _casadi_choose(condition: Any, then: Callable[[], Any], otherwise: Callable[[], Any]) -> Any:
    a, b = then(), otherwise()
    if isinstance(a, tuple):
        return tuple(ca.if_else(condition, x, y) for x, y in zip(a, b, strict=True))
    return ca.if_else(condition, a, b)


CASADI = Ops(
    ca.cos,
    ca.sin,
    ca.sqrt,
    ca.log,
    ca.fabs,
    ca.fmin,
    ca.fmax,
    ca.if_else,
    ca.logic_and,
    ca.logic_or,
    ca.logic_not,
    _casadi_choose,
)


def _where(condition: Any, a: Any, b: Any) -> Any:
    """a where ``condition`` else b; a plain number (a variant's switch) picks one whole."""
    if isinstance(condition, int | float):
        return a if condition else b
    return np.where(condition, a, b)


def _numpy_choose(condition: Any, then: Callable[[], Any], otherwise: Callable[[], Any]) -> Any:
    if isinstance(condition, int | float):
        return then() if condition else otherwise()
    a, b = then(), otherwise()
    if isinstance(a, tuple):
        return tuple(np.where(condition, x, y) for x, y in zip(a, b, strict=True))
    return np.where(condition, a, b)


NUMPY = Ops(
    np.cos,
    np.sin,
    np.sqrt,
    np.log,
    np.abs,
    np.fmin,
    np.fmax,
    _where,
    np.logical_and,
    np.logical_or,
    np.logical_not,
    _numpy_choose,
)
