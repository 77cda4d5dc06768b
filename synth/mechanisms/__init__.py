"""The mechanism types: each public module of this package defines one and registers it
(``_registry.register``). They are found, not listed: a new type is one new module.

A type kept outside the package is a module that registers it too: name it (or several,
comma-separated) in ``SYNTH_TYPES`` and every process that imports synth (a service's solver
processes too) imports it after the package's own."""

import importlib
import os
import pkgutil

from ._registry import Condition, Mechanism, Parameter, all_types, get

# the listing's order (and a default request's): these as the contract has them, then any
# other type by its module's name
FIRST = ("scotch_yoke", "offset_slider_crank", "crank_shaper", "whitworth",
         "crank_rocker_slider", "drag_link_slider")  # fmt: skip
_modules = [m.name for m in pkgutil.iter_modules(__path__) if not m.name.startswith("_")]
for _name in sorted(_modules, key=lambda n: (FIRST.index(n) if n in FIRST else len(FIRST), n)):
    importlib.import_module(f"{__name__}.{_name}")
for _name in filter(None, (n.strip() for n in os.environ.get("SYNTH_TYPES", "").split(","))):
    importlib.import_module(_name)

__all__ = ["Condition", "Mechanism", "Parameter", "all_types", "get"]
