"""A seventh type is one module: registered from outside the package (``SYNTH_TYPES`` names
tests/support/toy_type.py), it reaches the analysis, the synthesis by the generic path (no closed
forms, no reduced solver), the API's schemas, /v1/mechanisms and the property tests, with no
other edit. In its own process, so that the rest of the suite sees the six types only."""

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
# the property tests that take any type (those against the brute-force simulation or the
# independent global search know the six types' geometry only), and the toy's own checks
PROPERTY_TESTS = (
    "tests/referees/test_stress.py",
    "tests/library/test_registry.py",
    "tests/library/test_validity.py",
    "tests/referees/test_quality.py",
)
TOYS = ("centred_slider_crank", "offset_slider_crank_generic")


@pytest.mark.long  # tens of seconds: make long (CI runs it), not make test
def test_a_seventh_type_reaches_everything():
    # fewer examples per property than the suite's own (the generic path's IPOPT is slower)
    env = {**os.environ, "SYNTH_TYPES": "tests.support.toy_type", "HYPOTHESIS_PROFILE": "few"}
    out = subprocess.run(
        [
            sys.executable,
            "-m",
            "pytest",
            "-q",
            "-p",
            "no:cacheprovider",
            "-p",
            "no:randomly",
            "tests/support/toy_checks.py",
            *PROPERTY_TESTS,
            "-k",
            " or ".join((*TOYS, "toy_checks")),
        ],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
        timeout=900,
    )
    assert out.returncode == 0, out.stdout[-4000:] + out.stderr[-2000:]
    passed = int(re.search(r"(\d+) passed", out.stdout).group(1))
    # the toy's checks, and per toy type: 3 stress properties, 2 registry tests, the
    # conditions' parameters, sensitivities, envelope
    assert passed >= 14 + 2 * 8, out.stdout[-2000:]
