"""Exact reduced synthesis: the targets turn most of a design into closed forms.

The time ratio and the stroke are two equalities. A type's ``reduced`` solver (an optional
accelerator in its registry record) parametrises the designs that meet them exactly, by the
classical dead-centre construction, and solves what is left, a problem in at most two
variables, by closed forms, bracketed roots and Newton's method on its optimality conditions.
It returns every local optimum it finds (one per branch or structural choice), in stroke
units, and says whether the answer is ``exact``: the best design is the global optimum of the
stated problem, and an empty answer proves that no design exists. Anything it cannot take
(``None``, or not ``exact``) goes to IPOPT, warm-started from the designs it did find.

This module holds what the solvers share: the problem, the answer, the rule for a connecting
rod, and Newton's method on a Lagrangian (exact derivatives where a solver compiles them,
else central differences).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from functools import cache

import numpy as np

from ..errors import Unreachable
from ..results import TOL

MAX_TRANSMISSION, MIN_SIZE = "max_transmission_angle", "min_size"
STRICT = 1e-7  # the margin kept by a strict condition, in stroke units (the NLP's too)
# the cos margin kept from the one-way limit (facts' "one_way"): at the limit the slider dwells
# at its dead centre, a multiple root that the analysis locates only to ~1e-6 in the time
# ratio; the error falls as 1/margin (worst of 300 designs: 3e-12 at 1e-4, 2e-13 at 1e-3)
ONE_WAY = 1e-3


@dataclass(frozen=True)
class Problem:
    """One structural variant of one type, in stroke units (the stroke is 1).

    ``fixed`` holds the variant's fixed parameters, ``bounds`` the box of every free one (the
    caller's, else the defaults); ``beta`` = π(TR − 1)/(TR + 1) is the crank angle by which
    the slow stroke exceeds π; ``cos_bound`` is cos of the transmission bound (1: none).
    ``stroke`` is the caller's stroke, for messages in the caller's unit.

    Default bounds limit a search: a parameter that the targets and the fixed parts set on
    their own is taken as it comes unless the caller bounded it (``allows``).
    """

    variant: frozenset[str]
    fixed: Mapping[str, float]
    bounds: Mapping[str, tuple[float, float]]
    beta: float
    cos_bound: float
    objective: str
    stroke: float = 1.0
    explicit: frozenset[str] = frozenset()  # parameters whose bounds the caller gave
    hints: tuple[Mapping[str, float], ...] = ()  # the optima of the type's other variants
    # where this variant's optima were at a nearby bound (a front's previous point), in the
    # solver's own coordinates (``Reduced.at``): a solver may continue from there
    near: tuple[tuple[float, ...], ...] = ()

    @property
    def ratio(self) -> float:
        """The time ratio."""
        return (math.pi + self.beta) / (math.pi - self.beta)

    @property
    def half(self) -> tuple[float, float]:
        """sin and cos of β/2."""
        return math.sin(self.beta / 2), math.cos(self.beta / 2)

    def box(self, name: str) -> tuple[float, float]:
        """The interval a parameter may take: its fixed value, or its bounds."""
        if name in self.fixed:
            return self.fixed[name], self.fixed[name]
        return self.bounds[name]

    def allows(self, name: str, x: float) -> bool:
        """Whether a parameter set by the targets and fixed parts may take the value x: any
        value, unless the caller bounded it."""
        return name not in self.explicit or within(x, self.bounds[name])

    def shown(self, x: float) -> str:
        """A length in stroke units, in the caller's unit, for a message."""
        return f"{x * self.stroke:g}"


@dataclass(frozen=True)
class Reduced:
    """A reduced solver's answer: local optima (stroke units, every relevant parameter of the
    variant, fixed ones included), best first or not, and whether it is exact."""

    designs: list[dict[str, float]] = field(default_factory=list)
    exact: bool = True
    at: tuple[tuple[float, ...], ...] = ()  # where the solver found them, its coordinates


