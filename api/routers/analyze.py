"""POST /v1/analyze: one design over a crank revolution; curves only when asked."""

from typing import Annotated

from fastapi import APIRouter, Body, Request

from ..examples import ANALYZE
from ..schemas import AnalyzeRequest, AnalyzeResponse
from .common import run_design

router = APIRouter(tags=["analysis"])


@router.post("/v1/analyze", response_model=AnalyzeResponse, response_model_exclude_unset=True)
async def analyze(
    request: Request, body: Annotated[AnalyzeRequest, Body(openapi_examples=ANALYZE)]
) -> AnalyzeResponse:
    """Time ratio, stroke, dead centres, strokes and transmission angles of a design; curves at
    exactly ``crank_angles_deg`` or at ``samples`` evenly spaced angles, and only then."""
    a = await run_design(
        request,
        "analyze",
        body.mechanism,
        crank_speed=body.crank_speed,
        crank_acceleration=body.crank_acceleration,
        crank_angles_deg=body.crank_angles_deg,
        samples=body.samples,
    )
    return AnalyzeResponse(**a.to_dict())
