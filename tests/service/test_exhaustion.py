"""What no sequence of requests may do to the server (issue 38), against the real one where it
matters: keep memory with replies nobody reads, answer one request twice, leave a connection
made after SIGTERM hanging, drop a keep-alive connection after a 500 without saying so; and
the headers every reply carries (nosniff, the pages' policies, no banner, the Host allowed).
"""

from __future__ import annotations

import contextlib
import http.client
import json
import re
import select
import signal
import socket
import threading
import time
from collections import Counter
from collections.abc import Iterator
from pathlib import Path

import pytest
import uvicorn

from api.config import Settings
from api.connection import Connection
from api.gate import Hosts
from api.serve import configure

from ..support.server import descendants, free_port, serving
from .test_faults import SYNTH, post  # SYNTH: ~0.3 s of SLSQP in a solver

pytestmark = pytest.mark.serial  # timing-sensitive: alone, not beside other tests (make test)

WRITE_TIMEOUT_S = 2.0
REQUEST_TIMEOUT_S = 1.0
MAX_UNSENT_MB = 24  # per process: four ~5 MB replies not yet read, not five
# an analysis whose reply is ~5 MB, cheap to compute (the Scotch yoke's curves)
BIG = json.dumps({"mechanism": {"type": "scotch_yoke", "params": {"crank": 1}}, "samples": 67_000})


@pytest.fixture(scope="module")
def server():
    with serving(
        WEB_CONCURRENCY="2",
        SYNTH_WORKERS="2",
        SYNTH_WARM="0",
        SYNTH_WRITE_TIMEOUT_S=str(WRITE_TIMEOUT_S),
        SYNTH_REQUEST_TIMEOUT_S=str(REQUEST_TIMEOUT_S),
        SYNTH_MAX_UNSENT_MB=str(MAX_UNSENT_MB),
    ) as (port, proc):
        yield port, proc


def request(method: str, path: str, body: bytes = b"", *headers: bytes) -> bytes:
    head = b"".join(h + b"\r\n" for h in headers)
    length = b"Content-Length: %d\r\n" % len(body) if body else b""
    return b"%s %s HTTP/1.1\r\nHost: localhost\r\nContent-Type: application/json\r\n%s%s\r\n%s" % (
        method.encode(),
        path.encode(),
        head,
        length,
        body,
    )


def everything(s: socket.socket, seconds: float) -> tuple[bytes, str]:
    """What the server sends within ``seconds``, and how it ended: "closed" (its end of file),
    "reset", or "open" (still, at the end)."""
    got, end = b"", time.monotonic() + seconds
    try:
        while (left := end - time.monotonic()) > 0:
            s.settimeout(left)
            if not (chunk := s.recv(65536)):
                return got, "closed"
            got += chunk
    except TimeoutError:
        return got, "open"
    except ConnectionResetError:
        return got, "reset"
    finally:
        s.close()
    return got, "open"


def head_of(s: socket.socket, seconds: float) -> bytes:
    """A reply's status line and headers, lowercased (b"": none within ``seconds``)."""
    got, end = b"", time.monotonic() + seconds
    with contextlib.suppress(OSError):
        while b"\r\n\r\n" not in got and (left := end - time.monotonic()) > 0:
            s.settimeout(left)
            if not (chunk := s.recv(65536)):
                break
            got += chunk
    s.close()
    return got.partition(b"\r\n\r\n")[0].lower()


def statuses(data: bytes) -> list[int]:
    return [int(m) for m in re.findall(rb"(?i)HTTP/1\.1 (\d{3}) ", data)]


def rss_mb(pid: int) -> float:
    """The resident memory of ``pid`` and every process below it."""
    total = 0
    for p in {pid, *descendants(pid)}:
        with contextlib.suppress(OSError):
            total += int(Path(f"/proc/{p}/statm").read_text().split()[1])
    return total * 4096 / 1e6


# --- replies nobody reads --------------------------------------------------------------------


def test_replies_nobody_reads_are_dropped_and_their_memory_returned(server):
    """100 clients ask for a ~5 MB reply each and read none of it (eight waiting for their
    answer at a time). A process holds at most its limit of them, the rest get a 503 with
    Retry-After; each held one is dropped after the write timeout, its connection closed, and
    the servers' memory is back within 50 MB of where it was, write timeout + 1 s after the
    last answer."""
    port, proc = server
    for _ in range(4):  # each process's buffers and models for this request, read whole
        with contextlib.closing(http.client.HTTPConnection("127.0.0.1", port, timeout=30)) as c:
            c.request("POST", "/v1/analyze", BIG, {"Content-Type": "application/json"})
            assert len(c.getresponse().read()) > 4_000_000
    before = rss_mb(proc.pid)
    clients, waiting, held, got = [], [], [], Counter()
    deadline = time.monotonic() + 60

    def answered(wait: float) -> None:
        for c in select.select(waiting, [], [], wait)[0]:
            head = c.recv(4096, socket.MSG_PEEK)  # peeked, not read
            got[statuses(head)[0]] += 1
            got["with retry-after"] += b"\r\nretry-after: " in head.lower()
            got["held too many"] += b"not yet read" in head
            waiting.remove(c)
            if statuses(head) == [200]:
                held.append(c)

    for _ in range(100):
        c = socket.socket()
        c.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
        c.connect(("127.0.0.1", port))
        c.sendall(request("POST", "/v1/analyze", BIG.encode()))
        clients.append(c)
        waiting.append(c)
        while len(waiting) >= 8 and time.monotonic() < deadline:
            answered(1.0)
    while waiting and time.monotonic() < deadline:
        answered(1.0)
    time.sleep(WRITE_TIMEOUT_S + 1)  # from the last answer
    after = rss_mb(proc.pid)
    ends = Counter(everything(c, 0.2)[1] for c in held)  # read now: each one was reset
    for c in clients:
        c.close()
    assert after <= before + 50, f"{after:.0f} MB, from {before:.0f} MB before; {got}"
    assert not waiting, f"{len(waiting)} never answered"
    assert got[200] >= 8 and got["held too many"] > 0, got  # held, up to the limit
    assert got["with retry-after"] == got[503], got
    assert ends == {"reset": len(held)}, ends


