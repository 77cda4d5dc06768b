"""A searched objective cut short by its budget answers the same wherever the deadline falls
(the clock decides nothing but whether the answer is complete): before the type's search
began, no candidate and the budget's reason; within it, the exact solvers' designs, measured,
and a reason that says the search was cut. The clock here passes the deadline after its k-th
look, for k across the whole request: each cut is one the machine's load could make."""

from __future__ import annotations

import json
import time

import synth
from synth.synthesis import driver, local, motion

REQUEST = {
    "time_ratio": 1.6,
    "stroke": 300.0,
    "min_transmission_angle_deg": 20.0,
    "mechanisms": ["drag_link_slider"],  # SLSQP from ranked starts: ~90 looks at the clock
    "objective": "uniform_cutting_speed",
}


def test_a_search_cut_anywhere_gives_one_reply(monkeypatch):
    real, looks, cut_after = time.monotonic, [], [10**9]

    class Clock:  # the search's clock: past the deadline after its k-th look
        @staticmethod
        def monotonic() -> float:
            looks.append(1)
            return real() + (1e9 if len(looks) > cut_after[0] else 0.0)

    class Driver:  # the request's own clock agrees, without counting
        @staticmethod
        def monotonic() -> float:
            return real() + (1e9 if len(looks) > cut_after[0] else 0.0)

    monkeypatch.setattr(motion, "time", Clock)
    monkeypatch.setattr(local, "time", Clock)
    monkeypatch.setattr(driver, "time", Driver)

    def ask() -> tuple[synth.SynthesisResult, str]:
        looks.clear()
        r = synth.synthesize(**REQUEST)
        d = r.to_dict()
        del d["elapsed_ms"]
        return r, json.dumps(d, sort_keys=True)

    whole, _ = ask()
    n = len(looks)
    assert whole.complete and not whole.infeasible and n > 60
    replies: dict[str, list[int]] = {}
    within_search = [n // 20 + j * n // 13 for j in range(12)]  # after the exact designs
    for k in [0, *within_search]:
        cut_after[0] = k
        r, text = ask()
        assert not r.complete
        replies.setdefault(text, []).append(k)
    assert sorted(replies.values()) == [[0], within_search]  # exactly two replies
    before, within = (json.loads(t) for t in replies)
    assert not before["candidates"] and before["infeasible"][0]["code"] == "BUDGET_EXHAUSTED"
    (why,) = within["infeasible"]
    assert why["code"] == "BUDGET_EXHAUSTED" and "not searched" in why["reason"]
    # the exact solvers' designs: no better than the searched answer, which starts from them
    best = whole.candidates[0].objective_value
    assert within["candidates"]
    assert all(c["objective_value"] >= best * (1 - 1e-12) for c in within["candidates"])
    assert all(c["method"] != "slsqp" for c in within["candidates"])
