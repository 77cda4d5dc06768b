"""HTTP tests of every endpoint (TestClient, the shipped process-pool engine)."""

import dataclasses
import inspect
import io
import json
import math

import numpy as np
import pytest
from fastapi.routing import APIRoute
from fastapi.testclient import TestClient
from pydantic import TypeAdapter

import synth
from api.config import Settings
from api.engine import Engine
from api.main import app
from api.routers import analyze, atlas, mechanisms, sweep, synthesize
from api.routers.analyze import encoded
from api.routers.common import engine
from api.schemas import AnalyzeResponse
from benchmarks.analysis import DESIGNS  # a valid design of each type
from synth.mechanisms import all_types, get
from synth.requests import ANALYSIS_INCLUDE

from ..support import bruteforce
from ..support import reference_cases as ref


@pytest.fixture(scope="module")
def client():
    with TestClient(app) as c:
        yield c


def design(mtype, **params):
    return {"type": mtype, "params": params}


def test_every_endpoint_dependency_and_handler_is_a_coroutine():
    """None runs in a worker thread (``api.main``): that hop is a tenth of a millisecond."""
    calls = [r.dependant.call for r in app.routes if isinstance(r, APIRoute)]
    calls += [r.dependant.call for m in (analyze, sweep, synthesize) for r in m.router.routes]
    calls += [mechanisms.list_mechanisms, mechanisms.get_mechanism, atlas.get_atlas, engine]
    calls += [h for k, h in app.exception_handlers.items() if k not in (500, Exception)]
    plain = [getattr(c, "__name__", c) for c in calls if not inspect.iscoroutinefunction(c)]
    assert not plain, plain


def test_health(client):
    r = client.get("/health")
    assert r.status_code == 200
    assert r.json() == {"status": "ok", "version": synth.__version__}


def test_mechanisms_listing_comes_from_the_registry(client):
    r = client.get("/v1/mechanisms")
    assert r.status_code == 200
    body = r.json()
    assert [m["type"] for m in body] == list(all_types())
    for m in body:
        reg = get(m["type"])
        assert [q["name"] for q in m["parameters"]] == list(reg.names)
        assert m["validity"] == [c.text for c in reg.conditions]
        assert m["quick_return"] == (m["type"] != "scotch_yoke")
        assert m["sources"]
        for q in m["parameters"]:
            assert q["symbol"] and q["description"]


def test_one_mechanism_and_defaults(client):
    m = client.get("/v1/mechanisms/crank_shaper").json()
    params = {q["name"]: q for q in m["parameters"]}
    assert params["crank"]["required"] and params["crank"]["symbol"] == "r2"
    assert params["ram_link"]["required"] is False and params["ram_link"]["default"] == 0.0
    assert params["ram_height"]["default_rule"].startswith("lever·cos ψmax")


def test_unknown_type_is_404_with_the_known_types(client):
    r = client.get("/v1/mechanisms/slider_crank")
    assert r.status_code == 404
    (err,) = r.json()["detail"]
    assert err["loc"] == ["path", "type"]
    assert "known types: scotch_yoke" in err["msg"]


def test_analyze_slotted_lever_lab_table(client):
    body = {"mechanism": design("crank_shaper", **ref.SLOTTED_LEVER_LAB_PARAMS), "samples": 36}
    r = client.post("/v1/analyze", json=body)
    assert r.status_code == 200
    out = r.json()
    x = ref.SLOTTED_LEVER_LAB_SCALE_ZERO + np.array(out["curves"]["position"])
    np.testing.assert_allclose(x, ref.SLOTTED_LEVER_LAB_THEORY[:-1], atol=0.005 + 1e-9)
    assert out["time_ratio"] == pytest.approx(1.38340, abs=5e-6)
    assert out["extremes"]["max"]["crank_angle_deg"] == pytest.approx(104.48, abs=0.005)
    assert out["grashof"] is None and out["reversals"] == 2


def test_analyze_slotted_link_lab_scotch_yoke(client):
    body = {"mechanism": design("scotch_yoke", crank=35.0), "crank_angles_deg": [20.0]}
    out = client.post("/v1/analyze", json=body).json()
    assert 35.0 - out["curves"]["position"][0] == pytest.approx(2.11, abs=0.005)
    assert -out["curves"]["velocity"][0] == pytest.approx(11.97, abs=0.005)
    assert -out["curves"]["acceleration"][0] == pytest.approx(32.89, abs=0.005)
    assert out["time_ratio"] == pytest.approx(1.0) and out["transmission"]["min_deg"] == 90.0


def test_analyze_drag_link_project_at_60deg(client):
    p = {**ref.DRAG_LINK_PROJECT, "coupler": 0.2504}
    body = {
        "mechanism": design("drag_link_slider", **p),
        "crank_speed": 10.0,
        "crank_angles_deg": [60.0],
    }
    out = client.post("/v1/analyze", json=body).json()
    h = 1e-4
    s = bruteforce.position("drag_link_slider", p, math.radians(60) + np.array([-h, 0.0, h]))
    assert out["curves"]["velocity"][0] == pytest.approx((s[2] - s[0]) / (2 * h) * 10, rel=1e-7)
    assert out["curves"]["crank_angle_deg"] == [60.0]
    joints = {j["joint"]: j for j in out["transmission"]["joints"]}
    assert joints["coupler-follower"]["min_deg"] == pytest.approx(27.01, abs=0.01)
    assert out["grashof"] == "drag-link"


