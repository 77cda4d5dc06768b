"""CasADi expressions as the enclosures (``interval``) read them: a function's SX form
(``sx_function``), and derivatives by forward differentiation (``forward``)."""

from __future__ import annotations

from typing import Any

import casadi as ca


def sx_function(fn: ca.Function) -> ca.Function:
    """``fn`` as an SX function (an MX one expanded), or a ``TypeError`` saying why not."""
    if fn.is_a("SXFunction"):
        return fn
    try:
        return fn.expand()
    except RuntimeError as e:
        raise TypeError(
            f"interval: {fn.name()} is neither SX nor MX that expands to SX (a compiled or "
            "external function has no instructions to read): build it from its expressions"
        ) from e


def forward(y: Any, x: Any) -> Any:
    """The Jacobian of y in x by forward differentiation, a column per nonzero of x: what an
    enclosure of derivatives is built from. Reverse mode (``ca.jacobian``'s choice for few
    outputs) sends an if_else's seed down each branch as an if_else_zero of its own, which an
    undecided box hulls with 0 apart (c ? 1 : 0 plus !c ? 1 : 0 gives [0, 2]); forward mode
    keeps each if_else of the derivative a pair (``interval._rewrite``), its branches' hull."""
    seeds = ca.DM.eye(x.numel())
    return ca.horzcat(*(ca.jtimes(y, x, seeds[:, i]) for i in range(x.numel())))
