"""FlexibleOscillator: Eq. (55) re-derived from the Lagrangian, contact relation, modes, energy, uplift."""
from __future__ import annotations

import math

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp

from rocking_model.models.base import RockingModel
from rocking_model import Simulator
from rocking_model.models.flexible_oscillator import FlexibleOscillator
from rocking_model.modes import CLOSED, Mode

MODES = (Mode.FULL, Mode.LEFT, Mode.RIGHT, Mode.FLIGHT)

PARAMS = [
    {},                                                     # defaults
    dict(m=2.0, m_c=1.5, m_b=0.7, rho=0.3, h=1.3, b=0.4, EI=50.0, zeta=0.05, g=9.0),
    dict(m=1.0, m_c=0.0, m_b=0.5, rho=0.2, h=2.0, b=0.3, EI=10.0, zeta=0.0),   # lumped column
    dict(m=1.0, m_c=0.8, m_b=0.0, rho=0.0, h=1.0, b=0.2, EI=5.0, zeta=0.1),    # massless base
]


# ---------------------------------------------------------------------- symbolic Lagrangian (Eqs. 48-54)
@pytest.fixture(scope="module")
def lagrange_eom():
    """M(q) and f(q, v, ag) from Lagrange's equations with the ground displacement u_g (Eqs. 50, 52-54).

    Returns numeric functions M(params, q) and f(params, q, v, ag, vg); vg = u_g_dot must drop out."""
    m, mc, mb, rho, h, k, g, cd, xi = sp.symbols("m m_c m_b rho h k g c_d xi", real=True)
    q = sp.symbols("u x y phi", real=True)
    v = sp.symbols("ud xd yd phid", real=True)
    a = sp.symbols("udd xdd ydd phidd", real=True)
    ug, vg, ag = sp.symbols("u_g v_g a_g", real=True)

    def ddt(F):
        return (sum(sp.diff(F, qi) * vi for qi, vi in zip(q, v))
                + sum(sp.diff(F, vi) * ai for vi, ai in zip(v, a))
                + sp.diff(F, ug) * vg + sp.diff(F, vg) * ag)

    u, x, y, phi = q
    psi = 3 * xi ** 2 / (2 * h ** 2) - xi ** 3 / (2 * h ** 3)               # Eq. (48)
    Xm, Ym = ug + x - h * sp.sin(phi) + u * sp.cos(phi), y + h * sp.cos(phi) + u * sp.sin(phi)
    Xc, Yc = ug + x - xi * sp.sin(phi) + u * psi * sp.cos(phi), y + xi * sp.cos(phi) + u * psi * sp.sin(phi)
    Xb, Yb = ug + x, y                                                        # Eq. (50)

    def column_integral(expr):                       # integral over xi in [0, h] of a polynomial in xi
        poly = sp.Poly(sp.expand(expr), xi)
        return sum(c * h ** (mon[0] + 1) / (mon[0] + 1) for mon, c in zip(poly.monoms(), poly.coeffs()))

    T = (m / 2 * (ddt(Xm) ** 2 + ddt(Ym) ** 2)
         + column_integral(mc / h / 2 * (ddt(Xc) ** 2 + ddt(Yc) ** 2))
         + mb / 2 * (ddt(Xb) ** 2 + ddt(Yb) ** 2) + mb * rho ** 2 / 2 * v[3] ** 2)  # Eq. (52)
    V = (k / 2 * u ** 2 + m * g * Ym + mb * g * Yb + column_integral(mc / h * g * Yc))   # Eq. (53)
    L = T - V
    Q = [-cd * v[0], 0, 0, 0]                                                 # Eq. (54)
    eom = [sp.expand(ddt(sp.diff(L, vi)) - sp.diff(L, qi) - Qi) for qi, vi, Qi in zip(q, v, Q)]
    Msym = sp.Matrix([[sp.diff(e, aj) for aj in a] for e in eom])
    fsym = sp.Matrix([-e.subs({ai: 0 for ai in a}) for e in eom])
    assert all(sp.simplify(sp.diff(fi, vg)) == 0 for fi in fsym)             # Galilean invariance
    pars = (m, mc, mb, rho, h, k, g, cd)
    Mf = sp.lambdify((pars, q), Msym, "numpy")
    ff = sp.lambdify((pars, q, v, ag, vg), fsym, "numpy")
    return Mf, ff


