"""The vertical ground acceleration input ``ag_v`` of the rocking FMUs, both kinds (the pythonfmu
FMUs and the self-contained ones) and both models:

- declared like ``ag``: a continuous Real input, start 0, [-1000, 1000] m/s2, unit m/s2, the sign convention
  (positive upward, effective gravity g + ag_v) in its description;
- ag_v = 0 set explicitly gives the outputs of an FMU that never heard of it, bit for bit (the golden FMU runs
  of tests/test_golden.py pass unchanged too);
- a nonzero ag_v, held or as a ramp through fmi2SetRealInputDerivatives, gives the Python API's motion
  (`Simulator.advance(t_end, ag, ag_v=...)` with the same first-order hold) to round-off; the standalone FMU
  equals the pythonfmu FMU bit for bit; hypothesis: random ag / ag_v sequences, finite outputs;
- the checks, statuses and messages of ag: non-finite or out of range refused naming ag_v (fmi2Error, both
  kinds word for word), a ramp leaving the range refused (fmi2Discard) with ag_v and its rate kept, bad
  derivatives refused;
- the FMU state carries ag_v and its rate; a state of the FMU before ag_v existed is refused by name."""
from __future__ import annotations

import hashlib
import math
import os
import shutil
import struct
import sys
import zlib
from pathlib import Path

import numpy as np
import pytest

fmpy = pytest.importorskip("fmpy")
pytest.importorskip("pythonfmu")
from fmpy import extract, read_model_description  # noqa: E402
from fmpy.fmi1 import FMICallException  # noqa: E402
from hypothesis import HealthCheck, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

from fmu_instance import FMI2_DISCARD, FMI2_ERROR, Instance  # noqa: E402
from rocking_model import FlexibleOscillator, RigidBlock, Simulator  # noqa: E402
from rocking_model.ground_motion import LinearMotion  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
RIGID, FLEX = "RigidRockingBlock", "FlexibleRockingOscillator"
MODELS = {RIGID: RigidBlock, FLEX: FlexibleOscillator}
CC = os.environ.get("CC") or shutil.which("cc") or shutil.which("gcc")
HAS_STANDALONE = CC is not None and sys.platform.startswith("linux")
KINDS = ["pythonfmu", pytest.param("standalone", marks=pytest.mark.skipif(not HAS_STANDALONE,
                                                                          reason="needs a C compiler on Linux"))]
#: [s] communication step
DT = 0.01
#: [output unit, relative beyond 1] the FMU against the Python API where the two take different entry points
#: into the same compiled engine (the lean `Engine.advance` against `advance_motion`), or the compiled engine
#: against the Python reference engine: round-off carried through a few impacts on these 1.5 s scenes, far
#: from any decision boundary (the engines' own pinning: ~1e-13; tests/test_fmu_engine.py: 1e-9)
ROUNDOFF = 1e-9


# ---------------------------------------------------------------------------------------------- fixtures
@pytest.fixture(scope="module")
def fmus(extracted_fmus, build_module, tmp_path_factory):
    """{(kind, name): (path, model description, unzipped folder)}: the session's pythonfmu FMUs and the
    standalone ones (built here once, if a C compiler is there)."""
    out = {("pythonfmu", n): extracted_fmus[n] for n in MODELS}
    if HAS_STANDALONE:
        dest = tmp_path_factory.mktemp("standalone_vertical")
        for path in build_module.build_standalone(dest):
            out[("standalone", path.stem)] = (path, read_model_description(str(path)), extract(str(path)))
    return out


def output_names(md):
    return [v.name for v in md.modelVariables if v.causality == "output"]


def row(inst, names):
    return [float(x) for x in inst.get(*names)]


# ---------------------------------------------------------------------------------------------- scenes
def pulse(k, amplitude):
    """A one-sine pulse of period 1 s at the communication point k DT, then zero."""
    return amplitude * math.sin(2 * math.pi * k * DT) if k * DT < 1.0 else 0.0


