"""One drawing of a design at a crank angle, for every face that shows one (``drawing``), and
its symbols as plain shapes (``sketch``).

A ``Drawing`` holds what an engineering sketch of a linkage shows, in the design's lengths:
each link as a centre line between its pins (``drawing``'s members, their lengths the
design's), every pin named, the pivots fixed to the frame, the ram's guide along its path and
its stroke between the dead centres, and, when asked, each moving pin's path over a turn.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from ..analysis.kinematics import analyze, joints
from ..errors import InvalidParameters
from ..load import LENGTH_UNITS
from ..mechanisms import Mechanism, get
from ..mechanisms.registry import GROUND, RAM
from ..version import __version__
from .layout import Box, Layout, Point, span, text_box, title, title_block

PATH_SAMPLES = 181  # angles a pin's path is drawn through (2° apart)
GUIDE_OVERRUN = 0.15  # the guide runs past each end of the stroke by this share of it
YOKE_OVERRUN = 0.1  # a slot the ram carries runs past its pin's travel by this share of it


Segment = tuple[tuple[float, float], tuple[float, float]]  # two points (x, y)


@dataclass(frozen=True)
class Link:
    """A straight member between two pins: its name (the parameter it is as long as)."""

    name: str
    a: str
    b: str
    length: float


@dataclass(frozen=True)
class Drawing:
    """A design drawn at ``crank_angle_deg``, its coordinates in the design's unit: the frame
    of the type's equations (``synth.joints``), the crank pivot at the origin.

    ``pins``: every pin's (x, y); ``links``: the members (zero-length ones left out);
    ``slots``: each slot a block slides in, as (the line's first pin, the block's pin, the
    line's far pin), drawn along its line to the farther of the other two (``slot``);
    ``ground``: the pins fixed to the frame; ``ram``: the ram's pin, on its ``path`` (a unit
    vector); ``stroke``: the ram pin at its two dead centres; ``guide``: the guide's ends, the
    stroke and ``GUIDE_OVERRUN`` of it each side; ``yokes``: each slot the ram carries
    across its path (a slot drive's, a Scotch yoke's), as long as its pin's travel across
    the path over a turn and ``YOKE_OVERRUN`` of it each side (it moves with the ram);
    ``facts``: what the design achieves (time ratio, stroke, least transmission angle);
    ``paths``: each moving pin's path over a turn (asked only)."""

    type: str
    params: dict[str, float]
    crank_angle_deg: float
    pins: dict[str, tuple[float, float]]
    links: tuple[Link, ...]
    ground: tuple[str, ...]
    slots: tuple[tuple[str, str, str], ...]
    ram: str
    path: tuple[float, float]
    stroke: Segment
    guide: Segment
    facts: tuple[float, float, float]
    yokes: tuple[Segment, ...]
    paths: dict[str, np.ndarray] | None = None

    def yokes_at(self, pins: Mapping[str, tuple[float, float]]) -> list[Segment]:
        """The ``yokes`` where the ram's pin is at ``pins``' (they move with the ram)."""
        dx, dy = np.subtract(pins[self.ram], self.pins[self.ram])
        return [((a[0] + dx, a[1] + dy), (b[0] + dx, b[1] + dy)) for a, b in self.yokes]

    def bounds(self) -> tuple[float, float, float, float]:
        """(x min, y min, x max, y max) of everything drawn."""
        pts = [*self.pins.values(), *self.guide, *self.stroke, *(p for y in self.yokes for p in y)]
        for xy in (self.paths or {}).values():
            pts += [tuple(xy.min(axis=0)), tuple(xy.max(axis=0))]
        a = np.array(pts, dtype=float)
        x0, y0 = a.min(axis=0)
        x1, y1 = a.max(axis=0)
        return float(x0), float(y0), float(x1), float(y1)


