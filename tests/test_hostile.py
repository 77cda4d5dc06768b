"""Hostile and careless requests against the real server over one keep-alive socket.

Each row of CASES is a request as raw bytes and what it must get: never a 5xx; a 4xx that
names the field where there is one; a small body (no echo of a large input); and the same
connection still answering afterwards (a 413 closes it, as it says, without reading the body).
"""

from __future__ import annotations

import http.client
import json
import re

import pytest

from .server import serving

SMALL = 4096  # bytes: the most an error body for a bad request may take

SCOTCH = '{"type":"scotch_yoke","params":{"crank":1}}'
SWEEP = '{"mechanism":' + SCOTCH + ',"vary":"crank","start":1,"stop":2'
WHIT = '{"time_ratio":1.6,"stroke":300,"mechanisms":[{"type":"whitworth",'
BIG_LIST = "[" + ",".join(["1"] * 1_000_000) + "]"  # 2 MB: under the byte limit, over the count

# (name, method, path, body, status, a field the 4xx must name, or None)
CASES = [
    ("NaN parameter", "POST", "/v1/analyze",
     '{"mechanism":{"type":"scotch_yoke","params":{"crank":NaN}}}', 422, "crank"),
    ("Infinity angle", "POST", "/v1/analyze",
     '{"mechanism":' + SCOTCH + ',"crank_angles_deg":[Infinity]}', 422, "crank_angles_deg"),
    ("-Infinity angle", "POST", "/v1/analyze",
     '{"mechanism":' + SCOTCH + ',"crank_angles_deg":[1,-Infinity]}', 422, "crank_angles_deg"),
    ("NaN time ratio", "POST", "/v1/synthesize", '{"time_ratio":NaN,"stroke":1}', 422,
     "time_ratio"),
    ("Infinity budget", "POST", "/v1/synthesize",
     '{"time_ratio":1.5,"stroke":1,"time_budget_ms":Infinity}', 422, "time_budget_ms"),
    ("NaN sweep start", "POST", "/v1/sweep",
     '{"mechanism":' + SCOTCH + ',"vary":"crank","start":NaN,"stop":2}', 422, "start"),
    ("NaN in a bounds pair", "POST", "/v1/synthesize",
     WHIT + '"bounds":{"crank":[NaN,100]}}]}', 422, "crank"),
    ("1e309", "POST", "/v1/synthesize", '{"time_ratio":1.5,"stroke":1e309}', 422, "stroke"),
    ("lone surrogate type", "POST", "/v1/analyze",
     '{"mechanism":{"type":"\\ud800","params":{}}}', 422, "mechanism"),
    ("lone surrogate parameter", "POST", "/v1/analyze",
     '{"mechanism":{"type":"scotch_yoke","params":{"\\ud800":1}}}', 422, "params"),
    ("lone surrogate vary", "POST", "/v1/sweep",
     '{"mechanism":' + SCOTCH + ',"vary":"\\ud800","start":1,"stop":2}', 422, "vary"),
    ("unknown vary", "POST", "/v1/sweep",
     '{"mechanism":' + SCOTCH + ',"vary":"bogus","start":1,"stop":2}', 422, "vary"),
    ("start > stop", "POST", "/v1/sweep",
     '{"mechanism":' + SCOTCH + ',"vary":"crank","start":3,"stop":2}', 422, "stop"),
    ("samples and angles", "POST", "/v1/analyze",
     '{"mechanism":' + SCOTCH + ',"crank_angles_deg":[1],"samples":3}', 422, "samples"),
    ("bounds reversed", "POST", "/v1/synthesize", WHIT + '"bounds":{"crank":[200,100]}}]}',
     422, "crank"),
    ("fixed and bounded", "POST", "/v1/synthesize",
     WHIT + '"fixed":{"crank":50},"bounds":{"crank":[20,100]}}]}', 422, "bounds"),
    ("no mechanisms", "POST", "/v1/synthesize", '{"time_ratio":1.5,"stroke":1,"mechanisms":[]}',
     422, "mechanisms"),
    ("unknown type", "POST", "/v1/synthesize",
     '{"time_ratio":1.5,"stroke":1,"mechanisms":[{"type":"cam"}]}', 422, "mechanisms"),
    ("unknown field", "POST", "/v1/analyze", '{"mechanism":' + SCOTCH + ',"colour":"red"}', 422,
     "colour"),
    ("string for a number", "POST", "/v1/synthesize", '{"time_ratio":"1.5","stroke":1}', 422,
     "time_ratio"),
    ("huge integer", "POST", "/v1/synthesize",
     '{"time_ratio":1.5,"stroke":1,"max_candidates":' + "9" * 400 + "}", 422, "max_candidates"),
    ("unknown objective", "POST", "/v1/synthesize",
     '{"time_ratio":1.5,"stroke":1,"objective":"cheapest"}', 422, "objective"),
    ("negative tolerance", "POST", "/v1/analyze",
     '{"mechanism":' + SCOTCH + ',"tolerance":{"relative":-0.1}}', 422, "relative"),
    ("fluctuation limit below 1", "POST", "/v1/synthesize",
     '{"time_ratio":1.5,"stroke":1,"objective":"uniform_cutting_speed",'
     '"max_working_speed_fluctuation":0.5}', 422, "max_working_speed_fluctuation"),
    ("a design that cannot run", "POST", "/v1/analyze",
     '{"mechanism":{"type":"crank_shaper","params":{"crank":300,"pivot_distance":240,'
     '"lever":450}}}', 422, "crank"),
    ("10^6 angles, 2 MB", "POST", "/v1/analyze",
     '{"mechanism":' + SCOTCH + ',"crank_angles_deg":' + BIG_LIST + "}", 422, "crank_angles_deg"),
    ("not JSON", "POST", "/v1/analyze", "{mechanism: scotch}", 422, None),
    ("invalid UTF-8", "POST", "/v1/analyze", b'{"mechanism":"\xff\xfe"}', 422, None),
    ("nested 100 000 deep", "POST", "/v1/analyze", "[" * 100_000 + "]" * 100_000, 422, None),
    ("null body", "POST", "/v1/synthesize", "null", 422, None),
    ("empty body", "POST", "/v1/synthesize", "", 422, None),
    ("a JSON list", "POST", "/v1/synthesize", "[1,2,3]", 422, None),
    ("5 MB body", "POST", "/v1/analyze", 5_000_000, 413, None),  # announced, not sent
    ("wrong method", "GET", "/v1/synthesize", None, 405, None),
    ("unknown path", "GET", "/v2/anything", None, 404, None),
    ("unknown type in a path", "GET", "/v1/mechanisms/%ED%A0%80", None, 404, "type"),
    ("HEAD /health", "HEAD", "/health", None, 200, None),
    ("sweep, fine", "POST", "/v1/sweep", SWEEP + "}", 200, None),
]  # fmt: skip


