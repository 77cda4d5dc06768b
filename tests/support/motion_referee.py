"""An independent global search for the searched objectives: the referee of synthesize()'s
``uniform_cutting_speed``, ``min_peak_acceleration`` and ``min_peak_torque``.

It searches the design space through tests/support/globalsearch.py's own families (every design
meets the time ratio and stroke by construction, sharing no formula with synth; a fixed part is
an equality that family solves for one of its variables), by differential evolution from several
seeds per family and branch, polished by Nelder–Mead. The families set a four-bar's scale
to its smallest in bounds (the slider's motion does not depend on it); for the least peak
torque with massive links, which it does change, the scale is one more variable. The measure
of a design is the analysis's (synth.analyze, include motion, or with the load), which
tests/referees/test_quality.py and test_loads.py check against independent computations on 200
designs per type; the search is what is independent.

The feasible set is the stated problem's, which keeps a slider driven through a rod from a
swinging pin ``ONE_WAY`` (in the cosine) away from dwelling at its dead centre (the docs:
there the dead centres are located only to ~1e-6): the referee reads that margin off the
type's closed-form record (``facts``' one_way terms), a statement of the problem, not of the
search.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
from scipy.optimize import differential_evolution, minimize

import synth

from . import globalsearch as gs

PENALTY = 1e3
ONE_WAY = 1e-3  # the problem's margin from the dwell limit


@dataclass
class Best:
    value: float
    params: dict[str, float] | None


def measure(a, objective: str) -> float:
    if objective == "min_peak_torque":
        return a.loads.torque.max
    if objective == "uniform_cutting_speed":
        return a.motion.working_speed_fluctuation.middle
    p = a.motion.peak_acceleration
    return max(p.working_stroke, p.return_stroke)


def search(
    mtype: str,
    objective: str,
    tr: float,
    bound_deg: float,
    seeds=(0, 1),
    popsize: int = 12,
    maxiter: int = 60,
    fixed: Mapping[str, float] | None = None,
    load=None,
) -> Best:
    """The least measure over every family and branch of ``mtype`` at time ratio ``tr``,
    stroke 1, minimum transmission ≥ ``bound_deg``, within the default bounds; ``fixed``:
    parts kept at their values (stroke 1), the search space then a request's with them
    (``globalsearch.Fix``; each fixed part solved for by a variable of the family); ``load``:
    the load of ``min_peak_torque`` (its lengths' unit the stroke's)."""
    asked = {"load": load} if objective == "min_peak_torque" else {"include": ["motion"]}
    fx = gs.Fix(mtype, tuple(sorted((k, float(v)) for k, v in (fixed or {}).items())))
    m = synth.mechanisms.get(mtype)
    # a four-bar's scale leaves the slider's motion alone, so the families take the smallest;
    # with massive links it changes the torque: searched too (one more variable), unless a
    # fixed link sets it
    links = gs.LINKS.get(mtype, ())
    scaled = bool(links) and load is not None and load.link_mass_per_length > 0
    scaled = scaled and not set(links) & set(fx.fixed)
    top = {k: hi for k, (_, hi) in gs._bounds(mtype, fx).items()}
    best = Best(math.inf, None)
    for fam in gs.FAMILIES[mtype]:
        # the family's designs at the time ratio with the fixed parts, the bound a margin
        # (min_size's feasible set: the goal itself is not used)
        problem = gs._Problem(fam, "min_size", tr, bound_deg, 1.0, fx)
        for branch in range(problem.branches):

            def design(z, problem=problem, branch=branch):
                """The design at the free variables z, and its violation."""
                z = np.clip(z, 0.0, 1.0)
                with np.errstate(all="ignore"):
                    _, viol, d = problem.evaluate(z[None, : problem.dim], branch)
                params = {k: float(v[0]) for k, v in d.params.items()}
                if scaled and np.isfinite(viol[0]):  # from the smallest to the largest in bounds
                    grow = min(top[k] / params[k] for k in links)
                    params |= {k: params[k] * grow ** float(z[-1]) for k in links}
                return params, float(viol[0])

            def value(z, design=design):
                params, violation = design(z)
                if not np.isfinite(violation) or violation > 0:
                    return PENALTY + min(violation, 1e6) if np.isfinite(violation) else 2 * PENALTY
                one_way = m.facts(m.complete(params)).one_way
                short = sum(max(ONE_WAY - float(x), 0.0) for x in one_way)
                if short > 0:
                    return PENALTY + short
                try:
                    a = synth.analyze(mtype, params, **asked)
                except synth.SynthError:
                    return 2 * PENALTY
                if a.reversals != 2:
                    return 2 * PENALTY
                return measure(a, objective)

            dim = problem.dim + scaled
            if dim == 0:  # the fixed parts leave the family no freedom
                f, z = value(np.empty(0)), np.empty(0)
                if f < min(best.value, PENALTY):
                    best = Best(f, design(z)[0])
                continue
            for seed in seeds:
                res = differential_evolution(
                    value,
                    [(0.0, 1.0)] * dim,
                    seed=seed,
                    popsize=popsize,
                    maxiter=maxiter,
                    tol=1e-12,
                    init="sobol",
                    polish=False,
                )
                if res.fun >= PENALTY:
                    continue
                polished = minimize(
                    value,
                    res.x,
                    method="Nelder-Mead",
                    options={"xatol": 1e-12, "fatol": 1e-14, "maxiter": 4000},
                )
                z = polished.x if polished.fun < res.fun else res.x
                f = min(polished.fun, res.fun)
                if f < best.value:
                    best = Best(f, design(z)[0])
    return best


if __name__ == "__main__":  # the referee against synthesize() on one target per type
    import sys
    import time

    tr, bound = 1.6, 20.0
    for mtype in sys.argv[1:] or gs.TYPES:
        for objective in ("uniform_cutting_speed", "min_peak_acceleration"):
            t0 = time.monotonic()
            ref = search(mtype, objective, tr, bound)
            t1 = time.monotonic()
            r = synth.synthesize(
                tr, 1.0, bound, [{"type": mtype}], objective=objective, time_budget_ms=60_000
            )
            ours = r.candidates[0].objective_value if r.candidates else math.inf
            rel = (ours - ref.value) / ref.value
            print(
                f"{mtype:20} {objective:22} referee {ref.value:.10f} ({t1 - t0:.0f} s) "
                f"ours {ours:.10f} ({r.elapsed_ms:.0f} ms) rel {rel:+.2e}",
                flush=True,
            )
