"""The ASGI app: ``uvicorn api.main:app``. Its handlers turn synth's domain errors, placed in
the request by the routers, into 422s, and every other refusal into FastAPI's shape.

Every endpoint, dependency and error handler of the app is a coroutine: FastAPI and Starlette
run a plain function in a worker thread, a hop that cost /health ~0.2 ms of its 0.45
(docs/benchmarks.md, "Where a request's time goes")."""

import gc
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from pathlib import Path
from typing import Any

import fastapi_offline
from fastapi import FastAPI, Request
from fastapi.exception_handlers import http_exception_handler
from fastapi.exceptions import RequestValidationError
from fastapi.responses import FileResponse, JSONResponse, RedirectResponse, Response
from fastapi.staticfiles import StaticFiles
from fastapi_offline import FastAPIOffline
from starlette.exceptions import HTTPException as StarletteHTTPException

import synth
from synth.errors import UnknownMechanism

from .body_limit import too_large
from .engine import Busy, Engine
from .errors import capped, error_item, worded
from .gate import NOSNIFF, Gate, Headers
from .routers import analyze, atlas, export, mechanisms, report, sweep, synthesize
from .routers.common import Located
from .schemas import Health


@asynccontextmanager
async def lifespan(app: FastAPI) -> AsyncIterator[None]:
    engine = Engine.of(app)
    if engine.settings.warm:  # before uvicorn listens: a budget holds from the first request
        await engine.warm()
    gc.collect()
    gc.freeze()  # what the imports and the warm-up made lives as long as the process: unscanned
    yield
    engine.close()
    del app.state.engine


app = FastAPIOffline(  # /docs and /redoc load their scripts from this service, not a CDN
    title="Quick-return mechanism synthesis",
    version=synth.__version__,
    description="Dimensional synthesis and analysis of quick-return mechanisms: time ratio, "
    "stroke and minimum transmission angle to verified link lengths. A playground in the "
    "browser, served by this service: [/app/](/app/).",
    lifespan=lifespan,
    swagger_ui_parameters={"validatorUrl": None},  # no badge from validator.swagger.io
)
for module in (mechanisms, analyze, synthesize, sweep, export, report, atlas):
    app.include_router(module.router)
app.add_middleware(Gate)
# the playground: a page and its script and style, nothing from another origin
app.mount("/app", StaticFiles(directory=Path(__file__).parent / "static", html=True), name="app")


@app.get("/", include_in_schema=False)
async def root() -> RedirectResponse:
    return RedirectResponse("/app/")


# the icon a browser asks every page of the service for (the docs' own, served here)
FAVICON = Path(fastapi_offline.__file__).parent / "static" / "favicon.png"


@app.get("/favicon.ico", include_in_schema=False)
async def favicon() -> FileResponse:
    return FileResponse(FAVICON, media_type="image/png")


app.add_middleware(Headers)  # nosniff, and the pages' policies (api.gate)


@app.get("/health", response_model=Health, tags=["service"])
async def health() -> Health:
    return Health(version=synth.__version__)


@app.exception_handler(StarletteHTTPException)
async def http_error(request: Request, exc: StarletteHTTPException) -> Response:
    """A body that is not JSON at all is malformed input too: 422 in FastAPI's shape."""
    if exc.status_code == 400:
        detail = [error_item(["body"], str(exc.detail), "json_invalid")]
        return JSONResponse({"detail": detail}, status_code=422)
    if exc.status_code == 413:
        return too_large(str(exc.detail))
    return await http_exception_handler(request, exc)


@app.exception_handler(RequestValidationError)
async def invalid(request: Request, exc: RequestValidationError) -> JSONResponse:
    """FastAPI's 422, made safe to encode whatever the input held and bounded in size
    (``errors.error_item``, ``errors.capped``)."""

    def item(e: dict[str, Any]) -> dict[str, Any]:
        if e["type"] == "json_invalid":  # FastAPI locates it at a character: the msg says where
            e = {"loc": ["body"], "msg": e["ctx"]["error"], "type": e["type"]}
        more = {"input": e["input"]} if "input" in e else {}
        ctx = {k: v for k, v in (e.get("ctx") or {}).items() if k != "error"}
        return error_item(e["loc"], worded(e), e["type"], **more, **({"ctx": ctx} if ctx else {}))

    return JSONResponse({"detail": capped(exc.errors(), item)}, status_code=422)


@app.exception_handler(Busy)
async def busy(request: Request, exc: Busy) -> JSONResponse:
    """Every solver slot stayed taken for as long as the request could wait: 503, with when to
    try again."""
    detail = [error_item([], str(exc), "busy")]
    headers = {"Retry-After": str(exc.retry_after_s)}
    return JSONResponse({"detail": detail}, status_code=503, headers=headers)


@app.exception_handler(Located)
async def located(request: Request, exc: Located) -> JSONResponse:
    """Misuse and invalid designs: 422 in FastAPI's shape, one entry per place (an invalid
    design: each parameter of the failed condition)."""
    e = exc.error
    detail = capped(exc.locs, lambda loc: error_item(["body", *loc], e.msg, e.kind))
    return JSONResponse({"detail": detail}, status_code=422)


@app.exception_handler(Exception)
async def unexpected(request: Request, exc: Exception) -> JSONResponse:
    """Anything else: 500 in FastAPI's shape, nothing of the error in it (uvicorn logs it), and
    ``Connection: close``: uvicorn closes the connection once the error reaches it, so the client
    sends no next request on it to be reset."""
    msg = "the server failed to answer this request (the error is in its log)"
    headers = {"Connection": "close", NOSNIFF[0].decode(): NOSNIFF[1].decode()}
    detail = [error_item([], msg, "internal_error")]
    return JSONResponse({"detail": detail}, status_code=500, headers=headers)


@app.exception_handler(UnknownMechanism)
async def unknown(request: Request, exc: UnknownMechanism) -> JSONResponse:
    """A type in a path that is not one: 404."""
    return JSONResponse({"detail": [error_item(["path", *exc.loc], exc.msg, exc.kind)]}, 404)
