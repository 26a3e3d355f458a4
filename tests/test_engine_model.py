"""The C model kernels (issue 21, part A) pinned to the Python models on random parameters and states.

The Python models are the reference (rocking_model/engine/DESIGN.md, "Numerics"): closed forms agree bit for
bit (same libm calls, same operation order), numpy linear algebra (solve, lstsq, inv, products) to
``LA_RTOL``. Random inputs come from hypothesis, derandomized (the same examples on every run and machine)."""
from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rocking_model import _engine
from rocking_model.ground_motion import ConstantMotion
from rocking_model.models import FlexibleOscillator, RigidBlock
from rocking_model.models import sliding
from rocking_model.models.base import RockingModel
from rocking_model.modes import CLOSED, SLIDING, Mode
from rocking_model.tolerances import DEFAULT_TOLERANCES

#: [1] relative agreement of numpy's BLAS/LAPACK results (products, solve, lstsq, inv) with the C loops and
#: small solves (DESIGN.md section 7: the operation orders differ, the results by a few ulp times the
#: condition number)
LA_RTOL = 1e-13

SETTINGS = settings(derandomize=True, max_examples=150, deadline=None,
                    suppress_health_check=[HealthCheck.too_slow])

call = _engine.model_call
STICK = (Mode.FULL, Mode.LEFT, Mode.RIGHT, Mode.FLIGHT)
ALL_MODES = tuple(Mode)


def log_uniform(lo, hi):
    return st.floats(math.log10(lo), math.log10(hi)).map(lambda e: 10.0 ** e)


def rigid_params():
    return st.builds(
        lambda b, h, m, g, e_N, law, mu: dict(b=b, h=h, m=m, g=g, e_N=e_N, impact_law=law, mu=mu),
        log_uniform(1e-3, 1e2), log_uniform(1e-3, 1e2), log_uniform(1e-3, 1e9), log_uniform(1.0, 100.0),
        st.floats(0.0, 1.0), st.sampled_from([0, 1]), st.one_of(st.just(math.inf), log_uniform(1e-3, 1e3)))


def values_of(model) -> list:
    """The model's parameters in declared order, as floats (what the C API takes)."""
    return [float(getattr(model, p.name)) for p in type(model).parameters()]


def same(c, p):
    """Bitwise equality of two flat sequences (also -0.0 and 0.0 are told apart only where numpy would)."""
    c, p = np.asarray(c, dtype=float).ravel(), np.asarray(p, dtype=float).ravel()
    assert c.shape == p.shape, (c, p)
    assert np.array_equal(c, p, equal_nan=True), (c.tolist(), p.tolist(), (c - p).tolist())


def close(c, p, rtol=LA_RTOL, scale=0.0):
    """Agreement to rtol relative to the larger of each entry, the vector's largest entry and ``scale``, the
    natural magnitude of the quantity (numpy leaves round-off noise where the exact value is 0)."""
    c, p = np.asarray(c, dtype=float).ravel(), np.asarray(p, dtype=float).ravel()
    assert c.shape == p.shape, (c, p)
    scale = max(float(np.max(np.abs(p))) if p.size else 0.0, scale, 1e-300)
    assert np.all(np.abs(c - p) <= rtol * np.maximum(np.abs(p), scale)), (c.tolist(), p.tolist())


def slide_cond(model, mode, q) -> float:
    """Condition number of the Delassus matrix of sliding.slide_motion at q (the C and numpy solves agree to
    LA_RTOL times it)."""
    stick, sigma = SLIDING[mode]
    closed = list(model.closed_of(stick))
    W_N, W_T = model.contact_jacobians(np.asarray(q, dtype=float))
    inv_mu = 0.0 if math.isinf(model.mu) else 1.0 / model.mu
    Minv = model.inverse_mass_matrix(np.asarray(q, dtype=float))
    A = W_N[:, closed].T @ Minv @ (inv_mu * W_N[:, closed] - sigma * W_T[:, closed])
    return max(1.0, float(np.linalg.cond(A)))


def out_list(model, d) -> list:
    return [float(d[p.name]) for p in model.OUTPUTS]


# ------------------------------------------------------------------------------------------ states
def rigid_state(model, mode, phi, w, x, dx, dy, lift):
    """A reduced state y of ``mode`` (the corners not below the ground) and the full (q, v) it embeds."""
    if mode == Mode.FULL:
        y = []
    elif mode in (Mode.LEFT, Mode.RIGHT):
        phi = abs(phi) if mode == Mode.LEFT else -abs(phi)
        y = [phi, w]
    elif mode == Mode.FLIGHT:
        yc = model.h * math.cos(phi) + model.b * abs(math.sin(phi)) + lift * model.R
        y = [x, yc, phi, dx, dy, w]
    else:
        stick, _ = SLIDING[mode]
        base = rigid_state(model, stick, phi, w, x, dx, dy, lift)
        k = len(base) // 2
        y = base[:k] + [x] + base[k:] + [dx]
    return y


STATE = st.tuples(st.floats(-1.5, 1.5), st.floats(-20.0, 20.0), st.floats(-2.0, 2.0), st.floats(-5.0, 5.0),
                  st.floats(-5.0, 5.0), st.floats(0.0, 1.0))
AG = st.floats(-1000.0, 1000.0)


# ------------------------------------------------------------------------------------------ helpers
def test_float_repr_is_python_repr():
    rng = np.random.default_rng(5)
    xs = [0.0, -0.0, 1.0, 2.0, 0.1, 1e-6, 1e-5, 1e-4, 1e-3, 1e16, 1e15, 123456789012345678.0, 1.5e300, 5e-324,
          math.inf, -math.inf, math.nan, 1e22, 0.3, 2.5, -7.25e-12]
    xs += list(rng.standard_normal(200) * 10.0 ** rng.integers(-30, 30, 200))
    for x in xs:
        assert _engine.model_float_repr(float(x)) == repr(float(x))


def test_hypot_is_math_hypot():
    rng = np.random.default_rng(7)
    a = 10.0 ** rng.uniform(-8, 4, 20000)
    b = 10.0 ** rng.uniform(-8, 4, 20000)
    for x, y in zip(a.tolist(), b.tolist()):
        assert _engine.model_hypot(x, y) == math.hypot(x, y)
    assert _engine.model_hypot(0.0, 0.0) == 0.0
    assert _engine.model_hypot(math.inf, math.nan) == math.inf


