"""Dimensional synthesis and analysis of quick-return mechanisms.

>>> import synth
>>> a = synth.analyze("crank_shaper", {"crank": 120, "pivot_distance": 240, "lever": 450})
>>> round(a.time_ratio, 12), round(a.stroke, 9)
(2.0, 450.0)
"""

from . import mechanisms
from ._version import __version__ as __version__
from .errors import InvalidDesign, InvalidParameters, SynthError, UnknownMechanism
from .kinematics import analyze, analyze_many, joints
from .results import Analysis, Candidate, Infeasible, SweepResult, SynthesisResult, Tolerance
from .sweep import sweep
from .synthesis import Solver, Spec, synthesize


def __getattr__(name: str):
    """``synth.atlas`` (the design atlas, callable) is imported when first used, so that
    ``python -m synth.atlas`` runs it once."""
    if name == "atlas":
        import importlib

        return importlib.import_module(".atlas", __name__)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = [
    "Analysis",
    "Candidate",
    "Infeasible",
    "InvalidDesign",
    "InvalidParameters",
    "Solver",
    "Spec",
    "SweepResult",
    "SynthError",
    "SynthesisResult",
    "Tolerance",
    "UnknownMechanism",
    "analyze",
    "analyze_many",
    "atlas",
    "joints",
    "mechanisms",
    "sweep",
    "synthesize",
]
