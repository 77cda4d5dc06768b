"""A-posteriori check of every candidate by the forward analysis (root-found dead centres).

The analysis shares no formula with the synthesis: the time ratio and stroke it reports come
from root finding on ds/dθ of the position function, not from the closed forms the NLP used.
"""

from __future__ import annotations

from typing import Any

from ..errors import SynthError
from ..results import TOL, Analysis
from .kinematics import analyze, analyze_many


def verify(
    mtype: str,
    params: dict[str, float],
    time_ratio: float,
    stroke: float,
    bound_deg: float,
    **extras: Any,
) -> tuple[Analysis, dict[str, float]] | None:
    """The analysis and the relative residuals if the design meets every target, else None.

    A design must also run cleanly: exactly two slider reversals per revolution (one working
    and one return stroke). ``extras`` (include, tolerance) are added to the analysis.
    """
    try:
        a = analyze(mtype, params, **extras)
    except SynthError:
        return None
    return _judged(a, time_ratio, stroke, bound_deg)


def verify_many(
    mtype: str,
    designs: list[dict[str, float]],
    time_ratio: float,
    stroke: float,
    bound_deg: float,
    **extras: Any,
) -> list[tuple[Analysis, dict[str, float]] | None]:
    """``verify`` of each design, their analyses done together (``analyze_many``)."""
    return [
        None if isinstance(a, SynthError) else _judged(a, time_ratio, stroke, bound_deg)
        for a in analyze_many(mtype, designs, **extras)
    ]


def _judged(
    a: Analysis, time_ratio: float, stroke: float, bound_deg: float
) -> tuple[Analysis, dict[str, float]] | None:
    residuals = {
        "time_ratio": abs(a.time_ratio - time_ratio) / time_ratio,
        "stroke": abs(a.stroke - stroke) / stroke,
    }
    ok = (
        a.reversals == 2
        and max(residuals.values()) <= TOL
        and a.transmission.min_deg >= bound_deg - TOL * max(bound_deg, 1.0)
    )
    return (a, residuals) if ok else None
