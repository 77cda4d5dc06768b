"""The operations a formula written once needs, for CasADi symbols (``CASADI``: built into a
compiled function, differentiated) and for numpy arrays (``NUMPY``: evaluated at a grid of
points at once). Both take NaN the way C's fmin and fmax do (the other operand)."""

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


CASADI = Ops(ca.cos, ca.sin, ca.sqrt, ca.log, ca.fabs, ca.fmin, ca.fmax, ca.if_else,
             ca.logic_and, ca.logic_or, ca.logic_not)  # fmt: skip


def _where(condition: Any, a: Any, b: Any) -> Any:
    """a where ``condition`` else b; a plain number (a variant's switch) picks one whole."""
    if isinstance(condition, int | float):
        return a if condition else b
    return np.where(condition, a, b)


NUMPY = Ops(np.cos, np.sin, np.sqrt, np.log, np.abs, np.fmin, np.fmax, _where,
            np.logical_and, np.logical_or, np.logical_not)  # fmt: skip
