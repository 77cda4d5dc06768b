"""Each operation's arguments as one value: a frozen dataclass beside the operation
(``SynthesisRequest``, ``AnalysisRequest``, ``SweepRequest``, ``ExportRequest``,
``ReportRequest``), checked when it is built, as ``Load`` is. The library's function takes
its keyword form from it (``keyword``), the service builds it from a request's body and the
command line through the keyword form: each argument list is written once, in the request's
fields, and an argument nobody knows is an error everywhere."""

from __future__ import annotations

import copy
import inspect
import math
from collections.abc import Callable
from typing import ParamSpec, TypeVar

from .errors import InvalidParameters

INCLUDE = ("motion", "sensitivities", "envelope")  # what an analysis or a candidate adds when asked
# an analysis also adds its curves' pins when asked (they need the curves' angles), and with a
# load its curves' forces
ANALYSIS_INCLUDE = (*INCLUDE, "pins", "forces")
P = ParamSpec("P")
R = TypeVar("R")
T = TypeVar("T")


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


def check_budget(time_budget_ms: float) -> None:
    """A time budget is a finite number of milliseconds > 0."""
    if not (time_budget_ms > 0 and math.isfinite(time_budget_ms)):
        msg = f"time_budget_ms must be > 0, got {time_budget_ms}"
        raise InvalidParameters(msg, ("time_budget_ms",))


def rebudgeted(request: R, time_budget_ms: float) -> R:
    """``request`` (checked when built) with another time budget, not checked again: a
    budget is the one field a service changes, and a valid one keeps the request valid."""
    check_budget(time_budget_ms)
    out = copy.copy(request)
    object.__setattr__(out, "time_budget_ms", time_budget_ms)
    return out
