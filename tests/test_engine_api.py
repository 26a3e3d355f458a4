"""The C engine's public API through Python : ground motions pinned to ground_motion.py, the
Engine type, its errors, state round trips (both schemes), checkpoint / rollback, snapshots,
bounded logs, and Simulator(engine=...)."""
import math
import pickle

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from c_motion import motion_eval
from rocking_model import _engine
from rocking_model.engine import CompiledIntegrator, motion_spec
from rocking_model.ground_motion import (ConstantMotion, CosinePulse, FunctionMotion, LinearMotion, RectangularPulse,
                                         RickerPulse, SampledMotion, ScaledMotion, SinePulse, checked_motion)
from rocking_model.models import FlexibleOscillator, RigidBlock
from rocking_model.simulation import Simulator, simulate
from rocking_model.validation import WorkLimitError


def _engine_works(kind="rigid", scheme="moreau_jean"):
    """None if an engine of this model and scheme can run a step, else the reason (the part not merged)."""
    model = RigidBlock() if kind == "rigid" else FlexibleOscillator()
    try:
        sim = Simulator(model, scheme, engine="c", phi_0=0.05)
        sim.advance(0.01, 0.0)
    except NotImplementedError as exc:
        return str(exc)
    return None


_REASON = _engine_works()
needs_mj = pytest.mark.skipif(_REASON is not None, reason=f"needs parts A and B merged: {_REASON}")
_REASON_ED = _engine_works(scheme="event_driven")
needs_ed = pytest.mark.skipif(_REASON_ED is not None, reason=f"needs parts A-D merged: {_REASON_ED}")


# ---------------------------------------------------------------------------------------------- ground motions
def _python_trace(gm, times):
    return ([gm(t) for t in times], [gm.next_breakpoint(t) for t in times], [gm.continuous_at(t) for t in times])


def _times(lo, hi, n=200, seed=0):
    rng = np.random.default_rng(seed)
    t = list(rng.uniform(lo, hi, n))
    return t + [lo, hi, 0.5 * (lo + hi)]


RECORD_T = np.cumsum(np.r_[0.0, np.random.default_rng(1).uniform(0.002, 0.01, 300)])
RECORD_AG = np.random.default_rng(2).normal(0.0, 3.0, RECORD_T.size)


@pytest.mark.parametrize("gm", [
    ConstantMotion(1.25),
    LinearMotion(0.7, -3.1, 0.37, 0.0, 1.0),
    SampledMotion(RECORD_T, RECORD_AG),
    SinePulse(2.5, 7.0, 0.2),
    ScaledMotion(SinePulse(2.5, 7.0, 0.2), -1.7),
    ScaledMotion(SampledMotion(RECORD_T, RECORD_AG), 0.3),
    CosinePulse(2.0, 5.0, 0.3),
    RickerPulse(3.0, 6.0),
    RickerPulse(-2.5, 17.0, 0.3),
    RectangularPulse(2.0, 0.4, 0.2),
    RectangularPulse(-1.0, 1e-11, 1.5),
], ids=["constant", "linear", "sampled", "sine", "scaled_sine", "scaled_record", "cosine", "ricker", "ricker_tc",
        "rect", "rect_sliver"])
def test_motions_equal_the_python_classes_bit_for_bit(gm):
    spec = motion_spec(gm)
    assert spec[0] != "callback"
    times = [float(t) for t in _times(-0.5, 3.0, n=3000)]
    bps = list(getattr(gm, "_bp", []))
    times += bps + [float(np.nextafter(b, 9.0)) for b in bps] + [float(np.nextafter(b, -9.0)) for b in bps]
    # the samples themselves, their neighbours and the ends: the interval cache and the bisection
    times += list(RECORD_T[::7]) + [np.nextafter(x, -1.0) for x in RECORD_T[::11]] + [RECORD_T[-1] + 1.0]
    c = motion_eval(spec, times)
    p = _python_trace(gm, times)
    assert c[0] == p[0]
    assert c[1] == p[1]
    assert c[2] == p[2]