def steps_of(scene, name, n=150):
    """The inputs of each step: (ag, rate of ag or None, ag_v, rate of ag_v or None)."""
    amp = 3.0 if name == RIGID else 0.25 * 9.81
    out = []
    for k in range(n):
        ag = pulse(k, amp)
        if scene == "held":               # ag_v held at -2.5 m/s2: gravity 7.31 m/s2, rocking with impacts
            out.append((ag, None, -2.5, None))
        elif scene == "ramp":             # ag and ag_v as first-order holds of their curves (the slope over the step)
            agv0, agv1 = 4.0 * math.sin(3 * math.pi * k * DT), 4.0 * math.sin(3 * math.pi * (k + 1) * DT)
            out.append((ag, (pulse(k + 1, amp) - ag) / DT, agv0, (agv1 - agv0) / DT))
        elif scene == "lift-off":         # 0.15 s of ag_v = -12 m/s2: g + ag_v < 0, the body leaves the ground
            out.append((ag, None, -12.0 if 20 <= k < 35 else 0.0, None))
        else:
            raise ValueError(scene)
    return out


def run_fmu(fmu, steps, explicit_zero=True):
    """Drive an FMU through ``steps`` (as a master does: the values, then the rates, then fmi2DoStep); the
    outputs after initialization and after each step. ``explicit_zero``: ag_v is set even when 0."""
    inst = Instance(fmu)
    inst.init()
    md = fmu[1]
    names = output_names(md)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    rows = [row(inst, names)]
    t = 0.0
    for ag, rate, ag_v, rate_v in steps:
        if explicit_zero or ag_v != 0.0 or rate_v is not None:
            inst.fmu.setReal([vr["ag"], vr["ag_v"]], [ag, ag_v])
        else:
            inst.fmu.setReal([vr["ag"]], [ag])
        for name, r in (("ag", rate), ("ag_v", rate_v)):
            if r is not None:
                inst.fmu.setRealInputDerivatives([vr[name]], [1], [r])
        assert inst.step(DT, t) == 0, inst.errors()
        t = inst.t
        rows.append(row(inst, names))
    inst.free()
    return names, np.array(rows)


def run_api(name, steps, names):
    """The Python API driven as the FMU: the same step ends, each input a number held over the step or the
    LinearMotion of its value and rate from the step's start."""
    sim = Simulator(MODELS[name](), "event_driven", impact_log_size=0, on_report="raise")

    def values():
        out = sim.outputs()
        return [float(out[n]) for n in names]

    rows = [values()]
    t = 0.0
    for ag, rate, ag_v, rate_v in steps:
        t_end = t + DT
        a = ag if rate is None else LinearMotion(ag, rate, t, t, t_end)
        v = ag_v if rate_v is None else LinearMotion(ag_v, rate_v, t, t, t_end)
        if not sim.outputs()["overturned"]:     # the FMU stops integrating once overturned
            sim.advance(t_end, a, ag_v=v)
        t = t_end
        rows.append(values())
    return np.array(rows)


#: [1, relative] friction_demand, max |lambda_T| / lambda_N so far, divides by normal forces that pass near zero
#: around lift-off: the compiled engine against the Python one measured 9e-9 on the flexible ramp scene (1.6e-11
#: without ag_v), the other outputs within ROUNDOFF
FRICTION_DEMAND_RTOL = 1e-7


def assert_close(a, b, what, names):
    scale = np.maximum(1.0, np.abs(b))
    err = np.abs(a - b) / scale
    tol = np.array([FRICTION_DEMAND_RTOL if n == "friction_demand" else ROUNDOFF for n in names])
    worst = int(np.argmax(np.max(err / tol, axis=0)))
    assert np.all(err <= tol), f"{what}: {names[worst]} off by {np.max(err[:, worst]):.3g}"


