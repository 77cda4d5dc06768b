"""Each rule on what a request means lives in synth, once: the API checks only the shape of a
request, and answers a request synth refuses with synth's own message, located in the body.

One case per rule, asked both ways: through Python (the exception) and over HTTP (the 422).
"""

import pytest
from fastapi.testclient import TestClient

import synth
from api.main import app

SHAPER = {"crank": 40.0, "pivot_distance": 160.0, "lever": 240.0}
SWEEP = {"mechanism": {"type": "crank_shaper", "params": SHAPER}, "start": 10.0, "stop": 60.0}

# (rule, the Python call, the same request over HTTP, where the 422 puts it in the body)
RULES = [
    (
        "curves at given angles or evenly spaced, not both",
        lambda: synth.analyze("crank_shaper", SHAPER, crank_angles_deg=[0.0], samples=4),
        (
            "/v1/analyze",
            {
                "mechanism": {"type": "crank_shaper", "params": SHAPER},
                "crank_angles_deg": [0.0],
                "samples": 4,
            },
        ),
        ["body", "samples"],
    ),
    (
        "pins are at the curves' angles",
        lambda: synth.analyze("crank_shaper", SHAPER, include=["pins"]),
        (
            "/v1/analyze",
            {"mechanism": {"type": "crank_shaper", "params": SHAPER}, "include": ["pins"]},
        ),
        ["body", "include"],
    ),
    (
        "a part is fixed or bounded, not both",
        lambda: synth.synthesize(
            1.6,
            300.0,
            mechanisms=[
                {
                    "type": "whitworth",
                    "fixed": {"lever": 150.0},
                    "bounds": {"lever": (100.0, 200.0)},
                }
            ],
        ),
        (
            "/v1/synthesize",
            {
                "time_ratio": 1.6,
                "stroke": 300.0,
                "mechanisms": [
                    {
                        "type": "whitworth",
                        "fixed": {"lever": 150.0},
                        "bounds": {"lever": [100.0, 200.0]},
                    }
                ],
            },
        ),
        ["body", "mechanisms", 0, "whitworth", "bounds", "lever"],
    ),
    (
        "bounds are ordered",
        lambda: synth.synthesize(
            1.6,
            300.0,
            mechanisms=[
                {"type": "scotch_yoke"},
                {"type": "whitworth", "bounds": {"crank": (90.0, 60.0)}},
            ],
        ),
        (
            "/v1/synthesize",
            {
                "time_ratio": 1.6,
                "stroke": 300.0,
                "mechanisms": [
                    {"type": "scotch_yoke"},
                    {"type": "whitworth", "bounds": {"crank": [90.0, 60.0]}},
                ],
            },
        ),
        ["body", "mechanisms", 1, "whitworth", "bounds", "crank"],
    ),
    (
        "a sweep's start ≤ stop",
        lambda: synth.sweep("crank_shaper", SHAPER, "crank", 60.0, 50.0),
        ("/v1/sweep", {**SWEEP, "vary": "crank", "start": 60.0, "stop": 50.0}),
        ["body", "stop"],
    ),
    (
        "a sweep varies a parameter of the type",
        lambda: synth.sweep("crank_shaper", SHAPER, "colour", 10.0, 60.0),
        ("/v1/sweep", {**SWEEP, "vary": "colour"}),
        ["body", "vary"],
    ),
]


@pytest.fixture(scope="module")
def client():
    with TestClient(app) as c:
        yield c


@pytest.mark.parametrize(("rule", "call", "request_", "loc"), RULES, ids=[r[0] for r in RULES])
def test_a_rule_says_the_same_through_python_and_http(client, rule, call, request_, loc):
    with pytest.raises(synth.SynthError) as python:
        call()
    path, body = request_
    r = client.post(path, json=body)
    assert r.status_code == 422, r.text
    (detail,) = r.json()["detail"]
    assert detail["loc"] == loc
    assert detail["msg"] == python.value.msg
