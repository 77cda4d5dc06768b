"""Synthesis benchmark: every method on the same targets, verified the same way.

    python -m benchmarks.synthesis            # all targets and methods, ~9 min on 2 cores
    python -m benchmarks.synthesis --quick    # a smoke run: a few targets, small searches

Targets come from ``benchmarks.targets`` (seeded; feasible or infeasible by construction),
methods from ``benchmarks.methods``. Each method first runs once, untimed, on a case of every
structure (type, fixed parts, feasibility; the swarm and evolution once per type, whose build
costs are negligible beside their runs) so that no timing includes building a solver. Then the
cases run in turn, the types interleaved, every method on a case before the next case (in an
order rotated per case), so that changes in the machine's load touch every method alike.

Every returned candidate is re-analysed by ``synth.analyze`` (root-found dead centres): its
relative time-ratio and stroke errors and its transmission-angle violation (degrees below the
bound), a candidate's error being the largest of the three. A method succeeds on a feasible
target when a candidate's error is ≤ 1e-9, and refuses an infeasible one correctly when none is.
The best verified candidate's minimum transmission angle (every target asks for the largest)
is compared between ours and the generic multistart, target by target (``optimality``).
Ours is run once more per target, untimed, to count its fallbacks to IPOPT.

Prints the summary as markdown tables (``tables``) and writes (``files.write``) the results
to ``--out`` (default ``benchmarks/results``; ``--quick`` writes only where ``--out`` is given).
"""

from __future__ import annotations

import argparse
import warnings
from pathlib import Path
from typing import Any

from synth.synthesis import search

from .. import methods, targets
from ..common import machine
from .files import write
from .run import EVERY, TOL, run
from .stats import GOALS, SAME_ANGLE, goals, optimality, ratios, summary
from .tables import text

QUICK = {"n_feasible": 5, "n_infeasible": 2}
QUICK_BUDGETS = {  # the global searches cut to a smoke test's size
    "DE": {"maxiter": 20, "popsize": 5, "tol": 1e-8, "polish": False},
    "PSO": {"n_particles": 10, "iterations": 10},
}


def settings(names: list[str], sizes: dict[str, int]) -> dict[str, Any]:
    return {
        "methods": names,
        "targets": sizes,
        "seed": targets.SEED,
        "tol": TOL,
        "same_angle": SAME_ANGLE,
        "starts": search.STARTS,
        "de": methods.DE,
        "pso": methods.PSO,
        "pso_penalty": methods.PENALTY,
        "goals": GOALS,
    }


def main(argv: list[str] | None = None) -> dict[str, Any]:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="a few targets, small global searches")
    ap.add_argument("--out", type=Path, help="where to write the results")
    ap.add_argument("--methods", help="comma-separated subset of " + ", ".join(methods.METHODS))
    a = ap.parse_args(argv)
    sizes = (
        QUICK
        if a.quick
        else {"n_feasible": targets.N_FEASIBLE, "n_infeasible": targets.N_INFEASIBLE}
    )
    names = (
        a.methods.split(",") if a.methods else list(methods.QUICK if a.quick else methods.METHODS)
    )
    out = a.out if a.out or a.quick else targets.RESULTS
    cases = targets.cases(**sizes)
    targets.check(cases)
    info = machine()
    with warnings.catch_warnings(), methods.patched(methods, **(QUICK_BUDGETS if a.quick else {})):
        warnings.simplefilter("ignore")  # scipy's and pylinkage's numerical chatter
        config = settings(names, sizes)
        records = run(cases, names, 1 if a.quick else EVERY)
    rows = summary(records)
    result: dict[str, Any] = {"machine": info, "settings": config, "summary": rows}
    if "ours" in names:
        result["ratios"] = ratios(records)
        if "generic" in names:
            result["optimality"] = optimality(records)
        result["goals"] = goals(rows, result["ratios"], result.get("optimality"))
    report = text(result)
    print(report)
    if out:
        write(out, result, records, cases, report)
    return {**result, "records": records}
