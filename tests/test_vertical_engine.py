"""The compiled engine under a vertical ground acceleration ag_v (issue 23, C part) against the Python reference.

Same algorithm, same steps (rocking_model/engine/DESIGN.md, "Numerics"): on scenes with a vertical component
(constant, pulses, a sampled record pair, a fall of the ground faster than g: g + ag_v < 0, flight), for both
models and both schemes, the two engines take the same steps, count the same impacts at the same times, are in
the same contact mode after every advance and agree on phi to 1e-12 rad (the flexible oscillator within the bound
of tests/test_engine_event_driven.py: its impact LCP's ulps carried by the column's vibration). ag_v = 0 is
bit-identical to no vertical component; the state moves between engines during a vertical motion; the
extension's `Engine.advance` reads ag_v and its slope (the first-order hold) and refuses bad values naming
ag_v. Every scene is far from a decision boundary (developers' guide)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from rocking_model import SampledMotion, Simulator, SinePulse, TwoComponentMotion, _engine, simulate
from rocking_model.ground_motion import ConstantMotion, LinearMotion, RectangularPulse
from rocking_model.models import FlexibleOscillator, RigidBlock

G = 9.81
#: [rad] phi of the two engines on the rigid block (same steps: round-off of the contact solves only)
PHI_TOL = 1e-12
#: [s] impact times
T_TOL = 1e-12
#: [1] other outputs, relative to their scale max(1, |value|) (as tests/test_engine_event_driven.py)
OUT_RTOL = 1e-9
#: the flexible oscillator's slack on the tolerances above (tests/test_engine_event_driven.py,
#: test_flexible_free_and_pulse: numpy's and the C's impact-LCP ulps carried by the column's vibration)
FLEX_SLACK = 1e3


def _assert_same(py, c, where="", slack=1.0):
    ip, ic = py.integrator, c.integrator
    assert ic.t == ip.t, where
    assert int(ic.mode) == int(ip.mode), (where, int(ip.mode), int(ic.mode))
    assert bool(ic.overturned) == bool(ip.overturned), where
    assert ic.impacts == ip.impacts, (where, ip.impacts, ic.impacts)
    if slack == 1.0:
        assert ic.n_steps == ip.n_steps, (where, ip.n_steps, ic.n_steps)
    else:
        assert abs(ic.n_steps - ip.n_steps) <= 0.02 * ip.n_steps + 2, (where, ip.n_steps, ic.n_steps)
    op, oc = py.outputs(), c.outputs()
    assert abs(oc["phi"] - op["phi"]) <= PHI_TOL * slack, (where, op["phi"], oc["phi"])
    for name in op:
        assert abs(oc[name] - op[name]) <= OUT_RTOL * slack * max(1.0, abs(op[name])), (where, name, op[name],
                                                                                      oc[name])
    tp, tc = list(py.impact_times), list(c.impact_times)
    assert len(tp) == len(tc), where
    assert np.allclose(tc, tp, rtol=0.0, atol=T_TOL * slack), where


def _run(model, scheme, times, ag, ag_v, slack=1.0, **kw):
    """Both engines through the same advances under (ag, ag_v), compared after each; returns the pair."""
    kw.setdefault("on_report", "ignore")
    py = Simulator(model, scheme, engine="python", **kw)
    c = Simulator(model, scheme, engine="c", **kw)
    for t in times:
        py.advance(float(t), ag, ag_v=ag_v)
        c.advance(float(t), ag, ag_v=ag_v)
        _assert_same(py, c, f"t = {t}", slack)
    return py, c


def _record_pair(seed=7, dt=0.01, T=3.0):
    """(t, ag, ag_v): a smooth synthetic three-component-like record (horizontal about 0.4 g, vertical 0.3 g)."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, T + dt / 2, dt)
    env = np.sin(np.pi * t / T) ** 2
    ag = env * sum(a * np.sin(2.0 * np.pi * f * t + p) for a, f, p in
                   zip(rng.uniform(0.1, 0.2, 3) * G, (1.3, 2.1, 3.7), rng.uniform(0, 2 * np.pi, 3)))
    ag_v = env * sum(a * np.sin(2.0 * np.pi * f * t + p) for a, f, p in
                     zip(rng.uniform(0.05, 0.1, 3) * G, (4.0, 6.5, 9.0), rng.uniform(0, 2 * np.pi, 3)))
    return t, ag, ag_v