def test_analyze_without_curves_has_no_curves(client):
    body = {
        "mechanism": design("whitworth", crank=75, pivot_distance=50, lever=150, connecting_rod=200)
    }
    out = client.post("/v1/analyze", json=body).json()
    assert "curves" not in out and "motion" not in out and "sensitivities" not in out
    assert out["time_ratio"] == pytest.approx(2.73524, abs=5e-6)
    assert out["stroke"] == pytest.approx(300.0, rel=1e-12)


def test_analyze_includes_motion_and_tolerances_when_asked(client):
    body = {
        "mechanism": design("scotch_yoke", crank=35.0),
        "include": ["motion", "envelope"],
        "tolerance": {"relative": 1e-3},
    }
    out = client.post("/v1/analyze", json=body).json()
    assert out["motion"]["working_speed_fluctuation"]["whole"] == pytest.approx(math.pi / 2)
    peak = out["motion"]["peak_acceleration"]
    assert peak["working_stroke"] == pytest.approx(0.5)
    assert peak["return_stroke"] == pytest.approx(0.5)
    # at the dead centres (θ = 0 and 180°), where the yoke turns
    at = sorted((peak["working_stroke_at_deg"], peak["return_stroke_at_deg"]))
    assert at == pytest.approx([0.0, 180.0], abs=1e-9)
    sens = out["sensitivities"]  # the stroke is 2r: ± 2 × 1e-3 × 35
    assert sens["stroke"] == {"crank": pytest.approx(2.0)}
    assert sens["deviation"]["stroke"] == pytest.approx(0.07)
    assert sens["tolerance"] == {"absolute": None, "relative": 1e-3}
    # the crank pin's circle holds everything: the yoke's pin travels along its diameter
    assert out["envelope"] == {
        "x": [-35.0, 35.0],
        "y": [-35.0, 35.0],
        "width": 70.0,
        "height": 70.0,
        "link_length_sum": 35.0,
    }


def test_analyze_gives_the_pins_at_the_curves_angles_when_asked(client):
    p = {**ref.DRAG_LINK_PROJECT, "coupler": 0.2504}
    body = {
        "mechanism": design("drag_link_slider", **p),
        "crank_angles_deg": [0, 90, 180],
        "include": ["pins"],
    }
    r = client.post("/v1/analyze", json=body)
    assert r.status_code == 200, r.text
    pins = r.json()["curves"]["pins"]
    j = synth.joints("drag_link_slider", p, [0.0, 90.0, 180.0])
    assert list(pins) == list(j) == ["O2", "A", "O4", "B", "C", "D"]  # the drawing's order
    for name, xy in j.items():
        assert set(pins[name]) == {"x", "y"}
        assert len(pins[name]["x"]) == len(pins[name]["y"]) == 3
        assert pins[name] == {"x": xy[:, 0].tolist(), "y": xy[:, 1].tolist()}, name
    assert pins["A"]["x"][0] == p["crank"] and pins["A"]["y"][1] == p["crank"]


def test_analyze_pins_without_angles_is_422_at_include(client):
    body = {"mechanism": design("scotch_yoke", crank=35.0), "include": ["pins"]}
    r = client.post("/v1/analyze", json=body)
    assert r.status_code == 422, r.text
    (d,) = r.json()["detail"]
    assert d["loc"][-1] == "include" and d["loc"] == ["body", "include"]
    assert "needs crank_angles_deg or samples" in d["msg"]


def test_analyze_has_no_pins_unless_asked(client):
    body = {
        "mechanism": design("scotch_yoke", crank=35.0),
        "samples": 4,
        "include": ["motion", "envelope"],
    }
    r = client.post("/v1/analyze", json=body)
    assert r.status_code == 200, r.text
    assert "pins" not in r.json()["curves"] and '"pins"' not in r.text
    asked = client.post("/v1/analyze", json={**body, "include": ["pins"]})
    assert list(asked.json()["curves"]["pins"]) == ["O2", "B", "yoke"]  # the same, asked


TYPED = ("type", "$ref", "anyOf", "allOf", "oneOf", "items", "const", "enum")


