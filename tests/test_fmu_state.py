"""FMU state and co-simulation masters (issue 5): fmi2Get/SetFMUstate and (de)serialization reproduce
bit-identical outputs (both FMUs, both schemes, while rocking with impacts, in flight, after overturning,
across instances), determinism across instances and runs, 100 instances per FMU in one process, reset."""
from __future__ import annotations

import importlib.util
import math
from pathlib import Path

import pytest

fmpy = pytest.importorskip("fmpy")
pytest.importorskip("pythonfmu")
from fmpy import extract, read_model_description  # noqa: E402
from fmpy.fmi1 import FMICallException  # noqa: E402
from fmpy.fmi2 import (FMU2Slave, fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE,  # noqa: E402
                       fmi2CallbackFunctions, fmi2CallbackLoggerTYPE)

ROOT = Path(__file__).resolve().parents[1]
FMI2_ERROR, FMI2_DISCARD = 3, 2
RIGID, FLEX = "RigidRockingBlock", "FlexibleRockingOscillator"


# ---------------------------------------------------------------------------------------------- helpers
@pytest.fixture(scope="module")
def fmus(tmp_path_factory):
    spec = importlib.util.spec_from_file_location("build_fmu", ROOT / "build_fmu.py")
    build = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(build)
    dest = tmp_path_factory.mktemp("fmus")
    paths = build.build_all(dest, names=[RIGID, FLEX])
    return {p.stem: (p, read_model_description(str(p)), extract(str(p))) for p in paths}


class Instance:
    """One FMU2Slave instance with a logger that records (status, message)."""

    def __init__(self, fmu, name="instance"):
        path, md, unzip = fmu
        self.vars = {v.name: v for v in md.modelVariables}
        self.messages: list[tuple[int, str]] = []
        cb = fmi2CallbackFunctions()
        cb.logger = fmi2CallbackLoggerTYPE(self._log)
        cb.allocateMemory = fmi2CallbackAllocateMemoryTYPE(fmpy.calloc)
        cb.freeMemory = fmi2CallbackFreeMemoryTYPE(fmpy.free)
        # no fmpy.logging.addLoggerProxy: its proxy forwards to one process-wide Python logger (the last one
        # registered), so the messages of several instances would end up in one list. pythonfmu passes the
        # message itself as the format string, so the plain callback gets the text.
        self._cb = cb  # keep the callbacks alive
        self.fmu = FMU2Slave(guid=md.guid, unzipDirectory=unzip,
                             modelIdentifier=md.coSimulation.modelIdentifier, instanceName=name)
        self.fmu.instantiate(loggingOn=True, callbacks=cb)
        self.t = 0.0

    def _log(self, env, instance, status, category, message):
        self.messages.append((int(status), message.decode("utf-8", "replace")))

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
        """doStep; return the status (0 OK, 2 discard) and advance self.t on success."""
        t = self.t if t is None else t
        try:
            self.fmu.doStep(t, dt)
        except FMICallException as exc:
            return exc.status
        self.t = t + dt
        return 0

    def errors(self):
        return [m for s, m in self.messages if s == FMI2_ERROR]

    def free(self):
        self.fmu.terminate()
        self.fmu.freeInstance()



OUT = {RIGID: ("phi", "phi_dot", "x", "y", "x_dot", "y_dot", "energy", "contact", "impacts", "overturned"),
       FLEX: ("u", "u_dot", "phi", "phi_dot", "x", "y", "x_dot", "y_dot", "top_displacement", "energy",
              "contact", "impacts", "overturned")}


def ag_of(k, amplitude):
    """A one-sine pulse of period 1 s sampled at the communication points (step 0.01 s), then zero."""
    return amplitude * math.sin(2 * math.pi * k / 100) if k < 100 else 0.0


def outputs(inst, kind):
    return tuple(inst.get(*OUT[kind]))


def drive(inst, kind, k0, n, amplitude):
    """n steps of 0.01 s from step index k0; the outputs after each step (exact values, no rounding)."""
    rows = []
    for k in range(k0, k0 + n):
        inst.set(ag=ag_of(k, amplitude))
        assert inst.step() == 0, inst.errors()
        rows.append(outputs(inst, kind))
    return rows


