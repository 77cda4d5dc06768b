"""An atlas's values: the inputs that decide it, its points and the whole."""

from __future__ import annotations

import hashlib
import json
from dataclasses import asdict, dataclass, field
from typing import TypedDict

from ..version import __version__

CHUNK = 32  # grid points per task: a million points are 31 250 tasks, not a million


@dataclass(frozen=True)
class Inputs:
    """Everything that decides an atlas (``manifest.json``): the same inputs, the same atlas."""

    types: tuple[str, ...]
    ratios: tuple[float, ...]
    bounds: tuple[float, ...]
    chunk: int = CHUNK
    version: str = __version__

    def key(self) -> str:
        return hashlib.sha256(json.dumps(asdict(self), sort_keys=True).encode()).hexdigest()[:16]


@dataclass(frozen=True)
class Point:
    """One frontier point: the best angle at a time ratio, or why there is none."""

    type: str
    time_ratio: float
    best_angle_deg: float | None
    status: str  # certified, local or refused
    design: dict[str, float] | None = None  # stroke units
    reason: str | None = None


class Range(TypedDict):
    """The time ratios at which a type meets a bound (``reach``): None where it does not."""

    type: str
    bound_deg: float
    min: float | None
    max: float | None


@dataclass
class Atlas:
    inputs: Inputs
    frontier: list[Point]
    ranges: list[Range] = field(default_factory=list)
    computed: int = 0  # chunks computed by this run (the rest were read from the folder)

    def best(self, mtype: str) -> list[tuple[float, float | None]]:
        return [(p.time_ratio, p.best_angle_deg) for p in self.frontier if p.type == mtype]

    def meets(self, time_ratio: float, bound_deg: float) -> list[str]:
        """The types whose grid point at exactly this time ratio meets the bound."""
        return [
            p.type
            for p in self.frontier
            if p.time_ratio == time_ratio
            and p.best_angle_deg is not None
            and p.best_angle_deg >= bound_deg
        ]