# ---------------------------------------------------------------------------------------------- declaration
@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("name", [RIGID, FLEX])
def test_ag_v_is_declared_like_ag(fmus, kind, name):
    md = fmus[(kind, name)][1]
    v = {x.name: x for x in md.modelVariables}
    ag, ag_v = v["ag"], v["ag_v"]
    for x in (ag, ag_v):
        assert (x.causality, x.variability, x.type, x.unit) == ("input", "continuous", "Real", "m/s2")
        assert (float(x.start), float(x.min), float(x.max)) == (0.0, -1000.0, 1000.0)
    assert "positive upward" in ag_v.description and "g + ag_v" in ag_v.description
    assert md.coSimulation.canInterpolateInputs
    # the outputs depend on no input directly (co-simulation): ag_v adds no feed-through
    assert all(not u.dependencies for u in md.outputs)


# ---------------------------------------------------------------------------------------------- ag_v = 0
@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("name", [RIGID, FLEX])
def test_ag_v_zero_set_explicitly_is_bit_identical_to_never_set(fmus, kind, name):
    """ag_v = 0 given at every step (and ag as a ramp) takes the horizontal-only calls: the outputs of the FMU
    whose master never sets ag_v, bit for bit (tests/test_golden.py: and today's recorded outputs)."""
    steps = [(ag, rate, 0.0, None) for ag, rate, _, _ in steps_of("ramp", name)]
    names, a = run_fmu(fmus[(kind, name)], steps, explicit_zero=True)
    _, b = run_fmu(fmus[(kind, name)], steps, explicit_zero=False)
    assert np.array_equal(a, b)
    assert np.max(np.abs(a[:, names.index("phi")])) > 1e-3        # it rocks


# ---------------------------------------------------------------------------------------------- ag_v != 0
@pytest.mark.parametrize("scene", ["held", "ramp", "lift-off"])
@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("name", [RIGID, FLEX])
def test_fmu_on_the_compiled_engine_equals_the_api(fmus, kind, name, scene):
    """Both kinds equal the Python API (`Simulator.advance(t_end, ag, ag_v=...)` as the FMU calls it) to
    round-off, and the vertical component matters: the same steps without it give another motion."""
    steps = steps_of(scene, name)
    names, fmu = run_fmu(fmus[(kind, name)], steps)
    assert np.all(np.isfinite(fmu))
    api = run_api(name, steps, names)
    assert_close(fmu, api, f"{kind} vs the API", names)
    flat = run_api(name, [(a, r, 0.0, None) for a, r, _, _ in steps], names)
    assert np.max(np.abs(flat - api)) > 1e-4
    if scene == "lift-off" and name == RIGID:
        assert np.max(fmu[:, names.index("y")]) > 1e-3          # g + ag_v < 0: the block left the ground


@pytest.mark.skipif(not HAS_STANDALONE, reason="needs a C compiler on Linux")
@pytest.mark.parametrize("scene", ["held", "ramp"])
@pytest.mark.parametrize("name", [RIGID, FLEX])
def test_standalone_equals_the_pythonfmu_fmu_on_the_compiled_engine(fmus, name, scene):
    """The two kinds make the same calls into the same engine: the same outputs bit for bit."""
    steps = steps_of(scene, name)
    _, a = run_fmu(fmus[("standalone", name)], steps)
    _, b = run_fmu(fmus[("pythonfmu", name)], steps)
    assert np.array_equal(a, b)


# ---------------------------------------------------------------------------------------------- hypothesis
_step = st.tuples(st.floats(-6.0, 6.0), st.one_of(st.none(), st.floats(-300.0, 300.0)),
                  st.floats(-15.0, 15.0), st.one_of(st.none(), st.floats(-300.0, 300.0)))


@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture,
                                                                  HealthCheck.too_slow])
