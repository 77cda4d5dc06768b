"""IPOPT on a formulation: per-thread solver cache, deterministic multistart, polishing.

A CasADi ``nlpsol`` is never shared between threads (that crashes the process): each thread
builds its own, once per (type, variant, free set, objective). Every solve is bounded in
iterations and by the request's deadline, which an iteration callback checks: no other clock
decides anything, so a request gets the same answer however loaded the machine is, unless its
budget runs out (and then says so). Starts come from a Halton sequence over the bounds (no
clock, no random seed: the same request gives the same starts), lengths spread in log scale.
"""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from typing import Any, cast

import casadi as ca
import numpy as np

from ..analysis.kinematics import analyze
from ..analysis.terms import worst_transmission
from ..errors import SynthError
from ..mechanisms import Mechanism
from ..numerics.halton import halton
from .formulation import Formulation, formulate

MAX_ITER = 200
EXCHANGES = 6  # solves per start where a type's transmission is sampled (``formulation``)
MAX_WALL_S = 60.0  # one solve, a last resort: the request's deadline stops it (``_Deadline``)
DEADLINE_STEP = 20  # iterations between two looks at the deadline (a few ms; 3% of the time)
IPOPT: dict[str, Any] = {
    "print_time": False,
    "show_eval_warnings": False,  # NaN in a line search is handled by IPOPT (it cuts the step)
    "ipopt.print_level": 0,
    "ipopt.sb": "yes",
    "ipopt.max_iter": MAX_ITER,
    "ipopt.max_wall_time": MAX_WALL_S,
    "ipopt.tol": 1e-10,
    "ipopt.constr_viol_tol": 1e-11,
}
_local = threading.local()


@dataclass(frozen=True)
class Built:
    form: Formulation
    solver: ca.Function
    deadline: _Deadline  # the solver's iteration callback (it must outlive the solver)


def built(m: Mechanism, variant: frozenset[str], free: tuple[str, ...], objective: str) -> Built:
    """The formulation and its IPOPT solver, built once per thread and structure."""
    cache: dict[tuple[str, frozenset[str], tuple[str, ...], str], Built] = (
        _local.__dict__.setdefault("solvers", {})
    )
    key = (m.type, variant, free, objective)
    if key not in cache:
        form = formulate(m, variant, free, objective)
        name = f"{m.type}_{objective}"
        stop = _Deadline(f"{name}_deadline", form.nlp)
        options = {**IPOPT, "iteration_callback": stop, "iteration_callback_step": DEADLINE_STEP}
        cache[key] = Built(form, ca.nlpsol(name, "ipopt", form.nlp, options), stop)
    return cache[key]


class _Deadline(ca.Callback):
    """IPOPT's iteration callback: a nonzero answer stops the solve, once ``at`` (monotonic
    seconds, set before each solve) has passed."""

    def __init__(self, name: str, nlp: dict[str, ca.SX]) -> None:
        ca.Callback.__init__(self)
        self.nx, self.ng, self.np = (nlp[k].numel() for k in ("x", "g", "p"))
        self.at = float("inf")
        self.construct(name, {})

    def get_n_in(self) -> int:
        return ca.nlpsol_n_out()

    def get_n_out(self) -> int:
        return 1

    def get_name_in(self, i: int) -> str:
        return ca.nlpsol_out(i)

    def get_name_out(self, i: int) -> str:
        return "stop"

    def get_sparsity_in(self, i: int) -> ca.Sparsity:
        size = {
            "x": self.nx,
            "lam_x": self.nx,
            "g": self.ng,
            "lam_g": self.ng,
            "f": 1,
            "lam_p": self.np,
        }[ca.nlpsol_out(i)]
        return ca.Sparsity.dense(size, 1)

    def eval(self, arg: Sequence[ca.DM]) -> list[int]:
        return [1 if time.monotonic() >= self.at else 0]


def starts(lo: np.ndarray, hi: np.ndarray, log: np.ndarray, n: int) -> np.ndarray:
    """n deterministic points in the box: Halton, log-uniform where ``log`` (positive bounds)."""
    if lo.size == 0:
        return np.zeros((min(n, 1), 0))
    return spread(halton(lo.size, n + 1)[1:], lo, hi, log)  # the corner point 0 skipped


def spread(u: np.ndarray, lo: np.ndarray, hi: np.ndarray, log: np.ndarray) -> np.ndarray:
    """The points u of the unit cube (rows) in the box, log-uniform where ``log``."""
    llo, lhi = np.log(np.where(log, lo, 1.0)), np.log(np.where(log, hi, 1.0))
    return cast(np.ndarray, np.where(log, np.exp(llo + u * (lhi - llo)), lo + u * (hi - lo)))


