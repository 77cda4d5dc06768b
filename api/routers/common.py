"""The one way a router calls synth: the operation's own checks at once, then the operation
through the engine; synth's errors located in the request body."""

from collections.abc import Callable
from typing import Annotated, Any

from fastapi import Depends, Request

from synth.errors import InvalidDesign, InvalidParameters, SynthError
from synth.load import Load
from synth.results import Tolerance

from ..engine import Engine
from ..gate import arrival
from ..operations import OPERATIONS
from ..schemas import LoadSpec, ToleranceSpec

Loc = tuple[str | int, ...]


async def engine(request: Request) -> Engine:
    """The app's engine (and with it the settings): what the routes depend on. A coroutine:
    FastAPI runs a plain function in a worker thread, a hop of ~0.1 ms per request."""
    return Engine.of(request.app)


EngineDep = Annotated[Engine, Depends(engine)]


def budget(engine: Engine, budget_ms: float | None) -> float:
    """The request's ``time_budget_ms``, the server's default where it gives none; over the
    server's largest: a 422."""
    budget_ms = budget_ms or engine.settings.default_budget_ms
    largest = engine.settings.max_budget_ms
    if budget_ms > largest:
        e = InvalidParameters(
            f"time_budget_ms must be ≤ {largest:g} (this server's largest "
            f"budget), got {budget_ms:g}",
            ("time_budget_ms",),
        )
        raise Located(e, [e.loc])
    return budget_ms


class Located(Exception):
    """A domain error (``error``) at places in the request (``locs``): a 422 (api.main)."""

    def __init__(self, error: SynthError, locs: list[Loc]) -> None:
        super().__init__(error.msg)
        self.error, self.locs = error, locs


async def run(
    request: Request,
    engine: Engine,
    locate: Callable[[SynthError], list[Loc]],
    op: str,
    then: Callable[[Any], Any] | None = None,
    **kwargs: Any,
) -> Any:
    """Run ``op`` on the engine with its request value built from ``kwargs`` (checked there:
    a 422 under any load), on its short lane where the operation says it is short (waits and
    budgets count from the request's arrival); ``then`` of its result, in the lane too
    (``Engine.run``). A domain error goes where ``locate`` places it in the request body."""
    try:
        value = OPERATIONS[op].request(**kwargs)
        return await engine.run(op, value, arrival(request), then)
    except SynthError as e:
        raise Located(e, locate(e)) from None


async def run_design(
    request: Request,
    engine: Engine,
    op: str,
    design: Any,
    then: Callable[[Any], Any] | None = None,
    **kwargs: Any,
) -> Any:
    """``run`` for an operation on one design of the request (``body.mechanism``): an error
    about its parameters is located at each parameter in ``mechanism.params``, any other at
    the argument it names."""
    params = design.params.model_dump(exclude_none=True)

    def locate(e: SynthError) -> list[Loc]:
        if isinstance(e, InvalidDesign):
            return [("mechanism", "params", name) for name in e.loc] or [("mechanism",)]
        if e.loc and e.loc[0] in params:
            return [("mechanism", "params", *e.loc)]
        return [e.loc]

    return await run(
        request, engine, locate, op, then, mechanism=design.type, params=params, **kwargs
    )


def tolerance(spec: ToleranceSpec | None) -> Tolerance | None:
    """A request's tolerance as synth takes it; a rule the schema leaves to ``Tolerance``
    (one of its two fields): a 422 at its field."""
    try:
        return Tolerance(**spec.model_dump()) if spec else None
    except InvalidParameters as e:
        raise Located(e, [e.loc]) from None


def load(spec: LoadSpec | None) -> Load | None:
    """A request's load as synth takes it; a rule the schema leaves to ``Load`` (two fields
    that exclude each other): a 422 at its field."""
    try:
        return Load(**spec.model_dump(exclude_unset=True)) if spec else None
    except InvalidParameters as e:
        raise Located(e, [e.loc]) from None
