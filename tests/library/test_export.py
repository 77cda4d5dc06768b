"""Drawings that go to CAD and documents: every type in both formats, read back as a CAD
program and a browser would (ezdxf, an XML parser); the links as long as the design, the
stroke as the brute-force simulation's, the SVG in true size, the pins named; bad input
refused naming the field."""

import io
import itertools
import math
import re
import xml.etree.ElementTree as ET

import ezdxf
import matplotlib
import numpy as np
import pytest

import synth
from synth.load import LENGTH_UNITS

from ..support import bruteforce
from ..support.designs import random_designs

matplotlib.use("Agg")
TYPES = synth.mechanisms.all_types()
SVG = "{http://www.w3.org/2000/svg}"


def designs(mtype):
    return random_designs(mtype, 3, seed=31)


def read_dxf(doc: bytes):
    return ezdxf.read(io.StringIO(doc.decode()))


@pytest.mark.parametrize("mtype", TYPES)
def test_a_dxf_reads_back_with_the_designs_lengths_and_stroke(mtype):
    for i, p in enumerate(designs(mtype)):
        angle = 37.0 * i
        doc = read_dxf(synth.export(mtype, p, "dxf", angle, "mm", paths=i == 0))
        assert doc.units == ezdxf.units.MM
        msp = doc.modelspace()
        lines = {e.dxf.layer: e for e in msp.query("LINE") if e.dxf.layer in p}
        drawn = {name for name, *_ in synth.mechanisms.get(mtype).drawing if p.get(name, 0) > 0}
        assert set(lines) == drawn
        for name, e in lines.items():
            length = (e.dxf.end - e.dxf.start).magnitude
            assert length == pytest.approx(p[name], rel=1e-9), name
        pins = synth.joints(mtype, p, [angle])
        circles = msp.query('CIRCLE[layer=="PINS"]')
        assert len(circles) == len(pins)
        near = 1e-9 * (1 + max(abs(v) for v in p.values()))
        for e in circles:  # each at its pin
            c = (e.dxf.center.x, e.dxf.center.y)
            assert min(math.dist(c, xy[0]) for xy in pins.values()) < near
        labels = {e.dxf.text for e in msp.query('TEXT[layer=="PINS"]')}
        assert labels == set(pins)
        (dim,) = msp.query('DIMENSION[layer=="STROKE"]')
        stroke = bruteforce.simulate(mtype, p)["stroke"]
        assert dim.get_measurement() == pytest.approx(stroke, rel=1e-9)
        # what a CAD program shows: the dimension block's text, the stroke to 6 decimals
        (shown,) = [e.plain_text() for e in dim.get_geometry_block() if e.dxftype() == "MTEXT"]
        assert shown == f"{stroke:.6f}".rstrip("0").rstrip(".")
        assert len(msp.query('*[layer=="PIVOTS"]')) > 0 and len(msp.query('*[layer=="GUIDE"]')) == 2
        fixed = [
            k
            for k, xy in synth.joints(mtype, p, [0.0, 90.0, 200.0]).items()
            if np.ptp(xy, axis=0).max() == 0
        ]
        paths = msp.query('LWPOLYLINE[layer=="PATHS"]')
        assert len(paths) == (len(pins) - len(fixed) if i == 0 else 0)


@pytest.mark.parametrize("mtype", TYPES)
def test_by_default_the_drawing_shows_the_mechanism_open(mtype):
    """Without a crank angle the crank stands a third of the way through the working stroke
    (the brute force's), the ram away from both dead centres, no three pins of a link chain
    on one line (at 0°, and half way, a crank shaper's links lay on one line)."""
    for p in designs(mtype):
        b = bruteforce.simulate(mtype, p)
        start = b["theta_min"] if b["working_direction"] == 1 else b["theta_max"]
        mid = math.degrees(start + b["working_angle"] / 3) % 360
        root = ET.fromstring(synth.export(mtype, p))
        assert float(root.get("data-crank-angle-deg")) == pytest.approx(mid, abs=1e-5)  # 9 digits
        s = bruteforce.position(mtype, p, np.radians([mid]))[0]
        assert b["s_min"] + 0.1 * b["stroke"] < s < b["s_max"] - 0.1 * b["stroke"]
        at = {k: xy[0] for k, xy in synth.joints(mtype, p, [mid]).items()}
        m = synth.mechanisms.get(mtype)
        rigid = m.frame(m.variant(m.complete(p))).bodies  # members of one body keep their angle
        links = [(k, a, c) for k, a, c in m.drawing if p.get(k, 0)]
        for (k, a, c), (n, d, e) in itertools.combinations(links, 2):
            shared = {a, c} & {d, e}
            if len(shared) == 1 and not any({k, n} <= set(b) for b in rigid):
                (o,) = shared  # two links at one pin: not folded onto one line
                (ux, uy), (vx, vy) = (np.subtract(at[q], at[o]) for q in ({a, c, d, e} - shared))
                sine = abs(ux * vy - uy * vx) / (math.hypot(ux, uy) * math.hypot(vx, vy))
                assert sine > math.sin(math.radians(1.0)), (mtype, p, k, n)


