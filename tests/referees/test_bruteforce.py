"""Self-test of the independent reference simulator tests/support/bruteforce.py.

Checks it against the sources' reference cases (docs/model.md, Reference cases) and, on random
designs, against the types' closed forms (used here ONLY as a cross-check of the simulator).
"""

import math

import numpy as np
import pytest

from ..support import bruteforce as bf

D = math.degrees
R = math.radians
TIGHT = 1e-11  # relative, time ratio and stroke
MU_TOL = 1e-8  # degrees


def rel(a, b):
    return abs(a - b) / abs(b)


# ------------------------------------------------------------------ reference cases
# the slotted-lever lab handout, Table 1, theory column (X = 70 + s), crank angle 0, 10, …, 360°
SLOTTED_LEVER_LAB_TABLE = [
    70.00,
    78.36,
    86.58,
    94.53,
    102.08,
    109.07,
    115.36,
    120.77,
    125.12,
    128.21,
    129.82,
    129.71,
    127.65,
    123.39,
    116.79,
    107.81,
    96.66,
    83.80,
    70.00,
    56.20,
    43.34,
    32.19,
    23.21,
    16.61,
    12.35,
    10.29,
    10.18,
    11.79,
    14.88,
    19.23,
    24.64,
    30.93,
    37.92,
    45.47,
    53.42,
    61.64,
    70.00,
]
LAB = dict(crank=40, pivot_distance=160, lever=240, ram_link=0)


def test_slotted_lever_lab_table_and_extremes():
    th = np.radians(np.arange(0, 361, 10))
    x = 70 + bf.position("crank_shaper", LAB, th)
    assert np.max(np.abs(x - SLOTTED_LEVER_LAB_TABLE)) <= 0.005 + 1e-9
    r = bf.simulate("crank_shaper", LAB)
    assert 70 + r["s_max"] == pytest.approx(130.0, abs=1e-12)
    assert 70 + r["s_min"] == pytest.approx(10.0, abs=1e-12)
    assert round(D(r["theta_max"]), 2) == 104.48
    assert round(D(r["theta_min"]), 2) == 255.52
    assert round(r["time_ratio"], 5) == 1.38340  # the lab's 200/160 is a 10-deg sampling artefact
    assert r["working_direction"] == 1
    assert r["min_transmission_deg"] == r["max_transmission_deg"] == 90.0 and r["joints"] == {}


@pytest.mark.parametrize(
    "params, tr, stroke",
    [
        (dict(crank=120, pivot_distance=300, lever=420), 1.70995, None),  # textbook Ex. 1
        (dict(crank=120, pivot_distance=300, lever=600), 1.70995, None),  # any lever >= 420
        (dict(crank=120, pivot_distance=240, lever=450), 2.0, 450.0),  # textbook Ex. 2
        (dict(crank=100, pivot_distance=250, lever=650), 1.70995, 520.0),  # Shelare et al. (2012)
    ],
)
def test_crank_shaper_book_cases(params, tr, stroke):
    r = bf.simulate("crank_shaper", params)
    assert round(r["time_ratio"], 5) == pytest.approx(tr, abs=1e-12)
    if stroke is not None:
        assert r["stroke"] == pytest.approx(stroke, rel=1e-12)


def test_crank_shaper_ex2_lever_inclination():
    p = bf.complete("crank_shaper", dict(crank=120, pivot_distance=240, lever=450))
    assert D(math.acos(p["ram_height"] / 450)) == pytest.approx(30.0, abs=1e-11)
    assert p["ram_link"] == 0


def test_whitworth_textbook_example3():
    r = bf.simulate("whitworth", dict(crank=75, pivot_distance=50, lever=150, connecting_rod=200))
    assert round(r["time_ratio"], 5) == 2.73524
    assert round(D(2 * math.pi - r["working_angle"]), 2) == 96.38
    assert r["stroke"] == pytest.approx(300, rel=1e-12)
    with pytest.raises(ValueError):  # the book's rod 135 < lever 150 cannot run in this layout
        bf.simulate("whitworth", dict(crank=75, pivot_distance=50, lever=150, connecting_rod=135))


