"""The production command, ``make serve`` and the image: ``python -m api.serve [--host] [--port]``.

Runs ``WEB_CONCURRENCY`` uvicorn processes (default: one per core) on one listening socket;
``HOST`` and ``PORT`` give the defaults of ``--host`` and ``--port`` (``api.config``).
Each process answers in its own event loop and works in its own threads (``api.engine``'s
lanes); the processes share nothing, so throughput scales with the cores.
The event loop is uvloop's where it is installed (uvicorn's "auto" loop; the lock installs it):
~5% less of a process's time per short request than asyncio's (docs/benchmarks.md).
Their connections are ``api.connection``'s: a request that does not arrive whole in time is
refused (408), a half-closed one answered, Transfer-Encoding with Content-Length refused (400),
a reply nobody reads dropped after the write timeout.

The socket is made here rather than by ``uvicorn --workers``: uvicorn 0.54 binds it with
``proto`` 0, accepted connections inherit that, and asyncio then leaves Nagle's algorithm on
(it sets TCP_NODELAY only when ``proto`` is IPPROTO_TCP). Every keep-alive request after the
first then waits ~40 ms for a delayed ACK (uvicorn issue #3149, measured: 44 ms against 2 ms).
uvloop sets TCP_NODELAY on every TCP connection itself; the socket made here serves asyncio's
loop where uvloop is not installed.

The processes are supervised here too (``Supervisor``), not by uvicorn's ``Multiprocess``:
on SIGTERM its parent kept the shared socket listening while the processes drained, so the
kernel took new connections that nobody would answer, reset when the server exited.
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import ctypes
import logging
import multiprocessing
import os
import signal
import socket
import sys
import time
from multiprocessing.connection import wait
from multiprocessing.context import SpawnProcess
from types import FrameType

import uvicorn
from uvicorn.config import STARTUP_FAILURE

from .config import CORES, Settings
from .connection import Connection

APP = "api.main:app"
# on SIGTERM: stop accepting at once, give requests in flight this long, then cancel them and
# exit (uvicorn ends the process by the signal, solver threads and all): every process is gone
# within STOP_S (tests/service/test_faults.py)
SHUTDOWN_S = 5
STOP_S = 10  # after SIGTERM, what is left of the processes then is killed
# how long a thread holds the interpreter before another may take it (Python's default: 5 ms):
# the event loop waits that long behind a solver thread at each step, so /health under load
# took 230 ms at p99 with the default and 1 ms here (benchmarks/overload.py)
SWITCH_S = 0.001
# glibc's malloc, fixed: blocks from 1 MiB on are mapped on their own and unmapped when freed,
# and free memory past 16 MiB at a heap's top goes back to the system. Its defaults start
# lower but rise with the largest block freed (up to 32 MiB, and twice that): after a few
# 9 MB replies, later large blocks came from the heaps and stayed. 15 analyses with 8.5 MB
# replies left a server process at 587 MB, 323 MB with these (at c969e81; since the analyses
# work in fixed-width slots, 140 against 125 MB). A 1 MiB trim kept 311 MB but cost a request
# 10-16% more processor time; these cost none measurable
MMAP_THRESHOLD, TRIM_THRESHOLD = 1 << 20, 16 << 20
_M_TRIM_THRESHOLD, _M_MMAP_THRESHOLD = -1, -3  # mallopt's parameters (malloc.h)


def listener(host: str, port: int) -> socket.socket:
    """A TCP listening socket whose accepted connections get TCP_NODELAY from asyncio."""
    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    sock = socket.socket(family, socket.SOCK_STREAM, socket.IPPROTO_TCP)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    sock.bind((host, port))
    sock.set_inheritable(True)
    return sock


def tune() -> None:
    """A server process's own settings: the thread switch interval, and malloc's thresholds
    fixed (``MMAP_THRESHOLD``) where the C library is glibc."""
    sys.setswitchinterval(SWITCH_S)
    try:
        libc = ctypes.CDLL("libc.so.6")
        libc.mallopt(_M_MMAP_THRESHOLD, MMAP_THRESHOLD)
        libc.mallopt(_M_TRIM_THRESHOLD, TRIM_THRESHOLD)
    except (OSError, AttributeError):  # not glibc: its own malloc's defaults
        pass


class Server(uvicorn.Server):
    """uvicorn's server, which stops accepting at the signal itself: uvicorn's stops at its
    next tick, up to 0.1 s later. The ``owner`` of the listening socket (the only process on
    it) shuts it down too: new connections are refused from then on."""

    def __init__(self, config: uvicorn.Config, owner: bool) -> None:
        super().__init__(config)
        self.owner = owner
        self.loop: asyncio.AbstractEventLoop | None = None
        self.listening: list[socket.socket] = []

    async def startup(self, sockets: list[socket.socket] | None = None) -> None:
        self.loop, self.listening = asyncio.get_running_loop(), sockets or []
        await super().startup(sockets)

    def handle_exit(self, sig: int, frame: FrameType | None) -> None:
        super().handle_exit(sig, frame)
        if self.loop is not None and not self.loop.is_closed():
            self.loop.call_soon_threadsafe(self._stop_accepting)

    def _stop_accepting(self) -> None:
        for sock in self.listening if self.owner else ():
            with contextlib.suppress(OSError):
                sock.shutdown(socket.SHUT_RDWR)
        for server in getattr(self, "servers", ()):
            server.close()


def serve(config: uvicorn.Config, sockets: list[socket.socket]) -> None:
    """One of several server processes (started by ``Supervisor``): its logging and settings,
    then its server on the shared socket."""
    config.configure_logging()
    tune()
    with contextlib.suppress(KeyboardInterrupt):  # SIGINT, raised again once it has stopped
        Server(config, owner=False).run(sockets)


class Supervisor:
    """``config.workers`` server processes on ``sock``, each replaced if it dies. On SIGTERM
    (or SIGINT) the socket stops listening at once, for every process (``shutdown``): a new
    connection is refused, not queued for nobody. Each process is told to stop, finishes
    what it holds (``SHUTDOWN_S``) and exits; what is left after ``STOP_S`` is killed."""

    def __init__(self, config: uvicorn.Config, sock: socket.socket) -> None:
        self.config, self.sock = config, sock
        self.processes: list[SpawnProcess] = []
        self.stopping = False

    def run(self) -> int:
        """Supervise until a signal; the exit status (not 0: a process failed to start)."""
        for sig in (signal.SIGTERM, signal.SIGINT):
            signal.signal(sig, self._stop)
        self.processes = [self._start() for _ in range(self.config.workers)]
        status = 0
        while not self.stopping:
            wait([p.sentinel for p in self.processes], timeout=0.5)
            for i, p in enumerate(self.processes):
                if p.exitcode == STARTUP_FAILURE:  # the app or the socket is broken: every
                    self._stop(signal.SIGTERM, None)  # new one would fail the same way
                    status = STARTUP_FAILURE
                elif p.exitcode is not None and not self.stopping:
                    logging.getLogger("uvicorn.error").info("Server process %d died", p.pid)
                    self.processes[i] = self._start()
        self._stop(signal.SIGTERM, None)  # again: a process started as the signal came
        deadline = time.monotonic() + STOP_S - 0.5
        for p in self.processes:
            p.join(max(0.0, deadline - time.monotonic()))
            if p.exitcode is None:
                p.kill()
                p.join()
        return status

    def _start(self) -> SpawnProcess:
        process = multiprocessing.get_context("spawn").Process(
            target=serve, args=(self.config, [self.sock])
        )  # a fresh interpreter: nothing of this one's state (its signal handlers) comes along
        process.start()
        return process

    def _stop(self, sig: int, frame: FrameType | None) -> None:
        self.stopping = True
        for p in self.processes:  # told first: each closes its own listener at the signal
            if p.pid is not None and p.exitcode is None:
                with contextlib.suppress(OSError):
                    os.kill(p.pid, signal.SIGTERM)
        with contextlib.suppress(OSError):
            self.sock.shutdown(socket.SHUT_RDWR)


def configure(app: str, host: str, port: int, settings: Settings) -> uvicorn.Config:
    """uvicorn's configuration of ``app``: ``api.connection``'s connections, no ``server``
    header, and X-Forwarded-For and -Proto trusted only from FORWARDED_ALLOW_IPS (uvicorn
    trusts 127.0.0.1 unless told: any process on the machine could then say who it is)."""
    forwarded = settings.forwarded_allow_ips
    workers = settings.web_concurrency or CORES
    return uvicorn.Config(
        app,
        host=host,
        port=port,
        workers=workers,
        http=Connection,
        timeout_graceful_shutdown=SHUTDOWN_S,
        access_log=settings.access_log,
        server_header=False,
        proxy_headers=forwarded is not None,
        forwarded_allow_ips=forwarded,
    )


def main(argv: list[str] | None = None, app: str = APP) -> None:
    """Serve ``app`` (the service; ``benchmarks.bare`` serves a bare ASGI app the same way)."""
    settings = Settings()
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument(
        "--host", default=settings.host, help="default: HOST, else 127.0.0.1; empty: the default"
    )
    ap.add_argument("--port", type=int, default=settings.port, help="default: PORT, else 8000")
    a = ap.parse_args(argv)
    config = configure(app, a.host or settings.host, a.port, settings)
    os.environ["WEB_CONCURRENCY"] = str(config.workers)  # for the processes' own settings
    sock = listener(config.host, config.port)
    logging.getLogger("uvicorn.error").info(
        "Serving on http://%s:%d (server processes: %d)",
        config.host,
        sock.getsockname()[1],
        config.workers,
    )
    if config.workers == 1:
        tune()
        Server(config, owner=True).run([sock])
    elif status := Supervisor(config, sock).run():
        sys.exit(status)


if __name__ == "__main__":
    main()
