"""Several designs analysed together (synth.kinematics.analyze_many, a front's inner points)
give what each analysed alone gives, to the bit: the same analyses, and the same errors for
designs that do not run."""

import numpy as np
import pytest

import synth
from synth.errors import SynthError
from synth.kinematics import analyze_many
from synth.mechanisms import all_types

from .designs import random_designs


def alone(mtype, p, **extras):
    try:
        return synth.analyze(mtype, p, **extras)
    except SynthError as e:
        return e


@pytest.mark.parametrize("mtype", all_types())
def test_analyze_many_matches_analyze(mtype):
    rng = np.random.default_rng(3)
    designs = random_designs(mtype, 12, seed=5)
    # a few that do not run: a link stretched past validity, a part missing
    broken = [{k: v * (3.0 if i == 0 else 1.0) for i, (k, v) in enumerate(d.items())}
              for d in designs[:2]]  # fmt: skip
    broken.append({k: v for k, v in list(designs[0].items())[1:]})
    mixed = [*designs, *broken]
    order = rng.permutation(len(mixed))
    mixed = [mixed[i] for i in order]
    for extras in ({}, {"include": ["motion", "envelope"], "tolerance": synth.Tolerance(1e-3)}):
        together = analyze_many(mtype, mixed, **extras)
        for p, a in zip(mixed, together, strict=True):
            b = alone(mtype, p, **extras)
            if isinstance(b, SynthError):
                assert type(a) is type(b) and str(a) == str(b)
            else:
                assert a == b
