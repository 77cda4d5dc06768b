"""A line chart as inline SVG, for a page that must stand alone (the design report): axes with
ticks at round numbers, axis titles with their units, and the legend above the plotting area,
where it covers no point."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from xml.sax.saxutils import escape

import numpy as np

from .layout import CHAR

WIDTH, HEIGHT = 640.0, 250.0
LEFT, RIGHT, TOP, BOTTOM = 78.0, 16.0, 40.0, 44.0  # the margins: ticks, titles, the legend
FONT = 12.0
PALETTE = ("#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b", "#17becf")


@dataclass(frozen=True)
class Series:
    label: str
    y: np.ndarray
    dashed: bool = False


def ticks(lo: float, hi: float, most: int = 6) -> list[float]:
    """Round numbers 1, 2 or 5 × 10ⁿ apart, at least (hi − lo) / ``most``, from at or below
    ``lo`` to at or above ``hi``.

    >>> ticks(-14.3, 268.6)
    [-50.0, 0.0, 50.0, 100.0, 150.0, 200.0, 250.0, 300.0]
    """
    if not hi > lo:
        lo, hi = lo - max(abs(lo), 1.0) * 0.5, hi + max(abs(hi), 1.0) * 0.5
    raw = (hi - lo) / most
    base = 10.0 ** math.floor(math.log10(raw))
    step = next(k * base for k in (1, 2, 5, 10) if k * base >= raw * (1 - 1e-12))
    first, last = math.floor(lo / step + 1e-9), math.ceil(hi / step - 1e-9)
    out = [float(f"{k * step:.12g}") for k in range(first, last + 1)]  # 12 digits, any scale
    return out if out[-1] > out[0] else [lo, hi]  # a span below the digits: its ends


def label(x: float) -> str:
    """A tick's text: as few digits as tell the ticks apart."""
    return f"{x:.6g}" if abs(x) < 1e6 else f"{x:.3g}"


def chart(
    x: np.ndarray,
    series: Sequence[Series],
    x_title: str,
    y_title: str,
    x_ticks: Sequence[float] | None = None,
) -> str:
    """The series against ``x`` as an SVG element, ``x_title`` and ``y_title`` under and
    beside the axes (each with its unit)."""
    ys = np.concatenate([s.y for s in series]) if series else np.zeros(1)
    ys = ys[np.isfinite(ys)] if np.isfinite(ys).any() else np.zeros(1)
    xt = list(x_ticks) if x_ticks is not None else ticks(float(x.min()), float(x.max()))
    yt = ticks(float(ys.min()), float(ys.max()))
    x0, x1, y0, y1 = xt[0], xt[-1], yt[0], yt[-1]
    pw, ph = WIDTH - LEFT - RIGHT, HEIGHT - TOP - BOTTOM

    def px(v: float) -> float:
        return LEFT + (v - x0) / (x1 - x0) * pw

    def py(v: float) -> float:
        return TOP + ph - (v - y0) / (y1 - y0) * ph

    out = [
        f'<svg class="chart" xmlns="http://www.w3.org/2000/svg" viewBox="0 0 {WIDTH:g} '
        f'{HEIGHT:g}" width="{WIDTH:g}" height="{HEIGHT:g}" font-family="sans-serif" '
        f'font-size="{FONT:g}">',
        _el("rect", x=LEFT, y=TOP, width=pw, height=ph, fill="none", stroke="#444"),
    ]
    for v in xt:
        out.append(_el("line", x1=px(v), y1=TOP, x2=px(v), y2=TOP + ph, stroke="#ddd"))
        out.append(_el("text", label(v), x=px(v), y=TOP + ph + 16, text_anchor="middle"))
    for v in yt:
        out.append(_el("line", x1=LEFT, y1=py(v), x2=LEFT + pw, y2=py(v), stroke="#ddd"))
        out.append(_el("text", label(v), x=LEFT - 6, y=py(v) + 4, text_anchor="end"))
    out.append(_el("text", x_title, x=LEFT + pw / 2, y=HEIGHT - 8, text_anchor="middle"))
    cy = TOP + ph / 2
    turn = f"rotate(-90 14 {cy:g})"
    out.append(_el("text", y_title, x=14, y=cy, text_anchor="middle", transform=turn))
    at = LEFT
    for i, s in enumerate(series):
        style = {
            "stroke": PALETTE[i % len(PALETTE)],
            "stroke_dasharray": "6 4" if s.dashed else None,
        }
        ok = np.isfinite(s.y)
        points = " ".join(f"{px(a):.2f},{py(b):.2f}" for a, b in zip(x[ok], s.y[ok], strict=True))
        out.append(_el("polyline", fill="none", stroke_width=1.6, points=points, **style))
        out.append(
            _el("line", x1=at, y1=TOP - 14, x2=at + 18, y2=TOP - 14, stroke_width=2, **style)
        )
        out.append(_el("text", s.label, x=at + 22, y=TOP - 10))
        at += 22 + CHAR * FONT * len(s.label) + 16
    out.append("</svg>")
    return "\n".join(out)


def _el(tag: str, text: str | None = None, **attrs: float | str | None) -> str:
    """One SVG element: ``attrs`` with ``_`` for ``-``, numbers to two decimals, None left out."""
    at = " ".join(
        f'{k.replace("_", "-")}="{f"{v:.2f}" if isinstance(v, float) else escape(str(v))}"'
        for k, v in attrs.items()
        if v is not None
    )
    return f"<{tag} {at}/>" if text is None else f"<{tag} {at}>{escape(text)}</{tag}>"