def multistart(
    b: Built,
    fixed: np.ndarray,
    tr: float,
    cos_bound: float,
    lo: np.ndarray,
    hi: np.ndarray,
    start_points: np.ndarray,
    deadline: float,
) -> Iterator[tuple[int, dict[str, float]]]:
    """Solve from each start until the deadline; yield the converged, polished solutions (the
    free parameters, in stroke units) with the index of their start."""
    form = b.form
    pv = np.concatenate([fixed, [tr, cos_bound], form.angles])
    if not form.holds(pv):
        return  # the fixed parts alone break a constraint: no start can help
    n_free = len(form.free)
    lbx, ubx = np.concatenate([lo, form.extra_lb]), np.concatenate([hi, form.extra_ub])
    x: np.ndarray | None  # None where a solve fails
    for i, x0 in enumerate(start_points):
        if time.monotonic() >= deadline:
            return
        x = np.concatenate([x0, _extra_start(form, fixed, x0)])
        lbg, ubg = _independent(form, x, pv)
        for _ in range(EXCHANGES if form.joints else 1):
            b.deadline.at = deadline
            sol = b.solver(x0=x, p=pv, lbx=lbx, ubx=ubx, lbg=lbg, ubg=ubg)
            status = b.solver.stats()["return_status"]
            if status not in ("Solve_Succeeded", "Solved_To_Acceptable_Level"):
                x = None
                break
            x = polish(form.equalities, np.asarray(sol["x"]).ravel(), pv, lbx, ubx)
            if x is None or not form.joints or not _exchange(form, fixed, x, pv):
                break
        if x is not None:
            yield i, dict(zip(form.free, x[:n_free], strict=True))


def _design(form: Formulation, fixed: np.ndarray, free: np.ndarray) -> dict[str, float]:
    return {
        **dict(zip(form.fixed, fixed, strict=True)),
        **dict(zip(form.free, free, strict=True)),
        **dict.fromkeys(form.variant, 0.0),
    }


def _extra_start(form: Formulation, fixed: np.ndarray, x0: np.ndarray) -> np.ndarray:
    """Starts for the variables after the free parameters: the epigraph's t at 1, and without
    closed forms the start design's dead centres (θa, δ) by its analysis."""
    out = [1.0] * form.n_extra
    if form.angles.size:
        try:
            a = analyze(form.mtype, _design(form, fixed, x0))
            lo, hi = (math.radians(e.crank_angle_deg) for e in (a.extremes.min, a.extremes.max))
            out[:2] = [lo, (hi - lo) % (2 * math.pi)]
        except SynthError:
            out[:2] = [0.0, math.pi]
    return np.array(out)


def _independent(form: Formulation, x: np.ndarray, pv: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The constraints' bounds, with an equality left free where it depends on the others at
    the start x (kinematics alone: a symmetric linkage's second dead centre follows from its
    first at time ratio 1, and IPOPT stalls on the redundant row); tried in the order stroke,
    time ratio, then the dead centres. With closed forms, the formulation's own."""
    if not form.angles.size:
        return form.lbg, form.ubg
    jac = np.asarray(form.equalities(x, pv)[1])
    if not np.all(np.isfinite(jac)):
        return form.lbg, form.ubg
    n = jac.shape[0]
    order = [0, n - 1, *range(1, n - 1)] if n > 3 else list(range(n))
    kept: list[int] = []
    tol = 1e-9 * max(1.0, float(np.abs(jac).max()))
    for i in order:
        if np.linalg.matrix_rank(jac[[*kept, i]], tol=tol) > len(kept):
            kept.append(i)
    lbg, ubg = form.lbg.copy(), form.ubg.copy()
    free = [i for i in range(n) if i not in kept]
    lbg[free], ubg[free] = -np.inf, np.inf
    return lbg, ubg


def _exchange(form: Formulation, fixed: np.ndarray, x: np.ndarray, pv: np.ndarray) -> bool:
    """Put each joint's worst angle (the analysis's, of the solution x) among the sampled
    angles ``pv`` holds; whether any moved (then the solve runs again from x)."""
    try:
        worst = worst_transmission(form.mtype, _design(form, fixed, x[: len(form.free)]))
    except SynthError:
        return False
    slots = pv[pv.size - form.joints :]
    moved = any(abs(w - s) > 1e-14 for w, s in zip(worst, slots, strict=True))
    slots[:] = worst
    return moved


def polish(
    eq: ca.Function, x: np.ndarray, pv: np.ndarray, lo: np.ndarray, hi: np.ndarray
) -> np.ndarray | None:
    """A few minimum-norm Newton steps onto the equalities (IPOPT stops at ~1e-10), every
    variable within its bounds."""
    for _ in range(4):
        r, jac = (np.asarray(v) for v in eq(x, pv))
        r = r.ravel()
        if np.max(np.abs(r), initial=0.0) <= 1e-15:
            break
        step, *_ = np.linalg.lstsq(jac, r, rcond=None)
        x = np.clip(x - step, lo, hi)
    return x if np.all(np.isfinite(x)) else None
