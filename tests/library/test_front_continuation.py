"""A four-bar type's front continues each inner point from the previous one's optimum
(``FourBar.continued``); the full search per point (as a min_size request runs it) must find
the same designs: the same sizes and angles, on every front of a grid of targets, with and
without bounds on the lengths, fixed parts and slot drives."""

import itertools

import pytest

import synth
from synth.mechanisms.fourbar import solver

SPECS = [
    {"type": "crank_rocker_slider"},
    {"type": "drag_link_slider"},
    {"type": "crank_rocker_slider", "bounds": {"ground": [0.5, 3.0]}},
    {"type": "crank_rocker_slider", "fixed": {"connecting_rod": 0.0}},
    {"type": "drag_link_slider", "bounds": {"connecting_rod": [0.6, 1.2]}},
]


@pytest.mark.parametrize("spec", SPECS, ids=lambda s: str(s))
def test_continued_fronts_equal_the_full_search(spec, monkeypatch):
    continued = []
    original = solver.FourBar.continued

    def counted(self, cos_bound):
        answer = original(self, cos_bound)
        continued.append(answer is not None)
        return answer

    targets = list(itertools.product((1.2, 1.6, 2.2), (0.0, 10.0, 25.0), (1.0, 37.0)))
    fronts = []
    monkeypatch.setattr(solver.FourBar, "continued", counted)
    fronts.append([synth.synthesize(tr, s, b, [spec]).candidates for tr, b, s in targets])
    monkeypatch.setattr(solver.FourBar, "continued", lambda self, c: None)
    fronts.append([synth.synthesize(tr, s, b, [spec]).candidates for tr, b, s in targets])
    assert any(continued)  # the continuation was taken, not only its fallback
    for fast, full in zip(*fronts, strict=True):
        assert len(fast) == len(full)
        for a, b in zip(fast, full, strict=True):
            assert a.size == pytest.approx(b.size, rel=1e-9)
            assert a.min_transmission_angle_deg == pytest.approx(
                b.min_transmission_angle_deg, abs=1e-7
            )
