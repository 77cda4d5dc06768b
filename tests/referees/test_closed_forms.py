"""The types' closed forms (docs/model.md) agree with the root-found extremes on random designs.

The closed forms (each type's ``facts``) are only used by synthesis; the analysis never reads
them. Here each is checked against ``synth.analyze`` (root finding on ds/dθ), and both are
checked against the brute-force simulation in test_bruteforce_agreement.py.
"""

import math

import pytest

import synth
from synth.mechanisms import get

from ..support.designs import TYPES, random_designs

N = 200


@pytest.mark.parametrize("mtype", TYPES)
def test_closed_forms_match_root_found_extremes(mtype):
    m = get(mtype)
    for p in random_designs(mtype, N, seed=1):
        a = synth.analyze(mtype, p)
        facts = m.facts(a.params)
        beta = abs(float(facts.beta))
        assert a.time_ratio == pytest.approx((math.pi + beta) / (math.pi - beta), rel=1e-9), p
        assert a.stroke == pytest.approx(float(facts.stroke), rel=1e-9), p
        worst = max((abs(float(c)) for c in facts.transmission_cos), default=0.0)
        assert a.transmission.min_deg == pytest.approx(math.degrees(math.acos(worst)), abs=1e-7), p
        if facts.crank_at_max is not None:  # Podhorodeski et al. (2005) eq. (3a): TDC, θ2a
            assert math.radians(a.extremes["max"].crank_angle_deg) == pytest.approx(
                float(facts.crank_at_max), abs=1e-9
            )
