"""The synthesis benchmark's plot: median run time against verified error, per method and type."""

from __future__ import annotations

import itertools
from pathlib import Path
from typing import Any

from synth.mechanisms import all_types

from .run import TOL

FLOOR = 1e-17  # errors plotted no lower (exact zeros)
CAP = 1e3  # nor higher (a design that does not run counts as inf)


def figure(rows: list[dict[str, Any]]):
    """The run-time-against-error plot, one point per method and type (the summary rows, also
    as read back from synthesis.json, where an infinite error is the string "inf")."""
    import matplotlib.pyplot as plt

    names = list(dict.fromkeys(r["method"] for r in rows))
    markers = dict(zip(names, itertools.cycle("o^svD<>pP*Xh"), strict=False))
    colours = dict(zip(all_types(), plt.get_cmap("tab10").colors, strict=False))
    fig, ax = plt.subplots(figsize=(9, 6))
    for r in rows:
        if r["worst_error_median"] is None or not r["ms_median"]:
            continue
        y = min(max(float(r["worst_error_median"]), FLOOR), CAP)
        ax.scatter(r["ms_median"], y, marker=markers[r["method"]], color=colours[r["type"]])
    ax.axhline(TOL, color="grey", lw=0.8, ls="--")
    ax.set(
        xscale="log",
        yscale="log",
        xlabel="median wall time per target (ms)",
        ylabel=f"median worst error after verification (floor {FLOOR:g}, cap {CAP:g})",
        title="Synthesis: time vs verified error (feasible targets)",
    )
    handles = [plt.Line2D([], [], ls="", marker=markers[n], color="k", label=n) for n in names]
    handles += [plt.Line2D([], [], ls="", marker="s", color=c, label=t) for t, c in colours.items()]
    ax.legend(handles=handles, fontsize=7, loc="center left", bbox_to_anchor=(1, 0.5))
    fig.tight_layout()
    return fig


def plot(rows: list[dict[str, Any]], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig = figure(rows)
    fig.savefig(path, dpi=120)
    plt.close(fig)
