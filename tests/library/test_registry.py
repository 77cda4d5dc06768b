"""Registry-wide contract: every type is defined once and the same code runs on floats, SX, MX."""

import math
from pathlib import Path

import casadi as ca
import numpy as np
import pytest

import synth
from synth.mechanisms import all_types, get

from ..support.designs import TYPES, random_designs

# the short names of docs/references.md: the first column of its table
REFERENCES = {
    line.split("|")[1].strip()
    for line in (Path(__file__).parents[2] / "docs" / "references.md").read_text().splitlines()
    if line.startswith("| ") and not line.startswith("| short name")
}


def test_the_six_types_in_contract_order():
    assert all_types()[: len(TYPES)] == TYPES  # then any other, by its module's name


@pytest.mark.parametrize("mtype", all_types())
def test_module_documents_its_maths(mtype):
    m = get(mtype)
    doc = __import__(m.position.__module__, fromlist=["_"]).__doc__
    for q in m.parameters:
        assert q.name in doc and q.symbol in doc
    assert m.sources and all(s in REFERENCES for s in m.sources)
    names = [c.name for c in m.conditions]
    assert len(names) == len(set(names))


@pytest.mark.parametrize("mtype", all_types())
def test_same_code_on_floats_sx_and_mx(mtype):
    m = get(mtype)
    for p in random_designs(mtype, 5, seed=4):
        full = m.complete(p)
        theta = 0.7
        floats = [m.position(full, theta), *m.transmission(full, theta).values()]
        assert all(isinstance(v, float) for v in floats)
        for sym in (ca.SX, ca.MX):
            th = sym.sym("th")
            pv = sym.sym("p", len(full))
            ps = {k: (0.0 if k in m.variant(full) else pv[i]) for i, k in enumerate(full)}
            out = [m.position(ps, th), *m.transmission(ps, th).values()]
            fn = ca.Function("f", [th, pv], out)
            got = [float(v) for v in fn.call([theta, list(full.values())])]
            np.testing.assert_allclose(got, floats, rtol=1e-14, atol=1e-14)
        if m.facts is None:  # closed forms are optional
            continue
        facts = m.facts(full)
        assert all(math.isfinite(float(v)) for v in facts.transmission_cos)
        assert abs(float(facts.beta)) < math.pi and float(facts.stroke) > 0


def test_curves_only_where_asked():
    p = {"crank": 40.0, "pivot_distance": 160.0, "lever": 240.0}
    assert synth.analyze("crank_shaper", p).curves is None
    a = synth.analyze("crank_shaper", p, crank_angles_deg=[-30.0, 12.5, 400.0])
    assert list(a.curves.crank_angle_deg) == [-30.0, 12.5, 400.0]
    b = synth.analyze("crank_shaper", p, samples=8)
    assert list(b.curves.crank_angle_deg) == [0.0, 45.0, 90.0, 135.0, 180.0, 225.0, 270.0, 315.0]
    assert "curves" not in synth.analyze("crank_shaper", p).to_dict()
    assert len(b.to_dict()["curves"]["position"]) == 8


@pytest.mark.parametrize("mtype", all_types())
def test_a_drawings_members_are_as_long_as_their_parameters(mtype):
    """A drawing's member named by a parameter is that long at every crank angle (the pins
    from synth.joints), or not drawn where the part is 0."""
    m = get(mtype)
    if not m.drawing:
        return
    pins = set(synth.joints(mtype, m.complete(random_designs(mtype, 1, seed=2)[0]), [0.0]))
    assert {pin for _, a, b in m.drawing for pin in (a, b)} <= pins
    for p in random_designs(mtype, 10, seed=3):
        full = m.complete(p)
        j = synth.joints(mtype, full, np.linspace(0, 360, 7))
        for name, a, b in m.drawing:
            if name in full and full[name] != 0:
                np.testing.assert_allclose(np.hypot(*(j[a] - j[b]).T), full[name], rtol=1e-12)