def test_small_solves_match_numpy():
    rng = np.random.default_rng(11)
    for n in range(1, 9):
        for _ in range(20):
            A = rng.standard_normal((n, n)) + n * np.eye(n)
            b = rng.standard_normal(n)
            close(_engine.model_la("solve", n, n, A.ravel().tolist(), b.tolist(), 0.0), np.linalg.solve(A, b))
    assert _engine.model_la("solve", 2, 2, [1.0, 2.0, 2.0, 4.0], [1.0, 1.0], 0.0) is None
    for rows, cols in ((3, 1), (3, 2), (4, 2), (4, 3), (2, 2), (6, 4)):
        for _ in range(20):
            A = rng.standard_normal((rows, cols))
            b = rng.standard_normal(rows)
            close(_engine.model_la("lstsq", rows, cols, A.ravel().tolist(), b.tolist(), -1.0),
                  np.linalg.lstsq(A, b, rcond=None)[0], rtol=1e-12)
    # rank deficient: the minimum-norm solution with numpy's rcond
    A = np.array([[1.0, 2.0], [2.0, 4.0]])
    b = np.array([1.0, 3.0])
    close(_engine.model_la("lstsq", 2, 2, A.ravel().tolist(), b.tolist(), 1e-12),
          np.linalg.lstsq(A, b, rcond=1e-12)[0], rtol=1e-12)


# ------------------------------------------------------------------------------------------ rigid block
def test_registry_declares_the_rigid_block():
    kinds = {k["kind"]: k for k in _engine.model_kinds()}
    k = kinds["rigid"]
    assert k["class_name"] == "RigidBlock"
    model = RigidBlock()
    assert (k["n_dof"], k["n_contacts"], k["n_modes"]) == (model.n_dof, model.n_contacts, model.n_modes)
    assert (k["phi_index"], k["slide_index"], k["lift_index"]) == (model.phi_index, model.slide_index,
                                                                    model.lift_index)
    assert [p[0] for p in k["params"]] == [p.name for p in RigidBlock.parameters()]
    assert [p[2] for p in k["params"]] == [float(p.default) for p in RigidBlock.parameters()]
    assert [p[0] for p in k["initial"]] == [p.name for p in RigidBlock.INITIAL]
    assert [p[0] for p in k["outputs"]] == [p.name for p in RigidBlock.OUTPUTS]
    names = [p.name for p in RigidBlock.OUTPUTS]
    assert [names[i] for i in k["shifted"]] == list(RigidBlock.SHIFTED_OUTPUTS)


@SETTINGS
@given(rigid_params())
def test_rigid_derived_constants(kw):
    model = RigidBlock(**kw)
    c = call("rigid", values_of(model), "derived")
    same(c["p"], values_of(model))
    for name in ("e_N", "e_T", "mu", "g", "length_scale", "time_scale", "force_scale", "step_limit"):
        assert c[name] == getattr(model, name), name
    assert c["impact_law"] == model.impact_law
    same(c["dof_scales"], model.dof_scales)
    same(c["rest_abscissae"], model._rest_abscissae)
    same(call("rigid", values_of(model), "d")[:4], [model._R, model._alpha, model._I_c, model._p])
    tol = DEFAULT_TOLERANCES.for_model(model)
    ct = call("rigid", values_of(model), "scale_tolerances")
    for name, value in ct.items():
        assert value == getattr(tol, name), name


@SETTINGS
@given(rigid_params(), STATE, AG)
def test_rigid_full_coordinate_functions(kw, state, ag):
    model = RigidBlock(**kw)
    p = values_of(model)
    phi, w, x, dx, dy, lift = state
    q = [x, model.h * math.cos(phi) + model.b * abs(math.sin(phi)) + lift * model.R, phi]
    v = [dx, dy, w]
    same(call("rigid", p, "mass_matrix", a=q), model.mass_matrix(np.array(q)))
    same(call("rigid", p, "inverse_mass", a=q), model.inverse_mass_matrix(np.array(q)))
    close(call("rigid", p, "generic_inverse_mass", a=q), np.linalg.inv(model.mass_matrix(np.array(q))))
    same(call("rigid", p, "forces", a=q, b=v, ag=ag), model.forces(np.array(q), np.array(v), ag))
    assert call("rigid", p, "stiff_jacobians", a=q, b=v) is None
    same(call("rigid", p, "gaps", a=q), model.gaps(np.array(q)))
    W_N, W_T = call("rigid", p, "contact_jacobians", a=q)
    pw = model.contact_jacobians(np.array(q))
    same(W_N, pw[0])
    same(W_T, pw[1])
    a_N, a_T = call("rigid", p, "contact_drift", a=q, b=v)
    pd = model.contact_drift(np.array(q), np.array(v))
    same(a_N, pd[0])
    same(a_T, pd[1])
    same(call("rigid", p, "contact_abscissae", a=q), model.contact_abscissae(np.array(q)))
    assert call("rigid", p, "slip", a=q) == model.slip(np.array(q))
    assert call("rigid", p, "energy", a=q, b=v) == model.energy(np.array(q), np.array(v))
    assert call("rigid", p, "energy", a=q, b=v) == model.energy(q, v)
    same(call("rigid", p, "outputs", a=q, b=v), out_list(model, model.outputs(q, v)))
    same(call("rigid", p, "rest_position"), model.rest_position())
    assert call("rigid", p, "classical_impact_velocity", a=q, b=v, mode=1) is None
    assert call("rigid", p, "work_note") == model.work_note


@SETTINGS
@given(rigid_params(), STATE, AG)
def test_rigid_monitor_one_is_the_monitors_value(kw, state, ag):
    """rk_mode_monitor_one (the event location's single-function evaluation, issue 21): in the rocking modes the
    open corner's gap and the overturning margin alone, without ag and the pivot's force; each value it gives is
    the one rk_mode_monitors writes, bit for bit (with the friction cone when mu is finite); the rest is left to
    rk_mode_monitors (None)."""
    model = RigidBlock(**kw)
    p = values_of(model)
    for mode in STICK:
        y = rigid_state(model, mode, *state)
        g = call("rigid", p, "monitors_only", mode=mode, a=y, ag=ag)
        one = call("rigid", p, "monitor_one", mode=mode, a=y, ag=ag)
        assert len(one) == len(g)
        for gi, oi in zip(g, one):
            if oi is not None:
                same([oi], [gi])
        if mode in (Mode.LEFT, Mode.RIGHT):
            gap = 1 if mode == Mode.LEFT else 0     # the open corner: the right one rocking on the left pivot
            assert one[gap] is not None and one[-1] is not None
            assert one[1 - gap] is None             # the pivot's normal force needs ag and the trigonometry
        else:
            assert all(oi is None for oi in one)


