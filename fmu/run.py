"""Alias until 0.5.0 (CHANGELOG.md): the code lives in fmu/drive/run.py, instance.py and inputs.py."""

from fmu.drive.inputs import (
    INPUT_MODES,
    InputFunction,
    check_input_hold,
    communication_points,
    input_mode,
    node_input_names,
    node_values,
    scene_input,
)
from fmu.drive.instance import (
    FMI3_WARNING,
    DirectCalls,
    FmuError,
    FmuInstance,
    settable_variables,
)
from fmu.drive.run import (
    MAX_COMMUNICATION_POINTS,
    RunResult,
    experiment,
    run_fmu,
    run_length,
    simulate,
)

__all__ = [
    "FMI3_WARNING",
    "INPUT_MODES",
    "MAX_COMMUNICATION_POINTS",
    "DirectCalls",
    "FmuError",
    "FmuInstance",
    "InputFunction",
    "RunResult",
    "check_input_hold",
    "communication_points",
    "experiment",
    "input_mode",
    "node_input_names",
    "node_values",
    "run_fmu",
    "run_length",
    "scene_input",
    "settable_variables",
    "simulate",
]
