"""The slider's motion by brute force on the independent geometry of bruteforce.py (which
shares no code with synth): its velocity by complex step, its acceleration by a Cauchy contour
integral of the position, both sampled densely over each stroke and the largest refined by a
bounded scalar maximiser."""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import brentq, minimize_scalar

from . import bruteforce

SAMPLES = 2000  # per stroke, before the maximiser refines the largest
CONTOUR = 24  # points on the circle of the Cauchy integral for s″


def velocity(mtype, p, theta):
    """ds/dθ by complex step: exact to rounding."""
    h = 1e-30
    return np.imag(bruteforce.position(mtype, p, np.asarray(theta) + 1j * h)) / h


def acceleration(mtype, p, theta, rho=0.02):
    """d²s/dθ² = 2/(N ρ²) Σ (s(θ + ρ wʲ) − s(θ)) w⁻²ʲ, w = e^(2πi/N): Cauchy's integral on a
    circle, exact but for terms of order ρᴺ; a smaller circle where the geometry cannot be
    continued that far from the real axis."""
    theta = np.atleast_1d(np.asarray(theta, dtype=float))
    w = np.exp(2j * np.pi * np.arange(CONTOUR) / CONTOUR)
    try:
        s = bruteforce.position(mtype, p, theta[:, None] + rho * w[None, :])
    except ValueError:
        if rho < 1e-3:
            raise
        return acceleration(mtype, p, theta, rho / 4)
    s0 = bruteforce.position(mtype, p, theta)[:, None]
    return np.real(2 * np.sum((s - s0) * w[None, :] ** -2, axis=1) / (CONTOUR * rho**2))


def peak(f, lo, hi):
    """max f over [lo, hi]: dense samples, the best refined by a bounded maximiser."""
    t = np.linspace(lo, hi, SAMPLES)
    y = f(t)
    k = int(np.argmax(y))
    a, b = t[max(k - 1, 0)], t[min(k + 1, t.size - 1)]
    r = minimize_scalar(
        lambda x: -f(np.array([x]))[0], bounds=(a, b), method="bounded", options={"xatol": 1e-13}
    )
    return max(y[k], -r.fun, f(np.array([lo]))[0], f(np.array([hi]))[0])


def brute_motion(mtype, p):
    b = bruteforce.simulate(mtype, p, n=4000)
    work = b["working_angle"]
    start = b["theta_min"] if b["working_direction"] == 1 else b["theta_max"]
    s0, s1 = (b["s_min"], b["s_max"]) if b["working_direction"] == 1 else (b["s_max"], b["s_min"])
    stroke = b["stroke"]

    def speed(t):
        return np.abs(velocity(mtype, p, t))

    def accel(t):
        return np.abs(acceleration(mtype, p, t))

    mean = stroke / work
    whole = peak(speed, start, start + work) / mean

    def at(level):
        return brentq(
            lambda t: bruteforce.position(mtype, p, np.array([t]))[0] - level,
            start,
            start + work,
            xtol=1e-15,
            rtol=1e-15,
        )

    a, b_ = at(s0 + 0.1 * (s1 - s0)), at(s0 + 0.9 * (s1 - s0))
    middle = peak(speed, a, b_) / (0.8 * stroke / (b_ - a))
    working = peak(accel, start, start + work) / stroke
    ret = peak(accel, start + work, start + 2 * math.pi) / stroke
    return whole, middle, working, ret