def test_a_python_motion_runs_as_a_callback_with_its_breakpoints():
    gm = checked_motion(FunctionMotion(lambda t: 3.0 * math.sin(2.0 * t), breakpoints=[0.5, 1.25]))
    spec = motion_spec(gm)
    assert spec[0] == "callback"
    times = _times(0.0, 3.0)
    assert motion_eval(spec, times) == tuple(_python_trace(gm, times))


def test_a_failing_callback_raises_the_python_exception():
    gm = FunctionMotion(lambda t: 1e9 if t > 0.5 else 0.0)
    with pytest.raises(ValueError, match=r"ag\(0\.75\) = 1e\+09 is out of range"):
        motion_eval(motion_spec(gm), [0.25, 0.75])


@settings(max_examples=60, derandomize=True, deadline=None)
@given(st.floats(-1e3, 1e3), st.floats(0.1, 100.0), st.floats(-5.0, 5.0),
       st.lists(st.floats(-10.0, 20.0), min_size=1, max_size=20))
def test_pulses_agree_everywhere(A, w, t0, times):
    for gm in (SinePulse(A, w, t0), CosinePulse(A, w, t0), RickerPulse(A, w, t0), RectangularPulse(A, 1.0 / w, t0)):
        assert motion_eval(motion_spec(gm), times) == tuple(_python_trace(gm, times)), type(gm).__name__


def test_bad_motion_specs_are_clear_errors():
    with pytest.raises(ValueError, match="strictly increasing"):
        motion_eval(("sampled", np.array([0.0, 1.0, 1.0]), np.array([0.0, 1.0, 2.0])), [0.5])
    with pytest.raises(ValueError, match="omega_p"):
        motion_eval(("sine", 1.0, -2.0, 0.0), [0.5])
    with pytest.raises(TypeError, match="float64"):
        motion_eval(("sampled", np.array([0, 1, 2]), np.array([0.0, 1.0, 2.0])), [0.5])
    with pytest.raises(ValueError, match="unknown kind"):
        motion_eval(("cosine", 1.0), [0.5])


# ---------------------------------------------------------------------------------------------- Engine, errors
def test_engine_type_reports_what_is_missing_or_runs():
    params = [float(getattr(RigidBlock(), p.name)) for p in RigidBlock.parameters()]
    eng = _engine.Engine("rigid", params, [0.05, 0.0], scheme="moreau_jean")
    assert eng.output_names == tuple(p.name for p in RigidBlock.OUTPUTS)
    assert eng.t == 0.0 and eng.n_dof == 3 and eng.model_class == "RigidBlock"


def test_unknown_engine_is_refused_with_the_allowed_values():
    with pytest.raises(ValueError, match="engine = 'fortran' is not supported; allowed values: 'c'"):
        Simulator(RigidBlock(), engine="fortran")
    with pytest.raises(ValueError, match="engine = 'python' is not supported: the Python reference engine was "
                                         "removed"):
        Simulator(RigidBlock(), engine="python")


def test_engine_c_is_the_default_and_the_keyword_changes_nothing():
    a = Simulator(RigidBlock(), phi_0=0.1)
    b = Simulator(RigidBlock(), phi_0=0.1, engine="c")
    for t in (0.5, 1.0, 2.5):
        a.advance(t, 0.3)
        b.advance(t, 0.3)
    assert a.engine == b.engine == "c" and a.get_state() == b.get_state()


@needs_mj
@pytest.mark.parametrize("kwargs, match", [
    (dict(theta=0.3), r"theta = 0\.3 is out of range; allowed range \[0\.5, 1\]"),
    (dict(dt_max=-1.0), r"dt_max = -1 is out of range"),
    (dict(dt_max=1e-9), r"dt_max = 1e-09 is out of range; allowed values 0"),
    (dict(phi_0=2.0), r"phi_0"),
])
def test_bad_input_is_refused_naming_it(kwargs, match):
    with pytest.raises(ValueError, match=match):
        Simulator(RigidBlock(), "moreau_jean", **kwargs)


