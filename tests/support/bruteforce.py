"""Independent brute-force reference simulator for the six quick-return mechanism types.

This module is the INDEPENDENT reference that the project's analysis is tested against. It
shares no code with ``synth`` or ``api`` (and imports nothing from them): every type's geometry
is written directly from the model (the README's mechanism table) as plain circle/line
intersections in vector arithmetic, and none of the contract's closed forms ("facts") is used.
Extremes are found by forward simulation on an even grid of crank angles followed by
refinement: the derivative d/dtheta comes from complex-step differentiation
(``imag(f(theta + 1j*h)) / h`` with h = 1e-30, exact to rounding) and its sign changes between
grid neighbours are polished with ``scipy.optimize.brentq``.

Because of the complex step, the theta-dependent geometry uses only complex-analytic
operations (+, -, *, /, sqrt, cos, sin): no abs, arctan2, hypot, min or max of theta-dependent
values. Constant quantities (defaults, the rocker's mid-swing direction) are real.

API (theta in radians, numpy-vectorised):
    TYPES, complete(mtype, params), position(mtype, params, theta),
    transmission_cos(mtype, params, theta), simulate(mtype, params, n=20000)
"""

from __future__ import annotations

import functools
import math

import numpy as np
from scipy.optimize import brentq

TYPES = (
    "scotch_yoke",
    "offset_slider_crank",
    "crank_shaper",
    "whitworth",
    "crank_rocker_slider",
    "drag_link_slider",
)

_PARAMS = {
    "scotch_yoke": ("crank",),
    "offset_slider_crank": ("crank", "coupler", "offset"),
    "crank_shaper": ("crank", "pivot_distance", "lever", "ram_link", "ram_height"),
    "whitworth": ("crank", "pivot_distance", "lever", "connecting_rod"),
    "crank_rocker_slider": (
        "ground",
        "crank",
        "coupler",
        "rocker",
        "rocker_arm",
        "connecting_rod",
        "slider_height",
    ),
    "drag_link_slider": (
        "ground",
        "crank",
        "coupler",
        "follower",
        "follower_arm",
        "connecting_rod",
    ),
}
_H = 1e-30  # complex step
_XTOL = 1e-15  # brentq absolute tolerance on theta
_N_AUX = 20000  # grid used for the defaults (lever / rocker extremes)


# --------------------------------------------------------------------------- helpers
def _sqrt(x, scale2, what):
    """sqrt of a theta-dependent quantity; ValueError when its real part is negative.

    Round-off below 1e-12*scale2 is tolerated (clamped to 0, for designs exactly on a
    boundary)."""
    x = np.asarray(x)
    re = np.real(x)
    if np.any(np.isnan(re)):
        raise ValueError(f"cannot run: {what} is undefined")
    if np.any(re < -1e-12 * scale2):
        raise ValueError(f"cannot run: {what} (negative square root, min {re.min():.6g})")
    if np.any(re < 0):
        x = np.where(re < 0, x - re, x)
    return np.sqrt(x)


def _crank_pin(r2, theta):
    return r2 * np.cos(theta), r2 * np.sin(theta)


def _unit(vx, vy):
    n = np.sqrt(vx * vx + vy * vy)
    return vx / n, vy / n


def _fourbar(bx, by, o4x, o4y, r3, r4):
    """Pin D on circle(B, r3) and circle(O4, r4), to the LEFT of the directed line B->O4."""
    ux, uy = o4x - bx, o4y - by
    l2 = ux * ux + uy * uy
    k = (r3 * r3 - r4 * r4 + l2) / (2 * l2)  # along B->O4, in units of |BO4|
    # left, same units: Heron's product, not r3²/l2 − k², which cancels where the triangle
    # B, D, O4 is nearly flat (precision, not a new formula)
    bo4 = np.sqrt(l2)
    heron = (r3 + r4 + bo4) * (r3 + r4 - bo4) * (r3 - r4 + bo4) * (r4 - r3 + bo4)
    q = _sqrt(heron, (r3 + r4 + bo4) ** 4, "four-bar cannot be assembled") / (2 * l2)
    return bx + k * ux - q * uy, by + k * uy + q * ux


def _cos_between(ax, ay, bx, by):
    """Signed cosine of the angle between vectors a and b."""
    return (ax * bx + ay * by) / np.sqrt((ax * ax + ay * ay) * (bx * bx + by * by))


def d_dtheta(f, theta):
    """Complex-step derivative of a real-analytic f at real theta."""
    return np.imag(f(np.asarray(theta, dtype=float) + 1j * _H)) / _H


