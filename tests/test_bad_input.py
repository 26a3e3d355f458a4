"""Bad input: every case through the Python API (ValueError naming the variable and its allowed
range) and through the FMUs driven by fmpy's FMU2Slave (fmi2Error with the same message, which
reaches the logger with logging off; nothing crashes, the instance can be reset, restored or freed and other
instances keep working)."""
from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

fmpy = pytest.importorskip("fmpy")
pytest.importorskip("pythonfmu")

from fmu_instance import Instance  # noqa: E402
from rocking_model import FlexibleOscillator, RigidBlock, Simulator, simulate  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
FMI2_ERROR, FMI2_DISCARD = 3, 2
RIGID, FLEX = "RigidRockingBlock", "FlexibleRockingOscillator"


# ---------------------------------------------------------------------------------------------- helpers
@pytest.fixture(scope="module")
def fmus(extracted_fmus):
    return extracted_fmus


def python_simulator(kind, params):
    """The Python API with the FMU's parameter names (the FMU scripts' create_simulator, spelled out)."""
    p = dict(params)
    solver = {k: p.pop(k) for k in ("scheme", "dt_max", "tolerance") if k in p}
    initial = {k: p.pop(k) for k in ("phi_0", "phi_dot_0", "u_0", "u_dot_0") if k in p}
    model = RigidBlock(**p) if kind == RIGID else FlexibleOscillator(**p)
    return Simulator(model, **{"scheme": 0, **solver}, **initial)


def python_error(kind, params) -> str:
    with pytest.raises(ValueError) as info:
        python_simulator(kind, params)
    return str(info.value)


