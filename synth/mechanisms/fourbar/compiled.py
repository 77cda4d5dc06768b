"""The four-bar construction's evaluation (``_fourbar_construction.Construction.evaluate``)
as one CasADi function, compiled (``synth.numerics.native``) and evaluated through preallocated
buffers, for the few points of a Newton step or a single design: numpy's per-operation
overhead made such a call cost ~50 µs, most of a reduced synthesis's time.

The same formulas as the numpy version, in real arithmetic (the complex quotient written
out), with every structural choice of a variant (the fixed link that sets the scale, a
swinging arm, a rod, its path's placement, the objective) a number in the parameter vector,
so one function serves every variant. Where the numpy version yields NaN (no rod within the
bounds, a point that is no design) this one does too: the conditions are tracked as flags,
not left to NaN propagation (C's fmin and fmax drop a NaN). Its results agree with the numpy
version's to rounding (tests/test_fourbar_native.py). Like every CasADi function it is never
shared between threads: each thread builds (or loads) its own.
"""

from __future__ import annotations

import math
import threading

import casadi as ca
import numpy as np

from ...numerics.native import bind, native

# the parameter vector: the names of its entries, in order
PARAMS = (
    "ep_r", "ep_i",  # e^{iφ}, φ = π + σβ
    "lo0", "lo1", "lo2", "lo3", "hi0", "hi1", "hi2", "hi3",  # the links' boxes (scale 1)
    "free_scale", "set0", "set1", "set2", "set3",  # the scale free, or set by link i
    "swings", "arm",  # the arm swings (r5 = 1/(2 sin(ψ/2))), else its length
    "rod", "min_size", "cos_bound", "rod_lo", "rod_hi",  # a connecting rod, by reduced.rod
    "on_line", "height_fixed", "height", "height_lo", "height_hi",  # its path's placement
)  # fmt: skip
ROWS = ("valid", "feasible", "f", "size", "k", "a2", "a3", "a4", "r5", "l", "h", "rod_cos",
        "slack")  # fmt: skip
MAX_WIDTH = 16  # up to this many points go through a buffer; more (a grid): numpy

_local = threading.local()


def _function(bound_tol: float, strict: float, one_way: float) -> ca.Function:
    """The rows (``ROWS``) at x = (ψ, λ)."""
    x = ca.SX.sym("x", 2)
    p = ca.SX.sym("p", len(PARAMS))
    out = _rows(x[0], x[1], p, bound_tol, strict, one_way)
    return native(ca.Function("fourbar_construction", [x, p], [out], {"cse": True}))


def _taylor(bound_tol: float, strict: float, one_way: float) -> ca.Function:
    """At y = (ψ, u), λ = 1 + e^u (Newton's coordinates): valid, f, the size, their gradients
    (TAYLOR) and Hessians (ψψ, ψu, uu), by automatic differentiation."""
    y = ca.SX.sym("y", 2)
    p = ca.SX.sym("p", len(PARAMS))
    rows = _rows(y[0], 1 + ca.exp(ca.fmin(y[1], 50.0)), p, bound_tol, strict, one_way)
    f, size = rows[ROWS.index("f")], rows[ROWS.index("size")]
    (hf, gf), (hs, gs) = ca.hessian(f, y), ca.hessian(size, y)
    out = ca.vertcat(rows[ROWS.index("valid")], f, size, gf, gs,
                     hf[0, 0], hf[0, 1], hf[1, 1], hs[0, 0], hs[0, 1], hs[1, 1])  # fmt: skip
    return native(ca.Function("fourbar_construction_taylor", [y, p], [out], {"cse": True}))