@needs_mj
@pytest.mark.parametrize("t_end, ag, match", [
    (-1.0, 0.0, r"t_end = -1 is before the current time"),
    (float("nan"), 0.0, r"t_end = nan is not finite"),
    (1.0, 2e3, r"ag = 2000 is out of range; allowed range \[-1000, 1000\]"),
    (1.0, float("inf"), r"ag = inf is not finite"),
])
def test_bad_advances_are_refused_and_keep_the_state(t_end, ag, match):
    sim = Simulator(RigidBlock(), "moreau_jean", phi_0=0.1)
    sim.advance(0.1, 0.0)
    before = sim.get_state()
    with pytest.raises(ValueError, match=match):
        sim.advance(t_end, ag)
    assert sim.get_state() == before


@needs_mj
def test_the_raw_engine_checks_its_inputs_too():
    params = [float(getattr(RigidBlock(), p.name)) for p in RigidBlock.parameters()]
    eng = _engine.Engine("rigid", params, [0.05, 0.0], scheme="moreau_jean")
    for args, match in [((-1.0,), "before the current time"), ((1.0, float("nan")), "ag = nan is not finite"),
                        ((1.0, 1e4), "ag = 10000 is out of range"),
                        ((1.0, 0.0, float("inf")), "ag rate = inf is not finite"),
                        ((1.0, 900.0, 500.0), r"peak \|ag\| = 1400")]:
        with pytest.raises(ValueError, match=match):
            eng.advance(*args)
        assert eng.t == 0.0
    with pytest.raises(ValueError, match="model 'rigid' takes 7 parameters, got 2"):
        _engine.Engine("rigid", [1.0, 2.0])
    with pytest.raises(ValueError, match="b = "):
        _engine.Engine("rigid", [-1.0] + params[1:])


# ---------------------------------------------------------------------------------------------- work limit
@needs_mj
@pytest.mark.parametrize("model, t0, span", [(RigidBlock(), 0.0, 1.0),
                                             (FlexibleOscillator(EI=9.45e7), 123456.789, 1e6)],
                         ids=["rigid", "flexible_stiff"])
def test_work_refusal_before_any_work(model, t0, span):
    sim = Simulator(model, "moreau_jean", phi_0=0.1, max_steps=50, t0=t0)
    sim.advance(t0 + 0.02, 0.0)
    before = sim.get_state()
    with pytest.raises(WorkLimitError, match="max_steps = 50"):
        sim.advance(t0 + span, 0.0)
    assert sim.get_state() == before


# ---------------------------------------------------------------------------------------------- state, checkpoint
def _scene(scheme="moreau_jean", model=None, **kw):
    sim = Simulator(model or RigidBlock(b=0.25, h=1.0, e_N=0.9), scheme, phi_0=0.15, **kw)
    return sim


def _run(sim, t0, t1, dt=0.05, ag=lambda t: 0.0):
    t = t0
    while t < t1 - 1e-12:
        t = min(t + dt, t1)
        sim.advance(t, ag(t))


@needs_mj
@pytest.mark.parametrize("model", [None, FlexibleOscillator(e_N=0.5)], ids=["rigid", "flexible"])
@pytest.mark.parametrize("scheme", ["moreau_jean", pytest.param("event_driven", marks=needs_ed)])
def test_a_loaded_state_continues_exactly(scheme, model):
    ag = lambda t: 2.0 * math.sin(7.0 * t)  # noqa: E731
    c = _scene(scheme, model=model)
    _run(c, 0.0, 0.6, ag=ag)
    c2 = _scene(scheme, model=model)
    c2.set_state(c.get_state())
    for sim in (c, c2):
        _run(sim, 0.6, 1.2, ag=ag)
    assert c2.get_state() == c.get_state() and c.get_state()["t"] == 1.2


