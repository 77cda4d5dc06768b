"""synth.synthesize against an independent global search (tests/support/globalsearch.py).

The project rule: a claimed optimum, or a refusal's best reachable number, is checked against an
independent global search (several seeds) on a sample. Only synthesize()'s public answer is
used, for targets (time ratio, transmission bound) at stroke 1 with nothing fixed and the
default bounds:

- candidates: every one within the default bounds (the search space); the best is not
  beaten: max_transmission_angle by more than 1e-6°, min_size by more than 1e-9 relative; and
  the search reaches it too (1e-4°, 1e-6 relative), else it would be too weak to referee;
- TRANSMISSION_UNREACHABLE: no design at the targets beats the claimed best angle by 1e-6°,
  and one comes within 1e-4° of it (the claim is not an over-estimate);
- TIME_RATIO_UNREACHABLE: no design at the target time ratio meets the bound, and the range
  holds every reachable time ratio: 1e-6 relative at the end the target lies beyond, 1e-3 at
  the other (a sanity check there: an optimiser stopping 1e-6 short of TR 1 is no defect).

`make test` runs the quick form (a few targets per type, two seeds, short runs); `make stress`
(HYPOTHESIS_PROFILE=stress) the full one: more than 20 seeded targets per type and objective,
three seeds, longer runs. Both polish every seed's best. (The last finding, the offset
slider-crank's range at TR 3 and bound 0 ending 1e-5 short, went with its reduced solver's
reparametrisation without cancellation.)

Fixed parts: targets drawn from random valid designs (tests/support/designs.py) at stroke 1
within the default bounds, one or two of each design's parts kept at its values (every single
part among them), so a design exists; max_transmission_angle, min_size (the bound 1–5° below
the design's angle) and the front's two ends (``pareto``: its best angle and its smallest
design) each against the global search with the same parts fixed, in the search space a
request has (the upper bounds × the largest fixed length; parts the targets and the fixed
parts set on their own unbounded), neither beaten by more than 1e-9 relative. The quick form
checks a few, the full one at least ``FIXED_TARGETS`` per type. (The finding: a drag-link's
smallest design with its crank fixed was a local optimum, 0.16 % too large.)
"""

from __future__ import annotations

import math
import os

import numpy as np
import pytest

import synth

from ..support import globalsearch as gs
from ..support.designs import random_designs

FULL = os.environ.get("HYPOTHESIS_PROFILE") == "stress"
EFFORT = gs.FULL if FULL else gs.QUICK
BUDGET_MS = 60_000  # a complete answer: a partial one may rightly be worse
ANGLE_TOL = 1e-6  # degrees
SIZE_TOL = 1e-9  # relative
TR_TOL = 1e-6  # relative, at the end of the range the target lies beyond
TR_SANITY = 1e-3  # relative, at the other end
REACH_DEG = 1e-4  # the global search must come this close to a claim (else it is too weak)
REACH_SIZE = 1e-6
OBJECTIVES = ("max_transmission_angle", "min_size")

MAX, SIZE = OBJECTIVES

# parameters the targets set on their own: the default bounds limit a search, not these
SET_BY_TARGETS = {
    "crank_shaper": {"lever"},
    "whitworth": {"lever"},
    "drag_link_slider": {"follower_arm"},
}


# quick form: per type a target with candidates (both objectives) and a refusal; the findings
QUICK = [
    ("offset_slider_crank", MAX, 1.6, 15.0),
    ("offset_slider_crank", SIZE, 1.6, 15.0),
    ("offset_slider_crank", MAX, 3.0, 30.0),  # no TR 3 (β = 90°)
    ("crank_shaper", MAX, 2.2, 70.0),
    ("crank_shaper", SIZE, 2.2, 70.0),
    ("crank_shaper", MAX, 1.1, 20.0),  # a lever 6.69 × stroke: the only one for TR 1.1
    ("whitworth", MAX, 1.8, 50.0),
    ("whitworth", SIZE, 1.8, 50.0),
    ("whitworth", MAX, 2.4, 80.0),  # 75.52° at most (rod ≤ 2 × stroke)
    ("crank_rocker_slider", MAX, 1.4, 30.0),
    ("crank_rocker_slider", SIZE, 1.4, 30.0),
    ("crank_rocker_slider", MAX, 2.2, 25.0),
    ("drag_link_slider", MAX, 1.2, 45.0),
    ("drag_link_slider", SIZE, 1.2, 45.0),
    ("drag_link_slider", MAX, 2.7, 20.0),
    ("drag_link_slider", SIZE, 1.4687, 33.01),  # a design with 2.134 exists
]
# full form: the quick targets, the edges of each type and seeded random ones, both objectives
EDGES = {
    "offset_slider_crank": [(3.0, 0.0), (2.9, 0.0), (1.05, 80.0), (1.3, 0.0), (2.5, 0.0)],
    "crank_shaper": [(1.05, 0.0), (1.13, 80.0), (1.14, 80.0), (3.0, 0.0)],
    "whitworth": [(1.02, 10.0), (1.05, 84.0), (3.0, 84.5), (1.5, 0.0)],
    "crank_rocker_slider": [(1.3, 0.0), (2.0, 0.0), (3.0, 0.0), (1.05, 80.0), (1.1, 5.0)],
    "drag_link_slider": [(1.3, 0.0), (2.5, 0.0), (3.0, 0.0), (1.05, 80.0)],
}
RANDOM = 24  # per type


