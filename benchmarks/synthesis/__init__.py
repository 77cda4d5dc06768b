"""The synthesis benchmark: every method on the same targets, verified the same way (``cli``
says how it runs; ``python -m benchmarks.synthesis --help``)."""

import os

os.environ.setdefault("OMP_NUM_THREADS", "1")  # as the Makefile: one thread per process
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

# after the threads are set: numpy reads them when first imported
from .cli import main
from .plot import figure

__all__ = ["figure", "main"]
