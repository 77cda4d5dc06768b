"""The default answer, objective pareto: per type, the front of designs that no other beats in
both minimum transmission angle (up) and size (down, the sum of link lengths).

Checked from outside: every point by the brute-force simulation (tests/support/bruteforce.py), the
front's shape (non-domination, even spread, exact ends) on seeded random targets, and its
inner points against the independent global search (tests/support/globalsearch.py): each must be the
smallest design that transmits at least as well.
"""

import dataclasses
import itertools

import numpy as np
import pytest

import synth

from ..support import bruteforce
from ..support import globalsearch as gs
from ..support.assertions import assert_meets

TYPES = gs.TYPES
MAX, SIZE = "max_transmission_angle", "min_size"


def fronts(r):
    """The candidates per type, best angle first, as the answer lists them."""
    out: dict[str, list] = {}
    for c in r.candidates:
        out.setdefault(c.type, []).append(c)
    return out


def single(tr, stroke, bound, mtype, objective):
    r = synth.synthesize(tr, stroke, bound, [{"type": mtype}], objective=objective)
    return r.candidates[0]


def assert_same_design(a, b):
    assert a.params.keys() == b.params.keys()
    scale = max(abs(v) for v in b.params.values())
    for k, v in b.params.items():
        assert a.params[k] == pytest.approx(v, abs=1e-9 * scale), k
    assert a.min_transmission_angle_deg == pytest.approx(b.min_transmission_angle_deg, rel=1e-9)
    assert a.size == pytest.approx(b.size, rel=1e-9)


def assert_front(points, tr, stroke, bound):
    """Non-dominated, best angle first, ends exact, spread evenly in angle."""
    angles = [c.min_transmission_angle_deg for c in points]
    sizes = [c.size for c in points]
    assert angles == sorted(angles, reverse=True) and sizes == sorted(sizes, reverse=True)
    for a, b in itertools.permutations(points, 2):
        better = a.min_transmission_angle_deg >= b.min_transmission_angle_deg and a.size <= b.size
        assert not better, f"{a.params} dominates {b.params}"
    mtype, n = points[0].type, len(points)
    assert [c.front.index for c in points] == list(range(n))[::-1]
    assert all(c.front.points == n and c.front.measure == "link_length_sum" for c in points)
    assert_same_design(points[0], single(tr, stroke, bound, mtype, MAX))
    assert MAX in points[0].front.ends
    if bound > 0:
        assert_same_design(points[-1], single(tr, stroke, bound, mtype, SIZE))
        assert SIZE in points[-1].front.ends
        lo, hi = angles[-1], angles[0]
        even = [hi - (hi - lo) * k / (n - 1) for k in range(n)] if n > 1 else [hi]
    else:
        even = [angles[0] * (n - k) / n for k in range(n)]
    # each point is the smallest design with at least its grid angle: on a connected front,
    # exactly there
    assert angles == pytest.approx(even, abs=1e-7)


def test_whitworth_front_for_the_textbook_targets():
    """Time ratio 1.6, stroke 300, bound 40°: the acceptance example."""
    r = synth.synthesize(1.6, 300.0, 40.0)
    assert r.complete
    by_type = fronts(r)
    whitworth = by_type["whitworth"]
    assert len(whitworth) >= 3
    for c in r.candidates:
        assert_meets(c, 1.6, 300.0, 40.0)
    assert_front(whitworth, 1.6, 300.0, 40.0)
    assert whitworth[-1].min_transmission_angle_deg == pytest.approx(40.0, rel=1e-9)
    (shaper,) = by_type["crank_shaper"]  # a slot drive: 90° at every size, one point
    assert shaper.front.ends == (SIZE, MAX) and shaper.params["ram_link"] == 0


