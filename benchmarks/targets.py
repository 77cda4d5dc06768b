"""A fixed, seeded set of synthesis targets per mechanism type, feasible or not by construction.

Feasible: a random valid design, every parameter inside the default synthesis bounds (lengths in
[0.1, 5] × its own stroke, the offset in [0, 5] × stroke), analysed by ``synth.analyze``; the
target is its time ratio and stroke, a transmission bound 1–5° below its minimum transmission
angle (≥ 0), and in 40% of the cases one or two of its parameters fixed at their values.

Infeasible: a random valid design's targets changed so that no design can meet them, each kind
with its reason (``INFEASIBLE``): a time ratio the type cannot have, a transmission bound above
what the default bounds allow, or fixed parts that contradict the targets or the type.

Each case is a plain dict: ``case["target"]`` is ``synth.synthesize(**case["target"])``'s
arguments. ``python -m benchmarks.targets`` writes them to ``benchmarks/results/targets.json.gz``.
"""

from __future__ import annotations

import gzip
import json
import math
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from synth import SynthError, analyze
from synth.analysis.verify import verify
from synth.mechanisms import Mechanism, all_types, get
from synth.results import Analysis
from synth.synthesis.formulation import relevant

SEED = 6  # the random targets' seed: the same targets every run
N_FEASIBLE = 100
N_INFEASIBLE = 24
FIXED_SHARE = 0.4
RESULTS = Path(__file__).parent / "results"

Design = dict[str, float]
# (design, its analysis, rng) -> (time ratio, stroke, bound°, fixed parts)
Change = Callable[[Design, Analysis, np.random.Generator], tuple[float, float, float, Design]]


def _longer(short: str, other: str) -> Change:
    """Fix ``short``, which must be shorter than ``other``, longer than it."""
    return lambda p, an, rng: (
        an.time_ratio,
        an.stroke,
        0.0,
        {short: max(p[short], p[other]) * rng.uniform(1.05, 1.5), other: min(p[short], p[other])},
    )


def _stroke_beyond(parts: tuple[str, ...], most: Callable[[Design], float]) -> Change:
    """Fix ``parts``; ask for a stroke above the most they can give."""
    return lambda p, an, rng: (
        an.time_ratio,
        most(p) * rng.uniform(1.1, 2.0),
        0.0,
        {k: p[k] for k in parts},
    )


def _moved_stroke(parts: tuple[str, ...]) -> Change:
    """Fix ``parts``, which with the time ratio determine the stroke; ask for another stroke."""
    return lambda p, an, rng: (
        an.time_ratio,
        an.stroke * rng.choice([rng.uniform(0.5, 0.9), rng.uniform(1.1, 2.0)]),
        0.0,
        {k: p[k] for k in parts},
    )


def _moved_ratio(parts: tuple[str, ...]) -> Change:
    """Fix ``parts``, which alone determine the time ratio; ask for another one."""
    return lambda p, an, rng: (
        1 + (an.time_ratio - 1) * rng.uniform(1.2, 2.0),
        an.stroke,
        0.0,
        {k: p[k] for k in parts},
    )


def _ratio(lo: float, hi: float) -> Change:
    return lambda p, an, rng: (rng.uniform(lo, hi) if hi > lo else lo, an.stroke, 0.0, {})


def _bound(lo: float, hi: float) -> Change:
    return lambda p, an, rng: (an.time_ratio, an.stroke, rng.uniform(lo, hi), {})


ROD_LIMIT = "the rod's cos μ ≥ (stroke/2)/(2·stroke) = 1/4 within the default bounds: μ ≤ 75.52°"
INFEASIBLE: dict[str, list[tuple[str, str, Change]]] = {
    "scotch_yoke": [
        ("time_ratio", "time ratio 1 for every design", _ratio(1.05, 3.0)),
        ("fixed_crank", "stroke = 2 crank", _moved_stroke(("crank",))),
    ],
    "offset_slider_crank": [
        ("time_ratio", "β < π/2, so TR < 3", _ratio(3.05, 6.0)),
        (
            "bound",
            "cos μ = (crank + |e|)/coupler is least at e = 0, crank = stroke/2, coupler = 2·stroke "
            "(the upper bound): μ ≤ 75.52°",
            _bound(85.0, 89.9),
        ),
        (
            "fixed_links",
            "stroke ≤ 2√(crank·coupler), reached at |offset| = coupler − crank",
            _stroke_beyond(
                ("crank", "coupler"), lambda p: 2 * math.sqrt(p["crank"] * p["coupler"])
            ),
        ),
    ],
    "crank_shaper": [
        ("time_ratio", "TR > 1 for every design (crank ≥ 0.1·stroke > 0)", _ratio(1.0, 1.0)),
        (
            "fixed_ratio",
            "crank/pivot_distance alone sets TR",
            _moved_ratio(("crank", "pivot_distance")),
        ),
        (
            "fixed_lever",
            "lever and TR alone set the stroke (slot drive)",
            _moved_stroke(("lever",)),
        ),
        ("fixed_invalid", "crank < pivot_distance", _longer("crank", "pivot_distance")),
    ],
    "whitworth": [
        (
            "time_ratio",
            "TR > 1 for every design (pivot_distance ≥ 0.1·stroke > 0)",
            _ratio(1.0, 1.0),
        ),
        ("bound", ROD_LIMIT, _bound(85.0, 89.9)),
        (
            "fixed_ratio",
            "crank/pivot_distance alone sets TR",
            _moved_ratio(("crank", "pivot_distance")),
        ),
        ("fixed_lever", "stroke = 2 lever", _moved_stroke(("lever",))),
    ],
    "crank_rocker_slider": [
        (
            "bound",
            "89.9° is above the best the default bounds allow (no method finds one)",
            _bound(89.9, 89.9),
        ),
        ("fixed_invalid", "the crank must be the shortest link", _longer("crank", "ground")),
        (
            "fixed_arm",
            "slot drive: stroke ≤ 2 rocker_arm",
            _stroke_beyond(("rocker_arm",), lambda p: 2 * p["rocker_arm"]),
        ),
    ],
    "drag_link_slider": [
        ("bound", ROD_LIMIT, _bound(85.0, 89.9)),
        ("fixed_arm", "stroke = 2 follower_arm", _moved_stroke(("follower_arm",))),
        ("fixed_invalid", "the ground must be the shortest link", _longer("ground", "crank")),
    ],
}
# the slot drive's parts are fixed with these kinds: its ram_link / connecting_rod is 0
SLOT = {
    ("crank_shaper", "fixed_lever"): "ram_link",
    ("crank_rocker_slider", "fixed_arm"): "connecting_rod",
}