def test_every_field_a_client_reads_is_typed_in_the_openapi(client):
    """A client generated from /openapi.json types each field by its schema: none is left
    untyped (a generic's fields were, and a generator dropped the sweep's reply for it; a
    refusal's echo of the input is typed as what it may echo)."""
    schemas = client.get("/openapi.json").json()["components"]["schemas"]
    untyped = [
        (name, field)
        for name, schema in schemas.items()
        for field, prop in schema.get("properties", {}).items()
        if not any(k in prop for k in TYPED)
    ]
    assert untyped == []
    sweep = schemas["SweepResult"]["properties"]["time_ratio_range"]["anyOf"]
    assert {"$ref": "#/components/schemas/TimeRatioRange"} in sweep
    assert schemas["TimeRatioRange"]["properties"]["min"] == {
        "$ref": "#/components/schemas/Extremum"
    }
    extremes = schemas["AnalyzeResponse"]["properties"]["extremes"]
    assert extremes == {"$ref": "#/components/schemas/DeadCentres"}


def test_the_openapi_shows_the_pins_and_forces_for_an_analysis_only(client):
    schemas = client.get("/openapi.json").json()["components"]["schemas"]
    include = schemas["AnalyzeRequest"]["properties"]["include"]
    assert include["items"]["enum"] == ["motion", "sensitivities", "envelope", "pins", "forces"]
    assert "pins (with crank_angles_deg or samples" in include["description"]
    assert "forces (with a load and curves" in include["description"]
    pins = schemas["Curves"]["properties"]["pins"]
    assert {"$ref": "#/components/schemas/PinPath"} in [
        s.get("additionalProperties") for s in pins["anyOf"]
    ]
    assert set(schemas["PinPath"]["required"]) == {"x", "y"}
    # a candidate has no curves: synthesis does not offer them
    offered = schemas["SynthesizeRequest"]["properties"]["include"]["items"]["enum"]
    assert "pins" not in offered and "forces" not in offered


def test_invalid_design_names_each_parameter(client):
    body = {
        "mechanism": design("whitworth", crank=75, pivot_distance=50, lever=150, connecting_rod=135)
    }
    r = client.post("/v1/analyze", json=body)
    assert r.status_code == 422
    detail = r.json()["detail"]
    assert [d["loc"] for d in detail] == [  # in the type's order of its parameters
        ["body", "mechanism", "params", "lever"],
        ["body", "mechanism", "params", "connecting_rod"],
    ]
    assert detail[0]["msg"].startswith("connecting_rod 135 ≤ lever 150")
    assert detail[0]["type"] == "invalid_design"


def test_synthesize_drag_link_project(client):
    spec = {"type": "drag_link_slider", "fixed": {**ref.DRAG_LINK_FIXED, "connecting_rod": 0.3}}
    body = {"time_ratio": 1.5, "stroke": 0.3, "mechanisms": [spec]}
    out = client.post("/v1/synthesize", json=body).json()
    couplers = [c["params"]["coupler"] for c in out["candidates"]]
    assert couplers == pytest.approx([0.2504, 0.1544], abs=1e-4)
    assert out["complete"] and out["infeasible"] == []
    assert all(c["verified"] and c["method"] == "closed_form" for c in out["candidates"])
    body["min_transmission_angle_deg"] = 20.0
    out = client.post("/v1/synthesize", json=body).json()
    assert [c["params"]["coupler"] for c in out["candidates"]] == pytest.approx([0.2504], abs=1e-4)


def test_the_default_answer_is_the_front_with_families(client):
    body = {"time_ratio": 1.6, "stroke": 300.0, "min_transmission_angle_deg": 40.0}
    out = client.post("/v1/synthesize", json=body).json()
    whitworth = [c for c in out["candidates"] if c["type"] == "whitworth"]
    assert len(whitworth) >= 3
    assert [c["front"]["index"] for c in whitworth] == list(range(len(whitworth)))[::-1]
    assert whitworth[0]["front"]["ends"] == ["max_transmission_angle"]
    assert whitworth[-1]["front"]["ends"] == ["min_size"]
    assert {c["front"]["measure"] for c in out["candidates"]} == {"link_length_sum"}
    (shaper,) = [c for c in out["candidates"] if c["type"] == "crank_shaper"]
    assert shaper["family"]["free"] == ["crank"] and "pivot_distance" in shaper["family"]["tied"]
    schema = client.get("/openapi.json").json()["components"]["schemas"]
    request = schema["SynthesizeRequest"]["properties"]
    assert request["objective"]["default"] == "pareto"
    assert set(request["objective"]["enum"]) == {
        "pareto",
        "max_transmission_angle",
        "min_size",
        "uniform_cutting_speed",
        "min_peak_acceleration",
        "min_peak_torque",
    }
    assert request["max_working_speed_fluctuation"]["anyOf"][0]["minimum"] == 1
    assert {"front", "family", "envelope", "motion", "sensitivities", "loads"} <= set(
        schema["Candidate"]["properties"]
    )


def test_a_motion_objective_answers_with_each_candidates_motion(client):
    body = {
        "time_ratio": 1.6,
        "stroke": 300.0,
        "min_transmission_angle_deg": 20.0,
        "objective": "uniform_cutting_speed",
        "mechanisms": [{"type": "whitworth"}],
    }
    out = client.post("/v1/synthesize", json=body).json()
    c = out["candidates"][0]
    assert c["objective_value"] == c["motion"]["working_speed_fluctuation"]["middle"]
    assert out["complete"] and c["verified"]


