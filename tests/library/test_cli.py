"""The command line, end to end: ``quickreturn`` (the installed console script) and ``python -m
synth`` in a subprocess, each subcommand; its JSON checked by the brute-force simulation, its
exit status (0 an answer, 1 every type refuses, 2 bad input) and its messages."""

import csv
import io
import json
import math
import re
import shutil
import socket
import subprocess
import sys
import time
import urllib.request
from pathlib import Path
from types import SimpleNamespace

import ezdxf
import pytest

import synth

from ..support import bruteforce
from ..support.assertions import assert_meets
from ..support.motion_bruteforce import brute_motion
from .test_report import Page

CLI = shutil.which("quickreturn", path=str(Path(sys.executable).parent)) or "quickreturn"
WHITWORTH = [
    "-p",
    "crank=75",
    "-p",
    "pivot_distance=50",
    "-p",
    "lever=150",
    "-p",
    "connecting_rod=200",
]


def run(*args, module=False, timeout=120):
    cmd = [sys.executable, "-m", "synth", *args] if module else [CLI, *args]
    return subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)


def test_synthesize_json_meets_the_targets_by_brute_force():
    r = run(
        "synthesize",
        "--time-ratio",
        "1.8",
        "--stroke",
        "250",
        "--bound",
        "40",
        "--json",
        "--type",
        "crank_shaper",
        "--type",
        "whitworth",
        "--fix",
        "crank=60",
    )
    assert r.returncode == 0, r.stderr
    reply = json.loads(r.stdout)
    assert reply["candidates"]
    for c in reply["candidates"]:
        assert c["params"]["crank"] == 60.0
        assert_meets(SimpleNamespace(**c), 1.8, 250.0, 40.0)


def test_synthesize_table_and_csv():
    args = (
        "synthesize",
        "--time-ratio",
        "2",
        "--stroke",
        "450",
        "--type",
        "crank_shaper",
        "--objective",
        "max_transmission_angle",
    )
    table = run(*args)
    assert table.returncode == 0 and "crank_shaper" in table.stdout and "lever 450" in table.stdout
    rows = list(csv.DictReader(io.StringIO(run(*args, "--csv").stdout)))
    assert rows and all(row["type"] == "crank_shaper" for row in rows)
    for row in rows:
        params = {
            k: float(row[k]) for k in ("crank", "pivot_distance", "lever", "ram_link", "ram_height")
        }
        b = bruteforce.simulate("crank_shaper", params)
        assert b["time_ratio"] == pytest.approx(2.0, rel=1e-9)
        assert b["stroke"] == pytest.approx(450.0, rel=1e-9)


def test_a_certified_optimum_says_so_in_the_table_and_the_csv():
    args = (
        "synthesize",
        "--time-ratio",
        "1.6",
        "--stroke",
        "300",
        "--bound",
        "20",
        "--type",
        "whitworth",
        "--objective",
        "min_peak_acceleration",
        "--time-budget-ms",
        "60000",
    )
    table = run(*args)
    assert table.returncode == 0, table.stderr
    line = next(x for x in table.stdout.splitlines() if "certified" in x)
    assert line.startswith("#1 is certified the best whitworth (gap ")
    assert float(line.split("gap ")[1].rstrip(")")) <= 1e-9
    rows = list(csv.DictReader(io.StringIO(run(*args, "--csv").stdout)))
    assert rows[0]["certified"] == "True" and float(rows[0]["gap"]) <= 1e-9
    assert all(row["certified"] == "False" for row in rows[1:])


def test_every_type_refusing_exits_1_with_the_reasons():
    r = run(
        "synthesize",
        "--time-ratio",
        "1.8",
        "--stroke",
        "250",
        "--bound",
        "89",
        "--type",
        "whitworth",
        "--type",
        "offset_slider_crank",
    )
    assert r.returncode == 1
    assert "whitworth: no design (TRANSMISSION_UNREACHABLE)" in r.stdout
    assert "offset_slider_crank: no design" in r.stdout


