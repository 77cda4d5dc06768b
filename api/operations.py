"""The operations the service runs, by name: each the library's function, its checks, and
whether given arguments make it short work (``api.engine``'s short lane)."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import synth
from synth.analysis.kinematics import check as check_analysis
from synth.analysis.sweep import check as check_sweep
from synth.drawing.export import check as check_export
from synth.drawing.report import check as check_report
from synth.synthesis.driver import check as check_synthesis
from synth.synthesis.driver import short as short_synthesis

# an analysis with at most this many curve points is short work: ~1 ms, ~15 ms with a load
# (a four-bar's), against tens of ms and more for the longest (100 000 points)
SHORT_CURVE_POINTS = 1000


@dataclass(frozen=True)
class Operation:
    """``run``: the library's function; ``check``: its checks of the same arguments (cheap, no
    solving: a request synth refuses gets its 422 before it waits for a slot); ``short``:
    whether these arguments cost about what an analysis does (at most some tens of ms), so
    the service runs them on its short lane, not behind long solves (``Engine.run``)."""

    run: Callable[..., Any]
    check: Callable[..., Any]
    short: Callable[..., bool] = lambda **_: False


def short_analysis(
    crank_angles_deg: Sequence[float] | None = None, samples: int | None = None, **_: Any
) -> bool:
    """Whether an analysis has at most ``SHORT_CURVE_POINTS`` curve points (its extras and
    load, at most ~15 ms on top, do not change that it is short)."""
    return len(crank_angles_deg or ()) + (samples or 0) <= SHORT_CURVE_POINTS


OPERATIONS: dict[str, Operation] = {
    "analyze": Operation(synth.analyze, check_analysis, short_analysis),
    "synthesize": Operation(synth.synthesize, check_synthesis, short_synthesis),
    "sweep": Operation(synth.sweep, check_sweep),
    # a drawing: under 2 ms, ~20 ms as DXF with the pins' paths (ezdxf); a GIF's 36 frames ~80
    "export": Operation(synth.export, check_export, lambda format="svg", **_: format != "gif"),
    # a report: an analysis at 361 angles with every extra, and a drawing; ~20–40 ms
    "report": Operation(synth.report, check_report, lambda **_: True),
}
