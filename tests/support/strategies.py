"""Hypothesis strategies for valid designs of every type, weighted to the edges.

Every design is built from dimensionless shape numbers and a scale of 1e-6 … 1e6, with the
shape numbers drawn to reach the limits: a time ratio → 1⁺ (offset → 0, crank/pivot → 0) and
→ its maximum (crank/pivot → 1: crank_shaper ↔ whitworth), the Grashof equality (the
coupler exactly at a limit), rods exactly or barely long enough (dead points), link ratios
from 1e-3 to 1e3. Nothing here uses synth, but for a type these strategies do not know (a
new module of synth.mechanisms): its parameters are drawn from its registry record, each
log-uniform within its default bounds (a signed one uniform, a part that may be zero zero
half the time), and kept where synth accepts the design.
"""

from __future__ import annotations

import math

from hypothesis import assume
from hypothesis import strategies as st

from synth.errors import SynthError
from synth.mechanisms import get


def log_uniform(lo: float, hi: float) -> st.SearchStrategy[float]:
    return st.floats(math.log10(lo), math.log10(hi)).map(lambda e: 10.0**e)


def excess() -> st.SearchStrategy[float]:
    """How much longer than its limit a part is: exactly, barely (1e-12), or plenty (1e3)."""
    return st.one_of(st.just(0.0), log_uniform(1e-12, 1e3))


def unit_fraction() -> st.SearchStrategy[float]:
    """A number in (0, 1) near either end as often as in the middle."""
    return st.one_of(
        log_uniform(1e-6, 0.5), log_uniform(1e-9, 0.5).map(lambda x: 1.0 - x), st.floats(0.05, 0.95)
    )


def where(lo: float, hi: float, t: float) -> float:
    return lo + t * (hi - lo)


@st.composite
def offset_slider_crank(draw):
    e = draw(st.one_of(st.just(0.0), log_uniform(1e-3, 1e3))) * draw(st.sampled_from([1, -1]))
    return {"crank": 1.0, "coupler": (1 + abs(e)) * (1 + draw(excess())), "offset": e}


@st.composite
def crank_shaper(draw):
    k = draw(unit_fraction())
    lever = (1 + k) * (1 + draw(excess()))
    p = {"crank": k, "pivot_distance": 1.0, "lever": lever}
    if draw(st.booleans()):
        cos_max = math.sqrt((1 - k) * (1 + k))
        h = lever * cos_max * draw(st.one_of(st.just(1.0), st.floats(0.5, 1.5)))
        reach = max(abs(h - lever), abs(h - lever * cos_max))
        link = max(reach * (1 + draw(excess())), lever * draw(log_uniform(1e-3, 1e3)))
        p.update(ram_link=link, ram_height=h)
    return p


@st.composite
def whitworth(draw):
    lever = draw(log_uniform(1e-3, 1e3))
    return {
        "crank": 1.0,
        "pivot_distance": draw(unit_fraction()),
        "lever": lever,
        "connecting_rod": lever * (1 + draw(log_uniform(1e-9, 1e3))),
    }


def _coupler_range(short: float, a: float, b: float) -> tuple[float, float]:
    """The coupler range that keeps ``short`` the shortest link and the linkage Grashof, with
    the other two links a and b (crank-rocker: short = crank; drag-link: short = ground)."""
    return short + abs(a - b), a + b - short


@st.composite
def crank_rocker_slider(draw):
    r1, r4 = (1 + draw(log_uniform(1e-6, 1e3)) for _ in range(2))
    lo, hi = _coupler_range(1.0, r1, r4)
    r3 = where(lo, hi, draw(st.one_of(st.sampled_from([0.0, 1.0]), st.floats(0, 1))))
    p = {
        "ground": r1,
        "crank": 1.0,
        "coupler": r3,
        "rocker": r4,
        "rocker_arm": r4 * draw(log_uniform(1e-3, 1e3)),
    }
    if draw(st.booleans()):
        p["connecting_rod"] = p["rocker_arm"] * (1 + draw(excess()))  # ≥ the largest reach
    return p


@st.composite
def drag_link_slider(draw):
    r2, r4 = (1 + draw(log_uniform(1e-6, 1e3)) for _ in range(2))
    lo, hi = _coupler_range(1.0, r2, r4)
    r3 = where(lo, hi, draw(st.one_of(st.sampled_from([0.0, 1.0]), st.floats(0, 1))))
    r5 = draw(log_uniform(1e-3, 1e3))
    return {
        "ground": 1.0,
        "crank": r2,
        "coupler": r3,
        "follower": r4,
        "follower_arm": r5,
        "connecting_rod": r5 * (1 + draw(log_uniform(1e-9, 1e3))),
    }


def scotch_yoke():
    return st.just({"crank": 1.0})


SHAPES = {
    f.__name__: f
    for f in (
        scotch_yoke,
        offset_slider_crank,
        crank_shaper,
        whitworth,
        crank_rocker_slider,
        drag_link_slider,
    )
}


@st.composite
def from_registry(draw, mtype: str):
    """A design of a type without its own strategy (see the module's docstring)."""
    m = get(mtype)
    p = {}
    for q in m.parameters:
        lo, hi = q.bounds
        if q.zero_means and draw(st.booleans()):
            p[q.name] = 0.0
        else:
            p[q.name] = draw(st.floats(-hi, hi) if q.signed else log_uniform(lo, hi))
    try:
        m.complete(p)
    except SynthError:
        assume(False)
    return p


@st.composite
def design(draw, mtype: str):
    """A design of ``mtype`` at a scale of 1e-6 … 1e6."""
    shape = draw(SHAPES[mtype]() if mtype in SHAPES else from_registry(mtype))
    scale = draw(log_uniform(1e-6, 1e6))
    return {k: v * scale for k, v in shape.items()}
