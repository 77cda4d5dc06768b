"""The commands that compute: synthesize, analyze and sweep; and those that start another
program: atlas, serve."""

from __future__ import annotations

import sys
from typing import TYPE_CHECKING, Any

import click

from ..errors import SynthError
from ..load import Load
from ..mechanisms import all_types, get
from ..objectives import get as objective_of

if TYPE_CHECKING:
    from ..results import Analysis, Loads, Sensitivities, SweepResult, SynthesisResult
from .base import (
    CURVES,
    Command,
    design_args,
    emit,
    fail,
    formats,
    main,
    numbers,
    parse_load,
    ranges,
    table,
)


@main.command(
    help="Link lengths for the targets, verified, best first (POST /v1/synthesize).",
    cls=Command,
    request="synth.synthesis.driver:SynthesisRequest",
    apart=("mechanisms", "tolerance", "load"),
)
@click.option(
    "--type",
    "types",
    multiple=True,
    type=click.Choice(all_types()),
    help="a type to search (repeat; default: every quick-return type)",
)
@click.option(
    "--fix",
    multiple=True,
    metavar="NAME=LENGTH",
    help="a part kept at its length, in each type given",
)
@click.option(
    "--bounds",
    multiple=True,
    metavar="NAME=LOW:HIGH",
    help="a free part's range, in each type given",
)
@click.option("--load", "load_json", metavar="JSON", help="the API's load object")
@formats
def synthesize(
    types: tuple[str, ...],
    fix: tuple[str, ...],
    bounds: tuple[str, ...],
    load_json: str | None,
    fmt: str,
    **args: Any,
) -> None:
    fixed, boxes = numbers(fix, "--fix"), ranges(bounds)
    names = types or [t for t in all_types() if get(t).quick_return]
    specs = [{"type": t, "fixed": fixed, "bounds": boxes} for t in names]
    try:
        from ..synthesis import synthesize as _synthesize  # on use: --help stays quick

        r = _synthesize(**args, mechanisms=specs, load=parse_load(load_json))
    except SynthError as e:
        fail(e)
    emit(fmt, r.to_dict(), _candidate_rows(r), _candidate_text(r, args["objective"]))
    if not r.candidates:
        sys.exit(1)


def _candidate_rows(r: SynthesisResult) -> list[dict[str, Any]]:
    names = list(dict.fromkeys(k for c in r.candidates for k in c.params))
    return [
        {
            "rank": i + 1,
            "type": c.type,
            **{k: c.params.get(k) for k in names},
            "min_transmission_angle_deg": c.min_transmission_angle_deg,
            "objective_value": c.objective_value,
            "size": c.size,
            "method": c.method,
            "active": " ".join(c.active),
            "ranked_by": c.ranked_by,
            "certified": c.certified,
            "gap": c.gap,
            "uncertified": c.uncertified,
            **_drive(c.loads),
        }
        for i, c in enumerate(r.candidates)
    ]


def _drive(q: Loads | None) -> dict[str, float]:
    """What a load asks of the drive, as columns (none without a load)."""
    if q is None:
        return {}
    return {
        "peak_torque_Nm": q.torque.max,
        "motor_W": q.power.rated,
        "flywheel_kgm2": q.flywheel.inertia,
    }


