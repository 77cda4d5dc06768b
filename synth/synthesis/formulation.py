"""Registry → symbolic NLP for one (type, variant, free set, objective). No solver options here.

Variables are the free parameters divided by the stroke (the design is synthesised at stroke 1
and scaled at the end). The NLP parameters are the fixed values (also divided by the stroke),
the target time ratio and cos of the transmission bound, so one built solver serves every
request with the same structure. Every equation comes from the registry: the type's closed
forms (``facts``) give time ratio, stroke and the transmission cosines, its conditions' margins
give the validity constraints.

Constraints (all smooth):

- stroke = 1;
- time ratio, through the stroke-angle excess β = π(TR − 1)/(TR + 1) (bounded, unlike TR, and
  better conditioned near the Grashof limits): (β² − β*²)/(2β*) = 0 accepts either sign of the
  closed form's β (the circuit's orientation) and reads ±(β − β*) near a root;
- −cos μ_bound ≤ c_k ≤ cos μ_bound for every transmission cosine term;
- every validity margin term ≥ 0 (≥ ``STRICT`` for strict conditions), and the closed forms'
  own domain (``one_way``: a slider that a rod drives from a swinging pin moves one way over
  each swing) ≥ ``ONE_WAY``.

A row that does not depend on the variables (fixed parts that set the stroke, the scotch yoke's
β ≡ 0) is left out of the NLP: a zero Jacobian row makes the equality system rank-deficient.
It is a condition on the NLP parameters instead (``Formulation.holds``), checked before solving.

Objectives: ``max_transmission_angle`` minimises t ≥ |c_k| (an epigraph variable) plus
``TIE`` × size, so that a family of designs with the same best angle (a slot drive: 90° for
every design) resolves to its smallest mechanism; ``min_size`` minimises the sum of link
lengths. The diagnostics ``max_time_ratio`` and
``min_time_ratio`` drop the time-ratio equality and push β² up or down.

A type without closed forms (``facts`` None) is formulated from its kinematics alone: two
more variables, the crank angles θa of the slider's least and θa + δ of its greatest position,
with ds/dθ = 0 at both (d²s/dθ² ≥ 0 and ≤ 0: a minimum and a maximum), the stroke
s(θa + δ) − s(θa) and β = δ − π (the slow stroke takes π + |β|). The transmission cosines are
taken at ``SAMPLES`` crank angles, NLP parameters, and at one more per joint, where the
solver puts each joint's worst angle as the analysis finds it and solves again (an exchange
method for the constraint over the whole turn: ``solve.multistart``).
"""

from __future__ import annotations

import threading
from dataclasses import dataclass
from functools import cache
from typing import Any

import casadi as ca
import numpy as np

from .. import targets
from ..mechanisms import Mechanism, get
from ..mechanisms.reduced import ONE_WAY, STRICT
from ..targets import MAX_TRANSMISSION, MIN_SIZE

SOLVED = (MAX_TRANSMISSION, MIN_SIZE)  # the objectives IPOPT solves on the formulation
DIAGNOSTICS = ("max_time_ratio", "min_time_ratio")
TIE = 1e-7  # weight of size against |cos μ| (costs < 1e-5° of transmission angle)
SAMPLES = 64  # transmission samples per turn where a type has no closed forms


def relevant(m: Mechanism, variant: frozenset[str]) -> tuple[str, ...]:
    """The parameters the variant's kinematics depend on (a slot drive ignores ram_height)."""
    return _relevant(m.type, variant)


@cache
def _relevant(mtype: str, variant: frozenset[str]) -> tuple[str, ...]:
    # a symbolic dependency check (~5 ms): once per type and variant, not once per request
    m = get(mtype)
    th = ca.SX.sym("th")
    sym = {q.name: ca.SX.sym(q.name) for q in m.parameters}
    p = {k: (0.0 if k in variant else v) for k, v in sym.items()}
    out = ca.vertcat(m.position(p, th), *m.transmission(p, th).values())
    return tuple(k for k in m.names if k not in variant and ca.depends_on(out, sym[k]))


@dataclass(frozen=True)
class Formulation:
    mtype: str
    variant: frozenset[str]
    free: tuple[str, ...]
    fixed: tuple[str, ...]
    objective: str
    nlp: dict[str, ca.SX]  # x, p, f, g for nlpsol
    lbg: np.ndarray
    ubg: np.ndarray
    n_extra: int  # variables after the free parameters (θa and δ without closed forms, t)
    extra_lb: np.ndarray  # their bounds
    extra_ub: np.ndarray
    # the transmission's sample angles (NLP parameters after the time ratio and cos of the
    # bound; none with closed forms), the last one per joint kept for its worst angle
    angles: np.ndarray
    joints: int
    equalities: ca.Function  # (x, p) -> (residuals, Jacobian): for polishing
    constant: ca.Function  # p -> the rows that do not depend on x
    constant_lb: np.ndarray
    constant_ub: np.ndarray

    def holds(self, p: np.ndarray, tol: float = 1e-9) -> bool:
        """Whether the rows left out of the NLP hold for parameters ``p``."""
        v = np.asarray(self.constant(p)).ravel()
        return bool(np.all((v >= self.constant_lb - tol) & (v <= self.constant_ub + tol)))