SCHEMES = ["event_driven", "moreau_jean"]
BLOCK = dict(b=0.2, h=1.0)


# ---------------------------------------------------------------------------------------------- rigid scenes
@pytest.mark.parametrize("scheme", SCHEMES)
def test_rigid_free_rocking_under_a_constant_vertical_acceleration(scheme):
    """Free rocking from phi_0 = 0.1 under ag_v = +0.3 g (a heavier block): the same steps and impacts."""
    py, c = _run(RigidBlock(**BLOCK), scheme, np.arange(1, 31) * 0.1, 0.0, 0.3 * G, phi_0=0.1)
    assert py.integrator.impacts >= 3


@pytest.mark.parametrize("scheme", SCHEMES)
def test_rigid_uplift_threshold_moves_with_the_vertical_acceleration(scheme):
    """ag = 0.8 g tan(alpha) stays below the uplift threshold g tan(alpha) without a vertical component and lifts
    the block with ag_v = -0.5 g (threshold 0.5 g tan(alpha)): the same uplift in both engines."""
    block = RigidBlock(**BLOCK)
    ag = 0.8 * G * math.tan(block.alpha)
    py, c = _run(block, scheme, np.arange(1, 11) * 0.05, ag, -0.5 * G)
    assert abs(c.outputs()["phi"]) > 1e-3
    still = Simulator(block, scheme, engine="c")
    still.advance(0.5, ag)
    assert still.outputs()["phi"] == 0.0


@pytest.mark.parametrize("scheme", SCHEMES)
def test_rigid_pulses_in_both_directions(scheme):
    """A horizontal sine pulse (0.5 g, 2 Hz) with a vertical one (0.4 g, 5 Hz, starting later): both
    components' breakpoints, the same steps."""
    gm = TwoComponentMotion(SinePulse(0.5 * G, 2.0 * math.pi * 2.0), SinePulse(0.4 * G, 2.0 * math.pi * 5.0, 0.13))
    py, c = _run(RigidBlock(**BLOCK, e_N=0.2), scheme, np.arange(1, 41) * 0.05, gm, None)
    assert py.integrator.impacts >= 1


@pytest.mark.parametrize("scheme", SCHEMES)
@pytest.mark.parametrize("kind", ["rigid", "flexible"])
def test_ground_falling_faster_than_g_sends_the_body_into_flight(scheme, kind):
    """A rectangular vertical pulse of -1.5 g for 0.1 s (g + ag_v = -0.5 g): the body at rest leaves the
    ground (the uplift LCP returns flight, it never sinks) and lands after the pulse; both engines alike."""
    model = RigidBlock(**BLOCK) if kind == "rigid" else FlexibleOscillator(EI=9.45e4)
    drop = RectangularPulse(-1.5 * G, 0.1, 0.1)
    py, c = _run(model, scheme, np.arange(1, 41) * 0.02, 0.0, drop, slack=1.0 if kind == "rigid" else FLEX_SLACK)
    for sim in (py, c):
        assert sim.integrator.impacts >= 1
    # in the air at the pulse's end: lifted by 0.5 g (0.1 s)^2 / 2 = 0.0245 m, no corner below the ground
    sim = Simulator(model, scheme, engine="c")
    sim.advance(0.2, 0.0, ag_v=drop)
    out = sim.outputs()
    assert out["y"] > 1e-3 and int(sim.integrator.contact_code) == 3      # Mode.FLIGHT
    q, _ = sim.integrator.state()
    assert min(model.gaps(q)) >= -1e-9