def _candidate_text(r: SynthesisResult, objective: str) -> str:
    out = []
    if r.candidates:
        rows = [
            (
                i + 1,
                c.type,
                ", ".join(f"{k} {v:.6g}" for k, v in c.params.items()),
                c.min_transmission_angle_deg,
                c.objective_value,
                " ".join(c.active) or "-",
                *_drive(c.loads).values(),
            )
            for i, c in enumerate(r.candidates)
        ]
        # a front's candidates: their size
        measure = "size" if objective_of(objective).found == "front" else objective
        loaded = ("peak torque N·m", "motor W", "flywheel kg·m²") if r.candidates[0].loads else ()
        out.append(table(("#", "type", "lengths", "μ min °", measure, "at limit", *loaded), rows))
        out += dict.fromkeys(f"{c.type}: {c.family.relation}" for c in r.candidates if c.family)
        seen = set()  # each type's best: whether it is certified the best, or why not
        for i, c in enumerate(r.candidates):
            if c.type in seen:
                continue
            seen.add(c.type)
            if c.certified and c.gap is not None:
                out.append(f"#{i + 1} is certified the best {c.type} (gap {c.gap:.1e})")
            elif c.uncertified is not None:
                out.append(f"#{i + 1} is not certified the best {c.type}: {c.uncertified}")
    for why in r.infeasible:
        out.append(f"{why.type}: no design ({why.code}): {why.reason}")
    if not r.complete:
        out.append(f"(the time budget ended the search after {r.elapsed_ms:.0f} ms)")
    return "\n".join(out)


@main.command(
    help="One design over a crank revolution (POST /v1/analyze).",
    cls=Command,
    request="synth.analysis.request:AnalysisRequest",
    apart=("mechanism", "params", "tolerance", "load"),
)
@design_args
@click.option("--load", "load_json", metavar="JSON", help="the API's load object")
@formats
def analyze(
    mechanism: str, params: tuple[str, ...], load_json: str | None, fmt: str, **args: Any
) -> None:
    try:
        load = parse_load(load_json)
        from ..analysis.kinematics import analyze as _analyze

        a = _analyze(mechanism, numbers(params, "--param"), load=load, **args)
    except SynthError as e:
        fail(e)
    emit(fmt, a.to_dict(), _analysis_rows(a), _analysis_text(a, load))


def _analysis_rows(a: Analysis) -> list[dict[str, Any]]:
    """The curves, a row per angle; without curves, the summary in one row."""
    if a.curves is None:
        return [
            {
                "type": a.type,
                **a.params,
                "time_ratio": a.time_ratio,
                "stroke": a.stroke,
                "min_transmission_angle_deg": a.transmission.min_deg,
            }
        ]
    c = a.curves
    cols = {k: getattr(c, k) for k in CURVES if getattr(c, k) is not None}
    for name, pin in (c.pins or {}).items():
        cols |= {f"{name}_x": pin.x, f"{name}_y": pin.y}
    cols |= {f"force_{name}": v for name, v in (c.forces or {}).items()}
    n = len(a.curves.crank_angle_deg)
    return [{k: float(v[i]) for k, v in cols.items()} for i in range(n)]


def _analysis_text(a: Analysis, load: Load | None) -> str:
    t = a.transmission
    lines = [
        f"{a.type}: " + ", ".join(f"{k} {v:.6g}" for k, v in a.params.items()),
        f"time ratio {a.time_ratio:.9g}, stroke {a.stroke:.9g}",
        f"working stroke {a.working_stroke.crank_angle_deg:.6g}°, "
        f"return {a.return_stroke.crank_angle_deg:.6g}°",
        f"dead centres at {a.extremes.min.crank_angle_deg:.6g}° and "
        f"{a.extremes.max.crank_angle_deg:.6g}°",
        f"transmission angle {t.min_deg:.6g}° to {t.max_deg:.6g}°"
        + "".join(f"; {j.joint} {j.min_deg:.6g}°" for j in t.joints if len(t.joints) > 1),
    ]
    if a.motion is not None:
        m = a.motion
        lines.append(
            f"cutting-speed fluctuation {m.working_speed_fluctuation.middle:.6g}, "
            f"peak acceleration {m.peak_acceleration.working_stroke:.6g} (working) "
            f"{m.peak_acceleration.return_stroke:.6g} (return), in ω²·stroke"
        )
    if a.envelope is not None:
        e = a.envelope
        box = f"x {e.x[0]:.6g} to {e.x[1]:.6g}, y {e.y[0]:.6g} to {e.y[1]:.6g}"
        size = f"{e.width:.6g} × {e.height:.6g}"
        lines.append(f"envelope {box} ({size}), link lengths {e.link_length_sum:.6g}")
    if a.sensitivities is not None:
        lines += _sensitivities(a.sensitivities)
    if a.loads is not None and load is not None:
        q, fly = a.loads, a.loads.flywheel
        tq = q.torque
        lines.append(f"crank torque {tq.min:.6g} to {tq.max:.6g} N·m (mean {tq.mean:.6g})")
        lines[-1] += f", motor {q.power.rated:.6g} W"
        if q.power.motor_torque is not None:
            lines[-1] += f", {q.power.motor_torque:.6g} N·m at {load.motor_rpm:.6g} rpm"
        lines.append(f"flywheel {fly.inertia:.6g} kg·m² on a shaft at {fly.rpm:.6g} rpm")
        if fly.disc_diameter is not None:
            disc = f"{fly.disc_diameter:.6g} {load.length_unit} across"
            lines[-1] += f": a steel disc {disc}, {load.flywheel_width:.6g} wide"
        forces = [f"{k} {f.max:.6g} N at {f.at_deg:.6g}°" for k, f in q.joints.items()]
        lines.append(f"largest forces: {', '.join(forces)}; guide {q.guide.max:.6g} N")
    if a.curves is not None:
        lines.append(f"curves at {len(a.curves.crank_angle_deg)} angles: --csv or --json")
    return "\n".join(lines)


