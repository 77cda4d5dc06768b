"""The ASGI app: ``uvicorn api.main:app``. One handler turns synth's domain errors into HTTP."""

from collections.abc import AsyncIterator
from contextlib import asynccontextmanager

from fastapi import FastAPI, Request
from fastapi.exception_handlers import http_exception_handler
from fastapi.responses import JSONResponse, Response
from starlette.exceptions import HTTPException as StarletteHTTPException

import synth
from synth.errors import InvalidDesign, SynthError, UnknownMechanism

from .engine import Engine
from .routers import analyze, mechanisms, sweep, synthesize
from .schemas import Health


@asynccontextmanager
async def lifespan(app: FastAPI) -> AsyncIterator[None]:
    engine = Engine.of(app)
    if engine.settings.warm:
        engine.warm()  # in the background: /health answers at once
    yield
    engine.close()
    del app.state.engine


app = FastAPI(
    title="Quick-return mechanism synthesis",
    version=synth.__version__,
    description="Dimensional synthesis and analysis of quick-return mechanisms: time ratio, "
    "stroke and minimum transmission angle to verified link lengths.",
    lifespan=lifespan,
)
for module in (mechanisms, analyze, synthesize, sweep):
    app.include_router(module.router)


@app.get("/health", response_model=Health, tags=["service"])
def health() -> Health:
    return Health(version=synth.__version__)


@app.exception_handler(StarletteHTTPException)
async def http_error(request: Request, exc: StarletteHTTPException) -> Response:
    """A body that is not JSON at all is malformed input too: 422 in FastAPI's shape."""
    if exc.status_code == 400:
        detail = [{"loc": ["body"], "msg": str(exc.detail), "type": "json_invalid"}]
        return JSONResponse({"detail": detail}, status_code=422)
    return await http_exception_handler(request, exc)


@app.exception_handler(SynthError)
def synth_error(request: Request, exc: SynthError) -> JSONResponse:
    """Misuse and invalid designs: 422 in FastAPI's shape; an unknown type in a path: 404.

    An invalid design names each parameter of the failed condition (one entry each)."""
    root = ["path" if request.method == "GET" else "body", *exc.where]
    if isinstance(exc, InvalidDesign):
        locs = [[*root, name] for name in exc.loc] or [root]
    else:
        locs = [[*root, *exc.loc]]
    detail = [{"loc": loc, "msg": exc.msg, "type": exc.kind} for loc in locs]
    not_found = isinstance(exc, UnknownMechanism) and request.method == "GET"
    return JSONResponse({"detail": detail}, status_code=404 if not_found else 422)