def test_a_synthesis_with_a_load_gives_each_candidate_its_loads(client):
    body = {
        "time_ratio": 1.6,
        "stroke": 300.0,
        "min_transmission_angle_deg": 35.0,
        "mechanisms": [{"type": "whitworth"}],
        "load": LOAD,
    }
    r = client.post("/v1/synthesize", json=body)
    assert r.status_code == 200, r.text
    cands = r.json()["candidates"]
    assert cands and all(c["loads"]["flywheel"]["inertia"] > 0 for c in cands)
    assert cands[0]["loads"]["torque"]["mean"] == pytest.approx(2000 * 0.8 * 0.3 / (2 * math.pi))
    plain = client.post("/v1/synthesize", json={k: v for k, v in body.items() if k != "load"})
    assert all(c["loads"] is None for c in plain.json()["candidates"])


def test_every_worked_example_of_the_docs_answers(client):
    """Each example /docs offers for a request (OpenAPI's examples) is a request the service
    answers with 200."""
    paths = client.get("/openapi.json").json()["paths"]
    tried = 0
    for path, methods in paths.items():
        body = methods.get("post", {}).get("requestBody", {})
        for example in (
            body.get("content", {}).get("application/json", {}).get("examples", {}).values()
        ):
            r = client.post(path, json=example["value"])
            assert r.status_code == 200, (path, example["summary"], r.text[:300])
            tried += 1
    assert tried >= 6


def test_a_report_is_a_page_that_stands_alone(client):
    r = client.post("/v1/report", json={**ANALYZE, "load": LOAD, "targets": {"bound_deg": 20.0}})
    assert r.status_code == 200 and r.headers["content-type"] == "text/html; charset=utf-8"
    assert r.text.startswith("<!doctype html>") and "<script" not in r.text
    for section in ("drawing", "targets", "design", "motion", "loads", "sensitivities", "limits"):
        assert f'<section id="{section}">' in r.text


def test_an_export_as_gif_is_a_turn_of_the_crank(client):
    from PIL import Image

    r = client.post("/v1/export", json={**ANALYZE, "format": "gif", "crank_angle_deg": 10.0})
    assert r.status_code == 200 and r.headers["content-type"] == "image/gif"
    img = Image.open(io.BytesIO(r.content))
    assert img.n_frames == 36
    first = np.asarray(img.convert("RGB"))
    img.seek(18)  # half a turn on
    assert not np.array_equal(first, np.asarray(img.convert("RGB")))


def test_an_analysis_takes_a_force_profile(client):
    """A profile's force, linear between its points: the mean torque is its work a turn
    (the trapezoid's area under the profile, times the stroke) over 2π."""
    profile = [[0.0, 500.0], [0.1, 3000.0], [0.9, 2000.0]]
    load = {"length_unit": "mm", "crank_rpm": 40.0, "force_profile": profile, "slider_mass": 50.0}
    r = client.post("/v1/analyze", json={**ANALYZE, "load": load})
    assert r.status_code == 200, r.text
    work = (0.1 * 1750.0 + 0.8 * 2500.0) * r.json()["stroke"] * 1e-3
    assert r.json()["loads"]["torque"]["mean"] == pytest.approx(work / (2 * math.pi), rel=1e-9)


def test_an_analysis_sizes_the_flywheel_and_the_motor_on_their_shafts(client):
    """The flywheel on a shaft at 1 450 rpm: (crank rpm / 1 450)² of the crank shaft's inertia,
    and the diameter of a 60 mm steel disc with it; the motor's torque at 960 rpm."""
    crank = client.post("/v1/analyze", json={**ANALYZE, "load": LOAD}).json()["loads"]
    shafts = {"flywheel_rpm": 1450.0, "flywheel_width": 60.0, "motor_rpm": 960.0}
    r = client.post("/v1/analyze", json={**ANALYZE, "load": {**LOAD, **shafts}})
    assert r.status_code == 200, r.text
    fly, power = r.json()["loads"]["flywheel"], r.json()["loads"]["power"]
    rpm = LOAD["crank_rpm"]
    assert fly["rpm"] == 1450.0 and crank["flywheel"]["rpm"] == rpm
    assert fly["inertia"] == pytest.approx(crank["flywheel"]["inertia"] * (rpm / 1450) ** 2)
    d = fly["disc_diameter"] / 1000  # m: a solid disc's I = ρ π d⁴ w / 32
    assert 7850 * math.pi * d**4 * 0.060 / 32 == pytest.approx(fly["inertia"])
    assert power["motor_torque"] == pytest.approx(power["rated"] / (960 * math.pi / 30))
    assert crank["flywheel"]["disc_diameter"] is None and crank["power"]["motor_torque"] is None