def _stationary(f, n):
    """Grid + refinement: returns (theta_grid, f_grid, roots, f_roots) where roots are the
    zeros of df/dtheta in [0, 2pi) (polished by brentq between grid neighbours)."""
    th = np.linspace(0.0, 2 * np.pi, n + 1)
    fg = np.real(f(th))
    dg = d_dtheta(f, th)
    if not np.all(np.isfinite(fg)) or not np.all(np.isfinite(dg)):
        raise ValueError("cannot run: non-finite value during the revolution")

    def g(t):
        return float(d_dtheta(f, np.array([t]))[0])

    roots = []
    # a grid point whose derivative is zero up to rounding is a root (θ = 0 and 2π are one
    # angle, and rounding may give their derivatives opposite signs)
    dg = np.where(np.abs(dg) <= 1e-15 * np.max(np.abs(dg)), 0.0, dg)
    for i in np.nonzero(dg[:-1] * dg[1:] <= 0)[0]:
        if dg[i] == 0:
            t = th[i]
        elif dg[i + 1] == 0:
            t = th[i + 1]
        else:
            t = brentq(g, th[i], th[i + 1], xtol=_XTOL, maxiter=200)
        roots.append(t % (2 * np.pi))
    roots = np.array(roots, dtype=float)
    froots = np.real(f(roots)) if roots.size else np.array([])
    return th, fg, roots, froots


# --------------------------------------------------------------------------- defaults
@functools.lru_cache(maxsize=256)
def _lever_psi_max(r2, d):
    """crank_shaper: the lever's extreme angle, maximising psi(theta) over the revolution."""

    def psi(t):  # B_x + d > 0 because crank < pivot_distance
        bx, by = _crank_pin(r2, t)
        return np.arctan(by / (bx + d))

    _, _, _, vals = _stationary(psi, _N_AUX)
    return float(vals.max())


@functools.lru_cache(maxsize=256)
def _rocker_swing(r1, r2, r3, r4):
    """crank_rocker_slider: (psi_lo, psi_hi), the rocker O4->D's extreme angles, lo < hi."""

    def rocker_dir(t):
        bx, by = _crank_pin(r2, t)
        dx, dy = _fourbar(bx, by, r1, 0.0, r3, r4)
        return _unit(dx - r1, dy)

    th = np.linspace(0.0, 2 * np.pi, _N_AUX + 1)
    ex, ey = rocker_dir(th)
    psi = np.unwrap(np.arctan2(ey, ex))
    if abs(psi[-1] - psi[0]) > np.pi or psi.max() - psi.min() >= np.pi:
        raise ValueError("cannot run: the rocker turns fully (not a crank-rocker)")
    ref = (psi.max() + psi.min()) / 2  # the swing (< pi) stays within +-pi/2 of ref
    cr, sr = math.cos(ref), math.sin(ref)

    def rel(t):  # psi - ref, complex-analytic
        ux, uy = rocker_dir(t)
        return np.arctan((cr * uy - sr * ux) / (cr * ux + sr * uy))

    _, _, _, vals = _stationary(rel, _N_AUX)
    return ref + float(vals.min()), ref + float(vals.max())


def complete(mtype: str, params: dict) -> dict:
    """params with the contract's derived defaults filled in (explicit values are kept)."""
    if mtype not in TYPES:
        raise ValueError(f"unknown mechanism type {mtype!r}")
    p = {k: float(v) for k, v in params.items()}
    if mtype == "crank_shaper":
        p.setdefault("ram_link", 0.0)
        if "ram_height" not in p:
            _check(mtype, {**p, "ram_height": 0.0})
            p["ram_height"] = p["lever"] * math.cos(_lever_psi_max(p["crank"], p["pivot_distance"]))
    elif mtype == "crank_rocker_slider":
        p.setdefault("connecting_rod", 0.0)
        if "slider_height" not in p:
            _check(mtype, {**p, "slider_height": 0.0})
            lo, hi = _rocker_swing(p["ground"], p["crank"], p["coupler"], p["rocker"])
            p["slider_height"] = p["rocker_arm"] * math.cos((hi - lo) / 2)
    return p


