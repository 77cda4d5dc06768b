"""A drawing as DXF, for CAD (ezdxf): each link a centre line on its own layer (named as the
link, as long as the design says), the pins as circles, the fixed pivots, the ram's guide and
block, the stroke and each link as a dimension, the pins' paths when asked, and a title block
(the type, what the design achieves, its lengths, the unit and scale, the date, the project
and its version) below the drawing; the drawing's unit set."""

from __future__ import annotations

import io

from ezdxf import units
from ezdxf.document import Drawing as Document
from ezdxf.filemanagement import new
from ezdxf.layouts.layout import Modelspace

from .model import Drawing, Sketch, sketch, slot, unit_mm

UNITS = {"mm": units.MM, "m": units.M, "in": units.IN}
# the symbols' layers (none a parameter's name: layer names ignore case) and their colours
# (AutoCAD's colour index); the links' take 1, 2, 3, …
LAYERS = {"PINS": 7, "PIVOTS": 8, "SLOTS": 8, "GUIDE": 8, "RAM": 8, "STROKE": 7, "PATHS": 9}
LAYERS |= {"DIMENSIONS": 7, "TITLE": 7}


def dxf(d: Drawing, length_unit: str = "mm") -> bytes:
    """``d`` as a DXF document (R2010), its lengths in ``length_unit`` (mm, m or in)."""
    unit_mm(length_unit)  # checks the unit
    doc: Document = new("R2010", setup=True)
    doc.units = UNITS[length_unit]
    msp = doc.modelspace()
    sk = sketch(d)
    for name, colour in LAYERS.items():
        doc.layers.add(name, color=colour)
    for i, link in enumerate(d.links):
        doc.layers.add(link.name, color=i % 6 + 1)
        msp.add_line(d.pins[link.a], d.pins[link.b], dxfattribs={"layer": link.name})
    for a, b in (*(slot(d.pins, names) for names in d.slots), *d.yokes):
        msp.add_line(a, b, dxfattribs={"layer": "SLOTS"})
    for name, p in d.pins.items():
        msp.add_circle(p, sk.pin_radius, dxfattribs={"layer": "PINS"})
        label = msp.add_text(name, height=sk.text_height, dxfattribs={"layer": "PINS"})
        label.set_placement(sk.names[name])
    for tri in sk.ground:
        msp.add_lwpolyline(tri, close=True, dxfattribs={"layer": "PIVOTS"})
    for a, b in sk.hatch:
        msp.add_line(a, b, dxfattribs={"layer": "PIVOTS"})
    for a, b in sk.guide:
        msp.add_line(a, b, dxfattribs={"layer": "GUIDE"})
    msp.add_lwpolyline(sk.block, close=True, dxfattribs={"layer": "RAM"})
    (sx, sy), (ex, ey) = d.stroke
    (dx, dy), _ = sk.dimension
    run = ((ex - sx) ** 2 + (ey - sy) ** 2) ** 0.5
    offset = ((dx - sx) * (sy - ey) + (dy - sy) * (ex - sx)) / run  # to the left of the run
    # the text a CAD program shows: the length itself (dimlfac 1: the EZDXF style scales by
    # 100), to 6 decimals without trailing zeros (dimzin 8)
    size = {
        "dimtxt": sk.text_height,
        "dimasz": sk.text_height,
        "dimlfac": 1.0,
        "dimdec": 6,
        "dimzin": 8,
    }
    dim = msp.add_aligned_dim(
        p1=d.stroke[0],
        p2=d.stroke[1],
        distance=offset,
        dxfattribs={"layer": "STROKE"},
        override=size,
    )
    dim.render()
    on = {"layer": "DIMENSIONS"}
    for link in d.links:  # beside each link, its length
        a, b, away = d.pins[link.a], d.pins[link.b], 2 * sk.text_height
        msp.add_aligned_dim(p1=a, p2=b, distance=away, dxfattribs=on, override=size).render()
    _title(msp, d, sk, length_unit)
    for xy in (d.paths or {}).values():
        msp.add_lwpolyline([tuple(p) for p in xy], dxfattribs={"layer": "PATHS"})
    out = io.StringIO()
    doc.write(out)
    return out.getvalue().encode()


def _title(msp: Modelspace, d: Drawing, sk: Sketch, length_unit: str) -> None:
    """The title block, below the drawing: a framed column of lines (``Sketch.title``)."""
    lines, starts, (x0, y0, x1, y1) = sk.title(d, length_unit)
    for text, at in zip(lines, starts, strict=True):
        label = msp.add_text(text, height=sk.text_height, dxfattribs={"layer": "TITLE"})
        label.set_placement(at)
    corners = [(x0, y1), (x1, y1), (x1, y0), (x0, y0)]
    msp.add_lwpolyline(corners, close=True, dxfattribs={"layer": "TITLE"})
