"""A bare ASGI app served as the service is (``api.serve``: the same uvicorn, connection
protocol, processes and settings): what a round trip costs on this server with nothing of ours
in it. ``benchmarks.service`` measures the service against it.

    python -m benchmarks.bare [--host] [--port]

It answers every request, whatever its method and path, with a small JSON body, once it has
read the request's body.
"""

from __future__ import annotations

from typing import Any

from api import serve

BODY = b'{"status":"ok"}'
_START = {
    "type": "http.response.start",
    "status": 200,
    "headers": [(b"content-type", b"application/json"), (b"content-length", b"%d" % len(BODY))],
}


async def app(scope: dict[str, Any], receive: Any, send: Any) -> None:
    if scope["type"] == "lifespan":
        while (await receive())["type"] != "lifespan.shutdown":
            await send({"type": "lifespan.startup.complete"})
        await send({"type": "lifespan.shutdown.complete"})
        return
    more = True
    while more:
        more = (await receive()).get("more_body", False)
    await send(_START)
    await send({"type": "http.response.body", "body": BODY})


if __name__ == "__main__":
    serve.main(app="benchmarks.bare:app")