# --- one reply to one request ----------------------------------------------------------------


@pytest.mark.parametrize(
    ("method", "path", "status"),
    [("GET", "/health", 200), ("GET", "/nope", 404), ("DELETE", "/health", 405)],
)
def test_a_request_answered_before_its_body_arrives_gets_one_reply_and_a_close(
    server, method, path, status
):
    """A body announced and never sent: the reply says ``Connection: close`` and the
    connection closes after it; nothing else comes (no 408 after the request timeout)."""
    port, _ = server
    s = socket.create_connection(("127.0.0.1", port))
    s.sendall(request(method, path, b"", b"Content-Length: 100"))
    got, end = everything(s, REQUEST_TIMEOUT_S + 2.0)
    assert statuses(got) == [status], got[:300]
    assert b"\r\nconnection: close\r\n" in got.lower() and end == "closed", (end, got[:300])


# --- headers ---------------------------------------------------------------------------------

PAGES = ("/app/", "/docs", "/redoc")


def test_every_reply_says_nosniff_and_names_no_server_and_the_pages_have_a_policy(server):
    port, _ = server
    asked = [
        request("GET", p)
        for p in (
            *PAGES,
            "/health",
            "/v1/mechanisms",
            "/app/app.js",
            "/openapi.json",
            "/favicon.ico",
            "/nope",
        )
    ]
    asked += [
        request("POST", "/v1/analyze", b"{}"),
        request("HEAD", "/health"),
        request("GET", "/health").replace(b"localhost", b"evil.example"),
        request("GET", "/health", b"", b"X-Pad: " + b"a" * 20_000),  # 431
        request("GET", "/health")[:30],  # never whole: 408
    ]
    for r in asked:
        s = socket.create_connection(("127.0.0.1", port))
        s.sendall(r)
        head = head_of(s, REQUEST_TIMEOUT_S + 2.0)
        what = r.split(b"\r\n")[0][:40]
        assert statuses(head), (what, head)
        assert b"\r\nx-content-type-options: nosniff" in head, (what, head)
        assert b"\r\nserver:" not in head, (what, head)
        policy = re.search(rb"\r\ncontent-security-policy: ([^\r]*)", head)
        if any(r.startswith(b"GET %s " % p.encode()) for p in PAGES):
            assert policy and b"frame-ancestors 'none'" in policy.group(1), (what, head)
            assert b"default-src 'self'" in policy.group(1), (what, head)


def test_a_host_other_than_the_services_names_is_refused(server):
    """Bound to loopback: the loopback names, with any port; another (a page elsewhere whose
    name resolves to 127.0.0.1) gets a 400 that says why."""
    port, _ = server
    conn = http.client.HTTPConnection("127.0.0.1", port, timeout=30)
    for host, status in [
        ("localhost", 200),
        (f"localhost:{port}", 200),
        ("127.0.0.1:1", 200),
        (f"[::1]:{port}", 200),
        ("LOCALHOST", 200),
        ("evil.example", 400),
        (f"evil.example:{port}", 400),
        ("127.0.0.2", 400),
        ("", 400),
    ]:
        conn.putrequest("GET", "/health", skip_host=True)
        conn.putheader("Host", host)
        conn.endheaders()
        r = conn.getresponse()
        body = json.loads(r.read())
        assert r.status == status, (host, body)
        if status == 400:
            assert body["detail"][0]["type"] == "host_not_allowed", body


def test_allowed_hosts_name_the_hosts_otherwise_any_away_from_loopback():
    loopback, other = ("127.0.0.1", 8000), ("10.0.0.5", 8000)
    assert Hosts(None).allow(other, b"anything.example")
    assert Hosts(None).allow(("testserver", 80), b"testserver")  # TestClient
    assert Hosts(None).allow(("::ffff:127.0.0.1", 80), b"localhost:80")
    assert not Hosts(None).allow(("::ffff:127.0.0.1", 80), b"evil.example")
    named = Hosts("api.example.com, localhost:8000")
    assert named.allow(other, b"API.example.com:443") and named.allow(loopback, b"localhost")
    assert not named.allow(loopback, b"127.0.0.1") and not named.allow(other, b"example.com")
    assert Hosts("*").allow(loopback, b"evil.example")


