"""Reference values from the sources, with provenance. Printed slips are noted where they occur.

The sources are listed in docs/references.md.
"""

import math


def _table(text: str) -> list[float]:
    """A printed table's numbers, in reading order."""
    return [float(x) for x in text.split()]


# the slotted-lever lab handout, Table 1, "Theoretical Slider Position, x" at 0°, 10°, …, 360°
# for crank 40, pivot_distance 160, lever 240, ram_link 0; the apparatus scale reads x = 70 + s.
SLOTTED_LEVER_LAB_PARAMS = {"crank": 40.0, "pivot_distance": 160.0, "lever": 240.0, "ram_link": 0.0}
SLOTTED_LEVER_LAB_SCALE_ZERO = 70.0
SLOTTED_LEVER_LAB_THEORY = _table("""
70.00 78.36 86.58 94.53 102.08 109.07 115.36 120.77 125.12 128.21
129.82 129.71 127.65 123.39 116.79 107.81 96.66 83.80 70.00 56.20
43.34 32.19 23.21 16.61 12.35 10.29 10.18 11.79 14.88 19.23
24.64 30.93 37.92 45.47 53.42 61.64 70.00
""")

# the slotted-link lab handout: r = 35 mm, ω = 1; x = r(1 − cos θ) measured from one
# extreme (x = r − s), Table 1 "Theoretical displacement" and Table 2 velocity / acceleration.
SLOTTED_LINK_LAB_CRANK = 35.0
SLOTTED_LINK_LAB_DISPLACEMENT = _table("""
0 0.53 2.11 4.69 8.19 12.50 17.50 23.03 28.92 35
41.08 46.97 52.50 57.50 61.81 65.31 67.89 69.47 70
69.47 67.89 65.31 61.81 57.50 52.50 46.97 41.08 35
28.92 23.03 17.50 12.50 8.19 4.69 2.11 0.53 0
""")
SLOTTED_LINK_LAB_VELOCITY = _table("""
0.00 6.08 11.97 17.50 22.50 26.81 30.31 32.89 34.47 35.00
34.47 32.89 30.31 26.81 22.50 17.50 11.97 6.08 0.00
-6.08 -11.97 -17.50 -22.50 -26.81 -30.31 -32.89 -34.47 -35.00
-34.47 -32.89 -30.31 -26.81 -22.50 -17.50 -11.97 -6.08 0.00
""")
SLOTTED_LINK_LAB_ACCELERATION = _table("""
35.00 34.47 32.89 30.31 26.81 22.50 17.50 11.97 6.08 0.00
-6.08 -11.97 -17.50 -22.50 -26.81 -30.31 -32.89 -34.47 -35.00
-34.47 -32.89 -30.31 -26.81 -22.50 -17.50 -11.97 -6.08 0.00
6.08 11.97 17.50 22.50 26.81 30.31 32.89 34.47 35.00
""")

# Podhorodeski et al. (2005): the drag-link project.
DRAG_LINK_FIXED = {"ground": 0.1, "crank": 0.225, "follower": 0.275}
DRAG_LINK_PROJECT = {**DRAG_LINK_FIXED, "follower_arm": 0.15, "connecting_rod": 0.3}
DRAG_LINK_TR = 1.5
DRAG_LINK_STROKE = 0.3
# printed: r3 = 0.1544 / 0.2504 m. Printed θ2a = 6.18° / 39.38°, but eqs. (2a) and (13) give
# 7.18° / 40.39° for those couplers: the equations win.
DRAG_LINK_COUPLERS = (0.1544, 0.2504)
DRAG_LINK_THETA2A_DEG = (7.18, 40.39)
# "Selecting the preferred value for r3": minimum coupler–follower transmission over the
# revolution (not the paper's TDC/BDC values): 9.09° (r3 0.1544) and 27.01° (r3 0.2504); the
# slider dyad's is acos(0.15/0.3) = 60°.
DRAG_LINK_MIN_TRANSMISSION_DEG = (9.09, 27.01)
# Fig. 5: feasible 0.15 ≤ r3 ≤ 0.40; TR from 1.4298 (r3 ≈ 0.1871) to 3.538 at r3 = 0.40. The paper
# prints 5.538; its eqs. (3)–(5) give 3.538.
DRAG_LINK_COUPLER_RANGE = (0.15, 0.40)
DRAG_LINK_TR_MIN = (1.4298, 0.1871)
DRAG_LINK_TR_AT_MAX_COUPLER = 3.538


def podhorodeski_couplers(tr: float) -> list[float]:
    """Podhorodeski et al. (2005), eqs. (7)–(13), written out here from the paper: the couplers
    giving ``tr``."""
    r1, r2, r4 = (DRAG_LINK_FIXED[k] for k in ("ground", "crank", "follower"))
    f = (tr - 1) * math.pi / (tr + 1)
    a = (r4 + r1) - (r4 - r1) * math.cos(f)
    b = (r4 - r1) * math.sin(f)
    c = 2 * r4 * r1 / r2
    roots = [
        math.atan2(b, a) + sign * math.atan2(math.sqrt(a * a + b * b - c * c), c)
        for sign in (-1, 1)
    ]
    return sorted(
        math.sqrt(r2**2 + (r4 + r1) ** 2 - 2 * r2 * (r4 + r1) * math.cos(t)) for t in roots
    )
