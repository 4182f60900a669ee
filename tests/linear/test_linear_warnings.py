"""The warnings an FMU logs while linearised or trimmed reach the user as a run's: FmuWarnings, `rbfmu: warning:` lines.

The shipped C layer logs no Warning in the Model Exchange calls the linear models make (its one
warning there, an importer's tolerance it refuses at initialisation, needs a tolerance that
fmu.linear.model_exchange never passes), so these tests make the FMU's logger report one: they
call the log callback the FMU was given at instantiation (fmpy keeps it as `fmu.logMessage`),
with status Warning, from inside the FMI calls the linear models make, exactly as the FMU's C
does (fmu/c/rbfmu_core.c, rb_logf). Before, ModelExchange kept such a message among its
messages and nobody showed it. A real one, through `--at` (a run to the point): the tolerance
below rk8's floor of tests/cli/test_run_warnings.py.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import pytest

from fmu.cli import main
from fmu.drive.instance import FMI3_WARNING, FmuWarning
from fmu.linear.linearize import linearize
from fmu.linear.model_exchange import ModelExchange
from fmu.linear.operating_point import start_point
from fmu.linear.trim import trim

from ..harness.scenes import shared_fmu

SAID = "fmi3GetContinuousStateDerivatives: a warning the FMU logged"


@pytest.fixture(scope="module")
def torque_driven(build_dir) -> Path:
    return shared_fmu(build_dir, "torque_driven")


@pytest.fixture
def warning_fmu(monkeypatch):
    """Every ẋ and state read of a Model Exchange instance (also the ẋ a linearisation's
    directional derivatives read, ModelExchange.directional_calls) logs SAID with status
    Warning through the FMU's log callback, as the FMU's C would."""

    def logging(original):
        def call(self, *args):
            self.fmu.logMessage(None, FMI3_WARNING, b"logStatusWarning", SAID.encode())
            return original(self, *args)

        return call

    monkeypatch.setattr(ModelExchange, "rates", logging(ModelExchange.rates))
    monkeypatch.setattr(ModelExchange, "states_now", logging(ModelExchange.states_now))
    made = ModelExchange.directional_calls

    def directional_calls(self, *args, rates_at=None):  # a linearisation reads ẋ with its directional derivatives
        run = made(self, *args, rates_at=rates_at)
        return run if rates_at is None else logging(lambda _, *a: run(*a)).__get__(self)

    monkeypatch.setattr(ModelExchange, "directional_calls", directional_calls)


def _recorded(call):
    """(call's result, the texts of the FmuWarnings it raised), every one pointing at this file."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = call()
    fmu_warnings = [w for w in caught if issubclass(w.category, FmuWarning)]
    assert all(w.filename == __file__ for w in fmu_warnings), [w.filename for w in fmu_warnings]
    return result, [str(w.message) for w in fmu_warnings]


def test_start_point_linearize_and_trim_raise_the_fmus_warnings_once_each(torque_driven, warning_fmu):
    point, texts = _recorded(lambda: start_point(torque_driven, {"tau_body[1]": 0.5}))  # Newton has work below
    assert texts == [f"torque_driven.fmu: the FMU logged a warning: {SAID}"]
    _, texts = _recorded(lambda: linearize(torque_driven, point))
    assert texts == [f"torque_driven.fmu: the FMU logged a warning: {SAID}"]  # one ẋ read
    _, texts = _recorded(lambda: trim(torque_driven, point, ["tau_body[1]"], ["der(w_body[1])"]))
    assert len(texts) == 1 and texts[0].startswith(f"torque_driven.fmu: the FMU logged a warning: {SAID} (logged ")
    assert texts[0].endswith(" times in this run)")  # ẋ at every Newton iterate: one warning, counted


def test_a_reused_instance_raises_only_the_calls_own_warnings(torque_driven, warning_fmu):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", FmuWarning)
        point = start_point(torque_driven)
    with ModelExchange(torque_driven, point.parameters) as me:
        for _ in range(3):
            me.states_now()  # logged before the calls below: not theirs
        _, texts = _recorded(lambda: linearize(torque_driven, point, instance=me))
        assert texts == [f"torque_driven.fmu: the FMU logged a warning: {SAID}"]


def test_warnings_made_errors_do_not_hide_a_failed_trims_error(torque_driven, warning_fmu):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", FmuWarning)
        point = start_point(torque_driven)
    with warnings.catch_warnings():
        warnings.simplefilter("error", FmuWarning)
        with pytest.raises(Exception, match="more unknowns than equations"):
            trim(torque_driven, point, ["tau_body[1]", "tau_body[2]"], ["der(w_body[1])"])
        with pytest.raises(FmuWarning, match=SAID):
            linearize(torque_driven, point)


@pytest.mark.parametrize("command", [["linearize"], ["linearize", "--step-map", "0.1"],
                                     ["trim", "--unknown", "tau_body[1]", "--equation", "der(w_body[1])"]])  # fmt: skip
def test_rbfmu_linearize_and_trim_print_the_fmus_warning_as_one_line(command, torque_driven, warning_fmu, capsys):
    build = str(torque_driven.parent)
    assert main([command[0], "torque_driven", *command[1:], "--build-dir", build]) == 0
    lines = [line for line in capsys.readouterr().err.splitlines() if line]
    assert lines and all(
        line.startswith("rbfmu: warning: torque_driven.fmu: the FMU logged a warning: ") for line in lines
    )
    assert all(SAID in line for line in lines), lines


def test_the_step_map_at_a_run_shows_the_runs_real_warning(torque_driven, capsys):
    build = str(torque_driven.parent)
    args = ["linearize", "torque_driven", "--at", "0.5", "--set", "tolerance=1e-18", "--step-map", "0.1"]
    assert main([*args, "--build-dir", build]) == 0
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and "the error control holds" in lines[0] and "not tolerance = 1e-18" in lines[0], lines
