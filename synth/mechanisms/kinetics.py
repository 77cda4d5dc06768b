"""The forces in a design turning at constant crank speed: its Newton–Euler equations.

A type's ``frame`` says which drawn members move as one body and how the bodies meet (pins,
blocks in slots, the ram's guide). Each moving body's three equations (forces in x and y,
moment about the crank pivot) and the ram's two (along its path and across it) are linear in
the unknowns: the crank's driving torque, both components of each pin's force, each block's
push along its slot's normal and the guide's normal force. The accelerations come from the
type's pin positions (``joints``), differentiated twice in the crank angle and multiplied by
ω². Everything is in SI: the lengths are multiplied by the unit's metres.

Mass model: each drawn member of a body is a uniform slender rod of ``mass_per_length``
(its mass at its middle, m L²/12 about it); the ram's mass is ``slider_mass``; blocks are
massless. The force on the ram acts along its path (positive as s grows): ``force`` +
``force_slope`` × s, s in metres (a cut whose force varies linearly with the ram's position).
Gravity (``gx``, ``gy``) pulls each member at its middle and the ram. Only the ram's guide
rubs: its friction, −μ |N| sign(v) along the path, is ``friction`` × N where the signs of N
and v hold (``friction`` = −μ sign(v) sign(N): the caller splits the turn where they
change); pins and slots are frictionless.

Where the guide does not rub, the crank's torque alone follows from the motion by the balance
of power (``torque``), with the same mass model (``_members``).
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np

from ..load import Load
from .registry import GROUND, RAM, Mechanism, Params

# the load's numbers a compiled model takes after the type's parameters: metres per length
# unit, crank speed (rad/s), ram mass (kg), link mass per metre (kg/m), the force on the ram
# (N) at s = 0 and its change per metre of s (N/m), gravity's x and y in the drawing's frame
# (m/s²), the guide's friction per unit of N
LOAD = (
    "unit",
    "omega",
    "slider_mass",
    "mass_per_length",
    "force",
    "force_slope",
    "gx",
    "gy",
    "friction",
)


def system(
    m: Mechanism, variant: frozenset[str], p: Params, th: ca.SX, w: dict[str, ca.SX]
) -> tuple[ca.SX, ca.SX, Layout]:
    """The equations A z = b of a variant at crank angle θ, for the load ``w`` (``LOAD``), and
    where each unknown of z lies (``Layout``)."""
    assert m.frame is not None and m.joints is not None
    fr = m.frame(variant)
    u, om = w["unit"], w["omega"]
    pins = _pins(m, p, th, u)
    tx, ty = fr.path(p)

    def d2(v: Any) -> Any:  # the second derivative in time at constant ω
        return om**2 * ca.jacobian(ca.jacobian(v, th), th)

    names = [b[0] for b in fr.bodies]
    layout = Layout(tuple(q[0] for q in fr.pins), tuple(q[0] for q in fr.slots))
    n = layout.size
    rows_of = {b: 3 * i for i, b in enumerate(names)}
    ram = 3 * len(names)  # the ram's rows: along its path, across it
    assert ram + 2 == n  # as many equations as unknowns
    a = ca.SX.zeros(n, n)
    b = ca.SX.zeros(n, 1)

    def push(body: str, col: int, fx: Any, fy: Any, x: Any, y: Any) -> None:
        """A force (fx, fy) per unit of unknown ``col`` on ``body``, at (x, y)."""
        if body == GROUND:
            return
        if body == RAM:
            a[ram, col] += fx * tx + fy * ty
            a[ram + 1, col] += -fx * ty + fy * tx
            return
        r = rows_of[body]
        a[r, col] += fx
        a[r + 1, col] += fy
        a[r + 2, col] += x * fy - y * fx

    a[2, 0] = 1.0  # the torque, on the crank
    for j, (pin, b1, b2) in enumerate(fr.pins):
        x, y = pins[pin]
        for k, (fx, fy) in enumerate(((1.0, 0.0), (0.0, 1.0))):
            push(b1, layout.pin(j) + k, fx, fy, x, y)
            push(b2, layout.pin(j) + k, -fx, -fy, x, y)
    for j, (pin, carrier, slotted, line) in enumerate(fr.slots):
        x, y = pins[pin]
        if line is None:  # across the ram's path: the block pushes along it
            nx, ny = tx, ty
        else:
            (ax, ay), (bx, by) = pins[line[0]], pins[line[1]]
            length = ca.sqrt((bx - ax) ** 2 + (by - ay) ** 2)
            nx, ny = -(by - ay) / length, (bx - ax) / length
        push(slotted, layout.slot(j), nx, ny, x, y)
        push(carrier, layout.slot(j), -nx, -ny, x, y)
    a[ram + 1, n - 1] = 1.0  # the guide's normal force
    a[ram, n - 1] = w["friction"]  # and its friction along the path

    # what the unknowns balance: each body's inertia (Σ m a, and the moment of m a and I α
    # about the crank pivot) less its weight, the ram's, less the force on the ram
    g = (w["gx"], w["gy"])
    for body, mass, (cx, cy), inertia, angle in _members(m, fr.bodies, pins, p, w):
        r = rows_of[body]
        fx, fy = mass * (d2(cx) - g[0]), mass * (d2(cy) - g[1])
        b[r] += fx
        b[r + 1] += fy
        b[r + 2] += cx * fy - cy * fx + inertia * d2(angle)
    s = u * m.position(p, th)
    weight = (w["slider_mass"] * g[0], w["slider_mass"] * g[1])
    b[ram] += w["slider_mass"] * d2(s) - w["force"] - w["force_slope"] * s
    b[ram] -= weight[0] * tx + weight[1] * ty
    b[ram + 1] -= -weight[0] * ty + weight[1] * tx
    return a, b, layout


def torque(
    m: Mechanism, variant: frozenset[str], p: Params, th: ca.SX, w: dict[str, ca.SX]
) -> ca.SX:
    """The crank torque at θ by the balance of power, where the guide does not rub (its
    ``friction`` is left out): the joints' forces do no work, so at constant ω
    T = Σ m (ω² c″ − g)·c′ + I ω² φ″ φ′ over the members (c: a member's middle, φ: its body's
    angle; ′: d/dθ) + (m_ram (ω² s″ − g·t) − force − force_slope s) s′. It is ``system``'s
    torque from the motion alone: a far shorter expression, which an interval enclosure
    bounds tightly (``synth.synthesis.torque``)."""
    assert m.frame is not None and m.joints is not None
    fr = m.frame(variant)
    u, om = w["unit"], w["omega"]
    tx, ty = fr.path(p)

    def d(v: Any) -> Any:
        return ca.jacobian(v, th)

    g = (w["gx"], w["gy"])
    out = ca.SX(0.0)
    for _, mass, (cx, cy), inertia, angle in _members(m, fr.bodies, _pins(m, p, th, u), p, w):
        (vx, vy), spin = (d(cx), d(cy)), d(angle)
        out += mass * ((om**2 * d(vx) - g[0]) * vx + (om**2 * d(vy) - g[1]) * vy)
        out += inertia * om**2 * d(spin) * spin
    s = u * m.position(p, th)
    v = d(s)
    along = w["slider_mass"] * (om**2 * d(v) - g[0] * tx - g[1] * ty)
    out += (along - w["force"] - w["force_slope"] * s) * v
    return out


def _pins(m: Mechanism, p: Params, th: ca.SX, unit: Any) -> dict[str, tuple[Any, Any]]:
    """The type's pins at θ, in metres."""
    assert m.joints is not None
    return {k: (unit * x, unit * y) for k, (x, y) in m.joints(p, th).items()}


