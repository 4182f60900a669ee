"""Alias until 0.5.0 (CHANGELOG.md): the code lives in fmu/bench/ (benchmark.py, reference.py, steps.py)."""

from fmu.bench.benchmark import (
    CHEAP_METHODS,
    HARNESS,
    c_step_ns,
    c_step_ns_all,
    default_step,
    fmpy_step_us,
    fmu_compute_ctypes,
    generated_state,
    work_limit_walls,
)
from fmu.bench.reference import (
    REFERENCE,
    reference_features,
    reference_inputs,
    reference_parameters,
    reference_state,
    reference_step_ns,
)
from fmu.bench.steps import (
    BENCH_PAIRS,
    BENCH_STEPS,
    REFERENCE_METHODS,
    TARGET_NS,
    WORK_LIMIT_SCENES,
    Interleaved,
    interleaved_step_ns,
    main,
)

__all__ = [
    "BENCH_PAIRS",
    "BENCH_STEPS",
    "CHEAP_METHODS",
    "HARNESS",
    "REFERENCE",
    "REFERENCE_METHODS",
    "TARGET_NS",
    "WORK_LIMIT_SCENES",
    "Interleaved",
    "c_step_ns",
    "c_step_ns_all",
    "default_step",
    "fmpy_step_us",
    "fmu_compute_ctypes",
    "generated_state",
    "interleaved_step_ns",
    "main",
    "reference_features",
    "reference_inputs",
    "reference_parameters",
    "reference_state",
    "reference_step_ns",
    "work_limit_walls",
]
