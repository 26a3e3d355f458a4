"""Plain-data state of the simulators ("a state format that cannot execute code", library side):
`Simulator.get_state` / `set_state`, and the same on `MotionSource` and `StoreySimulator`.

- Round trip: a Simulator rebuilt from the same parameters and loaded with ``get_state()`` (through JSON)
  gives bit-identical outputs, step for step, to the original going on, on impact-rich scenes of both
  schemes and both models; split points include steps right after an impact and steps in flight (the
  scenes have e_N > 0, so every impact ends in flight: no decision boundary decides whether they occur).
  The original keeps its live Runge-Kutta stepper, the copy restarts from (t, y, h): this is the check that
  leaving ``EventDriven._live`` out of the state loses nothing.
- Rejections: every field with junk (missing, extra, wrong type, wrong length, not finite, out of range,
  inconsistent) raises ValueError naming it, and the simulator is unchanged.
"""
from __future__ import annotations

import json
import math
import warnings

import numpy as np
import pytest

from rocking_model import FlexibleOscillator, Mode, RigidBlock, Simulator, WorkLimitError
from rocking_model.cosim import MotionSource
from rocking_model.ground_motion import SinePulse
from rocking_model.models.linear_building import LinearStorey, StoreySimulator

DT = 0.01            # [s] communication step
N_FOLLOW = 8         # steps each copy is compared with the original
N_EACH = 3           # copies started right after an impact, and in flight (besides one every 40 steps)
PULSE = SinePulse(0.5, 2 * math.pi * 0.5)     # [m/s2] a slow, weak input (below uplift) that varies in time

# impact-rich scenes far from any decision boundary (factory, initial values, steps): a squat block released
# at 0.65 alpha with e_N = 0.8 (it bounces into flight at every impact, from t = 0.72 s on: 8 impacts and 0.7 s
# of flight in 1.5 s), and the flexible oscillator released in full contact with a deflected column (it
# uplifts at once and bounces: 13 impacts, 0.4 s of flight in 0.8 s)
SCENES = {
    "rigid": (lambda: RigidBlock(b=0.5, h=1.0, e_N=0.8), dict(phi_0=0.3), 150),
    "flexible": (lambda: FlexibleOscillator(e_N=0.6), dict(u_0=0.03), 60),
}
OPTS = {"moreau_jean": dict(dt_max=5e-3), "event_driven": {}}


def _assert_plain(state):
    """Only bool, int, float, short str and lists of int / float; json.dumps works."""
    for key, value in state.items():
        assert type(key) is str and len(key) <= 16
        if isinstance(value, list):
            assert all(type(x) in (int, float) for x in value), key
        else:
            assert type(value) in (bool, int, float, str), key
            if type(value) is str:
                assert len(value) <= 64
    json.loads(json.dumps(state))


def _roundtrip_run(scene, scheme, ag_of):
    """Advance the original; at split points start copies from its JSON'd state and compare every output of
    the next N_FOLLOW steps. Returns how many copies started right after an impact and in flight."""
    factory, initial, n_steps = SCENES[scene]
    sim = Simulator(factory(), scheme, **OPTS[scheme], **initial)
    copies, seen = [], {"after_impact": 0, "flight": 0, "other": 0}
    last_impacts = 0
    for k in range(n_steps):
        state = sim.get_state()
        tag = "after_impact" if state["impacts"] != last_impacts else "flight" if state["mode"] == 3 else "other"
        last_impacts = state["impacts"]
        if (tag != "other" and seen[tag] < N_EACH) or k % 40 == 0:
            _assert_plain(state)
            copy = Simulator(factory(), scheme, **OPTS[scheme])     # no initial values: set_state sets all
            copy.set_state(json.loads(json.dumps(state)))
            assert json.dumps(copy.get_state()) == json.dumps(state)
            copies.append([copy, N_FOLLOW])
            seen[tag] += 1
        t_end = (k + 1) * DT
        ag = ag_of(k * DT)
        sim.advance(t_end, ag)
        ref = sim.outputs()
        for c in copies:
            c[0].advance(t_end, ag)
            assert c[0].outputs() == ref, f"copy diverged at step {k}"
            c[1] -= 1
        copies = [c for c in copies if c[1] > 0]
    return seen


@pytest.mark.parametrize("scheme", ["moreau_jean", "event_driven"])
@pytest.mark.parametrize("scene", list(SCENES))
@pytest.mark.parametrize("hold", ["zoh", "motion"])
def test_roundtrip_is_bit_identical(scene, scheme, hold):
    # zoh: a constant per step (the FMU); motion: the pulse object itself each step (ag varies inside the
    # steps and the original's Runge-Kutta stepper carries on across them)
    ag_of = (lambda t: float(PULSE(t))) if hold == "zoh" else (lambda t: PULSE)
    seen = _roundtrip_run(scene, scheme, ag_of)
    assert seen["after_impact"] >= N_EACH and seen["flight"] >= N_EACH, seen


