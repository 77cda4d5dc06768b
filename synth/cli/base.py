"""The command line's group and what its commands share: flags with the API's names, the
table, JSON and CSV they print, and exit status 2 on bad input."""

from __future__ import annotations

import csv
import importlib
import io
import json
import math
import sys
from collections.abc import Callable, Iterable, Sequence
from dataclasses import MISSING
from typing import Any, NoReturn

import click

from ..errors import InvalidParameters, SynthError
from ..load import Load
from ..mechanisms import all_types
from ..requests import Argument, arguments

CURVES = ("crank_angle_deg", "position", "velocity", "acceleration", "transmission_deg", "torque")


def fail(e: SynthError) -> NoReturn:
    """Bad input: the library's message (and the field, as the API's 422 locates it), exit
    status 2."""
    where = ".".join(map(str, e.loc)) if isinstance(e, InvalidParameters) else ""
    click.echo(f"error: {where + ': ' if where else ''}{e.msg}", err=True)
    sys.exit(2)


def pairs(values: Iterable[str], flag: str) -> dict[str, str]:
    """``name=value`` flags as a mapping."""
    out = {}
    for v in values:
        name, eq, value = v.partition("=")
        if not eq or not name:
            raise click.BadParameter(f"{v!r}: expected name=value", param_hint=flag)
        out[name.strip()] = value.strip()
    return out


def numbers(values: Iterable[str], flag: str) -> dict[str, float]:
    out = {}
    for k, v in pairs(values, flag).items():
        try:
            out[k] = float(v)
        except ValueError:
            raise click.BadParameter(f"{k}={v!r}: not a number", param_hint=flag) from None
    return out


def ranges(values: Iterable[str]) -> dict[str, tuple[float, float]]:
    out = {}
    for k, v in pairs(values, "--bounds").items():
        try:
            lo, hi = v.split(":")
            out[k] = (float(lo), float(hi))
        except ValueError:
            msg = f"{k}={v!r}: expected low:high"
            raise click.BadParameter(msg, param_hint="--bounds") from None
    return out


def parse_load(text: str | None) -> Load | None:
    """``--load``: the API's load object as JSON (``length_unit``, ``crank_rpm``, …)."""
    if text is None:
        return None
    try:
        fields = json.loads(text)
    except json.JSONDecodeError as e:
        raise click.BadParameter(f"not JSON: {e.msg}", param_hint="--load") from None
    if not isinstance(fields, dict):
        raise click.BadParameter(
            'a JSON object, e.g. \'{"length_unit": "mm", ...}\'', param_hint="--load"
        )
    try:
        return Load.of(fields)
    except InvalidParameters as e:
        raise click.BadParameter(str(e), param_hint="--load") from None


def emit(fmt: str, reply: dict[str, Any], rows: list[dict[str, Any]], text: str) -> None:
    if fmt == "json":
        click.echo(json.dumps(plain(reply), indent=2, allow_nan=False))
    elif fmt == "csv":
        out = io.StringIO()
        if rows:
            w = csv.DictWriter(out, fieldnames=list(rows[0]), lineterminator="\n")
            w.writeheader()
            w.writerows(rows)
        click.echo(out.getvalue(), nl=False)
    else:
        click.echo(text)


def plain(x: Any) -> Any:
    """``x`` as JSON takes it, as the API gives it: arrays as lists, a non-finite number as
    null."""
    if hasattr(x, "tolist"):
        x = x.tolist()
    if isinstance(x, dict):
        return {k: plain(v) for k, v in x.items()}
    if isinstance(x, list | tuple):
        return [plain(v) for v in x]
    return None if isinstance(x, float) and not math.isfinite(x) else x