@SETTINGS
@given(rigid_params(), STATE, AG)
def test_rigid_sticking_modes_bitwise(kw, state, ag):
    """FULL, LEFT, RIGHT, FLIGHT: embed, mode_jacobian, the closures' rhs, monitors and totals, mode_outputs,
    contact_forces: the C closed forms equal the Python's bit for bit."""
    model = RigidBlock(**kw)
    p = values_of(model)
    motion = ConstantMotion(ag)
    for mode in STICK:
        y = rigid_state(model, mode, *state)
        k = len(y) // 2
        r, rd = y[:k], y[k:]
        assert call("rigid", p, "mode_dofs", mode=mode) == list(model.mode_dofs(mode))
        q, v = call("rigid", p, "embed", mode=mode, a=r, b=rd)
        pq, pv = model.embed(mode, np.array(r), np.array(rd))
        same(q, pq)
        same(v, pv)
        J, jd = call("rigid", p, "mode_jacobian", mode=mode, a=r, b=rd)
        pJ, pjd = model.mode_jacobian(mode, np.array(r), np.array(rd))
        same(J, pJ)
        same(jd, pjd)
        rhs, monitors, totals = model.mode_closures(mode, motion)
        same(call("rigid", p, "kernel_rhs", mode=mode, a=y, ag=ag), rhs(0.0, list(y)))
        g, tot = call("rigid", p, "kernel_monitors", mode=mode, a=y, ag=ag)
        same(g, monitors(0.0, list(y)))
        if totals is None:
            assert tot is None
        else:
            same(tot, totals(0.0, list(y)))
        same(call("rigid", p, "mode_outputs", mode=mode, a=y), out_list(model, model.mode_outputs(mode, list(y))))
        same(call("rigid", p, "contact_forces", mode=mode, a=pq.tolist(), b=pv.tolist(), ag=ag),
             model.contact_forces(mode, pq, pv, ag))
        # any-mode dispatch: functions_of (with the friction cone when mu is finite)
        frhs, fmon, ftot = model.functions_of(mode, motion)
        same(call("rigid", p, "rhs", mode=mode, a=y, ag=ag), frhs(0.0, list(y)))
        g, tot = call("rigid", p, "monitors", mode=mode, a=y, ag=ag)
        same(g, fmon(0.0, list(y)))
        same(call("rigid", p, "monitors_only", mode=mode, a=y, ag=ag), g)
        if ftot is None:
            assert tot is None
        else:
            same(tot, ftot(0.0, list(y)))
        assert call("rigid", p, "dofs_of", mode=mode) == list(model.dofs_of(mode))
        q2, v2 = call("rigid", p, "embed_any", mode=mode, a=y)
        same(q2, pq)
        same(v2, pv)
        same(call("rigid", p, "reduce_any", mode=mode, a=q, b=v), np.concatenate(model.reduce_any(mode, pq, pv)))
        for shift in (0.0, state[2]):
            same(call("rigid", p, "outputs_of", mode=mode, a=y, ag=shift),
                 out_list(model, model.outputs_of(mode, list(y), shift)))
        if mode != Mode.FLIGHT:
            assert call("rigid", p, "shift_of", mode=mode, a=(pq + [state[2], 0, 0]).tolist()) == \
                sliding.shift_of(model, mode, pq + [state[2], 0, 0])


@SETTINGS
@given(rigid_params(), STATE, AG)
def test_rigid_overturned_outputs(kw, state, ag):
    """Once overturned, the drivers report the pose reached at |phi| = pi/2 at rest: the event-driven scheme
    zeroes the reduced velocities and calls outputs_of, Moreau-Jean calls outputs(q, 0). Both are kernel
    functions pinned here at that pose (energy: the potential energy of the pose)."""
    model = RigidBlock(**kw)
    p = values_of(model)
    for mode, phi in ((Mode.LEFT, 0.5 * math.pi), (Mode.RIGHT, -0.5 * math.pi)):
        y = [phi, 0.0]
        same(call("rigid", p, "outputs_of", mode=mode, a=y, ag=state[2]),
             out_list(model, model.outputs_of(mode, y, state[2])))
        q, _ = model.embed(mode, np.array([phi]), np.array([0.0]))
        same(call("rigid", p, "outputs", a=q.tolist(), b=[0.0, 0.0, 0.0]),
             out_list(model, model.outputs(q, np.zeros(3))))
    for mode, phi in ((Mode.LEFT_SLIDE_POS, 0.5 * math.pi), (Mode.RIGHT_SLIDE_NEG, -0.5 * math.pi)):
        y = [phi, state[2], 0.0, 0.0]           # a sliding mode's pose: the base offset kept, at rest
        same(call("rigid", p, "outputs_of", mode=mode, a=y, ag=0.0), out_list(model, model.outputs_of(mode, y)))


@SETTINGS
@given(rigid_params(), STATE, AG)
def test_rigid_generic_fallbacks(kw, state, ag):
    """The generic rhs and monitors (a third model with only the required functions gets them) equal
    RockingModel's numpy defaults on the rigid block; the force totals equal sliding.force_totals."""
    model = RigidBlock(**kw)
    p = values_of(model)
    motion = ConstantMotion(ag)
    for mode in (Mode.LEFT, Mode.RIGHT, Mode.FLIGHT, Mode.FULL):
        y = rigid_state(model, mode, *state)
        k = len(y) // 2
        if k:
            pr = RockingModel.reduced_acceleration(model, mode, np.array(y[:k]), np.array(y[k:]), ag)
            close(call("rigid", p, "generic_rhs", mode=mode, a=y, ag=ag), list(y[k:]) + pr.tolist())
        g, tot = call("rigid", p, "generic_monitors", mode=mode, a=y, ag=ag)
        _, pmon = RockingModel.mode_functions(model, mode, motion)
        close(g, pmon(0.0, list(y)))
        q, v = model.embed(mode, np.array(y[:k]), np.array(y[k:]))
        if CLOSED[mode]:
            pt = sliding.force_totals(model, mode, q, v, ag)
            close(tot, pt)
            close(call("rigid", p, "force_totals", mode=mode, a=q.tolist(), b=v.tolist(), ag=ag), pt)


@SETTINGS
@given(rigid_params(), STATE, AG)
def test_rigid_sliding_modes(kw, state, ag):
    model = RigidBlock(**kw)
    p = values_of(model)
    motion = ConstantMotion(ag)
    acc = model.g + abs(ag) + model.R * state[1] ** 2        # [m/s2] the scale of the accelerations
    for mode in SLIDING:
        y = rigid_state(model, mode, *state)
        k = len(y) // 2
        assert call("rigid", p, "dofs_of", mode=mode) == list(model.dofs_of(mode))
        q, v = call("rigid", p, "embed_any", mode=mode, a=y)
        pq, pv = model.embed_any(mode, y[:k], y[k:])
        same(q, pq)
        same(v, pv)
        same(call("rigid", p, "reduce_any", mode=mode, a=q, b=v), np.concatenate(model.reduce_any(mode, pq, pv)))
        J, jd = call("rigid", p, "slide_jacobian", mode=mode, a=y[:k], b=y[k:])
        pJ, pjd = sliding.slide_jacobian(model, mode, y[:k], y[k:])
        same(J, pJ)
        same(jd, pjd)
        a, tau = call("rigid", p, "slide_motion", mode=mode, a=q, b=v, ag=ag)
        pa, ptau = sliding.slide_motion(model, mode, pq, pv, ag)
        if slide_singular(model, mode, pq):
            continue        # a singular sliding problem (mu = inf at phi ~ 0): numpy's solve returns noise
        rtol = LA_RTOL * slide_cond(model, mode, pq)
        close(a, pa, rtol, scale=acc)
        close(tau, ptau, rtol, scale=model.m * acc)
        close(call("rigid", p, "slide_acceleration", mode=mode, a=y[:k], b=y[k:], ag=ag),
              sliding.slide_acceleration(model, mode, np.array(y[:k]), np.array(y[k:]), ag), rtol, scale=acc)
        frhs, fmon, ftot = model.functions_of(mode, motion)
        close(call("rigid", p, "rhs", mode=mode, a=y, ag=ag), frhs(0.0, list(y)), rtol, scale=acc)
        g, tot = call("rigid", p, "monitors", mode=mode, a=y, ag=ag)
        close(g, fmon(0.0, list(y)), rtol, scale=acc / model.g)
        close(tot, ftot(0.0, list(y)), rtol, scale=model.m * acc)
        same(call("rigid", p, "outputs_of", mode=mode, a=y, ag=1.0), out_list(model, model.outputs_of(mode, y, 1.0)))