@pytest.mark.parametrize("mtype", TYPES)
@pytest.mark.parametrize("unit", list(LENGTH_UNITS))
def test_a_dxf_dimensions_every_link_and_has_a_title_block(mtype, unit):
    """Each link's dimension, read back as a CAD program shows it: the text in its block is
    the design's length to 6 decimals, in any unit; the title block names the type, the
    unit and scale, the brute force's time ratio and stroke, and the project's version."""
    p = designs(mtype)[0]
    msp = read_dxf(synth.export(mtype, p, "dxf", 50.0, unit)).modelspace()
    drawn = sorted(
        p[name] for name, *_ in synth.mechanisms.get(mtype).drawing if p.get(name, 0) > 0
    )
    dims = msp.query('DIMENSION[layer=="DIMENSIONS"]')
    assert sorted(d.get_measurement() for d in dims) == pytest.approx(drawn, rel=1e-9)
    for d in dims:
        (shown,) = [e.plain_text() for e in d.get_geometry_block() if e.dxftype() == "MTEXT"]
        assert shown == f"{d.get_measurement():.6f}".rstrip("0").rstrip(".")
    title = "\n".join(e.dxf.text for e in msp.query('TEXT[layer=="TITLE"]'))
    b = bruteforce.simulate(mtype, p)
    assert f"({mtype})" in title and f"lengths in {unit}, scale 1:1" in title
    said = re.search(r"time ratio (\S+), stroke (\S+) " + unit, title)
    assert said, title
    assert float(said[1]) == pytest.approx(b["time_ratio"], rel=1e-8)
    assert float(said[2]) == pytest.approx(b["stroke"], rel=1e-8)
    assert f"quickreturn-synth {synth.__version__}" in title
    assert len(msp.query('LWPOLYLINE[layer=="TITLE"]')) == 1


@pytest.mark.parametrize("mtype", TYPES)
@pytest.mark.parametrize("unit", list(LENGTH_UNITS))
def test_an_svg_is_true_size_with_the_links_and_pins(mtype, unit):
    p = designs(mtype)[0]
    root = ET.fromstring(synth.export(mtype, p, "svg", 10.0, unit))
    _, _, w, h = map(float, root.get("viewBox").split())
    width, height = root.get("width"), root.get("height")
    assert width.endswith("mm") and height.endswith("mm")
    mm = LENGTH_UNITS[unit] * 1e3  # one unit of the design drawn this long
    assert float(width[:-2]) == pytest.approx(w * mm, rel=1e-5)
    assert float(height[:-2]) == pytest.approx(h * mm, rel=1e-5)
    for e in root.iter(f"{SVG}line"):
        if "link" in e.get("class", "").split():
            name = e.get("class").split("link-")[1]
            x1, y1, x2, y2 = (float(e.get(k)) for k in ("x1", "y1", "x2", "y2"))
            assert math.hypot(x2 - x1, y2 - y1) == pytest.approx(p[name], rel=1e-9), name
    pins = synth.joints(mtype, p, [10.0])
    assert {e.get("data-pin") for e in root.iter(f"{SVG}circle")} == set(pins)
    assert {e.text for e in root.iter(f"{SVG}text") if e.get("class") == "pin-label"} == set(pins)
    (label,) = [e.text for e in root.iter(f"{SVG}text") if e.get("class") == "dimension"]
    assert label == f"stroke {bruteforce.simulate(mtype, p)['stroke']:.6g}"


@pytest.mark.parametrize("mtype", TYPES)
def test_an_svg_dimensions_every_link_and_has_a_title_block(mtype):
    """What the SVG says: each link's symbol and length (6 figures), and a title block with
    the type, the brute force's time ratio and stroke in the unit, and the project's version."""
    p = designs(mtype)[0]
    root = ET.fromstring(synth.export(mtype, p, "svg", 50.0, "in"))
    m = synth.mechanisms.get(mtype)
    shown = sorted(e.text for e in root.iter(f"{SVG}text") if e.get("class") == "link-dimension")
    drawn = [(name, p[name]) for name, *_ in m.drawing if p.get(name, 0) > 0]
    assert shown == sorted(f"{m.parameter(n).symbol} {v:.6g}" for n, v in drawn)
    title = "\n".join(e.text for e in root.iter(f"{SVG}text") if e.get("class") == "title")
    b = bruteforce.simulate(mtype, p)
    said = re.search(r"time ratio (\S+), stroke (\S+) in", title)
    assert said and f"({mtype})" in title and "lengths in in, scale 1:1" in title, title
    assert float(said[1]) == pytest.approx(b["time_ratio"], rel=1e-8)
    assert float(said[2]) == pytest.approx(b["stroke"], rel=1e-8)
    assert f"quickreturn-synth {synth.__version__}" in title


