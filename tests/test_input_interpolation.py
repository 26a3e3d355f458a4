"""Input interpolation: fmi2SetRealInputDerivatives of order 1 makes ag vary linearly over a
communication step inside the integrator. Driven at the record's own sampling (0.01 s) with the record's
slope, the FMU reproduces `simulate(..., hold="exact")` to round-off, where a zero-order hold is off by
O(dt). Also: bad orders, references and rates are fmi2Error; the rate is part of the FMU state."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

fmpy = pytest.importorskip("fmpy")
from fmpy.fmi1 import FMICallException  # noqa: E402

from fmu_instance import FMI2_DISCARD, FMI2_ERROR, Instance  # noqa: E402
from rocking_model import RigidBlock, simulate  # noqa: E402
from rocking_model.fmi import run_fmu_record  # noqa: E402
from rocking_model.ground_motion import SampledMotion  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
RIGID, STOREY = "RigidRockingBlock", "LinearBuildingStorey"
#: [s] sampling of the record and communication step
DT = 0.01


@pytest.fixture(scope="module")
def fmus(extracted_fmus):
    return extracted_fmus


def record(peak: float, seed: int = 3, duration: float = 3.0):
    """A real-looking record: smoothed white noise under a bell envelope, sampled at DT, scaled to ``peak``
    [m/s2]."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, duration + 1e-9, DT)
    a = np.convolve(rng.standard_normal(t.size), np.ones(15) / 15, "same") * np.exp(-((t - 1.5) / 0.7) ** 2)
    return t, a * (peak / np.abs(a).max())


def test_first_order_hold_reproduces_the_exact_record(fmus):
    """Rocking with impacts under a record (peak 4 m/s2, uplift at 1.96 m/s2; max |phi| = 0.35 alpha, far from
    overturning), 3 s: with the record's slope
    the FMU matches simulate(hold="exact") to round-off; the zero-order hold is off by O(dt)."""
    t, a = record(4.0)
    block = RigidBlock(b=0.2, h=1.0)
    ref = simulate(block, SampledMotion(t, a), t_end=3.0, scheme="event_driven", tolerance=1e-10,
                   output_interval=DT, hold="exact")
    assert np.abs(ref.phi).max() > 0.2 * block.alpha and ref.impacts[-1] >= 1  # it rocks, with impacts
    params = {"tolerance": 1e-10, "scheme": 1}
    errors = {}
    for hold in ("linear", "zoh"):
        out = run_fmu_record(fmus[RIGID][0], t, a, step=DT, stop_time=3.0, hold=hold, start_values=params)
        errors[hold] = np.abs(out["phi"] - np.interp(out["time"], ref.t, ref.phi)).max()
    assert errors["linear"] <= 1e-9 * block.alpha, errors
    assert errors["zoh"] >= 1e3 * max(errors["linear"], 1e-12), errors


def test_rate_is_applied_and_kept_in_the_state(fmus):
    """A constant ramp given once as value + rate: the FMU extrapolates it over the following steps; a state
    saved between steps carries the rate (save -> step -> restore -> step is bit-identical); fmi2SetReal
    resets the rate."""
    inst = Instance(fmus[RIGID])
    inst.init(phi_0=0.0)
    vr = inst.vars["ag"].valueReference
    inst.set(ag=0.0)
    inst.fmu.setRealInputDerivatives([vr], [1], [20.0])  # ag = 20 t m/s2: uplift at t = 0.098 s
    for _ in range(10):
        assert inst.step() == 0
    saved, t_saved = inst.fmu.getFMUState(), inst.t
    rows = []
    for _ in range(10):
        assert inst.step() == 0
        rows.append(inst.get("phi", "phi_dot"))
    assert abs(rows[-1][0]) > 0  # the ramp passed the uplift level: it rocks
    inst.fmu.setFMUState(saved)
    inst.t = t_saved
    again = []
    for _ in range(10):
        assert inst.step() == 0
        again.append(inst.get("phi", "phi_dot"))
    assert again == rows
    # a held value instead: no uplift below g tan(alpha)
    inst.fmu.setFMUState(saved)
    inst.t = t_saved
    inst.set(ag=1.0)
    for _ in range(10):
        assert inst.step() == 0
    assert inst.get("phi") == [0.0]
    inst.fmu.freeFMUState(saved)
    inst.free()


def test_ramp_leaving_the_input_range_is_discarded(fmus):
    inst = Instance(fmus[RIGID])
    inst.init()
    vr = inst.vars["ag"].valueReference
    inst.set(ag=990.0)
    inst.fmu.setRealInputDerivatives([vr], [1], [2000.0])
    assert inst.step() == FMI2_DISCARD  # 990 + 2000 * 0.01 > 1000
    assert "ag at the end of the step" in inst.errors()[-1] and "1000" in inst.errors()[-1]
    assert inst.step(0.001) == 0  # a shorter step stays inside the range
    inst.free()


@pytest.mark.parametrize("orders, rates, fragment", [([2], [1.0], "order = 2 is not supported; allowed: 1"),
                                                      ([0], [1.0], "order = 0 is not supported"),
                                                      ([1], [math.nan], "rate of ag = nan is not finite"),
                                                      ([1], [1e9], "rate of ag = 1e+09 is out of range")])
def test_bad_derivatives_are_errors(fmus, orders, rates, fragment):
    inst = Instance(fmus[RIGID])
    inst.init()
    with pytest.raises(FMICallException) as info:
        inst.fmu.setRealInputDerivatives([inst.vars["ag"].valueReference], orders, rates)
    assert info.value.status == FMI2_ERROR
    assert fragment in inst.errors()[-1], inst.errors()
    inst.free()


def test_only_real_inputs_and_interpolating_fmus(fmus):
    inst = Instance(fmus[RIGID])
    inst.init()
    with pytest.raises(FMICallException):
        inst.fmu.setRealInputDerivatives([inst.vars["b"].valueReference], [1], [1.0])
    assert "'b', not a Real input" in inst.errors()[-1]
    inst.free()
    assert fmus[RIGID][1].coSimulation.canInterpolateInputs
    storey = fmus[STOREY]
    assert not storey[1].coSimulation.canInterpolateInputs
    inst = Instance(storey)
    inst.init()
    with pytest.raises(FMICallException):
        inst.fmu.setRealInputDerivatives([inst.vars["ag"].valueReference], [1], [1.0])
    assert "canInterpolateInputs = false" in inst.errors()[-1]
    inst.free()


def test_first_order_hold_under_other_arithmetic_kernels():
    """The record test again in a subprocess under other kernels (glibc without AVX2/FMA, OpenBLAS Prescott,
    numpy's dispatch off: `roundoff.kernel_env`), where round-off differs: the same bounds hold."""
    import subprocess
    import sys

    import roundoff

    node = f"{Path(__file__).resolve()}::test_first_order_hold_reproduces_the_exact_record"
    proc = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", node],
                          env=roundoff.kernel_env(), capture_output=True, text=True, timeout=300, cwd=ROOT)
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-2000:]
    assert "1 passed" in proc.stdout
