"""FMU state and co-simulation masters: fmi2Get/SetFMUstate and (de)serialization reproduce
bit-identical outputs (both FMUs, both schemes, while rocking with impacts, in flight, after overturning,
across instances), determinism across instances and runs, 100 instances per FMU in one process, reset."""
from __future__ import annotations

import importlib.util
import math
import struct
import zlib
from pathlib import Path

import pytest

fmpy = pytest.importorskip("fmpy")
pytest.importorskip("pythonfmu")
from fmpy.fmi1 import FMICallException  # noqa: E402

from fmu_instance import Instance  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
FMI2_ERROR, FMI2_DISCARD = 3, 2
RIGID, FLEX = "RigidRockingBlock", "FlexibleRockingOscillator"


# ---------------------------------------------------------------------------------------------- helpers
@pytest.fixture(scope="module")
def fmus(extracted_fmus):
    return extracted_fmus


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
    """A state restores the parameter values, the communication time and the FMI state: one taken before a
    refused late parameter change brings the instance out of the error state; a state restored into an
    instance initialized at another time brings its own time along."""
    inst = Instance(fmus[RIGID])
    inst.init(phi_0=0.05, b=0.25)
    drive(inst, RIGID, 0, 5, 0.0)
    clean = inst.fmu.getFMUstate()
    assert inst.try_set(b=0.3) == FMI2_ERROR  # a fixed parameter: refused, the error state
    assert inst.step() == FMI2_ERROR
    inst.fmu.setFMUstate(clean)
    assert inst.step() == 0
    assert inst.get("b") == [0.25]
    other = Instance(fmus[RIGID], "other")
    other.init(t0=3.0)
    other.fmu.setFMUstate(clean)
    assert other.step(0.01, t=3.0) == FMI2_ERROR  # the state is at t = 0.05
    assert "does not match the time of the instance, 0.05" in other.errors()[-1]
    other.fmu.setFMUstate(clean)
    assert other.step(0.01, t=0.05) == 0
    inst.fmu.freeFMUstate(clean)
    inst.free()
    other.free()


def test_state_taken_before_initialization_and_after_an_error(fmus):
    """A state of initialization mode restores that mode; no state can be taken in the error state (FMI 2.0),
    but a good one can be set there."""
    inst = Instance(fmus[RIGID])
    inst.fmu.setupExperiment(startTime=0.0)
    inst.fmu.enterInitializationMode()
    fresh = inst.fmu.getFMUstate()
    inst.set(b=-1.0)
    with pytest.raises(FMICallException) as info:  # invalid parameters: fmi2Error
        inst.fmu.exitInitializationMode()
    assert info.value.status == FMI2_ERROR and "invalid parameters: b = -1" in inst.errors()[-1]
    assert inst.step() == FMI2_ERROR
    with pytest.raises(FMICallException):
        inst.fmu.getFMUstate()
    inst.fmu.setFMUstate(fresh)  # back to initialization mode with the start values
    assert inst.get("b") == [0.2]
    inst.set(phi_0=0.02)
    inst.fmu.exitInitializationMode()
    assert inst.step() == 0
    inst.fmu.freeFMUstate(fresh)
    inst.free()


#: [bytes] offset of the CRC-32 in the binary's header of a serialized state (rocking_model/fmi/binary/fmi2_common.c)
CRC_OFFSET = 42


def signed(data: bytes) -> bytes:
    """A serialized state with the binary's CRC-32 recomputed over it: the checks behind it (the binary's
    fields, the slave's header, digest and fields) are reached."""
    c = CRC_OFFSET
    return data[:c] + struct.pack("<I", zlib.crc32(data[c + 4:], zlib.crc32(data[:c]))) + data[c + 4:]


def test_foreign_or_corrupted_state_is_rejected(fmus):
    rigid = Instance(fmus[RIGID], "rigid")
    flex = Instance(fmus[FLEX], "flex")
    rigid.init(phi_0=0.02)
    flex.init()
    drive(rigid, RIGID, 0, 3, 0.0)
    drive(flex, FLEX, 0, 3, 0.0)
    before = outputs(rigid, RIGID)
    good = rigid.fmu.getFMUstate()
    blob = flex.fmu.serializeFMUstate(flex.fmu.getFMUstate())
    n = len(blob)

    for bad, reason in ((blob, "belongs to FMU 'FlexibleRockingOscillator'"),
                        (blob[:-7], "corrupted (CRC-32 mismatch)"),
                        (signed(blob[:-7]), "truncated"),
                        (blob[:n - 40] + bytes([blob[n - 40] ^ 1]) + blob[n - 39:], "corrupted (CRC-32 mismatch)"),
                        (signed(blob[:n - 40] + bytes([blob[n - 40] ^ 1]) + blob[n - 39:]), "corrupted (SHA-256"),
                        (b"not a state at all", "not a serialized state of this FMU"),
                        (blob[:30] + b"\xff" * 8 + blob[38:], "corrupted (CRC-32 mismatch)"),
                        (signed(blob[:30] + b"\xff" * 8 + blob[38:]), "header of the serialized state is corrupt")):
        try:
            state = rigid.fmu.deSerializeFMUstate(bad)
        except FMICallException as exc:  # the binary's own header
            assert exc.status == FMI2_ERROR
        else:
            with pytest.raises(FMICallException) as info:
                rigid.fmu.setFMUstate(state)
            assert info.value.status == FMI2_ERROR
            rigid.fmu.freeFMUstate(state)
            assert rigid.errors()[-1].startswith("fmi2SetFMUstate: state rejected")
        assert reason in rigid.errors()[-1], rigid.errors()[-1]
        assert outputs(rigid, RIGID) == before  # the instance keeps its state
        assert rigid.step() == FMI2_ERROR  # the error state ...
        rigid.fmu.setFMUstate(good)  # ... left with a good state
        assert rigid.step() == 0
        rigid.fmu.setFMUstate(good)
        rigid.t -= 0.01
    rigid.fmu.freeFMUstate(good)
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
    good = inst.fmu.getFMUstate()
    serialized = inst.fmu.serializeFMUstate(good)
    prefix = serialized[:serialized.index(MAGIC)]  # the binary's header: FMI state and time
    for bad, reason in ((old_layout, "bad header"), (new_header, "not valid JSON")):
        state = inst.fmu.deSerializeFMUstate(signed(prefix + bad))
        with pytest.raises(FMICallException):
            inst.fmu.setFMUstate(state)
        inst.fmu.freeFMUstate(state)
        assert reason in inst.errors()[-1]
        assert outputs(inst, RIGID) == before
        assert inst.step() == FMI2_ERROR
        inst.fmu.setFMUstate(good)
        assert inst.step() == 0
        inst.fmu.setFMUstate(good)
        inst.t -= 0.01
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
        inst.fmu.setupExperiment(startTime=0.0)
        inst.fmu.enterInitializationMode()
        assert inst.get("scheme", "phi_0") == [1, 0.0]  # start values
        inst.set(scheme=1, phi_0=0.01)
        inst.fmu.exitInitializationMode()
        inst.t = 0.0
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
    with pytest.raises(ValueError, match="before initialization"):  # not initialized any more
        slave.do_step(0.0, 0.01)