def test_the_least_peak_torque_answers_with_each_candidates_loads(client):
    body = {
        "time_ratio": 1.6,
        "stroke": 300.0,
        "min_transmission_angle_deg": 20.0,
        "mechanisms": [{"type": "whitworth"}],
        "objective": "min_peak_torque",
        "load": LOAD,
        "time_budget_ms": 60_000.0,  # the whole search, however busy the machine
    }
    roomy = Engine(Settings(max_budget_ms=60_000.0))  # the session's engine allows 1 s
    app.dependency_overrides[engine] = lambda: roomy
    try:
        r = client.post("/v1/synthesize", json=body)
        assert r.status_code == 200, r.text
        (c, *_) = r.json()["candidates"]
        assert c["certified"] and c["objective_value"] == c["loads"]["torque"]["max"]
        refused = client.post("/v1/synthesize", json={**body, "max_peak_torque": 1.0})
        assert refused.status_code == 200 and not refused.json()["candidates"]
        assert refused.json()["infeasible"][0]["code"] == "PEAK_TORQUE_UNREACHABLE"
    finally:
        del app.dependency_overrides[engine]
        roomy.close()


def test_synthesize_infeasible_is_200_with_reasons(client):
    body = {
        "time_ratio": 3.0,
        "stroke": 100.0,
        "min_transmission_angle_deg": 30.0,
        "mechanisms": [{"type": "offset_slider_crank"}],
    }
    r = client.post("/v1/synthesize", json=body)
    assert r.status_code == 200
    out = r.json()
    assert out["candidates"] == []
    assert out["infeasible"][0]["code"] == "TIME_RATIO_UNREACHABLE"


def test_sweep_drag_link_project_fig5(client):
    body = {
        "mechanism": design("drag_link_slider", **ref.DRAG_LINK_PROJECT, coupler=0.3),
        "vary": "coupler",
        "start": 0.1,
        "stop": 0.5,
        "points": 41,
    }
    out = client.post("/v1/sweep", json=body).json()
    assert out["valid_interval"] == [[pytest.approx(0.15), pytest.approx(0.40)]]
    assert out["time_ratio_range"]["min"]["time_ratio"] == pytest.approx(1.4298, abs=5e-5)
    assert out["time_ratio_range"]["max"]["time_ratio"] == pytest.approx(3.538, abs=5e-4)
    assert out["time_ratio"][0] is None and out["valid"][0] is False


SHAPER = {"crank": 40.0, "pivot_distance": 160.0, "lever": 240.0}
ANALYZE = {"mechanism": design("crank_shaper", **SHAPER)}
SYNTH = {"time_ratio": 1.5, "stroke": 1.0}
SPEC = {"type": "whitworth"}
SWEEP = {
    "mechanism": design("crank_shaper", **SHAPER),
    "vary": "crank",
    "start": 10.0,
    "stop": 50.0,
}
LOAD = {"length_unit": "mm", "crank_rpm": 40.0, "cutting_force": 2000.0, "slider_mass": 50.0}


def with_(base, path, value):
    """A copy of ``base`` with the value at ``path`` (a list of keys) replaced."""
    import copy

    out = copy.deepcopy(base)
    node = out
    for k in path[:-1]:
        node = node[k]
    node[path[-1]] = value
    return out


