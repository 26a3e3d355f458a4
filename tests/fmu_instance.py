"""One FMU instance driven through fmpy's FMU2Slave, for the tests: its own message list (status, text),
fed by `rocking_model.fmi.fmpy_callbacks` (the FMU passes every message as data; fmpy's proxy formats it),
with logging off, since errors and warnings reach the logger anyway."""
from __future__ import annotations

import pytest
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Slave

from rocking_model.fmi import fmpy_callbacks

FMI2_OK, FMI2_WARNING, FMI2_DISCARD, FMI2_ERROR = 0, 1, 2, 3


class Instance:
    """One FMU2Slave instance with a logger that records (status, message)."""

    def __init__(self, fmu, name="instance"):
        path, md, unzip = fmu
        self.vars = {v.name: v for v in md.modelVariables}
        self._sink: list[tuple[int, str, str]] = []
        # the FMU passes every message as data ("%s"): fmpy's proxy formats it, fmpy_callbacks routes it
        # to this instance's list; logging is off, errors and warnings arrive anyway
        self._cb = fmpy_callbacks(self._sink)  # keep the callbacks alive
        self.fmu = FMU2Slave(guid=md.guid, unzipDirectory=unzip,
                             modelIdentifier=md.coSimulation.modelIdentifier, instanceName=name)
        self.fmu.instantiate(loggingOn=False, callbacks=self._cb)
        self.t = 0.0

    @property
    def messages(self) -> list[tuple[int, str]]:
        return [(status, text) for status, _, text in self._sink]

    def try_set(self, **values) -> int:
        """set(); return the status (0 OK, 3 error)."""
        try:
            self.set(**values)
        except FMICallException as exc:
            return exc.status
        return 0

    def set(self, **values):
        for name, value in values.items():
            var = self.vars[name]
            if var.type == "Real":
                self.fmu.setReal([var.valueReference], [float(value)])
            elif var.type == "Integer":
                self.fmu.setInteger([var.valueReference], [int(value)])
            else:
                self.fmu.setBoolean([var.valueReference], [bool(value)])

    def get(self, *names):
        out = []
        for name in names:
            var = self.vars[name]
            getter = {"Real": self.fmu.getReal, "Integer": self.fmu.getInteger,
                      "Boolean": self.fmu.getBoolean}[var.type]
            out.append(getter([var.valueReference])[0])
        return out

    def init(self, t0=0.0, **params):
        self.fmu.setupExperiment(startTime=t0)
        self.fmu.enterInitializationMode()
        self.set(**params)
        self.fmu.exitInitializationMode()
        self.t = t0

    def step(self, dt=0.01, t=None):
        """doStep; return the status (0 OK, 2 discard, 3 error) and advance self.t on success."""
        t = self.t if t is None else t
        try:
            self.fmu.doStep(t, dt)
        except FMICallException as exc:
            return exc.status
        self.t = t + dt
        return 0

    def errors(self):
        return [m for s, m in self.messages if s == FMI2_ERROR]

    def error_init(self, **params):
        """init() with invalid parameters: fmi2ExitInitializationMode returns fmi2Error; returns its
        message."""
        with pytest.raises(FMICallException) as info:
            self.init(**params)
        assert info.value.status == FMI2_ERROR
        errors = self.errors()
        assert len(errors) == 1, self.messages
        return errors[0]

    def state(self):
        return self.fmu.getFMUState()

    def free(self):
        self.fmu.terminate()
        self.fmu.freeInstance()
