"""POST /v1/synthesize: targets to verified candidates, ranked; reasons where none."""

from typing import Annotated

from fastapi import APIRouter, Body, Request

from synth.errors import SynthError

from ..examples import SYNTHESIZE
from ..json_route import Route
from ..schemas import REFUSALS, SynthesizeRequest, SynthesizeResponse
from .common import EngineDep, Loc, budget, load, run, tolerance

router = APIRouter(tags=["synthesis"], route_class=Route)
# the fields the library takes as another value than the body's (the rest as they are)
_CONVERTED = {"mechanisms", "time_budget_ms", "tolerance", "load"}


@router.post("/v1/synthesize", response_model=SynthesizeResponse, responses=REFUSALS)
async def synthesize(
    request: Request,
    engine: EngineDep,
    body: Annotated[SynthesizeRequest, Body(openapi_examples=SYNTHESIZE)],
) -> SynthesizeResponse:
    """Every good design for the time ratio, stroke and transmission bound, each verified by
    the forward analysis; an impossible request gives no candidates and a reason per type.
    The budget counts from the request's arrival; a request that cannot get a solver within
    half of it gets a 503 with Retry-After instead of waiting."""
    specs = None
    if body.mechanisms is not None:
        specs = [
            {
                "type": s.type,
                "fixed": s.fixed.model_dump(exclude_none=True),
                "bounds": s.bounds.model_dump(exclude_none=True),
            }
            for s in body.mechanisms
        ]

    def locate(e: SynthError) -> list[Loc]:
        """At the argument; in ``mechanisms[i]``, under its type's tag (as FastAPI's own
        errors in a tagged union are)."""
        at = e.loc
        if len(at) > 1 and at[0] == "mechanisms" and body.mechanisms is not None:
            at = (*at[:2], body.mechanisms[int(at[1])].type, *at[2:])
        return [at]

    r: SynthesizeResponse = await run(
        request,
        engine,
        locate,
        "synthesize",
        **body.model_dump(exclude=_CONVERTED),  # the library's names
        mechanisms=specs,
        time_budget_ms=budget(engine, body.time_budget_ms),
        tolerance=tolerance(body.tolerance),
        load=load(body.load),
    )
    return r
