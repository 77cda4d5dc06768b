"""`make bench`: every benchmark in one run; tables on stdout, results/*.json and plots.

python -m benchmarks [--quick]
"""

import sys

from . import analysis, atlas, overload, searched, service, startup, synthesis

if __name__ == "__main__":
    quick = ["--quick"] if "--quick" in sys.argv[1:] else []
    for bench in (analysis, synthesis, searched, service, overload, startup, atlas):
        print(f"\n## {bench.__name__}\n", flush=True)
        bench.main(quick)