# scenes: (FMU, start values, pulse amplitude [m/s2], steps before the save, phase check at the save)
SCENES = {
    "rigid-rocking-impacts": (RIGID, {"e_N": 0.0}, 3.0, 140, lambda o: o[8] >= 1 and o[7] in (1, 2)),
    "rigid-flight": (RIGID, {"e_N": 1.0}, 3.0, 80, lambda o: o[7] == 3),
    "rigid-overturned": (RIGID, {}, 8.0, 150, lambda o: o[9]),
    "flex-rocking-impacts": (FLEX, {}, 4.0, 150, lambda o: o[11] >= 1),
    "flex-full-contact-vibrating": (FLEX, {"u_0": 5e-4}, 0.0, 7, lambda o: o[10] == 0 and o[0] != 5e-4),
}


@pytest.mark.parametrize("scheme", [0, 1])
@pytest.mark.parametrize("scene", list(SCENES))
def test_save_step_restore_step_is_bit_identical(fmus, scene, scheme):
    kind, params, amplitude, n_before, phase = SCENES[scene]
    inst = Instance(fmus[kind])
    inst.init(scheme=scheme, **params)
    drive(inst, kind, 0, n_before, amplitude)
    at_save = outputs(inst, kind)
    assert phase(at_save), at_save
    t_save = inst.t
    state = inst.fmu.getFMUstate()
    blob = inst.fmu.serializeFMUstate(state)
    first = drive(inst, kind, n_before, 60, amplitude)
    assert first[-1] != at_save or scene == "rigid-overturned"  # it moved on
    # rollback and redo: bit-identical
    inst.fmu.setFMUstate(state)
    inst.t = t_save
    assert outputs(inst, kind) == at_save
    assert drive(inst, kind, n_before, 60, amplitude) == first
    # the same state can be restored again (restoring does not hand the saved objects to the instance)
    inst.fmu.setFMUstate(state)
    inst.t = t_save
    assert drive(inst, kind, n_before, 60, amplitude) == first
    # serialize / deserialize round trip, into this instance and into a fresh one
    restored = inst.fmu.deSerializeFMUstate(blob)
    inst.fmu.setFMUstate(restored)
    inst.t = t_save
    assert drive(inst, kind, n_before, 60, amplitude) == first
    other = Instance(fmus[kind], "other")
    other.init()  # default parameters: the state brings the parameters along
    other_state = other.fmu.deSerializeFMUstate(blob)
    other.fmu.setFMUstate(other_state)
    other.t = t_save
    assert outputs(other, kind) == at_save
    assert drive(other, kind, n_before, 60, amplitude) == first
    assert not inst.errors() and not other.errors()
    for fmu_, s in ((inst.fmu, state), (inst.fmu, restored), (other.fmu, other_state)):
        fmu_.freeFMUstate(s)
    inst.free()
    other.free()


def test_state_captures_status_flags_and_parameters(fmus):
    """A state taken before a rejected late parameter change does not carry the pending error; one taken
    after it does; the restored state brings back the parameter values and the communication time."""
    inst = Instance(fmus[RIGID])
    inst.init(phi_0=0.05, b=0.25)
    drive(inst, RIGID, 0, 5, 0.0)
    clean = inst.fmu.getFMUstate()
    inst.set(b=0.3)  # rejected: error logged, next step discarded
    pending = inst.fmu.getFMUstate()
    inst.fmu.setFMUstate(clean)
    assert inst.step() == 0
    inst.fmu.setFMUstate(pending)
    inst.t = 0.05
    assert inst.step() == FMI2_DISCARD and inst.step() == 0
    assert inst.get("b") == [0.25]
    # a state restored into an instance initialized at another time brings its own time along
    other = Instance(fmus[RIGID], "other")
    other.init(t0=3.0)
    other.fmu.setFMUstate(clean)
    assert other.step(0.01, t=3.0) == FMI2_DISCARD  # the state is at t = 0.05
    assert "does not match the FMU time 0.05" in other.errors()[-1]
    assert other.step(0.01, t=0.05) == 0
    for s in (clean, pending):
        inst.fmu.freeFMUstate(s)
    inst.free()
    other.free()


