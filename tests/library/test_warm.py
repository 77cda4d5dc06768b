"""Every structure a request builds is one ``synth.synthesis.warm`` counts (its IPOPT solvers
and motion-search formulations: type, structural variant, free parameters, objective), and
``warm`` builds a thread's compiled analysis from the disk cache."""

from __future__ import annotations

import shutil
import threading

import pytest

import synth
from synth.analysis import forces, model
from synth.mechanisms import all_types, get
from synth.synthesis import local, search, warm

from ..support import reference_cases as ref

LOAD = synth.Load(length_unit="mm", crank_rpm=40.0, cutting_force=2000.0, slider_mass=50.0)
GENERIC = synth.Solver(accelerators=False)  # IPOPT for every variant, no exact solver first
# requests that take IPOPT (parts fixed or bounded, a refusal's diagnosis) and the motion search
REQUESTS = [
    {
        "time_ratio": 1.5,
        "stroke": 0.3,
        "solver": GENERIC,
        "mechanisms": [{"type": "drag_link_slider", "fixed": ref.DRAG_LINK_FIXED}],
    },
    {
        "time_ratio": 1.6,
        "stroke": 300.0,
        "min_transmission_angle_deg": 20.0,
        "solver": GENERIC,
        "mechanisms": ["crank_shaper", {"type": "whitworth", "fixed": {"crank": 60.0}}],
    },
    {
        "time_ratio": 2.9,
        "stroke": 300.0,
        "min_transmission_angle_deg": 60.0,
        "solver": GENERIC,
        "mechanisms": ["offset_slider_crank"],
    },
    {
        "time_ratio": 1.6,
        "stroke": 300.0,
        "min_transmission_angle_deg": 20.0,
        "mechanisms": [{"type": "crank_rocker_slider", "bounds": {"crank": [50, 200]}}],
    },
    {
        "time_ratio": 1.6,
        "stroke": 300.0,
        "min_transmission_angle_deg": 85.0,
        "mechanisms": [{"type": "crank_shaper", "bounds": {"ram_link": [30.0, 100.0]}}],
    },
    {
        "time_ratio": 1.6,
        "stroke": 300.0,
        "min_transmission_angle_deg": 20.0,
        "objective": "min_peak_torque",
        "load": LOAD,
        "mechanisms": [{"type": "crank_shaper", "fixed": {"pivot_distance": 100.0}}],
    },
]


def test_every_structure_a_request_builds_is_counted(monkeypatch):
    counted = {(s.type, s.variant, s.free) for s in warm.structures()}
    built, formulated = [], []

    def recorded_solver(m, variant, free, objective):
        built.append(((m.type, variant, free), objective))
        return solver(m, variant, free, objective)

    def recorded_formulation(m, variant, free):
        formulated.append((m.type, variant, free))
        return formulation(m, variant, free)

    solver, formulation = search.built, local.formulation
    monkeypatch.setattr(search, "built", recorded_solver)
    monkeypatch.setattr(local, "formulation", recorded_formulation)
    for body in REQUESTS:
        synth.synthesize(**body, time_budget_ms=20_000)
    assert built and formulated
    assert {s for s, _ in built} <= counted and {o for _, o in built} <= set(warm.OBJECTIVES)
    assert set(formulated) <= counted
    assert warm.counts() == {
        "analyses": 40,
        "solvers": 4 * len(counted),
        "motion_searches": len(counted),
    }


@pytest.mark.skipif(shutil.which("cc") is None, reason="no C compiler: the virtual machine runs")
def test_warm_builds_a_threads_analysis_compiled():
    def warmed() -> set[str]:
        warm.warm()
        return {
            fn.class_name()
            for t in all_types()
            for v in warm.variants(get(t))
            for fn in (*model.compiled(get(t), v), *forces.compiled(get(t), v))
        }

    out: list[set[str]] = []
    thread = threading.Thread(target=lambda: out.append(warmed()))  # a thread of its own
    thread.start()
    thread.join()
    assert out == [{"External"}]
