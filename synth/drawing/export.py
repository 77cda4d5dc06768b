"""A design's drawing in a file format (``synth.export``, ``POST /v1/export``)."""

from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import asdict
from typing import Any

from ..errors import InvalidParameters
from . import FORMATS
from .gif import gif
from .model import check_angle, drawing, drawn, sketch, unit_mm
from .svg import svg


def export(
    mechanism: str,
    params: Mapping[str, float],
    format: str = "svg",
    crank_angle_deg: float | None = None,
    length_unit: str = "mm",
    paths: bool = False,
) -> bytes:
    """The design drawn at ``crank_angle_deg`` (None: a third into the working stroke):
    ``format`` ``svg`` (true size, the lengths in ``length_unit``), ``dxf`` (each link on its
    own layer, the unit set), ``json`` (the ``Drawing`` and its ``Sketch``, for a page that
    draws them) or ``gif`` (a turn of the crank from that angle, animated); with ``paths``,
    each moving pin's path over a turn.

    >>> doc = export("crank_shaper", {"crank": 120, "pivot_distance": 240, "lever": 450})
    >>> doc.startswith(b"<?xml") and b'width="' in doc
    True
    """
    check(mechanism, params, format, crank_angle_deg, length_unit)
    d = drawing(mechanism, params, crank_angle_deg, paths)
    if format == "json":  # the drawing and its symbols, for a page that draws them itself
        return json.dumps(
            {"drawing": asdict(d), "sketch": asdict(sketch(d))}, default=_listed
        ).encode()
    if format == "svg":
        return svg(d, length_unit).encode()
    if format == "gif":  # a turn of the crank from that angle
        return gif(d)
    from .dxf import dxf  # ezdxf: ~0.2 s to import, so on the first DXF

    return dxf(d, length_unit)


def _listed(x: Any) -> Any:
    return x.tolist()


def check(
    mechanism: str,
    params: Mapping[str, float],
    format: str = "svg",
    crank_angle_deg: float | None = None,
    length_unit: str = "mm",
    **_: Any,
) -> None:
    """What ``export`` checks before it draws (its arguments' meaning)."""
    m = drawn(mechanism)
    for k in params:
        m.parameter(k)
    if format not in FORMATS:
        msg = f"format must be one of {', '.join(FORMATS)}, got {format!r}"
        raise InvalidParameters(msg, ("format",))
    unit_mm(length_unit)
    check_angle(crank_angle_deg)
