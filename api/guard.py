"""What stands between any bytes a client sends and the handlers: the body's size limit, a
fast JSON parser, and error bodies that are always valid JSON of a bounded size.

JSON bodies may hold ``NaN``, ``Infinity``, ``1e309`` (an infinite float) and ``\\ud800`` (a
string no UTF-8 encoder takes). The models refuse them, naming the field; a 422 that echoed
such input back failed to encode (a 500), so every value an error carries is made safe here.
"""

from __future__ import annotations

import itertools
import json
import math
import time
from collections.abc import Callable, Collection
from typing import Any

import pydantic_core
from fastapi.routing import APIRoute
from starlette.exceptions import HTTPException
from starlette.requests import Request
from starlette.responses import JSONResponse, Response
from starlette.types import ASGIApp, Message, Receive, Scope, Send

MAX_BODY_BYTES = 4 * 1024 * 1024  # 100 000 crank angles at full precision is ~2.4 MB
# an error reply is small whatever the request held (tests/test_hostile.py: ≤ 16 KB)
MAX_ECHO_CHARS = 200  # an error echoes its input only when its JSON is this short
MAX_TEXT_CHARS = 300  # a longer message or value is cut in the middle (``clip``)
MAX_NAME_CHARS = 100  # so is a longer name in a loc
MAX_ITEMS, MAX_DEPTH = 10, 3  # of a list or dict an error carries (its loc, ctx or input)
MAX_ERRORS, MAX_DETAIL_CHARS = 24, 12_000  # a reply lists at most these many, this large


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


def too_large(msg: str) -> JSONResponse:
    """413, closing the connection: the rest of the body is not read."""
    detail = [error_item(["body"], msg, "body_too_large")]
    return JSONResponse({"detail": detail}, status_code=413, headers={"Connection": "close"})


class _FastJSON(Request):
    async def json(self) -> Any:
        if not hasattr(self, "_json"):
            body = await self.body()
            try:
                self._json = pydantic_core.from_json(body, allow_inf_nan=False)
            except ValueError as e:
                # NaN, Infinity, a lone surrogate: Python's parser takes them, so that the
                # models can name the field they are in (and refuse them); anything else is
                # no JSON at all (FastAPI: a 422 of type json_invalid)
                try:
                    self._json = json.loads(body)
                except ValueError:
                    raise json.JSONDecodeError(f"not JSON ({e})", "", 0) from None
        return self._json


class Route(APIRoute):
    """The routers' routes: bodies parsed by pydantic's JSON parser (``_FastJSON``), ~4× faster
    than ``json.loads``: a 2 MB body (100 000 crank angles) holds the event loop ~12 ms, not
    ~55. Only a body it refuses goes to ``json.loads``."""

    def get_route_handler(self):
        handler = super().get_route_handler()

        async def strict(request: Request) -> Response:
            return await handler(_FastJSON(request.scope, request.receive))

        return strict


def arrival(request: Request) -> float:
    """When the request reached the service (``time.monotonic``)."""
    return getattr(request.state, "arrival", None) or time.monotonic()


def safe(x: Any, depth: int = 0) -> Any:
    """``x`` as JSON can carry it, in bounded size whatever it is: a non-finite float as its
    name ("nan", "inf"), a string with U+FFFD for its lone surrogates and cut (``clip``) past
    ``MAX_TEXT_CHARS``, a huge integer as such a string, at most ``MAX_ITEMS`` items of a list
    or dict and ``MAX_DEPTH`` levels of them (no recursion deeper than that, however deep the
    input), anything else unknown as its str()."""
    if isinstance(x, bool) or x is None:
        return x
    if isinstance(x, int):
        return x if abs(x) < 10**15 else clip(str(x))
    if isinstance(x, float):
        return x if math.isfinite(x) else repr(x)
    if isinstance(x, str):
        return clip(x)
    if isinstance(x, dict | list | tuple):
        if depth >= MAX_DEPTH:
            return "…"
        items = itertools.islice(x.items() if isinstance(x, dict) else x, MAX_ITEMS)
        more = [f"… {len(x) - MAX_ITEMS} more"] if len(x) > MAX_ITEMS else []
        if isinstance(x, dict):
            kept = {safe(str(k)): safe(v, depth + 1) for k, v in items}
            return kept | ({"…": more[0]} if more else {})
        return [safe(v, depth + 1) for v in items] + more
    return safe(str(x))


def clip(s: str, limit: int = MAX_TEXT_CHARS) -> str:
    """``s`` with U+FFFD for its lone surrogates; past ``limit``, its head and tail around a
    note of how much was cut (a message's end often says what is allowed)."""
    if _surrogates(s):
        s = s.encode("utf-16", "surrogatepass").decode("utf-16", "replace")
    if len(s) <= limit:
        return s
    head, tail = limit * 2 // 3, limit // 3
    return f"{s[:head]}…[{len(s) - head - tail} characters cut]…{s[-tail:]}"


def _surrogates(s: str) -> bool:
    try:
        s.encode("utf-8")
    except UnicodeEncodeError:
        return True
    return False


def error_item(loc, msg: str, kind: str, **more: Any) -> dict[str, Any]:
    """One entry of an error's detail, safe to encode and bounded (``safe``, ``clip``); what
    ``more`` adds (an ``input``, a ``ctx``) is kept only when short."""
    loc = [k if isinstance(k, int) else clip(str(k), MAX_NAME_CHARS) for k in loc]
    if len(loc) > MAX_ITEMS:
        loc = [*loc[: MAX_ITEMS - 1], "…"]
    item = {"loc": loc, "msg": safe(msg), "type": safe(kind)}
    for k, v in more.items():  # input, ctx: only when short
        shown = safe(v)
        if _size(shown) <= MAX_ECHO_CHARS:
            item[k] = shown
    return item


def capped(items: Collection[Any], item: Callable[[Any], dict[str, Any]]) -> list[dict[str, Any]]:
    """An error reply's detail: ``item`` of each of ``items``, at most ``MAX_ERRORS`` of them
    and ``MAX_DETAIL_CHARS`` in all, then one that says how many more there were."""
    kept: list[dict[str, Any]] = []
    size = 0
    for x in items:
        entry = item(x)
        size += _size(entry)
        if len(kept) == MAX_ERRORS or size > MAX_DETAIL_CHARS:
            break
        kept.append(entry)
    if len(kept) < len(items):
        more = len(items) - len(kept)
        kept.append(error_item([], f"{more} more errors not listed (a reply lists at most "
                               f"{MAX_ERRORS})", "too_many_errors"))  # fmt: skip
    return kept


def _size(x: Any) -> int:
    return len(json.dumps(x, ensure_ascii=False))