# ---------------------------------------------------------------------------------------------- parameters
NAN, INF = float("nan"), float("inf")
BAD_PARAMETERS = [
    # (FMU, parameter values, variable, allowed range as printed)
    (RIGID, {"b": -1.0}, "b", "[1e-06, 1000]"),
    (RIGID, {"b": 0.0}, "b", "[1e-06, 1000]"),
    (RIGID, {"b": NAN}, "b", "[1e-06, 1000]"),
    (RIGID, {"b": 1e200}, "b", "[1e-06, 1000]"),
    (RIGID, {"h": 0.0}, "h", "[1e-06, 1000]"),
    (RIGID, {"h": INF}, "h", "[1e-06, 1000]"),
    (RIGID, {"m": 0.0}, "m", "[1e-09, 1e+12]"),
    (RIGID, {"m": -2.0}, "m", "[1e-09, 1e+12]"),
    (RIGID, {"g": 0.0}, "g", "[0.001, 1000]"),
    (RIGID, {"g": -9.81}, "g", "[0.001, 1000]"),
    (RIGID, {"e_N": 1.5}, "e_N", "[0, 1]"),
    (RIGID, {"e_N": -0.1}, "e_N", "[0, 1]"),
    (RIGID, {"e_N": NAN}, "e_N", "[0, 1]"),
    (RIGID, {"phi_0": math.pi / 2}, "phi_0", "(-1.5708, 1.5708)"),
    (RIGID, {"phi_0": -2.0}, "phi_0", "(-1.5708, 1.5708)"),
    (RIGID, {"phi_dot_0": NAN}, "phi_dot_0", "[-10000, 10000]"),
    (RIGID, {"phi_dot_0": 1e5}, "phi_dot_0", "[-10000, 10000]"),
    (RIGID, {"dt_max": -1e-3}, "dt_max", "[0, inf)"),
    (RIGID, {"scheme": 1, "tolerance": 0.0}, "tolerance", "[1e-14, 0.01]"),
    (RIGID, {"scheme": 1, "tolerance": 0.5}, "tolerance", "[1e-14, 0.01]"),
    (RIGID, {"scheme": 1, "dt_max": INF}, "dt_max", "[0, inf)"),
    (RIGID, {"scheme": 2}, "scheme", "allowed values: 'moreau_jean', 0, 'event_driven', 1"),
    (RIGID, {"scheme": -1}, "scheme", "allowed values: 'moreau_jean', 0, 'event_driven', 1"),
    (FLEX, {"EI": 0.0}, "EI", "(0, 1e+15]"),
    (FLEX, {"EI": -9.45e5}, "EI", "(0, 1e+15]"),
    (FLEX, {"EI": INF}, "EI", "(0, 1e+15]"),
    (FLEX, {"rho": -0.1}, "rho", "[0, 1000]"),
    (FLEX, {"zeta": -0.01}, "zeta", "[0, 10]"),
    (FLEX, {"zeta": NAN}, "zeta", "[0, 10]"),
    (FLEX, {"m": 0.0}, "m", "[1e-09, 1e+12]"),
    (FLEX, {"m_c": -1.0}, "m_c", "[0, 1e+12]"),
    (FLEX, {"m_b": -1.0}, "m_b", "[0, 1e+12]"),
    (FLEX, {"m_c": 0.0, "m_b": 0.0}, "m_b", "m_b in (0, 1e+12] and rho in (0, 1000]"),
    (FLEX, {"m_c": 0.0, "rho": 0.0}, "rho", "m_b in (0, 1e+12] and rho in (0, 1000]"),
    (FLEX, {"h": 0.0}, "h", "[1e-06, 1000]"),
    (FLEX, {"b": -0.25}, "b", "[1e-06, 1000]"),
    (FLEX, {"g": 0.0}, "g", "[0.001, 1000]"),
    (FLEX, {"e_N": 2.0}, "e_N", "[0, 1]"),
    (FLEX, {"phi_0": -math.pi / 2}, "phi_0", "(-1.5708, 1.5708)"),
    (FLEX, {"u_0": 2.0}, "u_0", "[-1.5, 1.5]"),
    (FLEX, {"u_0": NAN}, "u_0", "[-1.5, 1.5]"),
    (FLEX, {"u_dot_0": -INF}, "u_dot_0", "[-10000, 10000]"),
    (FLEX, {"impact_rule": 3}, "impact_rule", "allowed values: 0, 1, 'lcp', 'classical'"),
    (FLEX, {"scheme": 7}, "scheme", "allowed values: 'moreau_jean', 0, 'event_driven', 1"),
    (FLEX, {"dt_max": NAN}, "dt_max", "[0, inf)"),
    # mu's stated minimum (1/mu = inf at 5e-324 hung the event-driven step in LAPACK)
    (RIGID, {"mu": 5e-324}, "mu", "[0.001, inf]"),
    (FLEX, {"scheme": 1, "mu": 5e-324}, "mu", "[0.001, inf]"),
    (FLEX, {"mu": 0.0}, "mu", "[0.001, inf]"),
]
IDS = [f"{k[:5]}-{'-'.join(f'{n}={v}' for n, v in p.items())}" for k, p, _, _ in BAD_PARAMETERS]


@pytest.mark.parametrize("kind, params, name, allowed", BAD_PARAMETERS, ids=IDS)
def test_bad_parameter_python_api(kind, params, name, allowed):
    msg = python_error(kind, params)
    assert msg.startswith(f"{name} = "), msg
    assert allowed in msg and "allowed" in msg, msg


@pytest.mark.parametrize("kind, params, name, allowed", BAD_PARAMETERS, ids=IDS)
def test_bad_parameter_fmu(fmus, kind, params, name, allowed):
    py_msg = python_error(kind, params)
    inst = Instance(fmus[kind])
    msg = inst.error_init(**params)  # fmi2ExitInitializationMode fails: fmpy raises
    assert msg == f"fmi2ExitInitializationMode: invalid parameters: {py_msg}"
    # the instance is in the error state: a step is an illegal call, answered with fmi2Error and a message
    assert inst.step() == FMI2_ERROR
    assert "fmi2DoStep: illegal call sequence" in inst.errors()[-1]
    assert inst.get("phi") == [0.0]  # getters still serve
    # the instance can be reset and used with valid parameters
    inst.fmu.reset()
    inst.init(phi_0=0.05)
    assert inst.step() == 0 and inst.step() == 0
    assert 0.0 < inst.get("phi")[0] < 0.05
    inst.free()