def _pars(model):
    return (model.m, model.m_c, model.m_b, model.rho, model.h, model.k_tilde, model.g, model.c)


@pytest.mark.parametrize("kw", PARAMS)
def test_mass_matrix_and_forces_match_lagrangian(lagrange_eom, kw):
    Mf, ff = lagrange_eom
    model = FlexibleOscillator(**kw)
    rng = np.random.default_rng(1)
    for _ in range(10):
        q = rng.normal(size=4) * np.array([0.1, 0.3, 0.3, 0.6])
        v = rng.normal(size=4)
        ag, vg = rng.normal() * 3.0, rng.normal()
        M_ref = np.array(Mf(_pars(model), q), dtype=float)
        f_ref = np.array(ff(_pars(model), q, v, ag, vg), dtype=float).ravel()
        M = model.mass_matrix(q)
        np.testing.assert_allclose(M, M_ref, rtol=1e-12, atol=1e-12 * np.abs(M_ref).max())
        np.testing.assert_allclose(M, M.T)
        assert np.all(np.linalg.eigvalsh(M) > 0.0)
        f = model.forces(q, v, ag)
        np.testing.assert_allclose(f, f_ref, rtol=1e-11, atol=1e-11 * np.abs(f_ref).max())


def test_shape_function_integrals():
    xi, h = sp.symbols("xi h", positive=True)
    psi = 3 * xi ** 2 / (2 * h ** 2) - xi ** 3 / (2 * h ** 3)
    assert sp.simplify(sp.integrate(psi ** 2, (xi, 0, h)) / h) == sp.Rational(33, 140)
    assert sp.simplify(sp.integrate(psi, (xi, 0, h)) / h) == sp.Rational(3, 8)
    assert sp.simplify(sp.integrate(xi * psi, (xi, 0, h)) / h ** 2) == sp.Rational(11, 40)
    EI = sp.symbols("EI", positive=True)
    assert sp.simplify(sp.integrate(EI * sp.diff(psi, xi, 2) ** 2, (xi, 0, h)) - 3 * EI / h ** 3) == 0


# ---------------------------------------------------------------------- parameters
def test_defaults_and_derived():
    model = FlexibleOscillator()
    assert model.m_tilde == pytest.approx(model.m + 33 / 140 * model.m_c)
    assert model.k_tilde == pytest.approx(3 * model.EI / model.h ** 3)
    assert model.M_t == pytest.approx(model.m + model.m_b + model.m_c)
    assert model.omega == pytest.approx(math.sqrt(model.k_tilde / model.m_tilde))
    assert model.c == pytest.approx(2 * model.zeta * math.sqrt(model.m_tilde * model.k_tilde))
    assert model.omega > 10 * model.p                 # column much stiffer than the rocking mode
    assert model.time_scale == pytest.approx(1 / model.p)
    assert model.length_scale > 0
    assert model.n_dof == 4 and model.dof_names == ("u", "x", "y", "phi") and model.phi_index == 3
    K, C = model.stiff_jacobians(np.zeros(4), np.zeros(4))
    assert K[0, 0] == model.k_tilde and C[0, 0] == model.c
    assert np.count_nonzero(K) == 1 and np.count_nonzero(C) == 1
    # K, C are -df/du, -df/du_dot of the linear part (at phi_dot = 0)
    q, v, eps = np.array([0.01, 0.0, 0.0, 0.2]), np.array([0.3, 0.1, 0.2, 0.0]), 1e-6
    e0 = np.eye(4)[0]
    assert -(model.forces(q + eps * e0, v, 0.0)[0] - model.forces(q - eps * e0, v, 0.0)[0]) / (2 * eps) \
        == pytest.approx(model.k_tilde, rel=1e-7)
    assert -(model.forces(q, v + eps * e0, 0.0)[0] - model.forces(q, v - eps * e0, 0.0)[0]) / (2 * eps) \
        == pytest.approx(model.c, rel=1e-7)