def test_rigid_modes_of_closed_sets():
    p = values_of(RigidBlock())
    model = RigidBlock()
    for mode in ALL_MODES:
        assert call("rigid", p, "closed_of", mode=mode) == list(model.closed_of(mode))
        stick, sigma = SLIDING.get(mode, (mode, 0))
        assert call("rigid", p, "stick_of", mode=mode) == (int(stick), sigma)
    for closed in ((), (0,), (1,), (0, 1)):
        for sigma in (-1, 0, 1):
            assert call("rigid", p, "mode_of", mode=sigma + 1, a=list(closed)) == model.mode_of(closed, sigma)


@SETTINGS
@given(rigid_params(), st.floats(-1.57, 1.57), st.floats(-1e4, 1e4), st.sampled_from([0.0, 1.0]))
def test_rigid_initial_state(kw, phi_0, phi_dot_0, zero):
    model = RigidBlock(**kw)
    phi_0 *= zero if phi_dot_0 > 5e3 else 1.0      # phi_0 = 0 with a rate: the mode follows the rate
    mode, q, v = call("rigid", values_of(model), "initial_state", a=[phi_0, phi_dot_0])
    pm, pq, pv = model.initial_state(phi_0=phi_0, phi_dot_0=phi_dot_0)
    assert mode == pm
    same(q, pq)
    same(v, pv)


BAD_VALUES = (0.0, -1.0, 1e-7, 2e3, 2e12, 1.5, math.nan, math.inf, -math.inf, 1e-4, 2.0, 0.5, -0.0)


@pytest.mark.parametrize("name", [p.name for p in RigidBlock.parameters()])
@pytest.mark.parametrize("bad", BAD_VALUES)
def test_rigid_parameter_checks_give_the_python_messages(name, bad):
    defaults = values_of(RigidBlock())
    names = [p.name for p in RigidBlock.parameters()]
    params = list(defaults)
    params[names.index(name)] = bad
    try:
        RigidBlock(**dict(zip(names, params)))
    except ValueError as exc:
        with pytest.raises(ValueError) as info:
            call("rigid", params, "derived")
        assert str(info.value) == str(exc)
    else:
        c = call("rigid", params, "derived")
        same(c["p"], values_of(RigidBlock(**dict(zip(names, params)))))


@pytest.mark.parametrize("initial", [(2.0, 0.0), (-1.5707963267948966, 0.0), (0.1, 2e4), (math.nan, 0.0),
                                     (0.0, math.inf), (0.1, -1e4)])
def test_rigid_initial_value_checks_give_the_python_messages(initial):
    model = RigidBlock()
    try:
        model.initial_state(phi_0=initial[0], phi_dot_0=initial[1])
    except ValueError as exc:
        with pytest.raises(ValueError) as info:
            call("rigid", values_of(model), "initial_state", a=list(initial))
        assert str(info.value) == str(exc)
    else:
        call("rigid", values_of(model), "initial_state", a=list(initial))


# ------------------------------------------------------------------------------------------ flexible oscillator
def flexible_params():
    def build(m, m_c, m_b, rho, h, b, omega, zeta, e_N, law, mu, rule, g):
        m_tilde = m + 33.0 / 140.0 * m_c
        EI = min(omega ** 2 * m_tilde * h ** 3 / 3.0, 1e15)
        return dict(m=m, m_c=m_c, m_b=m_b, rho=rho, h=h, b=b, EI=EI, zeta=zeta, e_N=e_N, impact_law=law, mu=mu,
                    impact_rule=rule, g=g)
    return st.builds(
        build, log_uniform(1e-2, 1e6), st.one_of(st.just(0.0), log_uniform(1e-2, 1e5)), log_uniform(1e-2, 1e5),
        log_uniform(1e-3, 10.0), log_uniform(1e-2, 1e2), log_uniform(1e-2, 1e2), log_uniform(1.0, 5e3),
        st.floats(0.0, 1.0), st.floats(0.0, 1.0), st.sampled_from([0, 1]),
        st.one_of(st.just(math.inf), log_uniform(1e-3, 1e3)), st.sampled_from([0, 1]), log_uniform(1.0, 100.0))


def flexible_state(model, mode, u, phi, ud, w, x, dx, dy, lift):
    """A reduced state y of ``mode`` of the flexible oscillator (corners not below the ground)."""
    u = u * model.h
    if mode == Mode.FULL:
        return [u, ud]
    if mode in (Mode.LEFT, Mode.RIGHT):
        phi = abs(phi) if mode == Mode.LEFT else -abs(phi)
        return [u, phi, ud, w]
    if mode == Mode.FLIGHT:
        yc = model.b * abs(math.sin(phi)) + lift * model.length_scale
        return [u, x, yc, phi, ud, dx, dy, w]
    stick, _ = SLIDING[mode]
    base = flexible_state(model, stick, u / model.h, phi, ud, w, x, dx, dy, lift)
    k = len(base) // 2
    return base[:k] + [x] + base[k:] + [dx]


FSTATE = st.tuples(st.floats(-0.5, 0.5), st.floats(-1.5, 1.5), st.floats(-5.0, 5.0), st.floats(-20.0, 20.0),
                   st.floats(-2.0, 2.0), st.floats(-5.0, 5.0), st.floats(-5.0, 5.0), st.floats(0.0, 1.0))
FLEX = FlexibleOscillator


def test_registry_declares_the_flexible_oscillator():
    k = {k["kind"]: k for k in _engine.model_kinds()}["flexible"]
    model = FLEX()
    assert k["class_name"] == "FlexibleOscillator"
    assert (k["n_dof"], k["n_contacts"], k["n_modes"]) == (model.n_dof, model.n_contacts, model.n_modes)
    assert (k["phi_index"], k["slide_index"], k["lift_index"]) == (model.phi_index, model.slide_index,
                                                                    model.lift_index)
    assert [p[0] for p in k["params"]] == [p.name for p in FLEX.parameters()]
    assert [p[2] for p in k["params"]] == [float(p.default) for p in FLEX.parameters()]
    assert [p[0] for p in k["initial"]] == [p.name for p in FLEX.INITIAL]
    assert [p[0] for p in k["outputs"]] == [p.name for p in FLEX.OUTPUTS]
    names = [p.name for p in FLEX.OUTPUTS]
    assert [names[i] for i in k["shifted"]] == list(FLEX.SHIFTED_OUTPUTS)


