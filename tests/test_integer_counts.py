"""The Integer outputs impacts and painleve of the self-contained FMUs: the engine counts them in 64
bits, and a state may hold any count >= 0 (a long run counts past 2**31 - 1; anyone writing a state can put
one there, recomputing both CRC-32s). fmi2GetInteger saturates them at 2147483647, the largest fmi2Integer (as
the variables' descriptions say), where it used to convert the count to int unchecked (undefined behaviour; the
reproducer below aborts under UBSan on that code: fuzz/regressions, run by tests/test_sanitize.py)."""
from __future__ import annotations

import struct
import sys
import zlib
from pathlib import Path

import pytest

pytest.importorskip("fmpy")

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
import fault_harness as fh  # noqa: E402
import sanitize  # noqa: E402

sys.path.remove(str(HERE))

INT_MAX = 2**31 - 1
#: the serialized state (rocking_model/fmi/binary/fmi2_common.h): a 46-byte header with its CRC-32 at 42 (over
#: the rest), then the engine FMU's payload ending ... int64 impacts, int32 overturned, int64 n_steps, 3 doubles,
#: int64 painleve, and its own CRC-32 (standalone/fmi2_engine.c)
HEADER, CRC_AT = 46, 42
FIELD_FROM_END = {"impacts": 56, "painleve": 12}


def patched(state: bytes, field: str, count: int) -> bytes:
    """The state with the engine's `field` set to `count`, both CRC-32s recomputed as the format defines them."""
    b = bytearray(state)
    at = len(b) - FIELD_FROM_END[field]
    b[at:at + 8] = struct.pack("<q", count)
    b[-4:] = struct.pack("<I", zlib.crc32(bytes(b[HEADER:-4])))
    b[CRC_AT:CRC_AT + 4] = struct.pack("<I", zlib.crc32(bytes(b[HEADER:]), zlib.crc32(bytes(b[:CRC_AT]))))
    return bytes(b)


def engine_count(state: bytes, field: str) -> int:
    at = len(state) - FIELD_FROM_END[field]
    return struct.unpack("<q", state[at:at + 8])[0]


@pytest.fixture(scope="module")
def standalone(build_module, tmp_path_factory):
    try:
        return fh.standalone_fmus(build_module, tmp_path_factory)
    except Exception as exc:  # no C compiler: the build's own message
        pytest.skip(f"the self-contained FMUs cannot be built here: {exc}")


def _slave(fmu: Path):
    import fmpy
    from fmpy.fmi2 import FMU2Slave

    md = fmpy.read_model_description(str(fmu))
    s = FMU2Slave(guid=md.guid, unzipDirectory=fmpy.extract(str(fmu)),
                  modelIdentifier=md.coSimulation.modelIdentifier, instanceName="counts")
    return s, {v.name: v.valueReference for v in md.modelVariables}


@pytest.mark.parametrize("field", ["impacts", "painleve"])
@pytest.mark.parametrize("scheme", [0, 1])
def test_counts_past_int_max_saturate(standalone, scheme, field):
    fmu = standalone["RigidRockingBlock"]
    s, vr = _slave(fmu)
    s.instantiate()
    s.setInteger([vr["scheme"]], [scheme])
    s.setupExperiment(startTime=0.0)
    s.enterInitializationMode()
    s.exitInitializationMode()
    t, h = 0.0, 0.01

    def step(n, ag):
        nonlocal t
        for _ in range(n):
            s.setReal([vr["ag"]], [ag])
            s.doStep(t, h)
            t += h

    step(30, 2.5)                      # a pulse that rocks the block
    t_saved = t
    st = s.getFMUstate()
    state = bytes(s.serializeFMUstate(st))
    s.freeFMUstate(st)
    for count in (INT_MAX, INT_MAX + 1, 2**40):
        # accepted (the engine takes any count >= 0); the slave's copy of the output is the state's own value
        st = s.deSerializeFMUstate(patched(state, field, count))
        s.setFMUstate(st)
        s.freeFMUstate(st)
        t = t_saved
        before = s.getInteger([vr[field]])[0]
        assert 0 <= before <= INT_MAX
        step(1, 0.0)
        # the engine's count is read into the output: saturated (count >= INT_MAX here)
        assert s.getInteger([vr[field]]) == [INT_MAX]
        # the state the FMU writes now holds the 64-bit count, and the FMU takes it back
        st = s.getFMUstate()
        again = bytes(s.serializeFMUstate(st))
        s.freeFMUstate(st)
        assert engine_count(again, field) >= count
        st = s.deSerializeFMUstate(again)
        s.setFMUstate(st)
        s.freeFMUstate(st)
        assert s.getInteger([vr[field]]) == [INT_MAX]
    s.terminate()
    s.freeInstance()


def test_count_description_says_it_saturates(standalone):
    import fmpy

    for fmu in standalone.values():
        md = fmpy.read_model_description(str(fmu))
        for v in md.modelVariables:
            if v.name in ("impacts", "painleve"):
                assert "saturates at 2147483647" in v.description, (fmu.name, v.name)


def test_reproducer_under_ubsan():
    """The committed reproducers (fuzz/regressions/<model>/: a signed state with the count at 2**31, read,
    stepped, every Integer read) through the state harness built with ASan and UBSan (halting on the first
    report): the unchecked conversion was `runtime error: 2.14748e+09 is outside the range of representable
    values of type 'int'` at fmi2GetInteger."""
    why = sanitize.missing_reason()
    if why:
        pytest.skip(why)
    work = Path(sanitize.ROOT / "build" / "sanitize")
    work.mkdir(parents=True, exist_ok=True)
    sanitize.run_regressions(work, sanitize.find_clang())
