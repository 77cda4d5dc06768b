"""The REST service over ``synth`` (FastAPI): ``api.main:app``."""
