"""POST /v1/report: a design's report, one printable HTML page that stands alone."""

from typing import Annotated

from fastapi import APIRouter, Body, Request
from fastapi.responses import Response

from ..examples import REPORT
from ..json_route import Route
from ..schemas import REFUSALS, ReportRequest
from .common import EngineDep, load, run_design

router = APIRouter(tags=["analysis"], route_class=Route)
MEDIA = "text/html; charset=utf-8"
# the fields the library takes as another value than the body's (the rest as they are)
_CONVERTED = {"mechanism", "load", "targets"}


@router.post(
    "/v1/report",
    response_class=Response,
    responses={
        **REFUSALS,
        200: {
            "content": {MEDIA: {"schema": {"type": "string"}}},
            "description": "the report, as HTML",
        },
    },
)
async def report(
    request: Request,
    engine: EngineDep,
    body: Annotated[ReportRequest, Body(openapi_examples=REPORT)],
) -> Response:
    """The design's report: its drawing, the ``targets`` and what it achieves, its parts, the
    motion over a turn, with a ``load`` the loads (the torque diagram, the flywheel, the joint
    forces), the tolerance sensitivities and the limits it rests on. Its styles, drawing and
    charts are inline: the page asks nothing of any site."""
    targets = body.targets.model_dump(exclude_none=True) if body.targets else None
    page: str = await run_design(
        request,
        engine,
        "report",
        body.mechanism,
        **body.model_dump(exclude=_CONVERTED),  # the library's names
        load=load(body.load),
        targets=targets,
    )
    return Response(page, media_type=MEDIA)