def test_roundtrip_of_a_fresh_and_of_an_overturned_simulator():
    for scheme in (0, 1):
        for model in (RigidBlock(), FlexibleOscillator()):
            sim = Simulator(model, scheme)
            twin = Simulator(model, scheme)
            twin.set_state(sim.get_state())
            assert twin.get_state() == sim.get_state()
        sim = Simulator(RigidBlock(b=0.1, h=1.0), scheme, phi_0=0.12)   # tips over (phi_0 > alpha = 0.0997)
        sim.advance(3.0, 0.0)
        assert sim.outputs()["overturned"]
        twin = Simulator(RigidBlock(b=0.1, h=1.0), scheme)
        twin.set_state(json.loads(json.dumps(sim.get_state())))
        assert twin.outputs() == sim.outputs()


def test_state_size_is_bounded_by_the_impact_log_size():
    for scheme in (0, 1):
        sim = Simulator(RigidBlock(b=0.5, h=1.0, e_N=0.8), scheme, impact_log_size=5, phi_0=0.3)
        sim.advance(1.5, PULSE)
        state = sim.get_state()
        assert state["impacts"] > 5
        assert len(state["impact_times"]) == 5
        if scheme == 1:
            assert len(state["impact_log"]) == 5 * (1 + 2 * 3)
        twin = Simulator(RigidBlock(b=0.5, h=1.0, e_N=0.8), scheme, impact_log_size=5)
        twin.set_state(state)
        assert twin.impact_times == sim.impact_times


def test_state_holds_no_live_stepper_and_h_is_nan_before_the_first_step():
    sim = Simulator(FlexibleOscillator(), "event_driven", phi_0=0.01)
    assert math.isnan(sim.get_state()["h"])
    sim.advance(0.05, 0.0)
    assert sim.get_state()["h"] > 0.0
    assert not any("live" in key for key in sim.get_state())


# ---------------------------------------------------------------------------------------------- rejections
_ROCKING = {}


def _rocking_sim(scheme):
    """A simulator right after its first impacts (the state computed once per scheme)."""
    opts = {"dt_max": 5e-3} if scheme == 0 else {}
    if scheme not in _ROCKING:
        sim = Simulator(RigidBlock(b=0.2, h=1.0, e_N=0.5), scheme, phi_0=0.1, **opts)
        sim.advance(0.6, 0.0)
        assert sim.get_state()["impacts"] >= 1
        _ROCKING[scheme] = sim.get_state()
    sim = Simulator(RigidBlock(b=0.2, h=1.0, e_N=0.5), scheme, **opts)
    sim.set_state(_ROCKING[scheme])
    return sim


COMMON_JUNK = [
    ("version", 1), ("version", 3), ("version", "2"), ("version", True),
    ("scheme", "other"), ("scheme", 1), ("scheme", "x" * 65),
    ("model", "FlexibleOscillator"), ("model", None),
    ("n_dof", 4), ("n_dof", 3.0),
    ("t", math.nan), ("t", math.inf), ("t", "0"), ("t", True), ("t", None),
    ("mode", 10), ("mode", -1), ("mode", 1.0), ("mode", True),
    ("impacts", -1), ("impacts", 2 ** 63), ("impacts", 1.5), ("impacts", False),
    ("overturned", 0), ("overturned", "False"), ("overturned", None),
    ("n_steps", -5), ("n_steps", 3.0),
    ("impact_times", [1e9]), ("impact_times", "0.5"), ("impact_times", [math.nan]), ("impact_times", ["0.5"]),
]
ED_JUNK = COMMON_JUNK + [
    ("y", [0.0]), ("y", [0.1, math.inf]), ("y", [0.1, math.nan]), ("y", "0.1, 0.0"), ("y", [0.1, "x"]),
    ("y", [1.6, 0.0]),                        # |phi| > pi/2 and not overturned
    ("h", -1.0), ("h", 0.0), ("h", math.inf), ("h", "nan"),
    ("impact_log", [0.1, 0.0]), ("impact_log", [1e9] + [0.0] * 6), ("impact_log", [math.nan] * 7),
    ("impact_log", 7),
]
MJ_JUNK = COMMON_JUNK + [
    ("q", [0.0, 1.0]), ("q", [0.0, 1.0, math.nan]), ("q", [0.0, -5.0, 0.0]), ("q", [0.0, 1.0, 2.0]),
    ("v", [0.0, 0.0, math.inf]), ("v", None),
    ("closed", [2]), ("closed", [1, 0]), ("closed", [0, 0]), ("closed", [0.0]), ("closed", [0, 1, 1]),
]