def test_forwarded_headers_are_trusted_only_from_the_proxies_named(monkeypatch):
    monkeypatch.delenv("FORWARDED_ALLOW_IPS", raising=False)
    plain = configure("api.main:app", "127.0.0.1", 0, Settings(_env_file=None))
    assert not plain.proxy_headers and not plain.server_header
    proxied = Settings(_env_file=None, FORWARDED_ALLOW_IPS="10.0.0.1")  # type: ignore[call-arg]
    config = configure("api.main:app", "127.0.0.1", 0, proxied)
    assert config.proxy_headers and config.forwarded_allow_ips == "10.0.0.1"


# --- an unexpected error ---------------------------------------------------------------------


@contextlib.contextmanager
def served_here(app: object) -> Iterator[int]:
    """``app`` on uvicorn with ``api.connection``'s connections, in a thread of this process
    (so a test can break it), on a free loopback port."""
    port = free_port()
    config = uvicorn.Config(
        app, host="127.0.0.1", port=port, http=Connection, lifespan="off", log_level="critical"
    )
    server = uvicorn.Server(config)
    thread = threading.Thread(target=server.run, daemon=True)
    thread.start()
    deadline = time.monotonic() + 30
    while not server.started and thread.is_alive() and time.monotonic() < deadline:
        time.sleep(0.02)
    try:
        assert server.started
        yield port
    finally:
        server.should_exit = True
        thread.join(10)


def test_an_unexpected_error_is_a_json_500_that_closes_its_connection_as_it_says(monkeypatch):
    import api.main

    def broken(**_: object) -> None:
        raise RuntimeError("a secret of the server's")

    monkeypatch.setattr(api.main, "Health", broken)  # /health fails inside its handler
    with served_here(api.main.app) as port:
        s = socket.create_connection(("127.0.0.1", port))
        s.sendall(request("GET", "/health"))  # HTTP/1.1: the connection is kept alive
        got, end = everything(s, 3.0)
        head, _, body = got.partition(b"\r\n\r\n")
        assert statuses(got) == [500], got[:300]
        assert b"\r\nconnection: close\r\n" in head.lower() and end == "closed", (end, head)
        assert b"application/json" in head and b"nosniff" in head, head
        assert json.loads(body)["detail"][0]["type"] == "internal_error"
        assert b"secret" not in got and b"Traceback" not in got
        with contextlib.closing(http.client.HTTPConnection("127.0.0.1", port, timeout=10)) as c:
            c.request("GET", "/v1/mechanisms")  # the server goes on
            assert c.getresponse().status == 200


# --- SIGTERM ---------------------------------------------------------------------------------


def probe(port: int) -> str:
    """A new connection's fate: "refused", "reset", "answered", or "hung" (nothing in 1 s)."""
    try:
        s = socket.create_connection(("127.0.0.1", port), timeout=1.0)
    except ConnectionRefusedError:
        return "refused"
    except ConnectionResetError:  # (in the backlog as the socket shut)
        return "reset"
    except TimeoutError:
        return "hung"
    try:  # (taken from the backlog as the socket shut: reset before a byte is read)
        s.sendall(request("GET", "/health"))
    except (ConnectionResetError, BrokenPipeError):
        return "reset"
    got, end = everything(s, 1.0)
    return "answered" if statuses(got) == [200] else "reset" if end != "open" else "hung"


@pytest.mark.parametrize("processes", ["2", "1"])
def test_after_sigterm_a_new_connection_is_refused_at_once_and_those_in_flight_answered(
    processes,
):
    """Syntheses under way when SIGTERM comes are answered; from 100 ms after it every new
    connection is refused, and none before it hangs: the listening socket is shut at once
    (uvicorn's supervisor kept it open while its processes drained)."""
    # no warm-up (a quicker start): the first synthesis builds what the others use
    with serving(WEB_CONCURRENCY=processes, SYNTH_WORKERS="2", SYNTH_WARM="0") as (port, proc):
        assert post(port, "/v1/synthesize", SYNTH, timeout=30) == 200  # a solver ready
        outcomes: list[int | str] = []

        def synthesis() -> None:
            outcomes.append(post(port, "/v1/synthesize", SYNTH, timeout=30))

        flying = [threading.Thread(target=synthesis) for _ in range(2)]
        for t in flying:
            t.start()
        time.sleep(0.2)
        t0 = time.monotonic()
        proc.send_signal(signal.SIGTERM)
        probes = []
        while (start := time.monotonic() - t0) < 0.6:
            fate = probe(port)
            probes.append((start, time.monotonic() - t0 - start, fate))
            time.sleep(0.01)
        for t in flying:
            t.join()
        assert outcomes == [200, 200], outcomes
        assert all(took < 0.5 for _, took, _ in probes), probes  # none hangs (1 s)
        assert all(fate == "refused" for start, _, fate in probes if start >= 0.1), probes
