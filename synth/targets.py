"""What a synthesis aims at, named once: the time ratio as the crank angle β, and the
names of the objectives a request may name.

A quick-return's slow stroke takes the crank through π + β and the quick one through π − β,
so the time ratio is TR = (π + β)/(π − β) and β = π (TR − 1)/(TR + 1).

>>> round(time_ratio(beta(2.5)), 12)
2.5
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, TypeVar

if TYPE_CHECKING:
    import casadi as ca

# a number or a CasADi symbol (the IPOPT formulation's time ratio)
T = TypeVar("T", float, "ca.DM", "ca.SX", "ca.MX")

# the objectives' names (``synth.objectives``: what each means): the reduced solvers' and
# IPOPT's two, the front between them, the two on how the slider moves, the least peak torque
MAX_TRANSMISSION = "max_transmission_angle"
MIN_SIZE = "min_size"
PARETO = "pareto"
UNIFORM = "uniform_cutting_speed"
PEAK = "min_peak_acceleration"
PEAK_TORQUE = "min_peak_torque"


def beta(time_ratio: T) -> T:
    """The crank angle by which the slow stroke exceeds π: π (TR − 1)/(TR + 1)."""
    return math.pi * (time_ratio - 1) / (time_ratio + 1)


def time_ratio(beta: T) -> T:
    """The time ratio (π + β)/(π − β) of the crank angle β (``beta``'s inverse)."""
    return (math.pi + beta) / (math.pi - beta)


def transmission_deg(cos_mu: float) -> float:
    """The transmission angle (degrees, 0–90) of a joint whose cos μ is ``cos_mu``."""
    return math.degrees(math.acos(min(1.0, abs(cos_mu))))
