"""A client generated from the service's /openapi.json by openapi-python-client, as a design
tool would make one: it is generated without a warning (every schema typed, none dropped),
and a synthesis with a load, an analysis and a sweep go through it and come back as its
typed models, their numbers those of the brute-force simulation."""

import importlib
import json
import os
import subprocess
import sys
import sysconfig
from pathlib import Path

import pytest
from fastapi.testclient import TestClient

from api.config import Settings
from api.engine import Engine
from api.main import app
from api.routers.common import engine

from ..support import bruteforce

PACKAGE = "quick_return_mechanism_synthesis_client"
WHITWORTH = {"crank": 75.0, "pivot_distance": 50.0, "lever": 150.0, "connecting_rod": 200.0}
LOAD = {"length_unit": "mm", "crank_rpm": 40.0, "cutting_force": 2000.0, "slider_mass": 20.0}


@pytest.fixture(scope="module")
def generated(tmp_path_factory):
    """The client package, generated into a temporary folder and imported, and what the
    generator printed."""
    out = tmp_path_factory.mktemp("client")
    spec = out / "openapi.json"
    spec.write_text(json.dumps(app.openapi()))
    scripts = sysconfig.get_path("scripts")  # the generator, and the ruff it formats with
    env = {**os.environ, "PATH": scripts + os.pathsep + os.environ.get("PATH", "")}
    run = subprocess.run(
        [
            Path(scripts) / "openapi-python-client",
            "generate",
            "--path",
            str(spec),
            "--output-path",
            str(out / PACKAGE),
            "--meta",
            "none",
        ],
        capture_output=True,
        text=True,
        env=env,
        check=False,
    )
    assert run.returncode == 0, run.stdout + run.stderr
    sys.path.insert(0, str(out))
    try:
        yield importlib.import_module(PACKAGE), run.stdout + run.stderr
    finally:
        sys.path.remove(str(out))
        for name in [m for m in sys.modules if m.split(".")[0] == PACKAGE]:
            del sys.modules[name]


@pytest.fixture(scope="module")
def client(generated):
    """The generated client on the app in process (a TestClient is an httpx client), with an
    engine that allows the least peak torque its whole search."""
    package, _ = generated
    roomy = Engine(Settings(max_budget_ms=60_000.0))
    app.dependency_overrides[engine] = lambda: roomy
    try:
        with TestClient(app) as http:
            c = package.Client(base_url="http://testserver")
            c.set_httpx_client(http)
            yield c
    finally:
        del app.dependency_overrides[engine]
        roomy.close()


def module(name):
    return importlib.import_module(f"{PACKAGE}.{name}")


def test_the_client_is_generated_without_a_warning(generated):
    _, printed = generated
    assert "warning" not in printed.lower(), printed
    models = module("models")
    for name in (
        "SynthesisResult",
        "AnalyzeResponse",
        "SweepResult",
        "TimeRatioRange",
        "DeadCentres",
        "Loads",
    ):
        assert hasattr(models, name), name


def test_a_least_peak_torque_synthesis_through_the_client(client):
    models = module("models")
    call = module("api.synthesis.synthesize_v1_synthesize_post")
    body = models.SynthesizeRequest.from_dict(
        {
            "time_ratio": 1.6,
            "stroke": 300.0,
            "min_transmission_angle_deg": 20.0,
            "mechanisms": [{"type": "whitworth"}],
            "objective": "min_peak_torque",
            "load": LOAD,
            "time_budget_ms": 60_000.0,
        }
    )
    r = call.sync(client=client, body=body)
    assert isinstance(r, models.SynthesisResult), r
    c = r.candidates[0]
    assert isinstance(c, models.Candidate) and c.certified
    assert c.objective_value == c.loads.torque.max_  # the generator adds _ to a builtin
    brute = bruteforce.simulate("whitworth", c.params.to_dict())
    assert brute["time_ratio"] == pytest.approx(1.6, rel=1e-9)
    assert brute["stroke"] == pytest.approx(300.0, rel=1e-9)


def test_an_analysis_and_a_sweep_through_the_client(client):
    models = module("models")
    analyze = module("api.analysis.analyze_v1_analyze_post")
    body = models.AnalyzeRequest.from_dict(
        {"mechanism": {"type": "whitworth", "params": WHITWORTH}}
    )
    a = analyze.sync(client=client, body=body)
    assert isinstance(a, models.AnalyzeResponse), a
    brute = bruteforce.simulate("whitworth", WHITWORTH)
    assert a.time_ratio == pytest.approx(brute["time_ratio"], rel=1e-9)
    assert isinstance(a.extremes, models.DeadCentres)
    stroke = a.extremes.max_.position - a.extremes.min_.position
    assert stroke == pytest.approx(brute["stroke"], rel=1e-9)
    sweep = module("api.analysis.sweep_v1_sweep_post")
    body = models.SweepRequest.from_dict(
        {
            "mechanism": {"type": "whitworth", "params": WHITWORTH},
            "vary": "pivot_distance",
            "start": 40.0,
            "stop": 60.0,
            "points": 3,
        }
    )
    s = sweep.sync(client=client, body=body)
    assert isinstance(s, models.SweepResult), s
    assert isinstance(s.time_ratio_range, models.TimeRatioRange)
    for value, ratio in zip(s.values, s.time_ratio, strict=True):
        brute = bruteforce.simulate("whitworth", {**WHITWORTH, "pivot_distance": value})
        assert ratio == pytest.approx(brute["time_ratio"], rel=1e-9)
    assert s.time_ratio_range.max_.time_ratio == pytest.approx(max(s.time_ratio), rel=1e-15)
