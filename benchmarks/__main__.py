"""`make bench`: every benchmark in one run; tables on stdout, results/*.json and plots.

python -m benchmarks [--quick] [--suite]

``--suite``: the cold-process benchmark (``benchmarks.cold``) runs `make test` too, for its wall
time and peak memory; without it, it reports the suite's latest records.
"""

import sys

from . import analysis, atlas, cold, overload, searched, service, startup, synthesis

if __name__ == "__main__":
    quick = ["--quick"] if "--quick" in sys.argv[1:] else []
    suite = ["--suite"] if "--suite" in sys.argv[1:] else []
    for bench in (analysis, synthesis, searched, service, overload, startup, cold, atlas):
        print(f"\n## {bench.__name__}\n", flush=True)
        bench.main(quick + suite if bench is cold else quick)