def _sensitivities(s: Sensitivities) -> list[str]:
    """A row per parameter: the derivatives of the time ratio, the stroke and the minimum
    transmission angle, and with a tolerance their worst-case deviations."""
    angle = s.min_transmission_angle_deg or {}
    rows = [(k, s.time_ratio[k], s.stroke[k], angle.get(k)) for k in s.time_ratio]
    out = [table(("d/d", "time ratio", "stroke", "μ min °"), rows)]
    if s.deviation is not None:
        out.append(
            "worst-case deviation: "
            + ", ".join(f"{k} {v:.6g}" for k, v in s.deviation.items() if v is not None)
        )
    return out


@main.command(
    help="One parameter varied, the rest held (POST /v1/sweep).",
    cls=Command,
    request="synth.analysis.sweep:SweepRequest",
    apart=("mechanism", "params"),
)
@design_args
@formats
def sweep(mechanism: str, params: tuple[str, ...], fmt: str, **args: Any) -> None:
    try:
        from ..analysis.sweep import sweep as _sweep

        s = _sweep(mechanism, numbers(params, "--param"), **args)
    except SynthError as e:
        fail(e)
    cols = ("values", "time_ratio", "stroke", "min_transmission_angle_deg", "valid")
    rows = [
        dict(zip((args["vary"], *cols[1:]), r, strict=True))
        for r in zip(*(getattr(s, k) for k in cols), strict=True)
    ]
    emit(fmt, s.to_dict(), rows, _sweep_text(s, rows))


def _sweep_text(s: SweepResult, rows: list[dict[str, Any]]) -> str:
    text = table(list(rows[0]), [list(r.values()) for r in rows]) if rows else ""
    valid = ", ".join(f"[{a:.6g}, {b:.6g}]" for a, b in s.valid_interval) or "none"
    return f"{text}\nvalid {s.vary}: {valid}"


@main.command(
    context_settings={"ignore_unknown_options": True, "help_option_names": []},
    help="Which type reaches which targets (python -m synth.atlas; --help there).",
)
@click.argument("args", nargs=-1, type=click.UNPROCESSED)
def atlas(args: tuple[str, ...]) -> None:
    from ..atlas.__main__ import main as atlas_main

    atlas_main(list(args))


@main.command(help="The REST service and its playground (the README, *Service*).")
@click.option("--host", help="default: HOST, else 127.0.0.1")
@click.option("--port", type=int, help="default: PORT, else 8000")
def serve(host: str | None, port: int | None) -> None:
    from api.serve import main as serve_main  # the service: installed beside the library

    serve_main([*(["--host", host] if host else []), *(["--port", str(port)] if port else [])])
