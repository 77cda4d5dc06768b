"""An atlas's charts (matplotlib, imported when drawn)."""

from __future__ import annotations

from pathlib import Path

from ..mechanisms import get
from .values import Atlas


def charts(a: Atlas, folder: Path) -> list[Path]:
    """frontier.png (every type's best angle against the time ratio) and selection.png (the
    (time ratio, bound) plane, each type's region where it meets the target)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    paths = []
    fig, ax = plt.subplots(figsize=(7, 4.2))
    for t in a.inputs.types:
        pts = [(tr, mu) for tr, mu in a.best(t) if mu is not None]
        if pts:
            ax.plot(*zip(*pts, strict=True), marker=".", label=get(t).title)
    ax.set(
        xlabel="time ratio",
        ylabel="best minimum transmission angle (°)",
        ylim=(0, 92),
        title="The frontier: the best transmission angle each type reaches",
    )
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    paths.append(folder / "frontier.png")
    fig.savefig(paths[-1], dpi=110)
    plt.close(fig)
    # the selection chart: each (time ratio, bound) cell coloured by the set of types that
    # meet it (a type meets it where its best angle at that time ratio is at least the bound)
    from matplotlib.colors import ListedColormap
    from matplotlib.patches import Patch

    ratios, bounds = list(a.inputs.ratios), [0.25 * k for k in range(361)]
    best = {t: dict(a.best(t)) for t in a.inputs.types}
    cells = [
        [
            frozenset(t for t in a.inputs.types if (mu := best[t][tr]) is not None and mu >= b)
            for tr in ratios
        ]
        for b in bounds
    ]
    kinds = sorted({c for row in cells for c in row}, key=lambda c: (-len(c), sorted(c)))
    index = {c: k for k, c in enumerate(kinds)}
    colors = ["#ffffff" if not c else f"C{k % 10}" for k, c in enumerate(kinds)]
    fig, ax = plt.subplots(figsize=(7.5, 4.6))
    ax.pcolormesh(
        ratios,
        bounds,
        [[index[c] for c in row] for row in cells],
        cmap=ListedColormap(colors),
        vmin=-0.5,
        vmax=len(kinds) - 0.5,
        shading="nearest",
        alpha=0.55,
    )
    short = {t: get(t).title.split(" (")[0] for t in a.inputs.types}
    handles = [
        Patch(
            color=col,
            alpha=0.55,
            label=", ".join(short[t] for t in a.inputs.types if t in c) or "none",
        )
        for c, col in zip(kinds, colors, strict=True)
    ]
    ax.legend(
        handles=handles, fontsize=7, loc="upper right", title="types that meet it", title_fontsize=7
    )
    ax.set(
        xlabel="time ratio",
        ylabel="minimum transmission angle asked (°)",
        ylim=(0, 90),
        title="Which types can meet a target",
    )
    fig.tight_layout()
    paths.append(folder / "selection.png")
    fig.savefig(paths[-1], dpi=110)
    plt.close(fig)
    return paths
