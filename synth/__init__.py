"""Dimensional synthesis and analysis of quick-return mechanisms.

>>> import synth
>>> a = synth.analyze("crank_shaper", {"crank": 120, "pivot_distance": 240, "lever": 450})
>>> round(a.time_ratio, 12), round(a.stroke, 9)
(2.0, 450.0)

A mechanism type kept outside the package is a module that calls ``synth.register``: name it
(or several, comma-separated) in ``SYNTH_TYPES`` and every process that imports synth (a
service's solver processes too) imports it, after the package's own types.
"""

import importlib
import os

from . import atlas, mechanisms
from .analysis.kinematics import analyze, analyze_many, joints
from .analysis.sweep import sweep
from .drawing.export import export
from .drawing.figure import animate, draw
from .errors import InvalidDesign, InvalidParameters, SynthError, UnknownMechanism
from .load import Load
from .mechanisms import register
from .results import Analysis, Candidate, Infeasible, SweepResult, SynthesisResult, Tolerance
from .synthesis import Solver, Spec, synthesize
from .version import __version__ as __version__

for _name in filter(None, (n.strip() for n in os.environ.get("SYNTH_TYPES", "").split(","))):
    importlib.import_module(_name)

__all__ = [
    "Analysis",
    "Candidate",
    "Infeasible",
    "InvalidDesign",
    "InvalidParameters",
    "Load",
    "Solver",
    "Spec",
    "SweepResult",
    "SynthError",
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
    "sweep",
    "synthesize",
]
