"""The ASGI gate every HTTP request passes first: its Host checked, its arrival stamped, its
body's size limited, a HEAD answered as its GET, and a redirect kept to a path; and the
headers every reply carries (``Headers``)."""

from __future__ import annotations

import base64
import hashlib
import ipaddress
import re
import time
from functools import lru_cache
from typing import Any

from starlette.exceptions import HTTPException
from starlette.requests import Request
from starlette.responses import JSONResponse
from starlette.types import ASGIApp, Message, Receive, Scope, Send

from .body_limit import MAX_BODY_BYTES, too_large
from .config import get_settings
from .errors import error_item

LOOPBACK_NAMES = frozenset((b"localhost", b"127.0.0.1", b"[::1]"))
NOSNIFF = (b"x-content-type-options", b"nosniff")
CSP = b"content-security-policy"


class Gate:
    """Every HTTP request passes here first: refused with 400 if its ``Host`` names another
    service (``Hosts``), stamped with its arrival (``arrival(request)``: a budget counts from
    it), and refused with 413 if its body is over ``limit`` bytes, at once by its
    Content-Length, else (chunked) as soon as the bytes read pass the limit: nothing past it
    is read or parsed. A HEAD is answered as its GET without the body (every GET route answers
    HEAD), and a redirect to this service's own host says only the path: a ``Host`` header
    never becomes a ``Location``."""

    def __init__(self, app: ASGIApp, limit: int = MAX_BODY_BYTES, hosts: str | None = None) -> None:
        self.app, self.limit = app, limit
        self.hosts = Hosts(get_settings().allowed_hosts if hosts is None else hosts)

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        scope.setdefault("state", {})["arrival"] = time.monotonic()
        headers = dict(scope["headers"])
        host = headers.get(b"host", b"")
        if not self.hosts.allow(scope.get("server"), host):
            await _other_host(host)(scope, receive, send)
            return
        length = headers.get(b"content-length", b"0")
        if not length.isdigit() or int(length) > self.limit:
            response = too_large(
                f"the request body is {length.decode('latin-1')} bytes; at most "
                f"{self.limit} are accepted"
            )
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

        async def sent(message: Message) -> None:
            if message["type"] == "http.response.start":
                message["headers"] = [
                    (k, _relative(v, host) if k.lower() == b"location" else v)
                    for k, v in message.get("headers", ())
                ]
            elif head and message["type"] == "http.response.body":
                message = {**message, "body": b""}
            await send(message)

        await self.app({**scope, "method": "GET"} if head else scope, counted, sent)


class Hosts:
    """The names a request's ``Host`` may give, with any port: ``allowed`` (ALLOWED_HOSTS,
    comma-separated; "*": any), else the loopback names on a connection made to a loopback
    address and any name on others. So a page on another site whose name its DNS turns into
    127.0.0.1 (DNS rebinding) gets no answer from a service on loopback."""

    def __init__(self, allowed: str | None) -> None:
        names = None if allowed is None else {_name(n.strip().encode()) for n in allowed.split(",")}
        self.names = None if names is None else frozenset(names - {b""})

    def allow(self, server: Any, host: bytes) -> bool:
        names = self.names
        if names is None:
            if not (server and _loopback(str(server[0]))):
                return True
            names = LOOPBACK_NAMES
        return b"*" in names or _name(host) in names


def _name(host: bytes) -> bytes:
    """A Host's name without its port: "[::1]:8000" is "[::1]", "LocalHost:80" "localhost"."""
    host = host.lower()
    if host.startswith(b"["):
        return host.partition(b"]")[0] + b"]"
    return host.partition(b":")[0]


@lru_cache(maxsize=64)
def _loopback(address: str) -> bool:
    try:
        ip = ipaddress.ip_address(address)
    except ValueError:  # not an address: a test client's "testserver", a Unix socket's path
        return False
    mapped = getattr(ip, "ipv4_mapped", None)  # ::ffff:127.0.0.1, on a dual-stack socket
    return ip.is_loopback or bool(mapped and mapped.is_loopback)


def _other_host(host: bytes) -> JSONResponse:
    msg = "this service does not answer to that name (ALLOWED_HOSTS lists those it does)"
    item = error_item(["header", "host"], msg, "host_not_allowed", input=host.decode("latin-1"))
    return JSONResponse({"detail": [item]}, status_code=400)


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


class Headers:
    """What every reply says to a browser: ``nosniff`` (take the reply as the type it states,
    never run it as a script or style it might look like), and each page's policy: the
    playground and the docs load scripts, styles and images from this service only (styles
    inline too: the playground sizes its drawing's labels so, ReDoc writes its own), the
    docs' inline scripts by their hashes, and no other site may frame them (clickjacking).
    /redoc draws its maker's logo from a CDN: the browser does not ask (nothing leaves the
    machine)."""

    POLICY = (
        b"default-src 'self'; style-src 'self' 'unsafe-inline'; img-src 'self' data:; "
        b"object-src 'none'; base-uri 'none'; form-action 'self'; frame-ancestors 'none'"
    )
    APP = "/app/"
    DOCS = ("/docs", "/redoc", "/docs/oauth2-redirect")

    def __init__(self, app: ASGIApp) -> None:
        self.app = app

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        path = scope["path"]
        page = path.startswith(self.APP)
        docs = path in self.DOCS
        held: Message | None = None  # a docs page's start, until its body names its scripts

        async def sending(message: Message) -> None:
            nonlocal held
            if message["type"] == "http.response.start":
                headers = [*message.get("headers", ()), NOSNIFF]
                if page:
                    headers.append((CSP, self.POLICY))
                message = {**message, "headers": headers}
                if docs:
                    held = message
                    return
            elif held is not None:
                held["headers"].append((CSP, _with_scripts(self.POLICY, message.get("body", b""))))
                await send(held)
                held = None
            await send(message)

        await self.app(scope, receive, sending)


_INLINE_SCRIPT = re.compile(rb"<script(?![^>]*\bsrc=)[^>]*>(.*?)</script>", re.DOTALL)


def _with_scripts(policy: bytes, page: bytes) -> bytes:
    """``policy`` with a script-src that allows this service's scripts and ``page``'s inline
    ones, each by its hash (FastAPI writes Swagger UI's settings into the page)."""
    hashes = [
        b"'sha256-%s'" % base64.b64encode(hashlib.sha256(s).digest())
        for s in _INLINE_SCRIPT.findall(page)
    ]
    return policy + b"; script-src 'self' %s; worker-src 'self' blob:" % b" ".join(hashes)