def _check(mtype, p):
    """Only what the plain geometry cannot detect by itself (NaNs are caught elsewhere)."""
    for k in _PARAMS[mtype]:
        if k not in p:
            raise ValueError(f"invalid: missing parameter {k!r}")
        if k != "offset" and not p[k] >= 0:
            raise ValueError(f"invalid: {k} = {p[k]} must be >= 0")
    if mtype == "crank_shaper":
        r2, d, L = p["crank"], p["pivot_distance"], p["lever"]
        if not r2 < d:
            raise ValueError(
                f"cannot run: crank {r2} >= pivot_distance {d} (the lever would turn fully)"
            )
        if not d + r2 <= L:
            raise ValueError(
                f"cannot run: block leaves the lever (pivot_distance + crank {d + r2} > lever {L})"
            )
    elif mtype == "whitworth":
        if not p["crank"] > p["pivot_distance"]:
            raise ValueError(
                f"cannot run: crank {p['crank']} <= pivot_distance "
                f"{p['pivot_distance']} (lever cannot turn fully)"
            )
    elif mtype in ("crank_rocker_slider", "drag_link_slider"):
        r1, r2, r3 = p["ground"], p["crank"], p["coupler"]
        r4 = p["rocker"] if mtype == "crank_rocker_slider" else p["follower"]
        # |B O4| sweeps [|r1 - r2|, r1 + r2]; the dyad reaches [|r3 - r4|, r3 + r4]
        if abs(r1 - r2) < abs(r3 - r4) or r1 + r2 > r3 + r4:
            raise ValueError(
                f"cannot run: four-bar cannot be assembled at every crank angle "
                f"(|BO4| in [{abs(r1 - r2):g}, {r1 + r2:g}], dyad reaches "
                f"[{abs(r3 - r4):g}, {r3 + r4:g}])"
            )


# --------------------------------------------------------------------------- geometry
# Each returns (s, {joint: signed cos of transmission angle}).


def _scotch_yoke(p, th):
    return p["crank"] * np.cos(th), {}


def _offset_slider_crank(p, th):
    r2, r3, e = p["crank"], p["coupler"], p["offset"]
    bx, by = _crank_pin(r2, th)
    dy = e - by  # slider C = (s, e)
    # factored, not r3² − dy²: a design on its limit has dy → r3 (precision, not a new formula)
    dx = _sqrt((r3 - dy) * (r3 + dy), r3 * r3, "coupler cannot reach the slider path")
    # path direction +x, normal +y
    return bx + dx, {"coupler-slider": dy / r3}


def _crank_shaper(p, th):
    r2, d, L, rod, h = (p["crank"], p["pivot_distance"], p["lever"], p["ram_link"], p["ram_height"])
    bx, by = _crank_pin(r2, th)
    ux, uy = _unit(bx + d, by)  # lever direction from O4
    px, py = -d + L * ux, L * uy  # lever tip P
    if rod == 0:
        return py, {}
    gap = (-d + h) - px  # ram path x = -d + h
    s = py + _sqrt(rod * rod - gap * gap, rod * rod, "ram_link cannot reach the ram path")
    return s, {"ram_link-ram": gap / rod}  # path +y, normal +x


def _whitworth(p, th):
    r2, d, L, rod = p["crank"], p["pivot_distance"], p["lever"], p["connecting_rod"]
    bx, by = _crank_pin(r2, th)
    ux, uy = _unit(bx + d, by)
    px, py = -d - L * ux, -L * uy  # output arm points the other way
    gap = -d - px  # ram path x = -d
    s = py + _sqrt(rod * rod - gap * gap, rod * rod, "connecting_rod cannot reach the ram path")
    return s, {"connecting_rod-ram": gap / rod}


def _crank_rocker_slider(p, th):
    r1, r2, r3, r4, r5, r6, h = (
        p["ground"],
        p["crank"],
        p["coupler"],
        p["rocker"],
        p["rocker_arm"],
        p["connecting_rod"],
        p["slider_height"],
    )
    lo, hi = _rocker_swing(r1, r2, r3, r4)
    mid = (lo + hi) / 2
    mx, my = math.cos(mid), math.sin(mid)  # mid-swing line (real constant)
    bx, by = _crank_pin(r2, th)
    dx, dy = _fourbar(bx, by, r1, 0.0, r3, r4)
    ex, ey = _unit(dx - r1, dy)  # rocker direction
    along = r5 * (mx * ey - my * ex)  # r5 sin(delta), +path = perp(m)
    towards = h - r5 * (mx * ex + my * ey)  # h - r5 cos(delta)
    joints = {"coupler-rocker": _cos_between(dx - bx, dy - by, dx - r1, dy)}
    if r6 == 0:
        return along, joints
    s = along + _sqrt(
        r6 * r6 - towards * towards, r6 * r6, "connecting_rod cannot reach the slider path"
    )
    joints["connecting_rod-slider"] = towards / r6  # normal to the path = m
    return s, joints


