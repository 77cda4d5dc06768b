"""A design's drawing in a file format (``synth.export``, ``POST /v1/export``)."""

from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import asdict, dataclass
from typing import Annotated, Any

from ..load import LENGTH_UNITS
from ..requests import Help, OneOf, check, keyword
from . import FORMATS
from .gif import gif
from .model import drawing, drawn, sketch
from .svg import svg


@dataclass(frozen=True)
class ExportRequest:
    """``export``'s arguments (``run``), checked when built."""

    mechanism: Annotated[str, Help("the design's type")]
    params: Annotated[Mapping[str, float], Help("its parameters, by name, in length_unit")]
    format: Annotated[
        str,
        OneOf(FORMATS),
        Help(
            "svg: true size; dxf: each link on its own layer; json: the drawing and its "
            "symbols' shapes, for a page that draws them; gif: a turn of the crank from "
            "crank_angle_deg, animated"
        ),
    ] = "svg"
    crank_angle_deg: Annotated[
        float | None,
        Help(
            "where the crank is drawn, degrees; omitted: a third of the way through the "
            "working stroke, where the mechanism stands open",
            "crank-angle",
        ),
    ] = None
    length_unit: Annotated[
        str,
        OneOf(tuple(LENGTH_UNITS)),
        Help("the unit of the design's lengths: the SVG's size, the DXF's units"),
    ] = "mm"
    paths: Annotated[bool, Help("each moving pin's path over a turn")] = False

    def __post_init__(self) -> None:
        check(self)
        m = drawn(self.mechanism)
        for k in self.params:
            m.parameter(k)


def run(r: ExportRequest) -> bytes:
    """The design drawn at ``crank_angle_deg`` (None: a third into the working stroke):
    ``format`` ``svg`` (true size, the lengths in ``length_unit``), ``dxf`` (each link on its
    own layer, the unit set), ``json`` (the ``Drawing`` and its ``Sketch``, for a page that
    draws them) or ``gif`` (a turn of the crank from that angle, animated); with ``paths``,
    each moving pin's path over a turn.

    >>> doc = export("crank_shaper", {"crank": 120, "pivot_distance": 240, "lever": 450})
    >>> doc.startswith(b"<?xml") and b'width="' in doc
    True
    """
    d = drawing(r.mechanism, r.params, r.crank_angle_deg, r.paths)
    if r.format == "json":  # the drawing and its symbols, for a page that draws them itself
        return json.dumps(
            {"drawing": asdict(d), "sketch": asdict(sketch(d))}, default=_listed
        ).encode()
    if r.format == "svg":
        return svg(d, r.length_unit).encode()
    if r.format == "gif":  # a turn of the crank from that angle
        return gif(d)
    from .dxf import dxf  # ezdxf: ~0.2 s to import, so on the first DXF

    return dxf(d, r.length_unit)


export = keyword(ExportRequest, run, "export")


def _listed(x: Any) -> Any:
    return x.tolist()
