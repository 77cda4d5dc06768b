"""The ASGI app: ``uvicorn api.main:app``. One handler turns synth's domain errors into HTTP."""

from fastapi import FastAPI, Request
from fastapi.responses import JSONResponse

import synth
from synth.errors import SynthError, UnknownMechanism

from .routers import mechanisms
from .schemas import Health

app = FastAPI(
    title="Quick-return mechanism synthesis",
    version=synth.__version__,
    description="Dimensional synthesis and analysis of quick-return mechanisms: time ratio, "
    "stroke and minimum transmission angle to verified link lengths.",
)
app.include_router(mechanisms.router)


@app.get("/health", response_model=Health, tags=["service"])
def health() -> Health:
    return Health(version=synth.__version__)


@app.exception_handler(SynthError)
def synth_error(request: Request, exc: SynthError) -> JSONResponse:
    """Misuse and invalid designs: 422 in FastAPI's shape; an unknown type in a path: 404."""
    in_path = isinstance(exc, UnknownMechanism) and request.method == "GET"
    detail = [{"loc": ["path" if in_path else "body", *exc.loc], "msg": exc.msg, "type": exc.kind}]
    return JSONResponse({"detail": detail}, status_code=404 if in_path else 422)