def _rows(psi, lam, p, bound_tol: float, strict: float, one_way: float) -> ca.SX:
    """The rows (``ROWS``) at (ψ, λ), symbolic."""
    q = {n: p[i] for i, n in enumerate(PARAMS)}
    nan, inf = ca.SX(math.nan), ca.SX(math.inf)
    er, ei = q["ep_r"], q["ep_i"]
    # z1 = (1 − e^{iψ}) / ((1 − λ) e^{iφ} − (1 + λ) e^{iψ})
    cp, sp = ca.cos(psi), ca.sin(psi)
    nr, ni = 1 - cp, -sp
    dr, di = (1 - lam) * er - (1 + lam) * cp, (1 - lam) * ei - (1 + lam) * sp
    dd = dr * dr + di * di
    zr, zi = (nr * dr + ni * di) / dd, (ni * dr - nr * di) / dd
    a2 = ca.sqrt(zr * zr + zi * zi)
    a3 = lam * a2
    wr, wi = (1 + lam) * zr - 1, (1 + lam) * zi
    a4 = ca.sqrt(wr * wr + wi * wi)
    longest = ca.fmax(ca.fmax(1.0, a3), a4)
    valid = ca.logic_and(
        ca.logic_and(zi * (zr * ei + zi * er) < 0, a2 <= ca.fmin(1.0, a4)),
        a2 + longest <= 1 + a3 + a4 - longest,
    )
    # the coupler's worst cos (worst_cos)
    base = a3 * a3 + a4 * a4
    c1 = (base - (1 - a2) ** 2) / (2 * a3 * a4)
    c2 = (base - (1 + a2) ** 2) / (2 * a3 * a4)
    f = ca.fmax(c1, -c2)
    # the scale
    rho = (1.0, a2, a3, a4)
    lo = [q[f"lo{i}"] / r for i, r in enumerate(rho)]
    hi = [q[f"hi{i}"] / r for i, r in enumerate(rho)]
    kmin = ca.fmax(ca.fmax(lo[0], lo[1]), ca.fmax(lo[2], lo[3]))
    kmax = ca.fmin(ca.fmin(hi[0], hi[1]), ca.fmin(hi[2], hi[3]))
    k = ca.if_else(q["set0"], lo[0], ca.if_else(q["set1"], lo[1], ca.if_else(q["set2"], lo[2],
                                                                              lo[3])))  # fmt: skip
    k = ca.if_else(q["free_scale"], kmin, k)
    feasible = ca.logic_and(valid, kmin <= kmax * (1 + bound_tol))
    rest = [
        ca.if_else(q[f"set{i}"], inf, ca.fmin(ca.log(k / a), ca.log(b / k)))
        for i, (a, b) in enumerate(zip(lo, hi, strict=True))
    ]
    slack = ca.if_else(
        q["free_scale"], ca.log(kmax / kmin), ca.fmin(ca.fmin(rest[0], rest[1]),
                                                      ca.fmin(rest[2], rest[3]))
    )  # fmt: skip
    r5 = ca.if_else(q["swings"], 0.5 / ca.sin(psi / 2), q["arm"])
    # the connecting rod (reduced.rod), its NaNs as flags
    rlo, rhi, arm = q["rod_lo"], q["rod_hi"], r5
    c = ca.if_else(q["min_size"], q["cos_bound"], f)
    # on the line (the pin turns fully about a centre on the path)
    w_line = arm
    short_line = ca.fmax(ca.fmax(rlo, w_line / c), w_line + strict)
    len_line = ca.if_else(q["min_size"], short_line, ca.if_else(short_line <= rhi, short_line,
                                                                rhi))  # fmt: skip
    # a swinging pin
    xc = ca.cos(psi / 2)
    m_ok = xc > one_way
    m = ca.fmin(c, xc - one_way)
    pos = c > 0

    def place(h):
        return ca.if_else(q["height_fixed"], q["height"],
                          ca.fmin(ca.fmax(h, q["height_lo"]), q["height_hi"]))  # fmt: skip

    h = place(ca.if_else(pos, arm * (m + c * xc) / ca.if_else(pos, m + c, 1.0), arm))
    g1, g2 = ca.fabs(h - arm), ca.fabs(h - arm * xc)
    short = ca.if_else(pos, ca.fmax(rlo, ca.fmax(g1 / c, g2 / m)), inf)
    short_nan = ca.logic_and(pos, ca.logic_not(m_ok))  # numpy's m is NaN there
    h_nan = ca.logic_and(short_nan, ca.logic_not(q["height_fixed"]))
    lean = (xc - one_way) * rhi
    mid = place(ca.fmin(ca.fmax(arm * (1 + xc) / 2, arm * xc - lean), arm * xc + lean))
    limited_ok = ca.fabs(mid - arm * xc) <= lean * (1 + 1e-12)
    use_short = ca.logic_and(ca.logic_not(short_nan), short <= rhi)
    len_swing = ca.if_else(q["min_size"], short, ca.if_else(use_short, short, rhi))
    neither = ca.logic_and(ca.logic_not(use_short), ca.logic_not(limited_ok))
    swing_nan = ca.if_else(q["min_size"], short_nan, neither)
    h = ca.if_else(ca.logic_or(q["min_size"], use_short), h, mid)
    h_nan = ca.logic_and(h_nan, ca.logic_or(q["min_size"], use_short))
    w_swing = ca.fmax(ca.fabs(h - arm), ca.fabs(h - arm * xc))
    line = q["on_line"]
    length = ca.if_else(line, len_line, len_swing)
    length_nan = ca.logic_and(ca.logic_not(line), swing_nan)
    w = ca.if_else(line, w_line, w_swing)
    l_ok = ca.logic_and(ca.logic_not(length_nan),
                        ca.logic_and(length <= rhi * (1 + 1e-12), length < inf))  # fmt: skip
    l_ok = ca.logic_and(l_ok, ca.fmin(length, rhi) < inf)
    rod_l = ca.if_else(l_ok, ca.fmin(length, rhi), nan)
    rod_h = ca.if_else(ca.logic_or(line, h_nan), nan, h)
    rod_cos = ca.if_else(ca.logic_and(l_ok, ca.logic_not(ca.logic_and(ca.logic_not(line), h_nan))),
                         w / ca.fmin(length, rhi), nan)  # fmt: skip
    rod = q["rod"]
    l = ca.if_else(rod, rod_l, 0.0)
    h_out = ca.if_else(rod, rod_h, nan)
    rc = ca.if_else(rod, rod_cos, 0.0)
    l_fin = ca.logic_or(ca.logic_not(rod), l_ok)
    feasible = ca.logic_and(feasible, l_fin)
    size = k * (1 + a2 + a3 + a4) + r5 + ca.if_else(l_fin, l, 0.0)
    return ca.vertcat(valid, feasible, f, size, k, a2, a3, a4, r5, l, h_out, rc, slack)