def test_parameters_inside_the_ranges_are_accepted():
    # the bounds themselves are supported
    RigidBlock(b=1e-6, h=1e3, m=1e-9, g=1e3)
    RigidBlock(b=1e3, h=1e-6, m=1e12, g=1e-3, e_N=1.0)
    FlexibleOscillator(m=1e12, m_c=0.0, m_b=1e12, rho=1e3, h=1e3, b=1e-6, EI=1e15, zeta=10.0, g=1e-3)
    FlexibleOscillator().initial_state(u_0=-1.5, u_dot_0=1e4, phi_dot_0=-1e4)
    # huge but allowed values give finite outputs (no overflow inside the supported ranges)
    for model in (RigidBlock(b=1e3, h=1e3, m=1e12, g=1e3), RigidBlock(b=1e-6, h=1e-6, m=1e-9, g=1e-3)):
        for scheme in (0, 1):
            sim = Simulator(model, scheme, dt_max=1e-3, phi_0=0.3, phi_dot_0=1e4 if model.b < 1 else -1.0)
            sim.advance(0.01, 0.3 * model.g)
            assert all(math.isfinite(float(v)) for v in sim.outputs().values())


@pytest.mark.parametrize("scheme", ["event_driven", "moreau_jean"])
def test_method_is_checked_for_every_scheme_and_rk45_is_dopri5(scheme):
    """The Runge-Kutta method is checked by the Simulator whatever the scheme (a name the engine would refuse
    never reaches it); scipy's name RK45 runs DOPRI5, bit for bit."""
    with pytest.raises(ValueError, match=r"method = 'RK23' is not supported; allowed values: 'DOP853', 'DOPRI5'"):
        Simulator(RigidBlock(), scheme, method="RK23")
    runs = [simulate(RigidBlock(b=0.2, h=1.0), lambda t: 4.0 if t < 0.5 else 0.0, 2.0, scheme=scheme, method=m)
            for m in ("RK45", "DOPRI5", 1)]
    assert max(abs(runs[0].phi)) > 1e-3, "the block rocks"
    for other in runs[1:]:
        assert np.array_equal(runs[0].phi, other.phi)


def test_dt_max_zero_selects_the_scheme_default():
    # the FMUs' start value dt_max = 0: Moreau-Jean 1e-3 s, the event-driven scheme uncapped
    assert Simulator(RigidBlock(), 0, dt_max=0.0).integrator.dt_max == 1e-3
    assert Simulator(RigidBlock(), 1, dt_max=0.0).integrator.dt_max == math.inf
    assert Simulator(RigidBlock(), 1).integrator.dt_max == math.inf
    assert Simulator(RigidBlock(), 1, dt_max=2e-3).integrator.dt_max == 2e-3


# ---------------------------------------------------------------------------------------------- steps
@pytest.mark.parametrize("kind", [RIGID, FLEX])
@pytest.mark.parametrize("dt", [0.0, -0.01, NAN, INF])
def test_bad_step_size(fmus, kind, dt):
    inst = Instance(fmus[kind])
    inst.init(phi_0=0.02)
    assert inst.step() == 0
    saved = inst.state()
    before = inst.get("phi", "phi_dot", "energy")
    assert inst.step(dt) == FMI2_ERROR  # an invalid argument
    assert inst.errors() == [f"fmi2DoStep: communicationStepSize = {dt:g} is invalid; allowed range (0, inf)"]
    assert inst.get("phi", "phi_dot", "energy") == before  # the state is unchanged
    inst.fmu.setFMUState(saved)  # out of the error state through a saved state
    assert inst.step() == 0
    inst.fmu.freeFMUState(saved)
    inst.free()