def test_rigid_record_pair_through_simulate():
    """A sampled record pair (t, ag, ag_v) in one `simulate` call (the engine's sample with both components as
    sampled motions): the same contact codes and impacts at every output, phi within PHI_TOL."""
    block = RigidBlock(b=0.15, h=0.8)
    t, ag, ag_v = _record_pair()
    rp = simulate(block, (t, ag, ag_v), t_end=3.0, output_interval=0.01, engine="python")
    rc = simulate(block, (t, ag, ag_v), t_end=3.0, output_interval=0.01, engine="c")
    assert np.array_equal(np.asarray(rp["contact"]), np.asarray(rc["contact"]))
    assert np.array_equal(np.asarray(rp["impacts"]), np.asarray(rc["impacts"]))
    assert np.asarray(rp["impacts"])[-1] >= 2
    assert np.max(np.abs(np.asarray(rp["phi"]) - np.asarray(rc["phi"]))) <= PHI_TOL
    # the vertical component matters in this scene (the comparison is not that of two copies of one run)
    rh = simulate(block, (t, ag), t_end=3.0, output_interval=0.01, engine="c")
    assert np.max(np.abs(np.asarray(rh["phi"]) - np.asarray(rc["phi"]))) > 1e-3


# ---------------------------------------------------------------------------------------------- flexible scenes
@pytest.mark.parametrize("scheme", SCHEMES)
def test_flexible_pulse_with_a_vertical_component(scheme):
    """The flexible oscillator (EI = 9.45e4 N m2) under the benchmark pulse (0.25 g, 1.5 Hz) with a vertical
    sine (0.3 g, 4 Hz): the same impacts and modes, the state within the flexible bound."""
    gm = TwoComponentMotion(SinePulse(0.25 * G, 2.0 * math.pi * 1.5), SinePulse(0.3 * G, 2.0 * math.pi * 4.0))
    py, c = _run(FlexibleOscillator(EI=9.45e4), scheme, np.arange(1, 41) * 0.05, gm, None, slack=FLEX_SLACK)
    assert py.integrator.impacts >= 1


@pytest.mark.parametrize("scheme", SCHEMES)
def test_flexible_free_rocking_under_a_constant_vertical_acceleration(scheme):
    py, c = _run(FlexibleOscillator(EI=9.45e4), scheme, np.arange(1, 31) * 0.05, 0.0, -0.2 * G, slack=FLEX_SLACK,
                 phi_0=0.05)
    assert py.integrator.impacts >= 1


# ---------------------------------------------------------------------------------------------- ag_v = 0
@pytest.mark.parametrize("scheme", SCHEMES)
@pytest.mark.parametrize("kind", ["rigid", "flexible"])
def test_zero_vertical_is_bit_identical_to_none(scheme, kind):
    """ag_v = 0 as a number, as a constant vertical component of a TwoComponentMotion and through the extension
    (advance(ag_v=0.0), advance_motion / sample with vspec ('constant', 0.0)) gives the very numbers of a run
    without vertical component."""
    model = RigidBlock(**BLOCK, e_N=0.3) if kind == "rigid" else FlexibleOscillator(EI=9.45e4)
    pulse = SinePulse(0.45 * G, 2.0 * math.pi * 2.0)
    times = np.arange(1, 21) * 0.1
    runs = []
    for variant in ("none", "number", "two"):
        sim = Simulator(model, scheme, engine="c")
        rows = []
        for t in times:
            if variant == "none":
                sim.advance(float(t), pulse)
            elif variant == "number":
                sim.advance(float(t), pulse, ag_v=0.0)
            else:
                sim.advance(float(t), TwoComponentMotion(pulse, ConstantMotion(0.0)))
            rows.append(list(sim.outputs().values()) + [sim.integrator.n_steps])
        runs.append(np.array(rows))
    assert runs[0][-1, -1] > 0 and np.max(np.abs(runs[0][:, 0])) > 1e-3
    for other in runs[1:]:
        assert np.array_equal(runs[0], other)
    # the extension's entry points
    eng = [Simulator(model, scheme, engine="c").integrator._engine for _ in range(3)]
    spec = ("sine", pulse.A, pulse.omega_p, pulse.t0)
    eng[0].advance_motion(1.0, spec)
    eng[1].advance_motion(1.0, spec, vspec=("constant", 0.0))
    eng[2].advance_motion(1.0, spec, None, 0, None)
    for e in eng:
        e.advance(1.5, 0.7, 0.0, None, ag_v=0.0, ag_v_slope=0.0)
    for e in eng[1:]:
        assert e.full_state() == eng[0].full_state() and e.n_steps == eng[0].n_steps


