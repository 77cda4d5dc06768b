"""Every type's reduced solver against the generic path (cold multistart IPOPT on the same
formulation, ``Solver(accelerators=False)``) on random targets: never a worse optimum, and the same
one to 1e-9 wherever the generic path finds it.

The targets come from random valid designs (tests/support/designs.py, analysed by the independent
brute-force simulator): their time ratio and stroke, a bound somewhere below their
transmission angle, either objective, nothing fixed or one part fixed at the design's value.
A second set bounds a type's optional rod away from zero, so that the rod variant must
answer alone (with everything free the slot drive wins and would hide it).
"""

import zlib

import numpy as np
import pytest

import synth
from synth.mechanisms import all_types, get

from ..support import bruteforce
from ..support.designs import random_designs

GENERIC = synth.Solver(accelerators=False)  # the generic path: the reduced solvers off

# every registered type with a reduced solver (an accelerator the generic path can referee)
ACCELERATED = tuple(t for t in all_types() if get(t).reduced is not None)
N = 50
# the share of a type's targets that must be compared: those the generic path (a local search)
# finds a design for, between 76 % and 100 % of each set
COMPARED = 0.7
SAME = 1e-9  # relative, on the objective


def best(result, objective):
    """The best candidate's objective (larger is better), or None for a refusal."""
    if not result.candidates:
        return None
    c = result.candidates[0]
    return c.min_transmission_angle_deg if objective == "max_transmission_angle" else -c.size


def optional(mtype: str) -> str | None:
    """The part whose zero selects a variant (a slot drive), if the type has one."""
    return next((q.name for q in synth.mechanisms.get(mtype).parameters if q.zero_means), None)


def targets(mtype: str, n: int = N, seed: int = 12):
    rng = np.random.default_rng([seed, zlib.crc32(mtype.encode())])
    for p in random_designs(mtype, n, seed=seed):
        full = bruteforce.complete(mtype, p)
        b = bruteforce.simulate(mtype, full)
        bound = b["min_transmission_deg"] * rng.uniform(0.0, 0.95)
        objective = str(rng.choice(["max_transmission_angle", "min_size"]))
        fixed = {}
        if rng.random() < 0.3:
            name = str(rng.choice(sorted(p)))
            fixed = {name: full[name]}
        yield b["time_ratio"], b["stroke"], bound, objective, fixed


ROD_TYPES = [t for t in ACCELERATED if optional(t)]


@pytest.mark.parametrize("mtype", ACCELERATED)
def test_reduced_solver_matches_the_generic_path(mtype):
    compare(mtype, targets(mtype), N)


@pytest.mark.parametrize("mtype", ROD_TYPES)
def test_the_rod_variant_alone_matches_the_generic_path(mtype):
    rod, n = optional(mtype), N // 2
    cases = []
    for tr, stroke, bound, objective, fixed in targets(mtype, n, seed=13):
        fixed.pop(rod, None)
        cases.append((tr, stroke, bound, objective, fixed, {rod: (0.05 * stroke, 5 * stroke)}))
    compare(mtype, cases, n)


def compare(mtype, cases, n):
    compared, worse, differ, refused = 0, [], [], []
    for tr, stroke, bound, objective, fixed, *bounds in cases:
        spec = [{"type": mtype, "fixed": fixed, "bounds": bounds[0] if bounds else {}}]
        args = (tr, stroke, bound, spec, objective)
        ours = best(synth.synthesize(*args, max_candidates=1), objective)
        generic = best(synth.synthesize(*args, max_candidates=1, solver=GENERIC), objective)
        if generic is None:
            continue
        compared += 1
        if ours is None:
            refused.append(args)
            continue
        gap = (ours - generic) / max(abs(generic), 1.0)
        if gap < -SAME:
            worse.append((args, ours, generic))
        elif gap > SAME:
            differ.append((args, ours, generic))  # the generic path missed the optimum
    assert compared >= COMPARED * n, f"{compared} of {n} targets compared"
    assert not refused, f"refused where the generic path has a design: {refused[:3]}"
    assert not worse, f"{len(worse)} worse than the generic path, e.g. {worse[:3]}"
    # the generic path is a local search: it may miss, but only now and then
    assert len(differ) <= n // 10, f"{len(differ)} better than the generic path: {differ[:3]}"