def _draw(
    m: Mechanism, rng: np.random.Generator, slot: str | None = None
) -> tuple[Design, Analysis]:
    """A random valid design with every relevant parameter inside the default bounds × stroke:
    lengths log-uniform, placements within 10% of their default, an optional part absent in
    half of the draws (always where ``slot`` names it)."""
    while True:
        variant = frozenset(
            q.name for q in m.parameters if q.zero_means and (q.name == slot or rng.random() < 0.5)
        )
        names = relevant(m, variant)
        unit = 10 ** rng.uniform(-1, 3)
        p: Design = dict.fromkeys(variant, 0.0)
        for k in names:
            lo, hi = m.parameter(k).bounds
            if m.parameter(k).default_rule is None:
                p[k] = unit * (
                    rng.uniform(lo, hi) if lo == 0 else np.exp(rng.uniform(np.log(lo), np.log(hi)))
                )
        try:
            p.update(
                {
                    k: float(v) * rng.uniform(0.9, 1.1)
                    for k, v in m.defaults(p).items()
                    if k in names
                }
            )
            a = analyze(m.type, p)
        except (SynthError, ZeroDivisionError):
            continue
        inside = all(
            m.parameter(k).bounds[0] <= p[k] / a.stroke <= m.parameter(k).bounds[1] for k in names
        )
        if a.reversals == 2 and inside:
            return {k: float(v) for k, v in p.items()}, a


def _case(
    mtype: str, i: int, kind: str, why: str, design: Design, tr, stroke, bound, fixed
) -> dict:
    target = {
        "time_ratio": float(tr),
        "stroke": float(stroke),
        "min_transmission_angle_deg": float(bound),
        "mechanisms": [{"type": mtype, "fixed": {k: float(v) for k, v in fixed.items()}}],
        "objective": "max_transmission_angle",
    }
    feasible = kind == "feasible"
    return {
        "id": f"{mtype}/{'f' if feasible else 'i'}{i:03d}",
        "type": mtype,
        "feasible": feasible,
        "kind": kind,
        "why": why,
        "design": design,
        "target": target,
    }


def _feasible(m: Mechanism, rng: np.random.Generator, i: int) -> dict:
    p, a = _draw(m, rng)
    bound = max(0.0, a.transmission.min_deg - rng.uniform(1.0, 5.0))
    fixed: Design = {}
    if rng.random() < FIXED_SHARE:
        keys = [k for k in m.names if k in p]
        chosen = set(rng.choice(keys, size=min(len(keys), int(rng.integers(1, 3))), replace=False))
        fixed = {k: p[k] for k in keys if k in chosen}
    return _case(
        m.type, i, "feasible", "the design meets it", p, a.time_ratio, a.stroke, bound, fixed
    )


def _infeasible(m: Mechanism, rng: np.random.Generator, i: int) -> dict:
    kinds = INFEASIBLE[m.type]
    kind, why, change = kinds[i % len(kinds)]
    slot = SLOT.get((m.type, kind))
    p, a = _draw(m, rng, slot)
    tr, stroke, bound, fixed = change(p, a, rng)
    if slot:
        fixed[slot] = 0.0
    return _case(m.type, i, kind, why, p, tr, stroke, bound, fixed)


def cases(n_feasible: int = N_FEASIBLE, n_infeasible: int = N_INFEASIBLE) -> list[dict]:
    """The first n feasible and n infeasible cases of every type (a prefix of the full set)."""
    out = []
    for k, mtype in enumerate(all_types()):
        m = get(mtype)
        rng = np.random.default_rng([SEED, k, 0])
        out += [_feasible(m, rng, i) for i in range(n_feasible)]
        rng = np.random.default_rng([SEED, k, 1])
        out += [_infeasible(m, rng, i) for i in range(n_infeasible)]
    return out


def write(path: Path = RESULTS / "targets.json.gz", items: list[dict] | None = None) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    text = json.dumps(items if items is not None else cases(), indent=1) + "\n"
    with gzip.GzipFile(path, "wb", mtime=0) as f:  # 0.4 MB of JSON otherwise
        f.write(text.encode())
    return path


def check(items: list[dict[str, Any]]) -> None:
    """Every feasible case's design meets its own target to 1e-9 (the construction's premise)."""
    bad = [
        c["id"]
        for c in items
        if c["feasible"] and verify(c["type"], c["design"], *_targets(c["target"])) is None
    ]
    if bad:
        raise ValueError(f"feasible cases whose own design misses the target: {bad}")


def _targets(t: dict[str, Any]) -> tuple[float, float, float]:
    return t["time_ratio"], t["stroke"], t["min_transmission_angle_deg"]


if __name__ == "__main__":
    items = cases()
    check(items)
    print(write(items=items), len(items), "cases", file=sys.stderr)