def test_bad_step_python_api():
    sim = Simulator(RigidBlock(), phi_0=0.02)
    sim.advance(1.0, 0.0)
    with pytest.raises(ValueError, match=r"^t_end = 0\.5 is before the current time; allowed range \[1, inf\)"):
        sim.advance(0.5, 0.0)
    with pytest.raises(ValueError, match=r"^t_end = nan is not finite"):
        sim.advance(float("nan"), 0.0)
    for interval in (0.0, -0.01):
        with pytest.raises(ValueError, match=r"^output_interval = .* allowed range \(0, inf\)"):
            simulate(RigidBlock(), 0.0, 1.0, output_interval=interval)
    with pytest.raises(ValueError, match=r"^t_end = 0\.5 is out of range; allowed range \[1, inf\)"):
        simulate(RigidBlock(), 0.0, 0.5, t0=1.0)


@pytest.mark.parametrize("kind", [RIGID, FLEX])
@pytest.mark.parametrize("offset", [-0.005, 0.005, -0.02, NAN])
def test_communication_point_must_follow_the_last_one(fmus, kind, offset):
    inst = Instance(fmus[kind])
    inst.init(phi_0=0.02)
    for _ in range(3):
        assert inst.step() == 0
    before = inst.get("phi", "phi_dot", "energy")
    saved = inst.state()
    t_bad = inst.t + offset
    assert inst.step(0.01, t=t_bad) == FMI2_ERROR
    (msg,) = inst.errors()
    assert msg.startswith("fmi2DoStep: currentCommunicationPoint = "), msg
    assert math.isnan(offset) or float(msg.split(" = ")[1].split()[0]) == t_bad
    assert f"does not match the time of the instance, {inst.t:.17g}" in msg
    assert inst.get("phi", "phi_dot", "energy") == before
    inst.fmu.setFMUState(saved)
    assert inst.step() == 0
    inst.fmu.freeFMUState(saved)
    inst.free()


# ---------------------------------------------------------------------------------------------- inputs
@pytest.mark.parametrize("kind", [RIGID, FLEX])
@pytest.mark.parametrize("ag", [NAN, INF, -INF])
def test_non_finite_ag(fmus, kind, ag):
    sim = python_simulator(kind, {})
    with pytest.raises(ValueError) as info:
        sim.advance(0.01, ag)
    py_msg = str(info.value)
    assert py_msg == f"ag = {ag!r} is not finite; allowed range [-1000, 1000]"       # |ag| <= AG_MAX
    inst = Instance(fmus[kind])
    inst.init()
    assert inst.step() == 0
    saved = inst.state()
    assert inst.try_set(ag=ag) == FMI2_ERROR  # an invalid value: refused where it is set
    # (the allowed range in the FMU's message is the input's declared min/max)
    (msg,) = inst.errors()
    assert msg == f"fmi2SetReal: input {py_msg} (nothing was set)"
    assert inst.get("ag") == [0.0]
    inst.fmu.setFMUState(saved)
    inst.set(ag=0.0)  # a valid input: the step goes through
    assert inst.step() == 0 and math.isclose(inst.t, 0.02)
    inst.fmu.freeFMUState(saved)
    inst.free()


# ---------------------------------------------------------------------------------------------- late changes
@pytest.mark.parametrize("kind, name, value", [(RIGID, "b", 0.3), (RIGID, "e_N", 0.5), (RIGID, "scheme", 0),
                                               (FLEX, "EI", 1e5), (FLEX, "impact_rule", 1)])
def test_fixed_parameter_changed_after_initialization(fmus, kind, name, value):
    inst = Instance(fmus[kind])
    inst.init(phi_0=0.02)
    assert inst.step() == 0
    old = inst.get(name)[0]
    assert inst.try_set(**{name: value}) == FMI2_ERROR
    assert inst.get(name) == [old]  # rejected, the old value is kept
    (msg,) = inst.errors()
    assert f"parameter {name} is 'fixed' and cannot be changed after initialization (requested {value!r}" in msg
    assert inst.step() == FMI2_ERROR  # the error state: only fmi2Reset, a saved state or the getters
    inst.fmu.reset()
    inst.init(phi_0=0.02, **{name: value})  # a fixed parameter is changed by starting again
    assert inst.get(name) == [value] and inst.step() == 0
    inst.free()


