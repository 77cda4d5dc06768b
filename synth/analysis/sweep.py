"""sweep(): vary one parameter of a design, the rest held (Podhorodeski et al. (2005), Fig. 5).

Each point is analysed; the exact valid interval(s) come from bisection on the validity of the
design (each boundary located to one ulp: for the Grashof limits, where a margin is exactly 0),
and the time-ratio range over them from bounded Brent refinement of the best sampled points.
A budget bounds the sampling: the points are analysed in order, ``CHUNK`` at a time, and past
the budget the sweep ends at the last point analysed (``complete`` False).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Annotated, Any

import numpy as np
from annotated_types import Ge, Gt, Le

from ..errors import InvalidParameters, SynthError
from ..mechanisms import get
from ..numerics.dense import bisect
from ..requests import Help, check, keyword
from ..results import Analysis, Extremum, SweepResult, TimeRatioRange
from .kinematics import analyze, analyze_many


def minimize_scalar(*args: Any, **kwargs: Any) -> Any:
    """scipy's, imported on first use (scipy.optimize: ~0.2 s of an import of synth)."""
    from scipy.optimize import minimize_scalar

    return minimize_scalar(*args, **kwargs)


MAX_POINTS = 10_000
CHUNK = 256  # points analysed between two looks at the clock (~25 ms of a four-bar's)


@dataclass(frozen=True)
class SweepRequest:
    """``sweep``'s arguments (``run``), checked when built."""

    mechanism: Annotated[str, Help("the design's type")]
    params: Annotated[Mapping[str, float], Help("its parameters, by name, in one length unit")]
    vary: Annotated[str, Help("the parameter to vary")]
    start: Annotated[float, Help("its first value")]
    stop: Annotated[float, Help("its last value")]
    points: Annotated[int, Ge(1), Le(MAX_POINTS), Help("how many values, evenly spaced")] = 101
    time_budget_ms: Annotated[
        float | None, Gt(0.0), Help("the sweep's time; past it, the points analysed by then")
    ] = None

    def __post_init__(self) -> None:
        check(self)
        m = get(self.mechanism)
        for k in self.params:
            m.parameter(k)
        try:
            q = m.parameter(self.vary)
        except InvalidParameters as e:
            raise InvalidParameters(e.msg, ("vary",)) from None
        start, stop = self.start, self.stop
        if start > stop:
            raise InvalidParameters(f"start {start:g} > stop {stop:g}", ("stop",))
        if not q.signed and start <= 0 and not (q.zero_means and start == 0):
            msg = f"{self.vary} is a length: start must be > 0, got {start:g}"
            raise InvalidParameters(msg, ("start",))


def run(r: SweepRequest) -> SweepResult:
    """Analyse the design at ``points`` values of ``vary`` from ``start`` to ``stop``; within
    ``time_budget_ms`` (None: however long it takes), else up to the last point analysed by
    then (``complete`` False), the intervals and the range over those.

    >>> r = sweep("drag_link_slider", {"ground": 0.1, "crank": 0.225, "coupler": 0.3,
    ...           "follower": 0.275, "follower_arm": 0.15, "connecting_rod": 0.3},
    ...           "coupler", 0.1, 0.5, 41)
    >>> [[round(v, 12) for v in iv] for iv in r.valid_interval]
    [[0.15, 0.4]]
    """
    mechanism, params, vary = r.mechanism, r.params, r.vary
    deadline = time.monotonic() + (r.time_budget_ms / 1000 if r.time_budget_ms else math.inf)
    held = {k: v for k, v in params.items() if k != vary}

    def at(v: float) -> Analysis | None:
        try:
            return analyze(mechanism, {**held, vary: v})
        except SynthError:
            return None

    values = np.linspace(r.start, r.stop, r.points) if r.points > 1 else np.array([r.start])
    designs = [{**held, vary: float(v)} for v in values]
    runs: list[Any] = []
    for k in range(0, len(designs), CHUNK):
        if time.monotonic() >= deadline:
            break
        runs += [  # analysed together: the same analyses as one by one, for less
            None if isinstance(a, SynthError) else a
            for a in analyze_many(mechanism, designs[k : k + CHUNK])
        ]
    complete = len(runs) == len(values)
    values = values[: len(runs)]
    valid = [a is not None for a in runs]
    intervals = _intervals(lambda v: at(v) is not None, values, valid)
    return SweepResult(
        type=mechanism,
        vary=vary,
        values=[float(v) for v in values],
        time_ratio=[a.time_ratio if a else None for a in runs],
        stroke=[a.stroke if a else None for a in runs],
        min_transmission_angle_deg=[a.transmission.min_deg if a else None for a in runs],
        valid=valid,
        valid_interval=intervals,
        time_ratio_range=_tr_range(at, values, runs, intervals),
        complete=complete,
    )


sweep = keyword(SweepRequest, run, "sweep")


def _intervals(
    ok: Callable[[float], bool], values: np.ndarray, valid: list[bool]
) -> list[tuple[float, float]]:
    """The valid intervals within [values[0], values[-1]], each boundary bisected to one ulp."""
    out: list[tuple[float, float]] = []
    if not valid:
        return out
    lo = float(values[0]) if valid[0] else None
    for k in range(1, len(values)):
        if valid[k] != valid[k - 1]:
            a, b = float(values[k - 1]), float(values[k])
            edge = bisect(ok, *((a, b) if valid[k - 1] else (b, a)))[0]
            if valid[k]:
                lo = edge
            else:
                assert lo is not None  # set where the valid run began
                out.append((lo, edge))
                lo = None
    if lo is not None:
        out.append((lo, float(values[-1])))
    return out


def _tr_range(
    at: Callable[[float], Analysis | None],
    values: np.ndarray,
    runs: Sequence[Analysis | None],
    intervals: list[tuple[float, float]],
) -> TimeRatioRange | None:
    if not intervals:
        return None
    found: list[tuple[float, float]] = []
    for lo, hi in intervals:
        for edge in (lo, hi):
            a = at(edge)
            if a is not None:
                found.append((a.time_ratio, edge))
        inside = [
            (a.time_ratio, float(v))
            for v, a in zip(values, runs, strict=True)
            if a is not None and lo <= v <= hi
        ]
        step = float(values[1] - values[0]) if len(values) > 1 else 0.0
        for sign in (1, -1) if inside else ():

            def signed_tr(v: float, sign: int = sign) -> float:
                a = at(v)
                return sign * a.time_ratio if a is not None else math.inf

            v0 = min(inside, key=lambda tv: sign * tv[0])[1]
            a_, b_ = max(lo, v0 - step), min(hi, v0 + step)
            if b_ > a_:
                r = minimize_scalar(
                    signed_tr, bounds=(a_, b_), method="bounded", options={"xatol": 1e-12}
                )
                if math.isfinite(r.fun):
                    found.append((sign * float(r.fun), float(r.x)))
    return TimeRatioRange(Extremum(*min(found)), Extremum(*max(found)))
