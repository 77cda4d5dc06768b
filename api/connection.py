"""The HTTP/1.1 connection ``api.serve`` runs: uvicorn's httptools protocol (the llhttp parser,
which refuses a request with both Transfer-Encoding and Content-Length: 400, RFC 9112 §6.1)
with the limits uvicorn lacks there, added as a byte count, timers and one end-of-file rule,
the parsing left to llhttp:

- A request line and headers of more than ``MAX_HEAD_BYTES`` get 431 and the connection is
  closed (uvicorn's h11 protocol has this limit; its httptools one has none).
- A request must arrive whole within ``request_timeout_s`` (``api.config``, 5 s) of the
  connection, or of its own first byte on a kept-alive connection: headers and body, however
  slowly they trickle. Past that a partial request gets 408 and the connection is closed; a
  connection that never sent a byte is closed. uvicorn times only the idle gap after a
  response, and restarts that on every byte.
- A client that sends its request and then shuts its side down (half-close) gets its reply,
  then the connection is closed; uvicorn closed it at the end of file, reply unsent.

Measured against hypercorn 0.18 and granian 2.8 (docs/service.md): neither does both, nor
refuses Transfer-Encoding with Content-Length.
"""

from __future__ import annotations

import asyncio
from typing import Any

from uvicorn.protocols.http.httptools_impl import HttpToolsProtocol

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
        self.head_bytes = 0  # read since the last request's headers were complete
        self.in_head = True  # no request's headers are complete since its first byte
        self.eof = False  # the client shut its side down
        self.deadline: asyncio.TimerHandle | None = None

    def connection_made(self, transport: asyncio.Transport) -> None:  # type: ignore[override]
        super().connection_made(transport)
        self._arm()

    def connection_lost(self, exc: Exception | None) -> None:
        self._disarm()
        super().connection_lost(exc)

    def data_received(self, data: bytes) -> None:
        head = self.in_head
        super().data_received(data)
        if head and self.in_head and not self.transport.is_closing():
            self.head_bytes += len(data)
            if self.head_bytes > MAX_HEAD_BYTES:
                msg = b"the request line and headers are over %d bytes" % MAX_HEAD_BYTES
                self._refuse(b"431 Request Header Fields Too Large", msg)

    def on_message_begin(self) -> None:
        super().on_message_begin()
        self.receiving = True
        if self.deadline is None:  # a kept-alive connection's next request: from its first byte
            self._arm()

    def on_headers_complete(self) -> None:
        self.in_head, self.head_bytes = False, 0
        super().on_headers_complete()
        if self.pipeline:  # queued behind a reply, unread until it is written: not timed
            self._disarm()

    def on_message_complete(self) -> None:
        self.receiving, self.in_head = False, True
        self._disarm()
        super().on_message_complete()

    def eof_received(self) -> bool:
        """Keep the connection open to write the reply to a whole request (a half-close);
        close it where nothing is being answered, or the request can no longer be whole."""
        self.eof = True
        return self.cycle is not None and not self.cycle.response_complete and not self.receiving

    def on_response_complete(self) -> None:
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