def _close_states(a, b, tol=1e-12):
    assert a.keys() == b.keys()
    for k in a:
        x, y = a[k], b[k]
        if isinstance(x, list):
            assert len(x) == len(y), k
            assert np.allclose(x, y, rtol=0.0, atol=tol), (k, x, y)
        elif isinstance(x, float):
            assert (math.isnan(x) and math.isnan(y)) or abs(x - y) <= tol * max(1.0, abs(x)), (k, x, y)
        else:
            assert x == y, (k, x, y)
    return True


@needs_mj
def test_bad_states_are_refused_and_nothing_changes():
    c = _scene()
    _run(c, 0.0, 0.3)
    good = c.get_state()
    bad_states = []
    for key, value in [("mode", 3), ("closed", [1, 0]), ("impacts", -1), ("t", float("nan")),
                       ("q", [0.0, 0.0]), ("impact_times", [5.0]), ("friction_demand", -1.0), ("version", 1),
                       ("overturned", 1)]:
        s = dict(good)
        s[key] = value
        bad_states.append(s)
    s = dict(good)
    s["q"] = [0.0, -2.0, 0.0]
    bad_states.append(s)
    for s in bad_states:
        before = c.get_state()
        with pytest.raises(ValueError, match="state field"):
            c.set_state(s)
        assert c.get_state() == before


@needs_mj
def test_the_c_engine_checks_a_loaded_state_itself():
    """The C API (the FMI binary's path) refuses an inconsistent state without the Python checks."""
    c = _scene()
    _run(c, 0.0, 0.3)
    eng = c.integrator._engine
    good = eng.get_state()
    for key, value, match in [("mode", 0, "does not match 'closed'"), ("impact_times", [9.0], "after t"),
                              ("q", [0.0, -2.0, 0.0], "below the ground"),
                              ("impacts", -3, "'impacts' = -3 is out of range")]:
        s = dict(good)
        s[key] = value
        if key == "mode":
            s["closed"] = []
        if key == "impact_times":
            s["impacts"] = good["impacts"] + 1
        with pytest.raises(ValueError, match=match):
            eng.set_state(s)
        assert eng.get_state() == good


@needs_mj
def test_checkpoint_rollback_and_snapshots_restore_exactly():
    c = _scene()
    _run(c, 0.0, 0.4, ag=lambda t: 1.5)
    eng = c.integrator._engine
    s0, out0, snap = eng.get_state(), eng.outputs(), eng.snapshot()
    eng.checkpoint()
    eng.advance(1.3, 0.7)
    assert eng.get_state() != s0
    eng.rollback()
    assert eng.get_state() == s0 and eng.outputs() == out0
    eng.advance(1.3, 0.7)
    s1 = eng.get_state()
    eng.restore(snap)
    assert eng.get_state() == s0 and eng.outputs() == out0
    eng.advance(1.3, 0.7)
    assert eng.get_state() == s1
    with pytest.raises(ValueError, match="no checkpoint"):
        eng.rollback()
    other = _engine.Engine("rigid", [0.3, 1.0, 1.0, 9.81, 0.9, 0.0, math.inf], scheme="moreau_jean")
    with pytest.raises(ValueError, match="another model, parameters or options"):
        other.restore(snap)
    with pytest.raises(ValueError, match="too short|expected"):
        eng.restore(snap[:-8])


@needs_mj
def test_a_simulator_on_the_c_engine_pickles_and_continues_identically():
    c = _scene()
    _run(c, 0.0, 0.4)
    c2 = pickle.loads(pickle.dumps(c))
    _run(c, 0.4, 0.9)
    _run(c2, 0.4, 0.9)
    assert c.get_state() == c2.get_state()


