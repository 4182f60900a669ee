"""The FMI state rules: the C layer's tables, the fuzz test's independent model and the generated docs agree.

The rules live once in the C (the MASK_ table of each API file, rb_set_mask[] in the core;
docs/fmi_layer.md §3). The fuzz test (tests/robustness/test_fuzz_fmi.py) checks the FMU's actual
behaviour against its own model, written from the docs and the standard; these tests check
that model against the tables, so that the behaviour, the tables and the docs are one thing.
"""

from __future__ import annotations

import re

import pytest

from fmu.gendocs import fmi_rules

from ..harness import fuzz_fmi_model as spec

KIND_NAMES = {"state": "state", "fixed": "param_fixed", "input": "input", "tunable": "param_tunable",
              "independent": "independent", "output": "output", "derivative": "derivative",
              "local": "local"}  # fmt: skip


def test_fuzz_model_states_are_the_c_states():
    assert set(spec.ALL_STATES) == set(fmi_rules.states())


@pytest.mark.parametrize("fn", sorted(spec.ALLOWED))
def test_fuzz_model_call_rules_match_the_c_table(fn):
    assert spec.ALLOWED[fn] == fmi_rules.call_rules("3")[fn], fn


def test_fuzz_model_set_rules_match_the_c_table():
    c_rules = fmi_rules.set_rules()
    assert set(KIND_NAMES.values()) == set(c_rules)
    for kind, c_kind in KIND_NAMES.items():
        assert spec.SETTABLE[kind] == c_rules[c_kind], kind


@pytest.mark.parametrize("version", ["3", "2"])
def test_every_checked_call_has_a_mask_and_every_mask_a_call(version):
    # CHECK(F) refers to MASK_F (a missing one does not compile); conversely no mask may be
    # left over from a function that no longer checks its state.
    text = (fmi_rules.C_DIR / f"rbfmu_fmi{version}.c").read_text()
    checked = set(re.findall(r"\bCHECK\((fmi\d\w+)\)", text))
    checked |= set(re.findall(r"NO_VARIABLES_OF_TYPE\((fmi\d\w+)\)", text))
    for macro, prefix in (("GETTER", "Get"), ("SETTER", "Set")):
        checked |= {f"fmi3{prefix}{t}" for t in re.findall(rf"\b{macro}\((\w+), fmi3\w+\)", text)}
    assert checked == set(fmi_rules.call_rules(version))


def test_the_same_rules_in_both_versions():
    # FMI 2.0 and 3.0 share the core, so calls with the same meaning have the same rules
    pairs = {"SetReal": "SetFloat64", "GetReal": "GetFloat64", "SetInteger": "SetInt64", "GetInteger": "GetInt64",
             "DoStep": "DoStep", "Terminate": "Terminate", "Reset": "Reset", "ExitInitializationMode":
             "ExitInitializationMode", "GetFMUstate": "GetFMUState", "SetFMUstate": "SetFMUState",
             "EnterEventMode": "EnterEventMode", "SetTime": "SetTime", "SetContinuousStates": "SetContinuousStates",
             "GetDerivatives": "GetContinuousStateDerivatives", "EnterContinuousTimeMode": "EnterContinuousTimeMode",
             "CompletedIntegratorStep": "CompletedIntegratorStep"}  # fmt: skip
    pairs["GetRealOutputDerivatives"] = "GetOutputDerivatives"
    r2, r3 = fmi_rules.call_rules("2"), fmi_rules.call_rules("3")
    for f2, f3 in pairs.items():  # IntermediateUpdateMode is FMI 3.0's alone (intermediate update)
        assert r2[f"fmi2{f2}"] == r3[f"fmi3{f3}"] - {"IntermediateUpdateMode"}, (f2, f3)
