"""POST /v1/export: a design's drawing as a file a CAD program or a document takes."""

from typing import Annotated

from fastapi import APIRouter, Body, Request
from fastapi.responses import Response

from ..examples import EXPORT
from ..json_route import Route
from ..schemas import REFUSALS, ExportRequest
from .common import EngineDep, run_design

router = APIRouter(tags=["analysis"], route_class=Route)
MEDIA = {
    "svg": "image/svg+xml",
    "dxf": "image/vnd.dxf",
    "json": "application/json",
    "gif": "image/gif",
}

FILE = {"type": "string", "format": "binary"}
# the json format's schema: the drawing and its symbols, objects (synth.drawing.model)
_SCHEMA: dict[str, dict[str, object]] = {
    "json": {
        "type": "object",
        "properties": {
            "drawing": {"type": "object", "additionalProperties": True},
            "sketch": {"type": "object", "additionalProperties": True},
        },
        "required": ["drawing", "sketch"],
    }
}


@router.post(
    "/v1/export",
    response_class=Response,
    responses={
        **REFUSALS,
        200: {
            "content": {m: {"schema": _SCHEMA.get(f, FILE)} for f, m in MEDIA.items()},
            "description": "the drawing, as a file",
        },
    },
)
async def export(
    request: Request,
    engine: EngineDep,
    body: Annotated[ExportRequest, Body(openapi_examples=EXPORT)],
) -> Response:
    """The design drawn at ``crank_angle_deg``: ``svg`` in true size (its width and height in
    millimetres for the lengths' ``length_unit``), or ``dxf`` for CAD (each link a centre line
    on its own layer, as long as the design says; the pins, the fixed pivots, the ram's guide
    and block, the stroke as a dimension; each moving pin's path with ``paths``), or ``gif``
    (a turn of the crank from there, animated)."""
    doc: bytes = await run_design(
        request,
        engine,
        "export",
        body.mechanism,
        **body.model_dump(exclude={"mechanism"}),  # the library's names
    )
    name = f"{body.mechanism.type}.{body.format}"
    return Response(
        doc,
        media_type=MEDIA[body.format],
        headers={"Content-Disposition": f'attachment; filename="{name}"'},
    )
