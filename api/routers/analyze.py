"""POST /v1/analyze: one design over a crank revolution; curves only when asked."""

from typing import Annotated

from fastapi import APIRouter, Body, Request

from ..examples import ANALYZE
from ..json_route import Route
from ..schemas import REFUSALS, AnalyzeRequest, AnalyzeResponse
from .common import EngineDep, run_design, tolerance

router = APIRouter(tags=["analysis"], route_class=Route)
# an analysis with at most this many curve points runs in the request's own thread: it costs
# ~1 ms, less than a round trip to a worker process (benchmarks/results/service.json)
INLINE_CURVE_POINTS = 1000


@router.post(
    "/v1/analyze",
    response_model=AnalyzeResponse,
    response_model_exclude_unset=True,
    responses=REFUSALS,
)
async def analyze(
    request: Request,
    engine: EngineDep,
    body: Annotated[AnalyzeRequest, Body(openapi_examples=ANALYZE)],
) -> AnalyzeResponse:
    """Time ratio, stroke, dead centres, strokes and transmission angles of a design; curves at
    exactly ``crank_angles_deg`` or at ``samples`` evenly spaced angles, and only then; motion
    quality, sensitivities, the envelope and the curves' pins only when ``include`` names them
    (or, for sensitivities, a ``tolerance`` is given)."""
    points = len(body.crank_angles_deg or ()) + (body.samples or 0)
    a = await run_design(
        request,
        engine,
        "analyze",
        body.mechanism,
        inline=points <= INLINE_CURVE_POINTS,
        crank_speed=body.crank_speed,
        crank_acceleration=body.crank_acceleration,
        crank_angles_deg=body.crank_angles_deg,
        samples=body.samples,
        include=body.include,
        tolerance=tolerance(body),
    )
    return AnalyzeResponse(**a.to_dict())
