"""Directional, adjoint and output derivatives are finite or refused with Error naming the value.

The rule of docs/robustness.md (Values entering and leaving the FMU): every value a Get
returns is finite, or the call returns Error with a message. Before issue 39's follow-up the
derivative Gets returned inf/NaN with OK at a state where the equations overflow (a state
set in InitializationMode is checked only at exitInitializationMode, and the Error state
keeps it), and took a seed of inf or NaN from the importer. FMI 3.0 through the ctypes
harness on the shipped eccentric_orbit (the central field: x_cm = 0 is the centre of the
central body, where the field is 0/0); FMI 2.0 through fmpy on the shared heavy_top.
"""

from __future__ import annotations

import math

import pytest

from ..harness.fmi3_ctypes import OK, Fmi3Instance, shared_library

ERROR = 3


@pytest.fixture(scope="module")
def orbit():
    return shared_library("eccentric_orbit")


def _log(inst: Fmi3Instance) -> str:
    return "\n".join(m for _, _, m in inst.log)


def _at_the_central_body(lib) -> Fmi3Instance:
    """A Co-Simulation instance in InitializationMode with x_cm = 0 (accepted there: the
    start values are checked at exitInitializationMode)."""
    vr = lib.info.vr
    inst = lib.instantiate()
    assert inst.enter_initialization_mode(0.0) == OK
    assert inst.set_float64([vr[f"x_cm[{k}]"] for k in (1, 2, 3)], [0.0] * 3) == OK
    return inst


@pytest.mark.parametrize("adjoint", [False, True], ids=["directional", "adjoint"])
@pytest.mark.parametrize("exit_first", [False, True], ids=["initialization", "error"])
def test_a_jacobian_that_is_not_finite_is_refused(orbit, adjoint, exit_first):
    """d der(v_cm[1]) / d x_cm[1] at x_cm = 0 (in InitializationMode, and in the Error state
    after the refused exitInitializationMode) is not finite: Error naming the unknown or known
    and the state values, never inf/NaN with OK."""
    vr = orbit.info.vr
    inst = _at_the_central_body(orbit)
    if exit_first:
        assert inst.exit_initialization_mode() == ERROR
    n = len(inst.log)
    status, sens = inst.get_directional([vr["der(v_cm[1])"]], [vr["x_cm[1]"]], [1.0], adjoint=adjoint)
    assert status == ERROR, sens
    message = "\n".join(inst.errors_since(n))
    name = "x_cm[1]" if adjoint else "der(v_cm[1])"
    assert f"'{name}' would be" in message and "x_cm[1]=0" in message, message


@pytest.mark.parametrize("order", [1, 2])
def test_an_output_derivative_that_is_not_finite_is_refused(orbit, order):
    """d/dt and d²/dt² of E_total at x_cm = 0 (potential −μm/|x|): Error naming E_total."""
    vr = orbit.info.vr
    inst = _at_the_central_body(orbit)
    n = len(inst.log)
    status, v = inst.get_output_derivatives([vr["E_total"]], [order])
    assert status == ERROR, v
    assert "derivative of 'E_total' would be" in "\n".join(inst.errors_since(n)), _log(inst)


@pytest.mark.parametrize("adjoint", [False, True], ids=["directional", "adjoint"])
@pytest.mark.parametrize("seed", [math.inf, -math.inf, math.nan])
def test_a_seed_that_is_not_finite_is_refused_naming_it(orbit, adjoint, seed):
    """A seed of ±inf or NaN from the importer is refused naming the seed and its variable; a
    finite seed at the same (started) state gives finite sensitivities with OK."""
    vr = orbit.info.vr
    inst = orbit.instantiate()
    assert inst.enter_initialization_mode(0.0) == OK and inst.exit_initialization_mode() == OK, _log(inst)
    unknowns, knowns = [vr["der(v_cm[1])"], vr["der(v_cm[2])"]], [vr["x_cm[1]"], vr["x_cm[2]"]]
    status, sens = inst.get_directional(unknowns, knowns, [1.0, 1.0], adjoint=adjoint)
    assert status == OK and all(math.isfinite(s) for s in sens), sens
    status, _ = inst.get_directional(unknowns, knowns, [0.5, seed], adjoint=adjoint)
    assert status == ERROR
    name = "der(v_cm[2])" if adjoint else "x_cm[2]"
    assert f"seed[1] (of '{name}') must be finite, got {seed:g}" in _log(inst), _log(inst)


def test_fmi2_directional_and_output_derivatives_follow_the_rule(fmi2_fmus):
    """FMI 2.0 (the same C core): fmi2GetDirectionalDerivative refuses a NaN seed, and at
    w_body = 1e300 set in InitializationMode (Jacobian entries ~ I w ~ 1e300, finite) a finite
    seed of 1e10 makes the sensitivity overflow: refused; fmi2GetRealOutputDerivatives of E_kin
    (~ I w² = inf) refused. Each names the value."""
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave

    from ..harness.fmi2_slave import Slave2, logging_callbacks

    md = read_model_description(str(fmi2_fmus["heavy_top"]))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    s = FMU2Slave(
        guid=md.guid,
        unzipDirectory=extract(str(fmi2_fmus["heavy_top"])),
        modelIdentifier=md.coSimulation.modelIdentifier,
    )
    s.instantiate(callbacks=logging_callbacks())
    s.setupExperiment(startTime=0.0)
    s.enterInitializationMode()
    unknown, known = [vr["der(w_body[1])"]], [vr["w_body[2]"]]
    assert math.isfinite(s.getDirectionalDerivative(unknown, known, [1.0])[0])
    n = len(Slave2.messages)
    with pytest.raises(Exception, match="fmi2GetDirectionalDerivative"):
        s.getDirectionalDerivative(unknown, known, [math.nan])
    assert "seed[0] (of 'w_body[2]') must be finite, got nan" in "\n".join(Slave2.messages[n:])
    s.setReal([vr[f"w_body[{k}]"] for k in (1, 2, 3)], [1e300] * 3)
    with pytest.raises(Exception, match="fmi2GetDirectionalDerivative"):
        s.getDirectionalDerivative(unknown, known, [1e10])
    assert "directional derivative of 'der(w_body[1])' would be" in "\n".join(Slave2.messages[n:])
    with pytest.raises(Exception, match="fmi2GetRealOutputDerivatives"):
        s.getRealOutputDerivatives([vr["E_kin"]], [1])
    assert "first derivative of 'E_kin' would be" in "\n".join(Slave2.messages[n:]), Slave2.messages[n:]
    s.freeInstance()
