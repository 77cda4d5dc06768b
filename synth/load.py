"""What a design drives: the load of an analysis (or of a synthesis's candidates), checked.

Lengths stay in the caller's unit (``length_unit``); forces, masses and everything the loads
answer are SI (``synth.analysis.loads``; ``docs/model.md``, *Loads*).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, replace
from typing import Annotated, Any

from annotated_types import Ge, Interval, Le

from .errors import InvalidParameters
from .requests import Help, OneOf, arguments, held

LENGTH_UNITS = {"m": 1.0, "mm": 1e-3, "in": 0.0254}  # metres per length unit
GRAVITY = 9.80665  # m/s², standard
# the ranges of the numbers the flywheel and the motor's power divide by, wider than any machine
# needs: a crank that turns once in 1.9 years to one at 1e6 rpm, a flywheel that holds the speed
# to a millionth or to ±50 %, a drive that wastes all but a millionth; a flywheel's shaft and a
# motor as slow or fast as a crank, a disc a nanometre to a billion length units wide. So Cs ω²
# ≥ 1.1e-20, mean·ω/η and a disc's diameter stay finite numbers
RANGES = {
    "crank_rpm": (1e-6, 1e6),
    "speed_fluctuation": (1e-6, 1.0),
    "efficiency": (1e-6, 1.0),
    "flywheel_rpm": (1e-6, 1e6),
    "motor_rpm": (1e-6, 1e6),
    "flywheel_width": (1e-9, 1e9),
}
_WORDED = ("efficiency", "ram_incline_deg")  # numbers whose ranges their own words say
STEEL = 7850.0  # kg/m³: the solid disc a flywheel's diameter is given for
# the least step between two fractions of the working stroke (a cut's zone, a profile's points):
# a nanometre of a metre's stroke. The force's slope between them, ΔF / (Δu · stroke), is finite
GAP = 1e-9


def _within(name: str) -> Interval:
    """A number's range as ``RANGES`` gives it."""
    lo, hi = RANGES[name]
    return Interval(ge=lo, le=hi)


