"""Designs at the targets drawn by their own geometry, not synth's: the offset slider-crank's
textbook construction (the crank pivot on the circle that sees the stroke under β), the
Whitworth's pivot ratio and lever with each rod; and a global search of a test's own over
them (a coarse draw, then twice densely about its best), each design checked by the brute
force (tests/support/bruteforce.py) and measured by the caller."""

from __future__ import annotations

import math

import numpy as np
import pytest

from . import bruteforce

COARSE, FINE = 60, 41
ACROSS_DEG = math.degrees(math.acos(1 - 1e-3))  # the least angle the motion searches keep


def slider_crank_designs(tr, angles, sign=1.0):
    """Designs at stroke 1 and time ratio ``tr`` by the textbook construction: the dead centres
    C1 = (0, 0) and C2 = (1, 0), the crank pivot O on the circle through them where C1 O C2 = β
    = π(TR − 1)/(TR + 1), at each angle φ about its centre; |O C1| and |O C2| are l − r and
    l + r (the dead centres on one side of O's foot), O's height the offset (times ``sign``:
    the mirror image). Those whose crank turns fully."""
    beta = math.pi * (tr - 1) / (tr + 1)
    radius, cy = 0.5 / math.sin(beta), 0.5 / math.tan(beta)
    out = []
    for phi in angles:
        ox, oy = 0.5 + radius * math.cos(phi), cy + radius * math.sin(phi)
        a, b = math.hypot(ox - 1, oy), math.hypot(ox, oy)
        seen = math.acos(max(-1.0, min(1.0, (ox * (ox - 1) + oy * oy) / (a * b))))
        crank, rod = abs(a - b) / 2, (a + b) / 2
        beside = ox <= 0 or ox >= 1  # both dead centres on one side of O's foot, as they are
        if oy > 0 and beside and abs(seen - beta) < 1e-9 and rod > crank + oy:
            out.append({"crank": crank, "coupler": rod, "offset": sign * oy})
    return out


def whitworth_designs(tr, rods):
    """Designs at stroke 1 and time ratio ``tr``: pivot_distance/crank = sin(β/2) (the quick
    stroke's half angle is acos(d/r2) = π/(1 + TR)), lever 1/2, one per rod."""
    d = math.cos(math.pi / (1 + tr))
    return [{"crank": 1.0, "pivot_distance": d, "lever": 0.5, "connecting_rod": x} for x in rods]


# each type's designs at the targets, by the number that places them, over its range (the
# Whitworth's rod: its default bounds, up to 2 strokes), and its worst transmission cosine by
# the textbook's formula, to draw where the bound holds
DRAWN = {
    "offset_slider_crank": (
        slider_crank_designs,
        (0.0, 2 * math.pi),
        lambda p: (p["crank"] + abs(p["offset"])) / p["coupler"],
    ),
    "whitworth": (whitworth_designs, (0.5, 2.0), lambda p: p["lever"] / p["connecting_rod"]),
}
# the box of every request here (the types' default bounds, stroke units), which the draw keeps
BOX = {
    "offset_slider_crank": {"crank": (0.1, 5.0), "coupler": (0.1, 2.0), "offset": (0.0, 5.0)},
    "whitworth": {"connecting_rod": (0.1, 2.0)},
}


def within(p, box):
    return all(lo <= p[k] <= hi for k, (lo, hi) in box.items())


def feasible(mtype, tr, bound):
    """The numbers, on a grid of 4 000, whose designs meet the bound (the cosine's formula),
    and the grid's step."""
    designs, (lo, hi), cos_mu = DRAWN[mtype]
    grid = np.linspace(lo, hi, 4001)[1:]
    ok = [x for x in grid for p in designs(tr, [x]) if cos_mu(p) <= math.cos(math.radians(bound))]
    return np.array(ok), grid[1] - grid[0]


def measured(mtype, tr, bound, values, measure, box, draw=None):
    """(measure, value) of each design drawn (by ``draw``, else the type's) at ``values`` that
    meets the targets, the bound and the ``box``, checked by brute force."""
    designs = draw or DRAWN[mtype][0]
    out = []
    for x in values:
        for p in designs(tr, [x]):
            try:
                b = bruteforce.simulate(mtype, p, n=4000)
            except (ValueError, ZeroDivisionError):  # a degenerate end of the family
                continue
            if b["min_transmission_deg"] >= max(bound, ACROSS_DEG) and within(p, box):
                assert b["time_ratio"] == pytest.approx(tr, rel=1e-9)
                assert b["stroke"] == pytest.approx(1.0, rel=1e-9)
                value = measure(p)
                if value is not None:
                    out.append((value, x))
    return out


def least_drawn(mtype, tr, bound, measure, box, draw=None):
    """The least ``measure`` of the drawn designs (``measured``): a coarse draw over the
    numbers whose designs meet the bound, then twice densely about its best; (value, number)
    and how many the coarse draw measured, of how many it drew."""
    ok, step = feasible(mtype, tr, bound)
    coarse = measured(mtype, tr, bound, ok[:: max(1, len(ok) // COARSE)], measure, box, draw)
    step *= max(1, len(ok) // COARSE)
    best = min(coarse)
    lo, hi = DRAWN[mtype][1]
    for _ in range(2):  # twice, densely about the best so far
        near = np.linspace(max(lo, best[1] - step), min(hi, best[1] + step), FINE)
        best = min([best, *measured(mtype, tr, bound, near, measure, box, draw)])
        step /= FINE / 2
    return best, len(coarse), min(COARSE, len(ok))
