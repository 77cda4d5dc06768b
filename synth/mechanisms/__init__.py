"""The mechanism types and what they share.

- ``registry``: the record of a type (``Mechanism``, its ``Parameter``s and ``Condition``s) and
  ``register``, which adds one; ``facts``: a type's closed forms at a design (``Facts``).
- ``types``: the six types, one module each; every module of that package registers one.
- ``geometry``: polymorphic planar geometry (floats and CasADi symbols alike).
- ``reduced``: the contract of a type's exact reduced solver (``Problem`` in, ``Reduced`` out)
  and ``rod``, the rule for a connecting rod from a pin to a straight path.
- ``fourbar``: the four-bar family (the output pin, Grashof, the dead-centre construction and
  its solver), shared by the two four-bar types; ``slotted``: the slotted-lever types' scale.

The types are found, not listed: a new type is one new module in ``types``. A type kept
outside the package calls ``synth.register`` (see ``synth``: ``SYNTH_TYPES``)."""

import importlib
import pkgutil

from . import types
from .facts import Facts
from .registry import Condition, Mechanism, Parameter, Scale, all_types, get, register

# the listing's order (and a default request's): these as the contract has them, then any
# other type by its module's name
FIRST = (
    "scotch_yoke",
    "offset_slider_crank",
    "crank_shaper",
    "whitworth",
    "crank_rocker_slider",
    "drag_link_slider",
)
_modules = [m.name for m in pkgutil.iter_modules(types.__path__) if not m.name.startswith("_")]
for _name in sorted(_modules, key=lambda n: (FIRST.index(n) if n in FIRST else len(FIRST), n)):
    importlib.import_module(f"{types.__name__}.{_name}")

__all__ = ["Condition", "Facts", "Mechanism", "Parameter", "Scale", "all_types", "get", "register"]