def unreachable(what: str) -> Unreachable:
    """Fixed parts that no design with the targets can have, with the reason."""
    return Unreachable("FIXED_PARTS_CONTRADICT_TARGETS", what)


def judge(p: Problem, facts: Callable[[dict], dict], design: dict[str, float]) -> None:
    """Raise when fixed parts that over-determine a design (more fixed than the targets leave
    free) miss the targets: by the type's closed forms, to the verification's tolerance."""
    f = facts(design)
    beta = abs(float(f["beta"]))
    got = {"time ratio": ((math.pi + beta) / (math.pi - beta), p.ratio),
           "stroke": (float(f["stroke"]) * p.stroke, p.stroke)}  # fmt: skip
    missed = [
        "{} {}, not {}".format(what, *differ(value, want))
        for what, (value, want) in got.items()
        if not agree(value, want)
    ]
    if missed:
        raise unreachable(f"the fixed parts give {' and '.join(missed)} (to a relative {TOL:g})")


def within(x: float, box: tuple[float, float]) -> bool:
    """lo ≤ x ≤ hi, to rounding (a value built on its bound)."""
    return box[0] * (1 - 1e-12) <= x <= box[1] * (1 + 1e-12)


def differ(a: float, b: float) -> tuple[str, str]:
    """a and b printed with the fewest significant digits, at least 9, that tell them apart."""
    for digits in range(9, 18):
        x, y = f"{a:.{digits}g}", f"{b:.{digits}g}"
        if x != y or a == b:
            return x, y
    return repr(a), repr(b)


def agree(got: float, want: float) -> bool:
    """Whether a value the fixed parts give meets its target, to the verification's tolerance."""
    return abs(got - want) <= TOL * abs(want)


def clip(x: float, lo: float, hi: float) -> float:
    return min(max(x, lo), hi)


def intersect(*intervals: tuple[float, float]) -> tuple[float, float] | None:
    lo = max(a for a, _ in intervals)
    hi = min(b for _, b in intervals)
    return (lo, hi) if lo <= hi else None


# A point's local model: the values of a problem's rows (the objective, then the equalities),
# their gradients and their Hessians, in Python floats; None where the point is not a design
Taylor = tuple[list[float], list[list[float]], list[list[list[float]]]]


