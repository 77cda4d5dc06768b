"""The Python API as a notebook user meets it: specs it does not understand are refused with
the keys it takes, a type's bare name is a spec, results read as attributes, and
help(synth.synthesize) names the types, the spec keys and the objectives."""

import pydoc

import pytest

import synth
from synth.objectives import REGISTRY

TARGETS = (1.8, 250.0, 40.0)


def test_an_unknown_spec_key_is_refused_naming_the_keys_it_takes():
    with pytest.raises(synth.InvalidParameters) as e:
        synth.synthesize(*TARGETS, mechanisms=[{"type": "crank_shaper", "fix": {"crank": 60}}])
    assert e.value.loc == ("mechanisms", 0, "fix")
    assert "'fix'" in str(e.value)
    assert all(k in str(e.value) for k in ("type", "fixed", "bounds"))


@pytest.mark.parametrize(
    ("spec", "loc"),
    [({"fixed": {"crank": 60}}, ("mechanisms", 0, "type")), (3, ("mechanisms", 0))],
)
def test_a_spec_without_a_type_or_not_a_mapping_is_refused(spec, loc):
    with pytest.raises(synth.InvalidParameters) as e:
        synth.synthesize(*TARGETS, mechanisms=[spec])
    assert e.value.loc == loc


def test_the_spec_the_key_was_meant_for_is_taken():
    r = synth.synthesize(*TARGETS, mechanisms=[{"type": "crank_shaper", "fixed": {"crank": 60}}])
    assert r.candidates and all(c.params["crank"] == 60 for c in r.candidates)


@pytest.mark.parametrize("mechanisms", ["crank_shaper", ["crank_shaper"]])
def test_a_types_bare_name_is_its_spec(mechanisms):
    named = synth.synthesize(*TARGETS, mechanisms=mechanisms)
    spelled = synth.synthesize(*TARGETS, mechanisms=[{"type": "crank_shaper"}])
    assert [c.params for c in named.candidates] == [c.params for c in spelled.candidates]
    assert {c.type for c in named.candidates} == {"crank_shaper"}


def test_an_unknown_bare_name_is_refused():
    with pytest.raises(synth.UnknownMechanism):
        synth.synthesize(*TARGETS, mechanisms="crank_shapper")


def test_results_read_as_attributes_and_as_before():
    a = synth.analyze("crank_shaper", {"crank": 120, "pivot_distance": 240, "lever": 450})
    assert a.extremes.max.position - a.extremes.min.position == pytest.approx(450.0, rel=1e-12)
    assert dict(a.extremes) == {"min": a.extremes.min, "max": a.extremes.max}  # and a mapping
    with pytest.raises(KeyError):
        a.extremes["mid"]
    assert set(a.to_dict()["extremes"]) == {"min", "max"}  # the JSON as the contract has it
    s = synth.sweep(
        "crank_shaper",
        {"crank": 120, "pivot_distance": 240, "lever": 450},
        "crank",
        100.0,
        200.0,
        11,
    )
    r = s.time_ratio_range
    assert r is not None and r.min.time_ratio <= r.max.time_ratio and r["max"] is r.max
    assert set(s.to_dict()["time_ratio_range"]) == {"min", "max"}


def test_help_names_the_types_the_spec_keys_and_the_objectives():
    text = pydoc.render_doc(synth.synthesize, renderer=pydoc.plaintext)
    quick = [t for t in synth.mechanisms.all_types() if synth.mechanisms.get(t).quick_return]
    for word in (*quick, *REGISTRY, "type", "fixed", "bounds"):
        assert word in text, word
    for t in quick:  # each type with its parameters
        line = next(x for x in text.splitlines() if x.strip().startswith(t))
        assert all(q.name in line for q in synth.mechanisms.get(t).parameters)


def test_a_load_may_be_the_apis_load_object():
    """``load`` as the API's object (a mapping) is the same load; a misspelt or missing
    field is refused naming it."""
    fields = {"length_unit": "mm", "crank_rpm": 40, "cutting_force": 2000, "slider_mass": 60}
    params = {"crank": 75, "pivot_distance": 50, "lever": 150, "connecting_rod": 200}
    as_dict = synth.analyze("whitworth", params, load=fields)
    assert as_dict.loads == synth.analyze("whitworth", params, load=synth.Load(**fields)).loads
    r = synth.synthesize(1.5, 300.0, 10.0, ["whitworth"], objective="min_peak_torque", load=fields)
    assert r.candidates and r.candidates[0].loads is not None
    for bad, loc in (
        ({**fields, "rpm": 40}, ("load", "rpm")),
        ({"crank_rpm": 40}, ("load", "length_unit")),
    ):
        with pytest.raises(synth.InvalidParameters) as e:
            synth.analyze("whitworth", params, load=bad)
        assert e.value.loc == loc and loc[1] in str(e.value)
