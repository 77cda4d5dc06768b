"""From targets to verified candidates.

``synthesize`` (``driver.py``) asks each type's exact reduced solver first and IPOPT on the
type's formulation (``formulation``, ``solve``) for what it cannot take (``search``); each
candidate is verified by the analysis (``candidate``); a type without a design gets the reason
(``diagnose``); a transmission-against-size front (``front``) and motion objectives
(``motion``) build on the same search."""

from .driver import Solver, Spec, synthesize

__all__ = ["Solver", "Spec", "synthesize"]
