"""Dimensional synthesis and analysis of quick-return mechanisms.

>>> import synth
>>> a = synth.analyze("crank_shaper", {"crank": 120, "pivot_distance": 240, "lever": 450})
>>> round(a.time_ratio, 12), round(a.stroke, 9)
(2.0, 450.0)

A mechanism type kept outside the package is a module that calls ``synth.register``: name it
(or several, comma-separated) in ``SYNTH_TYPES`` and every process that imports synth (a
service's solver processes too) imports it, after the package's own types.

The names below are imported on first use (``import synth`` loads neither CasADi nor scipy,
ezdxf or matplotlib): a command line called in a loop pays only for what it runs.
"""

from __future__ import annotations

import importlib
import os
from typing import TYPE_CHECKING, Any

from .version import __version__ as __version__

if TYPE_CHECKING:
    from . import atlas, mechanisms
    from .analysis.kinematics import analyze, analyze_many, joints
    from .analysis.request import AnalysisRequest
    from .analysis.sweep import SweepRequest, sweep
    from .drawing.export import ExportRequest, export
    from .drawing.figure import draw
    from .drawing.gif import animate
    from .drawing.report import ReportRequest, report
    from .errors import InvalidDesign, InvalidParameters, SynthError, UnknownMechanism
    from .load import Load
    from .mechanisms import register
    from .results import Analysis, Candidate, Infeasible, SweepResult, SynthesisResult, Tolerance
    from .synthesis import Solver, Spec, synthesize
    from .synthesis.driver import SynthesisRequest

# each public name and the module that defines it (None: the name is that submodule)
_WHERE = {
    "Analysis": ".results",
    "AnalysisRequest": ".analysis.request",
    "Candidate": ".results",
    "ExportRequest": ".drawing.export",
    "Infeasible": ".results",
    "InvalidDesign": ".errors",
    "InvalidParameters": ".errors",
    "Load": ".load",
    "ReportRequest": ".drawing.report",
    "Solver": ".synthesis",
    "Spec": ".synthesis",
    "SweepRequest": ".analysis.sweep",
    "SweepResult": ".results",
    "SynthError": ".errors",
    "SynthesisRequest": ".synthesis.driver",
    "SynthesisResult": ".results",
    "Tolerance": ".results",
    "UnknownMechanism": ".errors",
    "analyze": ".analysis.kinematics",
    "analyze_many": ".analysis.kinematics",
    "animate": ".drawing.gif",
    "atlas": None,
    "draw": ".drawing.figure",
    "export": ".drawing.export",
    "joints": ".analysis.kinematics",
    "mechanisms": None,
    "register": ".mechanisms",
    "report": ".drawing.report",
    "sweep": ".analysis.sweep",
    "synthesize": ".synthesis",
}
__all__ = [
    "Analysis",
    "AnalysisRequest",
    "Candidate",
    "ExportRequest",
    "Infeasible",
    "InvalidDesign",
    "InvalidParameters",
    "Load",
    "ReportRequest",
    "Solver",
    "Spec",
    "SweepRequest",
    "SweepResult",
    "SynthError",
    "SynthesisRequest",
    "SynthesisResult",
    "Tolerance",
    "UnknownMechanism",
    "analyze",
    "analyze_many",
    "animate",
    "atlas",
    "draw",
    "export",
    "joints",
    "mechanisms",
    "register",
    "report",
    "sweep",
    "synthesize",
]


def __getattr__(name: str) -> Any:
    """A public name, imported from its module on first use (then kept here)."""
    if name not in _WHERE:
        raise AttributeError(f"module 'synth' has no attribute {name!r}")
    where = _WHERE[name]
    value = importlib.import_module(f".{name}" if where is None else where, __name__)
    if where is not None:
        value = getattr(value, name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *__all__})


for _name in filter(None, (n.strip() for n in os.environ.get("SYNTH_TYPES", "").split(","))):
    importlib.import_module(_name)
