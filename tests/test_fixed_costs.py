"""The fixed costs of a compiled run (a short scene's `simulate` is dominated by what surrounds the C
call): what `Simulator(engine="c")` and `simulate` no longer build, and that the results, settings and messages
are the same as when they did. Not timed (benchmarks/ measures the times)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from rocking_model import FlexibleOscillator, RigidBlock, Simulator, SinePulse, simulate

@pytest.mark.parametrize("scheme", ["event_driven", "moreau_jean"])
def test_settings_read_from_the_checked_options(scheme):
    model = FlexibleOscillator()
    kw = dict(dt_max=2e-3, tolerance=1e-6, theta=0.6, zeno_tol=1e-5)
    c = Simulator(model, scheme, **kw).integrator
    if scheme == "event_driven":
        assert (c.dt_max, c.tolerance, c.method) == (2e-3, 1e-6, "DOP853")
        assert Simulator(model, scheme, method="DOPRI5").integrator.method == "DOPRI5"
        assert Simulator(model, scheme).integrator.dt_max == math.inf
    else:
        assert (c.dt_max, c.theta) == (min(2e-3, model.step_limit), 0.6)
        assert Simulator(model, scheme).integrator.dt_max == min(1e-3, model.step_limit)
    with pytest.raises(AttributeError, match="no attribute 'no_such_setting'"):
        c.no_such_setting  # noqa: B018


@pytest.mark.parametrize("scheme, kw, message", [
    ("event_driven", dict(tolerance=1.0), "tolerance = 1 is out of range"),
    ("event_driven", dict(tolerance="a"), "tolerance must be a real number"),
    ("event_driven", dict(zeno_tol=0.0), "zeno_tol = 0 is out of range"),
    ("event_driven", dict(method="RK4"), "method = 'RK4' is not supported"),
    ("moreau_jean", dict(theta=0.2), "theta = 0.2 is out of range"),
])
def test_option_errors_name_the_option(scheme, kw, message):
    with pytest.raises(ValueError, match=message):
        Simulator(RigidBlock(), scheme, **kw)


def test_rigid_block_mass_matrices_from_the_kernel():
    """The mass matrix and its inverse come from the kernel generated from the declaration (M = d2T/dv2)."""
    block = RigidBlock(b=0.3, h=1.2, m=2.5)
    M = np.diag([block.m, block.m, block.I_c])
    assert np.allclose(block.mass_matrix(np.zeros(3)), M, rtol=1e-15, atol=0)
    assert np.allclose(block.inverse_mass_matrix(np.zeros(3)), np.diag(1.0 / np.diag(M)), rtol=1e-15, atol=0)


@pytest.mark.parametrize("t_end, dt", [(0.7, 0.01), (0.705, 0.01), (0.3, 0.3), (0.0, 0.01)])
def test_simulate_grid_run_as_simulator_sample(t_end, dt):
    """simulate on the compiled engine samples its own grid without re-checking it: the same outputs as the
    checked Simulator.sample over the same times."""
    model, gm = RigidBlock(), SinePulse(4.0, 2 * math.pi)
    res = simulate(model, gm, t_end, output_interval=dt, phi_0=0.02)
    sim = Simulator(model, impact_log_size=None, phi_0=0.02)
    modes, values, impacts, overturned = sim.sample(res.t[1:], gm)
    assert np.array_equal(res.contact, modes) and np.array_equal(res.impacts, impacts)
    assert np.array_equal(res.overturned, overturned)
    for name, v in values.items():
        assert np.array_equal(res[name], v), name
        assert res[name].flags.c_contiguous and res[name].dtype == v.dtype
    assert np.array_equal(res.impact_times, np.array(sim.impact_times))


def test_solver_options_of_equals_the_constructor():
    from rocking_model.integrators.base import SolverOptions
    from rocking_model.tolerances import DEFAULT_TOLERANCES

    args = (2e-3, 1e-6, 0.6, 1e-5, "DOPRI5", None, DEFAULT_TOLERANCES)
    fast, slow = SolverOptions.of(*args), SolverOptions(*args)
    assert fast == slow and hash(fast) == hash(slow) and repr(fast) == repr(slow)
    with pytest.raises(AttributeError):           # still frozen
        fast.theta = 0.7


@pytest.mark.parametrize("value", [0.2, 1e-6, 1e3, 1, 0.0, -0.0, 1e-7, 1e3 + 1e-9, math.inf, -math.inf, math.nan,
                                   True, np.float64(0.3), "0.2", None, 2, 0, 1.0, -1])
def test_declared_parameters_accepted_as_is_exactly_when_check_returns_them(value):
    """Param.accepts_as_is (the fast path of check_parameters and Param.check) holds only for values that the
    checks return unchanged, of the same type: every declared parameter of both models, many kinds of values."""
    from rocking_model.params import declared_parameters

    for cls in (RigidBlock, FlexibleOscillator):
        for p in declared_parameters(cls):
            if not p.accepts_as_is(value):
                continue
            p_checks = object.__new__(type(p))
            object.__setattr__(p_checks, "__dict__", {**p.__dict__, "accepts_as_is": lambda x: False})
            checked = p_checks.check(value)
            assert checked == value and type(checked) is type(value), (cls.__name__, p.name, value)


def test_bad_parameters_still_named_after_the_fast_path():
    for kw, name in (({"b": 0.0}, "b"), ({"h": math.nan}, "h"), ({"mu": -1.0}, "mu"), ({"impact_law": 3}, "impact_law"),
                     ({"e_N": 1.5}, "e_N"), ({"m": math.inf}, "m")):
        with pytest.raises(ValueError, match=name):
            RigidBlock(**kw)
    assert RigidBlock(impact_law=1.0).impact_law == 1 and type(RigidBlock(impact_law=1.0).impact_law) is int
    assert RigidBlock(b=1).b == 1.0 and type(RigidBlock(b=1).b) is float


def test_sample_writes_the_dtypes_integrator_sample_returns():
    """Engine.sample writes int64 modes and bool overturned itself (no converted copies), and still takes the
    int32 arrays of its older callers: the same values either way."""
    from rocking_model.engine import motion_spec

    gm = SinePulse(4.0, 2 * math.pi)
    times = np.arange(1, 101) * 0.01
    outs = []
    for mode_t, over_t in ((np.int64, bool), (np.intc, np.intc)):
        sim = Simulator(RigidBlock(), phi_0=0.02)
        eng = sim.integrator._engine
        n = times.size + 1
        modes, values = np.empty(n, mode_t), np.empty((eng.n_outputs + 2, n))
        impacts, over = np.empty(n, np.int64), np.empty(n, over_t)
        eng.sample(times, motion_spec(gm), None, modes, values, impacts, over, 0, None, True)
        outs.append((modes.astype(np.int64), values, impacts, over.astype(bool)))
    for a, b in zip(*outs):
        assert np.array_equal(a, b)
    sim = Simulator(RigidBlock(), phi_0=0.02)
    modes, values, impacts, over = sim.sample(times, gm)
    assert modes.dtype == np.int64 and over.dtype == bool and values["painleve"].dtype == np.int64
    with pytest.raises(ValueError, match="modes"):
        sim.integrator._engine.sample(times, motion_spec(gm), None, np.empty(n, np.int16), values, impacts, over, 0,
                                      None, True)