@needs_mj
def test_the_impact_log_stays_bounded_over_a_long_run():
    c = _scene(impact_log_size=5)
    eng = c.integrator._engine
    ag = lambda t: 4.0 * math.sin(9.0 * t)  # noqa: E731
    _run(c, 0.0, 6.0, dt=0.5, ag=ag)
    assert eng.impacts > 10
    times = c.impact_times
    assert len(times) == 5 and times == sorted(times)
    snap = len(eng.snapshot())
    _run(c, 6.0, 12.0, dt=0.5, ag=ag)
    assert len(c.impact_times) == 5 and len(eng.snapshot()) == snap


@needs_mj
def test_nan_and_huge_inputs_never_crash():
    c = _scene()
    for ag in (float("nan"), 1e308, -float("inf")):
        with pytest.raises(ValueError):
            c.advance(1.0, ag)
    with pytest.raises(ValueError):
        c.advance(1.0, lambda t: float("nan"))
    assert c.t == 0.0
    c.advance(0.5, 1000.0)
    assert math.isfinite(c.outputs()["phi"])


@needs_mj
@pytest.mark.parametrize("hold", ["exact", "zoh"])
@pytest.mark.parametrize("scheme", ["moreau_jean", pytest.param("event_driven", marks=needs_ed)])
def test_simulate_runs_on_the_c_engine_with_the_same_layout(scheme, hold):
    gm = SinePulse(3.0, 6.0, 0.1)
    a = simulate(RigidBlock(), gm, 1.0, scheme=scheme, phi_0=0.05, hold=hold)
    b = simulate(RigidBlock(), gm, 1.0, scheme=scheme, phi_0=0.05, engine="c", hold=hold)
    assert list(a.values) == list(b.values)
    assert a.values.keys() == b.values.keys()
    for k in a.values:
        assert a.values[k].dtype == b.values[k].dtype, k
        assert np.allclose(a.values[k], b.values[k], rtol=0.0, atol=1e-12), k
    assert a.n_steps == b.n_steps


def test_compiled_integrator_is_an_integrator():
    from rocking_model.integrators.base import Integrator

    assert issubclass(CompiledIntegrator, Integrator)


# ---------------------------------------------------------------------------------------------- callbacks
@needs_mj
@pytest.mark.parametrize("scheme", ["moreau_jean", pytest.param("event_driven", marks=needs_ed)])
def test_python_motions_run_as_callbacks_with_the_same_results(scheme):
    """A pulse the engine evaluates itself (jumps included) and the same pulse as a callable (a callback into
    Python, with the pulse's breakpoints): the same motion."""
    for pulse in (RickerPulse(4.0, 8.0), CosinePulse(3.0, 8.0, 0.1), RectangularPulse(2.0, 0.3, 0.2)):
        native, cb = _scene(scheme, on_report="ignore"), _scene(scheme, on_report="ignore")
        wrapped = FunctionMotion(pulse, breakpoints=pulse.breakpoints) if hasattr(pulse, "breakpoints") else pulse
        for t in np.arange(0.1, 1.0, 0.1):
            native.advance(float(t), pulse)
            cb.advance(float(t), wrapped)
        _close_states(native.get_state(), cb.get_state(), tol=1e-11)


@needs_mj
@pytest.mark.parametrize("scheme", ["moreau_jean", pytest.param("event_driven", marks=needs_ed)])
def test_a_callback_that_fails_mid_advance_leaves_the_state_and_raises_its_error(scheme):
    def bad(t):
        if t > 0.35:
            raise ZeroDivisionError("boom")
        return 1.0

    sim = _scene(scheme)
    sim.advance(0.2, 1.0)
    before = sim.get_state()
    with pytest.raises(ValueError, match="boom"):
        sim.advance(0.6, bad)
    assert sim.get_state() == before


