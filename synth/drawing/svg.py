"""A drawing as SVG in true size: its width and height in millimetres, one of the design's
units drawn as long as it is (``length_unit``)."""

from __future__ import annotations

from collections.abc import Iterable
from xml.sax.saxutils import escape

from .layout import span
from .model import Drawing, sketch, slot, unit_mm

# each link's colour, in the order of the type's drawing (told apart in print too)
COLOURS = ("#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b", "#17becf")


def svg(d: Drawing, length_unit: str = "mm") -> str:
    """``d`` as an SVG document, true size for lengths in ``length_unit`` (mm, m or in)."""
    k = unit_mm(length_unit)
    sk = sketch(d)
    lines, starts, frame = sk.title(d, length_unit)
    x0, y0, x1, y1 = span([sk.extent(d), frame])
    pad = 0.05 * sk.size
    x0, y0, x1, y1 = x0 - pad, y0 - pad, x1 + pad, y1 + pad
    w, h = x1 - x0, y1 - y0

    def pt(p: tuple[float, float]) -> str:  # y up, as the design's frame has it
        return f"{p[0] - x0:.12g},{y1 - p[1]:.12g}"

    def line(a: tuple[float, float], b: tuple[float, float], cls: str, extra: str = "") -> str:
        (ax, ay), (bx, by) = pt(a).split(","), pt(b).split(",")
        return f'<line class="{cls}" x1="{ax}" y1="{ay}" x2="{bx}" y2="{by}"{extra}/>'

    def poly(points: Iterable[tuple[float, float]], cls: str, tag: str = "polygon") -> str:
        return f'<{tag} class="{cls}" points="{" ".join(pt(p) for p in points)}"/>'

    lw = sk.line_width
    out = [
        '<?xml version="1.0" encoding="UTF-8"?>',
        f'<svg xmlns="http://www.w3.org/2000/svg" class="drawing" width="{w * k:.6g}mm" '
        f'height="{h * k:.6g}mm" '
        f'viewBox="0 0 {w:.9g} {h:.9g}" data-type="{d.type}" '
        f'data-crank-angle-deg="{d.crank_angle_deg:.9g}" data-length-unit="{length_unit}">',
        f"<title>{escape(d.type)} at crank angle {d.crank_angle_deg:g}°</title>",
        # every rule under the root's class: the drawing set in a page styles nothing else
        "<style>"
        ".drawing :is(line,polyline,polygon){stroke-linecap:round;fill:none;stroke:#222;"
        f"stroke-width:{lw * 0.5:.6g}}}"
        f".drawing .link{{stroke-width:{lw * 1.6:.6g}}}"
        f".drawing .path{{stroke:#999;stroke-dasharray:{lw * 2:.6g} {lw * 2:.6g}}}"
        f".drawing .slot{{stroke:#777;stroke-width:{lw * 3.2:.6g};stroke-opacity:.35}}"
        f".drawing .block{{fill:#ddd}}.drawing .ground{{fill:#bbb}}"
        f".drawing .pin{{fill:#fff;stroke:#222;stroke-width:{lw * 0.5:.6g}}}"
        f".drawing text{{font-family:sans-serif;font-size:{sk.text_height:.6g}px;fill:#222}}"
        "</style>",
    ]
    for name, xy in (d.paths or {}).items():
        out.append(poly(map(tuple, xy), f"path path-{name}", "polyline"))
    out += [line(a, b, "guide") for a, b in sk.guide]
    out.append(poly(sk.block, "block"))
    out += [poly(t, "ground") for t in sk.ground]
    out += [line(a, b, "hatch") for a, b in sk.hatch]
    a, b = sk.dimension
    out.append(line(a, b, "dimension"))
    out += [line(end, pin, "extension") for end, pin in zip(sk.dimension, d.stroke, strict=True)]
    lx, ly = pt(sk.label_at).split(",")
    out.append(f'<text class="dimension" x="{lx}" y="{ly}" text-anchor="middle">{sk.label}</text>')
    out += [line(*slot(d.pins, names), "slot") for names in d.slots]
    out += [line(a, b, "slot yoke") for a, b in d.yokes]
    for i, link in enumerate(d.links):
        colour = COLOURS[i % len(COLOURS)]
        extra = f' style="stroke:{colour}" data-length="{link.length:.17g}"'
        out.append(line(d.pins[link.a], d.pins[link.b], f"link link-{link.name}", extra))
    for name, p in d.pins.items():
        cx, cy = pt(p).split(",")
        out.append(
            f'<circle class="pin" data-pin="{name}" cx="{cx}" cy="{cy}" r="{sk.pin_radius:.6g}"/>'
        )
        tx, ty = pt(sk.names[name]).split(",")
        out.append(f'<text class="pin-label" x="{tx}" y="{ty}">{escape(name)}</text>')
    for text, at in sk.dims:  # each link's length
        tx, ty = pt(at).split(",")
        out.append(
            f'<text class="link-dimension" x="{tx}" y="{ty}" text-anchor="middle">'
            f"{escape(text)}</text>"
        )
    fx0, fy0, fx1, fy1 = frame
    out.append(poly([(fx0, fy0), (fx1, fy0), (fx1, fy1), (fx0, fy1)], "title-block"))
    for text, at in zip(lines, starts, strict=True):
        tx, ty = pt(at).split(",")
        out.append(f'<text class="title" x="{tx}" y="{ty}">{escape(text)}</text>')
    out.append("</svg>")
    return "\n".join(out)
