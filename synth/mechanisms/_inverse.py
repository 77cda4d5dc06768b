"""Shared fast-path pieces for the slotted-lever types (crank_shaper, whitworth).

In both, the time ratio fixes crank/pivot_distance and the stroke fixes the lever, so with one
of crank and pivot_distance known the targets determine the rest: a finite set of one.
"""

from __future__ import annotations

import math

from ._registry import Unreachable

REL = 1e-12  # how exactly a fixed part must already meet a target


def crank_pivot_lever(
    fixed: dict[str, float], ratio: float, lever: float, tr_of_ratio, stroke_of_lever
) -> list[dict[str, float]] | None:
    """Determine crank, pivot_distance and lever from crank/pivot_distance = ``ratio`` and the
    required ``lever``; None when neither crank nor pivot_distance is fixed (a family)."""
    r2, d, L = fixed.get("crank"), fixed.get("pivot_distance"), fixed.get("lever")
    if r2 is None and d is None:
        return None
    out: dict[str, float] = {}
    if r2 is not None and d is not None:
        if not math.isclose(r2 / d, ratio, rel_tol=REL):
            raise Unreachable(
                "FIXED_PARTS_CONTRADICT_TARGETS",
                f"crank {r2:g} and pivot_distance {d:g} give time ratio {tr_of_ratio(r2 / d):.9g}"
                f", not {tr_of_ratio(ratio):.9g}",
            )
    elif r2 is None:
        out["crank"] = ratio * d
    else:
        out["pivot_distance"] = r2 / ratio
    if L is None:
        out["lever"] = lever
    elif not math.isclose(L, lever, rel_tol=REL):
        raise Unreachable(
            "FIXED_PARTS_CONTRADICT_TARGETS",
            f"lever {L:g} gives stroke {stroke_of_lever(L):.9g}, not {stroke_of_lever(lever):.9g}"
            " (the stroke is set by the lever and the time ratio alone)",
        )
    return [out]