def test_scotch_yoke_slotted_link_lab():
    p = dict(crank=35)
    th = np.radians(np.arange(0, 361, 10))
    x = 35 - bf.position("scotch_yoke", p, th)  # x = r(1 - cos)
    table = {20: 2.11, 50: 12.50, 90: 35.0, 170: 69.47, 180: 70.0, 250: 46.97, 350: 0.53}
    for deg, val in table.items():
        assert x[deg // 10] == pytest.approx(val, abs=0.005)
    v = -np.imag(bf.position("scotch_yoke", p, th + 1e-30j)) / 1e-30  # dx/dtheta (omega = 1)
    assert v[2] == pytest.approx(11.97, abs=0.005) and v[19] == pytest.approx(-6.08, abs=0.005)
    r = bf.simulate("scotch_yoke", p)
    assert r["time_ratio"] == pytest.approx(1.0, abs=1e-14)
    assert r["stroke"] == pytest.approx(70, rel=1e-14)
    assert r["min_transmission_deg"] == 90.0


def drag_link_coupler(r1, r2, r4, tr):
    """Podhorodeski et al. (2005) eqs. (7)-(13), for the self-test only."""
    f = (tr - 1) * math.pi / (tr + 1)
    a, b, c = (r4 + r1) - (r4 - r1) * math.cos(f), (r4 - r1) * math.sin(f), 2 * r4 * r1 / r2
    out = []
    for sg in (1, -1):
        t = math.atan2(b, a) + sg * math.atan2(math.sqrt(a * a + b * b - c * c), c)
        out.append(math.sqrt(r2**2 + (r4 + r1) ** 2 - 2 * r2 * (r4 + r1) * math.cos(t)))
    return sorted(out)


PROJECT = dict(ground=0.1, crank=0.225, follower=0.275, follower_arm=0.15, connecting_rod=0.3)


@pytest.mark.parametrize("coupler, mu", [(0.2504, 27.01), (0.1544, 9.09)])
def test_drag_link_project(coupler, mu):
    exact = drag_link_coupler(0.1, 0.225, 0.275, 1.5)
    # eq. (13) gives 0.154344 / 0.250428: the paper's "0.1544" is its own rounding slip
    assert np.allclose(exact, [0.1544, 0.2504], atol=1e-4)
    # the printed 4-decimal coupler: loose (the coupler is rounded; 0.1544 gives 9.15 deg)
    r = bf.simulate("drag_link_slider", dict(PROJECT, coupler=coupler))
    assert r["time_ratio"] == pytest.approx(1.5, abs=1e-3)
    assert r["stroke"] == pytest.approx(0.3, rel=1e-12)
    assert r["joints"]["coupler-follower"][0] == pytest.approx(mu, abs=0.1)
    assert r["joints"]["connecting_rod-slider"][0] == pytest.approx(60.0, abs=1e-9)
    # the exact coupler of eq. (13): tight
    c = min(exact, key=lambda x: abs(x - coupler))
    r = bf.simulate("drag_link_slider", dict(PROJECT, coupler=c))
    assert r["time_ratio"] == pytest.approx(1.5, rel=1e-11)
    assert round(r["min_transmission_deg"], 2) == mu


def test_drag_link_fig5_range():
    tr = {
        c: bf.simulate("drag_link_slider", dict(PROJECT, coupler=c))["time_ratio"]
        for c in np.linspace(0.151, 0.3999, 60)
    }
    c_min = min(tr, key=tr.get)
    assert 1.4295 < tr[c_min] < 1.4305 and 0.18 < c_min < 0.195
    # r3 = 0.40 is the Grashof change point (dyad straight at theta = 0); the paper prints 5.538,
    # its eqs. (3)-(5) give 3.538
    r = bf.simulate("drag_link_slider", dict(PROJECT, coupler=0.4))
    assert round(r["time_ratio"], 3) == 3.538
    with pytest.raises(ValueError):  # beyond the drag-link range
        bf.simulate("drag_link_slider", dict(PROJECT, coupler=0.41))


def test_drag_link_velocity_fd():
    c = drag_link_coupler(0.1, 0.225, 0.275, 1.5)[1]
    p = dict(PROJECT, coupler=c)
    t, h = R(60), 1e-4
    ds = np.imag(bf.position("drag_link_slider", p, np.array([t + 1e-30j])))[0] / 1e-30
    s = bf.position("drag_link_slider", p, np.array([t - h, t, t + h]))
    assert ds == pytest.approx((s[2] - s[0]) / (2 * h), rel=1e-7)


# ------------------------------------------------------------------ closed-form cross-checks
rng = np.random.default_rng(12345)


def u(a, b):
    return float(rng.uniform(a, b))


def fold(c):
    return D(math.acos(min(abs(c), 1.0)))


def check(mtype, params, tr=None, stroke=None, joints=None):
    r = bf.simulate(mtype, params)
    if tr is not None:
        assert rel(r["time_ratio"], max(tr, 1 / tr)) < TIGHT, (params, r["time_ratio"], tr)
    if stroke is not None:
        assert rel(r["stroke"], stroke) < TIGHT, (params, r["stroke"], stroke)
    for name, (lo, hi) in (joints or {}).items():
        got = r["joints"][name]
        assert abs(got[0] - lo) < MU_TOL and abs(got[1] - hi) < MU_TOL, (params, name, got, lo, hi)
    return r


def mu_range(c1, c2):
    """(min, max) folded transmission angle of a cos monotonic between c1 and c2."""
    lo = min(fold(c1), fold(c2))
    hi = 90.0 if c1 * c2 <= 0 else max(fold(c1), fold(c2))
    return lo, hi


@pytest.mark.parametrize("k", range(6))
def test_offset_slider_crank_closed_form(k):
    r2 = u(0.5, 2)
    e = u(-1.5, 1.5) * r2
    r3 = (r2 + abs(e)) * u(1.05, 3)
    beta = math.asin(abs(e) / (r3 - r2)) - math.asin(abs(e) / (r3 + r2))
    check(
        "offset_slider_crank",
        dict(crank=r2, coupler=r3, offset=e),
        tr=(math.pi + beta) / (math.pi - beta),
        stroke=math.sqrt((r3 + r2) ** 2 - e * e) - math.sqrt((r3 - r2) ** 2 - e * e),
        joints={"coupler-slider": mu_range((e - r2) / r3, (e + r2) / r3)},
    )


@pytest.mark.parametrize("k", range(6))
def test_crank_shaper_closed_form(k):
    r2 = u(0.5, 2)
    d = r2 / u(0.2, 0.9)
    L = (d + r2) * u(1, 2)
    a = math.asin(r2 / d)
    tr = (math.pi + 2 * a) / (math.pi - 2 * a)
    check("crank_shaper", dict(crank=r2, pivot_distance=d, lever=L), tr=tr, stroke=2 * L * r2 / d)
    p = bf.complete("crank_shaper", dict(crank=r2, pivot_distance=d, lever=L))
    assert rel(p["ram_height"], L * math.cos(a)) < 1e-13
    # ram link long enough for s to stay monotonic in psi; default ram height
    gap = L * (1 - math.cos(a))
    ll = gap * u(3, 10) + 0.5 * L
    check(
        "crank_shaper",
        dict(crank=r2, pivot_distance=d, lever=L, ram_link=ll),
        tr=tr,
        stroke=2 * L * r2 / d,
        joints={"ram_link-ram": (fold(gap / ll), 90.0)},
    )


@pytest.mark.parametrize("k", range(6))
def test_whitworth_closed_form(k):
    d = u(0.5, 2)
    r2 = d * u(1.1, 3)
    L = u(0.5, 3)
    ll = L * u(1.05, 3)
    q = math.acos(d / r2)
    check(
        "whitworth",
        dict(crank=r2, pivot_distance=d, lever=L, connecting_rod=ll),
        tr=(math.pi - q) / q,
        stroke=2 * L,
        joints={"connecting_rod-ram": (fold(L / ll), 90.0)},
    )


def grashof_four_bar(shortest):
    """Three random links and a shortest one satisfying Grashof."""
    limit = 0
    while limit < 0.1:
        a, b, c = u(1, 3), u(1, 3), u(1, 3)
        limit = min(a, b, c, a + b + c - 2 * max(a, b, c))
    return shortest * limit, a, b, c


@pytest.mark.parametrize("k", range(6))
def test_crank_rocker_slider_closed_form(k):
    r2, r1, r3, r4 = grashof_four_bar(u(0.1, 0.9))
    r5 = u(0.3, 2)
    fe = math.acos((r1**2 + (r2 + r3) ** 2 - r4**2) / (2 * r1 * (r2 + r3)))
    ff = math.acos((r1**2 + (r3 - r2) ** 2 - r4**2) / (2 * r1 * (r3 - r2)))
    dphi = abs(ff - fe)
    tr = (math.pi + dphi) / (math.pi - dphi)
    # rocker angles at the toggles (D at |O2D| = r3 +- r2, angle fe / ff above the ground line)
    psi = [
        math.atan2(x * math.sin(f), x * math.cos(f) - r1) for x, f in ((r2 + r3, fe), (r3 - r2, ff))
    ]
    swing = abs(psi[0] - psi[1])
    cc = [(r3**2 + r4**2 - (r1 - sg * r2) ** 2) / (2 * r3 * r4) for sg in (1, -1)]
    base = dict(ground=r1, crank=r2, coupler=r3, rocker=r4, rocker_arm=r5)
    p = bf.complete("crank_rocker_slider", base)
    assert p["connecting_rod"] == 0
    assert abs(p["slider_height"] - r5 * math.cos(swing / 2)) < 1e-13 * r5
    stroke = 2 * r5 * math.sin(swing / 2)
    check(
        "crank_rocker_slider", base, tr=tr, stroke=stroke, joints={"coupler-rocker": mu_range(*cc)}
    )
    r6 = r5 * u(2, 5)  # long rod, default height: s monotonic over the swing
    check(
        "crank_rocker_slider",
        dict(base, connecting_rod=r6),
        tr=tr,
        stroke=stroke,
        joints={"coupler-rocker": mu_range(*cc)},
    )


@pytest.mark.parametrize("k", range(6))
def test_drag_link_slider_closed_form(k):
    r1, r2, r3, r4 = grashof_four_bar(u(0.1, 0.9))
    r5 = u(0.3, 2)
    r6 = r5 * u(1.1, 3)
    t2a = math.acos((r2**2 + (r4 + r1) ** 2 - r3**2) / (2 * r2 * (r4 + r1)))
    t2b = math.acos((r2**2 + (r4 - r1) ** 2 - r3**2) / (2 * r2 * (r4 - r1)))
    cc = [(r3**2 + r4**2 - (r2 - sg * r1) ** 2) / (2 * r3 * r4) for sg in (1, -1)]
    check(
        "drag_link_slider",
        dict(ground=r1, crank=r2, coupler=r3, follower=r4, follower_arm=r5, connecting_rod=r6),
        tr=(math.pi - t2a + t2b) / (math.pi + t2a - t2b),
        stroke=2 * r5,
        joints={"coupler-follower": mu_range(*cc), "connecting_rod-slider": (fold(r5 / r6), 90.0)},
    )


# ------------------------------------------------------------------ conventions
def test_scale_invariance_and_direction():
    p = dict(
        ground=0.1,
        crank=0.225,
        coupler=0.2504,
        follower=0.275,
        follower_arm=0.15,
        connecting_rod=0.3,
    )
    a = bf.simulate("drag_link_slider", p)
    b = bf.simulate("drag_link_slider", {k: 1000 * v for k, v in p.items()})
    assert rel(b["time_ratio"], a["time_ratio"]) < 1e-12
    assert rel(b["stroke"], 1000 * a["stroke"]) < 1e-12
    assert abs(b["min_transmission_deg"] - a["min_transmission_deg"]) < 1e-9
    # slow stroke and working_direction agree with the positions
    for r in (a, b):
        up = (r["theta_max"] - r["theta_min"]) % (2 * math.pi)
        assert r["working_angle"] == pytest.approx(max(up, 2 * math.pi - up), abs=0)
        assert r["working_direction"] == (1 if up >= math.pi else -1)
        quick = 2 * math.pi - r["working_angle"]
        assert r["time_ratio"] == pytest.approx(r["working_angle"] / quick)


@pytest.mark.parametrize(
    "mtype, params",
    [
        ("crank_shaper", dict(crank=160, pivot_distance=160, lever=400)),
        ("crank_shaper", dict(crank=40, pivot_distance=160, lever=190)),
        ("whitworth", dict(crank=40, pivot_distance=50, lever=100, connecting_rod=150)),
        ("offset_slider_crank", dict(crank=1, coupler=1.5, offset=0.6)),
        ("offset_slider_crank", dict(crank=1, coupler=3)),
        ("crank_rocker_slider", dict(ground=1, crank=0.3, coupler=0.2, rocker=0.8, rocker_arm=0.5)),
        (
            "crank_rocker_slider",
            dict(ground=0.1, crank=0.225, coupler=0.25, rocker=0.275, rocker_arm=0.1),
        ),  # a drag-link: the rocker turns fully
        (
            "crank_rocker_slider",
            dict(
                ground=1,
                crank=0.3,
                coupler=1.1,
                rocker=0.8,
                rocker_arm=0.6,
                connecting_rod=0.05,
                slider_height=0.5,
            ),
        ),
    ],
)
def test_invalid_designs_raise(mtype, params):
    with pytest.raises(ValueError):
        bf.simulate(mtype, params)


def test_complex_step_matches_finite_difference():
    th = np.linspace(0.1, 6.2, 7)
    cases = [
        ("offset_slider_crank", dict(crank=1, coupler=3, offset=0.7)),
        ("crank_shaper", dict(crank=100, pivot_distance=250, lever=650, ram_link=200)),
        ("whitworth", dict(crank=75, pivot_distance=50, lever=150, connecting_rod=200)),
        (
            "crank_rocker_slider",
            dict(ground=1, crank=0.3, coupler=1.1, rocker=0.8, rocker_arm=0.6, connecting_rod=1.0),
        ),
    ]
    for mtype, p in cases:
        cs = np.imag(bf.position(mtype, p, th + 1e-30j)) / 1e-30
        h = 1e-5
        fd = (bf.position(mtype, p, th + h) - bf.position(mtype, p, th - h)) / (2 * h)
        assert np.allclose(cs, fd, rtol=1e-6, atol=1e-8 * np.max(np.abs(fd)))
        for name, c in bf.transmission_cos(mtype, p, th + 1e-30j).items():
            assert np.all(np.abs(np.imag(c)) < 1e-25), name
