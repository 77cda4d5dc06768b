"""``python -m benchmarks.synthesis``: the synthesis benchmark (``cli``)."""

import sys

from .cli import main

main(sys.argv[1:])
