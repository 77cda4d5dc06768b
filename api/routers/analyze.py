"""POST /v1/analyze: one design over a crank revolution; curves only when asked."""

from dataclasses import fields
from typing import Annotated, Any

import pydantic_core
from fastapi import APIRouter, Body, Request
from fastapi.responses import Response

from synth.results import Analysis, Curves

from ..examples import ANALYZE
from ..json_route import Route
from ..schemas import REFUSALS, AnalyzeRequest, AnalyzeResponse
from .common import EngineDep, load, run_design, tolerance

router = APIRouter(tags=["analysis"], route_class=Route)
# the fields the library takes as another value than the body's (the rest as they are)
_CONVERTED = {"mechanism", "tolerance", "load"}
# what an analysis and its curves hold only when asked: the fields whose default is None
_ASKED = {c: frozenset(f.name for f in fields(c) if f.default is None) for c in (Analysis, Curves)}


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
) -> Response:
    """Time ratio, stroke, dead centres, strokes and transmission angles of a design; curves at
    exactly ``crank_angles_deg`` or at ``samples`` evenly spaced angles, and only then; motion
    quality, sensitivities, the envelope and the curves' pins only when ``include`` names them
    (or, for sensitivities, a ``tolerance`` is given); the loads (crank torque, power,
    flywheel, joint forces) only with a ``load``."""
    reply: bytes = await run_design(
        request,
        engine,
        "analyze",
        body.mechanism,
        encoded,  # where it ran: 1 000 points with pins take ~0.7 ms to encode, 29 000 ~20
        **body.model_dump(exclude=_CONVERTED),  # the library's names
        tolerance=tolerance(body.tolerance),
        load=load(body.load),
    )
    return Response(reply, media_type="application/json")


def encoded(a: Analysis) -> bytes:
    """``a`` as JSON, by pydantic's encoder straight from synth's dataclasses, the bytes
    ``AnalyzeResponse`` gives for ``a.to_dict()`` (what is not asked for left out, arrays as
    lists, a non-finite number as null) without the dict and the model between: 6 µs against
    35 for a summary."""
    exclude: dict[str, Any] = {k: True for k in _ASKED[Analysis] if getattr(a, k) is None}
    if a.curves is not None:
        unasked = {k for k in _ASKED[Curves] if getattr(a.curves, k) is None}
        if unasked:
            exclude["curves"] = unasked
    return pydantic_core.to_json(a, exclude=exclude or None, fallback=_listed, inf_nan_mode="null")


def _listed(x: Any) -> Any:
    """A numpy array or number as JSON takes it (lists, Python numbers)."""
    return x.tolist()
