"""The operations the service runs, by name: each the library's function and its checks."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import synth
from synth.analysis.kinematics import check as check_analysis
from synth.analysis.sweep import check as check_sweep
from synth.drawing.export import check as check_export
from synth.synthesis.driver import check as check_synthesis
from synth.synthesis.driver import short as short_synthesis


@dataclass(frozen=True)
class Operation:
    """``run``: the library's function; ``check``: its checks of the same arguments (cheap, no
    solving: a request synth refuses gets its 422 before it waits for a solver); ``short``:
    whether the library says these arguments cost about what a short analysis does, so the
    service runs them in its event loop rather than hand them to a solver (``Engine.run``)."""

    run: Callable[..., Any]
    check: Callable[..., Any]
    short: Callable[..., bool] = lambda **_: False


OPERATIONS: dict[str, Operation] = {
    "analyze": Operation(synth.analyze, check_analysis),
    "synthesize": Operation(synth.synthesize, check_synthesis, short_synthesis),
    "sweep": Operation(synth.sweep, check_sweep),
    "export": Operation(synth.export, check_export),
}