SLOT_DRIVES = {  # the slot across the ram's path, and the pin it holds
    "scotch_yoke": ({"crank": 100.0}, "B"),
    "crank_shaper": ({"crank": 120.0, "pivot_distance": 240.0, "lever": 450.0}, "P"),
    "crank_rocker_slider": (
        {"ground": 240.0, "crank": 80.0, "coupler": 240.0, "rocker": 200.0, "rocker_arm": 300.0},
        "C",
    ),
}


@pytest.mark.parametrize("mtype", list(SLOT_DRIVES))
def test_a_slot_across_the_ram_holds_its_pin_at_every_angle(mtype):
    """What the SVG shows: at each crank angle the pin lies on the slot the ram carries (a
    slot drive's, the Scotch yoke's), between its ends."""
    p, pin = SLOT_DRIVES[mtype]
    for angle in range(0, 360, 15):
        root = ET.fromstring(synth.export(mtype, p, "svg", float(angle)))
        (slot,) = [e for e in root.iter(f"{SVG}line") if "yoke" in e.get("class", "").split()]
        a = np.array([float(slot.get("x1")), float(slot.get("y1"))])
        b = np.array([float(slot.get("x2")), float(slot.get("y2"))])
        (c,) = [e for e in root.iter(f"{SVG}circle") if e.get("data-pin") == pin]
        q = np.array([float(c.get("cx")), float(c.get("cy"))])
        t = (q - a) @ (b - a) / ((b - a) @ (b - a))
        assert 0.0 < t < 1.0, (angle, t)
        assert np.linalg.norm(a + t * (b - a) - q) <= 1e-9 * np.linalg.norm(b - a), angle


def test_the_drawing_puts_the_ram_on_its_guide_between_the_dead_centres():
    from synth.drawing.model import drawing

    for mtype in TYPES:
        for p in designs(mtype):
            d = drawing(mtype, p, 123.0)
            (ax, ay), (bx, by) = d.guide
            rx, ry = d.pins[d.ram]
            cross = (bx - ax) * (ry - ay) - (by - ay) * (rx - ax)
            assert abs(cross) <= 1e-9 * math.hypot(bx - ax, by - ay) ** 2  # on the guide's line
            (sx, sy), (ex, ey) = d.stroke
            run = math.hypot(ex - sx, ey - sy)
            assert math.hypot(rx - sx, ry - sy) + math.hypot(rx - ex, ry - ey) == pytest.approx(
                run, rel=1e-9
            )  # between the dead centres
            assert "O2" in d.ground


def test_draw_gives_a_figure_with_each_link():
    p = {"crank": 120.0, "pivot_distance": 240.0, "lever": 450.0}
    fig = synth.draw("crank_shaper", p, crank_angle_deg=30.0)
    labels = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert labels == ["pivot_distance 240", "crank 120", "lever 450"]
    assert fig.axes[0].get_aspect() == 1.0


@pytest.mark.parametrize(
    ("kw", "field"),
    [
        ({"format": "pdf"}, "format"),
        ({"length_unit": "ft"}, "length_unit"),
        ({"crank_angle_deg": math.nan}, "crank_angle_deg"),
        ({"params": {"crank": 120.0, "pivot_distance": 240.0, "levr": 450.0}}, "levr"),
    ],
)
def test_bad_export_arguments_name_the_field(kw, field):
    args = {
        "mechanism": "crank_shaper",
        "params": {"crank": 120.0, "pivot_distance": 240.0, "lever": 450.0},
    } | kw
    with pytest.raises(synth.InvalidParameters) as e:
        synth.export(**args)
    assert field in e.value.loc


def test_a_design_that_cannot_run_is_not_drawn():
    with pytest.raises(synth.InvalidDesign):
        synth.export(
            "whitworth", {"crank": 75, "pivot_distance": 50, "lever": 150, "connecting_rod": 20}
        )


def test_paths_close_over_a_turn():
    from synth.drawing.model import drawing

    d = drawing(
        "whitworth",
        {"crank": 75, "pivot_distance": 50, "lever": 150, "connecting_rod": 200},
        paths=True,
    )
    assert d.paths is not None and "O2" not in d.paths and "O4" not in d.paths
    for xy in d.paths.values():
        assert np.allclose(xy[0], xy[-1], atol=1e-9)


def test_animate_gives_a_gif_of_a_turn(tmp_path):
    from PIL import Image

    out = tmp_path / "shaper.gif"
    gif = synth.animate(
        "crank_shaper",
        {"crank": 120.0, "pivot_distance": 240.0, "lever": 450.0},
        frames=6,
        path=str(out),
    )
    assert out.read_bytes() == gif
    img = Image.open(out)
    assert img.format == "GIF" and img.n_frames == 6
    first = np.asarray(img.convert("RGB"))
    img.seek(3)  # half a turn on: the crank has moved
    assert not np.array_equal(first, np.asarray(img.convert("RGB")))
