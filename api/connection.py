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
- A request answered before its body arrived whole (a 404 to a body announced, never sent)
  gets ``Connection: close`` and the connection is closed after the reply: what follows on it
  is no request, and nothing answers it a second time (no 408 when the body never comes).
- A reply the client does not read is not kept: once the transport pauses writing (its buffer
  over the high-water mark), a client that takes no byte of it for ``write_timeout_s`` has its
  connection reset and what it held freed. And a process holds at most ``max_unsent_mb`` of
  replies not yet taken (``Connection.unsent``): a reply over ``SMALL_REPLY`` that would take
  it past that, while some are held, is answered 503 with Retry-After instead. uvicorn has no
  write timeout: a client that never reads holds its reply for as long as it stays connected.

A reply's status line and headers are written with its body's first part, in one send: uvicorn
writes them apart, two sends a reply, and on loopback a send (which wakes the client) is the
largest single cost of a short request (docs/benchmarks.md, "Where a request's time goes"); a
large body is not copied for it (a vectored write).

Measured against hypercorn 0.18 and granian 2.8 (docs/benchmarks.md, "Clients that
misbehave"): each lacks one of these or more, and neither refuses Transfer-Encoding with
Content-Length.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import math
import socket
import struct
from typing import Any, ClassVar

from starlette.types import Message, Send
from uvicorn.protocols.http.httptools_impl import HttpToolsProtocol, RequestResponseCycle

from .config import get_settings
from .errors import error_item
from .gate import NOSNIFF

MAX_HEAD_BYTES = 16 * 1024  # as h11's (uvicorn's h11_max_incomplete_event_size) default
# a reply this small always goes: a socket's buffer takes it whole (uvloop's high-water mark)
SMALL_REPLY = 64 * 1024
_RESET = struct.pack("ii", 1, 0)  # SO_LINGER on, 0 s: closing the socket resets the connection
_REFUSAL = (
    b"HTTP/1.1 %s\r\ncontent-type: text/plain; charset=utf-8\r\nx-content-type-options: "
    b"nosniff\r\ncontent-length: %d\r\nconnection: close\r\n\r\n%s"
)


class Connection(HttpToolsProtocol):
    # this process's connections whose transport paused writing: they hold replies not yet
    # taken by their clients
    backlogged: ClassVar[set[Connection]] = set()

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        settings = get_settings()
        self.timeout_s = settings.request_timeout_s
        self.write_timeout_s = settings.write_timeout_s
        self.max_unsent = int(settings.max_unsent_mb * 1e6)
        self.receiving = False  # between a request's first byte and its last
        self.heads = 0  # requests whose request line and headers were read whole
        self.head_bytes = 0  # read since then while no request line and headers were whole
        self.in_body = False  # between a request's headers and its last byte
        self.head_size = 0  # this request's line and headers as parsed so far
        self.too_large = False
        self.eof = False  # the client shut its side down
        self.deadline: asyncio.TimerHandle | None = None
        self.stall: asyncio.TimerHandle | None = None  # the write timeout, while paused
        self.written = 0  # bytes of replies handed to the transport
        self.last_write = 0  # the last one's size
        # while paused, what its replies keep in memory: the transport keeps each write whole
        # until all of it is sent (its buffer's size counts only the part not sent)
        self.holding = 0

    def connection_made(self, transport: asyncio.Transport) -> None:  # type: ignore[override]
        super().connection_made(transport)
        self._arm()

    def connection_lost(self, exc: Exception | None) -> None:
        self._disarm()
        self._unwatch()
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
            self._refuse(b"400 Bad Request", msg.encode("ascii", "replace"))

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
            cycle.transport = _OneWrite(self, cycle)  # type: ignore[assignment]
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

    def _start_asgi_task(self, cycle: RequestResponseCycle, app: Any) -> None:
        super()._start_asgi_task(cycle, _Replying(self, cycle, app))

    # the transport's flow control: paused when its buffer passes the high-water mark
    def pause_writing(self) -> None:
        super().pause_writing()
        self.holding = max(self.last_write, self.transport.get_write_buffer_size())
        Connection.backlogged.add(self)
        if self.stall is None:
            self._watch()

    def resume_writing(self) -> None:
        super().resume_writing()
        self._unwatch()

    def _watch(self) -> None:
        sent = self.written - self.transport.get_write_buffer_size()
        self.stall = self.loop.call_later(self.write_timeout_s, self._stalled, sent)

    def _unwatch(self) -> None:
        Connection.backlogged.discard(self)
        if self.stall is not None:
            self.stall.cancel()
            self.stall = None

    def _stalled(self, sent: int) -> None:
        """The client took no byte for the write timeout: the connection is reset, what its
        reply held freed, here and in the kernel (a close would wait for the reply to be sent,
        and a close of the socket alone still sends the kernel's part). One that reads,
        however slowly, is watched on."""
        self.stall = None
        if self.written - self.transport.get_write_buffer_size() > sent:
            self._watch()
            return
        sock = self.transport.get_extra_info("socket")
        if sock is not None:
            with contextlib.suppress(OSError):
                sock.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, _RESET)
        self.transport.abort()

    @classmethod
    def unsent(cls) -> int:
        """Bytes of this process's memory held by replies their clients have not taken whole
        (on connections whose buffer passed the high-water mark)."""
        return sum(c.holding for c in cls.backlogged)

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
        replying = cycle is not None and cycle.response_started and not cycle.response_complete
        # the request being received was answered already (it closes after its reply)
        answered = self.in_body and cycle is not None and cycle.response_started
        if self.receiving and not (replying or answered):
            msg = b"the request did not arrive whole within %g s" % self.timeout_s
            self._refuse(b"408 Request Timeout", msg)  # no reply under way: one is possible
        self.transport.close()

    def _refuse(self, status: bytes, msg: bytes) -> None:
        self.transport.write(_REFUSAL % (status, len(msg), msg))
        self.transport.close()


