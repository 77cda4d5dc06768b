"""What an analysis is asked (``AnalysisRequest``: ``analyze``'s arguments, checked when
built) and the checks of what an analysis, or a synthesis's candidates, may include."""

from __future__ import annotations

from collections.abc import Collection, Mapping, Sequence
from dataclasses import KW_ONLY, dataclass, field, fields
from typing import Annotated

import numpy as np
from annotated_types import Ge, Le

from ..errors import InvalidParameters
from ..load import Load
from ..mechanisms import get
from ..requests import ANALYSIS_INCLUDE, TOLERANCE_HELP, Help, OneOf, check, included
from ..results import Curves, Tolerance
from . import loads

MAX_CURVE_POINTS = 100_000
# the numbers an analysis's curves may carry, points × (each curve, and x and y of each pin):
# 100 000 points of curves alone, ~8 MB of JSON (README, "What a client can rely on")
MAX_CURVE_VALUES = 500_000


@dataclass(frozen=True)
class AnalysisRequest:
    """``analyze``'s arguments (``kinematics.run``), checked when built: the design
    (``design``: valid, completed with its defaults), the curves' angles (``angles``,
    degrees; None: no curves) and what ``include`` asks with them, the load (a ``Load``, or a
    mapping of its fields) and the crank's speed with it (``omega``, rad/s: the load's, or
    ``crank_speed``, 1 by default)."""

    mechanism: Annotated[str, Help("the design's type")]
    params: Annotated[Mapping[str, float], Help("its parameters, by name, in one length unit")]
    _: KW_ONLY
    crank_speed: Annotated[float | None, Help("ω, rad/s; omitted: 1, or a load's crank_rpm")] = None
    crank_acceleration: Annotated[float, Help("α, rad/s²")] = 0.0
    crank_angles_deg: Annotated[
        Sequence[float] | None, Help("curves at exactly these angles, degrees", "crank-angle")
    ] = None
    samples: Annotated[
        int | None, Ge(1), Le(MAX_CURVE_POINTS), Help("curves at evenly spaced angles")
    ] = None
    include: Annotated[
        Collection[str], OneOf(ANALYSIS_INCLUDE), Help(included(ANALYSIS_INCLUDE))
    ] = ()
    tolerance: Annotated[Tolerance | None, Help(TOLERANCE_HELP)] = None
    load: Annotated[
        Load | None,
        Help("what the design drives: adds loads (its crank_rpm is the curves' speed)"),
    ] = None
    design: dict[str, float] = field(init=False, repr=False, compare=False)
    angles: np.ndarray | None = field(init=False, repr=False, compare=False)
    omega: float = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        check(self)
        load = Load.of(self.load)
        object.__setattr__(self, "load", load)
        m = get(self.mechanism)
        object.__setattr__(self, "design", m.complete(self.params))
        deg = asked(self.mechanism, self.include, self.crank_angles_deg, self.samples, load)
        omega = loads.speed(m, load, self.crank_speed, self.crank_acceleration)
        object.__setattr__(self, "angles", deg)
        object.__setattr__(self, "omega", omega)

    @property
    def curve_points(self) -> int:
        """How many angles the curves are at."""
        return 0 if self.angles is None else int(self.angles.size)


def asked(
    mechanism: str,
    include: Collection[str],
    crank_angles_deg: Sequence[float] | None,
    samples: int | None,
    load: Load | None = None,
) -> np.ndarray | None:
    """The curves' angles (``curve_angles``), once ``include`` (of what an analysis may
    include) is checked against them: pins need angles to be at, and a drawing; a ``load``
    adds the torque curve."""
    deg = curve_angles(crank_angles_deg, samples)
    if "pins" in include and deg is None:
        msg = "include 'pins' needs crank_angles_deg or samples (the angles the pins are wanted at)"
        raise InvalidParameters(msg, ("include",))
    check_drawn(mechanism, include)
    if "forces" in include and not (load is not None and deg is not None):
        msg = "include 'forces' needs a load, and crank_angles_deg or samples (its curves' angles)"
        raise InvalidParameters(msg, ("include",))
    if deg is not None:
        loc = "samples" if samples else "crank_angles_deg"
        _check_values(mechanism, include, deg.size, loc, load is not None)
    return deg


def _check_values(
    mechanism: str, include: Collection[str], points: int, loc: str, loaded: bool
) -> None:
    m = get(mechanism)
    curves = len(fields(Curves)) - 3 + loaded  # the pins and forces aside, the torque with a load
    pins = len({pin for d in m.drawing for pin in d[1:]}) if "pins" in include else 0
    if "forces" in include:
        curves += loads.forces_of(m)
    per = curves + 2 * pins
    if points * per > MAX_CURVE_VALUES:
        what = f"{curves} curves" + (f" and x, y of {pins} pins" if pins else "")
        raise InvalidParameters(
            f"the curves would carry {points * per} numbers ({points} points × {per}: {what}); "
            f"an analysis carries at most {MAX_CURVE_VALUES}: ask for at most "
            f"{MAX_CURVE_VALUES // per} points" + (" (or no pins)" if pins else ""),
            (loc,),
        )


def check_drawn(mechanism: str, include: Collection[str]) -> None:
    """Raise InvalidParameters where ``include`` asks for what needs the type's pins (its
    drawing: ``pins``, the ``envelope``) and the type has none."""
    needs = [k for k in ("pins", "envelope") if k in include]
    if needs and get(mechanism).joints is None:
        raise InvalidParameters(
            f"include {needs[0]!r}: {mechanism} has no drawing yet", ("include",)
        )


def curve_angles(
    crank_angles_deg: Sequence[float] | None, samples: int | None
) -> np.ndarray | None:
    """The crank angles of the curves asked for, in degrees (None: no curves), checked."""
    if crank_angles_deg is None and samples is None:
        return None
    if crank_angles_deg is not None and samples is not None:
        raise InvalidParameters("give crank_angles_deg or samples, not both", ("samples",))
    if crank_angles_deg is not None:
        deg = np.asarray(crank_angles_deg, dtype=float).ravel()
    else:
        if not (isinstance(samples, int) and samples >= 1):
            raise InvalidParameters(f"samples must be ≥ 1, got {samples}", ("samples",))
        deg = np.arange(samples) * (360.0 / samples)
    if deg.size > MAX_CURVE_POINTS:
        raise InvalidParameters(
            f"at most {MAX_CURVE_POINTS} curve points, got {deg.size}", ("crank_angles_deg",)
        )
    if not np.all(np.isfinite(deg)):
        raise InvalidParameters("crank angles must be finite", ("crank_angles_deg",))
    return deg