@needs_ed
def test_event_driven_checkpoint_snapshot_and_pickle():
    c = _scene("event_driven")
    _run(c, 0.0, 0.5, ag=lambda t: 1.0)
    eng = c.integrator._engine
    s0, snap = eng.get_state(), eng.snapshot()
    eng.checkpoint()
    eng.advance(1.5, 0.5)
    s1 = eng.get_state()
    eng.rollback()
    assert eng.get_state() == s0
    eng.advance(1.5, 0.5)
    assert eng.get_state() == s1
    eng.restore(snap)
    c2 = pickle.loads(pickle.dumps(c))
    eng.advance(1.5, 0.5)
    c2.integrator._engine.advance(1.5, 0.5)
    assert eng.get_state() == s1 == c2.integrator._engine.get_state()


@needs_mj
@pytest.mark.parametrize("scheme", ["moreau_jean", pytest.param("event_driven", marks=needs_ed)])
def test_engines_run_in_threads_without_the_gil_and_agree_with_a_sequential_run(scheme):
    """No global state: engines advanced concurrently (the GIL released inside C) give the sequential results."""
    import threading

    rec = SampledMotion(RECORD_T, RECORD_AG)
    phis = [0.02 * k for k in range(1, 5)]

    def run(phi):
        sim = Simulator(RigidBlock(b=0.25, h=1.0, e_N=0.8), scheme, engine="c", phi_0=phi, on_report="ignore")
        sim.advance(RECORD_T[-1], rec)
        return sim.get_state()

    sequential = [run(p) for p in phis]
    out = [None] * len(phis)

    def worker(i):
        out[i] = run(phis[i])
    threads = [threading.Thread(target=worker, args=(i,)) for i in range(len(phis))]
    for th in threads:
        th.start()
    for th in threads:
        th.join(60.0)
    assert out == sequential


@needs_mj
@pytest.mark.parametrize("scheme", ["moreau_jean", pytest.param("event_driven", marks=needs_ed)])
def test_the_fmu_path_first_order_hold_equals_a_linear_motion(scheme):
    """Engine.advance(t_end, ag0, slope) is LinearMotion(ag0, slope, t_ref = t) (and linear=True with slope 0,
    the FMU's zero-rate input); slope 0 without it is ConstantMotion."""
    py = _scene(scheme, on_report="ignore")
    c = _scene(scheme, on_report="ignore")
    eng = c.integrator._engine
    for k in range(1, 40):
        t0, t1 = (k - 1) * 0.02, k * 0.02
        a, rate = 3.0 * math.sin(5.0 * t0), 15.0 * math.cos(5.0 * t0)
        if k % 3 == 0:
            rate = 0.0
        py.advance(t1, LinearMotion(a, rate, t0, t0, t1) if k % 5 else ConstantMotion(a))
        eng.advance(t1, a, rate if k % 5 else 0.0, None, False, bool(k % 5))
    assert py.get_state() == c.get_state()


@needs_mj
@pytest.mark.parametrize("scheme", ["moreau_jean", pytest.param("event_driven", marks=needs_ed)])
def test_an_engine_is_freed_with_its_simulator_without_the_cyclic_collector(scheme):
    """No reference cycle holds an engine (and its impact-log ring) alive after its simulator is gone: memory
    stays flat over many short runs (ensembles) without waiting for the cyclic garbage collector."""
    import gc
    import weakref

    gc.disable()
    try:
        sim = _scene(scheme)
        sim.advance(0.3, lambda t: 0.5)
        len(sim.impact_times)
        ref = weakref.ref(sim.integrator)
        del sim
        assert ref() is None
    finally:
        gc.enable()


@needs_mj
def test_sample_times_checked_at_once():
    for bad, match in (([0.1, float("nan")], r"times = (np.float64\()?nan\)? is not finite"), ([0.2, 0.1], "increasing"),
                       ([-1.0], r"times = (np.float64\()?-1(.0\))? is out of range"), ([0.1, float("inf")], r"times = (np.float64\()?inf\)? is not finite"),
                       ([], "at least one time")):
        sim = Simulator(RigidBlock())
        with pytest.raises(ValueError, match=match):
            sim.sample(np.array(bad, dtype=float), 0.0)


