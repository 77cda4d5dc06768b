"""Small dense numerics in Python floats: Newton's method on a Lagrangian (the KKT step of a
handful of unknowns; a safeguarded form in one or two variables that only descends), its
derivatives by central differences, and bisection of a bracket.

The systems have at most four unknowns: numpy's per-call overhead on such small arrays costs
several times the arithmetic, so the algebra is written out on lists of floats.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from functools import cache

import numpy as np

# A point's local model: the values of a problem's rows (the objective, then the equalities),
# their gradients and their Hessians, in Python floats; None where the point is not a design
Taylor = tuple[list[float], list[list[float]], list[list[list[float]]]]
CAP = 3.0  # the longest step of ``descend``, in cells
PROJECT = 6  # Gauss–Newton corrections back onto a curve after a step along it


def newton(
    local: Callable[[list[float]], Taylor | None],
    x0: np.ndarray,
    n_eq: int,
    iters: int = 30,
    keep: list[Taylor] | None = None,
    halvings: int | None = None,
) -> np.ndarray | None:
    """A stationary point of the first row on the set where the next ``n_eq`` rows are 0,
    from x0: Newton's method on the Lagrangian's stationarity and the equalities (with n_eq =
    d it is root finding), on the rows' values, gradients and Hessians (``local``: exact where
    the problem compiles them, else ``differences``). A step that leaves the designs is
    halved. Returns None when it does not converge.

    The algebra of a step (a system of at most four unknowns) is done in Python floats:
    numpy's per-call overhead on such small arrays cost several times the evaluation.
    ``keep`` (a list) receives ``local`` at the answer, for derivatives there; ``halvings``
    caps the halvings of a step (by default 30, 8 for root finding).
    """
    d = x0.size
    x = [float(a) for a in x0]
    t = local(x)
    if t is None:
        return None
    nu: list[float] | None = None
    last = math.inf
    for it in range(iters):
        step, nu = _step(t, d, n_eq, nu, it)
        if step is None:
            return None
        for _ in range(halvings or (30 if n_eq < d else 8)):  # a step leaving the designs is halved
            y = [a + b for a, b in zip(x, step, strict=True)]
            t = local(y)
            if t is not None:
                break
            step = [a / 2 for a in step]
        else:
            return None
        x = y
        # converged where the equalities hold and the step is down to the derivatives'
        # rounding (~1e-11 × a condition number with differences), or is 1e-6 and converging
        # quadratically (it leaves ~1e-12): a stationary value is off by that squared
        size = max(abs(a) for a in step)
        held = all(abs(r) <= 1e-10 for r in t[0][1 : 1 + n_eq])
        if held and (size <= 1e-8 or (size <= 1e-6 and size <= 1e-2 * last)):
            if keep is not None:
                keep.append(t)
            return np.array(x)
        last = size
    return None


def descend(
    local: Callable[[list[float]], Taylor | None],
    x0: np.ndarray,
    n_eq: int,
    cell: np.ndarray,
    iters: int = 40,
    halvings: int = 4,
) -> np.ndarray | None:
    """A local minimum of the first row on the set where the next ``n_eq`` rows are 0 (d ≤ 2
    variables, n_eq ≤ d), from x0: ``newton``'s step, safeguarded. Off the set a step first
    returns to it (the least correction); along it, where the Lagrangian curves upward the
    Newton step, else a step of one ``cell`` (the grid's spacing per variable) downhill;
    no step is longer than ``CAP`` cells, and one that leaves the designs is halved. So it
    ends at a minimum, never at a maximum or saddle. Converged as ``newton``: the equalities
    to 1e-10 and a step below 1e-8, or below 1e-6 and shrinking quadratically, where the
    Lagrangian curves upward. None where it does not converge."""
    x = [float(a) for a in x0]
    t = local(x)
    if t is None:
        return None
    last = math.inf
    along = 0 < n_eq < len(x)  # steps along a curve: kept near it
    for _ in range(iters):
        step, curved = _safe_step(t, len(x), n_eq, cell)
        if step is None:
            return None
        for _ in range(halvings + 1):
            y = [a + b for a, b in zip(x, step, strict=True)]
            ty = local(y)
            if ty is not None and along:  # back onto the curve: a step along it bends
                y, ty = _project(local, y, ty, n_eq)
            if ty is not None:
                break
            step = [a / 2 for a in step]  # a step that leaves the designs is halved
        else:
            return None
        x, t = y, ty
        size = max(abs(a) for a in step)
        held = all(abs(r) <= 1e-10 for r in t[0][1 : 1 + n_eq])
        if held and curved and (size <= 1e-8 or (size <= 1e-6 and size <= 1e-2 * last)):
            return np.array(x)
        last = size
    return None


def _project(
    local: Callable[[list[float]], Taylor | None], y: list[float], t: Taylor, n_eq: int
) -> tuple[list[float], Taylor | None]:
    """y moved back onto the set where the equalities hold (Gauss–Newton's least
    corrections, a few): the point and its model, None where it leaves the designs or does
    not get within 1e-12 of the set."""
    for _ in range(PROJECT):
        eq = t[0][1 : 1 + n_eq]
        if max(abs(r) for r in eq) <= 1e-12:
            return y, t
        jac = t[1][1 : 1 + n_eq]
        jjt = [[_dot(a, b) for b in jac] for a in jac]
        w = solve(jjt, [-r for r in eq])
        if w is None:
            return y, None
        y = [yi + sum(wk * jk[i] for wk, jk in zip(w, jac, strict=True)) for i, yi in enumerate(y)]
        t_next = local(y)
        if t_next is None:
            return y, None
        t = t_next
    return (y, t) if max(abs(r) for r in t[0][1 : 1 + n_eq]) <= 1e-9 else (y, None)


def _safe_step(t: Taylor, d: int, n_eq: int, cell: np.ndarray) -> tuple[list[float] | None, bool]:
    """``descend``'s step and whether the Lagrangian curves upward along the set there."""
    vals, grads, hess = t
    c = [float(a) for a in cell]
    if n_eq == d:  # the equalities fix the point: Newton's step on them
        step = solve(grads[1 : 1 + n_eq], [-e for e in vals[1 : 1 + n_eq]])
        return (None if step is None else _capped(step, c)), True
    g = grads[0]
    if n_eq == 0:
        h = hess[0]
        if d == 1:
            if h[0][0] > 0:
                return _capped([-g[0] / h[0][0]], c), True
            return [-math.copysign(c[0], g[0])], False
        det = h[0][0] * h[1][1] - h[0][1] ** 2
        if h[0][0] > 0 and det > 0:
            step = solve(h, [-g[0], -g[1]])
            if step is not None:
                return _capped(step, c), True
        return _downhill(g, c), False
    # d = 2, one equality: back to its curve, then along it
    (a0, a1), e = grads[1], vals[1]
    aa = a0 * a0 + a1 * a1
    if not aa:
        return None, False
    normal = [-e * a0 / aa, -e * a1 / aa]
    nu = -(a0 * g[0] + a1 * g[1]) / aa
    w = [[hess[0][i][j] + nu * hess[1][i][j] for j in range(2)] for i in range(2)]
    z = [-a1 / math.sqrt(aa), a0 / math.sqrt(aa)]  # the curve's tangent
    wz = [w[0][0] * z[0] + w[0][1] * z[1], w[1][0] * z[0] + w[1][1] * z[1]]
    kappa = z[0] * wz[0] + z[1] * wz[1]
    gamma = z[0] * (g[0] + w[0][0] * normal[0] + w[0][1] * normal[1])
    gamma += z[1] * (g[1] + w[1][0] * normal[0] + w[1][1] * normal[1])
    length = math.hypot(z[0] / c[0], z[1] / c[1])  # cells per unit along the tangent
    if kappa > 0:
        along = -gamma / kappa
        along = max(-CAP / length, min(CAP / length, along))
    else:
        along = -math.copysign(1.0 / length, gamma)
    return _capped([normal[0] + along * z[0], normal[1] + along * z[1]], c), kappa > 0


def _capped(step: list[float], cell: list[float]) -> list[float]:
    """The step shortened to at most ``CAP`` cells."""
    n = math.sqrt(sum((s / c) ** 2 for s, c in zip(step, cell, strict=True)))
    return step if n <= CAP else [s * CAP / n for s in step]


def _downhill(g: list[float], cell: list[float]) -> list[float]:
    """One cell down the gradient, in the grid's scaled coordinates."""
    sg = [a * c * c for a, c in zip(g, cell, strict=True)]
    n = math.sqrt(sum((s / c) ** 2 for s, c in zip(sg, cell, strict=True)))
    return [-s / n for s in sg] if n else [0.0] * len(g)


def differences(
    fn: Callable[[np.ndarray], np.ndarray], d: int, h: float = 1e-5
) -> Callable[[list[float]], Taylor | None]:
    """``newton``'s ``local`` by central differences of ``fn``, which maps points (m, d) to
    rows (r, m), NaN where a point is not a design: one batch of ≤ 9 points (``_stencil``) a
    call; a point is no design where any point of its stencil is not."""
    offsets = _stencil(d) * h

    def local(x: list[float]) -> Taylor | None:
        v = fn(np.array(x) + offsets)
        if not np.isfinite(v).all():
            return None
        rows = v.tolist()
        grads = [[(r[1 + 2 * i] - r[2 + 2 * i]) / (2 * h) for i in range(d)] for r in rows]
        hess = []
        for r in rows:
            c = 2 * r[0]
            m = [[0.0] * d for _ in range(d)]
            for i in range(d):
                m[i][i] = (r[1 + 2 * i] - c + r[2 + 2 * i]) / (h * h)
            if d == 2:
                m[0][1] = m[1][0] = (r[5] - r[6] - r[7] + r[8]) / (4 * h * h)
            hess.append(m)
        return [r[0] for r in rows], grads, hess

    return local


def _step(
    t: Taylor, d: int, n_eq: int, nu: list[float] | None, it: int
) -> tuple[list[float] | None, list[float] | None]:
    """A Newton step from a point's local model: (step, multipliers), or (None, _)."""
    vals, grads, hess = t
    if d == 2 and n_eq == 1:  # the common case (a size on a bound), written out
        return _step_2_1(vals, grads, hess, nu)
    g, jac = grads[0], grads[1 : 1 + n_eq]
    eq = vals[1 : 1 + n_eq]
    if n_eq == d:  # the equalities alone fix the point: quadratic convergence or none
        if it > 12:
            return None, nu
        return solve(jac, [-e for e in eq]), nu
    if nu is None:  # least-squares multipliers: jac jacᵀ ν = −jac g
        jjt = [[_dot(a, b) for b in jac] for a in jac]
        nu = solve(jjt, [-_dot(a, g) for a in jac]) if n_eq else []
        if nu is None:
            return None, None
    # the Lagrangian's Hessian (rows weighted 1, ν) and the KKT system
    kkt = [[0.0] * (d + n_eq) for _ in range(d + n_eq)]
    rhs = [-x for x in g] + [-e for e in eq]
    for w, m in zip([1.0, *nu], hess, strict=False):
        for i in range(d):
            for j in range(d):
                kkt[i][j] += w * m[i][j]
    for k in range(n_eq):
        for i in range(d):
            kkt[i][d + k] = kkt[d + k][i] = jac[k][i]
            rhs[i] -= jac[k][i] * nu[k]
    sol = solve(kkt, rhs)
    if sol is None:
        return None, None
    return sol[:d], [a + b for a, b in zip(nu, sol[d:], strict=True)]


def _step_2_1(
    vals: list[float],
    grads: list[list[float]],
    hess: list[list[list[float]]],
    nu: list[float] | None,
) -> tuple[list[float] | None, list[float] | None]:
    """``_step`` in two variables with one equality: the same system, unrolled."""
    (g0, g1), (a0, a1) = grads[0], grads[1]
    if nu is None:  # the least-squares multiplier
        aa = a0 * a0 + a1 * a1
        if not aa:
            return None, None
        nu = [-(a0 * g0 + a1 * g1) / aa]
    n = nu[0]
    (s00, s01), (_, s11) = hess[0]
    (r00, r01), (_, r11) = hess[1]
    sol = __solve3(
        [[s00 + n * r00, s01 + n * r01, a0], [s01 + n * r01, s11 + n * r11, a1], [a0, a1, 0.0]],
        [-g0 - a0 * n, -g1 - a1 * n, -vals[1]],
    )
    if sol is None:
        return None, None
    return sol[:2], [n + sol[2]]


def __solve3(a: list[list[float]], b: list[float]) -> list[float] | None:
    """``solve`` for three unknowns, unrolled: the same pivots and operations."""
    r0, r1, r2 = [*a[0], b[0]], [*a[1], b[1]], [*a[2], b[2]]
    # column 0: the largest of the three leads
    if abs(r1[0]) > abs(r0[0]) and abs(r1[0]) >= abs(r2[0]):
        r0, r1 = r1, r0
    elif abs(r2[0]) > abs(r0[0]) and abs(r2[0]) > abs(r1[0]):
        r0, r2 = r2, r0
    if r0[0] == 0:
        return None
    f1, f2 = r1[0] / r0[0], r2[0] / r0[0]
    if f1:
        r1 = [r1[0] - f1 * r0[0], r1[1] - f1 * r0[1], r1[2] - f1 * r0[2], r1[3] - f1 * r0[3]]
    if f2:
        r2 = [r2[0] - f2 * r0[0], r2[1] - f2 * r0[1], r2[2] - f2 * r0[2], r2[3] - f2 * r0[3]]
    if abs(r2[1]) > abs(r1[1]):  # column 1
        r1, r2 = r2, r1
    if r1[1] == 0:
        return None
    f = r2[1] / r1[1]
    if f:
        r2 = [r2[0], r2[1] - f * r1[1], r2[2] - f * r1[2], r2[3] - f * r1[3]]
    if r2[2] == 0:
        return None
    x2 = r2[3] / r2[2]
    x1 = (r1[3] - r1[2] * x2) / r1[1]
    x0 = (r0[3] - r0[1] * x1 - r0[2] * x2) / r0[0]
    return [x0, x1, x2]


def _dot(a: list[float], b: list[float]) -> float:
    return sum(x * y for x, y in zip(a, b, strict=True))


def solve(a: list[list[float]], b: list[float]) -> list[float] | None:
    """x with a x = b, by Gaussian elimination with partial pivoting (LAPACK's getrf/getrs
    for a handful of unknowns); None where a pivot is exactly zero (a singular system)."""
    n = len(b)
    if n == 3:
        return __solve3(a, b)
    m = [[*row, rhs] for row, rhs in zip(a, b, strict=True)]
    for c in range(n):
        p, big = c, abs(m[c][c])
        for r in range(c + 1, n):
            if abs(m[r][c]) > big:
                p, big = r, abs(m[r][c])
        if big == 0:
            return None
        m[c], m[p] = m[p], m[c]
        piv = m[c]
        for r in range(c + 1, n):
            row = m[r]
            f = row[c] / piv[c]
            if f:
                for k in range(c, n + 1):
                    row[k] -= f * piv[k]
    x = [0.0] * n
    for c in range(n - 1, -1, -1):
        row = m[c]
        s = row[n]
        for k in range(c + 1, n):
            s -= row[k] * x[k]
        x[c] = s / row[c]
    return x


@cache
def _stencil(d: int) -> np.ndarray:
    """The points of the central differences in d ≤ 2 dimensions, in units of the steps: the
    centre, ± each axis, then (for d = 2) the four corners (+ +, + −, − +, − −)."""
    rows = [np.zeros(d)]
    for i in range(d):
        rows += [np.eye(d)[i], -np.eye(d)[i]]
    if d == 2:
        rows += [np.array(c, dtype=float) for c in ((1, 1), (1, -1), (-1, 1), (-1, -1))]
    out = np.array(rows)
    out.flags.writeable = False  # shared by every caller
    return out


def bisect(
    ok: Callable[[float], bool], inside: float, outside: float, tol: float = 0.0
) -> tuple[float, float]:
    """Halve the bracket between a point where ``ok`` holds (``inside``) and one where it does
    not (``outside``) until it is at most tol × max(1, |inside|) wide, or (tol 0) down to two
    neighbouring floats: the narrowed (inside, outside)."""
    while abs(inside - outside) > tol * max(1.0, abs(inside)):
        mid = 0.5 * (inside + outside)
        if mid in (inside, outside):
            break
        if ok(mid):
            inside = mid
        else:
            outside = mid
    return inside, outside
