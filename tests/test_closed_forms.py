"""Closed-form solutions checked against the compiled engine through the public API only.

Every expected number is computed here from a formula (Housner 1963; Shenton 1996; Giouvanidis &
Dimitrakopoulos 2017, appendix and docs/physics.md), never from a second engine. Scenes are chosen far from
the decision boundaries (thresholds at +-2 %, amplitudes well inside the basin of each regime). SI units
throughout: lengths [m], times [s], angles [rad], accelerations [m/s2].
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import quad

from rocking_model import FlexibleOscillator, RigidBlock, Simulator, simulate

G = 9.81
FULL, LEFT, RIGHT, FLIGHT = 0, 1, 2, 3
FULL_SLIDE_POS, FULL_SLIDE_NEG, LEFT_SLIDE_POS, LEFT_SLIDE_NEG = 4, 5, 6, 7
TOL = 1e-12          # event-driven tolerance of the tight comparisons


# ---------------------------------------------------------------------------------------------- Housner
def block_constants(b, h, g=G):
    """(alpha [rad], p [rad/s], Housner's r [1]) of a rectangular block of half-width b, half-height h."""
    R = math.hypot(b, h)
    alpha = math.atan2(b, h)
    return alpha, math.sqrt(3.0 * g / (4.0 * R)), 1.0 - 1.5 * math.sin(alpha) ** 2


def fall_time(alpha, p, amp, phi=0.0):
    """[s] time of the nonlinear free fall from rest at |phi| = amp to |phi| = phi, by quadrature of the energy
    integral 1/2 phi_dot^2 = p^2 [cos(alpha - amp) - cos(alpha - psi)]. The integrand's inverse square-root
    singularity at psi = amp is taken by QUADPACK's algebraic weight; cos A - cos B is written as a product
    of sines so that nothing cancels near the end point."""
    def smooth(psi):
        d = amp - psi
        ratio = 2.0 if d == 0.0 else d / math.sin(0.5 * d)
        return math.sqrt(ratio / (4.0 * p * p * math.sin(alpha - 0.5 * (amp + psi))))
    val, _ = quad(smooth, phi, amp, weight="alg", wvar=(0.0, -0.5), epsabs=1e-15, epsrel=1e-13)
    return val


def nonlinear_phi(alpha, p, amp, t):
    """phi(t) [rad] of the nonlinear free fall from rest at phi = amp > 0 (before the first impact)."""
    from scipy.optimize import brentq
    if t == 0.0:
        return amp
    return brentq(lambda phi: fall_time(alpha, p, amp, phi) - t, 0.0, amp, xtol=1e-15, rtol=1e-15)


def amplitudes(alpha, r, amp0, n):
    """Amplitudes phi_k, k = 0..n-1, of free rocking with Housner's r: the energy above the rest position,
    cos(alpha - phi) - cos(alpha), is multiplied by r^2 at each impact."""
    e0 = math.cos(alpha - amp0) - math.cos(alpha)
    return [alpha - math.acos(math.cos(alpha) + r ** (2 * k) * e0) for k in range(n)]


def test_free_fall_matches_the_energy_quadrature():
    """phi(t) from release at rest to the first impact equals the inverted energy quadrature of the nonlinear
    equation to 1e-10 rad (b = 0.2 m, h = 1 m, phi_0 = 0.6 alpha)."""
    b, h = 0.2, 1.0
    alpha, p, _ = block_constants(b, h)
    amp = 0.6 * alpha
    t1 = fall_time(alpha, p, amp)
    ts = np.linspace(0.0, 0.98 * t1, 15)
    res = simulate(RigidBlock(b=b, h=h), 0.0, ts[-1], phi_0=amp, tolerance=TOL, output_interval=ts[1])
    expected = np.array([nonlinear_phi(alpha, p, amp, t) for t in res.t])
    np.testing.assert_allclose(res.t, ts, atol=1e-14)
    assert np.max(np.abs(res.phi - expected)) < 1e-10


def test_slender_free_fall_matches_the_linearised_solution():
    """For a slender block (alpha = 0.01 rad) phi(t) = alpha - (alpha - phi_0) cosh(p t) until the first
    impact at t = arccosh(1/(1 - phi_0/alpha))/p, a quarter of the free period T = 4/p arccosh(...). With
    theta = alpha - phi, the linearisation drops p^2 (theta - sin theta) <= p^2 alpha^3/6, so the nonlinear
    solution stays within (alpha^3/6) (cosh(p t) - 1) of the linear one (1.5e-7 rad, 3e-5 of phi_0 here);
    the impact time agrees to 2e-5 relative."""
    b, h = 0.01, 1.0
    alpha, p, _ = block_constants(b, h)
    phi0 = 0.5 * alpha
    quarter = math.acosh(1.0 / (1.0 - phi0 / alpha)) / p
    res = simulate(RigidBlock(b=b, h=h), 0.0, 0.95 * quarter, phi_0=phi0, tolerance=TOL,
                   output_interval=0.95 * quarter / 20)
    linear = alpha - (alpha - phi0) * np.cosh(p * res.t)
    bound = alpha ** 3 / 6.0 * (np.cosh(p * res.t) - 1.0)
    assert np.all(np.abs(res.phi - linear) <= bound + 1e-14)
    first = simulate(RigidBlock(b=b, h=h), 0.0, 1.2 * quarter, phi_0=phi0, tolerance=TOL).impact_times[0]
    assert first == pytest.approx(quarter, rel=2e-5)
    assert 4.0 * first == pytest.approx(4.0 / p * math.acosh(1.0 / (1.0 - phi0 / alpha)), rel=2e-5)


def test_free_rocking_impact_times_and_amplitudes_follow_housner():
    """Free rocking with e_N = 0 (the paper's sticking impact is Housner's): impact n + 1 follows impact n
    after two falls from the amplitude phi_n, cos(alpha - phi_n) - cos(alpha) = r^(2n) [cos(alpha - phi_0) -
    cos(alpha)] with r = 1 - 1.5 sin^2(alpha). The first 10 impact times agree to 1e-9 s and the peaks (|phi|
    at the time halfway between impacts) to 1e-10 rad."""
    b, h = 0.2, 1.0
    alpha, p, r = block_constants(b, h)
    n = 10
    amps = amplitudes(alpha, r, 0.5 * alpha, n)
    times = [fall_time(alpha, p, amps[0])]
    for a in amps[1:n]:
        times.append(times[-1] + 2.0 * fall_time(alpha, p, a))
    sim = Simulator(RigidBlock(b=b, h=h), "event_driven", tolerance=TOL, phi_0=amps[0])
    sim.advance(times[-1] + 0.05, 0.0)
    got = np.array(sim.impact_times[:n])
    assert len(got) == n
    assert np.max(np.abs(got - np.array(times))) < 1e-9
    # peaks: halfway between impacts the block is at rest at +-phi_k (alternating pivots, right first)
    sim = Simulator(RigidBlock(b=b, h=h), "event_driven", tolerance=TOL, phi_0=amps[0])
    for k in range(1, n - 1):
        sim.advance(times[k - 1] + fall_time(alpha, p, amps[k]), 0.0)
        out = sim.outputs()
        assert abs(out["phi"] - (-1) ** k * amps[k]) < 1e-10, (k, out["phi"], amps[k])
        assert abs(out["phi_dot"]) < 1e-8


def rocking_energy(alpha, p, phi, phi_dot):
    """[rad2/s2] free-rocking energy per unit I_O above the rest pose (nonlinear), for either pivot."""
    return 0.5 * phi_dot * phi_dot + p * p * (math.cos(alpha - abs(phi)) - math.cos(alpha))


@pytest.mark.parametrize("e_N", [0.0, 0.4])
def test_impact_ratio_is_housners(e_N):
    """The angular velocity ratio at the first impact of a slender block is 1 - 1.5 (1 + e_N) sin^2(alpha):
    Housner's r for e_N = 0 (rocking on about the other corner), and for e_N > 0 the ratio of the flight that
    follows, whose phi_dot is then constant (and its vertical centroid velocity e_N V - b phi_dot+ with
    V = 2 b |phi_dot-|). phi_dot at the impact is recovered from states 1e-4 s either side through the exact
    energy of rocking (e_N = 0) or read directly in flight; ratio to 1e-9."""
    b, h = 0.2, 1.0
    alpha, p, _ = block_constants(b, h)
    ratio = 1.0 - 1.5 * (1.0 + e_N) * math.sin(alpha) ** 2
    phi0 = 0.4 * alpha
    t1 = fall_time(alpha, p, phi0)
    sim = Simulator(RigidBlock(b=b, h=h, e_N=e_N), "event_driven", tolerance=TOL, phi_0=phi0)
    sim.advance(t1 - 1e-4, 0.0)
    before = sim.outputs()
    w_minus = -math.sqrt(2.0 * rocking_energy(alpha, p, before["phi"], before["phi_dot"]))
    sim.advance(t1 + 1e-4, 0.0)
    after = sim.outputs()
    assert sim.impact_times[0] == pytest.approx(t1, abs=1e-9)
    if e_N == 0.0:
        assert after["contact"] == RIGHT and after["phi"] < 0.0
        w_plus = -math.sqrt(2.0 * rocking_energy(alpha, p, after["phi"], after["phi_dot"]))
        assert w_plus / w_minus == pytest.approx(ratio, abs=1e-9)
    else:
        assert after["contact"] == FLIGHT
        assert after["phi_dot"] / w_minus == pytest.approx(ratio, abs=1e-9)
        # the centroid's vertical velocity at phi = 0 is that of the impacting (right) corner, e_N V,
        # minus b phi_dot+ (its lever arm); in flight y_dot then decreases by g t
        V = 2.0 * b * abs(w_minus)
        expected = e_N * V - b * ratio * w_minus - G * (t1 + 1e-4 - sim.impact_times[0])
        assert after["y_dot"] == pytest.approx(expected, abs=1e-8)


def test_squat_block_stops_at_its_first_impact():
    """sin^2(alpha) > 2/3 with e_N = 0: the impact LCP gives full contact, phi = 0 and phi_dot = 0 after."""
    b, h = 1.0, 0.5                   # sin^2(alpha) = 0.8
    alpha, p, _ = block_constants(b, h)
    t1 = fall_time(alpha, p, 0.2)
    res = simulate(RigidBlock(b=b, h=h), 0.0, t1 + 0.5, phi_0=0.2, tolerance=TOL, output_interval=0.01)
    assert len(res.impact_times) == 1 and res.impact_times[0] == pytest.approx(t1, abs=1e-9)
    after = res.t > t1
    assert np.all(res.contact[after] == FULL) and np.all(res.phi[after] == 0.0)
    assert np.all(res.phi_dot[after] == 0.0)


# ---------------------------------------------------------------------------------------------- uplift
@pytest.mark.parametrize("scheme", ["event_driven", "moreau_jean"])
@pytest.mark.parametrize("ag_v", [0.0, 3.0, -4.0])
@pytest.mark.parametrize("sign", [1.0, -1.0])
@pytest.mark.parametrize("factor", [0.98, 1.02])
def test_rigid_uplift_threshold_is_tan_alpha_times_g_plus_ag_v(factor, sign, ag_v, scheme):
    """A constant ag = +-factor tan(alpha) (g + ag_v) from rest: 2 % below, the block stays in full contact
    with phi = 0 exactly; 2 % above, it uplifts at once on the corner that ag drives (ag > 0: left pivot,
    phi > 0)."""
    b, h = 0.25, 1.0
    ag = sign * factor * (b / h) * (G + ag_v)
    res = simulate(RigidBlock(b=b, h=h), ag, 0.3, ag_v=ag_v, scheme=scheme, output_interval=0.01)
    if factor < 1.0:
        assert np.all(res.phi == 0.0) and np.all(res.contact == FULL)
    else:
        assert res.contact[1] == (LEFT if sign > 0 else RIGHT)
        assert np.all(sign * res.phi[1:] > 0.0) and sign * res.phi[-1] > 1e-4


@pytest.mark.parametrize("ag_v", [0.0, -3.0])
def test_rigid_uplift_time_under_a_ramp(ag_v):
    """ag(t) = k t reaches tan(alpha) (g + ag_v) at t* = tan(alpha) (g + ag_v)/k: the contact output leaves
    full contact in the output interval (1e-4 s, 0.05 % of t*) that contains t*."""
    b, h, k = 0.2, 1.0, 10.0
    t_star = (b / h) * (G + ag_v) / k
    dt = 1e-4
    res = simulate(RigidBlock(b=b, h=h), lambda t: k * t, 1.1 * t_star, ag_v=ag_v, tolerance=1e-10,
                   output_interval=dt)
    first = res.t[np.argmax(res.contact != FULL)]
    assert t_star <= first <= t_star + dt + 1e-12, (first, t_star)
    assert np.all(res.phi[res.t < t_star] == 0.0)


# ---------------------------------------------------------------------------------------------- Shenton
def rocking_friction_demand(tan_alpha, A):
    """Shenton's (1996) tangential/normal force ratio at the pivot of a block that starts to rock under a
    constant ag = A g (A > tan(alpha)): with phi_ddot = (3/(4 R^2)) (ag h - g b) the pivot forces are
    lambda_T = m (ag - h phi_ddot) and lambda_N = m (g + b phi_ddot)."""
    c2 = 1.0 / (1.0 + tan_alpha ** 2)               # cos^2(alpha)
    sc = tan_alpha * c2                              # sin(alpha) cos(alpha)
    return (A - 0.75 * c2 * (A - tan_alpha)) / (1.0 + 0.75 * sc * (A - tan_alpha))


@pytest.mark.parametrize("scheme", ["event_driven", "moreau_jean"])
@pytest.mark.parametrize("mu, A, regime", [
    (0.7, 0.45, "rest"),        # below mu g and below g tan(alpha)
    (0.3, 0.40, "slide"),       # mu < tan(alpha): slides at |ag| > mu g
    (0.3, 0.80, "slide"),       # mu < tan(alpha), above both thresholds: still slides, no rocking
    (0.7, 0.60, "rock"),        # mu > tan(alpha) and mu > the rocking demand (0.52): rocks on a sticking pivot
    (0.55, 1.20, "slide-rock"),  # tan(alpha) < mu < the rocking demand (0.64): the pivot slides as it rocks
    (0.75, 1.20, "rock"),       # the same ag with mu above that demand: rocks on a sticking pivot
])
def test_shenton_initiation_from_rest(mu, A, regime, scheme):
    """The first mode under a constant ag = A g from rest (tan(alpha) = 0.5), after Shenton (1996):
    rest if A < min(mu, tan(alpha)); slide if mu < tan(alpha) < ... and A > mu; rock if A > tan(alpha) and
    mu exceeds the pivot's friction demand of rocking; slide-rock if tan(alpha) < mu < that demand. Sliding is
    towards -x (the ground pushes the base towards +x, inertia pulls the block back)."""
    b, h = 0.25, 0.5
    t = b / h
    demand = rocking_friction_demand(t, A)
    # the scene's regime, derived from the criteria (and far from each boundary)
    if A < min(mu, t):
        derived = "rest"
    elif mu < t:
        derived = "slide"
    else:
        derived = "rock" if mu > demand else "slide-rock"
    assert derived == regime and abs(mu - demand) > 0.04 and abs(A - mu) > 0.04 and abs(A - t) > 0.04
    kw = {"dt_max": 1e-4} if scheme == "moreau_jean" else {}
    res = simulate(RigidBlock(b=b, h=h, mu=mu), A * G, 0.02, scheme=scheme, output_interval=1e-3, **kw)
    expected = {"rest": FULL, "slide": FULL_SLIDE_NEG, "rock": LEFT, "slide-rock": LEFT_SLIDE_NEG}[regime]
    assert np.all(res.contact[2:] == expected), res.contact
    if regime in ("rest", "slide"):
        assert np.all(res.phi == 0.0)
    if regime in ("rest", "rock"):
        # a sticking pivot: the lower corner does not move along the ground
        assert np.max(np.abs(res.slip)) < (1e-12 if scheme == "event_driven" else 1e-7)


# ---------------------------------------------------------------------------------------------- flight, sliding
@pytest.mark.parametrize("scheme", ["event_driven", "moreau_jean"])
def test_flight_is_a_parabola_with_constant_spin(scheme):
    """With g + ag_v < 0 a block released on its left corner (phi_0, phi_dot_0) flies at once: relative to the
    ground x = x0 + vx0 t - ag t^2/2, y = y0 + vy0 t - (g + ag_v) t^2/2, phi = phi_0 + phi_dot_0 t, with
    (x0, y0, vx0, vy0) the centroid's state when rotating about the corner (-b, 0); to 1e-11 (both
    schemes integrate a constant acceleration exactly)."""
    b, h, phi0, w0, ag, ag_v = 0.2, 1.0, 0.05, 0.3, 1.0, -1.5 * G
    s, c = math.sin(phi0), math.cos(phi0)
    x0, y0 = b * (c - 1.0) - h * s, b * s + h * c - h
    vx0, vy0 = w0 * (-b * s - h * c), w0 * (b * c - h * s)
    res = simulate(RigidBlock(b=b, h=h), ag, 0.3, ag_v=ag_v, scheme=scheme, phi_0=phi0, phi_dot_0=w0,
                   output_interval=0.01)
    t = res.t
    np.testing.assert_allclose(res.x, x0 + vx0 * t - 0.5 * ag * t ** 2, rtol=0, atol=1e-11)
    np.testing.assert_allclose(res.y, y0 + vy0 * t - 0.5 * (G + ag_v) * t ** 2, rtol=0, atol=1e-11)
    np.testing.assert_allclose(res.phi, phi0 + w0 * t, rtol=0, atol=1e-11)
    np.testing.assert_allclose(res.phi_dot, w0, rtol=0, atol=1e-11)
    np.testing.assert_allclose(res.y_dot, vy0 - (G + ag_v) * t, rtol=0, atol=1e-11)
    assert np.all(res.contact[1:] == FLIGHT)


@pytest.mark.parametrize("scheme", ["event_driven", "moreau_jean"])
@pytest.mark.parametrize("ag, ag_v", [(5.0, 0.0), (-4.0, 0.0), (5.0, 2.0)])
def test_sliding_velocity_grows_at_ag_minus_mu_g(ag, ag_v, scheme):
    """A square block (tan(alpha) = 1 > mu = 0.3) under constant |ag| > mu (g + ag_v) slides in full contact,
    against the ground's push: x_dot(t) = -sign(ag) (|ag| - mu (g + ag_v)) t relative to the ground, x the
    integral of it, and slip = x (the base does not rotate); to 1e-10 relative."""
    mu = 0.3
    rate = abs(ag) - mu * (G + ag_v)
    res = simulate(RigidBlock(b=0.5, h=0.5, mu=mu), ag, 1.0, ag_v=ag_v, scheme=scheme, output_interval=0.05)
    sign = math.copysign(1.0, ag)
    np.testing.assert_allclose(res.x_dot, -sign * rate * res.t, rtol=1e-10, atol=1e-13)
    np.testing.assert_allclose(res.x, -0.5 * sign * rate * res.t ** 2, rtol=1e-10, atol=1e-13)
    np.testing.assert_allclose(res.slip, res.x, rtol=0, atol=1e-14)
    assert np.all(res.phi == 0.0)
    assert np.all(res.contact[1:] == (FULL_SLIDE_NEG if ag > 0 else FULL_SLIDE_POS))


# ---------------------------------------------------------------------------------------------- flexible oscillator
def flexible_constants(f: FlexibleOscillator) -> dict:
    """The mass moments of the appendix (Eqs. 49, 55), recomputed from the parameters."""
    m, m_c, h = f.m, f.m_c, f.h
    mt = m + 33.0 / 140.0 * m_c
    C = (m + 11.0 / 40.0 * m_c) * h
    J0 = f.m_b * f.rho ** 2 + m * h * h + m_c * h * h / 3.0
    return dict(mt=mt, kt=3.0 * f.EI / h ** 3, Mt=m + f.m_b + m_c, D=m + 3.0 / 8.0 * m_c,
                A_h=(m + 0.5 * m_c) * h, C=C, J0=J0, J_eff=J0 - C * C / mt)


@pytest.mark.parametrize("ag_v", [0.0, 2.5])
@pytest.mark.parametrize("sign", [1.0, -1.0])
@pytest.mark.parametrize("factor", [0.98, 1.02])
def test_flexible_uplift_threshold_from_a_deflection(factor, sign, ag_v):
    """Full contact (Eq. 55 at phi = 0 with x = y = 0 held) gives, from the phi and y rows,
    b (lambda_R - lambda_L) = Q = -C u_ddot - A_h ag + (g + ag_v) D u and lambda_L + lambda_R = M_t (g + ag_v):
    the left corner lifts when Q > b M_t (g + ag_v). Released from rest at u_0 with ag = 0 and no damping,
    u_ddot = -k u/m_tilde and |u| <= |u_0| for ever, so Q = u (C k/m_tilde + (g + ag_v) D) never exceeds
    its initial value: 2 % below the threshold it never uplifts, 2 % above it uplifts at once, pivoting on
    the right corner (phi < 0) for u_0 > 0, briefly."""
    f = FlexibleOscillator(zeta=0.0)
    k = flexible_constants(f)
    ge = G + ag_v
    u_up = f.b * k["Mt"] * ge / (k["C"] * k["kt"] / k["mt"] + ge * k["D"])
    res = simulate(f, 0.0, 0.5, ag_v=ag_v, u_0=sign * factor * u_up, output_interval=0.005)
    if factor < 1.0:
        assert np.all(res.contact == FULL) and np.all(res.phi == 0.0)
        assert np.max(np.abs(res.u)) <= factor * u_up * (1.0 + 1e-9)
    else:
        assert res.contact[1] == (RIGHT if sign > 0 else LEFT)
        assert sign * res.phi[1] < 0.0      # (u swings back within ~0.02 s: the base lands again)


@pytest.mark.parametrize("sign", [1.0, -1.0])
@pytest.mark.parametrize("factor", [0.98, 1.02])
def test_flexible_uplift_threshold_under_constant_ag(factor, sign):
    """Started at the static deflection of a constant ag, u_0 = -D ag/k (u_ddot = 0, and it stays there while
    the base is down), Q = -ag (A_h + g D^2/k): uplift iff |ag| > b M_t g/(A_h + g D^2/k), on the corner
    that ag drives (ag > 0: left pivot, phi > 0)."""
    f = FlexibleOscillator()
    k = flexible_constants(f)
    ag_star = f.b * k["Mt"] * G / (k["A_h"] + G * k["D"] ** 2 / k["kt"])
    ag = sign * factor * ag_star
    res = simulate(f, ag, 0.5, u_0=-k["D"] * ag / k["kt"], output_interval=0.005)
    if factor < 1.0:
        assert np.all(res.contact == FULL) and np.all(res.phi == 0.0)
        # the static deflection held: to the scheme's accuracy (its tolerance 1e-8 scales u's error by the
        # length scale, 1.5 m), not to round-off, as the rhs there is zero only to round-off
        np.testing.assert_allclose(res.u, -k["D"] * ag / k["kt"], rtol=0, atol=1e-10)
    else:
        assert res.contact[1] == (LEFT if sign > 0 else RIGHT)
        assert np.all(sign * res.phi[1:] > 0.0)


def states_around_first_impact(f, delta, **initial):
    """Outputs at t_imp - delta and t_imp + delta of the first impact of a free-rocking run [s]."""
    sim = Simulator(f, "event_driven", tolerance=TOL, **initial)
    sim.advance(3.0, 0.0)
    t_imp = sim.impact_times[0]
    sim = Simulator(f, "event_driven", tolerance=TOL, **initial)
    sim.advance(t_imp - delta, 0.0)
    before = sim.outputs()
    sim.advance(t_imp + delta, 0.0)
    return before, sim.outputs()


def test_flexible_impact_with_immediate_rocking():
    """A base heavy in rotation (m_b rho^2 > M_t b^2 - ... so that u* = 0) rocking on its left corner hits
    with the right one: the paper's immediate rocking, with (docs/physics.md, flexible impact)
    phi_dot+/phi_dot- = 1 - 2 (M_t b^2 - s_n b D u)/(J_eff + m_tilde u^2 - 2 s_n b D u + M_t b^2), s_n = +1,
    and the u row taking no impulse: m_tilde (u_dot+ - u_dot-) = C (phi_dot+ - phi_dot-). Compared 1e-9 s
    either side of the impact: 1e-7 relative."""
    f = FlexibleOscillator(m=1.0, m_c=0.0, m_b=1.0, rho=0.4, h=1.0, b=0.2, EI=400.0 / 3.0, zeta=0.0)
    k = flexible_constants(f)
    assert k["Mt"] * f.b ** 2 < k["J_eff"]                       # u* = 0: no full-contact regime
    before, after = states_around_first_impact(f, 1e-9, phi_0=0.05, u_0=0.01)
    u, w = before["u"], before["phi_dot"]
    assert w < 0.0 and abs(after["u"] - u) < 1e-8
    N_n = k["J_eff"] + k["mt"] * u * u - 2.0 * f.b * k["D"] * u + k["Mt"] * f.b ** 2
    ratio = 1.0 - 2.0 * (k["Mt"] * f.b ** 2 - f.b * k["D"] * u) / N_n
    assert after["contact"] == RIGHT
    assert after["phi_dot"] / w == pytest.approx(ratio, rel=1e-7)
    expected_ud = before["u_dot"] + k["C"] / k["mt"] * (after["phi_dot"] - w)
    assert after["u_dot"] == pytest.approx(expected_ud, rel=1e-7, abs=1e-9)


def test_flexible_impact_to_full_contact_jumps_the_flexural_velocity():
    """|u| < u* with e_N = 0 (the default specimen: u* = 0.27 m): both corners take impulse, phi_dot+ = 0,
    y_dot+ = 0 and u_dot+ = u_dot- - (C/m_tilde) phi_dot- (the top mass nearly keeps its horizontal
    velocity: the paper's jump of the flexural velocity). 1e-9 s either side of the impact: 1e-6 relative."""
    f = FlexibleOscillator(zeta=0.0)
    k = flexible_constants(f)
    u_star = math.sqrt((k["Mt"] * f.b ** 2 - k["J_eff"]) / k["mt"])
    before, after = states_around_first_impact(f, 1e-9, phi_0=0.03)
    w = before["phi_dot"]
    assert abs(before["u"]) < 0.05 * u_star and w < -0.1
    expected_ud = before["u_dot"] - k["C"] / k["mt"] * w
    assert after["u_dot"] == pytest.approx(expected_ud, rel=1e-6)
    assert abs(after["phi_dot"]) < 1e-6 * abs(w) and abs(after["y_dot"]) < 1e-6 * abs(w)
