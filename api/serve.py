"""The production command, ``make serve`` and the image: ``python -m api.serve [--host] [--port]``.

Runs ``WEB_CONCURRENCY`` uvicorn processes (default: one per core) on one listening socket;
``HOST`` and ``PORT`` give the defaults of ``--host`` and ``--port`` (``api.config``).
Each process answers short analyses in its own event loop and solves in its own solver threads
(``api.config``); the processes share nothing, so analysis throughput scales with the cores.
The event loop is uvloop's where it is installed (uvicorn's "auto" loop; the lock installs it):
~5% less of a process's time per short request than asyncio's (docs/benchmarks.md).
Their connections are ``api.connection``'s: a request that does not arrive whole in time is
refused (408), a half-closed one answered, Transfer-Encoding with Content-Length refused (400).

The socket is made here rather than by ``uvicorn --workers``: uvicorn 0.54 binds it with
``proto`` 0, accepted connections inherit that, and asyncio then leaves Nagle's algorithm on
(it sets TCP_NODELAY only when ``proto`` is IPPROTO_TCP). Every keep-alive request after the
first then waits ~40 ms for a delayed ACK (uvicorn issue #3149, measured: 44 ms against 2 ms).
uvloop sets TCP_NODELAY on every TCP connection itself; the socket made here serves asyncio's
loop where uvloop is not installed.
"""

from __future__ import annotations

import argparse
import logging
import os
import socket
import sys

import uvicorn
from uvicorn.supervisors import Multiprocess

from .config import CORES, Settings
from .connection import Connection

APP = "api.main:app"
# on SIGTERM: stop accepting at once, give requests in flight this long, then cancel them and
# exit (uvicorn ends the process by the signal, solver threads and all): every process is gone
# within 10 s (tests/service/test_faults.py)
SHUTDOWN_S = 5
# how long a thread holds the interpreter before another may take it (Python's default: 5 ms):
# the event loop waits that long behind a solver thread at each step, so /health under load
# took 230 ms at p99 with the default and 1 ms here (benchmarks/overload.py)
SWITCH_S = 0.001


def listener(host: str, port: int) -> socket.socket:
    """A TCP listening socket whose accepted connections get TCP_NODELAY from asyncio."""
    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    sock = socket.socket(family, socket.SOCK_STREAM, socket.IPPROTO_TCP)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    sock.bind((host, port))
    sock.set_inheritable(True)
    return sock


def main(argv: list[str] | None = None, app: str = APP) -> None:
    """Serve ``app`` (the service; ``benchmarks.bare`` serves a bare ASGI app the same way)."""
    sys.setswitchinterval(SWITCH_S)
    settings = Settings()
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--host", default=settings.host, help="default: HOST, else 127.0.0.1; "
                    "empty: the default")  # fmt: skip
    ap.add_argument("--port", type=int, default=settings.port, help="default: PORT, else 8000")
    a = ap.parse_args(argv)
    a.host = a.host or settings.host
    workers = settings.web_concurrency or CORES
    os.environ["WEB_CONCURRENCY"] = str(workers)  # for the processes' own settings
    config = uvicorn.Config(app, host=a.host, port=a.port, workers=workers, http=Connection,
                            timeout_graceful_shutdown=SHUTDOWN_S,
                            access_log=settings.access_log)  # fmt: skip
    if workers == 1:
        uvicorn.Server(config).run()  # binds by host and port: proto is set
        return
    sock = listener(a.host, a.port)
    logging.getLogger("uvicorn.error").info(
        "Serving on http://%s:%d with %d processes", a.host, sock.getsockname()[1], workers
    )
    Multiprocess(config, sockets=[sock]).run()


if __name__ == "__main__":
    main()
