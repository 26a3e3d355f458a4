"""FMU overhead: the record scene through fmpy with the package's FMUs against a do-nothing pythonfmu FMU
driven by the same master loop; cold start of each FMU in a fresh interpreter."""
from __future__ import annotations

import gc
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
DIST = ROOT / "dist"


def build_null_fmu(dest: Path) -> Path:
    """Build benchmarks/fmu_null/NullSlave.py into dest/NullSlave.fmu (pythonfmu)."""
    from pythonfmu.builder import FmuBuilder

    dest.mkdir(parents=True, exist_ok=True)
    return Path(FmuBuilder.build_FMU(HERE / "fmu_null" / "NullSlave.py", dest=dest))


class Master:
    """A minimal fmpy co-simulation master: instantiate, set parameters, then one doStep per communication
    step with the input set at the start of the step (what fmpy.simulate_fmu does, minus its recording)."""

    def __init__(self, fmu_path, unzipdir=None):
        from fmpy import extract, read_model_description

        self.path = str(fmu_path)
        self.md = read_model_description(self.path)
        self.unzipdir = unzipdir or extract(self.path)
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.types = {v.name: v.type for v in self.md.modelVariables}

    def instantiate(self, start_values=None):
        from fmpy.fmi2 import FMU2Slave

        fmu = FMU2Slave(guid=self.md.guid, unzipDirectory=self.unzipdir,
                        modelIdentifier=self.md.coSimulation.modelIdentifier, instanceName="bench")
        fmu.instantiate()
        fmu.setupExperiment(startTime=0.0)
        fmu.enterInitializationMode()
        for name, value in (start_values or {}).items():
            kind = self.types[name]
            if kind == "Real":
                fmu.setReal([self.vr[name]], [float(value)])
            elif kind == "Integer":
                fmu.setInteger([self.vr[name]], [int(value)])
            else:
                fmu.setBoolean([self.vr[name]], [bool(value)])
        fmu.exitInitializationMode()
        return fmu

    def run(self, ag, dt, start_values=None, output="phi"):
        """Drive the FMU through the samples ``ag`` (held over each step of size dt); return
        (wall time of the stepping loop [s], output at every communication point)."""
        fmu = self.instantiate(start_values)
        vr_in, vr_out = [self.vr["ag"]], [self.vr[output]]
        out = np.empty(len(ag))
        out[0] = fmu.getReal(vr_out)[0]
        n = len(ag) - 1
        gc.collect()
        t0 = time.perf_counter()
        for k in range(n):
            fmu.setReal(vr_in, [float(ag[k])])
            fmu.doStep(currentCommunicationPoint=k * dt, communicationStepSize=dt)
            out[k + 1] = fmu.getReal(vr_out)[0]
        elapsed = time.perf_counter() - t0
        fmu.terminate()
        fmu.freeInstance()
        return elapsed, out


def simulate_fmu_time(fmu_path, unzipdir, t, ag, dt, start_values=None, output=("phi",)):
    """End-to-end fmpy.simulate_fmu (as a user calls it; the FMU already extracted: fmpy accepts the
    unzipped directory as filename) [s]."""
    import fmpy

    signal = np.array(list(zip(t, ag)), dtype=[("time", float), ("ag", float)])
    gc.collect()
    t0 = time.perf_counter()
    fmpy.simulate_fmu(str(unzipdir), start_time=0.0, stop_time=float(t[-1]),
                      output_interval=dt, input=signal, start_values=dict(start_values or {}), output=list(output))
    return time.perf_counter() - t0


COLD_START = r"""
import json, sys, time
t0 = time.perf_counter()
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave
t_import = time.perf_counter() - t0
path = sys.argv[1]
t1 = time.perf_counter()
md = read_model_description(path)
unzipdir = extract(path)
t_extract = time.perf_counter() - t1
vr = {v.name: v.valueReference for v in md.modelVariables}
# the first step sees ag = 0.5 m/s2 where the FMU takes ag as an input; a source FMU (GroundMotionSource)
# outputs ag, and setting an output is an error (fmi2SetReal answers fmi2Error = status 3)
inputs = {v.name for v in md.modelVariables if v.causality == "input"}
t2 = time.perf_counter()
fmu = FMU2Slave(guid=md.guid, unzipDirectory=unzipdir, modelIdentifier=md.coSimulation.modelIdentifier,
                instanceName="cold")
fmu.instantiate()
fmu.setupExperiment(startTime=0.0)
fmu.enterInitializationMode()
fmu.exitInitializationMode()
if "ag" in inputs:
    fmu.setReal([vr["ag"]], [0.5])
fmu.doStep(currentCommunicationPoint=0.0, communicationStepSize=0.01)
t_cold = time.perf_counter() - t2
fmu.terminate()
fmu.freeInstance()
print(json.dumps({"import_fmpy": t_import, "read_and_extract": t_extract, "instantiate_to_first_step": t_cold}))
"""


def cold_start(fmu_path, repeats: int = 3) -> dict:
    """Fresh interpreter per sample: time from FMU2Slave() (load the binary, pythonfmu imports the slave
    module and the package) to the end of the first doStep; fmpy import and unzip reported apart."""
    samples = []
    for _ in range(repeats):
        r = subprocess.run([sys.executable, "-c", COLD_START, str(fmu_path)], capture_output=True, text=True,
                           timeout=300, cwd=tempfile.gettempdir())
        if r.returncode != 0:
            return {"error": r.stderr.strip()[-2000:]}
        samples.append(json.loads(r.stdout.strip().splitlines()[-1]))
    return {k: sorted(s[k] for s in samples)[len(samples) // 2] for k in samples[0]} | {"samples": samples}