@pytest.fixture(scope="module")
def port():
    with serving() as (port, _):
        yield port


def send(conn: http.client.HTTPConnection, method: str, path: str, body, chunked=False):
    """The request (a body given as a number: only a Content-Length that announces it) and
    its response with its body."""
    if isinstance(body, int):
        conn.putrequest(method, path)
        conn.putheader("Content-Type", "application/json")
        conn.putheader("Content-Length", str(body))
        conn.endheaders()
    else:
        data = body.encode("utf-8", "surrogatepass") if isinstance(body, str) else body
        headers = {"Content-Type": "application/json"} if data is not None else {}
        conn.request(method, path, data, headers, encode_chunked=chunked)
    r = conn.getresponse()
    return r, r.read()


def located(detail: list[dict], field: str) -> bool:
    return any(field in map(str, d["loc"]) for d in detail)


def test_hostile_requests_get_a_4xx_that_names_the_field_on_a_connection_that_lasts(port):
    conn = http.client.HTTPConnection("127.0.0.1", port, timeout=60)
    failures = []
    for name, method, path, body, status, field in CASES:
        r, raw = send(conn, method, path, body)
        problems = []
        if r.status != status:
            problems.append(f"status {r.status}, not {status}: {raw[:300]!r}")
        if status >= 400 and len(raw) > SMALL:
            problems.append(f"a {len(raw)}-byte error body")
        if status >= 400 and method != "HEAD":
            detail = json.loads(raw)["detail"]
            if field and not located(detail, field):
                problems.append(f"no loc names {field}: {detail}")
        if r.getheader("connection", "").lower() == "close":
            if status != 413:
                problems.append("the server closed the connection")
            conn.close()
            conn = http.client.HTTPConnection("127.0.0.1", port, timeout=60)
        health, _ = send(conn, "GET", "/health", None)
        if health.status != 200:
            problems.append(f"/health on the same connection: {health.status}")
        failures += [f"{name}: {p}" for p in problems]
    assert not failures, "\n".join(failures)


def test_a_chunked_body_past_the_limit_is_refused_without_reading_it_all(port):
    conn = http.client.HTTPConnection("127.0.0.1", port, timeout=60)
    sent = 0

    def chunks():
        nonlocal sent
        for _ in range(200):  # 12.8 MB, if all were read
            sent += 65536
            yield b"1" * 65536

    try:
        r, raw = send(conn, "POST", "/v1/analyze", chunks(), chunked=True)
        assert r.status == 413 and json.loads(raw)["detail"][0]["type"] == "body_too_large"
    except (BrokenPipeError, ConnectionResetError):
        pass  # the server answered and closed while the client still sent: also a refusal
    assert sent < 200 * 65536


def test_the_contract_states_the_refusals_and_the_docs_load_nothing_from_elsewhere(port):
    from api.main import app

    for path in ("/v1/analyze", "/v1/synthesize", "/v1/sweep"):
        responses = app.openapi()["paths"][path]["post"]["responses"]
        assert {"413", "422", "503"} <= set(responses), path
        assert "Retry-After" in responses["503"]["headers"]
    conn = http.client.HTTPConnection("127.0.0.1", port, timeout=60)
    for page in ("/docs", "/redoc"):
        r, html = send(conn, "GET", page, None)
        assert r.status == 200
        refs = re.findall(rb'(?:src|href)="([^"]*)"', html)
        assert refs and all(ref.startswith(b"/") for ref in refs), refs
        assert not re.search(rb"https?://", html), page  # no host: works without a network
        for ref in refs:  # each script, style and icon comes from the service itself
            got, body = send(conn, "GET", ref.decode(), None)
            assert got.status == 200 and body, ref
