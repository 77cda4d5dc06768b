"""POST /v1/sweep: one parameter varied, the exact valid interval and time-ratio range."""

from typing import Annotated

from fastapi import APIRouter, Body, Request

from ..examples import SWEEP
from ..json_route import Route
from ..schemas import REFUSALS, SweepRequest, SweepResponse
from .common import EngineDep, budget, run_design

router = APIRouter(tags=["analysis"], route_class=Route)
# the fields the library takes as another value than the body's (the rest as they are)
_CONVERTED = {"mechanism", "time_budget_ms"}


@router.post("/v1/sweep", response_model=SweepResponse, responses=REFUSALS)
async def sweep(
    request: Request,
    engine: EngineDep,
    body: Annotated[SweepRequest, Body(openapi_examples=SWEEP)],
) -> SweepResponse:
    """What range must an adjustable part cover (Podhorodeski et al. (2005), Fig. 5). The
    budget counts from the request's arrival, as a synthesis's does: a sweep that runs out of
    it ends at the last value analysed (``complete`` false)."""
    r: SweepResponse = await run_design(
        request,
        engine,
        "sweep",
        body.mechanism,
        **body.model_dump(exclude=_CONVERTED),  # the library's names
        time_budget_ms=budget(engine, body.time_budget_ms),
    )
    return r