def cases():
    """(type, objective, time ratio, bound°): the quick cases, or in the full form every
    target with both objectives."""
    out = list(QUICK)
    if FULL:
        out = []
        for mtype in gs.TYPES:
            rng = np.random.default_rng(1000 + gs.TYPES.index(mtype))
            trs = np.round(rng.uniform(1.05, 3.0, RANDOM), 4).tolist()
            bounds = np.round(rng.uniform(0.0, 80.0, RANDOM), 2).tolist()
            quick = [(tr, b) for t, _, tr, b in QUICK if t == mtype]
            for tr, b in dict.fromkeys(quick + EDGES[mtype] + list(zip(trs, bounds, strict=True))):
                # at bound 0 the smallest design sits on a dead point, a strict limit: the
                # infimum is no design, and a solver's margin from it no defect
                out += [(mtype, o, tr, b) for o in OBJECTIVES if o != SIZE or b >= 1]
    for c in out:
        yield pytest.param(*c, id="-".join(map(str, c)))


def synthesize(mtype, objective, tr, bound, fixed=None):
    r = synth.synthesize(
        tr,
        1.0,
        bound,
        mechanisms=[{"type": mtype, "fixed": dict(fixed or {})}],
        objective=objective,
        max_candidates=50,
        time_budget_ms=BUDGET_MS,
    )
    assert r.complete, "synthesize ran out of its budget: no claim to check"
    return r


def judge(mtype: str, objective: str, tr: float, bound: float, r, effort=EFFORT) -> dict:
    """Check one synthesize() answer against the global search; returns by how much the search
    beat it (> 0: synth is worse; degrees, relative size or relative time ratio)."""
    if r.candidates:
        for c in r.candidates:
            _within_default_bounds(c)
        if objective == MAX:
            return _best_angle(mtype, tr, r, effort)
        return _smallest(mtype, tr, bound, r, effort)
    assert r.infeasible, "neither candidates nor a reason"
    why = r.infeasible[0]
    if why.code == "TRANSMISSION_UNREACHABLE":
        return _claimed_angle(mtype, tr, why, effort)
    if why.code == "TIME_RATIO_UNREACHABLE":
        return _claimed_range(mtype, tr, bound, why, effort)
    raise AssertionError(f"unexpected refusal with nothing fixed: {why}")


def _within_default_bounds(c, stroke=1.0, fixed=None):
    """The search space is the default bounds: a candidate outside them answers another
    question. A zero part is a variant; the placement of a part that is absent is idle; a part
    the targets set on their own is not searched. With ``fixed`` parts, the space a request
    with them has (``globalsearch.Fix``): a fixed part is as given."""
    idle = {"ram_height": "ram_link", "slider_height": "connecting_rod"}
    fx = gs.Fix(c.type, tuple(sorted((fixed or {}).items())))
    top = max([1.0, *(abs(v) for v in fx.fixed.values())])
    for q in synth.mechanisms.get(c.type).parameters:
        v = abs(c.params[q.name])  # a negative offset is the mirror of the positive one
        if (q.zero_means and v == 0) or (q.name in idle and c.params[idle[q.name]] == 0):
            continue
        if q.name in SET_BY_TARGETS.get(c.type, ()) or q.name in fx.fixed or q.name in fx.exempt:
            continue
        lo, hi = q.bounds[0] * stroke, q.bounds[1] * stroke * top
        assert lo * (1 - 1e-9) <= v <= hi * (1 + 1e-9), (
            f"candidate {c.params}: {q.name} {v!r} is outside the default bounds [{lo}, {hi}]"
        )


def _best_angle(mtype, tr, r, effort):
    mine = max(r.candidates, key=lambda c: c.min_transmission_angle_deg)
    angle = mine.min_transmission_angle_deg
    return _angle(mtype, tr, angle, effort, f"best {angle!r}° ({mine.params})")


