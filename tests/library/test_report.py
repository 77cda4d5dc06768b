"""The design report (synth.report, quickreturn report): read as a person reads the page (its
tables' text), checked against the brute-force simulation; it stands alone (nothing it would
fetch); bad input refused naming the field. Its rendering in a browser is
tests/service/test_report.py's."""

import re
from html.parser import HTMLParser

import pytest

import synth

from ..support import bruteforce
from ..support.designs import random_designs

TYPES = synth.mechanisms.all_types()
SHAPER = {"crank": 120.0, "pivot_distance": 240.0, "lever": 450.0}
LOAD = {"length_unit": "mm", "crank_rpm": 30.0, "cutting_force": 3000.0, "slider_mass": 40.0}


class Page(HTMLParser):
    """The page's sections' tables (rows of cell text), its tags and every URL-like
    attribute."""

    def __init__(self, html: str):
        super().__init__()
        self.tables: dict[str, list[list[str]]] = {}
        self.tags: set[str] = set()
        self.urls: list[str] = []
        self.section, self.row, self.cell = "", None, None
        self.feed(html)

    def handle_starttag(self, tag, attrs):
        self.tags.add(tag)
        a = dict(attrs)
        self.urls += [v for k, v in attrs if k in ("href", "src", "xlink:href", "action") and v]
        if tag == "section":
            self.section = a["id"]
            self.tables.setdefault(self.section, [])
        elif tag == "tr":
            self.row = []
        elif tag in ("td", "th"):
            self.cell = ""

    def handle_endtag(self, tag):
        if tag in ("td", "th") and self.row is not None:
            self.row.append(self.cell.strip())
            self.cell = None
        elif tag == "tr":
            self.tables[self.section].append(self.row)
            self.row = None

    def handle_data(self, data):
        if self.cell is not None:
            self.cell += data

    def value(self, section: str, label: str, column: int = 1) -> str:
        return next(r[column] for r in self.tables[section] if r and r[0].startswith(label))


@pytest.mark.parametrize("mtype", TYPES)
def test_the_report_shows_what_the_brute_force_simulation_finds(mtype):
    for p in random_designs(mtype, 2, seed=41):
        b = bruteforce.simulate(mtype, p)
        page = Page(synth.report(mtype, p, targets={"time_ratio": b["time_ratio"] * 1.01}))
        assert float(page.value("targets", "time ratio", 2)) == pytest.approx(
            b["time_ratio"], rel=1e-9
        )
        assert float(page.value("targets", "stroke", 2)) == pytest.approx(b["stroke"], rel=1e-9)
        assert page.value("targets", "time ratio", 3) == "missed"  # 1% off
        mu = float(page.value("targets", "least transmission angle", 2))
        assert mu == pytest.approx(b["min_transmission_deg"], abs=1e-6)
        shown = {r[0]: float(r[3]) for r in page.tables["design"][1:]}
        assert all(shown[k] == pytest.approx(v, rel=1e-8) for k, v in p.items())


def test_a_loaded_report_has_the_loads_and_stands_alone():
    b = bruteforce.simulate("crank_shaper", SHAPER)
    targets = {"time_ratio": b["time_ratio"], "stroke": b["stroke"], "bound_deg": 35.0}
    html = synth.report(
        "crank_shaper", SHAPER, load={**LOAD, "flywheel_width": 100.0}, targets=targets
    )
    page = Page(html)
    assert [r[3] for r in page.tables["targets"][1:4]] == ["met", "met", "met"]
    assert set(page.tables) == {
        "drawing",
        "targets",
        "design",
        "motion",
        "loads",
        "sensitivities",
        "limits",
    }
    # the flywheel at the crank's 30 rpm and its steel disc; every joint's force
    assert page.value("loads", "flywheel inertia at 30 rpm")
    assert float(page.value("loads", "… a steel disc 100 mm wide")) > 0
    joints = [r[0] for r in page.tables["loads"] if r and r[0] in ("O2", "O4", "B", "P", "guide")]
    assert joints == ["O2", "O4", "B", "P", "guide"]
    # the torque diagram and the force curves are drawn, with their axes' units
    for title in ("torque, N·m", "force, N", "position, mm", "velocity, mm/s"):
        assert f">{title}</text>" in html
    # nothing fetched: no script, no stylesheet or image from anywhere, no URL in a style
    assert not page.urls
    assert not page.tags & {"script", "link", "img", "iframe", "object", "embed"}
    assert not re.search(r"url\(|@import|https?://(?!www\.w3\.org/2000/svg)", html)


@pytest.mark.parametrize(
    ("kwargs", "loc"),
    [
        ({"targets": {"speed": 3.0}}, ("targets", "speed")),
        ({"targets": {"stroke": float("nan")}}, ("targets", "stroke")),
        ({"length_unit": "in", "load": LOAD}, ("length_unit",)),
        ({"length_unit": "cubits"}, ("length_unit",)),
        ({"crank_angle_deg": float("inf")}, ("crank_angle_deg",)),
    ],
)
def test_bad_input_is_refused_naming_the_field(kwargs, loc):
    with pytest.raises(synth.InvalidParameters) as e:
        synth.report("crank_shaper", SHAPER, **kwargs)
    assert e.value.loc == loc


def test_a_report_of_tiny_numbers_draws_its_charts():
    """A 1 mm crank at 1e-6 rpm: accelerations near 1e-17 m/s², below a fixed number of
    decimals, still get distinct axis ticks (schemathesis found the charts dividing by 0)."""
    load = {"crank_rpm": 1.0000000000000002e-06, "length_unit": "m"}
    html = synth.report("scotch_yoke", {"crank": 0.001}, load=load)
    charts = html.split('<svg class="chart"')[1:]
    assert charts
    for chart in charts:  # each chart's value axis: ticks that differ
        ticks = re.findall(r'text-anchor="end"[^>]*>([^<]+)<', chart)
        assert len(ticks) >= 2 and len(set(ticks)) == len(ticks), ticks