# ---------------------------------------------------------------------------------------------- state
@pytest.mark.parametrize("scheme", SCHEMES)
def test_state_round_trip_during_a_vertical_motion(scheme):
    """get_state in the middle of a vertical pulse, loaded into a fresh C simulator and into a Python one:
    all three go on alike (C -> C bit for bit, C -> Python as the scene comparison)."""
    block = RigidBlock(**BLOCK)
    gm = TwoComponentMotion(SinePulse(0.5 * G, 2.0 * math.pi * 2.0), SinePulse(-0.6 * G, 2.0 * math.pi * 3.0))
    c = Simulator(block, scheme, engine="c")
    c.advance(0.4, gm)
    state = c.get_state()
    c2 = Simulator(block, scheme, engine="c")
    c2.set_state(state)
    py = Simulator(block, scheme, engine="python", on_report="ignore")
    py.set_state(state)
    assert c2.get_state() == state
    for t in np.arange(1, 17) * 0.05 + 0.4:
        for sim in (c, c2, py):
            sim.advance(float(t), gm)
        assert c2.outputs() == c.outputs()
        assert abs(py.outputs()["phi"] - c.outputs()["phi"]) <= PHI_TOL
        assert py.integrator.impacts == c.integrator.impacts
    assert c.integrator.impacts >= 1
    # and the other way: a Python run's state, taken during the motion, goes on alike in the C engine
    p0 = Simulator(block, scheme, engine="python", on_report="ignore")
    p0.advance(0.6, gm)
    c3 = Simulator(block, scheme, engine="c")
    c3.set_state(p0.get_state())
    for t in np.arange(1, 11) * 0.05 + 0.6:
        p0.advance(float(t), gm)
        c3.advance(float(t), gm)
        assert abs(p0.outputs()["phi"] - c3.outputs()["phi"]) <= PHI_TOL
        assert p0.integrator.impacts == c3.integrator.impacts


# ---------------------------------------------------------------------------------------------- extension
def _engine_of(scheme="event_driven", **kw):
    return Simulator(RigidBlock(**BLOCK), scheme, engine="c", **kw).integrator._engine


@pytest.mark.parametrize("scheme", SCHEMES)
def test_advance_holds_ag_v_first_order(scheme):
    """Engine.advance(t1, ag0, slope, ag_v=a, ag_v_slope=s) is the first-order hold ag_v(t) = a + s (t - t0):
    the Python under TwoComponentMotion(LinearMotion(ag0, slope, t0), LinearMotion(a, s, t0))."""
    block = RigidBlock(**BLOCK)
    py = Simulator(block, scheme, engine="python", phi_0=0.05)
    c = Simulator(block, scheme, engine="c", phi_0=0.05)
    eng = c.integrator._engine
    t0 = 0.0
    for k in range(1, 16):
        t1 = 0.04 * k
        a, s = 0.4 * G * math.sin(5.0 * t0), 2.0 * G * math.cos(5.0 * t0)
        av, sv = -0.5 * G * math.cos(7.0 * t0), 3.5 * G * math.sin(7.0 * t0)
        py.advance(t1, TwoComponentMotion(LinearMotion(a, s, t0, t0, t1), LinearMotion(av, sv, t0, t0, t1)))
        eng.advance(t1, a, s, None, ag_v=av, ag_v_slope=sv)
        assert eng.t == t1
        assert abs(eng.output_dict()["phi"] - py.outputs()["phi"]) <= PHI_TOL
        assert eng.n_steps == py.integrator.n_steps
        t0 = t1


