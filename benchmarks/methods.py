"""The synthesis methods compared on the same targets; each maps a target to candidate designs.

- ``ours``: ``synth.synthesize`` as shipped: each type's exact reduced solver (closed forms,
  bracketed roots, Newton's method in at most two variables), IPOPT only where it cannot
  answer.
- ``generic``: ``synth.synthesize(..., accelerators=False)``, every type solved as if it had no
  reduced solver: cold multistart IPOPT, ``search.STARTS`` (8) Halton starts per structural
  variant. It is the path shipped before the reduced solvers, less the old closed-form fast
  paths: the "before" of the comparison, and the reference for optimality.
- Peers on the same NLP (``synth.synthesis.formulation``: same variables, bounds, objective and
  constraints, per structural variant, the same valid Halton starts): scipy SLSQP from each
  start, scipy differential evolution once per variant, pylinkage's particle swarm once per
  variant on the L1 exact-penalty function of the NLP (it takes only box bounds). They run
  through synth.synthesis.search's own ``ipopt`` with its local solve (``multistart``)
  swapped for theirs, so the problem set-up (variants, fixed parts checked, bounds, starts)
  is shared code, with no reduced solver and no time budget. They return, unverified and
  without synth's Newton polish, what SLSQP reports converged, and the best point of
  evolution and swarm (which have no usable convergence test here).

Candidates are in the caller's units; every method's are verified the same way afterwards.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Any

import casadi as ca
import numpy as np
from scipy.optimize import Bounds, NonlinearConstraint, differential_evolution, minimize

import synth
from synth.mechanisms import get
from synth.synthesis import search
from synth.synthesis.diagnose import forget_ranges
from synth.synthesis.driver import checked_spec
from synth.synthesis.formulation import Formulation, relevant
from synth.synthesis.solve import MAX_ITER, Built, multistart

SEED = 6
DE = {"maxiter": 150, "popsize": 15, "tol": 1e-8}  # bounded: ~1 s per variant with its polish
PSO = {"n_particles": 30, "iterations": 60}
PENALTY = 1e3  # weight of the swarm's L1 violation (exact once above the multipliers)


@dataclass(frozen=True)
class Outcome:
    """What a method returned for one target: candidate designs (caller's units); for synth,
    how each was found (``Candidate.method``) and the codes of its refusals."""

    candidates: list[dict[str, float]]
    how: tuple[str, ...] = ()
    refusals: tuple[str, ...] = ()


Method = Callable[[dict[str, Any]], Outcome]


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


# --- synth: as shipped, and the generic multistart -----------------------------------------


def _synth(target: dict[str, Any], solver: synth.Solver) -> Outcome:
    forget_ranges()  # each refusal pays its whole scan: no range kept from before
    r = synth.synthesize(**target, solver=solver)
    return Outcome(
        [dict(c.params) for c in r.candidates],
        tuple(c.method for c in r.candidates),
        tuple(i.code for i in r.infeasible),
    )


def ours(target: dict[str, Any]) -> Outcome:
    return _synth(target, synth.Solver())


def generic(target: dict[str, Any]) -> Outcome:
    return _synth(target, synth.Solver(accelerators=False))


@dataclass
class Solves:
    """How often IPOPT ran during a call: ``multistart`` calls and the starts it solved."""

    calls: int = 0
    starts: int = 0
    where: list[str] = field(default_factory=list)


def ipopt_solves(target: dict[str, Any]) -> Solves:
    """``ours`` once more, untimed, counting its fallbacks to IPOPT (search and refusals
    alike: both solve locally by the solver's ``local``, here IPOPT counted)."""
    n = Solves()

    def counted(b: Built, *args: Any, **kwargs: Any):
        n.calls += 1
        n.where.append(
            f"{b.form.mtype} {'+'.join(sorted(b.form.variant)) or '-'} {b.form.objective}"
        )
        start_points = args[5] if len(args) > 5 else kwargs["start_points"]
        n.starts += len(start_points)
        yield from multistart(b, *args, **kwargs)

    _synth(target, synth.Solver(local=counted))
    return n


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


# A local solve with synth.synthesis.solve.multistart's signature: (built, fixed values, TR,
# cos bound, lower and upper bounds of the free lengths, start points, deadline) -> (start
# index, free lengths in stroke units) of each converged solution.
LocalSolve = Callable[..., Iterator[tuple[int, dict[str, float]]]]


def on_nlp(local: LocalSolve) -> Method:
    """A peer on synthesis's NLP: every structural variant the request allows whose fixed parts
    can run (as synth checks them), its bounds and valid starts from ``search.ipopt``, the
    local solves by ``local``; no reduced solver, no verification."""

    def run(target: dict[str, Any]) -> Outcome:
        spec = checked_spec(target["mechanisms"][0], 0)
        m = get(spec.type)
        t = search.Targets(
            target["time_ratio"],
            target["stroke"],
            target["min_transmission_angle_deg"],
            target.get("objective", "max_transmission_angle"),
            math.inf,
            synth.Solver(local=_checked(local)),
        )
        out = []
        for parts in search.variants(m, spec):
            if search.fixed_violation(m, parts, spec.fixed):
                continue
            names = relevant(m, parts)
            fixed = {k: v for k, v in spec.fixed.items() if k in names}
            problem = search.build_problem(m, parts, names, fixed, spec, t)
            v = search.Variant(parts, names, fixed, problem, exact=False)
            found = [x for x, _ in search.ipopt(m, v, spec, t, t.objective)]
            out += [
                {**spec.fixed, **x, **dict.fromkeys(parts, 0.0)}
                for x in (found if v.free else [{}])
            ]
        return Outcome(out)

    return run


def _checked(local: LocalSolve) -> LocalSolve:
    """``local``, after the check ``multistart`` makes first: the rows left out of the NLP (they
    do not depend on the variables) hold for the fixed parts."""

    def run(b: Built, fixed, tr, cos_bound, *rest):
        if b.form.holds(_parameters(fixed, tr, cos_bound)):
            yield from local(b, fixed, tr, cos_bound, *rest)

    return run


def _box(form: Formulation, lo: np.ndarray, hi: np.ndarray, extra: tuple[float, float]) -> Bounds:
    """The free lengths' bounds, then the epigraph variable's (``extra``)."""
    k = form.n_extra
    return Bounds(np.r_[lo, [extra[0]] * k], np.r_[hi, [extra[1]] * k])


def _parameters(fixed: np.ndarray, tr: float, cos_bound: float) -> np.ndarray:
    return np.concatenate([fixed, [tr, cos_bound]])  # as synth.synthesis.solve.multistart


def _solution(form: Formulation, x: np.ndarray) -> dict[str, float]:
    return dict(zip(form.free, np.asarray(x).ravel()[: len(form.free)], strict=True))


def slsqp(b: Built, fixed, tr, cos_bound, lo, hi, start_points, deadline) -> Iterator:
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
    for i, x0 in enumerate(start_points):
        r = minimize(
            lambda x: float(fn.f(x, pv)),
            np.r_[x0, [1.0] * b.form.n_extra],  # as synth.synthesis.solve.multistart
            jac=lambda x: fn.grad_f(x, pv).full().ravel(),
            method="SLSQP",
            bounds=box,
            constraints=constraints,
            options={"maxiter": MAX_ITER, "ftol": 1e-10},
        )
        if r.success:
            yield i, _solution(b.form, r.x)


def evolution(b: Built, fixed, tr, cos_bound, lo, hi, start_points, deadline) -> Iterator:
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
    yield 0, _solution(b.form, r.x)


def swarm(b: Built, fixed, tr, cos_bound, lo, hi, start_points, deadline) -> Iterator:
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
            score,
            _NoLinkage(),
            dimensions=len(box.lb),
            bounds=(box.lb, box.ub),
            order_relation=min,
            verbose=False,
            **PSO,
        )
    yield 0, _solution(b.form, best.dimensions[0])


class _NoLinkage:
    """The swarm needs a linkage only for its joints' positions: this problem has none."""

    def get_coords(self) -> list:
        return []


METHODS: dict[str, Method] = {
    "ours": ours,
    "generic": generic,
    "scipy_slsqp": on_nlp(slsqp),
    "scipy_de": on_nlp(evolution),
    "pylinkage_pso": on_nlp(swarm),
}
QUICK = tuple(METHODS)
