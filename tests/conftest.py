"""Test-session settings, set before the app is imported; hypothesis profiles."""

import os

from hypothesis import HealthCheck, settings

# schemathesis generates requests up to the schema's limits: keep each synthesis short here
os.environ.setdefault("SYNTH_MAX_BUDGET_MS", "1000")
# no background warm-up competing for the two cores with the test that runs meanwhile (a
# motion objective's 1 s budget ran out under it); the servers the tests start warm up
os.environ.setdefault("SYNTH_WARM", "0")

# `make test`: a bounded, reproducible subset; `make stress`: the long run (HYPOTHESIS_PROFILE)
common = {"deadline": None, "suppress_health_check": list(HealthCheck)}
settings.register_profile("default", max_examples=40, derandomize=True, database=None, **common)
settings.register_profile("few", max_examples=10, derandomize=True, database=None, **common)
settings.register_profile("medium", max_examples=1_000, **common)
settings.register_profile("stress", max_examples=10_000, **common)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "default"))

# the toy types register themselves on import: only library/test_seventh_type.py's own process,
# which names them in SYNTH_TYPES, may collect them (the doctests would import them here too)
if not os.environ.get("SYNTH_TYPES"):
    collect_ignore = ["support/toy_type.py", "support/toy_checks.py"]
