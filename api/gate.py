"""The ASGI gate every HTTP request passes first: its arrival stamped, its body's size
limited, a HEAD answered as its GET, and a redirect kept to a path."""

from __future__ import annotations

import time

from starlette.exceptions import HTTPException
from starlette.requests import Request
from starlette.types import ASGIApp, Message, Receive, Scope, Send

from .body_limit import MAX_BODY_BYTES, too_large


class Gate:
    """Every HTTP request passes here first: stamped with its arrival (``arrival(request)``:
    a budget counts from it), and refused with 413 if its body is over ``limit`` bytes, at
    once by its Content-Length, else (chunked) as soon as the bytes read pass the limit:
    nothing past it is read or parsed. A HEAD is answered as its GET without the body (every
    GET route answers HEAD), and a redirect to this service's own host says only the path:
    a ``Host`` header never becomes a ``Location``."""

    def __init__(self, app: ASGIApp, limit: int = MAX_BODY_BYTES) -> None:
        self.app, self.limit = app, limit

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        scope.setdefault("state", {})["arrival"] = time.monotonic()
        headers = dict(scope["headers"])
        length = headers.get(b"content-length", b"0")
        if not length.isdigit() or int(length) > self.limit:
            response = too_large(f"the request body is {length.decode('latin-1')} bytes; at most "
                                 f"{self.limit} are accepted")  # fmt: skip
            await response(scope, receive, send)
            return
        seen = 0

        async def counted() -> Message:
            nonlocal seen
            message = await receive()
            seen += len(message.get("body", b""))
            if seen > self.limit:  # the handler's reading of the body ends here (api.main)
                raise HTTPException(413, f"the request body is over {self.limit} bytes")
            return message

        head = scope["method"] == "HEAD"
        host = headers.get(b"host", b"")

        async def sent(message: Message) -> None:
            if message["type"] == "http.response.start":
                message["headers"] = [(k, _relative(v, host) if k.lower() == b"location" else v)
                                      for k, v in message.get("headers", ())]  # fmt: skip
            elif head and message["type"] == "http.response.body":
                message = {**message, "body": b""}
            await send(message)

        await self.app({**scope, "method": "GET"} if head else scope, counted, sent)


def _relative(location: bytes, host: bytes) -> bytes:
    """An absolute ``location`` on ``host`` as its path (and query): where the service is
    reached is the client's business, not the Host header's."""
    scheme, sep, rest = location.partition(b"://")
    if not sep or scheme.lower() not in (b"http", b"https"):
        return location
    netloc, slash, path = rest.partition(b"/")
    return slash + path if netloc.lower() == host.lower() else location


def arrival(request: Request) -> float:
    """When the request reached the service (``time.monotonic``)."""
    return getattr(request.state, "arrival", None) or time.monotonic()
