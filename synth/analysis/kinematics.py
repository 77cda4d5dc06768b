"""Analysis of one design over a crank revolution, generic over the registry.

Dead centres and transmission extremes are the stationary points of the type's compiled
model (``model``), found to machine precision (``roots``); the motion's extremes and the
sensitivities to the lengths come from the same machinery (``quality``), only when asked.
Nothing here uses a type's closed forms.
"""

from __future__ import annotations

import math
from collections.abc import Collection, Mapping, Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from ..errors import InvalidDesign, InvalidParameters, SynthError
from ..load import Load
from ..mechanisms import Mechanism, get
from ..mechanisms.fourbar.geometry import grashof_class
from ..mechanisms.registry import GROUND, RAM
from ..requests import argument, keyword
from ..results import (
    NEAR_DEAD_POINT_DEG,
    NEAR_LIMIT,
    Analysis,
    Conditioning,
    Curves,
    DeadCentres,
    Extreme,
    Joint,
    PinPath,
    Stroke,
    Tolerance,
    Transmission,
)
from ..targets import transmission_deg
from . import loads, quality
from .model import Model, model
from .request import AnalysisRequest, asked
from .roots import Points, stationary_points, stationary_points_many


def run(r: AnalysisRequest) -> Analysis:
    """Analyse one design over a crank revolution (the semantics of POST /v1/analyze).

    Curves are computed only when asked: at exactly ``crank_angles_deg``, or at ``samples``
    evenly spaced angles (0° included, 360° not). So are ``include``'s ``"motion"`` (speed
    fluctuation and peak accelerations), ``"sensitivities"`` (to every length; also with a
    ``tolerance``, which adds the worst-case deviations), ``"envelope"`` (the box the frame
    must hold) and ``"pins"`` (the curves' ``pins``: every pin of the type's drawing at the
    curves' angles, as ``joints`` gives them; only with curves). A ``load`` adds ``loads``
    (the crank torque, power and flywheel, the joints' and the guide's largest forces) and,
    with curves, the torque curve (and with ``"forces"`` the forces'); its crank speed is the
    curves' too (``crank_speed``, rad/s, is 1 by default).

    >>> a = analyze("whitworth", {"crank": 75, "pivot_distance": 50, "lever": 150,
    ...                           "connecting_rod": 200})
    >>> round(a.time_ratio, 5), round(a.stroke, 9)
    (2.73524, 300.0)
    """
    return _analysis(
        _prepared(get(r.mechanism), r.design),
        r.omega,
        r.crank_acceleration,
        r.angles,
        r.include,
        r.tolerance,
        r.load,
    )


analyze = keyword(AnalysisRequest, run, "analyze")


def analyze_many(
    mechanism: str,
    designs: Sequence[Mapping[str, float]],
    *,
    include: Collection[str] = (),
    tolerance: Tolerance | None = None,
) -> list[Analysis | SynthError]:
    """``analyze`` of several designs of one type (no curves): each one's analysis, or the
    SynthError that refuses it. The same analyses to the bit, for less: the dead centres and
    transmission extremes of the designs of one variant are found in shared compiled calls
    (``roots.stationary_points_many``), which a front's verification and a sweep repeat."""
    argument(AnalysisRequest, "include").check(include)
    asked(mechanism, include, None, None)
    m = get(mechanism)
    out: list[Any] = [None] * len(designs)
    variants: dict[frozenset[str], list[tuple[int, dict[str, float]]]] = {}
    for i, params in enumerate(designs):
        try:
            p = m.complete(params)
        except SynthError as e:
            out[i] = e
            continue
        variants.setdefault(m.variant(p), []).append((i, p))
    for variant, members in variants.items():
        f = model(m, variant)
        pvs = np.array([[p[n] for n in m.names] for _, p in members], dtype=float)
        for (i, p), pv, found in zip(members, pvs, stationary_points_many(f, pvs), strict=True):
            try:
                found = stationary_points(f, pv) if found is None else found
                d = Prepared(m, p, variant, f, pv, found)
                out[i] = _analysis(d, 1.0, 0.0, None, include, tolerance)
            except SynthError as e:
                out[i] = e
    return out


