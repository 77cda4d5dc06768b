"""How a design runs beyond its targets: how evenly the slider cuts, how hard each stroke
accelerates it, how its time ratio, stroke and transmission move with its lengths, and how
much space its frame must hold.

Everything is exact to rounding, with no sampling and no finite differences:

- the extremes of the slider's velocity and acceleration are the stationary points of s′ and
  s″ (the model's ``motion`` kind), found as the dead centres are (``roots``);
- the middle 80% of the working stroke ends where s reaches 10% and 90% of its travel:
  bracketed roots of s − level, polished by the same safeguarded Newton iteration;
- the sensitivities follow from the conditions that fix the analysis's angles, by the
  implicit function theorem: a dead centre θ* has s′(θ*, p) = 0, so dθ*/dp = −∂s′/∂p / s″;
  the stroke and the transmission extremes are values at stationary points, so their
  derivatives are the partial derivatives there (the angle's own motion drops out).
  CasADi differentiates the type's expressions with respect to the parameters;
- the envelope's sides are extremes of the pins' moving coordinates: their stationary points
  (the model's ``envelope`` kind), with the fixed pivots.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import cast

import numpy as np

from ..mechanisms import Mechanism
from ..results import (
    Envelope,
    Motion,
    PeakAcceleration,
    Sensitivities,
    SpeedFluctuation,
    Tolerance,
)
from .model import Model, model
from .roots import TWO_PI, rtsafe, stationary_points

CUT = 0.1  # a tool cuts over the middle 80% of the working stroke: 10% run-in, 10% run-out
MIDDLE = f"middle {1 - 2 * CUT:.0%} of the working stroke"  # where a tool cuts, in words


class Strokes:
    """The working stroke of an analysed design: it starts at crank angle ``start`` (radians)
    and lasts ``working`` radians (the return stroke ``back``), while the slider goes from
    ``s0`` to ``s1``."""

    def __init__(self, t_min: float, t_max: float, s_min: float, s_max: float) -> None:
        up = (t_max - t_min) % TWO_PI  # crank travel while the slider goes min -> max
        down = TWO_PI - up
        slow_up = up >= down
        self.start, self.working, self.back = (t_min, up, down) if slow_up else (t_max, down, up)
        self.s0, self.s1 = (s_min, s_max) if slow_up else (s_max, s_min)
        self.t_min, self.t_max, self.slow_up = t_min, t_max, slow_up
        self.stroke = s_max - s_min


def reached(f: Model, pv: np.ndarray, st: Strokes, fractions: np.ndarray) -> np.ndarray:
    """The crank angles (radians, from ``st.start`` on) where the working stroke has run each
    of ``fractions`` (0 < each < 1) of its travel: roots of s − level, bracketed by the
    stroke's dead centres, where s is monotonic."""

    def fd(t: np.ndarray) -> np.ndarray:
        g, g1, _ = f(t, pv)
        return np.array([g[0] - levels, g1[0]])

    levels = st.s0 + fractions * (st.s1 - st.s0)
    k = fractions.size
    lo, hi = np.full(k, st.start), np.full(k, st.start + st.working)
    return rtsafe(fd, lo, hi, st.s0 - levels, st.s1 - levels, np.full(k, abs(st.stroke)))


def _inside(x: np.ndarray, start: float, length: float) -> np.ndarray:
    """Which angles x lie in the crank interval [start, start + length) (radians)."""
    return (x - start) % TWO_PI < length


@dataclass(frozen=True)
class MotionTerms:
    """The values whose largest is each motion measure: the speed fluctuation over the whole
    working stroke and over its middle (each |s′| that may peak there, scaled by the window's
    crank travel over its travel), and the acceleration over each stroke (each |s″| that may
    peak there, over the stroke). The measures are their maxima; an optimiser bounds each.
    With ``gradient``, ``*_dp`` hold each term's derivatives in the parameters (rows: terms,
    columns: the type's parameters), exact as the sensitivities are: the envelope theorem at a
    stationary point, the implicit function theorem for a dead centre or a window's end."""

    whole: np.ndarray
    middle: np.ndarray
    working: np.ndarray
    returning: np.ndarray
    working_at: np.ndarray  # the crank angle of each acceleration term (radians)
    returning_at: np.ndarray
    middle_dp: np.ndarray | None = None
    working_dp: np.ndarray | None = None
    returning_dp: np.ndarray | None = None