@pytest.mark.parametrize("name, value", [
    ("m", 0.0), ("m", -1.0), ("m_c", -0.1), ("m_b", -1.0), ("rho", -0.1), ("h", 0.0), ("b", -0.2),
    ("EI", 0.0), ("zeta", -0.01), ("e_N", 1.5), ("e_N", -0.1), ("g", 0.0), ("h", float("nan")),
    ("EI", float("inf")), ("m", "heavy"),
])
def test_invalid_parameters(name, value):
    with pytest.raises(ValueError, match=name):
        FlexibleOscillator(**{name: value})


@pytest.mark.parametrize("kw, name", [(dict(m_c=0.0, rho=0.0), "rho"), (dict(m_c=0.0, m_b=0.0), "m_b")])
def test_singular_mass_matrix_rejected(kw, name):
    with pytest.raises(ValueError, match=name):
        FlexibleOscillator(**kw)


def test_singular_case_really_singular():
    # the reason for the check: with m_c = 0 and I_mb = 0, M is singular at u = 0
    model = FlexibleOscillator(m_c=0.0, rho=1e-9)
    assert np.linalg.cond(model.mass_matrix(np.zeros(4))) > 1e12
    # massless base with a distributed column mass is fine
    model = FlexibleOscillator(m_b=0.0, rho=0.0)
    assert np.linalg.cond(model.mass_matrix(np.zeros(4))) < 1e8


# ---------------------------------------------------------------------- contact relation
def _corners(model, q):
    u, x, y, phi = q
    c, s = math.cos(phi), math.sin(phi)
    return np.array([[x - model.b * c, y - model.b * s], [x + model.b * c, y + model.b * s]])


@pytest.mark.parametrize("kw", PARAMS[:2])
def test_contact_relation_by_finite_differences(kw):
    model = FlexibleOscillator(**kw)
    rng = np.random.default_rng(2)
    eps = 1e-6
    for _ in range(5):
        q, v = rng.normal(size=4) * 0.3, rng.normal(size=4)
        np.testing.assert_allclose(model.gaps(q), _corners(model, q)[:, 1], atol=1e-15)
        W_N, W_T = model.contact_jacobians(q)
        assert W_N.shape == (4, 2) and W_T.shape == (4, 2)
        dpos = (_corners(model, q + eps * v) - _corners(model, q - eps * v)) / (2 * eps)
        np.testing.assert_allclose(W_N.T @ v, dpos[:, 1], rtol=1e-8, atol=1e-9)
        np.testing.assert_allclose(W_T.T @ v, dpos[:, 0], rtol=1e-8, atol=1e-9)
        a_N, a_T = model.contact_drift(q, v)
        W_Np, W_Tp = model.contact_jacobians(q + eps * v)
        W_Nm, W_Tm = model.contact_jacobians(q - eps * v)
        np.testing.assert_allclose(a_N, (W_Np - W_Nm).T @ v / (2 * eps), rtol=1e-7, atol=1e-8)
        np.testing.assert_allclose(a_T, (W_Tp - W_Tm).T @ v / (2 * eps), rtol=1e-7, atol=1e-8)


