"""The objectives' registry is the one place an objective is described: the schema's choices,
the command line's, the docs' table and the library's checks read it; and its tie rule orders
designs a searched measure cannot tell apart."""

from __future__ import annotations

import itertools
import re
from pathlib import Path

import pytest

import synth
from api.schemas import SynthesizeRequest
from synth.cli import main as cli
from synth.objectives import REGISTRY, SIZE, TRANSMISSION, all_objectives

ROOT = Path(__file__).resolve().parents[2]
RULES = {TRANSMISSION: "the larger minimum transmission angle", SIZE: "the smaller size"}


def table() -> str:
    """The docs' table of the objectives, as the registry says."""
    rows = [
        "| objective | what it is | best | found by | needs | limit | ties |",
        "|---|---|---|---|---|---|---|",
    ]
    for o in all_objectives():
        needs = "a load" if o.needs_load else "a bound > 0°" if o.needs_bound else "—"
        ties = ", then ".join(RULES[r] for r in o.ties) or "—"
        if o.ties and o.tie:
            ties += f" (values within {o.tie:.0e} relative)".replace("e-0", "e-")
        limit = f"`{o.limit.field}`" if o.limit else "—"
        best = "—" if o.found == "front" else "least" if o.sense == 1 else "largest"
        rows.append(f"| `{o.name}` | {o.words} | {best} | {o.found} | {needs} | {limit} | {ties} |")
    return "\n".join(rows)


def test_the_docs_table_is_the_registry():
    doc = (ROOT / "docs" / "synthesis.md").read_text()
    assert table() in doc, (
        "docs/synthesis.md's table of the objectives, as it should read:\n" + table()
    )


def test_the_schema_and_the_command_line_offer_the_registry():
    o = SynthesizeRequest.model_json_schema()["properties"]["objective"]
    assert o["enum"] == list(REGISTRY)
    assert o["x-titles"] == {k: v.words for k, v in REGISTRY.items()}
    assert o["x-searched"] == [k for k, v in REGISTRY.items() if v.found == "searched"]
    choices = next(p for p in cli.commands["synthesize"].params if p.name == "objective")
    assert list(choices.type.choices) == list(REGISTRY)  # type: ignore[attr-defined]


def test_no_module_compares_an_objective_by_name():
    """Dispatch goes through the records. (The exact solvers' own criterion, one of the two
    they solve, is theirs: a reduced solver's ``Problem`` and IPOPT's formulation.)"""
    names = "|".join(
        [
            "PARETO",
            "MIN_SIZE",
            "MAX_TRANSMISSION",
            "UNIFORM",
            "PEAK",
            "PEAK_TORQUE",
            *(f'"{k}"' for k in REGISTRY),
        ]
    )
    compared = re.compile(rf"\bobjective\b[^\n=]*(==|!=| in )\s*\(?({names})\b|({names})\s*(==|!=)")
    pages = [
        *ROOT.glob("synth/synthesis/*.py"),
        *ROOT.glob("synth/analysis/*.py"),
        *ROOT.glob("synth/cli/*.py"),
        *ROOT.glob("api/**/*.py"),
        ROOT / "api/static/app.js",
    ]
    pages.remove(ROOT / "synth" / "synthesis" / "formulation.py")
    found = [
        f"{p.relative_to(ROOT)}: {m.group(0)}"
        for p in pages
        for m in compared.finditer(p.read_text())
    ]
    assert not found
    app = (ROOT / "api" / "static" / "app.js").read_text().splitlines()
    lists = [line for line in app if sum(f'"{k}"' in line for k in REGISTRY) > 1]
    assert not lists, "the playground lists objectives itself"


CASE = {  # a new user's request: five candidates agree to six figures in peak torque
    "time_ratio": 1.7,
    "stroke": 250.0,
    "min_transmission_angle_deg": 35.0,
    "objective": "min_peak_torque",
    "mechanisms": ["crank_shaper"],
    "max_candidates": 10,
    "load": synth.Load(length_unit="mm", crank_rpm=30, cutting_force=3000, slider_mass=40),
    "time_budget_ms": 60_000,
}


def test_designs_tied_in_peak_torque_go_to_the_larger_transmission_angle():
    """Ties (values within 1e-6 relative) are ordered by the larger minimum transmission
    angle, then the smaller size, and each candidate says which rule placed it."""
    r = synth.synthesize(**CASE)
    c = r.candidates
    assert r.complete and len(c) >= 2
    best = c[0].objective_value
    tied = [x for x in c if abs(x.objective_value - best) <= 1e-6 * best]
    assert len(tied) >= 2, [x.objective_value for x in c]
    # every design tied with the best, by the values the reply gives: the larger angle first
    angles = [x.min_transmission_angle_deg for x in tied]
    assert angles == sorted(angles, reverse=True) and angles[0] == pytest.approx(90.0, abs=1e-9)
    assert c[0].ranked_by == "objective" and tied[1].ranked_by in ("min_transmission_angle", "size")
    for before, x in itertools.pairwise(c):
        if x.ranked_by == "objective":  # a worse value
            assert x.objective_value > before.objective_value
        else:  # the same value to 1e-6, and the rule tells the two apart
            assert abs(x.objective_value - before.objective_value) <= 1e-6 * best
            if x.ranked_by == "min_transmission_angle":
                assert x.min_transmission_angle_deg < before.min_transmission_angle_deg


def test_no_two_candidates_are_one_design_at_two_sizes():
    """A crank shaper's crank turns at constant speed about its pivot: with links that weigh,
    its peak torque is the same at every crank length its time ratio allows (the pivot
    distance in proportion, the rest as it is). The answer gives each such design once (the
    rest within 1e-6 of the stroke: a third of a micrometre here), its smallest member, and
    not four sizes of it in the places of different designs."""
    load = synth.Load(
        length_unit="mm", crank_rpm=40, cutting_force=2000, slider_mass=20, link_mass_per_length=8
    )
    r = synth.synthesize(
        1.6, 300.0, 20, objective="min_peak_torque", mechanisms=["crank_shaper"], load=load
    )
    assert r.complete and len(r.candidates) >= 2
    rest = ("lever", "ram_link", "ram_height")
    for a, b in itertools.combinations(r.candidates, 2):
        assert not (
            all(abs(a.params[k] - b.params[k]) <= 1e-6 * 300 for k in rest)
            and abs(a.objective_value - b.objective_value) <= 1e-9 * a.objective_value
            and abs(a.min_transmission_angle_deg - b.min_transmission_angle_deg) <= 1e-6
        ), (a.params, b.params)
    # and each is its smallest member: the crank at its least, 30 (the type's bound)
    assert all(c.params["crank"] == pytest.approx(30.0, rel=1e-12) for c in r.candidates)
    # the premise, by the forward analysis: twice the crank and pivot distance, the same torque
    for c in r.candidates:
        k = {q: 2 * c.params[q] for q in ("crank", "pivot_distance")}
        twice = synth.analyze("crank_shaper", {**c.params, **k}, load=load)
        assert twice.loads is not None and c.loads is not None
        assert twice.loads.torque.max == pytest.approx(c.loads.torque.max, rel=1e-12)
