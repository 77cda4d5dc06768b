"""Frozen result values. Angles in degrees and lengths in the caller's unit, as at the API."""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any

import numpy as np


@dataclass(frozen=True)
class Extreme:
    position: float
    crank_angle_deg: float


@dataclass(frozen=True)
class Stroke:
    crank_angle_deg: float  # crank travel during the stroke
    direction: int  # sign of the slider's travel along its path


@dataclass(frozen=True)
class Joint:
    joint: str
    min_deg: float
    max_deg: float


@dataclass(frozen=True)
class Transmission:
    min_deg: float
    max_deg: float
    joints: tuple[Joint, ...]


@dataclass(frozen=True)
class Curves:
    crank_angle_deg: np.ndarray
    position: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray
    transmission_deg: np.ndarray


@dataclass(frozen=True)
class Analysis:
    """One design over a crank revolution (POST /v1/analyze)."""

    type: str
    params: dict[str, float]
    time_ratio: float
    stroke: float
    extremes: dict[str, Extreme]  # "min", "max"
    working_stroke: Stroke
    return_stroke: Stroke
    transmission: Transmission
    grashof: str | None
    # stationary points of s per revolution where the slider reverses: 2 for a clean quick
    # return; more means the slider dithers near a dead centre and the strokes are ill-defined
    reversals: int
    curves: Curves | None = None

    def to_dict(self) -> dict[str, Any]:
        out = asdict(self)
        if self.curves is None:
            del out["curves"]
        else:
            out["curves"] = {k: np.asarray(v).tolist() for k, v in out["curves"].items()}
        return out
