"""What the synthesis's searches bound, for one design: the terms whose largest is a motion
measure or the peak crank torque, with their derivatives in the parameters, and where each
transmission joint is worst. Each from the design's analysis (``kinematics.prepared``)."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from ..errors import InvalidDesign
from ..load import Load
from . import loads, quality
from .kinematics import Prepared, prepared, slider_extremes, upright


def motion_terms(
    mechanism: str, params: Mapping[str, float], gradient: bool = False
) -> quality.MotionTerms:
    """The values whose maxima are the motion measures (``quality.MotionTerms``), with their
    derivatives in the parameters when ``gradient``, for an optimiser that bounds each;
    raises SynthError for a design that does not run."""
    d, st = _running(mechanism, params)
    return quality.motion_terms(d.mechanism, d.variant, d.model, d.pv, st, gradient)


def peak_torque_terms(
    mechanism: str, params: Mapping[str, float], load: Load, metres: float
) -> tuple[np.ndarray, np.ndarray]:
    """The values whose largest is the peak crank torque under ``load`` (the lengths
    ``metres`` each), and their derivatives in the parameters (``loads.peak_terms``), for an
    optimiser that bounds each; raises SynthError for a design that does not run."""
    d, st = _running(mechanism, params)
    m, variant, pv = d.mechanism, d.variant, d.pv
    return loads.peak_terms(m, variant, d.model, pv, st, upright(m, variant, pv, st, load), metres)


def _running(mechanism: str, params: Mapping[str, float]) -> tuple[Prepared, quality.Strokes]:
    """A design prepared, and its strokes; raises InvalidDesign where its slider does not run
    one working and one return stroke (two reversals a turn: counted before they are
    polished)."""
    d = prepared(mechanism, params, reversals=2)
    rows, theta, values = d.points
    st = quality.Strokes(*slider_extremes(rows, theta, values))
    if st.stroke == 0:  # a design at the edge of running: its extremes coincide
        raise InvalidDesign("the slider does not move: its stroke is 0", (), "stroke")
    return d, st


def worst_transmission(mechanism: str, params: Mapping[str, float]) -> tuple[float, ...]:
    """Each transmission joint's crank angle (radians) where its |cos μ| is largest, in the
    type's order; raises SynthError for a design that does not run."""
    d = prepared(mechanism, params)
    rows, theta, values = d.points
    out = []
    for j in range(1, len(d.model.names) + 1):
        k = np.nonzero(rows == j)[0]
        out.append(float(theta[k[np.argmax(np.abs(values[k]))]]) if k.size else 0.0)
    return tuple(out)
