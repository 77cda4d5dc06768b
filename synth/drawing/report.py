"""A design report (``synth.report``, ``POST /v1/report``, ``quickreturn report``): one
printable HTML page that stands alone (its styles, drawing and charts inline, nothing fetched
from anywhere), with what a workshop and a reviewer ask of a design: the drawing, the targets
and what the design achieves, its parts, the motion over a turn, the loads with the torque
diagram and the flywheel, the joint forces, the tolerance sensitivities and the limits the
design rests on."""

from __future__ import annotations

import datetime
import math
import re
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import KW_ONLY, dataclass, field
from typing import Annotated, Any
from xml.sax.saxutils import escape

import numpy as np
from annotated_types import Ge, Gt, Le

from ..analysis.kinematics import analyze
from ..errors import InvalidParameters
from ..load import LENGTH_UNITS, Load
from ..requests import Help, OneOf, check, held, keyword
from ..results import Analysis, Loads
from ..version import __version__
from .model import drawing, drawn
from .plot import Series, chart
from .svg import svg

SAMPLES = 361  # the curves' crank angles (1° apart)
ANGLE_TICKS = [60.0 * k for k in range(7)]
STYLE = """
body{font-family:sans-serif;color:#222;max-width:190mm;margin:1em auto;padding:0 1em}
h1{font-size:1.5em;margin-bottom:.2em}h2{font-size:1.15em;border-bottom:1px solid #999;
margin-top:1.6em}table{border-collapse:collapse;margin:.5em 0}td,th{border:1px solid #bbb;
padding:.2em .6em;text-align:left}td.n{text-align:right;font-variant-numeric:tabular-nums}
.meta{color:#555}.figure svg{width:100%;height:auto;max-height:120mm}
svg.chart{width:100%;height:auto;max-width:640px;display:block}
.met{color:#1a7f37}.missed{color:#b42318}
@page{size:A4;margin:14mm}@media print{section{break-inside:avoid}}
"""


@dataclass(frozen=True)
class Goals:
    """What a report compares the design with, each optional (``targets``)."""

    time_ratio: Annotated[
        float | None, Ge(1.0), Help("a target to compare the design with: slow/quick crank angle")
    ] = None
    stroke: Annotated[float | None, Gt(0.0), Help("a target, in the design's length unit")] = None
    bound_deg: Annotated[
        float | None,
        Ge(0.0),
        Le(90.0),
        Help("a target: the least transmission angle, degrees", "bound"),
    ] = None

    def __post_init__(self) -> None:
        check(self, at="targets")

    @property
    def given(self) -> dict[str, float]:
        """The targets given, by name."""
        return {k: v for k, v in vars(self).items() if v is not None}


@dataclass(frozen=True)
class ReportRequest:
    """``report``'s arguments (``run``), checked when built: ``load`` a ``Load`` or a mapping
    of its fields; ``unit`` the lengths' unit (``length_unit``, else the load's, else mm)."""

    mechanism: Annotated[str, Help("the design's type")]
    params: Annotated[Mapping[str, float], Help("its parameters, by name, in length_unit")]
    _: KW_ONLY
    load: Annotated[
        Load | None,
        Help(
            "what the design drives: adds the loads, the torque diagram, the flywheel and the "
            "joint forces"
        ),
    ] = None
    targets: Annotated[
        Goals | Mapping[str, float] | None, Help("compared with what the design achieves")
    ] = None
    crank_angle_deg: Annotated[
        float | None,
        Help("the drawing's, degrees; omitted: where the mechanism stands open", "crank-angle"),
    ] = None
    length_unit: Annotated[
        str | None,
        OneOf(tuple(LENGTH_UNITS)),
        Help("the design's lengths; omitted: the load's, else mm"),
    ] = None
    unit: str = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        check(self)
        m = drawn(self.mechanism)
        for k in self.params:
            m.parameter(k)
        q = Load.of(self.load)
        object.__setattr__(self, "load", q)
        unit = self.length_unit or (q.length_unit if q else "mm")
        if q is not None and unit != q.length_unit:
            msg = f"length_unit {unit!r} differs from the load's {q.length_unit!r}"
            raise InvalidParameters(msg, ("length_unit",))
        object.__setattr__(self, "targets", held(Goals, self.targets, "targets"))
        object.__setattr__(self, "unit", unit)