# ---------------------------------------------------------------------- modes
@pytest.mark.parametrize("mode", MODES)
def test_embedding_consistency(mode):
    model = FlexibleOscillator()
    rng = np.random.default_rng(3)
    n = len(model.mode_dofs(mode))
    eps = 1e-6
    for _ in range(5):
        r, rd, rdd = rng.normal(size=n) * 0.2, rng.normal(size=n), rng.normal(size=n)
        q, v = model.embed(mode, r, rd)
        closed = list(CLOSED[mode])
        W_N, W_T = model.contact_jacobians(q)
        np.testing.assert_allclose(model.gaps(q)[closed], 0.0, atol=1e-15)
        np.testing.assert_allclose((W_N.T @ v)[closed], 0.0, atol=1e-15)
        np.testing.assert_allclose((W_T.T @ v)[closed], 0.0, atol=1e-15)   # sticking
        if mode in (Mode.LEFT, Mode.RIGHT):        # the pivot stays at (s b, 0)
            i = closed[0]
            np.testing.assert_allclose(_corners(model, q)[i], [(-1) ** (i + 1) * model.b, 0.0], atol=1e-15)
        r2, rd2 = model.reduce(mode, q, v)
        np.testing.assert_allclose(r2, r)
        np.testing.assert_allclose(rd2, rd)
        J, jd = model.mode_jacobian(mode, r, rd)
        assert J.shape == (4, n)
        np.testing.assert_allclose(v, J @ rd, atol=1e-15)
        # q(r(t)), r(t) = r + rd t + rdd t^2/2: dq/dt = J rd, d2q/dt2 = J rdd + jd
        qt = [model.embed(mode, r + rd * t + rdd * t * t / 2, rd + rdd * t)[0] for t in (-eps, 0.0, eps)]
        vt = [model.embed(mode, r + rd * t + rdd * t * t / 2, rd + rdd * t)[1] for t in (-eps, eps)]
        np.testing.assert_allclose((qt[2] - qt[0]) / (2 * eps), v, rtol=1e-7, atol=1e-8)
        np.testing.assert_allclose((vt[1] - vt[0]) / (2 * eps), J @ rdd + jd, rtol=1e-6, atol=1e-7)


@pytest.mark.parametrize("kw", PARAMS)
@pytest.mark.parametrize("mode", MODES)
def test_closed_form_reduced_acceleration_matches_projection(kw, mode):
    model = FlexibleOscillator(**kw)
    rng = np.random.default_rng(4)
    n = len(model.mode_dofs(mode))
    for _ in range(10):
        r, rd, ag = rng.normal(size=n) * 0.3, rng.normal(size=n), rng.normal() * 5
        a = model.reduced_acceleration(mode, r, rd, ag)
        ref = RockingModel.reduced_acceleration(model, mode, r, rd, ag)
        np.testing.assert_allclose(a, ref, rtol=1e-10, atol=1e-10 * np.abs(ref).max())


def test_reduced_acceleration_satisfies_full_dynamics_with_contact_forces():
    # rocking: M v_dot - f must be a combination of the closed corner's W_N and W_T columns
    model = FlexibleOscillator()
    rng = np.random.default_rng(5)
    for mode in (Mode.LEFT, Mode.RIGHT, Mode.FULL):
        n = len(model.mode_dofs(mode))
        r, rd, ag = rng.normal(size=n) * 0.2, rng.normal(size=n), 2.0
        q, v = model.embed(mode, r, rd)
        J, jd = model.mode_jacobian(mode, r, rd)
        vdot = J @ model.reduced_acceleration(mode, r, rd, ag) + jd
        resid = model.mass_matrix(q) @ vdot - model.forces(q, v, ag)
        W_N, W_T = model.contact_jacobians(q)
        closed = list(CLOSED[mode])
        G = np.concatenate([W_N[:, closed], W_T[:, closed]], axis=1)
        lam, *_ = np.linalg.lstsq(G, resid, rcond=None)
        np.testing.assert_allclose(G @ lam, resid, atol=1e-9 * np.abs(resid).max())