def test_state_taken_before_initialization_and_after_an_error(fmus):
    inst = Instance(fmus[RIGID])
    inst.fmu.setupExperiment(startTime=0.0)
    inst.fmu.enterInitializationMode()
    fresh = inst.fmu.getFMUstate()
    inst.set(b=-1.0)
    with pytest.raises(FMICallException):  # invalid parameters: fmi2Fatal (pythonfmu 0.7), instance kept
        inst.fmu.exitInitializationMode()
    assert inst.step() == FMI2_DISCARD
    failed = inst.fmu.getFMUstate()
    inst.fmu.setFMUstate(fresh)  # back to initialization mode with the start values
    inst.set(phi_0=0.02)
    inst.fmu.exitInitializationMode()
    assert inst.step() == 0
    inst.fmu.setFMUstate(failed)
    inst.t = 0.0
    assert inst.step() == FMI2_DISCARD and "invalid parameters: b = -1" in inst.errors()[-1]
    inst.free()


def test_foreign_or_corrupted_state_is_rejected(fmus):
    rigid = Instance(fmus[RIGID], "rigid")
    flex = Instance(fmus[FLEX], "flex")
    rigid.init(phi_0=0.02)
    flex.init()
    drive(rigid, RIGID, 0, 3, 0.0)
    drive(flex, FLEX, 0, 3, 0.0)
    before = outputs(rigid, RIGID)
    blob = flex.fmu.serializeFMUstate(flex.fmu.getFMUstate())
    for bad, reason in ((blob, "belongs to FMU 'FlexibleRockingOscillator'"),
                        (blob[:-7], "truncated"),
                        (blob[:40] + bytes([blob[40] ^ 1]) + blob[41:], "corrupted"),
                        (b"not a state at all", "not a rocking_model FMU state")):
        state = rigid.fmu.deSerializeFMUstate(bad)
        rigid.fmu.setFMUstate(state)
        assert outputs(rigid, RIGID) == before  # the instance keeps its state
        assert rigid.errors()[-1].startswith("fmi2SetFMUstate: state rejected") and reason in rigid.errors()[-1]
        assert rigid.step() == FMI2_DISCARD  # discarded once
        rigid.t -= 0.0
        assert rigid.step() == 0
        before = outputs(rigid, RIGID)
    rigid.free()
    flex.free()


class _Gadget:
    """Unpickling this runs a shell command: what a pickle-based state format would execute."""

    def __reduce__(self):
        import os
        return (os.system, ("touch pwned",))


def test_state_bytes_never_execute_code(fmus, tmp_path, monkeypatch):
    """The state format is data only (rocking_model.fmi_state): a pickle gadget, in the old pickle layout or
    inside a well-formed new header, is rejected and nothing runs."""
    import hashlib
    import pickle

    from rocking_model.fmi_state import MAGIC, decode_state, encode_state

    monkeypatch.chdir(tmp_path)
    payload = pickle.dumps({"format": 1, "fields": _Gadget()}, protocol=5)
    old_layout = b"rocking_model FMU state v1\n" + hashlib.sha256(payload).digest() + payload
    blob = encode_state({"x": 1})
    assert decode_state(blob) == {"x": 1}
    # the gadget behind a valid header of the new format (magic, version, length, digest)
    new_header = blob[:len(MAGIC) + 4] + len(payload).to_bytes(4, "little") + hashlib.sha256(payload).digest() \
        + payload
    inst = Instance(fmus[RIGID])
    inst.init(phi_0=0.02)
    drive(inst, RIGID, 0, 2, 0.0)
    before = outputs(inst, RIGID)
    for bad, reason in ((old_layout, "bad header"), (new_header, "not valid JSON")):
        inst.fmu.setFMUstate(inst.fmu.deSerializeFMUstate(bad))
        assert reason in inst.errors()[-1]
        assert outputs(inst, RIGID) == before
        assert inst.step() == FMI2_DISCARD and inst.step() == 0
        before = outputs(inst, RIGID)
    assert not (tmp_path / "pwned").exists()
    inst.free()