def run(r: ReportRequest) -> str:
    """The design's report as an HTML document. Lengths are in ``length_unit`` (a load's,
    where one is given; else mm), forces and the rest SI; ``targets`` (``Goals``)
    are compared with what the design achieves; the drawing is at ``crank_angle_deg`` (None:
    where the mechanism stands open).

    >>> page = report("crank_shaper", {"crank": 120, "pivot_distance": 240, "lever": 450})
    >>> page.startswith("<!doctype html>") and "time ratio" in page
    True
    """
    mechanism, params, q, unit = r.mechanism, r.params, r.load, r.unit
    m, goals = drawn(mechanism), (r.targets.given if isinstance(r.targets, Goals) else {})
    angles = np.linspace(0.0, 360.0, SAMPLES)
    include = ("motion", "sensitivities", "envelope", *(("forces",) if q else ()))
    a = analyze(mechanism, params, crank_angles_deg=angles.tolist(), include=include, load=q)
    d = drawing(mechanism, params, r.crank_angle_deg)
    picture = re.sub(r"^<\?xml[^>]*>\s*", "", svg(d, unit))
    now = datetime.datetime.now(datetime.UTC)
    parts = [
        "<!doctype html>",
        '<html lang="en"><head><meta charset="utf-8">',
        f"<title>{escape(m.title)}: design report</title><style>{STYLE}</style></head><body>",
        f"<h1>{escape(m.title)}: design report</h1>",
        f'<p class="meta">quickreturn-synth {escape(__version__)} · {now:%Y-%m-%d %H:%M} UTC · '
        f"lengths in {unit}, forces in N, torques in N·m</p>",
        _section(
            "drawing",
            "Drawing",
            f'<p>At crank angle {d.crank_angle_deg:.4g}°.</p><div class="figure">{picture}</div>',
        ),
        _section("targets", "Targets and what the design achieves", _achieved(a, goals, unit)),
        _section(
            "design",
            "The design",
            _table(
                ("part", "symbol", "meaning", f"length, {unit}"),
                (
                    (p.name, p.symbol, p.description, _num(a.params[p.name], 9))
                    for p in m.parameters
                    if p.name in a.params
                ),
            ),
        ),
        _section("motion", "Motion over a crank turn", _motion(a, angles, unit, q)),
    ]
    if a.loads is not None and q is not None:
        parts.append(_section("loads", "Loads", _loads(a, a.loads, angles, q)))
    parts += [
        _section("sensitivities", "Tolerance sensitivities", _sensitivities(a, unit)),
        _section("limits", "The limits the design rests on", _limits(a, goals)),
        "</body></html>",
    ]
    return "\n".join(parts)


report = keyword(ReportRequest, run, "report")


def _section(key: str, title: str, body: str) -> str:
    return f'<section id="{key}"><h2>{escape(title)}</h2>\n{body}</section>'


def _num(x: float | None, digits: int = 6) -> str:
    return "—" if x is None or not math.isfinite(x) else f"{x:.{digits}g}"


def _table(header: Sequence[str], rows: Iterable[Sequence[Any]]) -> str:
    head = "".join(f"<th>{escape(h)}</th>" for h in header)
    body = "".join(
        "<tr>"
        + "".join(
            f'<td class="n">{escape(c)}</td>' if _numeric(c) else f"<td>{escape(str(c))}</td>"
            for c in row
        )
        + "</tr>"
        for row in rows
    )
    return f"<table><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>"


def _numeric(c: Any) -> bool:
    return isinstance(c, str) and bool(re.fullmatch(r"[-+0-9.e—]+", c))


def _achieved(a: Analysis, goals: Mapping[str, float], unit: str) -> str:
    def status(ok: bool) -> str:
        return "met" if ok else "missed"

    rows = []
    for what, got, key, u in (
        ("time ratio", a.time_ratio, "time_ratio", ""),
        ("stroke", a.stroke, "stroke", unit),
    ):
        want = goals.get(key)
        ok = want is None or abs(got - want) <= 1e-9 * abs(want)
        rows.append(
            (
                what + (f", {u}" if u else ""),
                _num(want, 10),
                _num(got, 10),
                "" if want is None else status(ok),
            )
        )
    bound = goals.get("bound_deg")
    mu = a.transmission.min_deg
    rows.append(
        (
            "least transmission angle, °",
            "—" if bound is None else f"≥ {bound:g}",
            _num(mu, 8),
            "" if bound is None else status(mu >= bound - 1e-9),
        )
    )
    e = a.envelope
    extra = (
        []
        if e is None
        else [
            ("sum of the link lengths, " + unit, "—", _num(e.link_length_sum), ""),
            (f"envelope (width × height), {unit}", "—", f"{e.width:.5g} × {e.height:.5g}", ""),
        ]
    )
    return _table(("", "target", "the design", ""), rows + extra)