@given(steps=st.lists(_step, min_size=5, max_size=30), flexible=st.booleans())
def test_hypothesis_random_ag_and_ag_v_finite_and_equal_to_the_api(fmus, steps, flexible):
    """Random ag / ag_v sequences (some with g + ag_v < 0, some with rates): every step done with finite
    outputs in both kinds, and the standalone FMU equals the pythonfmu FMU bit for bit (the same engine
    calls)."""
    name = FLEX if flexible else RIGID
    _, compiled = run_fmu(fmus[("pythonfmu", name)], steps)
    assert np.all(np.isfinite(compiled))
    if HAS_STANDALONE:
        _, standalone = run_fmu(fmus[("standalone", name)], steps)
        assert np.array_equal(standalone, compiled)


# ---------------------------------------------------------------------------------------------- checks
def _messages(fmu, action):
    inst = Instance(fmu)
    vr = {v.name: v.valueReference for v in fmu[1].modelVariables}
    statuses = []
    try:
        action(inst, vr, statuses)
    except FMICallException as exc:
        statuses.append(exc.status)
    return statuses, [m for s, m in inst.messages if s >= 2]


def _init(inst):
    inst.init()


ACTIONS = {
    "nan": lambda i, vr, s: (_init(i), i.fmu.setReal([vr["ag_v"]], [math.nan])),
    "out-of-range": lambda i, vr, s: (_init(i), i.fmu.setReal([vr["ag_v"]], [1500.0])),
    "both-bad": lambda i, vr, s: (_init(i), i.fmu.setReal([vr["ag"], vr["ag_v"]], [2000.0, -math.inf])),
    "order-2": lambda i, vr, s: (_init(i), i.fmu.setRealInputDerivatives([vr["ag_v"]], [2], [1.0])),
    "rate-nan": lambda i, vr, s: (_init(i), i.fmu.setRealInputDerivatives([vr["ag_v"]], [1], [math.nan])),
    "rate-too-large": lambda i, vr, s: (_init(i), i.fmu.setRealInputDerivatives([vr["ag_v"]], [1], [1e9])),
    "ramp-leaves-range": lambda i, vr, s: (_init(i), i.fmu.setReal([vr["ag_v"]], [990.0]),
                                           i.fmu.setRealInputDerivatives([vr["ag_v"]], [1], [2000.0]),
                                           s.append(i.step())),
    "set-when-terminated": lambda i, vr, s: (_init(i), i.fmu.terminate(), i.fmu.setReal([vr["ag_v"]], [1.0])),
}
FRAGMENTS = {
    "nan": "fmi2SetReal: input ag_v = nan is not finite; allowed range [-1000, 1000] (nothing was set)",
    "out-of-range": "input ag_v = 1500 is out of range; allowed range [-1000, 1000]",
    "both-bad": "input ag = 2000 is out of range",
    "order-2": "ag_v: order = 2 is not supported; allowed: 1",
    "rate-nan": "rate of ag_v = nan is not finite",
    "rate-too-large": "rate of ag_v = 1e+09 is out of range",
    "ramp-leaves-range": "input ag_v = 990.0 at t = 0.0 is invalid: ag_v at the end of the step (rate 2000 per s)",
    "set-when-terminated": "illegal call sequence: the instance is terminated",
}


@pytest.mark.parametrize("case", sorted(ACTIONS))
@pytest.mark.parametrize("name", [RIGID, FLEX])
def test_bad_ag_v_is_refused_like_ag_with_the_same_messages_in_both_kinds(fmus, name, case):
    statuses, messages = _messages(fmus[("pythonfmu", name)], ACTIONS[case])
    expected = FMI2_DISCARD if case == "ramp-leaves-range" else FMI2_ERROR
    assert statuses and statuses[-1] == expected, (statuses, messages)
    assert any(FRAGMENTS[case] in m for m in messages), messages
    if case == "both-bad":
        assert any("ag_v = -inf is not finite" in m for m in messages), messages
    if HAS_STANDALONE:
        assert _messages(fmus[("standalone", name)], ACTIONS[case]) == (statuses, messages)