@SETTINGS
@given(flexible_params())
def test_flexible_derived_constants(kw):
    model = FLEX(**kw)
    p = values_of(model)
    c = call("flexible", p, "derived")
    same(c["p"], p)
    for name in ("e_N", "e_T", "mu", "g", "length_scale", "time_scale", "force_scale", "step_limit"):
        assert c[name] == getattr(model, name), name
    same(c["dof_scales"], model.dof_scales)
    same(c["rest_abscissae"], model._rest_abscissae)
    same(call("flexible", p, "d")[:16], [model.m_tilde, model.k_tilde, model.M_t, model.D, model.A_h, model.C,
                                         model.I_mb, model.J0, model.J_eff, model.c, model.omega, model.h_cg,
                                         model.R, model.alpha, model.I_O, model.p])
    assert call("flexible", p, "work_note") == model.work_note
    tol = DEFAULT_TOLERANCES.for_model(model)
    for name, value in call("flexible", p, "scale_tolerances").items():
        assert value == getattr(tol, name), name


@SETTINGS
@given(flexible_params(), FSTATE, AG)
def test_flexible_full_coordinate_functions(kw, state, ag):
    model = FLEX(**kw)
    p = values_of(model)
    u, phi, ud, w, x, dx, dy, lift = state
    q = [u * model.h, x, model.b * abs(math.sin(phi)) + lift * model.length_scale, phi]
    v = [ud, dx, dy, w]
    qa, va = np.array(q), np.array(v)
    M = model.mass_matrix(qa)
    same(call("flexible", p, "mass_matrix", a=q), M)
    close(call("flexible", p, "inverse_mass", a=q), np.linalg.inv(M), rtol=LA_RTOL * np.linalg.cond(M))
    same(call("flexible", p, "forces", a=q, b=v, ag=ag), model.forces(qa, va, ag))
    K, C = call("flexible", p, "stiff_jacobians", a=q, b=v)
    pK, pC = model.stiff_jacobians(qa, va)
    same(K, pK)
    same(C, pC)
    same(call("flexible", p, "gaps", a=q), model.gaps(qa))
    W_N, W_T = call("flexible", p, "contact_jacobians", a=q)
    pw = model.contact_jacobians(qa)
    same(W_N, pw[0])
    same(W_T, pw[1])
    a_N, a_T = call("flexible", p, "contact_drift", a=q, b=v)
    pd = model.contact_drift(qa, va)
    same(a_N, pd[0])
    same(a_T, pd[1])
    same(call("flexible", p, "contact_abscissae", a=q), model.contact_abscissae(qa))
    assert call("flexible", p, "slip", a=q) == model.slip(qa)
    energy = model.energy(qa, va)
    close([call("flexible", p, "energy", a=q, b=v)], [energy],
          scale=model.kinetic_energy(qa, va) + abs(model.potential_energy(qa)) + 0.5 * model.k_tilde * q[0] ** 2)
    same(call("flexible", p, "outputs", a=q, b=v), out_list(model, model.outputs(qa, va)))
    same(call("flexible", p, "rest_position"), model.rest_position())


@SETTINGS
@given(flexible_params(), FSTATE, AG)
def test_flexible_sticking_modes_bitwise(kw, state, ag):
    model = FLEX(**kw)
    p = values_of(model)
    motion = ConstantMotion(ag)
    for mode in STICK:
        y = flexible_state(model, mode, *state)
        k = len(y) // 2
        r, rd = y[:k], y[k:]
        assert call("flexible", p, "mode_dofs", mode=mode) == list(model.mode_dofs(mode))
        q, v = call("flexible", p, "embed", mode=mode, a=r, b=rd)
        pq, pv = model.embed(mode, np.array(r), np.array(rd))
        same(q, pq)
        same(v, pv)
        J, jd = call("flexible", p, "mode_jacobian", mode=mode, a=r, b=rd)
        pJ, pjd = model.mode_jacobian(mode, np.array(r), np.array(rd))
        same(J, pJ)
        same(jd, pjd)
        rhs, monitors, totals = model.mode_closures(mode, motion)
        same(call("flexible", p, "kernel_rhs", mode=mode, a=y, ag=ag), rhs(0.0, list(y)))
        g, tot = call("flexible", p, "kernel_monitors", mode=mode, a=y, ag=ag)
        same(g, monitors(0.0, list(y)))
        if totals is None:
            assert tot is None
        else:
            same(tot, totals(0.0, list(y)))
        same(call("flexible", p, "mode_outputs", mode=mode, a=y), out_list(model, model.mode_outputs(mode, list(y))))
        force = model.M_t * (model.g + abs(ag) + model.length_scale * state[3] ** 2 + model.omega ** 2 * abs(y[0]))
        close(call("flexible", p, "contact_forces", mode=mode, a=pq.tolist(), b=pv.tolist(), ag=ag),
              model.contact_forces(mode, pq, pv, ag), rtol=1e-12, scale=force)
        frhs, fmon, ftot = model.functions_of(mode, motion)
        same(call("flexible", p, "rhs", mode=mode, a=y, ag=ag), frhs(0.0, list(y)))
        g, tot = call("flexible", p, "monitors", mode=mode, a=y, ag=ag)
        same(g, fmon(0.0, list(y)))
        same(call("flexible", p, "monitors_only", mode=mode, a=y, ag=ag), g)
        if ftot is None:
            assert tot is None
        else:
            same(tot, ftot(0.0, list(y)))
        assert call("flexible", p, "dofs_of", mode=mode) == list(model.dofs_of(mode))
        same(call("flexible", p, "reduce_any", mode=mode, a=q, b=v), np.concatenate(model.reduce_any(mode, pq, pv)))
        for shift in (0.0, state[4]):
            same(call("flexible", p, "outputs_of", mode=mode, a=y, ag=shift),
                 out_list(model, model.outputs_of(mode, list(y), shift)))
        if mode != Mode.FLIGHT:
            qs = pq + np.array([0.0, state[4], 0.0, 0.0])
            assert call("flexible", p, "shift_of", mode=mode, a=qs.tolist()) == sliding.shift_of(model, mode, qs)
            close(call("flexible", p, "force_totals", mode=mode, a=pq.tolist(), b=pv.tolist(), ag=ag),
                  sliding.force_totals(model, mode, pq, pv, ag), rtol=1e-12, scale=force)