# ---------------------------------------------------------------------- initial state, outputs, energy
def test_initial_state():
    model = FlexibleOscillator()
    mode, q, v = model.initial_state()
    assert mode == Mode.FULL and np.all(q == 0) and np.all(v == 0)
    mode, q, v = model.initial_state(u_0=0.01, u_dot_0=-0.2)
    assert mode == Mode.FULL and q[0] == 0.01 and v[0] == -0.2 and np.all(q[1:] == 0)
    mode, q, v = model.initial_state(phi_0=0.05, u_0=0.001)
    assert mode == Mode.LEFT and q[3] == 0.05 and q[0] == 0.001 and model.gaps(q)[0] == pytest.approx(0)
    mode, q, v = model.initial_state(phi_0=-0.05, phi_dot_0=0.1)
    assert mode == Mode.RIGHT and model.gaps(q)[1] == pytest.approx(0) and v[3] == 0.1
    mode, q, v = model.initial_state(phi_dot_0=-0.1)
    assert mode == Mode.RIGHT
    for bad in (dict(phi_0=math.pi / 2), dict(phi_0=-2.0), dict(u_0=float("nan")), dict(phi_dot_0="x")):
        with pytest.raises(ValueError, match=next(iter(bad))):
            model.initial_state(**bad)
    with pytest.raises(ValueError, match="allowed"):
        model.initial_state(theta=0.1)


def test_outputs_and_energy_at_rest():
    model = FlexibleOscillator()
    assert model.energy(model.rest_position(), np.zeros(4)) == 0.0
    mode, q, v = model.initial_state(phi_0=0.1, phi_dot_0=0.3, u_0=0.01, u_dot_0=0.1)
    out = model.outputs(q, v)
    assert set(out) == {"u", "u_dot", "phi", "phi_dot", "x", "y", "x_dot", "y_dot", "slip", "top_displacement",
                        "energy"}
    assert out["slip"] == 0.0            # rocking on its pivot: the lower corner stays where it was
    assert out["top_displacement"] == pytest.approx(q[1] - model.h * math.sin(q[3]) + q[0] * math.cos(q[3]))
    assert out["y"] == pytest.approx(model.b * math.sin(0.1))
    assert out["energy"] > 0
    # tilted at rest on the pivot: potential energy of the lifted centre of mass and column strain
    _, q, v = model.initial_state(phi_0=0.05)
    z_cm = model.M_t * q[2] + model.A_h * math.cos(0.05)
    assert model.energy(q, v) == pytest.approx(model.g * (z_cm - model.A_h))


def _power_ag(model, q, v, ag):
    return float((model.forces(q, v, ag) - model.forces(q, v, 0.0)) @ v)


@pytest.mark.parametrize("mode, r0, rd0", [
    (Mode.LEFT, [0.004, 0.03], [0.05, 0.1]),
    (Mode.RIGHT, [-0.01, -0.02], [0.2, -0.05]),
    (Mode.FULL, [0.01], [0.0]),
    (Mode.FLIGHT, [0.005, 0.01, 0.02, 0.03], [0.1, 0.2, 0.5, -0.3]),
])
@pytest.mark.parametrize("excited", [False, True])
def test_energy_balance(mode, r0, rd0, excited):
    """zeta = 0: E conserved with ag = 0; with ag(t) and damping dE/dt = P_ag - c u_dot^2."""
    model = FlexibleOscillator(zeta=0.05 if excited else 0.0)
    n = len(r0)

    def ag(t):
        return 2.0 * math.sin(7.0 * t) if excited else 0.0

    def rhs(t, z):
        r, rd = z[:n], z[n:2 * n]
        q, v = model.embed(mode, r, rd)
        work = _power_ag(model, q, v, ag(t)) - model.c * v[0] ** 2
        return np.concatenate([rd, model.reduced_acceleration(mode, r, rd, ag(t)), [work]])

    z0 = np.concatenate([r0, rd0, [0.0]])
    sol = solve_ivp(rhs, (0.0, 0.6), z0, method="DOP853", rtol=1e-11, atol=1e-13, dense_output=True)
    assert sol.success
    E0 = model.energy(*model.embed(mode, np.array(r0), np.array(rd0)))
    scale = max(abs(E0), 1.0)
    for t in np.linspace(0.0, 0.6, 7):
        z = sol.sol(t)
        E = model.energy(*model.embed(mode, z[:n], z[n:2 * n]))
        assert E - E0 == pytest.approx(z[-1], abs=1e-8 * scale)
    if not excited:
        assert abs(sol.y[-1, -1]) < 1e-12 * scale