def _motion(a: Analysis, angles: np.ndarray, unit: str, q: Load | None) -> str:
    c = a.curves
    assert c is not None
    per = (f"{unit}/s", f"{unit}/s²") if q else (f"{unit}/rad", f"{unit}/rad²")
    speed = f" at {q.crank_rpm:g} rpm" if q else " per radian of crank (any speed: × ω, × ω²)"
    x = "crank angle, °"
    out = [f"<p>The ram's motion{escape(speed)}.</p>"]
    out.append(chart(angles, [Series("position", c.position)], x, f"position, {unit}", ANGLE_TICKS))
    out.append(
        chart(angles, [Series("velocity", c.velocity)], x, f"velocity, {per[0]}", ANGLE_TICKS)
    )
    out.append(
        chart(
            angles,
            [Series("acceleration", c.acceleration)],
            x,
            f"acceleration, {per[1]}",
            ANGLE_TICKS,
        )
    )
    out.append(
        chart(
            angles,
            [Series("transmission angle", c.transmission_deg)],
            x,
            "transmission angle, °",
            ANGLE_TICKS,
        )
    )
    mo = a.motion
    if mo is not None:
        f, p = mo.working_speed_fluctuation, mo.peak_acceleration
        out.append(
            _table(
                ("measure", "value"),
                (
                    ("working stroke, crank travel, °", _num(a.working_stroke.crank_angle_deg)),
                    ("return stroke, crank travel, °", _num(a.return_stroke.crank_angle_deg)),
                    ("speed fluctuation over the working stroke (max / mean speed)", _num(f.whole)),
                    ("… over its middle 80 %", _num(f.middle)),
                    ("peak acceleration, working stroke, ω²·stroke", _num(p.working_stroke)),
                    ("peak acceleration, return stroke, ω²·stroke", _num(p.return_stroke)),
                ),
            )
        )
    return "\n".join(out)


def _loads(a: Analysis, ld: Loads, angles: np.ndarray, q: Load) -> str:
    c = a.curves
    assert c is not None and c.torque is not None
    t, pw, fw = ld.torque, ld.power, ld.flywheel
    x = "crank angle, °"
    mean = np.full_like(angles, t.mean)
    out = [
        chart(
            angles,
            [Series("crank torque", c.torque), Series("mean", mean, dashed=True)],
            x,
            "torque, N·m",
            ANGLE_TICKS,
        )
    ]
    rows = [
        ("torque, largest, N·m (at crank angle °)", f"{t.max:.5g} (at {t.max_at_deg:.4g})"),
        ("torque, least, N·m (at crank angle °)", f"{t.min:.5g} (at {t.min_at_deg:.4g})"),
        ("torque, mean / rms, N·m", f"{t.mean:.5g} / {t.rms:.5g}"),
        ("power, mean / peak, W", f"{pw.mean:.5g} / {pw.peak:.5g}"),
        (f"motor's rated power at efficiency {q.efficiency:g}, W", _num(pw.rated, 5)),
    ]
    if pw.motor_torque is not None:
        rows.append((f"motor torque at {q.motor_rpm:g} rpm, N·m", _num(pw.motor_torque, 5)))
    rows += [
        ("flywheel: energy to store, J", _num(fw.energy, 5)),
        (
            f"flywheel inertia at {fw.rpm:g} rpm (Cs {q.speed_fluctuation:g}), kg·m²",
            _num(fw.inertia, 5),
        ),
    ]
    if fw.disc_diameter is not None:
        rows.append(
            (
                f"… a steel disc {q.flywheel_width:g} {q.length_unit} wide: diameter, "
                f"{q.length_unit}",
                _num(fw.disc_diameter, 5),
            )
        )
    out.append(_table(("", "value"), rows))
    forces = [(k, f) for k, f in ld.joints.items()] + [("guide", ld.guide)]
    out.append("<h3>Joint forces</h3>")
    out.append(
        _table(
            ("joint", "largest force, N", "at crank angle, °"),
            ((k, _num(f.max, 5), _num(f.at_deg, 4)) for k, f in forces),
        )
    )
    if c.forces:
        series = [Series(k, v) for k, v in c.forces.items()]
        out.append(chart(angles, series, x, "force, N", ANGLE_TICKS))
    return "\n".join(out)


def _sensitivities(a: Analysis, unit: str) -> str:
    s = a.sensitivities
    assert s is not None
    mu = s.min_transmission_angle_deg or {}
    rows = [(k, _num(s.time_ratio[k]), _num(s.stroke[k]), _num(mu.get(k))) for k in s.time_ratio]
    return (
        f"<p>The change of each figure per {escape(unit)} of each part, the others held.</p>"
        + _table(("part", f"time ratio per {unit}", f"stroke per {unit}", f"° per {unit}"), rows)
    )


def _limits(a: Analysis, goals: Mapping[str, float]) -> str:
    k = a.conditioning
    rows = [
        ("nearest validity condition", k.limiting_condition or "—"),
        ("its margin (relative)", _num(k.validity_margin, 4)),
        ("margin from a dead point, °", _num(k.dead_point_margin_deg, 4)),
    ]
    bound = goals.get("bound_deg")
    if bound is not None:
        rows.append(
            ("transmission angle above the bound, °", _num(a.transmission.min_deg - bound, 4))
        )
    rows += [
        (f"transmission at {j.joint}, °", f"{j.min_deg:.5g} … {j.max_deg:.5g}")
        for j in a.transmission.joints
    ]
    rows += [("flag", f) for f in k.flags]
    return _table(("", "value"), rows)
