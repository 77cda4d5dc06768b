"""POST /v1/sweep: one parameter varied, the exact valid interval and time-ratio range."""

from typing import Annotated

from fastapi import APIRouter, Body

from ..examples import SWEEP
from ..guard import Route
from ..schemas import REFUSALS, SweepRequest, SweepResponse
from .common import EngineDep, run_design

router = APIRouter(tags=["analysis"], route_class=Route)


@router.post("/v1/sweep", response_model=SweepResponse, responses=REFUSALS)
async def sweep(
    engine: EngineDep, body: Annotated[SweepRequest, Body(openapi_examples=SWEEP)]
) -> SweepResponse:
    """What range must an adjustable part cover (Podhorodeski et al. (2005), Fig. 5)."""
    r = await run_design(
        engine,
        "sweep",
        body.mechanism,
        vary=body.vary,
        start=body.start,
        stop=body.stop,
        points=body.points,
    )
    return r
