"""The mechanism types: each public module of this package defines one and registers it
(``_registry.register``). They are found, not listed: a new type is one new module."""

import importlib
import pkgutil

from ._registry import Condition, Mechanism, Parameter, all_types, get

# the listing's order (and a default request's): these as the contract has them, then any
# other type by its module's name
FIRST = ("scotch_yoke", "offset_slider_crank", "crank_shaper", "whitworth",
         "crank_rocker_slider", "drag_link_slider")  # fmt: skip
_modules = [m.name for m in pkgutil.iter_modules(__path__) if not m.name.startswith("_")]
for _name in sorted(_modules, key=lambda n: (FIRST.index(n) if n in FIRST else len(FIRST), n)):
    importlib.import_module(f"{__name__}.{_name}")

__all__ = ["Condition", "Mechanism", "Parameter", "all_types", "get"]
