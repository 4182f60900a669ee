"""An FMI 3.0 or 2.0 Co-Simulation instance driven by variable names through fmpy (two-FMU loops in tests)."""

from __future__ import annotations

import shutil

import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave
from fmpy.fmi3 import FMU3Slave


class Slave:
    """An FMI 3.0 or 2.0 Co-Simulation instance by variable names, through fmpy; its log kept."""

    def __init__(self, path, version: int, start_values: dict[str, float] | None = None) -> None:
        self.md = read_model_description(path)
        self.dir = extract(path)
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.log: list[str] = []
        cls = FMU3Slave if version == 3 else FMU2Slave
        self.v3 = version == 3
        self.s = cls(guid=self.md.guid, unzipDirectory=self.dir, modelIdentifier=self.md.coSimulation.modelIdentifier,
                     instanceName="i")  # fmt: skip
        if self.v3:
            self.s.instantiate(logMessage=lambda env, status, cat, msg: self.log.append(msg.decode()))
            self.s.enterInitializationMode(startTime=0.0)
        else:
            self.s.instantiate(loggingOn=False)
            self.s.setupExperiment(startTime=0.0)
            self.s.enterInitializationMode()
        if start_values:
            self.set(start_values)
        self.s.exitInitializationMode()

    def set(self, values: dict[str, float]) -> None:
        (self.s.setFloat64 if self.v3 else self.s.setReal)([self.vr[n] for n in values], list(values.values()))

    def get(self, names) -> np.ndarray:
        return np.array((self.s.getFloat64 if self.v3 else self.s.getReal)([self.vr[n] for n in names]))

    def step(self, t: float, h: float) -> None:
        self.s.doStep(t, h)

    def close(self) -> None:
        self.s.terminate()
        self.s.freeInstance()
        shutil.rmtree(self.dir, ignore_errors=True)