def test_model_description_declares_state_capabilities(fmus):
    for kind in (RIGID, FLEX):
        cs = fmus[kind][1].coSimulation
        assert cs.canGetAndSetFMUstate and cs.canSerializeFMUstate


# ---------------------------------------------------------------------------------------------- determinism
@pytest.mark.parametrize("kind", [RIGID, FLEX])
def test_determinism_across_instances_and_runs(fmus, kind):
    runs = []
    for scheme in (0, 1):
        a, b = Instance(fmus[kind], "a"), Instance(fmus[kind], "b")
        a.init(scheme=scheme)
        b.init(scheme=scheme)
        rows_a, rows_b = [], []
        for k in range(150):  # interleaved: the instances share the interpreter
            rows_a += drive(a, kind, k, 1, 3.5)
            rows_b += drive(b, kind, k, 1, 3.5)
        assert rows_a == rows_b
        c = Instance(fmus[kind], "c")  # a later run
        c.init(scheme=scheme)
        assert drive(c, kind, 0, 150, 3.5) == rows_a
        assert max(r[OUT[kind].index("impacts")] for r in rows_a) >= 1
        for inst in (a, b, c):
            inst.free()
        runs.append(rows_a)
    assert runs[0] != runs[1]  # the schemes differ (the test can tell runs apart)


# ---------------------------------------------------------------------------------------------- many instances
def test_100_instances_of_each_fmu_in_one_process(fmus):
    n = 100
    insts = {kind: [Instance(fmus[kind], f"{kind}{i}") for i in range(n)] for kind in (RIGID, FLEX)}
    for kind, group in insts.items():
        for i, inst in enumerate(group):
            inst.init(scheme=i % 2, phi_0=0.001 * (i % 7))
    rows = {kind: [[] for _ in range(n)] for kind in insts}
    for k in range(20):  # both FMUs stepped in lock step, as a master would
        for kind, group in insts.items():
            for i, inst in enumerate(group):
                rows[kind][i] += drive(inst, kind, k, 1, 2.0)
    for kind, group in insts.items():
        # instances with the same settings agree bit for bit; reference: a lone instance run afterwards
        for i in range(14):
            same = [rows[kind][j] for j in range(i, n, 14)]
            assert all(r == same[0] for r in same)
        ref = Instance(fmus[kind], "ref")
        ref.init(scheme=3 % 2, phi_0=0.001 * (3 % 7))
        assert drive(ref, kind, 0, 20, 2.0) == rows[kind][3]
        ref.free()
        assert not any(inst.errors() for inst in group)
        for inst in group:
            inst.free()


def test_reset_returns_to_the_initial_state(fmus):
    for kind in (RIGID, FLEX):
        inst = Instance(fmus[kind])
        inst.init(scheme=1, phi_0=0.01)
        first = drive(inst, kind, 0, 80, 3.0)
        inst.fmu.reset()
        assert inst.get("scheme", "phi_0") == [1, 0.0]  # start values
        inst.init(scheme=1, phi_0=0.01)
        assert drive(inst, kind, 0, 80, 3.0) == first
        inst.free()


def test_reset_method_of_the_slave_class():
    spec = importlib.util.spec_from_file_location(RIGID, ROOT / "fmu_src" / f"{RIGID}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    slave = module.RigidRockingBlock(instance_name="direct")
    vr = {v.name: v.value_reference for v in slave.vars.values()}
    slave.setup_experiment(0.0)
    slave.set_real([vr["phi_0"]], [0.05])
    slave.exit_initialization_mode()
    assert slave.do_step(0.0, 0.01)
    slave.reset()
    assert slave.get_real([vr["phi_0"], vr["phi"]]) == [0.0, 0.0]
    assert slave.do_step(0.0, 0.01) is False  # not initialized any more
