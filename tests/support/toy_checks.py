"""The two types of tests/support/toy_type.py, through everything a type reaches: analysis,
synthesis by the generic path, the API's schemas, /v1/mechanisms. Run by
tests/library/test_seventh_type.py in its own processes (``SYNTH_TYPES=tests.support.toy_type``
registers the types in each); not collected otherwise.

The expected numbers are computed here from the toy's own geometry, or by the exact solver of
the type the generic one copies: never by the code under test.
"""

from __future__ import annotations

import math

import pytest
from fastapi.testclient import TestClient

import synth
from api.main import app
from synth.mechanisms import all_types

from .toy_type import GENERIC, TOY

client = TestClient(app)


def test_the_registry_lists_them_after_the_six():
    assert all_types()[6:] == tuple(sorted((TOY, GENERIC)))


@pytest.mark.parametrize(("r", "rod"), [(1.0, 3.0), (0.2, 0.25), (40.0, 41.0)])
def test_analysis(r, rod):
    a = synth.analyze(TOY, {"crank": r, "coupler": rod})
    assert a.time_ratio == pytest.approx(1.0, rel=1e-12)
    assert a.stroke == pytest.approx(2 * r, rel=1e-12)  # from the dead centres θ = 0, π
    assert a.transmission.min_deg == pytest.approx(math.degrees(math.acos(r / rod)), rel=1e-10)
    assert a.extremes["max"].position == pytest.approx(r + rod, rel=1e-12)


def test_synthesis_by_the_generic_path():
    stroke, bound = 2.0, 60.0
    one = {"mechanisms": [{"type": TOY}]}
    small = synth.synthesize(1.0, stroke, bound, objective="min_size", **one).candidates[0]
    # the smallest coupler with cos μ = r/l ≤ cos 60°: l = 2r, r = stroke/2
    assert small.params == pytest.approx({"crank": 1.0, "coupler": 2.0}, rel=1e-9)
    best = synth.synthesize(1.0, stroke, bound, objective="max_transmission_angle", **one)
    best = best.candidates[0]
    # the longest coupler the default bounds allow (2 strokes)
    assert best.params == pytest.approx({"crank": 1.0, "coupler": 4.0}, rel=1e-9)
    assert best.min_transmission_angle_deg == pytest.approx(math.degrees(math.acos(1 / 4)))
    front = synth.synthesize(1.0, stroke, bound, **one).candidates
    assert len(front) >= 3
    assert front[0].params == best.params and front[-1].params == small.params
    angles = [c.min_transmission_angle_deg for c in front]
    sizes = [c.size for c in front]
    assert angles == sorted(angles, reverse=True) and sizes == sorted(sizes, reverse=True)
    assert all(c.verified and c.method == "ipopt" for c in front)


@pytest.mark.parametrize(("tr", "bound"), [(1.2, 0.0), (1.5, 20.0), (2.0, 10.0)])
@pytest.mark.parametrize("objective", ["max_transmission_angle", "min_size"])
def test_the_generic_path_finds_the_exact_solvers_optimum(tr, bound, objective):
    if objective == "min_size" and bound == 0:
        return  # no smallest design without a bound
    exact = synth.synthesize(
        tr, 1.0, bound, [{"type": "offset_slider_crank"}], objective=objective
    ).candidates[0]
    generic = synth.synthesize(
        tr, 1.0, bound, [{"type": GENERIC}], objective=objective, time_budget_ms=20_000
    ).candidates[0]
    assert generic.method == "ipopt" and exact.method == "closed_form"
    assert generic.min_transmission_angle_deg == pytest.approx(
        exact.min_transmission_angle_deg, rel=1e-7
    )
    if objective == "min_size":
        assert generic.size == pytest.approx(exact.size, rel=1e-7)


def test_motion_objectives_refuse_a_type_without_closed_forms():
    r = synth.synthesize(1.0, 1.0, 20.0, [{"type": TOY}], objective="uniform_cutting_speed")
    assert not r.candidates and r.infeasible[0].code == "OBJECTIVE_UNSUPPORTED"


def test_the_api_serves_them():
    listed = {m["type"]: m for m in client.get("/v1/mechanisms").json()}
    assert [p["name"] for p in listed[TOY]["parameters"]] == ["crank", "coupler"]
    assert client.get(f"/v1/mechanisms/{GENERIC}").status_code == 200
    assert TOY in client.get("/openapi.json").text
    design = {"type": TOY, "params": {"crank": 1, "coupler": 3}}
    a = client.post("/v1/analyze", json={"mechanism": design})
    assert a.status_code == 200 and a.json()["stroke"] == pytest.approx(2.0)
    s = client.post(
        "/v1/synthesize",
        json={
            "time_ratio": 1.0,
            "stroke": 2.0,
            "min_transmission_angle_deg": 60,
            "mechanisms": [{"type": TOY}],
        },
    )
    assert s.status_code == 200 and len(s.json()["candidates"]) >= 3


def test_a_type_without_a_frame_is_not_drawn_but_refused():
    r = client.post(
        "/v1/export", json={"mechanism": {"type": TOY, "params": {"crank": 1, "coupler": 3}}}
    )
    assert r.status_code == 422, r.text
    assert "has no drawing yet" in r.json()["detail"][0]["msg"]


def test_a_broken_toy_is_a_422_at_the_parameters_its_condition_reads():
    design = {"type": TOY, "params": {"crank": 2, "coupler": 1}}
    r = client.post("/v1/analyze", json={"mechanism": design})
    assert r.status_code == 422
    errors = r.json()["detail"]
    assert all("coupler 1 ≤ crank 2: the crank cannot turn fully" in e["msg"] for e in errors)
    assert {e["loc"][-1] for e in errors} == {"crank", "coupler"}  # derived, never declared
