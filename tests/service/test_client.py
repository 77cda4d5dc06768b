"""A client generated from the service's /openapi.json by openapi-python-client, as a design
tool would make one.

The contract first: every schema in it (each component, and each operation's parameters, body
and replies, inline) is typed all the way down, each property, item and union member a
``type``, ``$ref``, ``const`` or ``enum``, or a union of such (the check finds properties
planted without one). The client is generated without a warning (told that the export's image
media types are files, which it reads as bytes). Every route of the contract is called through
the client's generated functions (a table of calls whose requests reach exactly the contract's
routes, the export once in each of its formats), and each answers 200 as the client's typed
model, not a dict. The replies' substance is checked against values from outside the service:
the brute-force simulation's time ratio, stroke and transmission angle (of a synthesis, an
analysis, a sweep, the SVG's caption, the report's page), the design's link lengths in the
drawings (the SVG's lines measured, the DXF's read from its group codes, the JSON's pins), the
version in pyproject.toml, the six types, the atlas's ranges against its own frontier."""

import copy
import importlib
import io
import json
import math
import os
import re
import subprocess
import sys
import sysconfig
import tomllib
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

import httpx
import pytest
from fastapi.testclient import TestClient
from PIL import Image

from api.config import Settings
from api.engine import Engine
from api.main import app
from api.routers.common import engine

from ..support import bruteforce

PACKAGE = "quick_return_mechanism_synthesis_client"
WHITWORTH = {"crank": 75.0, "pivot_distance": 50.0, "lever": 150.0, "connecting_rod": 200.0}
LOAD = {"length_unit": "mm", "crank_rpm": 40.0, "cutting_force": 2000.0, "slider_mass": 20.0}
DESIGN = {"mechanism": {"type": "whitworth", "params": WHITWORTH}}
FORMATS = ("svg", "dxf", "json", "gif")
# the export answers in the media type of its format; the generator reads a reply by the first
# media type it knows (application/json): told that the images are files, it reads them as bytes
IMAGES = ("image/svg+xml", "image/vnd.dxf", "image/gif")

# each call through the client: the generated module (under api.) and its arguments, a body
# as the name of its model and its value
CALLS: dict[str, tuple[str, dict[str, Any]]] = {
    "health": ("service.health_health_get", {}),
    "mechanisms": ("mechanisms.list_mechanisms_v1_mechanisms_get", {}),
    "mechanism": ("mechanisms.get_mechanism_v1_mechanisms_type_get", {"type_": "whitworth"}),
    "atlas": ("atlas.get_atlas_v1_atlas_get", {}),
    "synthesize": (
        "synthesis.synthesize_v1_synthesize_post",
        {
            "body": (
                "SynthesizeRequest",
                {
                    "time_ratio": 1.6,
                    "stroke": 300.0,
                    "min_transmission_angle_deg": 20.0,
                    "mechanisms": [{"type": "whitworth"}],
                    "objective": "min_peak_torque",
                    "load": LOAD,
                    "time_budget_ms": 60_000.0,
                },
            )
        },
    ),
    "analyze": ("analysis.analyze_v1_analyze_post", {"body": ("AnalyzeRequest", DESIGN)}),
    "sweep": (
        "analysis.sweep_v1_sweep_post",
        {
            "body": (
                "SweepRequest",
                {**DESIGN, "vary": "pivot_distance", "start": 40.0, "stop": 60.0, "points": 3},
            )
        },
    ),
    **{
        f"export-{f}": (
            "analysis.export_v1_export_post",
            {"body": ("ExportRequest", {**DESIGN, "format": f})},
        )
        for f in FORMATS
    },
    "report": (
        "analysis.report_v1_report_post",
        {"body": ("ReportRequest", {**DESIGN, "load": LOAD})},
    ),
}
# what each reply is in the client: a model of its models (by name), a list of them, a file's
# bytes (types.File) or a page's text (str)
TYPED = {
    "health": "Health",
    "mechanisms": "list[MechanismInfo]",
    "mechanism": "MechanismInfo",
    "atlas": "AtlasInfo",
    "synthesize": "SynthesisResult",
    "analyze": "AnalyzeResponse",
    "sweep": "SweepResult",
    **{f"export-{f}": "types.File" for f in FORMATS},
    "report": "str",
}