def _analysis(
    d: Prepared,
    crank_speed: float,
    crank_acceleration: float,
    deg: np.ndarray | None,
    include: Collection[str],
    tolerance: Tolerance | None,
    load: Load | None = None,
) -> Analysis:
    """``analyze``'s answer for a prepared design."""
    m, p, variant, f, pv = d.mechanism, d.params, d.variant, d.model, d.pv
    rows, theta, values = d.points
    summary = _summary(m, p, f, rows, theta, values)
    loaded = None
    if load is not None:
        st = quality.Strokes(*slider_extremes(rows, theta, values))
        upright_load = upright(m, variant, pv, st, load)
        summary["loads"], loaded = loads.loads(m, variant, f, pv, d.points, st, upright_load)
    if deg is not None:
        curves = _curves(f, pv, crank_speed, crank_acceleration, deg)
        if "pins" in include:
            xy = _pins(model(m, variant, "pins"), pv, deg)
            curves = replace(curves, pins={k: PinPath(x, y) for k, (x, y) in xy.items()})
        if loaded is not None:
            at = loaded(np.radians(deg))
            torque = at.pop("torque")
            curves = replace(curves, torque=torque, forces=at if "forces" in include else None)
        summary["curves"] = curves
    if "envelope" in include:
        summary["envelope"] = quality.envelope(m, variant, p, pv)
    if {"motion", "sensitivities"} & set(include) or tolerance is not None:
        st = quality.Strokes(*slider_extremes(rows, theta, values))
        if "motion" in include:
            summary["motion"] = quality.motion(m, variant, f, pv, st)
        if "sensitivities" in include or tolerance is not None:
            worst = _worst_joint(rows, theta, values)
            summary["sensitivities"] = quality.sensitivities(
                m, variant, f, pv, st, worst, tolerance
            )
    return Analysis(**summary)


@dataclass(frozen=True)
class Prepared:
    """A design ready for its analysis: its type, completed parameters and variant, the
    variant's compiled model, the parameter vector, and the stationary points of its rows
    (the dead centres and transmission extremes)."""

    mechanism: Mechanism
    params: dict[str, float]
    variant: frozenset[str]
    model: Model
    pv: np.ndarray
    points: Points


def prepared(mechanism: str, params: Mapping[str, float], reversals: int | None = None) -> Prepared:
    """The design ``params`` of type ``mechanism``, completed and prepared (``reversals``:
    ``roots.stationary_points``')."""
    m = get(mechanism)
    return _prepared(m, m.complete(params), reversals)


def _prepared(m: Mechanism, p: dict[str, float], reversals: int | None = None) -> Prepared:
    """A completed design ``p`` prepared."""
    variant = m.variant(p)
    f = model(m, variant)
    pv = np.array([p[n] for n in m.names], dtype=float)
    return Prepared(m, p, variant, f, pv, stationary_points(f, pv, reversals=reversals))


def slider_extremes(
    rows: np.ndarray, theta: np.ndarray, values: np.ndarray
) -> tuple[float, float, float, float]:
    """The slider's extremes: crank angles (radians) and positions (t_min, t_max, s_min, s_max)."""
    on_s = rows == 0
    s_theta, s_val = theta[on_s], values[on_s]
    i_max, i_min = s_val.argmax(), s_val.argmin()
    return float(s_theta[i_min]), float(s_theta[i_max]), float(s_val[i_min]), float(s_val[i_max])


def _worst_joint(
    rows: np.ndarray, theta: np.ndarray, values: np.ndarray
) -> tuple[int, float, float] | None:
    """(row, crank angle, cos μ) where the transmission is worst, None without joints."""
    joint = rows > 0
    if not np.any(joint):
        return None
    k = np.nonzero(joint)[0][np.argmax(np.abs(values[joint]))]
    return int(rows[k]), float(theta[k]), float(values[k])


def joints(
    mechanism: str, params: Mapping[str, float], crank_angles_deg: Sequence[float]
) -> dict[str, np.ndarray]:
    """The pin positions at each crank angle, {pin: array of (x, y)}, for drawings; the pins
    and the frame are named in the type's docstring (``synth.mechanisms.get(t).description``).

    >>> j = joints("drag_link_slider", {"ground": 0.1, "crank": 0.225, "coupler": 0.2504,
    ...            "follower": 0.275, "follower_arm": 0.15, "connecting_rod": 0.3}, [90.0])
    >>> sorted(j), j["A"].round(9).tolist()
    (['A', 'B', 'C', 'D', 'O2', 'O4'], [[0.0, 0.225]])
    """
    m = get(mechanism)
    if m.joints is None:
        raise InvalidParameters(f"{mechanism} has no drawing yet", ("mechanism",))
    p = m.complete(params)
    deg = np.asarray(crank_angles_deg, dtype=float).ravel()
    if deg.size == 0:
        return {}
    pv = np.array([p[n] for n in m.names], dtype=float)
    xy = _pins(model(m, m.variant(p), "pins"), pv, deg)
    return {k: np.column_stack(v) for k, v in xy.items()}