def test_advance_arguments():
    """The hand-written parser of Engine.advance: positional and keyword arguments as the signature says, the
    errors of the generic parser, bad ag_v values refused naming ag_v with the state unchanged."""
    eng = _engine_of(phi_0=0.05)
    eng.advance(0.1, 0.0, 0.0, None)
    eng.advance(0.2, ag0=0.1, slope=0.0, max_steps=1000, continuous=False, linear=True, ag_v=1.0, ag_v_slope=0.5,
                linear_v=False)
    eng.advance(t_end=0.25)
    eng.advance(0.3, 1, 0, 50)                          # ints as reals
    eng.advance(0.35, np.float64(0.2), ag_v=np.float64(-2.0))
    before = eng.full_state(), eng.t
    for bad, pattern in ((float("nan"), r"ag_v = nan is not finite"), (1500.0, r"ag_v = 1500 is out of range"),
                         (float("inf"), r"ag_v = inf is not finite")):
        with pytest.raises(ValueError, match=pattern):
            eng.advance(0.5, 0.0, ag_v=bad)
    with pytest.raises(ValueError, match=r"ag_v rate = nan"):
        eng.advance(0.5, 0.0, ag_v=1.0, ag_v_slope=float("nan"))
    with pytest.raises(ValueError, match=r"peak \|ag_v\|"):
        eng.advance(0.5, 0.0, ag_v=900.0, ag_v_slope=1e4)
    with pytest.raises(TypeError, match="unexpected keyword argument 'agv'"):
        eng.advance(0.5, agv=1.0)
    with pytest.raises(TypeError, match="multiple values for argument 'ag0'"):
        eng.advance(0.5, 0.0, ag0=1.0)
    with pytest.raises(TypeError, match="missing required argument 't_end'"):
        eng.advance(ag0=1.0)
    with pytest.raises(TypeError, match="at most 9 arguments"):
        eng.advance(0.5, 0.0, 0.0, None, False, False, 0.0, 0.0, False, 1.0)
    with pytest.raises(TypeError, match="'ag_v' must be a real number"):
        eng.advance(0.5, 0.0, ag_v="1")
    with pytest.raises(ValueError, match="max_steps"):
        eng.advance(0.5, 0.0, 0.0, -3)
    assert (eng.full_state(), eng.t) == before


def test_vspec_of_a_callback_vertical_motion():
    """A vertical component the engine does not describe natively runs as a Python callback (exact): the same
    numbers as its native description."""
    from rocking_model.engine import motion_spec, vertical_spec

    class Wrapped(SinePulse):
        """A subclass: not one of the classes the engine evaluates itself."""

    native = TwoComponentMotion(SinePulse(0.5 * G, 12.0), SinePulse(-0.7 * G, 20.0, 0.05))
    wrapped = TwoComponentMotion(SinePulse(0.5 * G, 12.0), Wrapped(-0.7 * G, 20.0, 0.05))
    assert vertical_spec(wrapped)[0] == "callback" and vertical_spec(native)[0] == "sine"
    assert motion_spec(native) == ("sine", 0.5 * G, 12.0, 0.0)
    assert vertical_spec(SinePulse(1.0, 1.0)) is None
    runs = []
    for gm in (native, wrapped):
        sim = Simulator(RigidBlock(**BLOCK), "event_driven", engine="c")
        sim.advance(1.0, gm)
        runs.append((sim.outputs(), sim.integrator.n_steps))
    assert runs[0] == runs[1]


def _pair_cases():
    t, ag, ag_v = _record_pair(dt=0.05, T=2.0)
    record = SampledMotion(t, ag)
    vrecord = SampledMotion(t, ag_v)
    shifted = SampledMotion(t[:20] + 0.025, ag_v[:20])         # samples between the horizontal record's
    return {
        "record pair (same samples)": TwoComponentMotion(record, vrecord),
        "records on interleaved samples": TwoComponentMotion(record, shifted),
        "record and a rectangular drop": TwoComponentMotion(record, RectangularPulse(-1.5 * G, 0.3, 0.4)),
        "sine pulses": TwoComponentMotion(SinePulse(2.0, 5.0, 0.1), SinePulse(-3.0, 9.0, 0.35)),
        "constant and a record": TwoComponentMotion(ConstantMotion(0.5), vrecord),
        "record and a constant": TwoComponentMotion(record, ConstantMotion(-2.0)),
        "a sine and its own start": TwoComponentMotion(SinePulse(2.0, 5.0, 0.5), RectangularPulse(1.0, 0.2, 0.5)),
    }