# --- the contract's types ---------------------------------------------------------------------

TYPES = {"type", "$ref", "const", "enum"}
UNIONS = ("anyOf", "oneOf", "allOf")


def untyped(schema: Any, where: str) -> list[str]:
    """The places in ``schema`` (standing at ``where``) without a type: it, each of its
    properties, its items, prefix items, additional properties and union members must have a
    ``type``, ``$ref``, ``const`` or ``enum``, or be a union whose members each have one. No
    schema at all (None) is untyped."""
    if not isinstance(schema, dict):
        return [where]
    members = [(f"{where}/{u}/{i}", m) for u in UNIONS for i, m in enumerate(schema.get(u, []))]
    inner = [
        *members,
        *((f"{where}/properties/{n}", p) for n, p in schema.get("properties", {}).items()),
        *((f"{where}/prefixItems/{i}", s) for i, s in enumerate(schema.get("prefixItems", []))),
        *(
            (f"{where}/{k}", schema[k])
            for k in ("items", "additionalProperties")
            if isinstance(schema.get(k), dict)
        ),
    ]
    found = [] if TYPES & schema.keys() or members else [where]
    return found + [place for at, s in inner for place in untyped(s, at)]


def contract(spec: dict[str, Any]) -> dict[str, list[tuple[str, Any]]]:
    """The schemas of ``spec`` to check, by where they stand: each component, and each
    operation's (``GET /health``) parameters, body and replies, inline; a body or reply declared
    without a schema as None."""
    found = {
        f"#/components/schemas/{n}": [(f"#/components/schemas/{n}", s)]
        for n, s in spec["components"]["schemas"].items()
    }
    for path, operations in spec["paths"].items():
        for method, op in operations.items():
            at = f"{method.upper()} {path}"
            body = op.get("requestBody", {}).get("content", {})
            found[at] = [
                *(
                    (f"{at} parameter {p['name']}", p.get("schema"))
                    for p in op.get("parameters", [])
                ),
                *((f"{at} body {t}", m.get("schema")) for t, m in body.items()),
                *(
                    (f"{at} reply {status} {t}", m.get("schema"))
                    for status, reply in op["responses"].items()
                    for t, m in reply.get("content", {}).items()
                ),
            ]
    return found


@pytest.mark.parametrize("where", contract(app.openapi()))
def test_every_schema_of_the_contract_is_typed(where):
    checked = contract(app.openapi())[where]
    assert checked, where
    assert [p for at, s in checked for p in untyped(s, at)] == []


def test_the_type_check_finds_untyped_properties():
    spec = copy.deepcopy(app.openapi())
    health = spec["components"]["schemas"]["Health"]["properties"]
    health["uptime"] = {"title": "Uptime", "description": "no type"}
    health["status"] = {"anyOf": [{"type": "string"}, {"title": "Neither"}]}
    spec["components"]["schemas"]["PinPath"]["properties"]["x"]["items"] = {}
    del spec["paths"]["/health"]["get"]["responses"]["200"]["content"]["application/json"]["schema"]
    found = {
        where: [p for at, s in checked for p in untyped(s, at)]
        for where, checked in contract(spec).items()
    }
    at = "#/components/schemas/"
    assert found[at + "Health"] == [
        at + "Health/properties/status/anyOf/1",
        at + "Health/properties/uptime",
    ]
    assert found[at + "PinPath"] == [at + "PinPath/properties/x/items"]
    assert found["GET /health"] == ["GET /health reply 200 application/json"]
    assert found[at + "AnalyzeRequest"] == []