def formulate(
    m: Mechanism, variant: frozenset[str], free: tuple[str, ...], objective: str
) -> Formulation:
    names = relevant(m, variant)
    fixed = tuple(k for k in names if k not in free)
    x = ca.SX.sym("x", len(free))
    fx = ca.SX.sym("fixed", len(fixed))
    tr_t, cos_b = ca.SX.sym("tr"), ca.SX.sym("cos_bound")
    beta_t = targets.beta(tr_t)
    p: dict[str, Any] = {k: 0.0 for k in variant}  # floats and symbols
    p.update({k: x[i] for i, k in enumerate(free)})
    p.update({k: fx[i] for i, k in enumerate(fixed)})
    p.update({k: v for k, v in m.defaults(p).items() if k not in p})  # irrelevant placements
    extra, extra_lb, extra_ub, angles = [], [], [], np.zeros(0)
    dead: list[ca.SX] = []  # the dead centres' second-order rows (kinematics alone), ≥ 0
    if m.facts is not None:
        facts = m.facts(p)
        beta, stroke, cosines = facts.beta, facts.stroke, list(facts.transmission_cos)
        one_way = facts.one_way
    else:
        th, ta, delta = ca.SX.sym("th"), ca.SX.sym("theta_a"), ca.SX.sym("delta")
        extra, extra_lb, extra_ub = [ta, delta], [-ca.inf, 0.0], [ca.inf, 2 * ca.pi]
        s = m.position(p, th)
        ds = ca.jacobian(s, th)
        d2s = ca.jacobian(ds, th)
        at_a, at_b = ([ca.substitute(e, th, t) for e in (s, ds, d2s)] for t in (ta, ta + delta))
        beta, stroke = delta - ca.pi, at_b[0] - at_a[0]
        dead = [at_a[1], at_b[1], at_a[2], -at_b[2]]
        joints = list(m.transmission(p, th).values())
        angles = np.concatenate([np.arange(SAMPLES) * (2 * np.pi / SAMPLES), np.zeros(len(joints))])
        a = ca.SX.sym("angles", angles.size)
        cosines = [ca.substitute(c, th, a[k]) for c in joints for k in range(angles.size)]
        one_way = ()
    size = sum(p[q.name] for q in m.parameters if q.link and q.name not in variant)

    g = [stroke - 1, *dead[:2]]
    lb, ub = [0.0] * len(g), [0.0] * len(g)
    if objective not in DIAGNOSTICS:
        g.append(ca.if_else(beta_t == 0, beta, (beta - beta_t) * (beta + beta_t) / (2 * beta_t)))
        lb.append(0.0)
        ub.append(0.0)
    n_eq = len(g)
    for c in cosines:
        g += [c - cos_b, -c - cos_b]
        lb += [-ca.inf, -ca.inf]
        ub += [0.0, 0.0]
    for term in one_way:  # the closed forms' own domain
        g.append(term)
        lb.append(ONE_WAY)
        ub.append(ca.inf)
    for term in dead[2:]:  # a minimum and a maximum of the slider's position
        g.append(term)
        lb.append(0.0)
        ub.append(ca.inf)
    for cond in m.conditions:
        if cond.applies(variant):
            for term in cond.margin(p):
                g.append(term)
                lb.append(STRICT if cond.strict else 0.0)
                ub.append(ca.inf)

    if objective == MAX_TRANSMISSION and cosines:
        t = ca.SX.sym("t")
        extra, extra_lb, extra_ub = [*extra, t], [*extra_lb, -ca.inf], [*extra_ub, ca.inf]
        for c in cosines:
            g += [c - t, -c - t]
            lb += [-ca.inf, -ca.inf]
            ub += [0.0, 0.0]
        f = t + TIE * size
    elif objective in SOLVED:
        f = size
    else:
        f = (-1 if objective == "max_time_ratio" else 1) * beta**2

    xs = ca.vertcat(x, *extra)
    params = ca.vertcat(fx, tr_t, cos_b, a) if angles.size else ca.vertcat(fx, tr_t, cos_b)
    keep = np.array([ca.depends_on(ca.SX(gi), xs) for gi in g], dtype=bool)
    varying = [gi for gi, k in zip(g, keep, strict=True) if k]
    eqs = ca.vertcat(*(gi for gi, k in zip(g[:n_eq], keep, strict=False) if k))
    lo, hi = np.array(lb, dtype=float), np.array(ub, dtype=float)
    return Formulation(
        mtype=m.type,
        variant=variant,
        free=free,
        fixed=fixed,
        objective=objective,
        nlp={"x": xs, "p": params, "f": f, "g": ca.vertcat(*varying)},
        lbg=lo[keep],
        ubg=hi[keep],
        n_extra=len(extra),
        extra_lb=np.array(extra_lb, dtype=float),
        extra_ub=np.array(extra_ub, dtype=float),
        angles=angles,
        joints=0 if m.facts is not None else len(joints),
        equalities=ca.Function("eq", [xs, params], [eqs, ca.jacobian(eqs, xs)]),
        constant=ca.Function(
            "constant", [params], [ca.vertcat(*(g[i] for i in np.flatnonzero(~keep)))]
        ),
        constant_lb=lo[~keep],
        constant_ub=hi[~keep],
    )


Key = tuple[str, frozenset[str], tuple[str, ...]]
_local = threading.local()


def kept_by(m: Mechanism, variant: frozenset[str], free: tuple[str, ...]) -> Key:
    """What a variant's free set is kept by: its formulation here, its compiled constraints in
    ``screen``."""
    return (m.type, variant, free)


def formulation(m: Mechanism, variant: frozenset[str], free: tuple[str, ...]) -> Formulation:
    """The type's formulation for a variant and its free parameters (its constraints: the
    searches' and the certified search's), once per thread and structure (CasADi functions
    are never shared between threads)."""
    cache: dict[Key, Formulation] = _local.__dict__.setdefault("formulations", {})
    key = kept_by(m, variant, free)
    if key not in cache:
        cache[key] = formulate(m, variant, free, MIN_SIZE)
    return cache[key]