@pytest.mark.parametrize("scheme, field, junk", [(0, f, j) for f, j in MJ_JUNK] + [(1, f, j) for f, j in ED_JUNK],
                         ids=lambda x: repr(x)[:20])
def test_junk_field_is_refused_naming_it(scheme, field, junk):
    sim = _rocking_sim(scheme)
    good = sim.get_state()
    before = json.dumps(good)
    bad = dict(good, **{field: junk})
    with pytest.raises(ValueError, match=repr(field).replace("[", r"\[")):
        sim.set_state(bad)
    assert json.dumps(sim.get_state()) == before


@pytest.mark.parametrize("scheme", [0, 1])
def test_missing_extra_and_non_mapping_states_are_refused(scheme):
    sim = _rocking_sim(scheme)
    good = sim.get_state()
    before = json.dumps(good)
    for key in good:
        bad = {k: v for k, v in good.items() if k != key}
        with pytest.raises(ValueError, match=f"'{key}' is missing"):
            sim.set_state(bad)
    with pytest.raises(ValueError, match="'extra' is not expected"):
        sim.set_state(dict(good, extra=1))
    for junk in (None, [1, 2], "state", b"\x80\x04"):
        with pytest.raises(ValueError, match="state must be a mapping"):
            sim.set_state(junk)
    assert json.dumps(sim.get_state()) == before


def test_inconsistent_fields_are_refused():
    sim = _rocking_sim(1)
    good = sim.get_state()
    # more impact times than impacts; times out of order
    with pytest.raises(ValueError, match="'impact_times'"):
        sim.set_state(dict(good, impacts=0))
    with pytest.raises(ValueError, match="'impact_times'"):
        sim.set_state(dict(good, impact_times=[0.3, 0.2], impacts=2))
    mj = _rocking_sim(0)
    state = mj.get_state()
    with pytest.raises(ValueError, match="'mode'"):
        mj.set_state(dict(state, mode=0, closed=[1]))          # full contact needs both corners closed


def test_a_state_of_another_scheme_or_model_is_refused():
    states = {(s, m): Simulator(model, s).get_state() for s in (0, 1)
              for m, model in (("rigid", RigidBlock()), ("flex", FlexibleOscillator()))}
    for (s, m), state in states.items():
        other_scheme = Simulator(RigidBlock() if m == "rigid" else FlexibleOscillator(), 1 - s)
        with pytest.raises(ValueError, match="'scheme'"):
            other_scheme.set_state(state)
        other_model = Simulator(FlexibleOscillator() if m == "rigid" else RigidBlock(), s)
        with pytest.raises(ValueError, match="'model'"):
            other_model.set_state(state)


def test_a_valid_but_huge_state_is_refused_at_advance_and_kept():
    """Finite values whose motion overflows within a step (a column deflected by 1e148 m while rocking: its
    reduced mass m_tilde u^2 times the elastic force k_tilde u overflows): advance raises ValueError naming
    the cause, the state is kept; outputs are never inf or nan."""
    model = FlexibleOscillator()
    r, r_dot = np.array([1e148, 0.01]), np.array([0.0, 0.1])
    for scheme in (0, 1):
        sim = Simulator(model, scheme)
        state = sim.get_state()
        state["mode"] = 1                      # rocking on the left corner
        if scheme == 1:
            state["y"] = [*r, *r_dot]
        else:
            q, v = model.embed(Mode.LEFT, r, r_dot)
            state.update(q=q.tolist(), v=v.tolist(), closed=[0])
        sim.set_state(state)
        assert all(math.isfinite(x) for x in sim.outputs().values())
        before = json.dumps(sim.get_state())
        with pytest.raises(ValueError, match="not finite.*Likely cause"):
            sim.advance(0.01, 0.0)
        assert json.dumps(sim.get_state()) == before


#: states with absurd but finite velocities that set_state accepts, whose event-driven advance diverged into a pose
#: with a corner kilometres below the ground (found by fuzzing the FMU's state, fuzz/README.md): (model, state
#: fields, t_end, ag)
_DIVERGING = [
    (dict(m_c=30.14453125, EI=1431248.0),
     dict(t=0.31, mode=1, y=[-0.0012249407628530662, 0.02987721141020171, -0.0012431255314855668,
                             -4295153942528.1152], h=4.836298536748469e-193, n_steps=57), 0.32, 4.0),
    (dict(m_c=30.14453125, EI=1431248.0),
     dict(mode=2, y=[0.0, -0.05323353753625318, 4330.578885401834, 5559058514220.813]), 0.015782479493159623,
     -4.718334464929004),
    (dict(m_c=30.14453125, EI=1431248.0),
     dict(mode=2, y=[0.0, -0.09190809793018517, -6971807.0678922245, 871743453305.2798]), 0.009279781827465826,
     -1.1136735536585967),
]


