"""The commands that write a file: a drawing (export), a design report (report) and a turn of
the crank, animated (animate)."""

from __future__ import annotations

import sys
from dataclasses import fields
from typing import Any

import click

from ..drawing import FPS, FRAMES
from ..errors import SynthError
from .base import Command, design_args, fail, main, numbers, parse_load, value_of

GOALS = "synth.drawing.report:Goals"  # what a report compares the design with
# -o/--out: where a command writes its file
to_file = click.option(
    "-o",
    "--out",
    type=click.Path(dir_okay=False, writable=True),
    help="the file (default: standard output)",
)


@main.command(
    help="A design's drawing for CAD or a document (POST /v1/export).",
    cls=Command,
    request="synth.drawing.export:ExportRequest",
    apart=("mechanism", "params"),
)
@design_args
@to_file
def export(mechanism: str, params: tuple[str, ...], out: str | None, **args: Any) -> None:
    try:
        from ..drawing.export import export as _export  # the library on use: --help stays quick

        doc = _export(mechanism, numbers(params, "--param"), **args)
    except SynthError as e:
        fail(e)
    write(doc, out)


@main.command(
    help="A design's report: one printable HTML page, standing alone (POST /v1/report).",
    cls=Command,
    request="synth.drawing.report:ReportRequest",
    apart=("mechanism", "params", "load", "targets"),
    also=(GOALS,),
)
@design_args
@click.option("--load", "load_json", metavar="JSON", help="the API's load object: adds the loads")
@to_file
def report(
    mechanism: str, params: tuple[str, ...], load_json: str | None, out: str | None, **args: Any
) -> None:
    goals = [f.name for f in fields(value_of(GOALS))]
    targets = {k: v for k in goals if (v := args.pop(k)) is not None}
    try:
        from ..drawing.report import report as _report

        page = _report(
            mechanism,
            numbers(params, "--param"),
            load=parse_load(load_json),
            targets=targets,
            **args,
        )
    except SynthError as e:
        fail(e)
    write(page.encode(), out)


@main.command(help="A turn of the crank as an animated GIF (POST /v1/export, format gif).")
@design_args
@click.option("--frames", type=int, default=FRAMES, show_default=True, help="equal crank steps")
@click.option("--fps", type=float, default=FPS, show_default=True, help="frames a second")
@to_file
def animate(
    mechanism: str, params: tuple[str, ...], frames: int, fps: float, out: str | None
) -> None:
    try:
        from ..drawing.gif import animate as _animate

        doc = _animate(mechanism, numbers(params, "--param"), frames, fps)
    except SynthError as e:
        fail(e)
    write(doc, out)


def write(doc: bytes, out: str | None) -> None:
    """``doc`` to the file ``out``, or to standard output."""
    if out is None:
        sys.stdout.buffer.write(doc)
    else:
        with open(out, "wb") as f:
            f.write(doc)
