"""Parameters in their ranges keep every output finite: values that would overflow the equations are refused.

Parameters that passed the earlier checks (mass 1e-310, g 1e300, r_cm 1.7e308) gave
non-finite outputs with status OK (docs/robustness.md): each is now refused at
exitInitializationMode naming the value and its range, and a state whose outputs would
overflow (a finite spin with an infinite energy) is refused too.
"""

from __future__ import annotations

import pytest

from modelsrc.model import PARAM_MAX, POSITIVE_MIN

from ..harness.fmi3_ctypes import OK, shared_library
from ..harness.misuse_helpers import refused, refused_at_exit_initialization


@pytest.mark.parametrize(
    "kind, name, value, fragment",
    [
        ("sleeping_top", "mass", 1e-310, "mass must be in [1e-100, 1e+100] kg"),
        ("sleeping_top", "mass", 1e300, "mass must be in [1e-100, 1e+100] kg"),
        ("extreme_free", "I_principal[1]", 1e-310, "I_principal[1] must be in [1e-100, 1e+100] kg.m2"),
        ("sleeping_top", "g[3]", 1e300, "|g[3]| must be <= 1e+100 m/s2"),
        ("sleeping_top", "r_cm[3]", 1.7e308, "|r_cm[3]| must be <= 1e+100 m"),
    ],
)
def test_parameters_that_overflow_the_equations_are_refused(kind, name, value, fragment):
    """Before: accepted, and the outputs (a_cm, E, sensor_v, ...) were non-finite with status OK."""
    refused_at_exit_initialization(kind, name, value, fragment)
    assert (POSITIVE_MIN, PARAM_MAX) == (1e-100, 1e100)


def test_an_output_never_becomes_non_finite_with_status_ok():
    """Parameters in range, a state that overflows an output: a spin of 1e160 rad/s about a
    moment of 1e-10 is finite, its energy w^2 I / 2 = 5e309 is not. Refused at
    exitInitializationMode; the same from a doStep leaves the instance at its start."""
    lib = shared_library("extreme_free")
    inst = lib.instantiate()
    vr = lib.info.vr
    assert inst.set_float64([vr["w_body[1]"], vr["I_principal[2]"], vr["I_principal[3]"]], [1e160, 1.0, 1.0]) == OK
    assert inst.enter_initialization_mode(0.0) == OK
    n = len(inst.log)
    refused(inst, inst.exit_initialization_mode(), n, "fmi3ExitInitializationMode", "output 'E_kin' would be inf")
    inst.free()
