"""Random valid designs of every type, drawn with numpy from a seed (no code shared with synth).

Each generator builds a design from dimensionless shape ratios and a random overall scale, so
the set spans sizes from 1e-2 to 1e3 and shapes from gentle to near the validity limits.

A type these generators do not know (a new module of synth.mechanisms) gets designs drawn from
its registry record: every parameter log-uniform within its default bounds (a signed one
uniform, a part that may be zero zero half the time), kept where synth accepts the design.
"""

from __future__ import annotations

import zlib

import numpy as np

from synth.errors import SynthError
from synth.mechanisms import get

from .bruteforce import TYPES


def _scotch_yoke(rng):
    return {"crank": 1.0}


def _offset_slider_crank(rng):
    e = rng.uniform(-1.5, 1.5)
    return {"crank": 1.0, "coupler": (1 + abs(e)) * rng.uniform(1.02, 4.0), "offset": e}


def _crank_shaper(rng):
    r2 = rng.uniform(0.05, 0.95)
    p = {"crank": r2, "pivot_distance": 1.0, "lever": (1 + r2) * rng.uniform(1.0, 2.0)}
    if rng.random() < 0.5:
        # a ram link, with the ram path anywhere near the tip's extreme positions
        lever = p["lever"]
        h = lever * np.sqrt(1 - r2 * r2) * rng.uniform(0.9, 1.05)
        reach = max(abs(h - lever), abs(h - lever * np.sqrt(1 - r2 * r2)))
        p.update(ram_link=max(reach, 0.05 * lever) * rng.uniform(1.5, 6.0), ram_height=h)
    return p


def _whitworth(rng):
    lever = rng.uniform(0.2, 3.0)
    return {
        "crank": 1.0,
        "pivot_distance": rng.uniform(0.05, 0.95),
        "lever": lever,
        "connecting_rod": lever * rng.uniform(1.05, 4.0),
    }


def _grashof(rng, shortest: int) -> list[float]:
    """Four links (ground, crank, coupler, rocker), link ``shortest`` = 1 the shortest, Grashof."""
    while True:
        links = list(rng.uniform(1.1, 4.0, size=4))
        links[shortest] = 1.0
        s = links[shortest]
        others = [x for i, x in enumerate(links) if i != shortest]
        if all(s + x <= sum(others) - x for x in others):
            return links


def _crank_rocker_slider(rng):
    r1, r2, r3, r4 = _grashof(rng, shortest=1)
    p = {
        "ground": r1,
        "crank": r2,
        "coupler": r3,
        "rocker": r4,
        "rocker_arm": r4 * rng.uniform(0.3, 2.0),
    }
    if rng.random() < 0.6:
        p["connecting_rod"] = p["rocker_arm"] * rng.uniform(1.0, 3.0)
    return p


def _drag_link_slider(rng):
    r1, r2, r3, r4 = _grashof(rng, shortest=0)
    r5 = rng.uniform(0.2, 3.0)
    return {
        "ground": r1,
        "crank": r2,
        "coupler": r3,
        "follower": r4,
        "follower_arm": r5,
        "connecting_rod": r5 * rng.uniform(1.05, 4.0),
    }


GENERATORS = {t: globals()[f"_{t}"] for t in TYPES}


def _from_registry(mtype: str):
    """A generator for a type without its own: see the module's docstring."""
    m = get(mtype)

    def draw(rng):
        for _ in range(10_000):
            p = {}
            for q in m.parameters:
                lo, hi = q.bounds
                if q.zero_means and rng.random() < 0.5:
                    p[q.name] = 0.0
                elif q.signed:
                    p[q.name] = rng.uniform(-hi, hi)
                else:
                    p[q.name] = float(np.exp(rng.uniform(np.log(lo), np.log(hi))))
            try:
                m.complete(p)
            except SynthError:
                continue
            return p
        raise AssertionError(f"no valid {mtype} in 10 000 draws within its default bounds")

    return draw


def random_designs(mtype: str, n: int, seed: int = 0) -> list[dict[str, float]]:
    """n random valid designs of one type, each scaled by 10**U(-2, 3)."""
    index = TYPES.index(mtype) if mtype in TYPES else zlib.crc32(mtype.encode())
    rng = np.random.default_rng([seed, index])
    generate = GENERATORS.get(mtype) or _from_registry(mtype)
    out = []
    for _ in range(n):
        p = generate(rng)
        scale = 10 ** rng.uniform(-2, 3)
        out.append({k: v * scale for k, v in p.items()})
    return out