def test_python_models_are_immutable():
    block = RigidBlock()
    with pytest.raises(dataclasses.FrozenInstanceError):
        block.b = 0.3
    with pytest.raises(dataclasses.FrozenInstanceError):
        FlexibleOscillator().EI = 1.0


def test_unknown_initial_values_python_api():
    with pytest.raises(ValueError, match=r"unknown keyword argument\(s\) 'u_0' for RigidBlock; allowed initial "
                                         r"values: phi_0, phi_dot_0; solver options: scheme, dt_max"):
        Simulator(RigidBlock(), u_0=0.1)


@pytest.mark.parametrize("keyword, hint", [("sheme", "scheme"), ("phi0", "phi_0"), ("tolerence", "tolerance"),
                                           ("dtmax", "dt_max")])
def test_misspelt_keyword_names_the_closest(keyword, hint):
    """A misspelt solver option is not reported as an unknown initial value only."""
    with pytest.raises(ValueError, match=f"'{keyword}' \\(did you mean '{hint}'\\?\\)"):
        simulate(RigidBlock(), 0.0, 0.1, **{keyword: 1})


def test_no_initial_penetration():
    """The initial state comes from phi_0 alone (the pivot corner on the ground): it cannot penetrate."""
    for model in (RigidBlock(b=0.3, h=0.7), FlexibleOscillator()):
        for phi_0 in np.linspace(-1.5707, 1.5707, 41):
            for phi_dot_0 in (-1.0, 0.0, 1.0):
                mode, q, v = model.initial_state(phi_0=float(phi_0), phi_dot_0=phi_dot_0)
                gaps = model.gaps(q)
                assert gaps.min() >= -1e-15 * model.length_scale
                assert abs(gaps.min()) <= 1e-15 * model.length_scale  # resting on a corner


# ---------------------------------------------------------------------------------------------- robustness
def test_errors_do_not_disturb_other_instances(fmus):
    """An instance that fails (bad parameters, bad steps, bad inputs) leaves the others in the process
    untouched: the good instance gives bit-identical outputs to a run without the bad one."""
    table = [2.0 * math.sin(2 * math.pi * k / 100) for k in range(100)]

    def run(with_bad):
        good = Instance(fmus[RIGID], "good")
        good.init(phi_0=0.0)
        bad = [Instance(fmus[RIGID], "bad"), Instance(fmus[FLEX], "bad2")] if with_bad else []
        if with_bad:
            bad[0].error_init(b=-1.0)
            bad[1].error_init(EI=0.0)
        out = []
        for k, ag in enumerate(table):
            good.set(ag=ag)
            assert good.step() == 0
            out.append(good.get("phi", "phi_dot", "x", "y", "energy", "impacts"))
            for inst in bad:
                assert inst.try_set(ag=NAN if k % 3 == 0 else ag) == FMI2_ERROR
                assert inst.step(dt=0.0 if k % 2 else 0.01) == FMI2_ERROR
        for inst in bad:
            inst.free()  # freeing a failed instance is fine
        good.free()
        return out

    assert run(True) == run(False)


def test_reset_after_error_brings_back_the_start_values(fmus):
    inst = Instance(fmus[FLEX])
    inst.error_init(zeta=-1.0)
    assert inst.step() == FMI2_ERROR
    inst.fmu.reset()
    inst.fmu.setupExperiment(startTime=0.0)
    inst.fmu.enterInitializationMode()  # (FMI 2.0: no getters before initialization mode)
    assert inst.get("zeta") == [0.02]  # start value again
    inst.set(phi_0=0.01)
    inst.fmu.exitInitializationMode()
    n_errors = len(inst.errors())
    for _ in range(5):
        assert inst.step() == 0
    assert len(inst.errors()) == n_errors  # no new error
    inst.free()
