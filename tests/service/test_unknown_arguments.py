"""An argument nobody knows is an error at every edge, for every operation: the library raises
(a TypeError that names it), the service answers 422 naming the field, the command line exits
2 naming the option. Each call is otherwise valid: without the stranger it succeeds."""

import pytest
from fastapi.testclient import TestClient

import synth
from api.main import app

from ..library.test_cli import run

WHITWORTH = {"crank": 75.0, "pivot_distance": 50.0, "lever": 150.0, "connecting_rod": 200.0}
FLAGS = [x for k, v in WHITWORTH.items() for x in ("-p", f"{k}={v:g}")]
DESIGN = {"mechanism": {"type": "whitworth", "params": WHITWORTH}}
# each operation: its library call, its endpoint and body, its command line
OPERATIONS = {
    "synthesize": (
        lambda **kw: synth.synthesize(1.6, 300.0, 20.0, ["whitworth"], **kw),
        (
            "/v1/synthesize",
            {"time_ratio": 1.6, "stroke": 300.0, "mechanisms": [{"type": "whitworth"}]},
        ),
        ["synthesize", "--time-ratio", "1.6", "--stroke", "300", "--type", "whitworth"],
    ),
    "analyze": (
        lambda **kw: synth.analyze("whitworth", WHITWORTH, **kw),
        ("/v1/analyze", DESIGN),
        ["analyze", "whitworth", *FLAGS],
    ),
    "sweep": (
        lambda **kw: synth.sweep("whitworth", WHITWORTH, "pivot_distance", 40.0, 60.0, 3, **kw),
        (
            "/v1/sweep",
            {**DESIGN, "vary": "pivot_distance", "start": 40.0, "stop": 60.0, "points": 3},
        ),
        [
            "sweep",
            "whitworth",
            *FLAGS,
            "--vary",
            "pivot_distance",
            "--start",
            "40",
            "--stop",
            "60",
            "--points",
            "3",
        ],
    ),
    "export": (
        lambda **kw: synth.export("whitworth", WHITWORTH, **kw),
        ("/v1/export", DESIGN),
        ["export", "whitworth", *FLAGS],
    ),
    "report": (
        lambda **kw: synth.report("whitworth", WHITWORTH, **kw),
        ("/v1/report", DESIGN),
        ["report", "whitworth", *FLAGS],
    ),
}


@pytest.fixture(scope="module")
def client():
    with TestClient(app) as c:
        yield c


@pytest.mark.parametrize("op", OPERATIONS)
def test_the_library_refuses_an_unknown_keyword(op):
    call, _, _ = OPERATIONS[op]
    call()
    with pytest.raises(TypeError, match="colour"):
        call(colour="red")


@pytest.mark.parametrize("op", OPERATIONS)
def test_the_service_refuses_an_unknown_field(client, op):
    _, (path, body), _ = OPERATIONS[op]
    assert client.post(path, json=body).status_code == 200
    r = client.post(path, json={**body, "colour": "red"})
    assert r.status_code == 422
    assert [e["loc"][-1] for e in r.json()["detail"]] == ["colour"]


@pytest.mark.parametrize("op", OPERATIONS)
def test_the_command_line_refuses_an_unknown_option(op, tmp_path):
    _, _, args = OPERATIONS[op]
    if op in ("export", "report"):  # a file, not the terminal
        args = [*args, "-o", str(tmp_path / op)]
    assert run(*args).returncode == 0
    r = run(*args, "--colour", "red")
    assert r.returncode == 2 and "--colour" in r.stderr