def _serialized(inst):
    state = inst.fmu.getFMUstate()
    data = bytes(inst.fmu.serializeFMUstate(state))
    inst.fmu.freeFMUstate(state)
    return data


@pytest.mark.parametrize("kind", KINDS)
def test_refused_step_keeps_ag_v_and_its_rate(fmus, kind):
    """A step refused because ag's ramp leaves its range (fmi2Discard) keeps ag_v and its rate: the state is
    bit-identical to before, and a shorter step then equals a control instance's."""
    fmu = fmus[(kind, RIGID)]
    vr = {v.name: v.valueReference for v in fmu[1].modelVariables}
    subject, control = Instance(fmu, "subject"), Instance(fmu, "control")
    for inst in (subject, control):
        inst.init()
        inst.fmu.setReal([vr["ag"], vr["ag_v"]], [990.0, -3.0])
        inst.fmu.setRealInputDerivatives([vr["ag"], vr["ag_v"]], [1, 1], [2000.0, 40.0])
    before = _serialized(subject)[46:]        # the slave's bytes (the header records the step's fmi2Discard)
    assert subject.step(DT) == FMI2_DISCARD                    # 990 + 2000 * 0.01 > 1000
    assert "ag at the end of the step" in subject.errors()[-1]
    assert _serialized(subject)[46:] == before
    assert subject.get("ag_v") == [-3.0]
    for inst in (subject, control):
        assert inst.step(0.001) == 0                            # inside the range: ag_v = -3 + 40 t
    assert _serialized(subject) == _serialized(control)
    assert subject.get("phi", "y", "energy") == control.get("phi", "y", "energy")
    subject.free()
    control.free()


@pytest.mark.parametrize("kind", KINDS)
def test_state_carries_ag_v_and_its_rate(fmus, kind):
    """Saved mid-ramp, serialized and restored into a fresh instance: ag_v and its rate (and reference time)
    come back, and the continuation is bit-identical to the instance that went on."""
    from fault_harness import decode_payload, slave_bytes

    fmu = fmus[(kind, FLEX)]
    vr = {v.name: v.valueReference for v in fmu[1].modelVariables}
    a = Instance(fmu, "a")
    a.init()
    for k in range(30):
        a.fmu.setReal([vr["ag"], vr["ag_v"]], [pulse(k, 2.5), -2.0])
        assert a.step() == 0
    a.fmu.setRealInputDerivatives([vr["ag_v"]], [1], [50.0])
    for _ in range(3):
        assert a.step() == 0                                    # ag_v = -2 + 50 (t - 0.3)
    data = _serialized(a)
    doc = decode_payload(slave_bytes(data))
    if kind == "pythonfmu":
        rate, t_ref = doc["slave"]["rates"]["ag_v"]
        assert doc["slave"]["values"]["ag_v"] == -2.0
    else:
        names = [v.name for v in fmu[1].modelVariables]
        rate, t_ref = doc["rates"][1]["rate"], doc["rates"][1]["rate_t"]
        assert doc["rates"][1]["has_rate"] == 1 and doc["rates"][0]["has_rate"] == 0
        assert doc["values"][names.index("ag_v")] == -2.0
    assert rate == 50.0 and t_ref == pytest.approx(0.3, abs=1e-12)
    b = Instance(fmu, "b")
    b.init()
    b.fmu.setFMUstate(b.fmu.deSerializeFMUstate(data))
    b.t = a.t
    for inst in (a, b):
        for _ in range(5):
            assert inst.step() == 0
    assert a.get("u", "phi", "y", "energy") == b.get("u", "phi", "y", "energy")
    assert _serialized(a) == _serialized(b)
    a.free()
    b.free()


def _with_crc(data: bytes) -> bytes:
    """A serialized state with the CRC-32 of the binary's header recomputed (rocking_model/fmi/binary/fmi2_common.h)."""
    head, payload = data[:42], data[46:]
    return head + struct.pack("<I", zlib.crc32(payload, zlib.crc32(head))) + payload