def _members(
    m: Mechanism,
    bodies: tuple[tuple[str, ...], ...],
    pins: dict[str, tuple[Any, Any]],
    p: Params,
    w: dict[str, ca.SX],
) -> Iterator[tuple[str, Any, tuple[Any, Any], Any, Any]]:
    """Each drawn member of the moving ``bodies``, a uniform slender rod: its body's name, its
    mass, its middle, its moment of inertia about it, and its body's angle (its first
    member's direction)."""
    ends = {name: (a, b) for name, a, b in m.drawing}
    for body in bodies:
        (ax, ay), (bx, by) = (pins[q] for q in ends[body[0]])
        angle = ca.atan2(by - ay, bx - ax)
        for member in body:
            (ax, ay), (bx, by) = (pins[q] for q in ends[member])
            length = w["unit"] * p[member]
            mass = w["mass_per_length"] * length
            yield body[0], mass, ((ax + bx) / 2, (ay + by) / 2), mass * length**2 / 12, angle


@dataclass(frozen=True)
class Layout:
    """Where the unknowns lie in z: the torque first, then (Fx, Fy) of each pin joint (the
    force on its first body), each block's push, and the guide's normal force last."""

    pins: tuple[str, ...]
    slots: tuple[str, ...]

    @property
    def size(self) -> int:
        return 2 + 2 * len(self.pins) + len(self.slots)

    def pin(self, j: int) -> int:
        return 1 + 2 * j

    def slot(self, j: int) -> int:
        return 1 + 2 * len(self.pins) + j


def numbers(
    load: Load, metres: float, force: float = 0.0, slope: float = 0.0, friction: float = 0.0
) -> np.ndarray:
    """A load's numbers as a compiled model takes them after the type's parameters
    (``LOAD``): the lengths ``metres`` each, the force on the ram ``force`` +
    ``slope`` × s, the guide's friction per unit of its force ``friction``."""
    gx, gy = load.gravity
    w = {
        "unit": metres,
        "omega": load.omega,
        "slider_mass": load.slider_mass,
        "mass_per_length": load.link_mass_per_length,
        "force": force,
        "force_slope": slope,
        "gx": gx,
        "gy": gy,
        "friction": friction,
    }
    return np.array([w[k] for k in LOAD])
