"""Where a drawing's words go: the stroke's label, each pin's name, each link's length and the
title block, placed so that no two meet, none lies on a pin or a fixed pivot's symbol, and the
sheet holds them all. A
text's box is estimated generously (``text_box``), as a browser or a CAD program would set it
in a sans-serif face; the places tried are few and fixed, so the same drawing gets the same
places."""

from __future__ import annotations

import datetime
from collections.abc import Mapping, Sequence

Point = tuple[float, float]
Box = tuple[float, float, float, float]  # x min, y min, x max, y max

CHAR = 0.8  # a character's width, of the text's height (sans-serif capitals, generously)
LINE = 1.6  # the title block's line spacing, of the text's height


def text_box(text: str, at: Point, height: float, middle: bool = False) -> Box:
    """The box a line of text takes from ``at`` on its baseline, where it starts or
    (``middle``) its middle."""
    w = CHAR * height * len(text)
    x = at[0] - w / 2 if middle else at[0]
    return x, at[1] - 0.3 * height, x + w, at[1] + 1.0 * height


class Layout:
    """The words placed so far (their boxes) among the drawing's pins (radius ``r``), text
    ``h`` high."""

    def __init__(self, pins: Mapping[str, Point], r: float, h: float) -> None:
        self.pins, self.r, self.h = pins, r, h
        self.boxes: list[Box] = []

    def free(self, box: Box, own: str | None = None) -> bool:
        """Whether ``box`` meets no word placed and no pin but ``own``."""
        if any(
            box[0] < b[2] and b[0] < box[2] and box[1] < b[3] and b[1] < box[3] for b in self.boxes
        ):
            return False
        r = self.r
        return all(
            not (box[0] - r < x < box[2] + r and box[1] - r < y < box[3] + r)
            for name, (x, y) in self.pins.items()
            if name != own
        )

    def put(
        self, text: str, spots: Sequence[Point], middle: bool = False, own: str | None = None
    ) -> Point:
        """The first of ``spots`` where ``text`` is free (else the first), taken."""
        at = next((s for s in spots if self.free(text_box(text, s, self.h, middle), own)), spots[0])
        self.boxes.append(text_box(text, at, self.h, middle))
        return at

    def along(self, a: Point, b: Point, out: Point, text: str, sides: Sequence[float]) -> Point:
        """``text``'s middle (on its baseline) beside the segment ab, clear of it, on the side
        ``out`` (a unit vector) or its opposite (``sides``: 1, -1): at its middle first,
        then further along, then further out."""
        h = self.h
        x0, y0, x1, y1 = text_box(text, (0.0, 0.0), h, middle=True)  # about its baseline's middle
        rise = (y0 + y1) / 2  # the box's centre above the baseline
        clear = 0.3 * h + (x1 - x0) / 2 * abs(out[0]) + (y1 - y0) / 2 * abs(out[1])  # its reach
        spots = [
            (
                a[0] + t * (b[0] - a[0]) + side * (clear + 1.2 * h * i) * out[0],
                a[1] + t * (b[1] - a[1]) + side * (clear + 1.2 * h * i) * out[1] - rise,
            )
            for i in range(12)
            for side in sides
            for t in (0.5, 0.35, 0.65, 0.2, 0.8)
        ]
        return self.put(text, spots, middle=True)

    def name(self, pin: str) -> Point:
        """Where a pin's name starts: beside it, diagonally first, further out if need be."""
        (x, y), r, h = self.pins[pin], self.r, self.h
        w = CHAR * h * len(pin)
        spots = [
            (
                x + ux * k * r - (w if ux < 0 else w / 2 if ux == 0 else 0.0),
                y + uy * k * r - (1.0 * h if uy < 0 else 0.35 * h if uy == 0 else -0.3 * h),
            )
            for k in (1.5, 3.0, 5.0)
            for ux, uy in ((1, 1), (-1, 1), (1, -1), (-1, -1), (1, 0), (-1, 0), (0, 1), (0, -1))
        ]
        return self.put(pin, spots, own=pin)


def title(
    title: str,
    mtype: str,
    facts: tuple[float, float, float],
    params: Mapping[str, float],
    unit: str,
    crank_angle_deg: float,
    version: str,
) -> list[str]:
    """The title block's lines: the type, what the design achieves (``facts``: time ratio,
    stroke, least transmission angle), its lengths (``params``, each named as the drawing
    names it), the unit and scale, the crank's angle and the date, the project and its
    version."""
    ratio, stroke, mu = facts
    lengths = [f"{k} {v:.9g}" for k, v in params.items()]
    rows = [", ".join(lengths[i : i + 2]) for i in range(0, len(lengths), 2)]  # two a line
    return [
        f"{title} ({mtype})",
        f"time ratio {ratio:.9g}, stroke {stroke:.9g} {unit}",
        f"minimum transmission angle {mu:.4f} deg",
        *rows,
        f"lengths in {unit}, scale 1:1, crank at {crank_angle_deg:g} deg",
        f"{datetime.datetime.now(datetime.UTC).date().isoformat()}, quickreturn-synth {version}",
    ]


def title_block(lines: Sequence[str], x0: float, y0: float, h: float) -> tuple[list[Point], Box]:
    """Each line's start and the block's frame, below ``y0`` from ``x0``."""
    top = y0 - 2.5 * h
    starts = [(x0 + h, top - (i + 1) * LINE * h) for i in range(len(lines))]
    width = max(len(t) for t in lines) * CHAR * h + 2 * h
    bottom = top - (len(lines) + 0.8) * LINE * h
    return starts, (x0, bottom, x0 + width, top)


def span(boxes: Sequence[Box]) -> Box:
    """The box that holds ``boxes``."""
    return (
        min(b[0] for b in boxes),
        min(b[1] for b in boxes),
        max(b[2] for b in boxes),
        max(b[3] for b in boxes),
    )