@SETTINGS
@given(flexible_params(), FSTATE, AG)
def test_flexible_sliding_modes(kw, state, ag):
    model = FLEX(**kw)
    p = values_of(model)
    motion = ConstantMotion(ag)
    acc = model.g + abs(ag) + model.length_scale * state[3] ** 2 + model.omega ** 2 * model.h * abs(state[0]) \
        + model.omega * abs(state[2])
    for mode in SLIDING:
        y = flexible_state(model, mode, *state)
        k = len(y) // 2
        q, v = call("flexible", p, "embed_any", mode=mode, a=y)
        pq, pv = model.embed_any(mode, y[:k], y[k:])
        same(q, pq)
        same(v, pv)
        same(call("flexible", p, "reduce_any", mode=mode, a=q, b=v), np.concatenate(model.reduce_any(mode, pq, pv)))
        if slide_singular(model, mode, pq):
            continue        # a singular sliding problem (mu = inf at phi ~ 0): numpy's solve returns noise
        rtol = LA_RTOL * slide_cond(model, mode, pq) * np.linalg.cond(model.mass_matrix(pq))
        a, tau = call("flexible", p, "slide_motion", mode=mode, a=q, b=v, ag=ag)
        pa, ptau = sliding.slide_motion(model, mode, pq, pv, ag)
        close(a, pa, rtol, scale=acc)
        close(tau, ptau, rtol, scale=model.M_t * acc)
        frhs, fmon, ftot = model.functions_of(mode, motion)
        close(call("flexible", p, "rhs", mode=mode, a=y, ag=ag), frhs(0.0, list(y)), rtol, scale=acc)
        g, tot = call("flexible", p, "monitors", mode=mode, a=y, ag=ag)
        close(g, fmon(0.0, list(y)), rtol, scale=acc / model.g)
        close(tot, ftot(0.0, list(y)), rtol, scale=model.M_t * acc)


@SETTINGS
@given(flexible_params(), FSTATE, AG)
def test_flexible_overturned_outputs(kw, state, ag):
    """The pose at |phi| = pi/2 at rest (what the drivers report once overturned): outputs_of with zero
    velocities (event-driven) and outputs(q, 0) (Moreau-Jean); energy the potential + strain energy."""
    model = FLEX(**kw)
    p = values_of(model)
    for mode, phi in ((Mode.LEFT, 0.5 * math.pi), (Mode.RIGHT, -0.5 * math.pi)):
        y = [state[0] * model.h, phi, 0.0, 0.0]
        same(call("flexible", p, "outputs_of", mode=mode, a=y, ag=state[4]),
             out_list(model, model.outputs_of(mode, y, state[4])))
        q, _ = model.embed(mode, np.array(y[:2]), np.zeros(2))
        same(call("flexible", p, "outputs", a=q.tolist(), b=[0.0] * 4), out_list(model, model.outputs(q, np.zeros(4))))
    for mode, phi in ((Mode.LEFT_SLIDE_NEG, 0.5 * math.pi), (Mode.RIGHT_SLIDE_POS, -0.5 * math.pi)):
        y = [state[0] * model.h, phi, state[4], 0.0, 0.0, 0.0]
        same(call("flexible", p, "outputs_of", mode=mode, a=y, ag=0.0), out_list(model, model.outputs_of(mode, y)))


@SETTINGS
@given(flexible_params(), FSTATE)
def test_flexible_classical_impact_velocity(kw, state):
    model = FLEX(**kw)
    p = values_of(model)
    u, _, ud, w = state[:4]
    for pivot in (Mode.LEFT, Mode.RIGHT):
        s_n = -(-1 if pivot == Mode.LEFT else 1)
        w_minus = -s_n * (abs(w) + 1e-3)          # closes the gap of the other corner
        q = np.array([u * model.h, 0.0, 0.0, 0.0])
        v = np.array([ud, 0.0, -(-s_n) * model.b * w_minus, w_minus])
        pv = model.classical_impact_velocity(q, v, pivot)
        cv = call("flexible", p, "classical_impact_velocity", mode=pivot, a=q.tolist(), b=v.tolist())
        if pv is None:
            assert model.impact_rule == 0 and cv is None
        else:
            same(cv, pv)
        if model.impact_rule == 1:
            # a rate that opens the other corner's gap, and a sliding mode as the pivot: the Python raises
            bad = v.copy()
            bad[3] = -w_minus
            with pytest.raises(ValueError):
                model.classical_impact_velocity(q, bad, pivot)
            with pytest.raises(ValueError):
                call("flexible", p, "classical_impact_velocity", mode=pivot, a=q.tolist(), b=bad.tolist())
            slide = Mode.LEFT_SLIDE_POS if pivot == Mode.LEFT else Mode.RIGHT_SLIDE_NEG
            with pytest.raises(ValueError):
                model.classical_impact_velocity(q, v, slide)
            with pytest.raises(ValueError):
                call("flexible", p, "classical_impact_velocity", mode=slide, a=q.tolist(), b=v.tolist())


@SETTINGS
@given(flexible_params(), st.floats(-1.57, 1.57), st.floats(-1e4, 1e4), st.floats(-1.0, 1.0),
       st.floats(-1e4, 1e4))
def test_flexible_initial_state(kw, phi_0, phi_dot_0, u_0, u_dot_0):
    model = FLEX(**kw)
    if phi_dot_0 > 5e3:
        phi_0 = 0.0
    initial = [phi_0, phi_dot_0, u_0 * model.h, u_dot_0]
    mode, q, v = call("flexible", values_of(model), "initial_state", a=initial)
    pm, pq, pv = model.initial_state(*initial)
    assert mode == pm
    same(q, pq)
    same(v, pv)


@pytest.mark.parametrize("name", [p.name for p in FLEX.parameters()])
@pytest.mark.parametrize("bad", BAD_VALUES + (1e16, 1e14))
def test_flexible_parameter_checks_give_the_python_messages(name, bad):
    names = [p.name for p in FLEX.parameters()]
    params = values_of(FLEX())
    params[names.index(name)] = bad
    try:
        FLEX(**dict(zip(names, params)))
    except ValueError as exc:
        with pytest.raises(ValueError) as info:
            call("flexible", params, "derived")
        assert str(info.value) == str(exc)
    else:
        same(call("flexible", params, "derived")["p"], values_of(FLEX(**dict(zip(names, params)))))


@pytest.mark.parametrize("kw", [dict(m_c=0.0, m_b=0.0), dict(m_c=0.0, rho=0.0), dict(m_c=0.0, m_b=1e-300, rho=1e-300),
                                dict(EI=1e15), dict(EI=1e12, m=1.0, m_c=0.0, h=0.1)])
def test_flexible_derived_checks_give_the_python_messages(kw):
    names = [p.name for p in FLEX.parameters()]
    params = values_of(FLEX())
    for k, value in kw.items():
        params[names.index(k)] = value
    with pytest.raises(ValueError) as exc:
        FLEX(**dict(zip(names, params)))
    with pytest.raises(ValueError) as info:
        call("flexible", params, "derived")
    assert str(info.value) == str(exc.value)


@pytest.mark.parametrize("initial", [(0.1, 0.0, 2.0, 0.0), (0.1, 0.0, -1.6, 0.0), (0.0, 0.0, 0.0, 2e4),
                                     (2.0, 0.0, 0.0, 0.0), (0.0, 0.0, math.nan, 0.0), (0.0, 0.1, 1.5, -1e4)])
def test_flexible_initial_value_checks_give_the_python_messages(initial):
    model = FLEX()
    try:
        model.initial_state(*initial)
    except ValueError as exc:
        with pytest.raises(ValueError) as info:
            call("flexible", values_of(model), "initial_state", a=list(initial))
        assert str(info.value) == str(exc)
    else:
        call("flexible", values_of(model), "initial_state", a=list(initial))