@pytest.mark.parametrize(
    ("args", "library"),
    [
        (
            ("synthesize", "--time-ratio", "1.8", "--stroke", "-250"),
            lambda: synth.synthesize(1.8, -250.0),
        ),
        (
            (
                "synthesize",
                "--time-ratio",
                "1.8",
                "--stroke",
                "250",
                "--type",
                "crank_shaper",
                "--fix",
                "rocker=3",
            ),
            lambda: synth.synthesize(
                1.8, 250.0, mechanisms=[{"type": "crank_shaper", "fixed": {"rocker": 3.0}}]
            ),
        ),
        (
            (
                "analyze",
                "whitworth",
                "-p",
                "crank=75",
                "-p",
                "pivot_distance=50",
                "-p",
                "lever=150",
                "-p",
                "connecting_rod=20",
            ),
            lambda: synth.analyze(
                "whitworth", {"crank": 75, "pivot_distance": 50, "lever": 150, "connecting_rod": 20}
            ),
        ),
    ],
)
def test_bad_input_exits_2_with_the_librarys_message(args, library):
    with pytest.raises(synth.SynthError) as e:
        library()
    r = run(*args)
    assert r.returncode == 2 and not r.stdout
    assert r.stderr.startswith("error: ") and e.value.msg in r.stderr


@pytest.mark.parametrize(
    ("args", "words"),
    [
        (("synthesize", "--time-ratio", "x", "--stroke", "250"), ["--time-ratio", "'x'"]),
        (("synthesize", "--stroke", "250"), ["--time-ratio"]),
        (("analyze", "whitworth", "-p", "crank"), ["--param", "name=value"]),
        (("analyze", "whitworth", "-p", "crank=1", "--load", "{"), ["--load", "not JSON"]),
        (
            ("analyze", "whitworth", "-p", "crank=1", "--load", '{"length_unit": "mm", "rpm": 4}'),
            ["--load", "no field 'rpm'", "crank_rpm"],
        ),
        (("analyze", "whitworth", "--frobnicate"), ["--frobnicate"]),
        (("analyze", "whitworthh"), ["whitworthh"]),
    ],
)
def test_a_bad_flag_exits_2_naming_it(args, words):
    r = run(*args)
    assert r.returncode == 2
    assert all(w in r.stderr for w in words), r.stderr


def test_analyze_json_csv_and_table_agree_with_the_simulation():
    reply = json.loads(run("analyze", "whitworth", *WHITWORTH, "--json").stdout)
    b = bruteforce.simulate("whitworth", reply["params"])
    assert reply["time_ratio"] == pytest.approx(b["time_ratio"], rel=1e-9)
    assert reply["stroke"] == pytest.approx(b["stroke"], rel=1e-9)
    assert "curves" not in reply  # none asked
    r = run("analyze", "whitworth", *WHITWORTH, "--samples", "8", "--include", "pins", "--csv")
    rows = list(csv.DictReader(io.StringIO(r.stdout)))
    assert [float(row["crank_angle_deg"]) for row in rows] == [45.0 * k for k in range(8)]
    for row in rows:  # the ram's pin is where the position says
        assert float(row["R_y"]) == pytest.approx(float(row["position"]), rel=1e-12)
    text = run("analyze", "whitworth", *WHITWORTH).stdout
    assert f"time ratio {reply['time_ratio']:.9g}" in text


def test_analyze_with_a_load_gives_the_loads():
    load = {"length_unit": "mm", "crank_rpm": 40, "cutting_force": 2000, "slider_mass": 60}
    reply = json.loads(
        run("analyze", "whitworth", *WHITWORTH, "--load", json.dumps(load), "--json").stdout
    )
    direct = synth.analyze("whitworth", reply["params"], load=synth.Load(**load))
    assert reply["loads"]["torque"]["max"] == direct.loads.torque.max