def motion_terms(
    m: Mechanism,
    variant: frozenset[str],
    f: Model,
    pv: np.ndarray,
    st: Strokes,
    gradient: bool = False,
) -> MotionTerms:
    fm = model(m, variant, "motion")
    rows, x, values = stationary_points(fm, pv)
    v_at, a_at = x[rows == 0], x[rows == 1]  # where |s′| and |s″| may peak

    ends = reached(f, pv, st, np.array([CUT, 1 - CUT]))  # the middle of the working stroke
    middle = ends[1] - ends[0]
    dead = np.array([st.start, st.start + st.working])  # the working stroke's dead centres
    v_in, a_work, a_ret = (
        _inside(v_at, ends[0], middle),
        _inside(a_at, st.start, st.working),
        _inside(a_at, st.start + st.working, TWO_PI - st.working),
    )
    # s′ at the window's peaks and ends; s″ at the strokes' peaks and the dead centres
    _, s1_ends, s2_ends = (g[0] for g in f(ends, pv))
    (_, a_d), (_, s3_dead), _ = fm(dead, pv)
    v = np.concatenate([values[rows == 0][v_in], s1_ends])
    a_w, a_r = values[rows == 1][a_work], values[rows == 1][a_ret]
    window = middle / ((1 - 2 * CUT) * st.stroke)
    out = MotionTerms(
        whole=np.append(np.abs(values[rows == 0][_inside(v_at, st.start, st.working)]), 0.0)
        * (st.working / st.stroke),
        middle=np.abs(v) * window,
        working=np.abs(np.concatenate([a_w, a_d])) / st.stroke,
        returning=np.abs(np.concatenate([a_r, a_d])) / st.stroke,
        working_at=np.concatenate([a_at[a_work], dead]),
        returning_at=np.concatenate([a_at[a_ret], dead]),
    )
    if not gradient:
        return out
    # the dead centres: s′(θd, p) = 0, so dθd/dp = −∂s′/∂p / s″; s there moves by ∂s/∂p
    g_dead, _, g2_dead = f(dead, pv)
    nr = g_dead.shape[0]
    kd = f.dp(np.concatenate([dead, ends]), pv)  # (angle, [rows; θ-derivatives], parameter)
    dt_dead = -kd[:2, nr] / g2_dead[0][:, None]
    ds0, ds1 = kd[0, 0], kd[1, 0]  # s at the working stroke's start and end
    d_stroke = (ds1 - ds0) * np.sign(st.s1 - st.s0)
    # the window's ends: s(θe, p) = s0 + c (s1 − s0), so dθe/dp = (dlevel − ∂s/∂p) / s′
    d_level = ds0[None, :] + np.array([CUT, 1 - CUT])[:, None] * (ds1 - ds0)[None, :]
    dt_ends = (d_level - kd[2:, 0]) / s1_ends[:, None]
    d_window = (dt_ends[1] - dt_ends[0]) / (
        (1 - 2 * CUT) * st.stroke
    ) - window * d_stroke / st.stroke
    # ∂s′/∂p and ∂s″/∂p at the peaks (the envelope theorem) and at the dead centres
    peaks = np.concatenate([v_at[v_in], a_at[a_work], a_at[a_ret], dead])
    mp = fm.dp(peaks, pv)
    n_v, n_w, n_r = (int(np.count_nonzero(k)) for k in (v_in, a_work, a_ret))
    dv = np.concatenate([mp[:n_v, 0], kd[2:, nr] + s2_ends[:, None] * dt_ends])
    middle_dp = np.sign(v)[:, None] * dv * window + np.abs(v)[:, None] * d_window[None, :]
    da_dead = mp[-2:, 1] + s3_dead[:, None] * dt_dead

    def accel_dp(da_in: np.ndarray, a_in: np.ndarray) -> np.ndarray:
        """d(|s″| / stroke) at the stroke's peaks and at the dead centres."""
        a = np.concatenate([a_in, a_d])
        da = np.concatenate([da_in, da_dead])
        return cast(
            np.ndarray,
            (np.sign(a)[:, None] * da - np.abs(a)[:, None] * d_stroke[None, :] / st.stroke)
            / st.stroke,
        )

    working_dp = accel_dp(mp[n_v : n_v + n_w, 1], a_w)
    returning_dp = accel_dp(mp[n_v + n_w : n_v + n_w + n_r, 1], a_r)
    return replace(out, middle_dp=middle_dp, working_dp=working_dp, returning_dp=returning_dp)


