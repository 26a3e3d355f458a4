"""FlexibleRockingOscillator FMU: validation, equivalence with the Python Simulator, both FMUs in one process."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

fmpy = pytest.importorskip("fmpy")
pytest.importorskip("pythonfmu")
from fmpy.simulation import Input  # noqa: E402
from fmpy.validation import validate_fmu  # noqa: E402

from rocking_model import FlexibleOscillator, Simulator  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
OUTPUTS = ["u", "u_dot", "phi", "phi_dot", "x", "y", "x_dot", "y_dot", "top_displacement", "energy",
           "contact", "impacts", "overturned"]


@pytest.fixture(scope="module")
def fmus(built_fmus):
    return built_fmus


def pulse_table(amplitude, t_end=2.0, period=1.0, n=201):
    t = np.linspace(0.0, t_end, n)
    ag = np.where(t < period, amplitude * np.sin(2 * np.pi * t / period), 0.0)
    return np.array(list(zip(t, ag)), dtype=[("time", np.float64), ("ag", np.float64)])


def test_validate_reports_no_problems(fmus):
    assert validate_fmu(str(fmus["FlexibleRockingOscillator"])) == []


@pytest.mark.parametrize("scheme,impact_rule", [(0, 0), (1, 0), (1, 1)])
def test_fmu_matches_python_simulator(fmus, scheme, impact_rule):
    table = pulse_table(0.25 * 9.81)   # rocks (max |phi| ~ 0.1 rad) without overturning
    start, stop, h = 0.0, 2.0, 0.01
    res = fmpy.simulate_fmu(str(fmus["FlexibleRockingOscillator"]), start_time=start, stop_time=stop,
                            output_interval=h, input=table,
                            start_values={"scheme": scheme, "impact_rule": impact_rule,
                                          "dt_max": 1e-3, "tolerance": 1e-8})
    assert np.abs(res["phi"]).max() > 1e-3 and res["impacts"][-1] >= 1
    # the Simulator on the FMU's engine, driven as fmpy drives the FMU: bit for bit
    sim = Simulator(FlexibleOscillator(impact_rule=impact_rule), scheme=scheme, dt_max=1e-3, tolerance=1e-8,
                    t0=start)
    values = table["ag"].reshape(1, -1)
    rows = [sim.outputs()]
    time, n = start, 0
    while not (time > stop or math.isclose(time, stop)):
        nxt = start + (n + 1) * h
        ag = float(Input.interpolate(time=time, t=table["time"], table=values, after_event=True)[0][0])
        sim.advance(time + (nxt - time), ag)
        time, n = nxt, n + 1
        rows.append(sim.outputs())
    assert len(res) == len(rows) == 201
    for name in OUTPUTS:
        ref = np.array([r[name] for r in rows], dtype=float)
        np.testing.assert_array_equal(res[name].astype(float), ref, err_msg=name)


def test_both_fmus_in_one_process(fmus):
    from fmpy import read_model_description
    from fmpy.fmi2 import FMU2Slave

    slaves = []
    for name in ("FlexibleRockingOscillator", "RigidRockingBlock"):
        path = str(fmus[name])
        md = read_model_description(path)
        unzip = fmpy.extract(path)
        vr = {v.name: v.valueReference for v in md.modelVariables}
        s = FMU2Slave(guid=md.guid, unzipDirectory=unzip, modelIdentifier=md.coSimulation.modelIdentifier,
                      instanceName=name)
        s.instantiate()
        s.setupExperiment(startTime=0.0)
        s.enterInitializationMode()
        s.exitInitializationMode()
        slaves.append((s, vr))
    for k in range(100):
        for s, vr in slaves:
            s.setReal([vr["ag"]], [0.8 * 9.81 if k < 50 else 0.0])
            s.doStep(currentCommunicationPoint=k * 0.01, communicationStepSize=0.01)
    for s, vr in slaves:
        assert abs(s.getReal([vr["phi"]])[0]) > 1e-4
        s.terminate()
        s.freeInstance()