# ------------------------------------------------------------------------------------------ a third model
def generic_expectations(model, mode, y, ag):
    """What RockingModel's generic code gives for ``mode`` at y: (rhs, monitors with the cone, totals)."""
    motion = ConstantMotion(ag)
    k = len(y) // 2
    r, rd = np.array(y[:k]), np.array(y[k:])
    rhs = list(y[k:]) + (RockingModel.reduced_acceleration(model, mode, r, rd, ag).tolist() if k else [])
    g = RockingModel.mode_functions(model, mode, motion)[1](0.0, list(y))
    totals = None
    if CLOSED[mode]:
        q, v = model.embed(mode, r, rd)
        totals = sliding.force_totals(model, mode, q, v, ag)
        if not math.isinf(model.mu):
            g = g[:-1] + [(model.mu * totals[0] - abs(totals[1])) / model.force_scale, g[-1]]
    return rhs, g, totals


@SETTINGS
@given(st.sampled_from(["rigid", "flexible"]), rigid_params(), flexible_params(), STATE, FSTATE, AG)
def test_a_kernel_with_only_the_required_functions_runs_every_mode(kind, rkw, fkw, rstate, fstate, ag):
    """The any-mode functions on a kernel without the optional closed forms (mode_rhs, mode_monitors,
    mode_outputs, inverse_mass_matrix) use the generic fallbacks and agree with RockingModel's generic code:
    adding a model needs only the required kernel functions."""
    model = RigidBlock(**rkw) if kind == "rigid" else FLEX(**fkw)
    p = values_of(model)
    state_of = (lambda mode: rigid_state(model, mode, *rstate)) if kind == "rigid" else \
        (lambda mode: flexible_state(model, mode, *fstate))
    w = rstate[1] if kind == "rigid" else fstate[3]
    acc = model.g + abs(ag) + model.length_scale * w ** 2
    if kind == "flexible":
        acc += model.omega ** 2 * model.h * abs(fstate[0]) + model.omega * abs(fstate[2])
    for mode in STICK:
        y = state_of(mode)
        q, _ = model.embed(mode, np.array(y[:len(y) // 2]), np.array(y[len(y) // 2:]))
        cond = np.linalg.cond(model.mass_matrix(q))
        rtol = 1e-12 * cond
        rhs, g, totals = generic_expectations(model, mode, y, ag)
        close(call(kind, p, "bare:rhs", mode=mode, a=y, ag=ag), rhs, rtol, scale=acc)
        cg, ctot = call(kind, p, "bare:monitors", mode=mode, a=y, ag=ag)
        close(cg, g, rtol, scale=acc / model.g)
        if totals is None:
            assert ctot is None
        else:
            close(ctot, totals, rtol, scale=model.force_scale * acc / model.g)
        close(call(kind, p, "bare:outputs_of", mode=mode, a=y, ag=0.5), out_list(model, model.outputs_of(mode, y, 0.5)),
              1e-14, scale=1.0)
        close(call(kind, p, "bare:inverse_mass", a=q.tolist()), np.linalg.inv(model.mass_matrix(q)), LA_RTOL * cond)


@SETTINGS
@given(st.sampled_from(["rigid", "flexible"]), rigid_params(), flexible_params(), STATE, FSTATE, AG)
def test_the_generic_monitors_without_kernel_contact_forces_use_the_contact_problem(kind, rkw, fkw, rstate, fstate,
                                                                                     ag):
    """Without a kernel contact_forces the generic monitors take the closed corners' forces from
    contact.mode_forces (part B's rk_mode_forces): RockingModel.contact_forces' default."""
    from rocking_model.contact import mode_forces

    model = RigidBlock(**rkw) if kind == "rigid" else FLEX(**fkw)
    p = values_of(model)
    state_of = (lambda mode: rigid_state(model, mode, *rstate)) if kind == "rigid" else \
        (lambda mode: flexible_state(model, mode, *fstate))
    w = rstate[1] if kind == "rigid" else fstate[3]
    acc = model.g + abs(ag) + model.length_scale * w ** 2
    if kind == "flexible":
        acc += model.omega ** 2 * model.h * abs(fstate[0]) + model.omega * abs(fstate[2])
    for mode in (Mode.FULL, Mode.LEFT, Mode.RIGHT):
        y = state_of(mode)
        k = len(y) // 2
        q, v = model.embed(mode, np.array(y[:k]), np.array(y[k:]))
        lam = mode_forces(model, mode, q, v, ag)
        _, g, _ = generic_expectations(model, mode, y, ag)
        for i in CLOSED[mode]:
            g[i] = float(lam[i]) / model.force_scale
        cg, _ = call(kind, p, "bare_all:monitors", mode=mode, a=y, ag=ag)
        close(cg, g, 1e-12 * np.linalg.cond(model.mass_matrix(q)), scale=acc / model.g)


def test_part_a_sources_compile_without_warnings(tmp_path):
    """rk_model.c, rk_sliding.c, rk_rigid.c, rk_flexible.c compile warning-free as strict C99 (the flags of
    setup.py plus -Wall -Wextra -pedantic -Werror), so that warnings do not accumulate."""
    import os
    import shutil
    import subprocess

    cc = shutil.which("gcc") or shutil.which("cc")
    if cc is None:
        pytest.skip("no C compiler on this machine")
    src = os.path.join(os.path.dirname(__file__), "..", "rocking_model", "engine", "src")
    for name in ("rk_model.c", "rk_sliding.c", "rk_rigid.c", "rk_flexible.c"):
        out = subprocess.run([cc, "-std=c99", "-O2", "-ffp-contract=off", "-fno-fast-math", "-Wall", "-Wextra",
                              "-pedantic", "-Werror", "-c", os.path.join(src, name), "-o", str(tmp_path / "x.o")],
                             capture_output=True, text=True, timeout=120)
        assert out.returncode == 0, out.stderr


# ------------------------------------------------------------------------------------------ vertical (issue 23)
#: the vertical ground acceleration [m/s2] (positive upward): exactly 0 (the bit-identity case) or any value up
#: to AG_MAX, g + ag_v < 0 included (the ground falls faster than g)
AG_V = st.one_of(st.just(0.0), st.floats(-1000.0, 1000.0))


#: [1] smallest singular value of a sliding problem's Delassus matrix, relative to the product of its factors'
#: norms, below which the problem is singular (numpy's LU then returns round-off noise of order 1/eps, the C's
#: least squares a finite answer: neither is meaningful to compare)
SLIDE_SINGULAR_RTOL = 1e-8


def slide_singular(model, mode, q) -> bool:
    """Whether sliding.slide_motion's Delassus matrix at q is singular (see SLIDE_SINGULAR_RTOL)."""
    stick, sigma = SLIDING[mode]
    closed = list(model.closed_of(stick))
    W_N, W_T = model.contact_jacobians(np.asarray(q, dtype=float))
    inv_mu = 0.0 if math.isinf(model.mu) else 1.0 / model.mu
    Minv = model.inverse_mass_matrix(np.asarray(q, dtype=float))
    C = inv_mu * W_N[:, closed] - sigma * W_T[:, closed]
    A = W_N[:, closed].T @ Minv @ C
    scale = np.linalg.norm(W_N[:, closed]) * np.linalg.norm(Minv) * np.linalg.norm(C)
    return bool(np.linalg.svd(A, compute_uv=False).min() <= SLIDE_SINGULAR_RTOL * scale)


def two_component(ag, ag_v):
    from rocking_model.ground_motion import TwoComponentMotion
    return TwoComponentMotion(ConstantMotion(ag), ConstantMotion(ag_v))


def vertical_pins(kind, model, state_of, ag, ag_v, acc, sliding_rtol):
    """Every kernel function that takes ag, called with ag_v, against the Python under the two-component motion:
    closed forms bitwise, numpy linear algebra (generic fallbacks, sliding modes) to round-off."""
    p = values_of(model)
    motion = two_component(ag, ag_v)
    for mode in STICK:
        y = state_of(mode)
        k = len(y) // 2
        pq, pv = model.embed(mode, np.array(y[:k]), np.array(y[k:]))
        same(call(kind, p, "forces", a=pq.tolist(), b=pv.tolist(), ag=ag, ag_v=ag_v),
             model.forces(pq, pv, ag, ag_v))
        rhs, monitors, totals = model.mode_closures(mode, motion)
        same(call(kind, p, "kernel_rhs", mode=mode, a=y, ag=ag, ag_v=ag_v), rhs(0.0, list(y)))
        g, tot = call(kind, p, "kernel_monitors", mode=mode, a=y, ag=ag, ag_v=ag_v)
        same(g, monitors(0.0, list(y)))
        if totals is None:
            assert tot is None
        else:
            same(tot, totals(0.0, list(y)))
        frhs, fmon, ftot = model.functions_of(mode, motion)
        same(call(kind, p, "rhs", mode=mode, a=y, ag=ag, ag_v=ag_v), frhs(0.0, list(y)))
        g, tot = call(kind, p, "monitors", mode=mode, a=y, ag=ag, ag_v=ag_v)
        same(g, fmon(0.0, list(y)))
        if ftot is not None:
            same(tot, ftot(0.0, list(y)))
        if ag_v == 0.0:
            # ag_v = 0: the same numbers as without a vertical component (today's closures)
            rhs0, mon0, _ = model.mode_closures(mode, ConstantMotion(ag))
            same(rhs(0.0, list(y)), rhs0(0.0, list(y)))
            same(monitors(0.0, list(y)), mon0(0.0, list(y)))
        cond = np.linalg.cond(model.mass_matrix(pq))
        force = model.force_scale * acc / model.g
        if kind == "rigid" or mode != Mode.FLIGHT:
            c = call(kind, p, "contact_forces", mode=mode, a=pq.tolist(), b=pv.tolist(), ag=ag, ag_v=ag_v)
            if kind == "rigid":
                same(c, model.contact_forces(mode, pq, pv, ag, ag_v))
            else:
                close(c, model.contact_forces(mode, pq, pv, ag, ag_v), rtol=1e-12, scale=force)
        if k:
            pr = RockingModel.reduced_acceleration(model, mode, np.array(y[:k]), np.array(y[k:]), ag, ag_v)
            close(call(kind, p, "generic_rhs", mode=mode, a=y, ag=ag, ag_v=ag_v), list(y[k:]) + pr.tolist(),
                  1e-12 * cond, scale=acc)
        g, tot = call(kind, p, "generic_monitors", mode=mode, a=y, ag=ag, ag_v=ag_v)
        close(g, RockingModel.mode_functions(model, mode, motion)[1](0.0, list(y)), 1e-12 * cond, scale=acc / model.g)
        if CLOSED[mode]:
            pt = sliding.force_totals(model, mode, pq, pv, ag, ag_v)
            close(tot, pt, 1e-12 * cond, scale=force)
            close(call(kind, p, "force_totals", mode=mode, a=pq.tolist(), b=pv.tolist(), ag=ag, ag_v=ag_v), pt,
                  1e-12 * cond, scale=force)
    for mode in SLIDING:
        y = state_of(mode)
        k = len(y) // 2
        pq, pv = model.embed_any(mode, y[:k], y[k:])
        if slide_singular(model, mode, pq):
            continue        # a singular sliding problem (mu = inf at phi = 0): numpy's solve returns noise
        rtol = sliding_rtol(mode, pq)
        a, tau = call(kind, p, "slide_motion", mode=mode, a=pq.tolist(), b=pv.tolist(), ag=ag, ag_v=ag_v)
        pa, ptau = sliding.slide_motion(model, mode, pq, pv, ag, ag_v)
        close(a, pa, rtol, scale=acc)
        close(tau, ptau, rtol, scale=model.force_scale * acc / model.g)
        frhs, fmon, ftot = model.functions_of(mode, motion)
        close(call(kind, p, "rhs", mode=mode, a=y, ag=ag, ag_v=ag_v), frhs(0.0, list(y)), rtol, scale=acc)
        g, tot = call(kind, p, "monitors", mode=mode, a=y, ag=ag, ag_v=ag_v)
        close(g, fmon(0.0, list(y)), rtol, scale=acc / model.g)
        close(tot, ftot(0.0, list(y)), rtol, scale=model.force_scale * acc / model.g)


@SETTINGS
@given(rigid_params(), STATE, AG, AG_V)
def test_rigid_kernels_with_a_vertical_ground_acceleration(kw, state, ag, ag_v):
    """Issue 23: the rigid kernel with ag_v (forces, closures' rhs / monitors / totals, contact forces, the
    generic fallbacks, the sliding modes) equals the Python under TwoComponentMotion(ag, ag_v)."""
    model = RigidBlock(**kw)
    acc = model.g + abs(ag) + abs(ag_v) + model.R * state[1] ** 2        # [m/s2] the scale of the accelerations
    vertical_pins("rigid", model, lambda mode: rigid_state(model, mode, *state), ag, ag_v, acc,
                  lambda mode, q: LA_RTOL * slide_cond(model, mode, q))


@SETTINGS
@given(flexible_params(), FSTATE, AG, AG_V)
def test_flexible_kernels_with_a_vertical_ground_acceleration(kw, state, ag, ag_v):
    """Issue 23: the flexible kernel with ag_v, as the rigid one above."""
    model = FLEX(**kw)
    acc = model.g + abs(ag) + abs(ag_v) + model.length_scale * state[3] ** 2 \
        + model.omega ** 2 * model.h * abs(state[0]) + model.omega * abs(state[2])
    vertical_pins("flexible", model, lambda mode: flexible_state(model, mode, *state), ag, ag_v, acc,
                  lambda mode, q: LA_RTOL * slide_cond(model, mode, q) * np.linalg.cond(model.mass_matrix(q)))