def newton(
    local: Callable[[list[float]], Taylor | None],
    x0: np.ndarray,
    n_eq: int,
    iters: int = 30,
    keep: list | None = None,
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


def differences(fn: Callable[[np.ndarray], np.ndarray], d: int, h: float = 1e-5):
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


def _step(t: Taylor, d: int, n_eq: int, nu, it: int):
    """A Newton step from a point's local model: (step, multipliers), or (None, _)."""
    vals, grads, hess = t
    if d == 2 and n_eq == 1:  # the common case (a size on a bound), written out
        return _step_2_1(vals, grads, hess, nu)
    g, jac = grads[0], grads[1 : 1 + n_eq]
    eq = vals[1 : 1 + n_eq]
    if n_eq == d:  # the equalities alone fix the point: quadratic convergence or none
        if it > 12:
            return None, nu
        return _solve(jac, [-e for e in eq]), nu
    if nu is None:  # least-squares multipliers: jac jacᵀ ν = −jac g
        jjt = [[_dot(a, b) for b in jac] for a in jac]
        nu = _solve(jjt, [-_dot(a, g) for a in jac]) if n_eq else []
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
    sol = _solve(kkt, rhs)
    if sol is None:
        return None, None
    return sol[:d], [a + b for a, b in zip(nu, sol[d:], strict=True)]


def _step_2_1(vals, grads, hess, nu):
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
    sol = _solve3([[s00 + n * r00, s01 + n * r01, a0], [s01 + n * r01, s11 + n * r11, a1],
                   [a0, a1, 0.0]], [-g0 - a0 * n, -g1 - a1 * n, -vals[1]])  # fmt: skip
    if sol is None:
        return None, None
    return sol[:2], [n + sol[2]]


def _solve3(a: list[list[float]], b: list[float]) -> list[float] | None:
    """``_solve`` for three unknowns, unrolled: the same pivots and operations."""
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


def _solve(a: list[list[float]], b: list[float]) -> list[float] | None:
    """x with a x = b, by Gaussian elimination with partial pivoting (LAPACK's getrf/getrs
    for a handful of unknowns); None where a pivot is exactly zero (a singular system)."""
    n = len(b)
    if n == 3:
        return _solve3(a, b)
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


def rod(p: Problem, name: str, height: str | None, arm, half, cos_other):
    """The connecting rod ``name`` (and its path's placement ``height``) from a pin at ``arm``
    from its pivot to a straight path: (length l, placement h, the rod's worst cos μ), arrays;
    l is NaN where the bounds allow no rod.

    A pin that swings ±``half`` about the path's normal (``height`` given) transmits worst at
    mid-swing or at the swing's ends, where its offset from the path is g1 = |h − arm| or
    g2 = |h − arm x|, x = cos(half). The slider moves one way over the swing (so the swing's
    ends are its dead centres, as the closed forms take them) exactly when g2 ≤ x l: at the
    ends the rod may not lean further from the path's normal than the pin's own turn (kept
    ``ONE_WAY`` from it). The shortest rod with worst cos ≤ c is then max(g1/c, g2/m),
    m = min(c, x − ONE_WAY), least at h = arm (m + c x)/(m + c) (the midpoint when x > c).
    With max transmission, c is ``cos_other``, the other joints' worst cos: a rod that cannot
    transmit as well within its upper bound sits there, h at the midpoint (the least worst
    offset) as far as the one way allows; else the shortest rod that transmits no worse (ties
    go to the smaller design).
    With min size c is cos(bound). A pin that turns fully about a centre on the path
    (``height`` None) needs l > arm, and transmits worst at w = arm.
    """
    lo, hi = p.box(name)
    c = p.cos_bound if p.objective == MIN_SIZE else cos_other
    c = np.asarray(c, dtype=float) + 0 * np.asarray(arm, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        if height is None:
            h, w = np.full(np.shape(c), np.nan), np.asarray(arm, dtype=float) + 0 * c
            short = np.maximum(np.maximum(lo, w / c), w + STRICT)
            limited = hi + 0 * c
        else:
            x = np.cos(half)
            # no rod moves the slider one way past a swing of ±90° (less the margin)
            m = np.where(x > ONE_WAY, np.minimum(c, x - ONE_WAY), np.nan)
            fixed, box = p.fixed.get(height), p.bounds.get(height)

            def place(h):  # the caller's placement, or one within its bounds
                return fixed + 0 * h if fixed is not None else np.clip(h, *box)

            # the shortest rod with worst cos ≤ c; none to find where c = 0 (nothing else
            # limits the transmission: the rod sits at its upper bound)
            positive = c > 0
            h = place(np.where(positive, arm * (m + c * x) / np.where(positive, m + c, 1.0), arm))
            g1, g2 = np.abs(h - arm), np.abs(h - arm * x)
            short = np.where(positive, np.maximum(lo, np.maximum(g1 / c, g2 / m)), np.inf)
            # at the upper bound: the midpoint, moved as little as the one way needs
            lean = (x - ONE_WAY) * hi  # the most the one way allows at the upper bound
            mid = place(np.clip(arm * (1 + x) / 2, arm * x - lean, arm * x + lean))
            limited = np.where(np.abs(mid - arm * x) <= lean * (1 + 1e-12), hi, np.nan)
            if p.objective != MIN_SIZE:
                h = np.where(short <= hi, h, mid)
            w = np.maximum(np.abs(h - arm), np.abs(h - arm * x))
        length = short if p.objective == MIN_SIZE else np.where(short <= hi, short, limited)
        length = np.where(length <= hi * (1 + 1e-12), np.minimum(length, hi), np.nan)
        return length, h, w / length