@pytest.mark.parametrize("kind", KINDS)
def test_state_of_the_fmu_before_ag_v_is_refused(fmus, kind):
    """A state saved by the FMU before ag_v existed is refused with a message saying so (fmi2Error, the
    instance keeps its state): its variable table (pythonfmu) or its format and GUID (standalone) are another
    FMU's; reading it on would silently assume ag_v = 0 for a master that never knew the input."""
    fmu = fmus[(kind, RIGID)]
    inst = Instance(fmu)
    inst.init()
    inst.set(ag=3.0)
    assert inst.step() == 0
    data = _serialized(inst)
    if kind == "pythonfmu":
        from rocking_model.fmi_state import MAGIC, decode_state, encode_state

        i = data.index(MAGIC)
        doc = decode_state(data[i:])
        del doc["slave"]["values"]["ag_v"]
        table = [(v.name, v.causality, v.type) for v in fmu[1].modelVariables if v.name != "ag_v"]
        doc["signature"] = hashlib.sha256(repr(table).encode()).hexdigest()
        old = _with_crc(data[:i] + encode_state(doc))
        fragment = "another version of its variables"
    else:
        old = bytearray(data)
        i = data.index(b"rocking engine FMU state v2\n")
        old[i:i + 28] = b"rocking engine FMU state v1\n"
        payload = bytes(old[46:-4])
        old = _with_crc(bytes(old[:-4]) + struct.pack("<I", zlib.crc32(payload)))
        fragment = "format version 2"
    before = inst.get("phi", "phi_dot")
    state = inst.fmu.deSerializeFMUstate(old)
    with pytest.raises(FMICallException):
        inst.fmu.setFMUstate(state)
    assert fragment in inst.errors()[-1] and "state rejected" in inst.errors()[-1]
    assert inst.get("phi", "phi_dot") == before
    inst.fmu.freeFMUstate(state)
    inst.fmu.freeInstance()


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("where", ["instantiated", "initialization"])
def test_rate_of_ag_v_set_before_initialization_refers_to_the_start_time(fmus, kind, where):
    """fmi2SetRealInputDerivatives of ag_v before initialization, startTime = 1 s: the line starts at the
    start time, as for ag: the run equals a control that set value and rate at t = 1 s."""
    fmu = fmus[(kind, RIGID)]
    vr = {v.name: v.valueReference for v in fmu[1].modelVariables}
    s, c = Instance(fmu, "subject"), Instance(fmu, "control")

    def inputs(inst):
        inst.fmu.setReal([vr["ag"], vr["ag_v"]], [2.5, -1.0])
        inst.fmu.setRealInputDerivatives([vr["ag_v"]], [1], [-40.0])

    if where == "instantiated":
        inputs(s)
    s.fmu.setupExperiment(startTime=1.0)
    s.fmu.enterInitializationMode()
    if where == "initialization":
        inputs(s)
    s.fmu.exitInitializationMode()
    s.t = 1.0
    c.init(1.0)
    inputs(c)
    for _ in range(10):                                         # g + ag_v from 8.81 to 4.81 m/s2: uplift
        assert s.step() == 0 and c.step() == 0
        assert s.get("phi", "phi_dot", "y") == c.get("phi", "phi_dot", "y")
    assert s.get("phi")[0] != 0.0
    assert _serialized(s) == _serialized(c)
    s.free()
    c.free()