def drawing(
    mechanism: str,
    params: Mapping[str, float],
    crank_angle_deg: float | None = None,
    paths: bool = False,
) -> Drawing:
    """The drawing of a design at a crank angle (degrees; None: a third of the way through the
    working stroke, where the mechanism stands open: half way, a crank shaper's links lie on
    one line); with ``paths``, each moving pin's path over a turn. Raises what
    ``synth.analyze`` raises for a design that cannot run."""
    check_angle(crank_angle_deg)
    m = drawn(mechanism)
    a = analyze(mechanism, params)  # checks the design, and finds its dead centres
    if crank_angle_deg is None:
        e = a.extremes
        start = e.max if a.working_stroke.direction < 0 else e.min
        crank_angle_deg = (start.crank_angle_deg + a.working_stroke.crank_angle_deg / 3) % 360
    p = m.complete(a.params)
    assert m.frame is not None  # ``drawn`` saw it
    frame = m.frame(m.variant(p))
    angles = [crank_angle_deg, a.extremes.min.crank_angle_deg, a.extremes.max.crank_angle_deg]
    at = joints(mechanism, a.params, angles)
    pins = {k: (float(v[0, 0]), float(v[0, 1])) for k, v in at.items()}
    ram = list(at)[-1]  # each type names its ram's pin last
    (x0, y0), (x1, y1) = ends = (
        (float(at[ram][1, 0]), float(at[ram][1, 1])),
        (float(at[ram][2, 0]), float(at[ram][2, 1])),
    )
    tx, ty = (float(c) for c in frame.path(p))
    run = np.hypot(x1 - x0, y1 - y0) * GUIDE_OVERRUN
    sign = 1.0 if (x1 - x0) * tx + (y1 - y0) * ty > 0 else -1.0
    guide = (
        (x0 - sign * run * tx, y0 - sign * run * ty),
        (x1 + sign * run * tx, y1 + sign * run * ty),
    )
    links = tuple(
        Link(name, u, v, float(a.params[name]))
        for name, u, v in m.drawing
        if a.params.get(name, 0.0) > 0
    )
    ground = tuple(pin for pin, b1, b2 in frame.pins if GROUND in (b1, b2))
    slots = tuple((line[0], block, line[1]) for block, _, _, line in frame.slots if line)
    across = [block for block, _, slotted, line in frame.slots if slotted == RAM and line is None]
    turn = {}
    if paths or across:
        turn = joints(mechanism, a.params, np.linspace(0.0, 360.0, PATH_SAMPLES).tolist())
    yokes = []
    for pin in across:  # its travel across the path, from the ram's pin
        off = (turn[pin] - turn[ram]) @ np.array([-ty, tx])
        lo, hi = float(off.min()), float(off.max())
        lo, hi = lo - YOKE_OVERRUN * (hi - lo), hi + YOKE_OVERRUN * (hi - lo)
        (rx, ry) = pins[ram]
        yokes.append(((rx - lo * ty, ry + lo * tx), (rx - hi * ty, ry + hi * tx)))
    traced = {k: v for k, v in turn.items() if np.ptp(v, axis=0).max() > 0} if paths else None
    facts = (a.time_ratio, a.stroke, a.transmission.min_deg)
    return Drawing(
        mechanism,
        dict(a.params),
        float(crank_angle_deg),
        pins,
        links,
        ground,
        slots,
        ram,
        (tx, ty),
        ends,
        guide,
        facts,
        tuple(yokes),
        traced,
    )


@dataclass(frozen=True)
class Sketch:
    """A drawing's symbols as plain shapes, which every renderer draws as they are: sizes in
    the design's unit, in proportion to the drawing's extent (``size``).

    ``guide``: the guide's two rails, either side of the path; ``block``: the ram's block, a
    polygon around its pin; ``ground``: a triangle under each fixed pivot, ``hatch`` the
    strokes under it; ``dimension``: the stroke's dimension line beside the guide, its
    ``label`` and where the label's middle goes (``label_at``); ``names``: where each pin's
    name starts; ``dims``: each link's length and where its middle goes (all placed by
    ``layout``: no two meet)."""

    size: float
    pin_radius: float
    text_height: float
    line_width: float
    guide: tuple[Segment, Segment]
    block: tuple[tuple[float, float], ...]
    ground: tuple[tuple[tuple[float, float], ...], ...]
    hatch: tuple[Segment, ...]
    dimension: Segment
    label: str
    label_at: tuple[float, float]
    names: dict[str, tuple[float, float]]
    dims: tuple[tuple[str, tuple[float, float]], ...]

    def extent(self, d: Drawing) -> Box:
        """(x min, y min, x max, y max) of ``d`` and every word of this sketch."""
        h = self.text_height
        boxes = [d.bounds(), text_box(self.label, self.label_at, h, middle=True)]
        boxes += [text_box(n, at, h) for n, at in self.names.items()]
        boxes += [text_box(t, at, h, middle=True) for t, at in self.dims]
        return span(boxes)

    def title(self, d: Drawing, length_unit: str) -> tuple[list[str], list[Point], Box]:
        """The title block below the drawing: its lines, where each starts, its frame."""
        m = get(d.type)
        named = {f"{m.parameter(k).symbol} {k}": v for k, v in d.params.items()}
        lines = title(m.title, d.type, d.facts, named, length_unit, d.crank_angle_deg, __version__)
        x0, y0, _, _ = self.extent(d)
        return lines, *title_block(lines, x0, y0, self.text_height)