def _drag_link_slider(p, th):
    r1, r2, r3, r4, r5, r6 = (
        p["ground"],
        p["crank"],
        p["coupler"],
        p["follower"],
        p["follower_arm"],
        p["connecting_rod"],
    )
    bx, by = _crank_pin(r2, th)
    dx, dy = _fourbar(bx, by, r1, 0.0, r3, r4)
    ex, ey = _unit(dx - r1, dy)
    cx, cy = r1 + r5 * ex, r5 * ey  # pin C on the follower line
    s = cx + _sqrt(r6 * r6 - cy * cy, r6 * r6, "connecting_rod cannot reach the ground line")
    return s, {
        "coupler-follower": _cos_between(dx - bx, dy - by, dx - r1, dy),
        "connecting_rod-slider": -cy / r6,
    }  # path +x, normal +y


_GEOM = {
    "scotch_yoke": _scotch_yoke,
    "offset_slider_crank": _offset_slider_crank,
    "crank_shaper": _crank_shaper,
    "whitworth": _whitworth,
    "crank_rocker_slider": _crank_rocker_slider,
    "drag_link_slider": _drag_link_slider,
}


def _prepare(mtype, params):
    p = complete(mtype, params)
    _check(mtype, p)
    return p


# --------------------------------------------------------------------------- public API
def position(mtype: str, params: dict, theta) -> np.ndarray:
    """Slider position s(theta); theta may be complex (complex-step differentiation)."""
    p = _prepare(mtype, params)
    return _GEOM[mtype](p, np.asarray(theta))[0]


def transmission_cos(mtype: str, params: dict, theta) -> dict:
    """Signed cos of the transmission angle at every pin-jointed output coupler."""
    p = _prepare(mtype, params)
    return _GEOM[mtype](p, np.asarray(theta))[1]


def simulate(mtype: str, params: dict, n: int = 20000) -> dict:
    """Full revolution on n even crank angles, extremes refined by complex-step + brentq.

    Returns time_ratio (>= 1), stroke, s_min, s_max, theta_min, theta_max (rad, [0, 2pi)),
    working_angle (the larger crank travel between the extremes), working_direction (+1 if the
    slow stroke runs s_min -> s_max with the crank turning counter-clockwise, else -1; +1 on a
    tie), min/max_transmission_deg (folded into [0, 90], over the revolution and all joints,
    90 with no joints) and joints = {name: (min_deg, max_deg)}.
    """
    p = _prepare(mtype, params)
    geom = _GEOM[mtype]
    two_pi = 2 * np.pi

    # --- slider extremes
    _, sg, roots, sr = _stationary(lambda t: geom(p, t)[0], n)
    if roots.size < 2:
        raise ValueError("cannot run: the slider does not reciprocate")
    imax, imin = int(np.argmax(sr)), int(np.argmin(sr))
    s_max, s_min = float(sr[imax]), float(sr[imin])
    t_max, t_min = float(roots[imax]), float(roots[imin])
    if s_max < sg.max() - 1e-9 * (abs(s_max) + 1) or s_min > sg.min() + 1e-9 * (abs(s_min) + 1):
        raise ValueError("refinement failed: grid extreme beyond the stationary points")
    up = (t_max - t_min) % two_pi  # crank travel while s goes min -> max
    down = two_pi - up
    if up >= down:
        direction, work, quick = 1, up, down
    else:
        direction, work, quick = -1, down, up

    # --- transmission angles
    joints = {}
    for name in geom(p, np.zeros(1))[1]:
        _, cg, _, cr = _stationary(lambda t, name=name: geom(p, t)[1][name], n)
        allc = np.concatenate([cg, cr])
        crosses = np.any(cg[:-1] * cg[1:] <= 0) or (allc.max() >= 0 >= allc.min())
        cmax = float(np.max(np.abs(allc)))
        cmin = 0.0 if crosses else float(np.min(np.abs(allc)))
        joints[name] = (
            math.degrees(math.acos(min(cmax, 1.0))),
            math.degrees(math.acos(min(cmin, 1.0))),
        )
    mins = [v[0] for v in joints.values()] or [90.0]
    maxs = [v[1] for v in joints.values()] or [90.0]

    return {
        "time_ratio": work / quick,
        "stroke": s_max - s_min,
        "s_min": s_min,
        "s_max": s_max,
        "theta_min": t_min,
        "theta_max": t_max,
        "working_angle": work,
        "working_direction": direction,
        "min_transmission_deg": min(mins),
        "max_transmission_deg": max(maxs),
        "joints": joints,
    }
