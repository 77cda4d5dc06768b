"""HTTP tests of the endpoints so far (TestClient)."""

from fastapi.testclient import TestClient

import synth
from api.main import app
from synth.mechanisms import all_types, get

client = TestClient(app)


def test_health():
    r = client.get("/health")
    assert r.status_code == 200
    assert r.json() == {"status": "ok", "version": synth.__version__}


def test_mechanisms_listing_comes_from_the_registry():
    r = client.get("/v1/mechanisms")
    assert r.status_code == 200
    body = r.json()
    assert [m["type"] for m in body] == list(all_types()) and len(body) == 6
    for m in body:
        reg = get(m["type"])
        assert [q["name"] for q in m["parameters"]] == list(reg.names)
        assert m["validity"] == [c.text for c in reg.conditions]
        assert m["quick_return"] == (m["type"] != "scotch_yoke")
        assert m["seeds"]
        for q in m["parameters"]:
            assert q["symbol"] and q["description"]


def test_one_mechanism_and_defaults():
    m = client.get("/v1/mechanisms/crank_shaper").json()
    params = {q["name"]: q for q in m["parameters"]}
    assert params["crank"]["required"] and params["crank"]["symbol"] == "r2"
    assert params["ram_link"]["required"] is False and params["ram_link"]["default"] == 0.0
    assert params["ram_height"]["default_rule"].startswith("lever·cos ψmax")


def test_unknown_type_is_404_with_the_known_types():
    r = client.get("/v1/mechanisms/slider_crank")
    assert r.status_code == 404
    (err,) = r.json()["detail"]
    assert err["loc"] == ["path", "type"]
    assert "known types: scotch_yoke" in err["msg"]
