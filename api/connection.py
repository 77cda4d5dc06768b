"""The HTTP/1.1 connection ``api.serve`` runs: uvicorn's httptools protocol (the llhttp parser,
which refuses a request with both Transfer-Encoding and Content-Length: 400, RFC 9112 §6.1)
with the limits uvicorn lacks there, added as a byte count, timers and one end-of-file rule,
the parsing left to llhttp:

- A request line and headers of more than ``MAX_HEAD_BYTES`` get 431 and the connection is
  closed, counted as parsed and, while incomplete, as read (uvicorn's h11 protocol has this
  limit; its httptools one has none).
- A request must arrive whole within ``request_timeout_s`` (``api.config``, 5 s) of the
  connection, or of its own first byte on a kept-alive connection: headers and body, however
  slowly they trickle. Past that a partial request gets 408 and the connection is closed; a
  connection that never sent a byte is closed. uvicorn times only the idle gap after a
  response, and restarts that on every byte.
- A client that sends its request and then shuts its side down (half-close) gets its reply,
  then the connection is closed; uvicorn's closes it at the end of file, reply unsent.

A reply's status line and headers are written with its body's first part, in one send: uvicorn
writes them apart, two sends a reply, and on loopback a send (which wakes the client) is the
largest single cost of a short request (docs/benchmarks.md, "Where a request's time goes").

Measured against hypercorn 0.18 and granian 2.8 (docs/benchmarks.md, "Clients that
misbehave"): each lacks one of these or more, and neither refuses Transfer-Encoding with
Content-Length.
"""

from __future__ import annotations

import asyncio
from typing import Any

from uvicorn.protocols.http.httptools_impl import HttpToolsProtocol, RequestResponseCycle

from .config import get_settings

MAX_HEAD_BYTES = 16 * 1024  # as h11's (uvicorn's h11_max_incomplete_event_size) default
_REFUSAL = (
    b"HTTP/1.1 %s\r\ncontent-type: text/plain; charset=utf-8\r\n"
    b"content-length: %d\r\nconnection: close\r\n\r\n%s"
)


class Connection(HttpToolsProtocol):
    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.timeout_s = get_settings().request_timeout_s
        self.receiving = False  # between a request's first byte and its last
        self.heads = 0  # requests whose request line and headers were read whole
        self.head_bytes = 0  # read since then while no request line and headers were whole
        self.in_body = False  # between a request's headers and its last byte
        self.head_size = 0  # this request's line and headers as parsed so far
        self.too_large = False
        self.eof = False  # the client shut its side down
        self.deadline: asyncio.TimerHandle | None = None

    def connection_made(self, transport: asyncio.Transport) -> None:  # type: ignore[override]
        super().connection_made(transport)
        self._arm()

    def connection_lost(self, exc: Exception | None) -> None:
        self._disarm()
        super().connection_lost(exc)

    def data_received(self, data: bytes) -> None:
        heads, body = self.heads, self.in_body
        super().data_received(data)
        if self.heads == heads and not (body or self.in_body or self.transport.is_closing()):
            self.head_bytes += len(data)  # all of it headers, none whole yet (llhttp holds them)
            if self.head_bytes > MAX_HEAD_BYTES:
                self._too_large()

    # the parsed request line and headers, as the parser hands them over
    def on_url(self, url: bytes) -> None:
        self._count(len(url))
        super().on_url(url)

    def on_header(self, name: bytes, value: bytes) -> None:
        self._count(len(name) + len(value) + 4)
        super().on_header(name, value)

    def _count(self, n: int) -> None:
        self.head_size += n
        if self.head_size > MAX_HEAD_BYTES:
            self.too_large = True
            raise ValueError("request line and headers too large")  # the parser stops: 400...

    def send_400_response(self, msg: str) -> None:
        if self.too_large:  # ...which is 431 here
            self._too_large()
        else:
            super().send_400_response(msg)

    def _too_large(self) -> None:
        msg = b"the request line and headers are over %d bytes" % MAX_HEAD_BYTES
        self._refuse(b"431 Request Header Fields Too Large", msg)

    def on_message_begin(self) -> None:
        super().on_message_begin()
        self.receiving, self.head_size = True, 0
        if self.deadline is None:  # a kept-alive connection's next request: from its first byte
            self._arm()

    def on_headers_complete(self) -> None:
        self.heads, self.head_bytes, self.in_body = self.heads + 1, 0, True
        super().on_headers_complete()
        cycle = self.cycle
        if cycle is not None and not isinstance(cycle.transport, _OneWrite):
            cycle.transport = _OneWrite(self.transport, cycle)  # type: ignore[assignment]
        if self.pipeline:  # queued behind a reply, unread until it is written: not timed
            self._disarm()

    def on_message_complete(self) -> None:
        self.receiving = self.in_body = False
        self._disarm()
        super().on_message_complete()

    # asyncio's protocol lets it answer whether to keep the transport open; uvicorn's says None
    def eof_received(self) -> bool:  # type: ignore[override]
        """Keep the connection open to write the reply to a whole request (a half-close);
        close it where nothing is being answered, or the request can no longer be whole."""
        self.eof = True
        return self.cycle is not None and not self.cycle.response_complete and not self.receiving

    def on_response_complete(self) -> None:
        if self.cycle is not None and isinstance(self.cycle.transport, _OneWrite):
            self.cycle.transport.flush()  # a reply without a body (HEAD): its head alone
        super().on_response_complete()
        if self.eof and not self.transport.is_closing():
            self.transport.close()  # after the reply is written: the client sends no more
        elif self.receiving and self.deadline is None:  # a queued request is read from now
            self._arm()

    def _arm(self) -> None:
        self.deadline = self.loop.call_later(self.timeout_s, self._expired)

    def _disarm(self) -> None:
        if self.deadline is not None:
            self.deadline.cancel()
            self.deadline = None

    def _expired(self) -> None:
        self.deadline = None
        if self.transport.is_closing():
            return
        cycle = self.cycle
        if self.receiving and not (
            cycle and cycle.response_started and not cycle.response_complete
        ):
            msg = b"the request did not arrive whole within %g s" % self.timeout_s
            self._refuse(b"408 Request Timeout", msg)  # no reply under way: one is possible
        self.transport.close()

    def _refuse(self, status: bytes, msg: bytes) -> None:
        self.transport.write(_REFUSAL % (status, len(msg), msg))
        self.transport.close()


class _OneWrite:
    """The transport as a reply's cycle sees it: the reply's head (the first write once the
    response has started) is held and written with the next write, the body's first part, or
    alone when the reply ends without one. Writes before the response starts (``100
    Continue``) and after the head go through as they come."""

    def __init__(self, transport: asyncio.Transport, cycle: RequestResponseCycle) -> None:
        self.transport, self.cycle = transport, cycle
        self.head: bytes | None = None
        self.held = False  # the head came and is held, or was written: later writes go through

    def write(self, data: bytes) -> None:
        if self.head is not None:
            data, self.head = self.head + data, None
        elif not self.held and self.cycle.response_started:
            self.head, self.held = data, True
            return
        self.transport.write(data)

    def flush(self) -> None:
        if self.head is not None:
            head, self.head = self.head, None
            self.transport.write(head)

    def close(self) -> None:
        self.flush()
        self.transport.close()

    def is_closing(self) -> bool:
        return self.transport.is_closing()

    def __getattr__(self, name: str) -> Any:
        return getattr(self.transport, name)