def test_a_loaded_synthesis_prints_what_the_drive_needs():
    """The table and the CSV carry each candidate's peak torque, motor and flywheel, as the
    library's analysis of the printed design gives them."""
    load = {"length_unit": "mm", "crank_rpm": 40, "cutting_force": 2000, "slider_mass": 60}
    args = (
        "synthesize",
        "--time-ratio",
        "1.5",
        "--stroke",
        "300",
        "--bound",
        "20",
        "--type",
        "whitworth",
        "--objective",
        "min_peak_torque",
        "--load",
        json.dumps(load),
    )
    text = run(*args).stdout.splitlines()
    header = text[0].split("  ")
    assert {"peak torque N·m", "motor W", "flywheel kg·m²"} <= {h.strip() for h in header}
    (row,) = list(csv.DictReader(io.StringIO(run(*args, "--csv").stdout)))[:1]
    params = {k: float(row[k]) for k in ("crank", "pivot_distance", "lever", "connecting_rod")}
    q = synth.analyze("whitworth", params, load=load).loads
    assert float(row["peak_torque_Nm"]) == pytest.approx(q.torque.max, rel=1e-9)
    assert float(row["flywheel_kgm2"]) == pytest.approx(q.flywheel.inertia, rel=1e-9)
    assert f"{q.torque.max:.6g}" in text[1] and f"{q.flywheel.inertia:.6g}" in text[1]


def test_analyze_prints_the_flywheel_and_the_motor_on_their_shafts():
    """The flywheel at 1 450 rpm: the crank shaft's inertia × (40 / 1 450)², as the library
    gives it on the crank shaft; the steel disc of that inertia 80 mm wide (I = ρ π d⁴ w / 32,
    solved for d here); the motor's torque at 960 rpm, its rated power over its speed."""
    load = {"length_unit": "mm", "crank_rpm": 40, "cutting_force": 2000, "slider_mass": 60}
    shafts = {"flywheel_rpm": 1450, "flywheel_width": 80, "motor_rpm": 960, "efficiency": 0.8}
    text = run("analyze", "whitworth", *WHITWORTH, "--load", json.dumps({**load, **shafts}))
    p = {"crank": 75.0, "pivot_distance": 50.0, "lever": 150.0, "connecting_rod": 200.0}
    q = synth.analyze("whitworth", p, load=load).loads
    inertia = q.flywheel.inertia * (40 / 1450) ** 2
    disc = (32 * inertia / (7850 * math.pi * 0.080)) ** 0.25 * 1000
    motor = q.power.mean / 0.8 / (960 * math.pi / 30)
    (fly,) = [line for line in text.stdout.splitlines() if line.startswith("flywheel ")]
    assert (
        fly == f"flywheel {inertia:.6g} kg·m² on a shaft at 1450 rpm: a steel disc "
        f"{disc:.6g} mm across, 80 wide"
    )
    assert f"motor {q.power.mean / 0.8:.6g} W, {motor:.6g} N·m at 960 rpm" in text.stdout


def test_analyze_prints_what_include_asks_for():
    """The envelope and the sensitivities in the text; the stroke's derivative in the lever,
    by central differences of the analysed stroke."""
    text = run(
        "analyze", "whitworth", *WHITWORTH, "--include", "envelope", "--include", "sensitivities"
    ).stdout
    p = {"crank": 75.0, "pivot_distance": 50.0, "lever": 150.0, "connecting_rod": 200.0}
    e = synth.analyze("whitworth", p, include=["envelope"]).envelope
    assert f"({e.width:.6g} × {e.height:.6g})" in text
    h = 1e-4
    up, down = ({**p, "lever": 150.0 + d} for d in (h, -h))
    slope = (synth.analyze("whitworth", up).stroke - synth.analyze("whitworth", down).stroke) / (
        2 * h
    )
    (lever,) = [line.split() for line in text.splitlines() if line.startswith("lever ")]
    assert float(lever[2]) == pytest.approx(slope, rel=1e-6)