def upright(
    m: Mechanism, variant: frozenset[str], pv: np.ndarray, st: quality.Strokes, load: Load
) -> Load:
    """``load`` with its gravity in the design's drawing frame (``Load.drawn``): its working
    stroke along the type's path, the way the slider goes from ``st.s0`` to ``st.s1``; up,
    the path's normal pointing from the crank's pivot to the ram's pin."""
    if load.ram_incline_deg is None:
        return load
    p = dict(zip(m.names, pv.tolist(), strict=True))
    assert m.frame is not None  # a type that carries loads
    frame = m.frame(variant)
    ux, uy = (float(c) for c in frame.path(p))
    way = math.copysign(1.0, st.s1 - st.s0)
    crank = next(a for a, b, c in frame.pins if (b, c) == (frame.bodies[0][0], GROUND))
    ram = [a for a, *joined in frame.pins if RAM in joined] + [
        a for a, _, slotted, _ in frame.slots if slotted == RAM
    ]
    xy = _pins(model(m, variant, "pins"), pv, np.degrees([st.start]))
    side = ux * (xy[ram[0]][1][0] - xy[crank][1][0]) - uy * (xy[ram[0]][0][0] - xy[crank][0][0])
    return load.drawn((way * ux, way * uy), (-uy, ux) if side >= 0 else (uy, -ux))


def _pins(f: Model, pv: np.ndarray, deg: np.ndarray) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Each pin's x and y at each crank angle (degrees), {pin: (x, y)}, from the compiled
    ``pins`` model ``f``; empty arrays for no angles."""
    if deg.size == 0:
        return {k: (np.empty(0), np.empty(0)) for k in f.names}
    g = f(np.radians(deg), pv)[0]
    return {k: (g[2 * i].copy(), g[2 * i + 1].copy()) for i, k in enumerate(f.names)}


def _summary(
    m: Mechanism,
    p: dict[str, float],
    f: Model,
    rows: np.ndarray,
    theta: np.ndarray,
    values: np.ndarray,
) -> dict[str, Any]:
    reversals = int(np.count_nonzero(rows == 0))
    if reversals < 2:
        raise InvalidDesign("the slider does not move: no dead centres found", (), "stroke")
    t_min, t_max, s_min, s_max = slider_extremes(rows, theta, values)
    st = quality.Strokes(t_min, t_max, s_min, s_max)
    if st.back < 1e-12:
        raise InvalidDesign(
            f"the slider's extremes fall at one crank angle ({math.degrees(t_max):.6g}°): the "
            "linkage passes a change point there and its assembly circuit switches, so the "
            "slider jumps",
            (),
            "change_point",
        )
    joints = []
    for j, name in enumerate(f.names, start=1):
        c = values[rows == j]
        lo, hi = float(c.min()), float(c.max())
        best = 0.0 if lo < 0 < hi else min(abs(lo), abs(hi))
        joints.append(Joint(name, transmission_deg(max(abs(lo), abs(hi))), transmission_deg(best)))
    mu_min = min((jt.min_deg for jt in joints), default=90.0)
    return {
        "type": m.type,
        "params": p,
        "time_ratio": st.working / st.back,
        "stroke": s_max - s_min,
        "extremes": DeadCentres(
            Extreme(s_min, math.degrees(t_min)),
            Extreme(s_max, math.degrees(t_max)),
        ),
        "working_stroke": Stroke(math.degrees(st.working), 1 if st.slow_up else -1),
        "return_stroke": Stroke(math.degrees(st.back), -1 if st.slow_up else 1),
        "transmission": Transmission(
            mu_min,
            max((jt.max_deg for jt in joints), default=90.0),
            tuple(joints),
        ),
        "grashof": grashof_class(*m.fourbar(p)) if m.fourbar else None,
        "reversals": reversals,
        "conditioning": conditioning(m, p, mu_min, reversals),
    }


def conditioning(m: Mechanism, p: dict[str, float], mu_deg: float, reversals: int) -> Conditioning:
    """Distance to a dead point and to the nearest validity limit, flagged when small."""
    scale = max(abs(v) for v in p.values())
    variant = m.variant(p)
    margins = [
        (min(float(t) for t in c.margin(p)) / scale, c.name)
        for c in m.conditions
        if c.applies(variant)
    ]
    margin, name = min(margins, default=(None, None))
    flags = []
    if mu_deg < NEAR_DEAD_POINT_DEG:
        flags.append("near_dead_point")
    if margin is not None and margin < NEAR_LIMIT:
        flags.append("near_validity_limit")
    if reversals > 2:
        flags.append("dithering")
    return Conditioning(mu_deg, margin, name, tuple(flags))


def _curves(f: Model, pv: np.ndarray, omega: float, alpha: float, deg: np.ndarray) -> Curves:
    if deg.size == 0:
        empty = np.empty(0)
        return Curves(deg, empty, empty, empty, empty)
    g, g1, g2 = f(np.radians(deg), pv)
    mu = np.degrees(np.arccos(np.minimum(1.0, np.abs(g[1:])))) if g.shape[0] > 1 else None
    return Curves(
        crank_angle_deg=deg,
        position=g[0],
        velocity=g1[0] * omega,
        acceleration=g2[0] * omega**2 + g1[0] * alpha,
        transmission_deg=np.min(mu, axis=0) if mu is not None else np.full(deg.size, 90.0),
    )