BAD = [
    ("/v1/analyze", with_(ANALYZE, ["mechanism", "params", "crank"], "NaN"), "crank"),
    ("/v1/analyze", with_(ANALYZE, ["mechanism", "params", "crank"], "Infinity"), "crank"),
    ("/v1/analyze", with_(ANALYZE, ["mechanism", "params", "crank"], "-inf"), "crank"),
    ("/v1/analyze", with_(ANALYZE, ["mechanism", "params", "crank"], -40.0), "crank"),
    ("/v1/analyze", with_(ANALYZE, ["mechanism", "params", "crank"], 0.0), "crank"),
    ("/v1/analyze", with_(ANALYZE, ["mechanism", "params", "crank"], 1e300), "crank"),
    ("/v1/analyze", with_(ANALYZE, ["mechanism", "params", "rod"], 1.0), "rod"),
    ("/v1/analyze", with_(ANALYZE, ["mechanism", "params"], {"crank": 40.0}), "pivot_distance"),
    ("/v1/analyze", with_(ANALYZE, ["mechanism", "type"], "cam"), "mechanism"),
    ("/v1/analyze", with_(ANALYZE, ["colour"], "red"), "colour"),
    ("/v1/analyze", with_(ANALYZE, ["samples"], 100_001), "samples"),
    ("/v1/analyze", with_(ANALYZE, ["samples"], 0), "samples"),
    ("/v1/analyze", with_(ANALYZE, ["crank_angles_deg"], [0.0] * 100_001), "crank_angles_deg"),
    ("/v1/analyze", with_(ANALYZE, ["crank_angles_deg"], [0.0, "nan"]), "crank_angles_deg"),
    ("/v1/analyze", {**ANALYZE, "samples": 4, "crank_angles_deg": [1.0]}, "not both"),
    ("/v1/analyze", with_(ANALYZE, ["crank_speed"], "inf"), "crank_speed"),
    ("/v1/analyze", with_(ANALYZE, ["tolerance"], {"absolute": -0.1}), "tolerance"),
    ("/v1/analyze", with_(ANALYZE, ["tolerance"], {"absolute": 1.0, "relative": 0.1}), "tolerance"),
    ("/v1/analyze", with_(ANALYZE, ["tolerance"], {"relative": "nan"}), "relative"),
    ("/v1/analyze", with_(ANALYZE, ["include"], ["curvature"]), "include"),
    ("/v1/analyze", with_(ANALYZE, ["include"], ["pins"]), "include"),
    ("/v1/analyze", {**ANALYZE, "samples": 4, "include": ["forces"]}, "include"),
    ("/v1/analyze", {**ANALYZE, "load": LOAD, "include": ["forces"]}, "include"),
    ("/v1/analyze", with_(ANALYZE, ["load"], {**LOAD, "guide_friction": -0.1}), "guide_friction"),
    ("/v1/analyze", with_(ANALYZE, ["load"], {**LOAD, "gravity_deg": 400.0}), "gravity_deg"),
    ("/v1/analyze", with_(ANALYZE, ["load"], {"crank_rpm": 40.0}), "length_unit"),
    ("/v1/analyze", with_(ANALYZE, ["load"], {**LOAD, "length_unit": "ft"}), "length_unit"),
    ("/v1/analyze", with_(ANALYZE, ["load"], {**LOAD, "crank_rpm": 0.0}), "crank_rpm"),
    ("/v1/analyze", with_(ANALYZE, ["load"], {**LOAD, "cutting_force": -1.0}), "cutting_force"),
    ("/v1/analyze", with_(ANALYZE, ["load"], {**LOAD, "slider_mass": "NaN"}), "slider_mass"),
    ("/v1/analyze", with_(ANALYZE, ["load"], {**LOAD, "cutting_zone": [0.9, 0.1]}), "cutting_zone"),
    ("/v1/analyze", with_(ANALYZE, ["load"], {**LOAD, "cutting_zone": [0.1, 1.5]}), "cutting_zone"),
    ("/v1/analyze", with_(ANALYZE, ["load"], {**LOAD, "efficiency": 0.0}), "efficiency"),
    ("/v1/analyze", with_(ANALYZE, ["load"], {**LOAD, "flywheel_rpm": 0.0}), "flywheel_rpm"),
    (
        "/v1/analyze",
        with_(ANALYZE, ["load"], {**LOAD, "ram_incline_deg": -95.0}),
        "ram_incline_deg",
    ),
    (
        "/v1/analyze",
        with_(ANALYZE, ["load"], {**LOAD, "ram_incline_deg": 0.0, "gravity_deg": 0.0}),
        "not both",
    ),
    ("/v1/analyze", with_(ANALYZE, ["load"], {**LOAD, "motor_rpm": -960.0}), "motor_rpm"),
    ("/v1/analyze", with_(ANALYZE, ["load"], {**LOAD, "flywheel_width": "inf"}), "flywheel_width"),
    ("/v1/analyze", with_(ANALYZE, ["load"], {**LOAD, "colour": 1}), "colour"),
    (
        "/v1/analyze",
        with_(ANALYZE, ["load"], {**LOAD, "force_profile": [[0.0, 5.0], [1.2, 6.0]]}),
        "force_profile",
    ),
    (
        "/v1/analyze",
        with_(ANALYZE, ["load"], {**LOAD, "force_profile": [[0.5, 5.0], [0.4, 6.0]]}),
        "force_profile",
    ),
    (
        "/v1/analyze",
        with_(ANALYZE, ["load"], {**LOAD, "force_profile": [[0.0, -5.0], [1, 6.0]]}),
        "force_profile",
    ),
    (
        "/v1/analyze",
        with_(ANALYZE, ["load"], {**LOAD, "force_profile": [[0.0, 5.0], [1, 6.0]]}),
        "not both",
    ),
    ("/v1/analyze", {**ANALYZE, "load": LOAD, "crank_speed": 2.0}, "crank_speed"),
    ("/v1/analyze", {**ANALYZE, "load": LOAD, "crank_acceleration": 2.0}, "crank_acceleration"),
    ("/v1/synthesize", {**SYNTH, "time_ratio": 0.5}, "time_ratio"),
    ("/v1/synthesize", {**SYNTH, "time_ratio": "NaN"}, "time_ratio"),
    ("/v1/synthesize", {**SYNTH, "stroke": -1.0}, "stroke"),
    ("/v1/synthesize", {**SYNTH, "stroke": 0}, "stroke"),
    ("/v1/synthesize", {**SYNTH, "min_transmission_angle_deg": 90.0}, "min_transmission_angle_deg"),
    ("/v1/synthesize", {**SYNTH, "max_candidates": 51}, "max_candidates"),
    ("/v1/synthesize", {**SYNTH, "time_budget_ms": 0}, "time_budget_ms"),
    ("/v1/synthesize", {**SYNTH, "objective": "cheapest"}, "objective"),
    (
        "/v1/synthesize",
        {**SYNTH, "objective": "uniform_cutting_speed", "max_working_speed_fluctuation": 0.9},
        "max_working_speed_fluctuation",
    ),
    (
        "/v1/synthesize",
        {**SYNTH, "max_working_speed_fluctuation": 1.5},
        "max_working_speed_fluctuation",
    ),
    (
        "/v1/synthesize",
        {**SYNTH, "max_working_speed_fluctuation": "NaN", "objective": "min_peak_acceleration"},
        "max_working_speed_fluctuation",
    ),
    ("/v1/synthesize", {**SYNTH, "include": ["colour"]}, "include"),
    ("/v1/synthesize", {**SYNTH, "load": {**LOAD, "length_unit": None}}, "length_unit"),
    ("/v1/synthesize", {**SYNTH, "objective": "min_peak_torque"}, "load"),
    (
        "/v1/synthesize",
        {**SYNTH, "objective": "min_peak_torque", "load": LOAD, "max_peak_torque": 0},
        "max_peak_torque",
    ),
    ("/v1/synthesize", {**SYNTH, "load": LOAD, "max_peak_torque": 5.0}, "max_peak_torque"),
    ("/v1/synthesize", {**SYNTH, "load": {**LOAD, "speed_fluctuation": 0.0}}, "speed_fluctuation"),
    ("/v1/synthesize", {**SYNTH, "include": ["pins"]}, "include"),
    ("/v1/synthesize", {**SYNTH, "tolerance": {"relative": -1e-3}}, "tolerance"),
    ("/v1/synthesize", {**SYNTH, "stroke_mm": 1.0}, "stroke_mm"),
    ("/v1/synthesize", {**SYNTH, "mechanisms": [{**SPEC, "fixed": {"rod": 1.0}}]}, "rod"),
    ("/v1/synthesize", {**SYNTH, "mechanisms": [{**SPEC, "fixed": {"lever": 0.0}}]}, "lever"),
    (
        "/v1/synthesize",
        {**SYNTH, "mechanisms": [{**SPEC, "bounds": {"lever": [2.0, 1.0]}}]},
        "lower bound 2 > upper bound 1",
    ),
    (
        "/v1/synthesize",
        {**SYNTH, "mechanisms": [{**SPEC, "bounds": {"lever": [1.0, "inf"]}}]},
        "lever",
    ),
    (
        "/v1/synthesize",
        {
            **SYNTH,
            "mechanisms": [{**SPEC, "fixed": {"lever": 1.0}, "bounds": {"lever": [0.5, 2.0]}}],
        },
        "lever: both fixed and bounded",
    ),
    ("/v1/synthesize", {**SYNTH, "mechanisms": [{"type": "cam"}]}, "mechanisms"),
    ("/v1/sweep", {**SWEEP, "points": 10_001}, "points"),
    ("/v1/sweep", {**SWEEP, "start": 60.0}, "start 60 > stop 50"),
    ("/v1/sweep", {**SWEEP, "vary": "colour"}, "crank_shaper has no parameter 'colour'"),
    ("/v1/sweep", {**SWEEP, "start": -10.0}, "start"),
    ("/v1/report", {**ANALYZE, "targets": {"bound_deg": 91.0}}, "bound_deg"),
    ("/v1/report", {**ANALYZE, "targets": {"speed": 1.0}}, "speed"),
    ("/v1/report", {**ANALYZE, "load": LOAD, "length_unit": "in"}, "length_unit"),
    ("/v1/report", {**ANALYZE, "crank_angle_deg": "inf"}, "crank_angle_deg"),
]