def test_sweep_csv_and_json():
    args = (
        "sweep",
        "crank_shaper",
        "-p",
        "crank=120",
        "-p",
        "pivot_distance=240",
        "-p",
        "lever=450",
        "--vary",
        "crank",
        "--start",
        "100",
        "--stop",
        "300",
        "--points",
        "5",
    )
    rows = list(csv.DictReader(io.StringIO(run(*args, "--csv").stdout)))
    assert [row["valid"] for row in rows] == ["True"] * 3 + ["False"] * 2
    for row in rows[:3]:
        p = {"crank": float(row["crank"]), "pivot_distance": 240.0, "lever": 450.0}
        assert float(row["time_ratio"]) == pytest.approx(
            bruteforce.simulate("crank_shaper", p)["time_ratio"], rel=1e-9
        )
    reply = json.loads(run(*args, "--json").stdout)
    assert reply["time_ratio"][3] is None  # an invalid design: null, as the API says
    assert "valid crank: [100, 210]" in run(*args).stdout


def test_export_writes_a_drawing_cad_reads(tmp_path):
    out = tmp_path / "shaper.dxf"
    r = run(
        "export",
        "crank_shaper",
        "-p",
        "crank=120",
        "-p",
        "pivot_distance=240",
        "-p",
        "lever=450",
        "--format",
        "dxf",
        "--crank-angle",
        "30",
        "-o",
        str(out),
    )
    assert r.returncode == 0, r.stderr
    lines = {e.dxf.layer: e for e in ezdxf.readfile(out).modelspace().query("LINE")}
    assert (lines["lever"].dxf.end - lines["lever"].dxf.start).magnitude == pytest.approx(450.0)
    svg = run(
        "export", "crank_shaper", "-p", "crank=120", "-p", "pivot_distance=240", "-p", "lever=450"
    ).stdout
    assert svg.startswith("<?xml") and 'width="' in svg


def test_report_writes_a_page_with_the_design_and_its_loads(tmp_path):
    out = tmp_path / "whitworth.html"
    load = json.dumps({"length_unit": "mm", "crank_rpm": 40, "cutting_force": 2000})
    flags = ["--stroke", "300", "--bound", "30", "--load", load, "-o", str(out)]
    r = run("report", "whitworth", *WHITWORTH, *flags)
    assert r.returncode == 0, r.stderr
    page = Page(out.read_text())
    b = bruteforce.simulate(
        "whitworth", {"crank": 75, "pivot_distance": 50, "lever": 150, "connecting_rod": 200}
    )
    assert float(page.value("targets", "time ratio", 2)) == pytest.approx(b["time_ratio"], rel=1e-9)
    assert page.value("targets", "stroke", 3) == (
        "met" if abs(b["stroke"] - 300) < 3e-7 else "missed"
    )
    assert "loads" in page.tables
    bad = run("report", "whitworth", *WHITWORTH, "--length-unit", "in", "--load", load)
    assert bad.returncode == 2 and "length_unit" in bad.stderr


def test_animate_writes_a_gif_of_a_turn(tmp_path):
    from PIL import Image

    out = tmp_path / "whitworth.gif"
    r = run("animate", "whitworth", *WHITWORTH, "--frames", "12", "-o", str(out))
    assert r.returncode == 0, r.stderr
    img = Image.open(out)
    assert img.format == "GIF" and img.n_frames == 12
    bad = run("animate", "whitworth", *WHITWORTH, "--frames", "0")
    assert bad.returncode == 2 and "frames" in bad.stderr


