"""The one way a router calls synth: through the engine, with domain errors located in the body."""

from typing import Any

from fastapi import Request

from synth.errors import InvalidDesign, SynthError
from synth.results import Tolerance

from ..engine import Engine
from ..schemas import Extras


async def run(
    request: Request,
    params_loc: tuple[str, ...],
    op: str,
    inline: bool = False,
    deadline: float | None = None,
    **kwargs: Any,
) -> Any:
    """Run ``op`` on the engine (see ``Engine.run`` for ``inline`` and ``deadline``); an error
    about the design's parameters is placed at ``params_loc`` in the request body."""
    try:
        return await Engine.of(request.app).run(op, inline, deadline, **kwargs)
    except SynthError as e:
        params = kwargs.get("params", ())
        if isinstance(e, InvalidDesign) or (e.loc and e.loc[0] in params):
            e.where = params_loc
        raise


async def run_design(
    request: Request, op: str, design: Any, inline: bool = False, **kwargs: Any
) -> Any:
    """``run`` for an operation on one design of the request (``body.mechanism``)."""
    params = design.params.model_dump(exclude_none=True)
    loc = ("mechanism", "params")
    return await run(request, loc, op, inline, mechanism=design.type, params=params, **kwargs)


def tolerance(body: Extras) -> Tolerance | None:
    """The request's tolerance as synth takes it."""
    return Tolerance(**body.tolerance.model_dump()) if body.tolerance else None