@pytest.mark.parametrize("params, fields, t_end, ag", _DIVERGING)
def test_a_diverging_advance_is_refused_so_every_state_reads_back(params, fields, t_end, ag):
    """The engine never ends a call in a state its set_state refuses: an advance whose pose ends past the bounds a
    state may have (a corner far below the ground, |phi| past pi/2 without the overturning) is refused as a
    diverged motion (ValueError naming the likely cause), with the state before it kept."""
    model = FlexibleOscillator(**params)
    sim = Simulator(model, "event_driven")
    state = dict(sim.get_state(), **fields)
    sim.set_state(state)
    before = json.dumps(sim.get_state())
    with pytest.raises(ValueError, match="diverged.*below the ground.*Likely cause"):
        sim.advance(t_end, ag)
    assert json.dumps(sim.get_state()) == before
    Simulator(model, "event_driven").set_state(sim.get_state())


def test_every_state_an_advance_ends_in_reads_back():
    """Random absurd velocities that set_state accepts, both models and schemes: whatever the advance does (it
    may raise), the state the simulator holds afterwards is taken back by a fresh one."""
    rng = np.random.default_rng(1)
    read_back = 0
    for model in (FlexibleOscillator(m_c=30.14453125, EI=1431248.0), RigidBlock()):
        for scheme in ("moreau_jean", "event_driven"):
            for _ in range(120):
                sim = Simulator(model, scheme, phi_0=float(rng.uniform(-0.1, 0.1)))
                state = sim.get_state()
                key = "v" if scheme == "moreau_jean" else "y"
                values = list(state[key])
                for i in range(0 if key == "v" else len(values) // 2, len(values)):
                    values[i] = float(rng.choice([-1, 1]) * 10 ** rng.uniform(0, 13))
                try:
                    sim.set_state(dict(state, **{key: values}))
                except ValueError:
                    continue
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    try:
                        sim.advance(float(rng.uniform(0.001, 0.05)), float(rng.uniform(-10, 10)))
                    except (ValueError, WorkLimitError):
                        pass
                Simulator(model, scheme).set_state(sim.get_state())
                read_back += 1
    assert read_back > 300


# ---------------------------------------------------------------------------------------------- components
def test_motion_source_state():
    src = MotionSource(SinePulse(3.0, 2 * math.pi), t0=0.0)
    src.advance(0.125)
    state = src.get_state()
    _assert_plain(state)
    twin = MotionSource(SinePulse(3.0, 2 * math.pi))
    twin.set_state(json.loads(json.dumps(state)))
    assert twin.outputs() == src.outputs() and twin.t == src.t
    for t in (0.3, 0.31, 0.9):
        src.advance(t)
        twin.advance(t)
        assert twin.outputs() == src.outputs()
    before = twin.get_state()
    for field, junk in (("t", math.nan), ("t", "0"), ("version", 2), ("model", "Simulator"), ("extra", 1)):
        with pytest.raises(ValueError, match=repr(field)):
            twin.set_state(dict(before, **{field: junk}))
    with pytest.raises(ValueError, match="'t' is missing"):
        twin.set_state({"version": 1, "model": "MotionSource"})
    assert twin.get_state() == before


@pytest.mark.parametrize("T", [0.4, 0.0])
def test_storey_state(T):
    sim = StoreySimulator(LinearStorey(T=T, zeta=0.05))
    rec = SinePulse(3.0, 2 * math.pi * 1.5)
    for k in range(1, 50):
        sim.advance(k * DT, float(rec(k * DT)))
    state = sim.get_state()
    _assert_plain(state)
    twin = StoreySimulator(LinearStorey(T=T, zeta=0.05))
    twin.set_state(json.loads(json.dumps(state)))
    for k in range(50, 120):
        a = float(rec(k * DT))
        sim.advance((k + 1) * DT, a)
        twin.advance((k + 1) * DT, a)
        assert twin.outputs() == sim.outputs()
    before = twin.get_state()
    junk = [("t", math.inf), ("x", [0.0]), ("x", [0.0, math.nan]), ("ag", 2000.0), ("ag", "1"), ("version", 0),
            ("model", "MotionSource"), ("extra", 0)]
    if T == 0.0:
        junk.append(("x", [0.1, 0.0]))                     # a rigid storey does not move relative to the ground
    for field, value in junk:
        with pytest.raises(ValueError, match=repr(field)):
            twin.set_state(dict(before, **{field: value}))
    assert twin.get_state() == before