class _Replying:
    """The app as one request's cycle runs it, its reply's start checked first: a request whose
    body has not arrived whole is answered with ``Connection: close``, and a reply the process
    cannot hold besides the unsent ones (``Connection.unsent``) is replaced by a 503."""

    def __init__(self, connection: Connection, cycle: RequestResponseCycle, app: Any) -> None:
        self.connection, self.cycle, self.app = connection, cycle, app
        self.refused = False  # the app's reply is dropped: a 503 went instead
        self.send: Send | None = None

    async def __call__(self, scope: Any, receive: Any, send: Any) -> None:
        self.send = send
        await self.app(scope, receive, self.sending)

    async def sending(self, message: Message) -> None:
        assert self.send is not None
        if self.refused:
            return
        if message["type"] == "http.response.start":
            cycle, connection = self.cycle, self.connection
            if cycle.more_body:  # what follows on the connection is this body's rest
                cycle.keep_alive = False
            size = _length(message)
            if size > SMALL_REPLY and cycle.scope["method"] != "HEAD":
                held = Connection.unsent()
                if held and held + size > connection.max_unsent:
                    self.refused = True
                    await self._busy(math.ceil(connection.write_timeout_s))
                    return
        await self.send(message)

    async def _busy(self, retry_after_s: int) -> None:
        assert self.send is not None
        msg = (
            f"the server holds as many replies not yet read as it may; try again in "
            f"{retry_after_s} s"
        )
        body = json.dumps({"detail": [error_item([], msg, "busy")]}).encode()
        headers = [
            (b"content-type", b"application/json"),
            (b"content-length", b"%d" % len(body)),
            (b"retry-after", b"%d" % retry_after_s),
            NOSNIFF,
        ]
        await self.send({"type": "http.response.start", "status": 503, "headers": headers})
        await self.send({"type": "http.response.body", "body": body})


def _length(start: Message) -> int:
    """A reply's Content-Length (0 where it gives none)."""
    for name, value in start.get("headers", ()):
        if name.lower() == b"content-length":
            return int(value) if value.isdigit() else 0
    return 0


class _OneWrite:
    """The transport as a reply's cycle sees it: the reply's head (the first write once the
    response has started) is held and written with the next write, the body's first part, or
    alone when the reply ends without one. Writes before the response starts (``100
    Continue``) and after the head go through as they come. Each write is counted
    (``Connection.written``, ``last_write``: what the write timeout and the bound watch)."""

    def __init__(self, connection: Connection, cycle: RequestResponseCycle) -> None:
        self.connection, self.transport, self.cycle = connection, connection.transport, cycle
        self.head: bytes | None = None
        self.held = False  # the head came and is held, or was written: later writes go through

    def write(self, data: bytes) -> None:
        if self.head is not None:
            head, self.head = self.head, None
            self._count(len(head) + len(data))
            if len(data) > SMALL_REPLY:
                self.transport.writelines((head, data))  # one send, the body not copied
            else:
                self.transport.write(head + data)
            return
        if not self.held and self.cycle.response_started:
            self.head, self.held = data, True
            return
        self._count(len(data))
        self.transport.write(data)

    def flush(self) -> None:
        if self.head is not None:
            head, self.head = self.head, None
            self._count(len(head))
            self.transport.write(head)

    def _count(self, n: int) -> None:
        self.connection.written += n
        self.connection.last_write = n

    def close(self) -> None:
        self.flush()
        self.transport.close()

    def is_closing(self) -> bool:
        return self.transport.is_closing()

    def __getattr__(self, name: str) -> Any:
        return getattr(self.transport, name)
