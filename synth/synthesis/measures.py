"""What the certified search (``certify``) bounds, per objective's terms: a design's measure
at points of a variant's space (floats, many at once) and a rigorous lower bound of it over
boxes of the space (``numerics.interval``'s centred enclosures, compiled).

Both come from the type's position s(θ, u) and its θ-derivatives (``Kinematics``):

- ``acceleration`` (``min_peak_acceleration``): max over the turn of |s″|. For any angles
  θⱼ, every u in a box U has max_θ |s″| ≥ maxⱼ inf_U |s″(θⱼ, ·)|; the angles are the centre's
  peaks, where the bound is tight;
- ``speed`` (``uniform_cutting_speed``): max |s′| over the middle 80% of the working stroke
  (by travel) times that window's crank travel over 80% of the stroke. Over a box, each
  angle where the window starts or ends, and each dead centre, is enclosed in an interval
  proved to hold it for every u (the sign of s′ or of s − level differs, for every u, at
  its ends: the design's motion has one dead centre of each kind, so that root is the
  one); the stroke's and the levels' intervals follow from s over the dead centres'. Every
  angle θⱼ between the window's start interval and its end interval is in every window, and
  G(u) = |s′(θⱼ, u)| (θb − θa)/(0.8 S) is at most the measure. The bound is the better of
  G at the box's centre less its gradient's enclosure over the box times the half-widths
  (the angles moving by the implicit function theorem over their proved intervals: O(h²)
  at a smooth optimum), and the factors' own bounds (inf_U |s′(θⱼ, ·)|, the gap between the
  window's intervals, the top of the stroke's: O(h), better on a wide box). A box where a
  proof fails gets the bound 0 (it is cut further).

A design that is not one (no two dead centres on the grid) measures ∞.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..analysis.quality import CUT
from .stroke import GRID, PEAKS, TAU, Kinematics, enclose, prove, strokes


def least_abs(bounds: tuple[np.ndarray, np.ndarray]) -> np.ndarray:
    """inf |f| of each enclosure (0 where it may pass 0; NaN: 0)."""
    out: np.ndarray = np.fmax(np.fmax(bounds[0], -bounds[1]), 0.0)
    return out


def local_peaks(
    v: np.ndarray, count: int, where: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """The grid indices of each row's ``count`` largest local maxima of v ≥ 0 (rows), among
    ``where``'s (cyclic neighbours), and whether each is one (a row may have fewer)."""
    local = (v >= np.roll(v, 1, axis=1)) & (v >= np.roll(v, -1, axis=1))
    if where is not None:
        local &= where
    order = np.argsort(-np.where(local, v, -1.0), axis=1, kind="stable")[:, :count]
    return order, np.take_along_axis(local, order, axis=1)


class Acceleration:
    """The peak |s″| over the turn (``min_peak_acceleration``)."""

    @staticmethod
    def measure(kin: Kinematics, points: np.ndarray, k: np.ndarray) -> tuple[Any, Any]:
        """The measure at each point, and its ``PEAKS`` largest peaks' angles (rows)."""
        grid = np.tile(np.arange(GRID) * (TAU / GRID), (len(points), 1))
        v = np.abs(kin.at(grid, points, k)[2])
        theta = np.take_along_axis(grid, local_peaks(v, PEAKS)[0], axis=1)
        theta = kin.newton(theta, points, k, 3)
        w = np.abs(kin.at(theta, points, k)[2])
        return np.maximum(w.max(axis=1), v.max(axis=1)), theta

    @staticmethod
    def lower(kin: Kinematics, lo: Any, hi: Any, angles: Any, k: np.ndarray) -> np.ndarray:
        """maxⱼ inf_U |s″(θⱼ, ·)| of each box, at its centre's peak angles."""
        out: np.ndarray = least_abs(enclose(kin.acceleration, (angles, angles), lo, hi, k))
        return out.max(axis=1)  # type: ignore[no-any-return]