# ---------------------------------------------------------------------------------------------- records
def test_record_with_a_vertical_component_through_input_derivatives(fmus):
    """`run_fmu_record(..., ag_v_record=...)` drives ag and ag_v as first-order holds at the record's own
    sampling: the FMU reproduces `simulate((t, ag, ag_v), hold="exact")` to the integrator's tolerance (as
    tests/test_input_interpolation.py for ag alone), and the vertical component changes the motion."""
    from rocking_model import simulate
    from rocking_model.fmi import run_fmu_record

    rng = np.random.default_rng(5)
    t = np.arange(0.0, 3.0 + 1e-9, DT)
    bell = np.exp(-((t - 1.5) / 0.7) ** 2)
    ag, ag_v = (np.convolve(rng.standard_normal(t.size), np.ones(15) / 15, "same") * bell for _ in range(2))
    ag, ag_v = ag * (4.0 / np.abs(ag).max()), ag_v * (3.0 / np.abs(ag_v).max())
    block = RigidBlock(b=0.2, h=1.0)
    ref = simulate(block, (t, ag, ag_v), t_end=3.0, scheme="event_driven", tolerance=1e-10, output_interval=DT,
                   hold="exact")
    flat = simulate(block, (t, ag), t_end=3.0, scheme="event_driven", tolerance=1e-10, output_interval=DT,
                    hold="exact")
    assert ref.impacts[-1] >= 1 and np.abs(ref.phi - flat.phi).max() > 1e-2 * block.alpha
    out = run_fmu_record(fmus[("pythonfmu", RIGID)][0], t, ag, ag_v_record=ag_v, step=DT, stop_time=3.0,
                         hold="linear", start_values={"tolerance": 1e-10, "scheme": 1}, output=("phi", "y"))
    assert np.abs(out["phi"] - np.interp(out["time"], ref.t, ref.phi)).max() <= 1e-9 * block.alpha


def test_source_drives_both_components_through_the_fmpy_master(fmus, built_fmus, tmp_path):
    """GroundMotionSource (a three-column record: time, ag, ag_v) -> RigidRockingBlock with ag -> ag and
    ag_v -> ag_v in rocking_model.cosim's fmpy master: the block equals the block FMU driven step by step by
    the table ag(t_n), ag_v(t_n), and the Python API with both held, to round-off (the master's
    communication points n h against the sums of h)."""
    from rocking_model.cosim import Component, Connection, System, run_fmpy

    t = np.round(np.arange(0.0, 1.5 + 1e-9, DT), 12)
    # |ag| <= 1.8 < g tan(alpha) = 1.96 m/s2: the block rocks only because g + ag_v drops to 6.8 m/s2
    ag = np.where(t < 1.0, 1.8 * np.sin(2 * np.pi * t), 0.0)
    ag_v = np.where(t < 1.0, -3.0 * np.sin(np.pi * t), 0.0)
    record = tmp_path / "three.csv"
    record.write_text("time [s],ag [m/s2],ag_v [m/s2]\n"
                      + "".join(f"{a!r},{b!r},{c!r}\n" for a, b, c in zip(t.tolist(), ag.tolist(), ag_v.tolist())))
    system = System([Component("ground", built_fmus["GroundMotionSource"],
                               start_values={"motion": 1, "record": str(record)}),
                     Component("block", built_fmus[RIGID], start_values={"scheme": 1})],
                    [Connection(("ground", "ag"), ("block", "ag")), Connection(("ground", "ag_v"), ("block", "ag_v"))],
                    step_size=DT)
    res = run_fmpy(system, 1.5, ["ground.ag", "ground.ag_v", "block.phi", "block.y", "block.impacts"])
    np.testing.assert_allclose(res["ground.ag_v"], np.interp(res["time"], t, ag_v), rtol=0, atol=1e-12)
    steps = [(float(a), None, float(v), None) for a, v in zip(res["ground.ag"][:-1], res["ground.ag_v"][:-1])]
    names, alone = run_fmu(fmus[("pythonfmu", RIGID)], steps)
    for out in ("phi", "y", "impacts"):
        np.testing.assert_allclose(res[f"block.{out}"], alone[:, names.index(out)], rtol=0, atol=ROUNDOFF,
                                   err_msg=out)
    assert_close(alone, run_api(RIGID, steps, names), "the block FMU vs the API", names)
    flat = run_api(RIGID, [(a, None, 0.0, None) for a, _, _, _ in steps], names)
    assert 0.01 < np.abs(res["block.phi"]).max() < 0.5 * RigidBlock().alpha and res["block.impacts"][-1] >= 1
    assert np.all(flat[:, names.index("phi")] == 0.0)                  # without ag_v: no uplift


