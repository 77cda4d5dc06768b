"""Round trips: a random valid design's targets, asked back, give a verified design.

The targets (time ratio, stroke, minimum transmission angle) come from the brute-force
simulation of the design; the request fixes one or two of its parameters and sets the bound a
degree or two below the design's. The design itself meets the request, so at least one
verified candidate must come back, every time.
"""

import numpy as np
import pytest

import synth

from ..support import bruteforce
from ..support.assertions import assert_meets
from ..support.designs import TYPES, random_designs

N = 50


@pytest.mark.parametrize("mtype", TYPES)
def test_round_trip(mtype):
    rng = np.random.default_rng([7, TYPES.index(mtype)])
    failures = []
    for p in random_designs(mtype, N, seed=7):
        full = bruteforce.complete(mtype, p)
        b = bruteforce.simulate(mtype, full)
        names = sorted(p)
        fixed = {
            k: full[k]
            for k in rng.choice(names, size=min(len(names), rng.integers(1, 3)), replace=False)
        }
        bound = max(0.0, b["min_transmission_deg"] - rng.uniform(1.0, 2.0))
        r = synth.synthesize(
            b["time_ratio"], b["stroke"], bound, mechanisms=[{"type": mtype, "fixed": fixed}]
        )
        if not r.candidates:
            failures.append((p, fixed, bound, r.infeasible))
            continue
        for c in r.candidates:
            assert_meets(c, b["time_ratio"], b["stroke"], bound)
            assert all(c.params[k] == v for k, v in fixed.items())
    assert not failures, f"{len(failures)}/{N} without a candidate, e.g. {failures[0]}"