def sketch(d: Drawing) -> Sketch:
    """The symbols of ``d`` (``Sketch``)."""
    x0, y0, x1, y1 = d.bounds()
    size = max(x1 - x0, y1 - y0)
    h = 0.035 * size  # the block's half height across the path
    tx, ty = d.path
    nx, ny = -ty, tx  # the path's normal
    (ax, ay), (bx, by) = d.guide
    rails = tuple(
        ((ax + k * h * nx, ay + k * h * ny), (bx + k * h * nx, by + k * h * ny))
        for k in (-1.0, 1.0)
    )
    rx, ry = d.pins[d.ram]
    corners = ((-1.6, -0.8), (1.6, -0.8), (1.6, 0.8), (-1.6, 0.8))  # along, across, × h
    block = tuple((rx + h * (u * tx + v * nx), ry + h * (u * ty + v * ny)) for u, v in corners)
    tri, hatch, symbols = [], [], []
    for pin in d.ground:
        px, py = d.pins[pin]
        w = 0.9 * h
        base = py - 1.6 * w
        tri.append(((px, py), (px - w, base), (px + w, base)))
        symbols.append((px - 1.6 * w, base - 0.6 * w, px + 1.4 * w, py))  # with its hatch
        hatch.append(((px - 1.4 * w, base), (px + 1.4 * w, base)))
        hatch += [
            ((px + k * w * 0.7, base), (px + k * w * 0.7 - 0.5 * w, base - 0.6 * w))
            for k in (-1.5, -0.5, 0.5, 1.5)
        ]
    (sx, sy), (ex, ey) = d.stroke
    off = 3.0 * h
    dim = ((sx - off * nx, sy - off * ny), (ex - off * nx, ey - off * ny))
    label = f"stroke {np.hypot(ex - sx, ey - sy):.6g}"
    r, th = 0.012 * size, 0.03 * size
    m = get(d.type)
    lay = Layout(d.pins, r, th)
    lay.boxes += symbols  # no word on a fixed pivot's symbol
    label_at = lay.along(*dim, (-nx, -ny), label, (1,))
    names = {pin: lay.name(pin) for pin in d.pins}
    dims = []
    for link in d.links:  # beside its middle, either side
        (ax, ay), (bx, by) = d.pins[link.a], d.pins[link.b]
        n = math.hypot(bx - ax, by - ay) or 1.0
        out = (-(by - ay) / n, (bx - ax) / n)
        # its symbol and length ("r2 120"): the title block says whose symbol it is
        text = f"{m.parameter(link.name).symbol} {link.length:.6g}"
        dims.append((text, lay.along((ax, ay), (bx, by), out, text, (1, -1))))
    return Sketch(
        size,
        r,
        th,
        0.006 * size,
        (rails[0], rails[1]),
        block,
        tuple(tri),
        tuple(hatch),
        dim,
        label,
        label_at,
        names,
        tuple(dims),
    )


def slot(pins: Mapping[str, tuple[float, float]], names: tuple[str, str, str]) -> Segment:
    """A slot's centre line (``Drawing.slots``) at pins: from its line's first pin to the
    farther of its block and its line's far pin."""
    start, block, far = (pins[n] for n in names)
    return start, max((block, far), key=lambda q: math.dist(start, q))


def unit_mm(length_unit: str) -> float:
    """Millimetres per ``length_unit`` (one of ``synth.load.LENGTH_UNITS``)."""
    if length_unit not in LENGTH_UNITS:
        msg = f"length_unit must be one of {', '.join(LENGTH_UNITS)}, got {length_unit!r}"
        raise InvalidParameters(msg, ("length_unit",))
    return LENGTH_UNITS[length_unit] * 1e3


def drawn(mechanism: str) -> Mechanism:
    """The type, if it can be drawn (its pins and its frame, ``Mechanism.joints`` and
    ``.frame``); else InvalidParameters (a registered type may have neither)."""
    m = get(mechanism)
    if m.joints is None or m.frame is None:
        raise InvalidParameters(f"{mechanism} has no drawing yet", ("mechanism",))
    return m


def check_angle(crank_angle_deg: float | None) -> None:
    if crank_angle_deg is not None and not np.isfinite(crank_angle_deg):
        msg = f"crank_angle_deg must be finite, got {crank_angle_deg!r}"
        raise InvalidParameters(msg, ("crank_angle_deg",))