@dataclass(frozen=True)
class Load:
    """What a design drives, at constant crank speed (an analysis's ``load``).

    The lengths stay in the caller's unit, ``length_unit`` (one of ``LENGTH_UNITS``); forces
    and masses are SI. ``cutting_force`` (N) resists the ram through ``cutting_zone``, the
    fractions of the working stroke (by position) where the tool cuts; or ``force_profile``
    gives the resisting force as (fraction of the working stroke, N) points, increasing in
    the fraction, linear between them and 0 outside them. ``slider_mass`` (kg) is the ram
    and its tool, ``link_mass_per_length`` (kg/m) the links' (uniform slender rods; 0:
    massless), ``guide_friction`` the Coulomb coefficient at the ram's guide. ``gravity_deg``
    is the direction gravity pulls in, in the drawing's frame (degrees from +x, counter-
    clockwise; −90: down the drawing's y axis); or ``ram_incline_deg`` says it in the
    machine's, the same for every type: the mechanism in a vertical plane, its drive below
    the ram's path, the working stroke this many degrees above the horizontal (0: a shaper,
    −90: a slotter cutting downwards); neither: no weight (the plane is horizontal).
    ``speed_fluctuation`` is the coefficient Cs = (ω_max − ω_min)/ω a flywheel must hold the
    crank within, ``efficiency`` the drive's from motor to crank; ``flywheel_rpm`` the speed
    of the shaft that carries the flywheel (None: the crank's), ``flywheel_width`` the width
    of a solid steel disc flywheel (in ``length_unit``) whose diameter the loads give,
    ``motor_rpm`` the motor's speed, at which they give its rated torque; each number within
    ``RANGES``."""

    length_unit: Annotated[
        str,
        OneOf(tuple(LENGTH_UNITS)),
        Help("the unit of the design's lengths (forces and masses are SI)"),
    ]
    crank_rpm: Annotated[float, _within("crank_rpm"), Help("the crank's constant speed")]
    cutting_force: Annotated[
        float, Ge(0.0), Help("N, resisting the ram through the cutting zone")
    ] = 0.0
    cutting_zone: Annotated[
        tuple[float, float],
        Help(
            "[start, end]: the fractions of the working stroke (by position) where the tool "
            f"cuts, 0 ≤ start < end ≤ 1, end − start ≥ {GAP:g}"
        ),
    ] = (0.1, 0.9)
    slider_mass: Annotated[float, Ge(0.0), Help("kg: the ram and its tool")] = 0.0
    link_mass_per_length: Annotated[
        float, Ge(0.0), Help("kg/m: each drawn link a uniform slender rod (0: none)")
    ] = 0.0
    speed_fluctuation: Annotated[
        float,
        _within("speed_fluctuation"),
        Help("Cs = (ω_max − ω_min)/ω the flywheel keeps the crank to"),
    ] = 0.05
    efficiency: Annotated[float, _within("efficiency"), Help("the drive's, motor to crank")] = 1.0
    force_profile: Annotated[
        tuple[tuple[float, float], ...] | None,
        Help(
            "instead of cutting_force and cutting_zone: [fraction of the working stroke, N] "
            f"points, the fractions increasing in [0, 1] (each by {GAP:g} or more), the force "
            "≥ 0, linear between them and 0 outside them"
        ),
    ] = None
    guide_friction: Annotated[
        float, Ge(0.0), Help("Coulomb coefficient at the ram's guide (0: none)")
    ] = 0.0
    gravity_deg: Annotated[
        float | None,
        Help(
            "the direction gravity pulls in, in the drawing's frame (degrees from +x, "
            "counter-clockwise: -90 is down the drawing's y axis); omitted, and no "
            "ram_incline_deg: no weight"
        ),
    ] = None
    ram_incline_deg: Annotated[
        float | None,
        Ge(-90.0),
        Le(90.0),
        Help(
            "instead of gravity_deg, gravity in the machine's frame, the same for every type: "
            "the mechanism in a vertical plane, its drive below the ram's path, the working "
            "stroke this many degrees above the horizontal (0: a shaper, -90: a slotter "
            "cutting downwards)"
        ),
    ] = None
    flywheel_rpm: Annotated[
        float | None,
        _within("flywheel_rpm"),
        Help("the speed of the shaft that carries the flywheel (omitted: the crank's)"),
    ] = None
    flywheel_width: Annotated[
        float | None,
        _within("flywheel_width"),
        Help("in length_unit: adds the diameter of a solid steel disc flywheel this wide"),
    ] = None
    motor_rpm: Annotated[
        float | None,
        _within("motor_rpm"),
        Help("the motor's speed: adds its rated torque there"),
    ] = None

    @classmethod
    def of(cls, load: Load | Mapping[str, Any] | None) -> Load | None:
        """A load as a ``Load``: one already, or the API's load object (a mapping of its
        fields); InvalidParameters naming a field that is not one of them or is missing."""
        return held(cls, load, "load")

    def __post_init__(self) -> None:
        if self.length_unit not in LENGTH_UNITS:
            raise InvalidParameters(
                f"load.length_unit must be one of {', '.join(LENGTH_UNITS)} (the unit of the "
                f"design's lengths: forces and masses are SI), got {self.length_unit!r}",
                ("load", "length_unit"),
            )
        for a in arguments(Load):  # the numbers from 0, or within RANGES
            v, name, limits = getattr(self, a.name), a.name, {type(m): m for m in a.limits}
            if Ge not in limits or a.many or name in _WORDED or (v is None and a.optional):
                continue
            lo, hi = limits[Ge].ge, limits[Le].le if Le in limits else math.inf
            if not (_number(v) and lo <= v <= hi):
                rule = f"> 0, at least {lo:g} and at most {hi:g}" if name in RANGES else "≥ 0"
                msg = f"load.{name} must be a finite number {rule}, got {v!r}"
                raise InvalidParameters(msg, ("load", name))
        if self.gravity_deg is not None and not _number(self.gravity_deg):
            msg = f"load.gravity_deg must be a finite angle, got {self.gravity_deg!r}"
            raise InvalidParameters(msg, ("load", "gravity_deg"))
        incline = self.ram_incline_deg
        if incline is not None and not (_number(incline) and -90 <= incline <= 90):
            msg = f"load.ram_incline_deg must be an angle from -90 to 90, got {incline!r}"
            raise InvalidParameters(msg, ("load", "ram_incline_deg"))
        if incline is not None and self.gravity_deg is not None:
            msg = "load: give gravity_deg (the drawing's frame) or ram_incline_deg, not both"
            raise InvalidParameters(msg, ("load", "ram_incline_deg"))
        e, (lo, hi) = self.efficiency, RANGES["efficiency"]
        if not (_number(e) and lo <= e <= hi):
            msg = f"load.efficiency must be in (0, 1], at least {lo:g}, got {e!r}"
            raise InvalidParameters(msg, ("load", "efficiency"))
        zone = tuple(self.cutting_zone)
        if not (
            len(zone) == 2
            and all(_number(z) for z in zone)
            and 0 <= zone[0] < zone[1] <= 1
            and zone[1] - zone[0] >= GAP
        ):
            msg = (
                f"load.cutting_zone must be [start, end] with 0 ≤ start < end ≤ 1, end − "
                f"start ≥ {GAP:g} (fractions of the working stroke), got "
                f"{list(zone)!r}"
            )
            raise InvalidParameters(msg, ("load", "cutting_zone"))
        object.__setattr__(self, "cutting_zone", (float(zone[0]), float(zone[1])))
        if self.force_profile is not None:
            self._check_profile()

    def _check_profile(self) -> None:
        loc = ("load", "force_profile")
        if self.cutting_force or self.cutting_zone != (0.1, 0.9):
            msg = "load: give cutting_force (and cutting_zone) or force_profile, not both"
            raise InvalidParameters(msg, loc)
        points = [tuple(q) for q in self.force_profile or ()]
        if len(points) < 2 or any(len(q) != 2 or not all(map(_number, q)) for q in points):
            msg = (
                f"load.force_profile must be at least two [fraction, force] pairs of finite "
                f"numbers, got {self.force_profile!r}"
            )
            raise InvalidParameters(msg, loc)
        for i, (u, f) in enumerate(points):
            if not 0 <= u <= 1 or f < 0:
                msg = (
                    f"load.force_profile[{i}]: the fraction must be in [0, 1] and the force "
                    f"≥ 0, got [{u:g}, {f:g}]"
                )
                raise InvalidParameters(msg, (*loc, i))
            if i and not u - points[i - 1][0] >= GAP:
                msg = (
                    f"load.force_profile[{i}]: fractions must increase, each by at least "
                    f"{GAP:g}, got {u:g} after {points[i - 1][0]:g}"
                )
                raise InvalidParameters(msg, (*loc, i))
        object.__setattr__(self, "force_profile", tuple((float(u), float(f)) for u, f in points))

    @property
    def profile(self) -> tuple[tuple[float, float], ...]:
        """The resisting force as (fraction of the working stroke, N) points: the given
        profile, or the cutting force over its zone."""
        if self.force_profile is not None:
            return self.force_profile
        (a, b), f = self.cutting_zone, self.cutting_force
        return ((a, f), (b, f))

    @property
    def metres(self) -> float:
        """Metres per length unit."""
        return LENGTH_UNITS[self.length_unit]

    @property
    def omega(self) -> float:
        """The crank speed, rad/s."""
        return _rad_s(self.crank_rpm)

    @property
    def flywheel_speed(self) -> float:
        """The speed of the shaft that carries the flywheel, rpm."""
        return float(self.flywheel_rpm or self.crank_rpm)

    def inertia(self, energy: float) -> float:
        """The flywheel inertia (kg·m²) that holds its shaft's speed within
        ``speed_fluctuation`` against an energy swing ``energy`` (J): ΔE / (Cs ω²)."""
        return energy / self.speed_fluctuation / _rad_s(self.flywheel_speed) ** 2

    def motor_torque(self, rated: float) -> float | None:
        """The motor's torque (N·m) at ``motor_rpm`` for its rated power ``rated`` (W); None
        without a motor speed."""
        return None if self.motor_rpm is None else rated / _rad_s(self.motor_rpm)

    def disc(self, inertia: float) -> float | None:
        """The diameter (``length_unit``) of a solid steel disc ``flywheel_width`` wide whose
        inertia about its axis is ``inertia`` (kg·m²): I = π ρ w D⁴ / 32; None without a
        width."""
        if self.flywheel_width is None:
            return None
        width = self.flywheel_width * self.metres
        return math.sqrt(math.sqrt(32 * inertia / (math.pi * STEEL * width))) / self.metres

    def drawn(self, working: tuple[float, float], up: tuple[float, float]) -> Load:
        """This load with its gravity in a design's drawing frame: ``working``, the unit
        vector of the ram's working stroke there, and ``up``, the unit normal of its path
        pointing away from the crank's side (``ram_incline_deg`` α: gravity is
        −g (sin α working + cos α up))."""
        if self.ram_incline_deg is None:
            return self
        a = math.radians(self.ram_incline_deg)
        gx = -(math.sin(a) * working[0] + math.cos(a) * up[0])
        gy = -(math.sin(a) * working[1] + math.cos(a) * up[1])
        return replace(self, gravity_deg=math.degrees(math.atan2(gy, gx)), ram_incline_deg=None)

    @property
    def gravity(self) -> tuple[float, float]:
        """Gravity's acceleration in the drawing's frame, m/s² (0 without ``gravity_deg``)."""
        assert self.ram_incline_deg is None  # in the machine's frame: ``drawn`` first
        if self.gravity_deg is None:
            return 0.0, 0.0
        a = math.radians(self.gravity_deg)
        return GRAVITY * math.cos(a), GRAVITY * math.sin(a)


def _rad_s(rpm: float) -> float:
    """A shaft's speed in rad/s, from rpm."""
    return 2 * math.pi * rpm / 60


def _number(v: Any) -> bool:
    return isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)
