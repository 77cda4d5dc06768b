"""IPOPT on a formulation: per-thread solver cache, deterministic multistart, polishing.

A CasADi ``nlpsol`` is never shared between threads (that crashes the process): each thread
builds its own, once per (type, variant, free set, objective). Every solve is bounded in
iterations and by the request's deadline, which an iteration callback checks: no other clock
decides anything, so a request gets the same answer however loaded the machine is, unless its
budget runs out (and then says so). Starts come from a Halton sequence over the bounds (no
clock, no random seed: the same request gives the same starts), lengths spread in log scale.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Iterator
from dataclasses import dataclass

import casadi as ca
import numpy as np
from scipy.stats import qmc

from .formulation import Formulation, formulate
from .mechanisms import Mechanism

MAX_ITER = 200
MAX_WALL_S = 60.0  # one solve, a last resort: the request's deadline stops it (``_Deadline``)
DEADLINE_STEP = 20  # iterations between two looks at the deadline (a few ms; 3% of the time)
IPOPT = {
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
    cache: dict = _local.__dict__.setdefault("solvers", {})
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

    def __init__(self, name: str, nlp: dict) -> None:
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
        size = {"x": self.nx, "lam_x": self.nx, "g": self.ng, "lam_g": self.ng, "f": 1,
                "lam_p": self.np}[ca.nlpsol_out(i)]  # fmt: skip
        return ca.Sparsity.dense(size, 1)

    def eval(self, arg):
        return [1 if time.monotonic() >= self.at else 0]


def starts(lo: np.ndarray, hi: np.ndarray, log: np.ndarray, n: int) -> np.ndarray:
    """n deterministic points in the box: Halton, log-uniform where ``log`` (positive bounds)."""
    if lo.size == 0:
        return np.zeros((min(n, 1), 0))
    u = qmc.Halton(d=lo.size, scramble=False).random(n + 1)[1:]  # skip the corner point 0
    llo, lhi = np.log(np.where(log, lo, 1.0)), np.log(np.where(log, hi, 1.0))
    return np.where(log, np.exp(llo + u * (lhi - llo)), lo + u * (hi - lo))


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
    pv = np.concatenate([fixed, [tr, cos_bound]])
    if not form.holds(pv):
        return  # the fixed parts alone break a constraint: no start can help
    n_free = len(form.free)
    lbx = np.concatenate([lo, [-np.inf] * form.n_extra])
    ubx = np.concatenate([hi, [np.inf] * form.n_extra])
    for i, x0 in enumerate(start_points):
        if time.monotonic() >= deadline:
            return
        x0 = np.concatenate([x0, [1.0] * form.n_extra])
        b.deadline.at = deadline
        sol = b.solver(x0=x0, p=pv, lbx=lbx, ubx=ubx, lbg=form.lbg, ubg=form.ubg)
        status = b.solver.stats()["return_status"]
        if status not in ("Solve_Succeeded", "Solved_To_Acceptable_Level"):
            continue
        x = polish(form.equalities, np.asarray(sol["x"]).ravel()[:n_free], pv, lo, hi)
        if x is not None:
            yield i, dict(zip(form.free, x, strict=True))


def polish(
    eq: ca.Function, x: np.ndarray, pv: np.ndarray, lo: np.ndarray, hi: np.ndarray
) -> np.ndarray | None:
    """A few minimum-norm Newton steps onto the equalities (IPOPT stops at ~1e-10)."""
    for _ in range(4):
        r, jac = (np.asarray(v) for v in eq(x, pv))
        r = r.ravel()
        if np.max(np.abs(r), initial=0.0) <= 1e-15:
            break
        step, *_ = np.linalg.lstsq(jac, r, rcond=None)
        x = np.clip(x - step, lo, hi)
    return x if np.all(np.isfinite(x)) else None