@pytest.mark.parametrize(("path", "body", "named"), BAD)
def test_bad_bodies_are_422_naming_the_field(client, path, body, named):
    r = client.post(path, json=body)
    assert r.status_code == 422, r.text
    detail = r.json()["detail"]
    assert isinstance(detail, list) and detail
    assert any(named in map(str, d["loc"]) or named in d["msg"] for d in detail), detail


def test_an_analysis_answers_every_field_synth_gives(client):
    """Everything synth.analyze returns for a request that asks for everything reaches the
    client, value for value: a field added to synth.Analysis is served, not dropped."""
    params = {"crank": 75.0, "pivot_distance": 50.0, "lever": 150.0, "connecting_rod": 200.0}
    everything = list(ANALYSIS_INCLUDE)
    body = {
        "mechanism": {"type": "whitworth", "params": params},
        "samples": 4,
        "include": everything,
        "tolerance": {"relative": 1e-3},
        "load": LOAD,
    }
    r = client.post("/v1/analyze", json=body)
    assert r.status_code == 200, r.text
    want = synth.analyze(
        "whitworth",
        params,
        samples=4,
        include=everything,
        tolerance=synth.Tolerance(relative=1e-3),
        load=synth.Load(**LOAD),
    ).to_dict()
    assert set(want) == {f.name for f in dataclasses.fields(synth.Analysis)}
    assert r.json() == json.loads(json.dumps(want))


