"""Test-session settings, set before the app is imported."""

import os

# schemathesis generates requests up to the schema's limits: keep each synthesis short here
os.environ.setdefault("SYNTH_MAX_BUDGET_MS", "1000")