def _angle(mtype, tr, claim, effort, what):
    """The global search's best angle at TR ``tr`` against synth's ``claim`` (``what``)."""
    g = gs.search(mtype, "max_transmission_angle", tr, 0.0, effort)
    assert g.value is not None, f"the global search finds no design at TR {tr}; synth: {what}"
    beat = g.value - claim
    assert beat <= ANGLE_TOL, (
        f"synth's {what} is beaten by {g.value!r}° ({g.params}, simulated "
        f"{g.simulated['min_transmission_deg']!r}°)"
    )
    assert beat >= -REACH_DEG, (
        f"the global search reaches only {g.value!r}° ({g.params}), synth's {what}: one of "
        f"them is wrong (a weak search, or an angle claimed that no design reaches)"
    )
    return {"beat": beat, "global": g}


def _smallest(mtype, tr, bound, r, effort):
    mine = min(r.candidates, key=lambda c: c.size)
    g = gs.search(mtype, "min_size", tr, bound, effort)
    assert g.value is not None, f"the global search found no design; synth found {mine.params}"
    beat = (mine.size - g.value) / g.value
    assert beat <= SIZE_TOL, (
        f"synth's smallest {mine.size!r} ({mine.params}) is beaten by {g.value!r} ({g.params})"
    )
    assert beat >= -REACH_SIZE, (
        f"the global search reaches only size {g.value!r} ({g.params}), synth {mine.size!r} "
        f"({mine.params}): too weak to referee"
    )
    return {"beat": beat, "global": g}


def _claimed_angle(mtype, tr, why, effort):
    claim = why.best_transmission_angle_deg
    assert claim is not None and math.isfinite(claim), f"no number in the refusal: {why}"
    return _angle(mtype, tr, claim, effort, f"refusal's best reachable {claim!r}°")


def _claimed_range(mtype, tr, bound, why, effort):
    assert why.time_ratio_range is not None, f"no range in the refusal: {why}"
    lo, hi = why.time_ratio_range
    at = gs.search(mtype, "max_transmission_angle", tr, 0.0, effort)
    assert at.value is None or at.value < bound + ANGLE_TOL, (
        f"refused, yet {at.params} has time ratio {tr} and a transmission angle of "
        f"{at.value!r}° ≥ {bound}°"
    )
    up_tol, down_tol = (TR_TOL, TR_SANITY) if tr > hi else (TR_SANITY, TR_TOL)
    # each search stops just past the tolerance: reaching there refutes the claim
    top = gs.search(mtype, "max_time_ratio", None, bound, effort, limit=hi * (1 + 2 * up_tol))
    low = gs.search(mtype, "min_time_ratio", None, bound, effort, limit=lo * (1 - 2 * down_tol))
    assert top.value is not None and low.value is not None, "no design meets the bound at all"
    assert top.value <= hi * (1 + up_tol), (
        f"synth's range {lo!r} … {hi!r}; {top.params} reaches time ratio {top.value!r} with a "
        f"transmission angle ≥ {bound}°"
    )
    assert low.value >= lo * (1 - down_tol), (
        f"synth's range {lo!r} … {hi!r}; {low.params} reaches time ratio {low.value!r} with a "
        f"transmission angle ≥ {bound}°"
    )
    return {"beat": max(top.value / hi - 1, 1 - low.value / lo), "global": top}


@pytest.mark.parametrize(("mtype", "objective", "tr", "bound"), list(cases()))
def test_synthesis_is_not_beaten_by_a_global_search(mtype, objective, tr, bound):
    judge(mtype, objective, tr, bound, synthesize(mtype, objective, tr, bound))


# ------------------------------------------------------------------ fixed parts
FIXED_TARGETS = 30  # per type in the full form, each with every objective
FIXED_TOL = 1e-9  # relative, angle and size alike
PARETO = "pareto"
FIXED_OBJECTIVES = (MAX, SIZE, PARETO)
# the quick form: (type, objective, time ratio, bound°, fixed parts), stroke 1
FIXED_QUICK = [
    ("drag_link_slider", SIZE, 1.5, 20.0, {"crank": 1.0}),  # the finding
    ("drag_link_slider", MAX, 1.6, 20.0, {"coupler": 0.6, "follower": 0.5}),
    ("crank_rocker_slider", SIZE, 1.6, 20.0, {"ground": 1.0}),
    ("crank_rocker_slider", PARETO, 1.4, 25.0, {"rocker": 0.8}),
    ("offset_slider_crank", SIZE, 1.6, 15.0, {"crank": 0.45}),
    ("whitworth", MAX, 1.8, 40.0, {"connecting_rod": 1.2}),
]


