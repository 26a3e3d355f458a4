"""The model FMUs on the compiled engine : the slave classes of fmu_src/ driven directly (no
binary), so that the engine's own objects can be inspected. Each doStep is one `Engine.advance` between the
engine's checkpoint and commit; the results equal the Python API bit for bit; a refused step
leaves the instance bit-identical. No timing is asserted here (benchmarks/fmu_bench.py measures it)."""
from __future__ import annotations

import importlib.util
import math
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("pythonfmu")

from rocking_model import FlexibleOscillator, RigidBlock, Simulator, simulate  # noqa: E402
from rocking_model.engine import available  # noqa: E402
from rocking_model.ground_motion import LinearMotion  # noqa: E402
from pythonfmu.enums import Fmi2Status  # noqa: E402

pytestmark = pytest.mark.skipif(not available(), reason="the compiled engine is not built")

ROOT = Path(__file__).resolve().parents[1]
RIGID, FLEX = "RigidRockingBlock", "FlexibleRockingOscillator"
MODELS = {RIGID: RigidBlock, FLEX: FlexibleOscillator}
DT = 0.01


def slave_class(name):
    spec = importlib.util.spec_from_file_location(name, ROOT / "fmu_src" / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return getattr(module, name)


CLASSES = {name: slave_class(name) for name in (RIGID, FLEX)}


def started(name, **params):
    """An initialized instance with the given start values (parameters by name)."""
    slave = CLASSES[name](instance_name="engine-test")
    vr = {v.name: v.value_reference for v in slave.vars.values()}
    slave.setup_experiment(0.0)
    slave.enter_initialization_mode()
    for key, value in params.items():
        (slave.set_integer if isinstance(value, int) else slave.set_real)([vr[key]], [value])
    slave.exit_initialization_mode()
    return slave, vr


def record(n=200, amplitude=3.0):
    """A one-sine pulse of period 1 s sampled every DT, then zero: the block rocks with impacts."""
    t = DT * np.arange(n + 1)
    return t, np.where(t < 1.0, amplitude * np.sin(2 * np.pi * t), 0.0)


def outputs(slave, vr, names):
    """The outputs as the importer reads them (fmi2GetReal / Integer / Boolean, one reference each)."""
    getters = {"Real": slave.get_real, "Integer": slave.get_integer, "Boolean": slave.get_boolean}
    return {name: getters[slave._specs[name].type]([vr[name]])[0] for name in names}


def output_names(name):
    return [*(p.name for p in MODELS[name].OUTPUTS), "contact", "impacts", "overturned", "friction_demand",
            "painleve"]


def run_zoh(slave, vr, t, a):
    """Drive the slave as a master does: the input set at the start of each step, steps ending on t."""
    names = output_names(type(slave).__name__)
    rows = [outputs(slave, vr, names)]
    for k in range(len(t) - 1):
        slave.set_real([vr["ag"]], [float(a[k])])
        assert slave.do_step(float(t[k]), float(t[k + 1] - t[k])) is True
        rows.append(outputs(slave, vr, names))
    return {n: np.array([r[n] for r in rows], dtype=float) for n in names}


# ---------------------------------------------------------------------------------------------- engine choice
def test_the_fmu_runs_the_compiled_engine_on_the_lean_path():
    slave, _ = started(RIGID)
    assert slave._sim.engine == "c" and slave._eng is slave._sim.integrator._engine and slave._lean


# ---------------------------------------------------------------------------------------------- results
@pytest.mark.parametrize("name,scheme", [(RIGID, 1), (RIGID, 0), (FLEX, 1), (FLEX, 0)])
def test_zero_order_hold_equals_simulate_on_the_compiled_engine_bit_for_bit(monkeypatch, name, scheme):
    t, a = record(amplitude=3.0 if name == RIGID else 0.25 * 9.81)
    slave, vr = started(name, scheme=scheme, tolerance=1e-8, dt_max=1e-3)
    fmu = run_zoh(slave, vr, t, a)
    assert fmu["impacts"][-1] >= 1 and not fmu["overturned"][-1]     # rocks with impacts, stays up
    ref = simulate(MODELS[name](), (t, a), t_end=float(t[-1]), scheme=scheme, output_interval=DT, hold="zoh",
                   tolerance=1e-8, dt_max=1e-3, engine="c", impact_log_size=0)
    for key, values in fmu.items():
        np.testing.assert_array_equal(values, np.asarray(ref[key], dtype=float), err_msg=key)


@pytest.mark.parametrize("name", [RIGID, FLEX])
def test_interpolated_input_equals_the_simulator_on_the_compiled_engine(monkeypatch, name):
    """fmi2SetRealInputDerivatives (first-order hold) takes the checked path; it equals Simulator(engine="c")
    advanced under the same LinearMotion of each step, bit for bit."""
    t, a = record(n=100, amplitude=3.0 if name == RIGID else 0.25 * 9.81)
    slave, vr = started(name, scheme=1)
    sim = Simulator(MODELS[name](), "event_driven", engine="c", impact_log_size=0, on_report="raise")
    names = output_names(name)
    for k in range(len(t) - 1):
        rate = float((a[k + 1] - a[k]) / DT)
        slave.set_real([vr["ag"]], [float(a[k])])
        slave.set_real_input_derivatives([vr["ag"]], [1], [rate])
        t_end = float(t[k]) + float(t[k + 1] - t[k])
        assert slave.do_step(float(t[k]), float(t[k + 1] - t[k]))
        sim.advance(t_end, LinearMotion(float(a[k]), rate, float(t[k]), float(t[k]), t_end))
        got, want = outputs(slave, vr, names), sim.outputs()
        assert all(float(got[n]) == float(want[n]) for n in names), (k, got, want)
    assert sim.outputs()["impacts"] >= 1


# ---------------------------------------------------------------------------------------------- refused steps
class FailingEngine:
    """The slave's engine with the reports of its next advance replaced by one report of ``kind``: a failed
    step (what the C scheme reports when a step is accepted at the smallest size) or an inexact contact solve.
    Fault injection at the boundary the slave reads, as the fault suite forces the Python stepper and solvers."""

    def __init__(self, engine, kind="failed_step", message="DOP853: forced failure (engine fault case)"):
        self._engine = engine
        self.kind, self.message = kind, message
        self.armed = True

    def __getattr__(self, name):
        return getattr(self._engine, name)

    @property
    def report_count(self):
        return 1 if self.armed else self._engine.report_count

    def reports(self):
        if self.armed:
            self.armed = False
            return [(self.kind, self._engine.t, self.message)]
        return self._engine.reports()


def snapshot(slave):
    return slave._get_fmu_state()


@pytest.mark.parametrize("name", [RIGID, FLEX])
def test_a_failed_step_is_refused_with_the_state_unchanged(monkeypatch, name):
    slave, vr = started(name, phi_0=0.05)
    control, _ = started(name, phi_0=0.05)
    slave._eng = FailingEngine(slave._eng)
    slave.set_real([vr["ag"]], [0.5])
    before = snapshot(slave)
    assert slave.do_step(0.0, DT) is False                   # fmi2Discard
    assert any("refused" in m.msg and "failed step" in m.msg and "forced failure" in m.msg
               for m in slave.log_queue)
    assert snapshot(slave) == before                        # bit-identical: rolled back in C
    names = output_names(name)
    for k in range(5):                                      # the retry goes on like a control instance
        for s in (slave, control):
            s.set_real([vr["ag"]], [0.5])
            assert s.do_step(k * DT, DT)
        assert outputs(slave, vr, names) == outputs(control, vr, names)


@pytest.mark.parametrize("name", [RIGID, FLEX])
def test_an_inexact_contact_solve_is_a_warning_and_the_step_is_done(monkeypatch, name):
    slave, vr = started(name, phi_0=0.05)
    control, _ = started(name, phi_0=0.05)
    slave._eng = FailingEngine(slave._eng, "inexact_contact", "the contact problem has no exact solution (forced)")
    for s in (slave, control):
        s.set_real([vr["ag"]], [0.5])
        assert s.do_step(0.0, DT) is True
    warnings = [m for m in slave.log_queue if m.status == Fmi2Status.warning]
    assert any("inexact contact report" in m.msg and "no exact solution (forced)" in m.msg for m in warnings)
    assert slave._sim.last_reports and slave._sim.last_reports[0].kind == "inexact_contact"
    names = output_names(name)
    assert outputs(slave, vr, names) == outputs(control, vr, names)     # the step done as without the report
    slave.set_real([vr["ag"]], [0.5])
    assert slave.do_step(DT, DT) and slave._sim.last_reports == []      # the next step's reports (none)


def test_a_step_over_the_work_budget_is_refused_on_the_lean_path(monkeypatch):
    slave, vr = started(RIGID, max_steps=1, phi_0=0.05, scheme=1, dt_max=1e-4)
    slave.set_real([vr["ag"]], [0.5])
    before = snapshot(slave)
    assert slave.do_step(0.0, DT) is False
    assert any("refused" in m.msg and "max_steps" in m.msg for m in slave.log_queue), \
        [m.msg for m in slave.log_queue]
    assert snapshot(slave) == before


def test_outputs_are_read_from_the_engine_and_saved_in_the_state(monkeypatch):
    """No output is copied per step: what the importer reads, the pythonfmu getters and the saved state all
    give the engine's values now; a state restored into another instance gives the same outputs."""
    t, a = record(n=80)
    slave, vr = started(RIGID)
    for k in range(80):
        slave.set_real([vr["ag"]], [float(a[k])])
        slave.do_step(float(t[k]), DT)
    names = output_names(RIGID)
    now = slave._sim.outputs()
    assert outputs(slave, vr, names) == {n: now[n] for n in names}
    assert {n: slave.vars[vr[n]].getter() for n in names} == {n: now[n] for n in names}
    other = CLASSES[RIGID](instance_name="restored")
    other._set_fmu_state(slave._get_fmu_state())
    assert outputs(other, vr, names) == outputs(slave, vr, names)
    assert other._eng is not None and other._lean is not None   # the restored instance steps the lean way
    for s in (slave, other):
        s.set_real([vr["ag"]], [1.0])
        assert s.do_step(float(t[80]), DT)
    assert outputs(other, vr, names) == outputs(slave, vr, names)


def test_bad_input_and_bad_times_keep_their_messages_on_the_lean_path(monkeypatch):
    slave, vr = started(RIGID)
    with pytest.raises(ValueError, match=r"input ag = nan is not finite"):
        slave.set_real([vr["ag"]], [math.nan])
    with pytest.raises(ValueError, match=r"currentCommunicationPoint = 0.5 does not match the FMU time"):
        slave.do_step(0.5, DT)
    with pytest.raises(ValueError, match=r"communicationStepSize = inf is invalid"):
        slave.do_step(0.0, math.inf)
    assert slave.do_step(0.0, DT) and slave._t == DT


def test_after_overturning_the_time_moves_on_and_the_engine_is_not_called(monkeypatch):
    slave, vr = started(RIGID)
    k = 0
    while not slave.get_boolean([vr["overturned"]])[0]:
        slave.set_real([vr["ag"]], [15.0])                # 1.5 g held: the block overturns within a second
        assert slave.do_step(k * DT, DT)
        k += 1
        assert k < 200
    assert slave._frozen
    names = output_names(RIGID)
    frozen, t_engine = outputs(slave, vr, names), slave._eng.t
    for j in range(k, k + 5):
        slave.set_real([vr["ag"]], [-15.0])
        assert slave.do_step(j * DT, DT)
        assert outputs(slave, vr, names) == frozen and slave._eng.t == t_engine
    assert slave._t == (k + 4) * DT + DT
    with pytest.raises(ValueError, match="does not match the FMU time"):   # the checks still hold
        slave.do_step(0.0, DT)