# --- the client -------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def generated(tmp_path_factory):
    """The client package, generated into a temporary folder and imported, and what the
    generator printed."""
    out = tmp_path_factory.mktemp("client")
    spec = out / "openapi.json"
    spec.write_text(json.dumps(app.openapi()))
    config = out / "config.json"
    overrides = {m: "application/octet-stream" for m in IMAGES}
    config.write_text(json.dumps({"content_type_overrides": overrides}))
    scripts = sysconfig.get_path("scripts")  # the generator, and the ruff it formats with
    env = {**os.environ, "PATH": scripts + os.pathsep + os.environ.get("PATH", "")}
    run = subprocess.run(
        [
            Path(scripts) / "openapi-python-client",
            "generate",
            "--path",
            str(spec),
            "--config",
            str(config),
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


def send(client, name):
    """The call ``name`` of ``CALLS`` through the client's generated function: its detailed
    response (status, content, the typed reply as ``parsed``)."""
    operation, args = CALLS[name]
    kwargs = dict(args)
    if "body" in kwargs:
        model, value = kwargs["body"]
        kwargs["body"] = getattr(module("models"), model).from_dict(value)
    return module(f"api.{operation}").sync_detailed(client=client, **kwargs)


@pytest.fixture(scope="module")
def replies(client):
    """Each call's response, sent once whichever tests read it."""
    sent = {}

    def reply(name):
        if name not in sent:
            sent[name] = send(client, name)
        return sent[name]

    return reply


def is_typed(value, expected):
    """Whether ``value`` is what ``TYPED`` says a reply is in the client."""
    if expected.startswith("list["):
        inner = expected.removeprefix("list[").removesuffix("]")
        return isinstance(value, list) and bool(value) and all(is_typed(v, inner) for v in value)
    if expected == "str":
        return isinstance(value, str)
    home, _, name = expected.rpartition(".")
    return isinstance(value, getattr(module(home or "models"), name))


def test_the_client_is_generated_without_a_warning(generated):
    _, printed = generated
    assert "warning" not in printed.lower(), printed
    models = module("models")
    for name in (
        "Health",
        "MechanismInfo",
        "AtlasInfo",
        "SynthesisResult",
        "AnalyzeResponse",
        "SweepResult",
        "ExportRequest",
        "ReportRequest",
        "TimeRatioRange",
        "DeadCentres",
        "Loads",
    ):
        assert hasattr(models, name), name


def test_the_calls_reach_every_route_of_the_contract(generated):
    """Sent through the generated functions to a recorder (which answers an undeclared 204),
    the calls' requests reach each route of the contract, and only those; the export is called
    in each format the contract has."""
    package, _ = generated
    requests = []

    def record(request):
        requests.append((request.method, request.url.path))
        return httpx.Response(204)

    recorder = package.Client(base_url="http://recorder")
    with httpx.Client(base_url="http://recorder", transport=httpx.MockTransport(record)) as h:
        recorder.set_httpx_client(h)
        for name in CALLS:
            assert send(recorder, name).parsed is None, name
    spec = app.openapi()
    routes = {(m.upper(), path) for path, operations in spec["paths"].items() for m in operations}

    def route(method, path):
        parts = path.split("/")
        (found,) = [
            (m, t)
            for m, t in routes
            if m == method
            and len(t.split("/")) == len(parts)
            and all(a == b or a.startswith("{") for a, b in zip(t.split("/"), parts, strict=True))
        ]
        return found

    assert len(requests) == len(CALLS)
    assert {route(m, p) for m, p in requests} == routes
    formats = spec["components"]["schemas"]["ExportRequest"]["properties"]["format"]["enum"]
    assert sorted(formats) == sorted(FORMATS)
    assert set(TYPED) == set(CALLS)


@pytest.mark.parametrize("name", CALLS)
def test_every_route_replies_with_the_clients_typed_model(replies, name):
    r = replies(name)
    assert r.status_code == 200, r.content[:500]
    assert is_typed(r.parsed, TYPED[name]), (TYPED[name], type(r.parsed))
    if TYPED[name] == "types.File":
        assert r.parsed.payload.read() == r.content


# --- the replies' numbers ---------------------------------------------------------------------


def test_the_service_and_its_registry_through_the_client(replies):
    pyproject = Path(__file__).resolve().parents[2] / "pyproject.toml"
    health = replies("health").parsed
    assert health.status == "ok"
    assert health.version == tomllib.loads(pyproject.read_text())["project"]["version"]
    listed = replies("mechanisms").parsed
    assert sorted(m.type_ for m in listed) == sorted(bruteforce.TYPES)  # the six
    one = replies("mechanism").parsed
    assert one.type_ == "whitworth" and "Whitworth" in one.title
    assert [p.name for p in one.parameters] == list(WHITWORTH)
    assert one.to_dict() == next(m.to_dict() for m in listed if m.type_ == "whitworth")


def test_the_atlas_through_the_client(replies):
    """Each type's time-ratio range at a bound holds every ratio of the grid where the type's
    best minimum transmission angle meets the bound, and no certified one where it does not."""
    models = module("models")
    atlas = replies("atlas").parsed
    assert isinstance(atlas.inputs, models.AtlasInputs)
    assert set(atlas.inputs.types) <= set(bruteforce.TYPES)
    assert set(atlas.frontier.additional_properties) == set(atlas.inputs.types)
    assert {(r.type_, r.bound_deg) for r in atlas.ranges} == {
        (t, b) for t in atlas.inputs.types for b in atlas.inputs.bounds
    }
    for r in atlas.ranges:
        assert isinstance(r, models.AtlasRange)
        rows = atlas.frontier[r.type_]
        assert [ratio for ratio, _, _ in rows] == atlas.inputs.ratios
        for ratio, best, status in rows:
            inside = r.min_ is not None and r.min_ <= ratio <= r.max_
            if best is not None and best >= r.bound_deg:
                assert inside, (r.to_dict(), ratio, best)
            elif status == "certified":
                assert not inside, (r.to_dict(), ratio, best)


def test_a_least_peak_torque_synthesis_through_the_client(replies):
    models = module("models")
    r = replies("synthesize").parsed
    assert isinstance(r, models.SynthesisResult), r
    c = r.candidates[0]
    assert isinstance(c, models.Candidate) and c.certified
    assert c.objective_value == c.loads.torque.max_  # the generator adds _ to a builtin
    brute = bruteforce.simulate("whitworth", c.params.to_dict())
    assert brute["time_ratio"] == pytest.approx(1.6, rel=1e-9)
    assert brute["stroke"] == pytest.approx(300.0, rel=1e-9)


def test_an_analysis_and_a_sweep_through_the_client(replies):
    models = module("models")
    a = replies("analyze").parsed
    assert isinstance(a, models.AnalyzeResponse), a
    brute = bruteforce.simulate("whitworth", WHITWORTH)
    assert a.time_ratio == pytest.approx(brute["time_ratio"], rel=1e-9)
    assert isinstance(a.extremes, models.DeadCentres)
    stroke = a.extremes.max_.position - a.extremes.min_.position
    assert stroke == pytest.approx(brute["stroke"], rel=1e-9)
    s = replies("sweep").parsed
    assert isinstance(s, models.SweepResult), s
    assert isinstance(s.time_ratio_range, models.TimeRatioRange)
    assert s.values == pytest.approx([40.0, 50.0, 60.0], rel=1e-15)
    for value, ratio in zip(s.values, s.time_ratio, strict=True):
        brute = bruteforce.simulate("whitworth", {**WHITWORTH, "pivot_distance": value})
        assert ratio == pytest.approx(brute["time_ratio"], rel=1e-9)
    assert s.time_ratio_range.max_.time_ratio == pytest.approx(max(s.time_ratio), rel=1e-15)


def dxf_pairs(text):
    """A DXF file's (group code, value) pairs."""
    lines = [line.strip() for line in text.splitlines()]
    return list(zip(lines[::2], lines[1::2], strict=True))


def dxf_line_lengths(pairs):
    """Each LINE entity's layer and length, from its group codes 8, 10/20 and 11/21."""
    entities, current = [], None
    for code, value in pairs:
        if code == "0":
            current = {} if value == "LINE" else None
            if current is not None:
                entities.append(current)
        elif current is not None:
            current.setdefault(code, value)
    lengths = {}
    for e in entities:
        a, b = (float(e["10"]), float(e["20"])), (float(e["11"]), float(e["21"]))
        lengths.setdefault(e["8"], []).append(math.dist(a, b))
    return lengths


def test_the_exports_carry_the_designs_lengths(replies):
    """The SVG in true size (its lines measured in mm), the DXF in mm (its lines read from the
    group codes), the JSON drawing and the GIF animation, of the design the request gave."""
    brute = bruteforce.simulate("whitworth", WHITWORTH)
    for f in FORMATS:
        r = replies(f"export-{f}")
        assert r.status_code == 200, (f, r.content[:500])
    svg = ET.fromstring(replies("export-svg").content)
    _, _, width, height = (float(x) for x in svg.get("viewBox").split())
    assert float(svg.get("width").removesuffix("mm")) == pytest.approx(width, rel=1e-6)
    assert float(svg.get("height").removesuffix("mm")) == pytest.approx(height, rel=1e-6)
    links = {}
    for line in svg.iter("{http://www.w3.org/2000/svg}line"):
        name = next((c[5:] for c in line.get("class", "").split() if c.startswith("link-")), None)
        if name:
            a = float(line.get("x1")), float(line.get("y1"))
            b = float(line.get("x2")), float(line.get("y2"))
            links[name] = math.dist(a, b)  # in the viewBox's units: mm
    assert links == pytest.approx(WHITWORTH, rel=1e-9)
    caption = " ".join(t.text or "" for t in svg.iter("{http://www.w3.org/2000/svg}text"))
    ratio, stroke = re.search(r"time ratio ([\d.]+), stroke ([\d.]+) mm", caption).groups()
    assert float(ratio) == pytest.approx(brute["time_ratio"], rel=1e-8)
    assert float(stroke) == pytest.approx(brute["stroke"], rel=1e-8)

    pairs = dxf_pairs(replies("export-dxf").content.decode())
    assert pairs[pairs.index(("9", "$INSUNITS")) + 1] == ("70", "4")  # millimetres
    lengths = dxf_line_lengths(pairs)
    assert {n: lengths.get(n) for n in WHITWORTH} == {
        n: pytest.approx([v], rel=1e-9) for n, v in WHITWORTH.items()
    }

    drawing = json.loads(replies("export-json").content)["drawing"]
    assert drawing["type"] == "whitworth" and drawing["params"] == WHITWORTH
    pins = drawing["pins"]
    drawn = {k["name"]: math.dist(pins[k["a"]], pins[k["b"]]) for k in drawing["links"]}
    assert drawn == pytest.approx(WHITWORTH, rel=1e-9)

    gif = Image.open(io.BytesIO(replies("export-gif").content))
    assert gif.format == "GIF" and gif.is_animated and gif.n_frames > 1


def test_the_report_is_a_page_about_the_design(replies):
    r = replies("report")
    assert r.status_code == 200, r.content[:500]
    page = r.content.decode()
    assert page.lower().startswith("<!doctype html>")
    title = next(m.title for m in replies("mechanisms").parsed if m.type_ == "whitworth")
    assert re.search(r"<title>([^<]*)</title>", page).group(1).startswith(title)
    text = re.sub(r"<[^>]+>", " ", page)
    numbers = [float(x) for x in re.findall(r"\d+\.\d+", text)]
    brute = bruteforce.simulate("whitworth", WHITWORTH)
    assert any(x == pytest.approx(brute["time_ratio"], rel=1e-8) for x in numbers)
    assert any(x == pytest.approx(brute["min_transmission_deg"], rel=1e-7) for x in numbers)
