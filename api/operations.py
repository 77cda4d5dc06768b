"""The operations the service runs, by name: each the request value the library checks its
arguments with (built from a body: a request synth refuses gets its 422 before it waits for a
slot), the library's function that runs it, and whether it is short work (``api.engine``'s
short lane)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from synth.analysis import kinematics, sweep
from synth.analysis.request import AnalysisRequest
from synth.analysis.sweep import SweepRequest
from synth.drawing import export, report
from synth.drawing.export import ExportRequest
from synth.drawing.report import ReportRequest
from synth.synthesis import driver
from synth.synthesis.driver import SynthesisRequest

# an analysis with at most this many curve points is short work: ~1 ms, ~15 ms with a load
# (a four-bar's), against tens of ms and more for the longest (100 000 points)
SHORT_CURVE_POINTS = 1000


@dataclass(frozen=True)
class Operation:
    """``request``: the operation's arguments as one value, checked when built; ``run``: the
    library's function of it; ``short``: whether it costs about what an analysis does (at
    most some tens of ms), so the service runs it on its short lane, not behind long solves
    (``Engine.run``)."""

    request: Callable[..., Any]
    run: Callable[[Any], Any]
    short: Callable[[Any], bool] = lambda _: False


OPERATIONS: dict[str, Operation] = {
    "analyze": Operation(
        AnalysisRequest, kinematics.run, lambda r: r.curve_points <= SHORT_CURVE_POINTS
    ),
    # with nothing but the exact solvers to ask: under a millisecond a type
    "synthesize": Operation(SynthesisRequest, driver.run, lambda r: r.exact_only),
    "sweep": Operation(SweepRequest, sweep.run),
    # a drawing: under 2 ms, ~20 ms as DXF with the pins' paths (ezdxf); a GIF's 36 frames ~80
    "export": Operation(ExportRequest, export.run, lambda r: r.format != "gif"),
    # a report: an analysis at 361 angles with every extra, and a drawing; ~20–40 ms
    "report": Operation(ReportRequest, report.run, lambda _: True),
}