# ---------------------------------------------------------------------------------------------- lean path
def _slave(name):
    import importlib.util

    spec = importlib.util.spec_from_file_location(name, ROOT / "fmu_src" / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    slave = getattr(module, name)(instance_name="vertical-lean")
    vr = {v.name: v.value_reference for v in slave.vars.values()}
    slave.setup_experiment(0.0)
    slave.enter_initialization_mode()
    slave.exit_initialization_mode()
    return slave, vr


def test_held_ag_v_takes_the_lean_path(monkeypatch):
    """A nonzero ag_v held over the step is one Engine.advance with ag_v (the lean path, no checked path)."""
    slave, vr = _slave(RIGID)
    assert slave._lean is not None and slave._lean[3] == "ag_v"
    monkeypatch.setattr(slave, "_do_step", lambda *a: pytest.fail("the checked path was taken"))
    slave.set_real([vr["ag"]], [2.5])
    slave.set_real([vr["ag_v"]], [-3.0])
    assert slave.do_step(0.0, 0.2)
    assert slave.get_real([vr["phi"]])[0] != 0.0


def test_overflowing_step_under_ag_v_names_it_as_the_simulator_does(fmus, monkeypatch):
    """A huge state (the column deflected by 1e148 m while rocking) whose motion overflows within a step under
    ag_v = 500 m/s2 (> 10 g): the lean path refuses it (fmi2Discard, state kept) with Simulator._diverged's
    message word for word, which names the vertical ground acceleration as a likely cause; the standalone FMU
    (the state crafted into its serialized form) says the same."""
    slave, vr = _slave(FLEX)
    state = slave._sim.get_state()
    state.update(mode=1, y=[1e148, 0.01, 0.0, 0.1])                   # mode LEFT, y = [u, phi, u', phi']
    slave._sim.set_state(state)
    slave.set_real([vr["ag_v"]], [500.0])
    before = slave._sim.get_state()
    assert not slave.do_step(0.0, 0.01)
    assert slave._sim.get_state() == before
    sim = Simulator(FlexibleOscillator(), "event_driven", engine="c", impact_log_size=0, on_report="raise")
    sim.set_state(state)
    with pytest.raises(ValueError, match=r"the vertical ground acceleration \(\|ag_v\| up to 500 m/s2") as info:
        sim.advance(0.01, 0.0, ag_v=500.0)
    expected = f"step [0.0, 0.01] refused, the FMU state is unchanged: {info.value}"
    assert [m.msg for m in slave.log_queue if m.status == 3] == [expected]
    if not HAS_STANDALONE:
        return
    fmu = fmus[("standalone", FLEX)]
    inst = Instance(fmu)
    inst.init()
    inst.set(ag_v=500.0)
    blob = bytearray(_serialized(inst))
    n_vars = len(fmu[1].modelVariables)
    # the engine's plain state: header, magic, GUID, n_vars, values, 4 flags, t, t0, n_inputs, 2 x (has_rate,
    # rate, rate_t), the error's length, has_engine
    off = 46 + 28 + 36 + 4 + 8 * n_vars + 16 + 16 + 4 + 2 * 20 + 4 + 4
    struct.pack_into("<ii4d", blob, off + 8, 1, 4, 1e148, 0.01, 0.0, 0.1)
    blob[-4:] = struct.pack("<I", zlib.crc32(bytes(blob[46:-4])))
    inst.fmu.setFMUstate(inst.fmu.deSerializeFMUstate(_with_crc(bytes(blob))))
    assert inst.step() == FMI2_DISCARD
    assert inst.errors()[-1] == expected