@pytest.mark.parametrize("seed", range(6))
def test_fronts_on_random_targets(seed):
    rng = np.random.default_rng(seed)
    tr = float(rng.uniform(1.1, 2.6))
    bound = 0.0 if seed % 3 == 0 else float(rng.uniform(5.0, 45.0))
    stroke = float(10 ** rng.uniform(-2, 3))
    r = synth.synthesize(tr, stroke, bound)
    assert r.complete
    for points in fronts(r).values():
        assert len(points) <= 5
        assert_front(points, tr, stroke, bound)
        for c in points[:: max(1, len(points) // 2)]:
            assert_meets(c, tr, stroke, bound)


def test_max_candidates_counts_in_all():
    r = synth.synthesize(1.5, 1.0, 20.0, max_candidates=7)
    assert len(r.candidates) == 7 and not r.infeasible
    shares = {t: len(p) for t, p in fronts(r).items()}
    assert shares["crank_shaper"] == 1  # a slot drive: its front is one point
    assert sorted(shares.values()) == [1, 1, 1, 2, 2]
    one = synth.synthesize(1.5, 1.0, 20.0, max_candidates=2)
    assert len(one.candidates) == 2 and not one.infeasible  # the rest: not shown, not refused


@pytest.mark.parametrize("mtype", TYPES)
def test_inner_points_are_the_smallest_at_their_angle(mtype):
    """The global search for the smallest design at a front point's angle finds none smaller
    (and comes as close, or it is too weak to referee)."""
    tr, bound = 1.5, 10.0
    points = fronts(synth.synthesize(tr, 1.0, bound, [{"type": mtype}]))[mtype]
    inner = points[len(points) // 2]
    g = gs.search(mtype, SIZE, tr, inner.min_transmission_angle_deg, gs.QUICK)
    assert g.value is not None
    beat = (inner.size - g.value) / g.value
    assert -1e-6 <= beat <= 1e-9, (inner.params, g.params)


@pytest.mark.parametrize(("tr", "stroke", "bound"), [(1.6, 300.0, 40.0), (1.5, 1.0, 20.0)])
def test_families_are_equal_designs_and_the_free_scale_can_be_fixed(tr, stroke, bound):
    """A family's every member (by the brute-force simulation) has the candidate's time ratio,
    stroke and transmission angle; the candidate is its smallest member; fixing the free
    length in the request picks a member."""
    r = synth.synthesize(tr, stroke, bound)
    families = [c for c in r.candidates if c.family is not None]
    assert {c.type for c in families} >= {"crank_shaper", "whitworth"}
    for c in families:
        (free,) = c.family.free
        lo, hi = c.family.range[free]
        assert lo == pytest.approx(c.params[free], rel=1e-12) and hi > lo
        for x in (lo + (hi - lo) / 3, hi):
            member = {**c.params, free: x}
            member.update({k: ratio * x for k, (_, ratio) in c.family.tied.items()})
            b = bruteforce.simulate(c.type, member)
            assert b["time_ratio"] == pytest.approx(tr, rel=1e-9)
            assert b["stroke"] == pytest.approx(stroke, rel=1e-9)
            assert b["min_transmission_deg"] == pytest.approx(
                c.min_transmission_angle_deg, abs=1e-7
            )
        if MAX not in c.front.ends:
            continue  # the tied lengths, left free, would transmit better than an inner point
        x = (lo + hi) / 2
        fixed = {k: v for k, v in c.params.items() if k != free and k not in c.family.tied}
        spec = {"type": c.type, "fixed": {**fixed, free: x}}
        picked = synth.synthesize(tr, stroke, bound, [spec], objective=MAX).candidates[0]
        assert picked.family is None and picked.params[free] == x
        for k, (_, ratio) in c.family.tied.items():
            assert picked.params[k] == pytest.approx(ratio * x, rel=1e-9)
        assert picked.min_transmission_angle_deg == pytest.approx(
            c.min_transmission_angle_deg, abs=1e-9
        )


@pytest.mark.parametrize(("mtype", "bound"), [("whitworth", 40.0), ("drag_link_slider", 0.0)])
def test_a_wrong_prediction_of_the_ends_is_planned_again(mtype, bound, monkeypatch):
    """The front is planned on its ends' predictions, then verified. Predictions 1° too low
    (as if the best proposals had failed their verification and others stood in): the
    verified ends differ, the inner points are planned again from them, and the answer is the
    front planned on the right ends."""
    from synth.synthesis import front

    want = synth.synthesize(1.6, 300.0, bound, [{"type": mtype}]).candidates
    head = front.head_of

    def wrong(s, t):
        p = head(s, t)
        return None if p is None else dataclasses.replace(p, angle_deg=p.angle_deg - 1.0)

    monkeypatch.setattr(front, "head_of", wrong)
    got = synth.synthesize(1.6, 300.0, bound, [{"type": mtype}]).candidates
    assert len(got) == len(want) == 5
    for a, b in zip(got, want, strict=True):
        assert a.min_transmission_angle_deg == pytest.approx(
            b.min_transmission_angle_deg, rel=1e-12
        )
        assert a.size == pytest.approx(b.size, rel=1e-12) and a.front == b.front