class Compiled:
    """The function (this thread's) and a buffer per number of points."""

    def __init__(self, bound_tol: float, strict: float, one_way: float) -> None:
        self.fn = _function(bound_tol, strict, one_way)
        self.taylor_fn = _taylor(bound_tol, strict, one_way)
        self.buffers: dict[int, tuple] = {}
        self._taylor = None

    def taylor(self, psi: float, u: float, params) -> list[float]:
        """``_taylor``'s outputs at one point (ψ, u), a list (``params`` as for ``at``)."""
        if self._taylor is None:
            self._taylor = self._buffer(1, self.taylor_fn, self.taylor_fn.nnz_out(0))
        b = self._taylor
        x, p, out, run = b[:4]
        x[0, 0], x[0, 1] = psi, u
        if params is not b[5]:
            p[:] = params
            b[5] = params
        run()
        return out[0].tolist()

    def __call__(self, points: np.ndarray, params) -> np.ndarray:
        """The rows (ROWS) at each point (ψ, λ) of ``points`` (n, 2): shape (rows, n)."""
        return self.at(points[:, 0], points[:, 1], params)

    def at(self, psi, lam, params) -> np.ndarray:
        """The rows (ROWS) at the points (ψ_i, λ_i): shape (rows, n). ``params`` is copied
        into the buffer unless it is the list the buffer last took (kept, so never another
        list at its address)."""
        n = len(psi)
        b = self.buffers.get(n)
        if b is None:
            b = self.buffers[n] = self._buffer(n)
        x, p, out, run = b[:4]
        x[:, 0], x[:, 1] = psi, lam
        if params is not b[5]:
            p[:] = params
            b[5] = params
        run()
        return out.T.copy()  # the buffer is reused by the next call

    def _buffer(self, width: int, fn: ca.Function | None = None, rows: int = len(ROWS)) -> list:
        x, p = np.zeros((width, 2)), np.zeros(len(PARAMS))  # x column-major (2, width)
        out = np.zeros((width, rows))
        run, buf = bind((fn or self.fn).map(width, [False, True], [False]), [x, p], out)
        return [x, p, out, run, buf, None]  # the last: the params the buffer last took


def compiled(bound_tol: float, strict: float, one_way: float) -> Compiled:
    """This thread's compiled evaluation (CasADi functions are never shared by threads)."""
    key = (bound_tol, strict, one_way)
    cache = _local.__dict__.setdefault("fns", {})
    if key not in cache:
        cache[key] = Compiled(*key)
    return cache[key]