def _drawn(mtype: str) -> list[tuple[float, float, dict[str, float]]]:
    """Designs at stroke 1 within the default bounds: (time ratio, min transmission°, params
    that may be fixed), seeded."""
    m = synth.mechanisms.get(mtype)
    out = []
    for p in random_designs(mtype, 3000, seed=28):
        try:
            a = synth.analyze(mtype, p)
        except synth.SynthError:
            continue
        if a.reversals != 2 or not 1.05 <= a.time_ratio <= 3.0 or a.transmission.min_deg < 6:
            continue
        q = {k: v / a.stroke for k, v in a.params.items() if k in m.names}
        inside = all(
            (m.parameter(k).zero_means and v == 0) or lo <= abs(v) <= hi
            for k, v in q.items()
            for lo, hi in [m.parameter(k).bounds]
            if k not in SET_BY_TARGETS.get(mtype, ()) and m.parameter(k).default_rule is None
        )
        if inside:
            out.append((a.time_ratio, a.transmission.min_deg, q))
        if len(out) == FIXED_TARGETS:
            break
    return out


def fixed_targets(mtype: str) -> list[tuple[float, float, dict[str, float]]]:
    """(time ratio, bound°, fixed) of ``FIXED_TARGETS`` drawn designs of a type, each with one
    part fixed (every part in turn) or two, the bound 1–5° below the design's angle, seeded:
    the targets of the full form here and of the motion objectives' (test_motion_search)."""
    rng = np.random.default_rng(2800 + gs.TYPES.index(mtype))
    out = []
    for n, (tr, mu, q) in enumerate(_drawn(mtype)):
        names = sorted(q)
        one = names[n % len(names)]
        chosen = (
            [one]
            if n < len(names) or rng.random() < 0.5
            else [one, rng.choice([k for k in names if k != one])]
        )
        # the design's own numbers: two fixed parts of a slider-crank leave it alone,
        # so they must agree with the time ratio to rounding
        fixed = {str(k): float(q[k]) for k in chosen}
        bound = round(max(1.0, mu - rng.uniform(1.0, 5.0)), 4)
        out.append((float(tr), bound, fixed))
    return out


def case_id(c: tuple) -> str:
    """(type, objective, time ratio, bound°, fixed) as a test's id."""
    return f"{c[0]}-{c[1]}-{c[2]:.9g}-{c[3]:g}-" + "+".join(sorted(c[4]))


def fixed_cases():
    """(type, objective, time ratio, bound°, fixed): the quick cases, or in the full form per
    type ``fixed_targets`` with every objective."""
    out = list(FIXED_QUICK)
    if FULL:
        out = [
            (mtype, o, tr, bound, fixed)
            for mtype in gs.TYPES
            for tr, bound, fixed in fixed_targets(mtype)
            for o in FIXED_OBJECTIVES
        ]
    for c in out:
        yield pytest.param(*c, id=case_id(c))


def _beaten(what: str, mine: float, theirs: float, up: bool, g) -> float:
    """By how much (relative) the global search's ``theirs`` beats synth's ``mine``."""
    beat = (theirs - mine if up else mine - theirs) / abs(theirs)
    assert beat <= FIXED_TOL, f"synth's {what} {mine!r} is beaten by {theirs!r} ({g.params})"
    assert beat >= -(1e-6 if up else REACH_SIZE), (
        f"the global search reaches only {theirs!r} ({g.params}), synth's {what} {mine!r}: "
        f"too weak to referee"
    )
    return beat


@pytest.mark.parametrize(("mtype", "objective", "tr", "bound", "fixed"), list(fixed_cases()))
def test_synthesis_with_fixed_parts_is_not_beaten_by_a_global_search(
    mtype, objective, tr, bound, fixed
):
    r = synthesize(mtype, objective, tr, bound, fixed)
    assert r.candidates, f"no design, yet the targets are a design's: {r.infeasible}"
    for c in r.candidates:
        _within_default_bounds(c, fixed=fixed)
    if objective in (MAX, PARETO):
        g = gs.search(mtype, MAX, tr, 0.0, EFFORT, fixed=fixed)
        assert g.value is not None, "the global search finds no design"
        mine = max(c.min_transmission_angle_deg for c in r.candidates)
        _beaten("best angle", mine, g.value, True, g)
    if objective in (SIZE, PARETO):
        g = gs.search(mtype, SIZE, tr, bound, EFFORT, fixed=fixed)
        assert g.value is not None, "the global search finds no design"
        mine = min(c.size for c in r.candidates)
        _beaten("smallest size", mine, g.value, False, g)
