"""The README's figures of the default answer (objective pareto) for time ratio 1.6, stroke
300 mm and a 40° bound: each type's front, and the Whitworth front's two ends drawn.

    python docs/front.py          # writes docs/front.png

The notebook ``notebooks/synthesis_tour.ipynb`` draws the same with these functions.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt

import synth

TARGETS = {"time_ratio": 1.6, "stroke": 300.0, "min_transmission_angle_deg": 40.0}
MARKERS = dict(zip(synth.mechanisms.all_types(), "os^vDP", strict=False))
WHITWORTH_LINKS = (("O2", "B"), ("O4", "B"), ("O4", "P"), ("P", "R"))


def plot_front(result: synth.SynthesisResult, ax) -> None:
    """Size (the sum of link lengths) against the minimum transmission angle, a marker per
    type, each type's front joined."""
    by_type: dict[str, list] = {}
    for c in result.candidates:
        by_type.setdefault(c.type, []).append(c)
    for mtype, points in by_type.items():
        ax.plot(
            [c.min_transmission_angle_deg for c in points],
            [c.size for c in points],
            "-" + MARKERS.get(mtype, "o"),
            label=mtype,
        )
    ax.set(xlabel="minimum transmission angle (°)", ylabel="sum of link lengths (mm)")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)


def draw_ends(result: synth.SynthesisResult, axes, mtype: str = "whitworth") -> None:
    """The front's smallest and best-transmitting designs, at mid working stroke."""
    points = [c for c in result.candidates if c.type == mtype]
    for ax, c in zip(axes, (points[-1], points[0]), strict=True):
        a = synth.analyze(mtype, c.params)
        at = a.extremes.min.crank_angle_deg + a.working_stroke.crank_angle_deg / 2
        j = synth.joints(mtype, c.params, [at])
        for p, q in WHITWORTH_LINKS:
            ax.plot(*zip(j[p][0], j[q][0], strict=True), "-o", ms=3, color="C0")
        ax.axvline(j["R"][0][0], color="grey", lw=0.5)  # the ram's path
        ax.set_title(
            f"{', '.join(c.front.ends)}: {c.min_transmission_angle_deg:.1f}°, size {c.size:.0f} mm",
            fontsize=9,
        )
        ax.set_aspect("equal")


def main() -> None:
    plt.switch_backend("Agg")
    r = synth.synthesize(**TARGETS)
    fig = plt.figure(figsize=(11, 4.5))
    grid = fig.add_gridspec(1, 3, width_ratios=(1.4, 1, 1))
    plot_front(r, fig.add_subplot(grid[0]))
    draw_ends(r, [fig.add_subplot(grid[k]) for k in (1, 2)])
    fig.suptitle("Time ratio 1.6, stroke 300 mm, transmission ≥ 40°: the default answer")
    fig.tight_layout()
    fig.savefig(Path(__file__).with_name("front.png"), dpi=110)


if __name__ == "__main__":
    main()