def test_analyze_prints_each_section_asked_for():
    """--include's sections in the table, each checked from outside: the motion by the brute
    force's maximiser, the stroke's sensitivity by its central difference, the envelope's link
    lengths by their sum; the forces' curves as CSV columns, one per joint and the guide."""
    design = {"crank": 75.0, "pivot_distance": 50.0, "lever": 150.0, "connecting_rod": 200.0}
    flags = [f"--include={k}" for k in ("motion", "sensitivities", "envelope")]
    r = run("analyze", "whitworth", *WHITWORTH, *flags)
    assert r.returncode == 0, r.stderr
    lines = r.stdout.splitlines()
    (motion,) = [x for x in lines if x.startswith("cutting-speed fluctuation")]
    numbers = [float(x) for x in re.findall(r"\d+\.?\d*", motion)]
    _, middle, working, returning = brute_motion("whitworth", design)
    assert numbers[0] == pytest.approx(middle, rel=1e-5)
    assert numbers[1:3] == pytest.approx([working, returning], rel=1e-5)
    assert motion.endswith("in ω²·stroke")
    (envelope,) = [x for x in lines if x.startswith("envelope")]
    assert envelope.endswith(f"link lengths {sum(design.values()):g}")
    (lever,) = [x.split() for x in lines if x.startswith("lever ")]
    h = 1e-4
    up, down = (bruteforce.simulate("whitworth", {**design, "lever": 150.0 + d}) for d in (h, -h))
    assert float(lever[2]) == pytest.approx((up["stroke"] - down["stroke"]) / (2 * h), rel=1e-5)
    load = json.dumps({"length_unit": "mm", "crank_rpm": 40, "cutting_force": 2000})
    curves = run(
        "analyze",
        "whitworth",
        *WHITWORTH,
        "--include",
        "forces",
        "--samples",
        "6",
        "--load",
        load,
        "--csv",
    )
    header = curves.stdout.splitlines()[0].split(",")
    joints = synth.analyze("whitworth", design, load=json.loads(load)).loads.joints
    assert {f"force_{k}" for k in [*joints, "guide"]} <= set(header)


def test_atlas_writes_its_tables(tmp_path):
    r = run(
        "atlas",
        "--types",
        "crank_shaper",
        "--ratios",
        "1.5:2:2",
        "--bounds",
        "20",
        "--out",
        str(tmp_path),
        "--inline",
    )
    assert r.returncode == 0, r.stderr
    assert (tmp_path / "frontier.csv").exists() and "2 points" in r.stdout


def test_python_m_synth_is_the_same_command():
    r = run("--version", module=True)
    assert r.returncode == 0 and synth.__version__ in r.stdout
    assert "synthesize" in run("--help", module=True).stdout


def test_serve_answers_on_its_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    server = subprocess.Popen(
        [CLI, "serve", "--port", str(port)], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL
    )
    try:
        for _ in range(300):
            try:
                with urllib.request.urlopen(f"http://127.0.0.1:{port}/health", timeout=1) as r:
                    assert r.status == 200
                    break
            except OSError:
                time.sleep(0.1)
        else:
            pytest.fail("the service did not answer")
    finally:
        server.terminate()
        server.wait(timeout=30)


def test_every_option_says_what_it_is_for():
    """Each subcommand's and the atlas's options carry help text."""
    import argparse

    import click

    from synth.atlas import __main__ as atlas_main
    from synth.cli import main

    bare = []
    for name, command in main.commands.items():
        for p in command.params:
            if isinstance(p, click.Option) and not p.hidden and not (p.help or p.is_flag):
                bare.append(f"{name} {p.opts[0]}")
    assert not bare, bare
    captured: list[argparse.ArgumentParser] = []
    real = argparse.ArgumentParser.parse_args

    def keep(self, *a, **k):
        captured.append(self)
        raise SystemExit(0)

    argparse.ArgumentParser.parse_args = keep
    try:
        with pytest.raises(SystemExit):
            atlas_main.main([])
    finally:
        argparse.ArgumentParser.parse_args = real
    (parser,) = captured
    assert all(a.help for a in parser._actions if a.option_strings), [
        a.option_strings for a in parser._actions if not a.help
    ]


def test_an_answer_not_certified_says_why_in_the_table_and_the_csv():
    args = (
        "synthesize",
        "--time-ratio",
        "1.6",
        "--stroke",
        "300",
        "--bound",
        "20",
        "--type",
        "drag_link_slider",
        "--objective",
        "min_peak_acceleration",
    )
    table = run(*args)
    assert table.returncode == 0, table.stderr
    lines = [x for x in table.stdout.splitlines() if "certified" in x]
    assert len(lines) == 1  # once for the type, at its best
    assert lines[0].startswith("#1 is not certified the best drag_link_slider: ")
    assert lines[0].endswith("SLSQP's local optimum from ranked starts")
    rows = list(csv.DictReader(io.StringIO(run(*args, "--csv").stdout)))
    assert all(row["certified"] == "False" and "SLSQP" in row["uncertified"] for row in rows)