# ---------------------------------------------------------------------- rocking initiation (uplift LCP)
def _start_mode(model, ag, **initial):
    """The contact mode the engine enters from a state in full contact under the constant ag (its uplift LCP at
    the start), read after a step too short for the mode to change again."""
    sim = Simulator(model, **initial)
    sim.advance(1e-7, ag)
    return sim.outputs()["contact"]


def _Q(model, u, ud, ag):
    udd = (-model.c * ud - model.k_tilde * u - model.D * ag) / model.m_tilde
    return -model.C * udd - model.A_h * ag + model.g * model.D * u


@pytest.mark.parametrize("kw", PARAMS)
@pytest.mark.parametrize("ud, ag", [(0.0, 0.0), (0.3, 0.0), (-0.2, 1.5), (0.1, -4.0)])
@pytest.mark.parametrize("side", [1.0, -1.0])
def test_uplift_threshold(kw, ud, ag, side):
    model = FlexibleOscillator(**kw)
    limit = model.b * model.M_t * model.g
    Q0 = _Q(model, 0.0, ud, ag)
    dQ = _Q(model, 1.0, ud, ag) - Q0          # Q is affine in u
    assert dQ > 0
    for fac, lifts in ((0.98, False), (1.02, True)):
        u = (side * fac * limit - Q0) / dQ           # Q = side * fac * limit
        Q = _Q(model, u, ud, ag)
        assert (abs(Q) > limit) == lifts
        # Q > 0 lifts the left corner: the structure pivots on the right corner
        expected = (Mode.RIGHT if side > 0 else Mode.LEFT) if lifts else Mode.FULL
        assert _start_mode(model, ag, u_0=u, u_dot_0=ud) == expected


def test_uplift_lumped_mass_classical_criterion():
    """m_c = 0, zeta = 0, u_dot = 0, ag = 0: the model (with P-Delta) lifts at
    |u| = (m + m_b) g b / (k_tilde h + m g); the classical |u| > (m + m_b) g b / (k_tilde h) neglects the
    P-Delta moment m g u and is recovered when m g << k_tilde h."""
    model = FlexibleOscillator(m=1.0, m_c=0.0, m_b=0.5, rho=0.2, h=1.0, b=0.3, EI=3.0, zeta=0.0)
    w = (model.m + model.m_b) * model.g * model.b
    u_pd = w / (model.k_tilde * model.h + model.m * model.g)
    u_cl = w / (model.k_tilde * model.h)
    assert u_cl > 1.5 * u_pd            # soft column: P-Delta clearly visible
    for sign, pivot in ((1.0, Mode.RIGHT), (-1.0, Mode.LEFT)):
        for u, mode in ((0.999 * u_pd, Mode.FULL), (1.001 * u_pd, pivot), (0.5 * (u_pd + u_cl), pivot)):
            assert _start_mode(model, 0.0, u_0=sign * u) == mode
    stiff = FlexibleOscillator(m=1.0, m_c=0.0, m_b=0.5, rho=0.2, h=1.0, b=0.3, EI=3.0e6, zeta=0.0)
    u_cl = w / (stiff.k_tilde * stiff.h)
    for u, mode in ((0.999 * u_cl, Mode.FULL), (1.001 * u_cl, Mode.RIGHT)):
        assert _start_mode(stiff, 0.0, u_0=u) == mode
