"""The FMU in an independent co-simulation master: libcosim (Open Simulation Platform) through libcosimpy.

libcosimpy runs FMI 2.0 Co-Simulation FMUs only (its FMI 3.0 path crashes in
add_local_slave with libcosimpy 0.0.6) and skips FMI enumerations: it never sees
`method`, so the FMU runs its default method there (docs/importing.md). libcosim steps
on an integer nanosecond clock: communication point t_i = i·Δ/1e9 s and step
t_{i+1} − t_i. Driven with those same communication points, fmpy must give the same
results bit for bit: the FMU's result depends only on its inputs, parameters and the
step sizes it is given.
"""

from __future__ import annotations

import numpy as np
import pytest
from fmpy import extract, instantiate_fmu, read_model_description

STEP_NS, STEPS = 1_000_000, 500  # 1 ms communication step, 0.5 s
STATES = [f"q[{k}]" for k in (1, 2, 3, 4)] + [f"w_body[{k}]" for k in (1, 2, 3)]


def _libcosim_run(fmu, vr: dict[str, int], start: dict[str, float]) -> tuple[np.ndarray, list[str]]:
    pytest.importorskip("libcosimpy")
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimObserver import CosimObserver
    from libcosimpy.CosimSlave import CosimLocalSlave

    log_output_level(CosimLogLevel.ERROR)  # FMI Library still reports that `time` has no start (harmless)
    execution = CosimExecution.from_step_size(step_size=STEP_NS)
    index = execution.add_local_slave(local_slave=CosimLocalSlave(fmu_path=str(fmu), instance_name="body"))
    seen = [v.name.decode() for v in execution.slave_variables(index)]
    for name, value in start.items():
        execution.real_initial_value(index, vr[name], value)
    observer = CosimObserver.create_last_value()
    execution.add_observer(observer=observer)
    rows = []
    for _ in range(STEPS):
        assert execution.step()
        rows.append(observer.last_real_values(index, [vr[n] for n in STATES]))
    return np.array(rows), seen


def _fmpy_run(fmu, md, vr: dict[str, int], start: dict[str, float]) -> np.ndarray:
    """fmpy's FMU2Slave on libcosim's communication points."""
    slave = instantiate_fmu(extract(str(fmu)), md, fmi_type="CoSimulation")
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    slave.setReal([vr[n] for n in start], list(start.values()))
    slave.exitInitializationMode()
    rows = []
    for i in range(STEPS):
        t0, t1 = i * STEP_NS / 1e9, (i + 1) * STEP_NS / 1e9
        slave.doStep(currentCommunicationPoint=t0, communicationStepSize=t1 - t0)
        rows.append(slave.getReal([vr[n] for n in STATES]))
    slave.terminate()
    slave.freeInstance()
    return np.array(rows)


@pytest.mark.slow
def test_libcosim_run_equals_fmpy_bit_for_bit(fmi2_fmus):
    fmu = fmi2_fmus["heavy_top"]
    md = read_model_description(str(fmu))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    start = {"w_body[3]": 180.0, "h_max": 2e-4}  # set through each master's own API
    cosim, seen = _libcosim_run(fmu, vr, start)
    reference = _fmpy_run(fmu, md, vr, start)
    assert np.array_equal(cosim, reference)
    assert abs(cosim[-1, 6] - 180.0) < 1e-9 * 180.0  # the start value reached the FMU: ω3 of the top is conserved
    # libcosim skips the Enumeration `method`: it cannot choose the integrator
    assert "method" not in seen and "w_body[3]" in seen