def test_part_e_sources_compile_without_warnings(tmp_path):
    """rk_engine.c, rk_mj.c, rk_motion.c compile warning-free as strict C99 (setup.py's flags plus -Wall
    -Wextra -pedantic -Werror), and the extension's _engine.c with -Wall -Wextra -Werror (the Python headers
    are not pedantic C99)."""
    import os
    import shutil
    import subprocess
    import sysconfig

    cc = shutil.which("gcc") or shutil.which("cc")
    if cc is None:
        pytest.skip("no C compiler on this machine")
    here = os.path.join(os.path.dirname(__file__), "..", "rocking_model", "engine")
    flags = ["-std=c99", "-O2", "-ffp-contract=off", "-fno-fast-math", "-Wall", "-Wextra", "-Werror"]
    for name in ("rk_engine.c", "rk_mj.c", "rk_motion.c"):
        out = subprocess.run([cc, *flags, "-pedantic", "-c", os.path.join(here, "src", name), "-o",
                              str(tmp_path / "x.o")], capture_output=True, text=True, timeout=120)
        assert out.returncode == 0, out.stderr
    out = subprocess.run([cc, *flags, "-I", sysconfig.get_paths()["include"], "-I", here, "-c",
                          os.path.join(here, "_engine.c"), "-o", str(tmp_path / "y.o")],
                         capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr


@needs_mj
@pytest.mark.parametrize("t_end, ag", [
    (np.float64(0.1), np.float64(np.nan)), (np.float64(np.nan), 0.0), (np.float64(-1.0), np.float64(1.0)),
    (0.1, np.float64(2000.0)), (np.float64(0.1), np.float64(-np.inf)), (np.float64(0.1), np.float64(0.5))])
def test_numpy_numbers_take_the_same_path_and_messages(t_end, ag):
    """numpy floats go through the lean path when finite, the checked one otherwise: the same results and
    messages as Python floats (np.float64(nan) named as such)."""
    out = []
    for args in ((t_end, ag), (float(t_end), float(ag))):
        sim = Simulator(RigidBlock(), phi_0=0.05)
        try:
            sim.advance(*args)
            out.append(sim.outputs()["phi"])
        except ValueError as exc:
            out.append(str(exc).replace("np.float64(", "").replace(")", ""))
    assert out[0] == out[1]


@needs_ed
def test_raw_engine_calls_with_broken_motions_end_with_an_error_not_a_hang():
    """Found by fuzzing the Engine type: a plain callable without GroundMotion methods, a NaN factor or value,
    a callable returning NaN: each call ends (the work bounded) with a ValueError, the state unchanged."""
    params = [0.2, 1.0, 1.0, 9.81, 0.5, 0.0, math.inf]
    for scheme in (0, 1):
        eng = _engine.Engine("rigid", params, [0.05, 0.0], scheme=scheme)
        eng.advance(0.3, 0.0)
        before = eng.get_state()
        eng.advance_motion(0.4, ("callback", lambda t: -1.0, False, 0.0), 5000)   # no breakpoints: runs
        eng.restore(eng.snapshot())
        for spec in (("scaled", float("nan"), ("ricker", 1.0, 2.0, 0.0)), ("constant", float("nan")),
                     ("linear", 1.0, float("inf"), 0.0), ("callback", lambda t: float("nan"), False, 0.0)):
            eng2 = _engine.Engine("rigid", params, [0.05, 0.0], scheme=scheme)
            eng2.advance(0.3, 0.0)
            with pytest.raises(ValueError):
                eng2.advance_motion(0.5, spec, 5000)
            assert eng2.get_state() == before


# ---------------------------------------------------------------------------------------------- sample layouts
@pytest.mark.parametrize("kind,scheme", [("rigid", "event_driven"), ("rigid", "moreau_jean"),
                                         ("flexible", "event_driven"), ("flexible", "moreau_jean")])
def test_sample_in_columns_writes_the_rows_transposed_bit_for_bit(kind, scheme):
    """Engine.sample(columns=True) (what Integrator.sample asks for: one contiguous array per output, no
    transposed copy) writes the same numbers as the row layout, across impacts; the other arrays are the same."""
    model = RigidBlock(b=0.2, h=1.0) if kind == "rigid" else FlexibleOscillator()
    gm = checked_motion(SinePulse(0.4 * 9.81, 4 * math.pi))
    times = np.linspace(0.01, 2.0, 200)
    arrays = []
    for columns in (False, True):
        sim = Simulator(model, scheme, engine="c", tolerance=1e-8)
        eng = sim.integrator._engine
        n, k = times.size + 1, len(eng.output_names) + 2
        modes, impacts, over = np.empty(n, np.intc), np.empty(n, np.int64), np.empty(n, np.intc)
        values = np.full((k, n) if columns else (n, k), np.nan)
        eng.sample(times, motion_spec(gm), None, modes, values, impacts, over, 0, None, columns)
        arrays.append((modes, values.T if columns else values, impacts, over, eng.get_state()))
    (m0, v0, i0, o0, s0), (m1, v1, i1, o1, s1) = arrays
    assert np.any(i0 > 0)                                  # the rows cover impacts
    assert np.array_equal(v0, v1) and not np.isnan(v1).any()
    assert np.array_equal(m0, m1) and np.array_equal(i0, i1) and np.array_equal(o0, o1)
    assert s0 == s1


def test_the_engine_reads_each_tolerances_object_it_is_given():
    """The engine keeps the fields of the last frozen ContactTolerances it read (every run reads the same default
    object): another object is read afresh (its results are not the default's), the default
    again gives the default's results, and a mutable object with the same attributes is read every time."""
    import dataclasses
    import types

    from rocking_model.tolerances import DEFAULT_TOLERANCES

    model, gm = RigidBlock(b=0.2, h=1.0), SinePulse(0.4 * 9.81, 4 * math.pi)
    base = simulate(model, gm, 4.0, engine="c", tolerance=1e-8).phi
    coarse = dataclasses.replace(DEFAULT_TOLERANCES, event=1e-4)   # events located less tightly: phi moves ~1e-9
    c = simulate(model, gm, 4.0, engine="c", tolerance=1e-8, tolerances=coarse).phi
    assert not np.array_equal(c, base)
    assert np.array_equal(simulate(model, gm, 4.0, engine="c", tolerance=1e-8).phi, base)

    sim = Simulator(model, "event_driven", engine="c")
    integ = sim.integrator
    args, kwargs = integ._engine_args(), integ._engine_kwargs()
    kwargs["tolerances"] = ns = types.SimpleNamespace(**dataclasses.asdict(DEFAULT_TOLERANCES))
    _engine.Engine(*args, state=integ._start, **kwargs)
    ns.gap = "not a number"
    with pytest.raises(TypeError):
        _engine.Engine(*args, state=integ._start, **kwargs)


def test_record_runs_on_the_sampled_path_bit_for_bit():
    """A records.Record (a SampledMotion with a name and a vertical component) is evaluated by the engine itself,
    as its plain SampledMotion, not through a Python callback, with the same results."""
    from rocking_model.engine import motion_spec
    from rocking_model.ground_motion import SampledMotion
    from rocking_model.models import RigidBlock
    from rocking_model.records import Record, synthetic_record
    from rocking_model.simulation import simulate

    t, a = synthetic_record(duration=4.0, pga_g=0.5, seed=3)
    rec = Record(t, a, "r", vertical=0.3 * a)
    assert motion_spec(rec.horizontal)[0] == "sampled"
    assert motion_spec(rec.vertical)[0] == "sampled"
    m = RigidBlock(b=0.15, h=1.0)
    r1, r2 = simulate(m, rec.horizontal, 6.0), simulate(m, SampledMotion(t, a), 6.0)
    assert np.array_equal(r1.phi, r2.phi) and r1.impacts[-1] == r2.impacts[-1]
