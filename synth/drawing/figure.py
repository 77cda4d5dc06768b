"""A drawing as a matplotlib figure, for notebooks (``synth.draw``): the same shapes as the
SVG and DXF exports, equal axes in the design's unit."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from .model import Drawing, drawing, sketch, slot
from .svg import COLOURS


def draw(
    mechanism: str,
    params: Mapping[str, float],
    crank_angle_deg: float | None = None,
    paths: bool = True,
    ax: Any = None,
) -> Any:
    """The design at ``crank_angle_deg`` drawn on ``ax`` (a new figure's by default), each pin's
    path over a turn with ``paths``: the figure (matplotlib, imported here: notebooks have
    it, the service does not need it)."""
    import matplotlib.pyplot as plt

    if ax is None:
        _, ax = plt.subplots(figsize=(6, 4.5))
    _render(drawing(mechanism, params, crank_angle_deg, paths), ax)
    return ax.figure


def _render(d: Drawing, ax: Any) -> None:
    """``d`` on the matplotlib axes ``ax``."""
    from matplotlib.patches import Circle, Polygon

    sk = sketch(d)
    lw = 1.0
    for xy in (d.paths or {}).values():
        ax.plot(xy[:, 0], xy[:, 1], color="#999", lw=0.7 * lw, ls="--", zorder=1)
    for a, b in (*sk.guide, *sk.hatch):
        ax.plot(*zip(a, b, strict=True), color="#222", lw=lw, zorder=2)
    ax.add_patch(Polygon(sk.block, closed=True, fc="#ddd", ec="#222", lw=lw, zorder=3))
    for tri in sk.ground:
        ax.add_patch(Polygon(tri, closed=True, fc="#bbb", ec="#222", lw=lw, zorder=3))
    (a, b), (sa, sb) = sk.dimension, d.stroke
    ax.annotate("", xy=b, xytext=a, arrowprops={"arrowstyle": "<->", "lw": 0.8 * lw})
    for end, pin in ((a, sa), (b, sb)):
        ax.plot(*zip(end, pin, strict=True), color="#222", lw=0.5 * lw)
    ax.text(*sk.label_at, sk.label, ha="center", va="center", fontsize=8)
    for a, b in (*(slot(d.pins, names) for names in d.slots), *d.yokes):
        ax.plot(*zip(a, b, strict=True), color="#777", lw=7 * lw, alpha=0.35, zorder=3.5)
    for i, link in enumerate(d.links):
        (ax_, ay), (bx, by) = d.pins[link.a], d.pins[link.b]
        label = f"{link.name} {link.length:.6g}"
        ax.plot(
            [ax_, bx],
            [ay, by],
            color=COLOURS[i % len(COLOURS)],
            lw=3 * lw,
            solid_capstyle="round",
            zorder=4,
            label=label,
        )
    for name, (x, y) in d.pins.items():
        ax.add_patch(Circle((x, y), sk.pin_radius, fc="white", ec="#222", lw=lw, zorder=5))
        ax.annotate(name, (x, y), xytext=(5, 5), textcoords="offset points", fontsize=8)
    ax.set_aspect("equal")
    ax.set_title(f"{d.type} at crank angle {d.crank_angle_deg:g}°", fontsize=10)
    ax.legend(fontsize=7, loc="best", frameon=False)
    ax.grid(True, lw=0.3, alpha=0.5)
