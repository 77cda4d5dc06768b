"""The synthesis methods compared on the same targets; each maps a target to candidate designs.

- ``ours``: ``synth.synthesize`` as shipped.
- Alternatives we weighed, patched in for the call and restored afterwards (synth unchanged):
  no fast paths (every type's ``inverse`` removed), multistart sizes 1, 4 and 16, and CasADi's
  ``sqpmethod`` (qpsol ``qrqp``, exact or limited-memory Hessian) in place of IPOPT.
- Peers on the same NLP (``synth.formulation``: same variables, bounds, objective and
  constraints, per structural variant, the same valid Halton starts): scipy SLSQP from each
  start, scipy differential evolution once per variant, pylinkage's particle swarm once per
  variant on the L1 exact-penalty function of the NLP (it takes only box bounds). They run
  through synthesis's own ``_ipopt`` with its local solve (``multistart``) swapped for theirs,
  so the problem set-up is shared code, and without a time budget. They return, unverified
  and without synth's Newton polish, what SLSQP reports converged, and the best point of
  evolution and swarm (which have no usable convergence test here).

Candidates are in the caller's units; every method's are verified the same way afterwards.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Iterator
from contextlib import AbstractContextManager, contextmanager
from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np
from scipy.optimize import Bounds, NonlinearConstraint, differential_evolution, minimize

import synth
from synth import synthesis
from synth.formulation import Formulation, formulate, relevant
from synth.mechanisms import _registry, get
from synth.solve import MAX_ITER, Built

Outcome = tuple[list[dict[str, float]], str]  # candidates (caller's units), a note
Method = Callable[[dict[str, Any]], Outcome]
SEED = 6
DE = {"maxiter": 150, "popsize": 15, "tol": 1e-8}  # bounded: ~1 s per variant with its polish
PSO = {"n_particles": 30, "iterations": 60}
PENALTY = 1e3  # weight of the swarm's L1 violation (exact once above the multipliers)


@contextmanager
def patched(owner: Any, **values: Any) -> Iterator[None]:
    """Set attributes of a module or object (or items of a dict) for the duration, then
    restore them."""
    is_dict = isinstance(owner, dict)
    old = {k: owner[k] if is_dict else getattr(owner, k) for k in values}
    try:
        for k, v in values.items():
            owner.__setitem__(k, v) if is_dict else setattr(owner, k, v)
        yield
    finally:
        for k, v in old.items():
            owner.__setitem__(k, v) if is_dict else setattr(owner, k, v)


# --- ours and the alternatives ------------------------------------------------------------


def ours(target: dict[str, Any]) -> Outcome:
    r = synth.synthesize(**target)
    return [dict(c.params) for c in r.candidates], " ".join(i.code for i in r.infeasible)


def ours_with(patch: Callable[[], AbstractContextManager[None]]) -> Method:
    def run(target: dict[str, Any]) -> Outcome:
        with patch():
            return ours(target)

    return run


def no_fast_paths() -> AbstractContextManager[None]:
    reg = _registry._REGISTRY
    return patched(reg, **{k: dataclasses.replace(m, inverse=None) for k, m in reg.items()})


def starts(n: int) -> Callable[[], AbstractContextManager[None]]:
    """n starts for a whole family, n/2 for what a closed form leaves (as 8 and 4 ship)."""
    return lambda: patched(synthesis, STARTS=n, STARTS_LEFTOVER=max(1, n // 2))


SQP = {
    "qpsol": "qrqp",
    "qpsol_options": {"print_iter": False, "print_header": False, "print_info": False,
                      "error_on_fail": False},
    "print_header": False, "print_iteration": False, "print_status": False, "print_time": False,
    "show_eval_warnings": False, "max_iter": MAX_ITER,
}  # fmt: skip
_solvers: dict[tuple, Built] = {}  # the benchmark runs in one thread


def solver(plugin: str, options: dict[str, Any]) -> Callable[[], AbstractContextManager[None]]:
    """Another CasADi nlpsol in place of IPOPT: synth.solve.built with the plugin and options
    swapped (it hard-codes both), its own cache."""

    def build(m, variant: frozenset[str], free: tuple[str, ...], objective: str) -> Built:
        key = (plugin, str(options), m.type, variant, free, objective)
        if key not in _solvers:
            form = formulate(m, variant, free, objective)
            nlpsol = ca.nlpsol(f"{m.type}_{plugin}", plugin, form.nlp, options)
            _solvers[key] = Built(form, _Guarded(nlpsol))  # type: ignore[arg-type]
        return _solvers[key]

    return lambda: patched(synthesis, built=build)


class _Guarded:
    """An nlpsol whose ``stats()`` may raise: casadi 3.8.2's sqpmethod throws "basic_string:
    construction from null is not valid" after some failed solves. Those count as failed
    (and are counted)."""

    raised = 0

    def __init__(self, f: ca.Function) -> None:
        self.f = f

    def __call__(self, **kwargs: Any) -> dict:
        return self.f(**kwargs)

    def stats(self) -> dict:
        try:
            return self.f.stats()
        except RuntimeError:
            _Guarded.raised += 1
            return {"return_status": "stats() raised"}


# --- peers on the same NLP ----------------------------------------------------------------


@dataclass(frozen=True)
class Nlp:
    """One formulation as numeric functions of (x, p), x columns (several at once)."""

    form: Formulation
    f: ca.Function
    grad_f: ca.Function
    g: ca.Function
    jac_g: ca.Function

    def violation(self, x: np.ndarray, pv: np.ndarray) -> np.ndarray:
        g = self.g(x, pv).full()
        lb, ub = self.form.lbg[:, None], self.form.ubg[:, None]
        return np.sum(np.maximum(lb - g, 0) + np.maximum(g - ub, 0), axis=0)


_nlps: dict[tuple, Nlp] = {}


def nlp(form: Formulation) -> Nlp:
    key = (form.mtype, form.variant, form.free, form.objective)
    if key not in _nlps:
        x, p, f, g = (form.nlp[k] for k in ("x", "p", "f", "g"))
        _nlps[key] = Nlp(
            form,
            ca.Function("f", [x, p], [f]),
            ca.Function("grad_f", [x, p], [ca.gradient(f, x)]),
            ca.Function("g", [x, p], [g]),
            ca.Function("jac_g", [x, p], [ca.jacobian(g, x)]),
        )
    return _nlps[key]


# A local solve with synth.solve.multistart's signature: (built, fixed values, TR, cos bound,
# lower and upper bounds of the free lengths, start points, deadline) -> free lengths (stroke
# units) of each converged solution.
LocalSolve = Callable[..., Iterator[dict[str, float]]]


def on_nlp(local: LocalSolve) -> Method:
    """A peer on synthesis's NLP: every structural variant the request allows, its bounds and
    valid starts from synth, the local solves by ``local``; no fast path, no verification."""

    def run(target: dict[str, Any]) -> Outcome:
        spec = synthesis._spec(target["mechanisms"][0], 0)
        m = get(spec.type)
        t = synthesis.Targets(
            target["time_ratio"], target["stroke"], target["min_transmission_angle_deg"],
            target.get("objective", "max_transmission_angle"), math.inf,
        )  # fmt: skip
        out = []
        with patched(synthesis, multistart=local):
            for variant in synthesis._variants(m, spec):
                names = relevant(m, variant)
                fixed = {k: v for k, v in spec.fixed.items() if k in names}
                free = tuple(k for k in names if k not in fixed)
                found = (
                    synthesis._ipopt(
                        m, variant, free, fixed, spec, t, synthesis.STARTS, t.objective
                    )
                    if free
                    else [{}]
                )
                out += [{**spec.fixed, **x, **dict.fromkeys(variant, 0.0)} for x in found]
        return out, ""

    return run


def _box(form: Formulation, lo: np.ndarray, hi: np.ndarray, extra: tuple[float, float]) -> Bounds:
    """The free lengths' bounds, then the epigraph variable's (``extra``)."""
    k = form.n_extra
    return Bounds(np.r_[lo, [extra[0]] * k], np.r_[hi, [extra[1]] * k])


def _parameters(fixed: np.ndarray, tr: float, cos_bound: float) -> np.ndarray:
    return np.concatenate([fixed, [tr, cos_bound]])  # as synth.solve.multistart


def _solution(form: Formulation, x: np.ndarray) -> dict[str, float]:
    return dict(zip(form.free, np.asarray(x).ravel()[: len(form.free)], strict=True))


def slsqp(b: Built, fixed, tr, cos_bound, lo, hi, start_points, deadline) -> Iterator[dict]:
    """scipy SLSQP from each start, with exact gradients and Jacobians."""
    fn, pv = nlp(b.form), _parameters(fixed, tr, cos_bound)
    lb, ub = b.form.lbg, b.form.ubg
    eq = lb == ub
    low, up = np.isfinite(lb) & ~eq, np.isfinite(ub) & ~eq

    def g(x):
        v = fn.g(x, pv).full().ravel()
        return v[eq] - lb[eq], np.r_[v[low] - lb[low], ub[up] - v[up]]

    def jac(x):
        j = fn.jac_g(x, pv).full()
        return j[eq], np.r_[j[low], -j[up]]

    constraints = [
        {"type": "eq", "fun": lambda x: g(x)[0], "jac": lambda x: jac(x)[0]},
        {"type": "ineq", "fun": lambda x: g(x)[1], "jac": lambda x: jac(x)[1]},
    ]
    box = _box(b.form, lo, hi, (-np.inf, np.inf))
    for x0 in start_points:
        r = minimize(
            lambda x: float(fn.f(x, pv)),
            np.r_[x0, [1.0] * b.form.n_extra],  # as synth.solve.multistart
            jac=lambda x: fn.grad_f(x, pv).full().ravel(),
            method="SLSQP",
            bounds=box,
            constraints=constraints,
            options={"maxiter": MAX_ITER, "ftol": 1e-10},
        )
        if r.success:
            yield _solution(b.form, r.x)


def evolution(b: Built, fixed, tr, cos_bound, lo, hi, start_points, deadline) -> Iterator[dict]:
    """scipy differential evolution once over the box: seeded, bounded, its default polish
    (trust-constr) given the constraints' Jacobian. Its best point is returned whatever its
    status: DE calls a point feasible only at zero violation, which equalities never reach."""
    fn, pv = nlp(b.form), _parameters(fixed, tr, cos_bound)

    def columns(f: ca.Function) -> Callable[[np.ndarray], np.ndarray]:
        """x (n, S) -> (rows, S), S = 0 when no member is feasible; x (n,) -> (rows,) (polish)"""

        def call(x: np.ndarray) -> np.ndarray:
            out = np.reshape(f(x, pv).full() if x.size else [], (f.size1_out(0), -1))
            return out if x.ndim == 2 else out.ravel()

        return call

    constraint = NonlinearConstraint(
        columns(fn.g), b.form.lbg, b.form.ubg, jac=lambda x: fn.jac_g(x, pv).full()
    )
    try:
        r = differential_evolution(
            lambda x: columns(fn.f)(x)[0],
            _box(b.form, lo, hi, (0.0, 1.0)),  # the epigraph t = max |cos μ| ∈ [0, 1]
            constraints=constraint,
            seed=SEED,
            vectorized=True,
            updating="deferred",
            **DE,
        )
    except ValueError:  # trust-constr refuses more equalities than variables
        return
    yield _solution(b.form, r.x)


def swarm(b: Built, fixed, tr, cos_bound, lo, hi, start_points, deadline) -> Iterator[dict]:
    """pylinkage's particle swarm once over the box, on f + PENALTY × the L1 violation."""
    from pylinkage.optimization import particle_swarm_optimization

    fn, pv = nlp(b.form), _parameters(fixed, tr, cos_bound)
    box = _box(b.form, lo, hi, (0.0, 1.0))

    def score(_linkage, dims, _positions) -> float:
        x = np.asarray(dims)
        return float(fn.f(x, pv)) + PENALTY * float(fn.violation(x, pv)[0])

    rng = np.random.default_rng  # pylinkage 1.3 seeds its swarm from the clock only
    with patched(np.random, default_rng=lambda *a: rng(*(a or (SEED,)))):
        best = particle_swarm_optimization(
            score, _NoLinkage(), dimensions=len(box.lb), bounds=(box.lb, box.ub),
            order_relation=min, verbose=False, **PSO,
        )  # fmt: skip
    yield _solution(b.form, best.dimensions[0])


class _NoLinkage:
    """The swarm needs a linkage only for its joints' positions: this problem has none."""

    def get_coords(self) -> list:
        return []


METHODS: dict[str, Method] = {
    "ours": ours,
    "ours_no_fast_paths": ours_with(no_fast_paths),
    "ours_starts_1": ours_with(starts(1)),
    "ours_starts_4": ours_with(starts(4)),
    "ours_starts_16": ours_with(starts(16)),
    "ours_sqpmethod": ours_with(solver("sqpmethod", SQP)),
    "ours_sqpmethod_bfgs": ours_with(
        solver("sqpmethod", {**SQP, "hessian_approximation": "limited-memory"})
    ),
    "scipy_slsqp": on_nlp(slsqp),
    "scipy_de": on_nlp(evolution),
    "pylinkage_pso": on_nlp(swarm),
}
QUICK = (
    "ours",
    "ours_no_fast_paths",
    "ours_starts_1",
    "ours_sqpmethod_bfgs",
    "scipy_slsqp",
    "scipy_de",
    "pylinkage_pso",
)
