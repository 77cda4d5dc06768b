"""A refusal's reachable-range scan that the deadline cuts short is kept as far as it got,
finished meanwhile or by the next request: the numbers are those of one uninterrupted scan,
and no request waits past its budget for one (issue 38: 4.76 s on a 300 ms budget)."""

import synth
from synth.synthesis.diagnose import forget_ranges

REQUEST = {
    "time_ratio": 3.5,
    "stroke": 100.0,
    "min_transmission_angle_deg": 30.0,
    "mechanisms": ["offset_slider_crank", "whitworth"],
}


def test_a_scan_cut_short_goes_on_at_the_next_request_to_the_same_numbers():
    forget_ranges()
    whole = synth.synthesize(**REQUEST, time_budget_ms=60_000)
    assert whole.complete and whole.infeasible[0].code == "TIME_RATIO_UNREACHABLE"
    forget_ranges()
    budget, answers = 0.25, []
    while not answers or not answers[-1].complete:  # budgets doubling: each gets further
        answers.append(synth.synthesize(**REQUEST, time_budget_ms=budget))
        budget *= 2
    assert len(answers) > 1 and not answers[0].complete
    assert answers[-1].infeasible == whole.infeasible
    assert answers[-1].candidates == whole.candidates
