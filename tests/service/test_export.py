"""POST /v1/export: every type in both formats over HTTP, read back as CAD and a browser read
them (ezdxf, an XML parser), and bad requests refused with a 422 naming the field."""

import io
import math
import xml.etree.ElementTree as ET

import ezdxf
import pytest
from fastapi.testclient import TestClient

import synth
from api.main import app

from ..support import bruteforce
from ..support.designs import random_designs

TYPES = synth.mechanisms.all_types()


@pytest.fixture(scope="module")
def client():
    with TestClient(app) as c:
        yield c


def body(mtype, params, **kw):
    return {"mechanism": {"type": mtype, "params": params}} | kw


@pytest.mark.parametrize("mtype", TYPES)
def test_every_type_exports_in_both_formats(client, mtype):
    (p,) = random_designs(mtype, 1, seed=41)
    r = client.post("/v1/export", json=body(mtype, p, format="dxf", length_unit="in", paths=True))
    assert r.status_code == 200 and r.headers["content-type"] == "image/vnd.dxf"
    assert f'filename="{mtype}.dxf"' in r.headers["content-disposition"]
    doc = ezdxf.read(io.StringIO(r.text))
    assert doc.units == ezdxf.units.IN
    for e in doc.modelspace().query("LINE"):
        if e.dxf.layer in p:
            assert (e.dxf.end - e.dxf.start).magnitude == pytest.approx(p[e.dxf.layer], rel=1e-9)
    (dim,) = doc.modelspace().query('DIMENSION[layer=="STROKE"]')
    assert dim.get_measurement() == pytest.approx(bruteforce.simulate(mtype, p)["stroke"], rel=1e-9)

    r = client.post("/v1/export", json=body(mtype, p, format="json"))
    assert r.status_code == 200 and r.headers["content-type"] == "application/json"
    drawn = r.json()["drawing"]
    for link in drawn["links"]:  # each between its pins, as long as the design says
        (ax, ay), (bx, by) = drawn["pins"][link["a"]], drawn["pins"][link["b"]]
        assert math.hypot(bx - ax, by - ay) == pytest.approx(p[link["name"]], rel=1e-9)
    assert len(r.json()["sketch"]["ground"]) == len(drawn["ground"])

    r = client.post("/v1/export", json=body(mtype, p, crank_angle_deg=45.0))
    assert r.status_code == 200 and r.headers["content-type"].startswith("image/svg+xml")
    root = ET.fromstring(r.content)
    assert root.get("width").endswith("mm") and root.get("data-crank-angle-deg") == "45"


@pytest.mark.parametrize(
    ("change", "loc"),
    [
        ({"format": "pdf"}, ["body", "format"]),
        ({"length_unit": "ft"}, ["body", "length_unit"]),
        ({"crank_angle_deg": 1e7}, ["body", "crank_angle_deg"]),
        ({"paths": "sometimes"}, ["body", "paths"]),
        (
            {
                "mechanism": {
                    "type": "whitworth",
                    "params": {
                        "crank": 75,
                        "pivot_distance": 50,
                        "lever": 150,
                        "connecting_rod": 20,
                    },
                }
            },
            ["body", "mechanism", "params", "connecting_rod"],
        ),
        (
            {
                "mechanism": {
                    "type": "whitworth",
                    "params": {
                        "crank": -75,
                        "pivot_distance": 50,
                        "lever": 150,
                        "connecting_rod": 200,
                    },
                }
            },
            ["body", "mechanism", "whitworth", "params", "crank"],
        ),
        ({"colour": "red"}, ["body", "colour"]),
    ],
)
def test_a_bad_export_is_a_422_naming_the_field(client, change, loc):
    good = body(
        "whitworth", {"crank": 75, "pivot_distance": 50, "lever": 150, "connecting_rod": 200}
    )
    r = client.post("/v1/export", json=good | change)
    assert r.status_code == 422, r.text
    assert loc in [e["loc"] for e in r.json()["detail"]], r.text
    assert all(isinstance(e["msg"], str) and e["msg"] for e in r.json()["detail"])