class Speed:
    """The speed fluctuation over the middle of the working stroke (``uniform_cutting_speed``):
    max |s′| over the window where the slider has run ``CUT`` to 1 − ``CUT`` of the working
    stroke's travel, times the window's crank travel over (1 − 2 ``CUT``) × the stroke."""

    @staticmethod
    def measure(kin: Kinematics, points: np.ndarray, k: np.ndarray) -> tuple[Any, Any]:
        """The measure at each point, and what its bound takes (``lower``)."""
        info = strokes(kin, points, k, (CUT, 1 - CUT))
        v, unwrapped, window = info["rows"][1], info["unwrapped"], info["window"]
        a, b, s0, s1 = info["ends"][:, :1], info["ends"][:, 1:], info["s0"], info["s1"]
        speed = np.abs(v)
        idx, real = local_peaks(speed, PEAKS, window)
        peaks = kin.newton(np.take_along_axis(unwrapped, idx, axis=1), points, k, 2)
        real &= (peaks > a) & (peaks < b)
        vp = np.where(real, np.abs(kin.at(peaks, points, k)[1]), 0.0)
        ve = np.abs(kin.at(info["ends"], points, k)[1])
        with np.errstate(all="ignore"):
            value = np.maximum(vp.max(axis=1), ve.max(axis=1)) * (b - a)[:, 0]
            value /= (1 - 2 * CUT) * np.abs(s1 - s0)
        value[~(info["ok"] & np.isfinite(value))] = math.inf
        info["peaks"] = np.where(real, peaks, np.nan)
        return value, info

    @staticmethod
    def lower(kin: Kinematics, lo: Any, hi: Any, info: Any, k: np.ndarray) -> np.ndarray:
        """The bound of each box from its centre's dead centres, window ends and peaks (see
        the module's docstring); 0 where a proof fails."""
        c, half = 0.5 * (lo + hi), 0.5 * (hi - lo)
        proved, dead, ends, stroke = prove(kin, lo, hi, info, k)
        at_c, _, ends_c, stroke_c = prove(kin, c, c, info, k)  # tight, about the centre's own
        core = ends[1][:, :1], ends[0][:, 1:]  # in every window of the box
        peaks = info["peaks"]
        inner = np.where((peaks > core[0]) & (peaks < core[1]), peaks, core[0])
        angles = np.hstack([core[0], core[1], inner])
        n, per = angles.shape
        order = np.where(info["slow_up"][:, None], [[0, 1]], [[1, 0]])  # start, end

        def enclosed(ivals: list[tuple[np.ndarray, np.ndarray]], a: Any, b: Any) -> Any:
            """The gradient of the window's bound over the angles' intervals and the box."""
            lo_in = [angles.reshape(-1, 1)] + [np.repeat(x[0], per, axis=0) for x in ivals]
            hi_in = [angles.reshape(-1, 1)] + [np.repeat(x[1], per, axis=0) for x in ivals]
            return kin.window([*lo_in, np.repeat(a, per, 0), k], [*hi_in, np.repeat(b, per, 0), k])

        def parts(d: Any, e: Any) -> list[tuple[np.ndarray, np.ndarray]]:
            start = [np.take_along_axis(x, order, 1) for x in d]
            return [(e[0][:, i : i + 1], e[1][:, i : i + 1]) for i in (0, 1)] + [
                (start[0][:, i : i + 1], start[1][:, i : i + 1]) for i in (0, 1)
            ]

        slope = enclosed(parts(dead, ends), lo, hi)
        # G at the centre, from intervals about its own angles (a few 1e-12 wide)
        speed = least_abs(enclose(kin.velocity, (angles, angles), c, c, k))
        travel = ends_c[0][:, 1:] - ends_c[1][:, :1]
        with np.errstate(all="ignore"):
            g = speed * travel / ((1 - 2 * CUT) * stroke_c[:, None]) * (1 - 1e-14)
        steep = np.maximum(np.abs(slope.lo[0]), np.abs(slope.hi[0])).reshape(n, per, -1)
        with np.errstate(all="ignore"):
            out = g - np.sum(steep * half[:, None, :], axis=2)
        out = np.where(np.isfinite(out), out, 0.0).max(axis=1)
        # on a wide box the gradient's enclosure is loose: each factor's own bound may do
        # better (the least speed, the least travel, the greatest stroke; first order)
        least = least_abs(enclose(kin.velocity, (angles, angles), lo, hi, k)).max(axis=1)
        with np.errstate(all="ignore"):
            plain = least * (core[1] - core[0])[:, 0] / ((1 - 2 * CUT) * stroke) * (1 - 1e-14)
        out = np.maximum(out, np.where(np.isfinite(plain), plain, 0.0))
        return np.where(proved & at_c & (core[1][:, 0] > core[0][:, 0]), np.maximum(out, 0), 0.0)
