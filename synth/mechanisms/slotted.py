"""Shared by the slotted-lever types (crank_shaper, whitworth): the crank as a free scale, and
the slider's dead centres.

In both, the time ratio fixes the ratio of pivot_distance to crank and the stroke fixes the
lever, so crank and pivot_distance are one family with a free scale; and the slider's dead
centres are two crank angles mirrored about the line of centres, wherever the link moves it.
"""

from __future__ import annotations

import math
from collections.abc import Callable

from ..numerics import ROUNDING
from .reduced import Problem, agree, differ, intersect, unreachable


def check(
    p: Problem, time_ratio: Callable[[float], float], stroke: Callable[[float], float]
) -> None:
    """Fixed parts that alone set the time ratio (crank and pivot_distance) or the stroke (the
    lever) must meet it: ``time_ratio(crank/pivot_distance)``, ``stroke(lever)``."""
    f = p.fixed
    if "crank" in f and "pivot_distance" in f:
        got = time_ratio(f["crank"] / f["pivot_distance"])
        if not agree(got, p.ratio):
            raise unreachable(
                "crank {} and pivot_distance {} give time ratio {}, not {}".format(
                    p.shown(f["crank"]), p.shown(f["pivot_distance"]), *differ(got, p.ratio)
                )
            )
    if "lever" in f and not agree(stroke(f["lever"]), 1.0):
        raise unreachable(
            "lever {} gives stroke {}, not {} (the stroke is set by the lever and the time "
            "ratio alone)".format(
                p.shown(f["lever"]), *differ(stroke(f["lever"]) * p.stroke, p.stroke)
            )
        )


def ratio(p: Problem, over: str, under: str) -> float:
    """``over``/``under`` of crank and pivot_distance: the fixed pair's (``check`` holds it to
    the target), else what the time ratio sets, sin(β/2)."""
    f = p.fixed
    if {"crank", "pivot_distance"} <= f.keys():
        return f[over] / f[under]
    return math.sin(p.beta / 2)


def scale(p: Problem, pivot_per_crank: float, reach: float = math.inf) -> float | None:
    """The crank of the smallest design with pivot_distance = ``pivot_per_crank`` × crank and
    crank ≤ ``reach``; a fixed crank or pivot_distance sets it (both fixed: the crank, the pair
    checked by ``check``), else it is the smallest the bounds allow. None if there is none."""
    if "crank" in p.fixed:
        crank = p.fixed["crank"]
    elif "pivot_distance" in p.fixed:
        crank = p.fixed["pivot_distance"] / pivot_per_crank
    else:
        lo, hi = p.bounds["pivot_distance"]
        span = intersect(p.bounds["crank"], (lo / pivot_per_crank, hi / pivot_per_crank))
        if span is None:
            return None
        crank = span[0]
    ok = crank <= reach * (1 + ROUNDING) and p.allows("crank", crank)
    return crank if ok and p.allows("pivot_distance", crank * pivot_per_crank) else None


def dead_centres(cos: float) -> tuple[float, float]:
    """The crank angles θ and 2π − θ with cos θ = ``cos``: a slotted lever's two dead centres
    (``Space.dead``), the lower first."""
    theta = math.acos(cos)
    return theta, 2 * math.pi - theta
