"""An FMI 2.0 Co-Simulation instance through fmpy for tests: input and output derivatives, the FMU's messages."""

from __future__ import annotations

import ctypes as C
import shutil
from pathlib import Path
from typing import ClassVar

import numpy as np

TAU = ["tau_body[1]", "tau_body[2]", "tau_body[3]"]


def logging_callbacks():
    """The one fmi2CallbackFunctions of this process whose logger appends each FMU message to
    Slave2.messages. fmpy's native logger proxy (fmpy.logging.addLoggerProxy), which formats
    the variadic message, forwards to the logger registered last, process-wide: a callbacks
    object freed after its registration leaves it dangling, and the next FMI 2.0 message of
    any instance in the process crashes it (seen under pytest-xdist, where one worker runs
    many test files). So it is registered once and lives as long as the process."""
    if Slave2._callbacks is None:
        from fmpy.fmi2 import fmi2CallbackFunctions, fmi2CallbackLoggerTYPE
        from fmpy.logging import addLoggerProxy

        cb = fmi2CallbackFunctions()
        cb.logger = fmi2CallbackLoggerTYPE(lambda env, name, status, cat, msg: Slave2.messages.append(msg.decode()))
        addLoggerProxy(C.byref(cb))
        Slave2._callbacks = cb
    return Slave2._callbacks


class Slave2:
    """One FMI 2.0 Co-Simulation instance of an FMU through fmpy, initialised at t = 0. The
    messages the FMU logs go to Slave2.messages: one list for every instance, because fmpy's
    native logger proxy (which formats the variadic message) forwards to the logger of the
    instance made last."""

    messages: ClassVar[list[str]] = []
    _callbacks = None

    def __init__(
        self, fmu: Path, start: dict[str, float] | None = None, tolerance: float | None = None, logging_on: bool = False
    ):
        """tolerance: the importer's, passed to fmi2SetupExperiment (None: toleranceDefined = false)."""
        from fmpy import extract, read_model_description
        from fmpy.fmi2 import FMU2Slave

        md = read_model_description(str(fmu))
        self.vr = {v.name: v.valueReference for v in md.modelVariables}
        self.unzip = extract(str(fmu))
        self.s = FMU2Slave(guid=md.guid, unzipDirectory=self.unzip, modelIdentifier=md.coSimulation.modelIdentifier)
        self.s.instantiate(callbacks=logging_callbacks(), loggingOn=logging_on)
        self.s.setupExperiment(tolerance=tolerance, startTime=0.0)
        for name, value in (start or {}).items():
            if name == "method":
                self.s.setInteger([self.vr[name]], [int(value)])
            else:
                self.s.setReal([self.vr[name]], [float(value)])
        self.s.enterInitializationMode()
        self.s.exitInitializationMode()
        self.t = 0.0

    def names(self, names: list[str]) -> list[int]:
        return [self.vr[n] for n in names]

    def step(self, dt: float, tau: np.ndarray, derivatives: list[np.ndarray] | None = None) -> None:
        """Set tau_body (N·m) and, if given, its derivatives of order 1, 2, ...; one doStep of dt (s)."""
        self.s.setReal(self.names(TAU), [float(v) for v in tau])
        for order, d in enumerate(derivatives or [], start=1):
            self.s.setRealInputDerivatives(self.names(TAU), [order] * 3, [float(v) for v in d])
        self.s.doStep(self.t, dt)
        self.t += dt

    def get(self, names: list[str]) -> np.ndarray:
        return np.array(self.s.getReal(self.names(names)))

    def close(self) -> None:
        self.s.freeInstance()
        shutil.rmtree(self.unzip, ignore_errors=True)
