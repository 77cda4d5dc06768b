"""``python -m synth.atlas``: an atlas from the command line, its tables (and charts) in a
folder."""

from __future__ import annotations

import argparse
import os
import sys
from collections.abc import Sequence
from pathlib import Path

from . import compute
from .charts import charts
from .compute import DEFAULT_BOUNDS, atlas
from .values import CHUNK


class _Progress:
    def __init__(self, total: int, done: int) -> None:
        self.total, self.done = total, done
        self.show()

    def step(self) -> None:
        self.done += 1
        self.show()

    def show(self) -> None:
        filled = int(30 * self.done / max(self.total, 1))
        end = "\n" if self.done >= self.total else ""
        print(
            f"\r[{'#' * filled}{'.' * (30 - filled)}] {self.done}/{self.total} chunks",
            end=end,
            file=sys.stderr,
            flush=True,
        )


def main(argv: Sequence[str] | None = None) -> None:
    p = argparse.ArgumentParser(
        prog="python -m synth.atlas", description=compute.__doc__.split("\n\n")[0]
    )
    p.add_argument("--types", nargs="*", help="default: the quick-return types")
    p.add_argument("--ratios", default="1.05:4.0:60", help="start:stop:count (default %(default)s)")
    p.add_argument(
        "--bounds",
        nargs="*",
        type=float,
        default=list(DEFAULT_BOUNDS),
        help="the transmission bounds, degrees (default %(default)s)",
    )
    p.add_argument(
        "--chunk",
        type=int,
        default=CHUNK,
        help="grid points (time ratio, bound) per task: the unit of work and of "
        "resuming (default %(default)s)",
    )
    p.add_argument("--out", default="atlas", help="the folder (resumed if it holds a run)")
    p.add_argument("--workers", type=int, help="local processes (default: the cores)")
    p.add_argument(
        "--scheduler",
        default=os.environ.get("DASK_SCHEDULER_ADDRESS"),
        help="a Dask scheduler's address: the tasks run on its cluster (default: "
        "DASK_SCHEDULER_ADDRESS, else a local process pool)",
    )
    p.add_argument("--inline", action="store_true", help="run every task in this process")
    p.add_argument("--charts", action="store_true", help="also frontier.png and selection.png")
    args = p.parse_args(argv)
    start, stop, count = args.ratios.split(":")
    n = int(count)
    ratios = [float(start) + (float(stop) - float(start)) * k / max(n - 1, 1) for k in range(n)]
    a = atlas(
        args.types,
        [round(r, 12) for r in ratios],
        args.bounds,
        chunk=args.chunk,
        out=args.out,
        workers=args.workers,
        inline=args.inline,
        scheduler=args.scheduler,
        progress=_Progress,
    )
    if args.charts:
        charts(a, Path(args.out))
    refused = sum(p.status == "refused" for p in a.frontier)
    print(
        f"{len(a.frontier)} points ({refused} refused), {a.computed} chunks computed, "
        f"tables in {args.out}/"
    )


if __name__ == "__main__":
    main()