@pytest.mark.parametrize("case", sorted(_pair_cases()))
def test_the_pair_of_motions_equals_two_component_motion(case):
    """rk_motion_pair_*: the values of both components, the next breakpoint (the earlier of both) and the
    continuity at a breakpoint (both continuous, a component without a breakpoint there continuous) equal
    TwoComponentMotion's at the breakpoints of both, their neighbours and a grid."""
    from rocking_model.engine import motion_spec, vertical_spec
    gm = _pair_cases()[case]
    times = list(np.linspace(-0.3, 2.5, 701))
    bps, t = [], -1.0
    while len(bps) < 200:
        t = gm.next_breakpoint(t)
        if not math.isfinite(t):
            break
        bps.append(t)
    times += bps + [float(np.nextafter(b, 9.0)) for b in bps] + [float(np.nextafter(b, -9.0)) for b in bps]
    values, nb, cont, vvalues = _engine.motion_eval(motion_spec(gm), times, vertical_spec(gm))
    assert values == [float(gm(x)) for x in times]
    assert vvalues == [float(gm.vertical(x)) for x in times]
    assert nb == [float(gm.next_breakpoint(x)) for x in times]
    assert cont == [bool(gm.continuous_at(x)) for x in times]


# ---------------------------------------------------------------------------------------------- hypothesis
from hypothesis import HealthCheck, given, settings          # noqa: E402
from hypothesis import strategies as st                      # noqa: E402
from test_engine_event_driven import advance_pair             # noqa: E402

#: [rad] hypothesis scenes: the same motion to the scheme's tolerance (an error of order tol per step that
#: impacts amplify; 1e-6 rad is 1e-5 of the rocking amplitudes), as tests/test_engine_event_driven.py
SCENE_PHI_TOL = 1e-6


def _hypothesis_scene(model, scheme, phi0, gm, times):
    py = Simulator(model, scheme, engine="python", phi_0=phi0, on_report="ignore", max_steps=None)
    c = Simulator(model, scheme, engine="c", phi_0=phi0, on_report="ignore", max_steps=None)
    if advance_pair(py, c, gm, times):
        assert abs(c.outputs()["phi"] - py.outputs()["phi"]) <= SCENE_PHI_TOL, (py.outputs()["phi"],
                                                                                 c.outputs()["phi"])


@settings(max_examples=30, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
@given(b=st.floats(0.1, 0.5), h=st.floats(0.8, 2.0), e_N=st.floats(0.0, 1.0), mu=st.sampled_from([math.inf, 0.5]),
       scheme=st.sampled_from(SCHEMES), phi0=st.floats(-0.1, 0.1), A=st.floats(0.0, 0.6), f=st.floats(0.5, 4.0),
       Av=st.floats(-1.5, 0.8), fv=st.floats(1.0, 10.0))
def test_hypothesis_rigid_vertical_scenes(b, h, e_N, mu, scheme, phi0, A, f, Av, fv):
    """Random blocks under random pulses in both directions (the vertical one down to -1.5 g: flight):
    finite states, the same motion in both engines within the scheme's tolerance."""
    block = RigidBlock(b=b, h=h, e_N=e_N, mu=mu)
    gm = TwoComponentMotion(SinePulse(A * G, 2.0 * math.pi * f), SinePulse(Av * G, 2.0 * math.pi * fv, 0.05))
    _hypothesis_scene(block, scheme, phi0 * block.alpha, gm, (0.5, 1.0))


@settings(max_examples=8, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
@given(EI=st.floats(4.5, 5.3), e_N=st.floats(0.0, 1.0), rule=st.sampled_from([0, 1]), phi0=st.floats(-0.1, 0.1),
       A=st.floats(0.0, 0.5), f=st.floats(0.5, 3.0), Av=st.floats(-1.2, 0.8), fv=st.floats(1.0, 8.0))
def test_hypothesis_flexible_vertical_scenes(EI, e_N, rule, phi0, A, f, Av, fv):
    osc = FlexibleOscillator(EI=10.0 ** EI, e_N=e_N, impact_rule=rule)
    gm = TwoComponentMotion(SinePulse(A * G, 2.0 * math.pi * f), SinePulse(Av * G, 2.0 * math.pi * fv, 0.05))
    _hypothesis_scene(osc, "event_driven", phi0 * math.atan2(osc.b, osc.h), gm, (0.5, 1.0))
