"""The request body's size limit, and the 413 that refuses a body over it."""

from __future__ import annotations

from starlette.responses import JSONResponse

from .errors import error_item

MAX_BODY_BYTES = 4 * 1024 * 1024  # 100 000 crank angles at full precision is ~2.4 MB


def too_large(msg: str) -> JSONResponse:
    """413, closing the connection: the rest of the body is not read."""
    detail = [error_item(["body"], msg, "body_too_large")]
    return JSONResponse({"detail": detail}, status_code=413, headers={"Connection": "close"})