def table(header: Sequence[str], rows: Iterable[Sequence[Any]]) -> str:
    """Left-aligned text columns; numbers to 6 significant digits."""
    cells = [[cell(v) for v in r] for r in rows]
    widths = [max(len(h), *(len(r[i]) for r in cells)) for i, h in enumerate(header)]
    lines = ["  ".join(h.ljust(w) for h, w in zip(header, widths, strict=True))]
    lines += ["  ".join(c.ljust(w) for c, w in zip(r, widths, strict=True)) for r in cells]
    return "\n".join(line.rstrip() for line in lines)


def cell(v: Any) -> str:
    if isinstance(v, float):
        return "" if not math.isfinite(v) else f"{v:.6g}"
    return "" if v is None else str(v)


def formats(f: Callable[..., Any]) -> Callable[..., Any]:
    """``--json`` and ``--csv`` (the table by default)."""
    f = click.option("--json", "fmt", flag_value="json", help="the reply the API gives, as JSON")(f)
    f = click.option("--csv", "fmt", flag_value="csv", help="rows for a spreadsheet")(f)
    return click.option("--table", "fmt", flag_value="table", default=True, hidden=True)(f)


class Command(click.Command):
    """A command that also takes the fields of its ``request`` (``"module:Name"``, a request
    value), and of the values ``also`` names (parts of it), that the edges take, but those it
    takes in a shape of its own or not at all (``apart``): each ``--name`` (dashes for
    underscores; its ``Help.flag`` too), of its kind and choices, with its default and words,
    a collection's repeated; the command passes them on by their names. They are made when
    first asked for (its help, a run): the request's module, and the library with it, is
    imported then, and the group's help stays quick."""

    def __init__(
        self,
        *args: Any,
        request: str,
        apart: tuple[str, ...] = (),
        also: tuple[str, ...] = (),
        **kwargs: Any,
    ) -> None:
        self._values, self._apart = (request, *also), apart
        self._made: list[click.Parameter] | None = None
        super().__init__(*args, **kwargs)

    @property
    def params(self) -> list[click.Parameter]:
        if self._made is None:
            made = [
                _option(a)
                for value in map(value_of, self._values)
                for a in arguments(value)
                if a.edge and a.name not in self._apart
            ]
            self._made = [*made, *self._declared]
        return self._made

    @params.setter
    def params(self, declared: list[click.Parameter]) -> None:
        self._declared, self._made = declared, None


def value_of(where: str) -> type:
    """The value ``"module:Name"`` names."""
    module, name = where.split(":")
    value: type = getattr(importlib.import_module(module), name)
    return value


def _option(a: Argument) -> click.Option:
    names = [f"--{a.name.replace('_', '-')}"]
    if a.help and a.help.flag:
        names.insert(0, f"--{a.help.flag}")
    kw: dict[str, Any] = {"help": a.help.text if a.help else None}
    if a.kind is bool:
        kw.update(is_flag=True, default=a.default)
    else:
        kw["type"] = click.Choice(a.choices) if a.choices else a.kind
        if a.many:  # repeated; none given: the field's default
            kw.update(multiple=True, callback=lambda _c, _p, v: v or a.default)
        elif a.default is MISSING:
            kw["required"] = True
        else:
            kw.update(default=a.default, show_default=a.default is not None)
    return click.Option([*names, a.name], **kw)


def design_args(f: Callable[..., Any]) -> Callable[..., Any]:
    f = click.argument("mechanism", type=click.Choice(all_types()))(f)
    return click.option(
        "-p",
        "--param",
        "params",
        multiple=True,
        metavar="NAME=LENGTH",
        help="a parameter of the design (repeat for each)",
    )(f)


@click.group(
    help="Quick-return mechanisms from the shell: link lengths for a time ratio, stroke and "
    "transmission bound (synthesize), a design's motion and loads (analyze), a parameter's "
    "effect (sweep), a drawing for CAD (export), a design report (report), which type reaches "
    "which targets (atlas), the service (serve). Each command prints a table, --json the API's "
    "reply, --csv rows. Exit status: 0 with an answer, 1 when every type refuses, 2 on bad input."
)
@click.version_option(package_name="quickreturn-synth")
def main() -> None:
    pass
