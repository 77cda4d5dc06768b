"""The six mechanism types, one module each, registered in the order of mechanisms.md."""

# isort: skip_file
# Importing a module registers its type; this order is the contract's (and the listing's).
from . import scotch_yoke, offset_slider_crank, crank_shaper, whitworth  # noqa: F401
from . import crank_rocker_slider, drag_link_slider  # noqa: F401
from ._registry import Condition, Mechanism, Parameter, all_types, get

__all__ = ["Condition", "Mechanism", "Parameter", "all_types", "get"]
