"""``quickreturn`` (and ``python -m synth``): the library from a shell, for people and for build
scripts.

    quickreturn synthesize --time-ratio 1.8 --stroke 250 --bound 40 --type crank_shaper \\
        --fix crank=60
    quickreturn analyze whitworth -p crank=75 -p pivot_distance=50 -p lever=150 \\
        -p connecting_rod=200 --include motion
    quickreturn sweep crank_shaper -p crank=120 -p pivot_distance=240 -p lever=450 \\
        --vary crank --start 100 --stop 200
    quickreturn export crank_shaper -p crank=120 -p pivot_distance=240 -p lever=450 \\
        --format dxf --crank-angle 30 -o shaper.dxf
    quickreturn report crank_shaper -p crank=120 -p pivot_distance=240 -p lever=450 \\
        --load '{"length_unit": "mm", "crank_rpm": 30, "cutting_force": 3000}' -o shaper.html
    quickreturn atlas --out atlas        quickreturn serve --port 8000

The flags are the API's names (the README, *Over HTTP*) with dashes. Each command prints a
table, or with ``--json`` the API's JSON reply and with ``--csv`` rows for a spreadsheet. Exit
status: 0 with an answer, 1 when every type refuses (each reason printed), 2 on bad input (the
library's message, naming the field).
"""

from . import commands, files  # noqa: F401  (each registers its commands on main)
from .base import main

__all__ = ["main"]
