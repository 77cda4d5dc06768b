"""A type's closed forms at a design (``Mechanism.facts``), as one record."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any


@dataclass(frozen=True)
class Facts:
    """A type's closed forms at a design, in CasADi maths (numbers at numbers).

    ``beta``: the crank angle by which the strokes differ from π (the slow one takes
    π + |β|, the quick one π − |β|: TR = (π + |β|)/(π − |β|); the sign follows the circuit's
    orientation). ``stroke``. ``transmission_cos``: the signed cos μ terms whose largest |·|
    is the worst transmission (empty for slot drives). ``one_way``, where a rod follows a
    swinging pin: cos margins ≥ 0 for the slider to move one way over each swing (the closed
    forms hold only then; a design that breaks them still runs). ``crank_at_max``, where a
    closed form gives it: the crank angle (radians) at which the slider is farthest out.
    """

    beta: Any
    stroke: Any
    transmission_cos: tuple[Any, ...]
    one_way: tuple[Any, ...] = ()
    crank_at_max: Any = None