def motion(m: Mechanism, variant: frozenset[str], f: Model, pv: np.ndarray, st: Strokes) -> Motion:
    """Speed fluctuation over the working stroke and peak accelerations, at constant ω."""
    t = motion_terms(m, variant, f, pv, st)
    k, j = int(np.argmax(t.working)), int(np.argmax(t.returning))
    at = np.degrees([t.working_at[k] % TWO_PI, t.returning_at[j] % TWO_PI])
    return Motion(
        SpeedFluctuation(float(t.whole.max()), float(t.middle.max())),
        PeakAcceleration(float(t.working[k]), float(t.returning[j]), float(at[0]), float(at[1])),
    )


def sensitivities(
    m: Mechanism,
    variant: frozenset[str],
    f: Model,
    pv: np.ndarray,
    st: Strokes,
    worst: tuple[int, float, float] | None,
    tolerance: Tolerance | None,
) -> Sensitivities:
    """d(time ratio, stroke, minimum transmission angle)/d(each parameter of the design).

    ``worst`` is the limiting joint's (row, crank angle, cos μ) at its transmission extreme,
    None where the transmission is 90° throughout (no pin-jointed output, slot drives)."""
    at = [st.t_min, st.t_max] + ([worst[1]] if worst else [])
    d = f.dp(np.array(at), pv)  # (angle, [rows; their θ-derivatives], parameter)
    nr = d.shape[1] // 2
    s2 = f(np.array(at[:2]), pv)[2][0]
    dt_min, dt_max = -d[0, nr] / s2[0], -d[1, nr] / s2[1]  # s′(θ*, p) = 0
    d_working = (dt_max - dt_min) if st.slow_up else (dt_min - dt_max)
    quick = TWO_PI - st.working
    d_ratio = d_working * TWO_PI / quick**2  # TR = W / (2π − W)
    d_stroke = d[1, 0] - d[0, 0]
    d_mu: np.ndarray | None = np.zeros_like(d_stroke)
    if worst is not None:
        row, _, c = worst
        d_mu = None if abs(c) >= 1 else -math.copysign(1, c) / math.sqrt(1 - c * c) * d[2, row]
        d_mu = None if d_mu is None else np.degrees(d_mu)
    names = [q.name for q in m.parameters if q.name not in variant]
    keep = [i for i, q in enumerate(m.parameters) if q.name not in variant]

    def per(dv: np.ndarray) -> dict[str, float]:
        return {n: float(dv[i]) for n, i in zip(names, keep, strict=True)}

    deviation = None
    if tolerance is not None:
        tol = np.array([tolerance.of(pv[i]) for i in keep])

        def worst_case(dv: np.ndarray | None) -> float | None:
            return None if dv is None else float(np.abs(dv[keep]) @ tol)

        deviation = {
            "time_ratio": worst_case(d_ratio),
            "stroke": worst_case(d_stroke),
            "min_transmission_angle_deg": worst_case(d_mu),
        }
    mu = None if d_mu is None else per(d_mu)
    return Sensitivities(per(d_ratio), per(d_stroke), mu, tolerance, deviation)


def envelope(
    m: Mechanism, variant: frozenset[str], p: dict[str, float], pv: np.ndarray
) -> Envelope:
    """The bounding box of every pivot and every pin's path over a revolution."""
    moving = model(m, variant, "envelope")
    rows, _, values = stationary_points(moving, pv)
    axes = moving.axes[rows]
    at_zero = model(m, variant, "pins")(np.zeros(1), pv)[0][:, 0]  # the fixed pivots too
    x = np.concatenate([values[axes == 0], at_zero[0::2]])
    y = np.concatenate([values[axes == 1], at_zero[1::2]])
    lo, hi = (float(x.min()), float(x.max())), (float(y.min()), float(y.max()))
    return Envelope(lo, hi, lo[1] - lo[0], hi[1] - hi[0], float(m.size(p)))