def test_the_budget_limit_is_the_servers_setting(client):
    """The largest budget is read from the settings of the engine the routes depend on, at
    request time: the session's (SYNTH_MAX_BUDGET_MS=1000, tests/conftest.py), then another."""
    r = client.post("/v1/synthesize", json={**SYNTH, "time_budget_ms": 1500})
    assert r.status_code == 422
    (d,) = r.json()["detail"]
    assert d["loc"] == ["body", "time_budget_ms"] and "≤ 1000" in d["msg"], d
    small = Engine(Settings(max_budget_ms=5.0))
    app.dependency_overrides[engine] = lambda: small
    try:
        r = client.post("/v1/synthesize", json={**SYNTH, "time_budget_ms": 10})
        assert r.status_code == 422 and "≤ 5 " in r.json()["detail"][0]["msg"]
    finally:
        del app.dependency_overrides[engine]
        small.close()
    assert client.post("/v1/synthesize", json={**SYNTH, "time_budget_ms": 10}).status_code == 200


def test_a_synthesis_on_the_exact_solvers_alone_runs_without_a_solver_slot(client):
    """With every solver slot taken, what the library calls short (everything free, not a motion
    objective, nothing added) is answered on the short lane; anything else waits and gets 503."""
    # the short ones are refused too once they wait past this (the short lane may still be
    # building its models when the first arrives): ample for them, short for the waiters' 503s
    busy = Engine(Settings(max_queue_ms=1000.0))
    busy.slots.free = 0
    app.dependency_overrides[engine] = lambda: busy
    one = {"time_ratio": 1.6, "stroke": 300.0, "min_transmission_angle_deg": 20.0}
    try:
        for body in (
            {**one, "mechanisms": [{"type": "crank_shaper"}]},
            one,
            {**one, "objective": "min_size"},
        ):
            r = client.post("/v1/synthesize", json=body)
            assert r.status_code == 200 and r.json()["candidates"], body
        for body in (
            {**one, "mechanisms": [{"type": "crank_shaper", "fixed": {"crank": 60.0}}]},
            {**one, "objective": "min_peak_acceleration"},
            {**one, "include": ["motion"]},
        ):
            assert client.post("/v1/synthesize", json=body).status_code == 503, body
    finally:
        del app.dependency_overrides[engine]
        busy.close()


@pytest.mark.parametrize(
    "kwargs",
    [
        {},
        {"samples": 7},
        {"crank_angles_deg": [0.0, 33.3, 90.0], "include": ["pins"]},
        {
            "samples": 4,
            "include": ["motion", "sensitivities", "envelope", "pins"],
            "tolerance": synth.Tolerance(relative=1e-3),
        },
        {
            "samples": 5,
            "include": ["forces"],
            "load": synth.Load(
                "mm", 40.0, cutting_force=2000.0, slider_mass=50.0, guide_friction=0.1
            ),
        },
    ],
)
@pytest.mark.parametrize("mtype", DESIGNS)
def test_an_analysis_is_encoded_as_its_model_encodes_it(mtype, kwargs):
    """The analysis reply, encoded straight from synth's dataclasses, is the JSON the response
    model gives for ``to_dict()``, byte for byte."""
    a = synth.analyze(mtype, DESIGNS[mtype], **kwargs)
    model = AnalyzeResponse(**a.to_dict())
    assert encoded(a) == TypeAdapter(AnalyzeResponse).dump_json(model, exclude_unset=True)


@pytest.mark.parametrize(
    ("body", "loc", "msg"),
    [
        (
            {"time_ratio": 0.5, "stroke": 250},
            ["body", "time_ratio"],
            "time_ratio must be ≥ 1, got 0.5",
        ),
        (
            {"time_ratio": 1.5, "stroke": -250},
            ["body", "stroke"],
            "stroke must be ≥ 1e-09, got -250",
        ),
        ({"stroke": 250}, ["body", "time_ratio"], "time_ratio is required"),
        (
            {"time_ratio": "x", "stroke": 250},
            ["body", "time_ratio"],
            "time_ratio must be a finite number, got 'x'",
        ),
        (
            {"time_ratio": 1.5, "stroke": 250, "colour": 1},
            ["body", "colour"],
            "colour: no such field here",
        ),
        (
            {"time_ratio": 1.5, "stroke": 250, "objective": "fast"},
            ["body", "objective"],
            "objective must be 'pareto', 'max_transmission_angle', 'min_size', "
            "'uniform_cutting_speed', 'min_peak_acceleration' or 'min_peak_torque', got 'fast'",
        ),
    ],
)
def test_a_schemas_refusal_is_worded_like_the_librarys(client, body, loc, msg):
    """The field, the rule with its number and what was given, as the library says its own
    refusals; the machine-readable type and context as pydantic gives them."""
    r = client.post("/v1/synthesize", json=body)
    assert r.status_code == 422
    (e,) = r.json()["detail"]
    assert e["loc"] == loc and e["msg"] == msg
    assert e["type"] in {
        "greater_than_equal",
        "missing",
        "float_type",
        "extra_forbidden",
        "literal_error",
    }
