"""The Zeno rule and the Painleve count of the event-driven scheme.

Zeno rule (docs/guide/schemes.md, "Impact accumulation (Zeno)"; `ContactTolerances`): after an impact a corner at the ground is
closed plastically if (velocity test) it leaves slower than v_Zeno = zeno_tol sqrt(g L), or (bounce test, only
while every corner leaves in free flight and none is closed) its free-flight bounce U+^2 / (2 |a_N|) stays
within gap = 1e-9 L of the ground, i.e. U+ < sqrt(2 |a_N| 1e-9 L) ~ 44.7 v_Zeno at |a_N| = g and the default
zeno_tol. Before this rule the bounce test ran on both corners of a rocking impact with the free-flight
acceleration -g, so the old pivot, which rotates about the new one (its normal acceleration some 2 b p^2
sin(alpha), 17 times smaller than g here), was closed at up to 44.7 v_Zeno and micro-rocking ended early.

Painleve: a sliding corner whose sliding Delassus a_sigma = W_N M^-1 (W_N - sigma mu W_T) is <= 0 cannot stay
on the ground sliding; the tangential impulse that makes it stick (impact without collision, Genot & Brogliato
1999) is counted in ``painleve``, whether the uplift LCP meets the paradox or an impact LCP resolves it.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from rocking_model import RigidBlock, Simulator, simulate
from rocking_model.ground_motion import RectangularPulse
from rocking_model.modes import Mode
from rocking_model.tolerances import DEFAULT_TOLERANCES

G = 9.81
B, H = 0.2, 1.0
R = math.hypot(B, H)
ALPHA = math.atan2(B, H)
P2 = 3.0 * G / (4.0 * R)
#: Housner's coefficient: the plastic rocking impact (angular momentum about the new pivot)
R_HOUSNER = 1.0 - 1.5 * math.sin(ALPHA) ** 2
V_ZENO = 1e-6 * math.sqrt(G * R)                       # default zeno_tol
#: the bounce test's threshold in free flight (|a_N| = g): U+ below it rises less than 1e-9 L
U_BOUNCE = math.sqrt(2.0 * G * DEFAULT_TOLERANCES.gap * R)


# ============================================================================================== Zeno rule
def test_bounce_threshold_is_45_v_zeno():
    """The figure quoted in docs/guide/schemes.md and in `rocking_model.tolerances`: sqrt(2 g 1e-9 L) / (1e-6 sqrt(g L)),
    with the defaults that every entry point shares."""
    import inspect

    from rocking_model.integrators.base import SolverOptions
    from rocking_model.tolerances import ZENO_TOL
    assert ZENO_TOL == 1e-6 == SolverOptions().zeno_tol
    assert inspect.signature(Simulator.__init__).parameters["zeno_tol"].default == ZENO_TOL
    assert U_BOUNCE / V_ZENO == pytest.approx(math.sqrt(2e-9) / 1e-6) == pytest.approx(44.72, abs=0.01)


def _rocking_impact(phi_dot, e_N=0.2):
    """A block rocking on its left corner at phi = 1e-14 rad towards phi = 0 with rate phi_dot < 0: its right
    corner hits the ground within 3 ns. Returns (mode, impacts, U_N of the left and right corners) at 0.1 us
    (gravity changes the rocking speed by p^2 sin(alpha) 0.1 us = 1.4e-7 rad/s by then, 0.02 v_Zeno)."""
    block = RigidBlock(b=B, h=H, e_N=e_N)
    sim = Simulator(block, "event_driven", phi_0=1e-14, phi_dot_0=phi_dot, on_report="raise")
    assert sim.outputs()["contact"] == Mode.LEFT
    sim.advance(1e-7, 0.0)
    q, v = sim.state()
    U_N = block.contact_jacobians(q)[0].T @ v
    return Mode(sim.outputs()["contact"]), sim.outputs()["impacts"], U_N


@pytest.mark.parametrize("k, mode", [(0.5, Mode.FULL), (3.0, Mode.RIGHT), (10.0, Mode.RIGHT), (100.0, Mode.RIGHT)])
def test_velocity_test_closes_only_below_v_zeno(k, mode):
    """Rocking impact, e_N = 0.2: the impacting corner's bounce (e_N U-, below U_BOUNCE in every case) is closed
    by the bounce test, the block rocks on about the new pivot and the old pivot leaves at
    U+ = 2 b r |phi_dot-| = k v_Zeno. Only the velocity test may close it: below v_Zeno (k = 0.5: full contact),
    not at 3, 10 or 100 v_Zeno (k = 10 went to full contact under the old rule: both corners were tested for a
    free-flight bounce, sqrt(2 g 1e-9 L) = 44.7 v_Zeno)."""
    phi_dot = -k * V_ZENO / (2.0 * B * R_HOUSNER)
    assert 0.2 * 2.0 * B * abs(phi_dot) < 0.5 * U_BOUNCE          # the bounce is closed in every case
    got, impacts, U_N = _rocking_impact(phi_dot)
    assert got == mode
    if mode == Mode.RIGHT:
        assert U_N[0] == pytest.approx(k * V_ZENO, abs=0.05 * V_ZENO) and abs(U_N[1]) < 1e-12
        assert impacts == 1                     # the right corner hit at k / r v_Zeno > v_Zeno
    else:
        assert np.all(np.abs(U_N) < 1e-15)
        assert impacts == 0                     # slower than v_Zeno: not counted


@pytest.mark.parametrize("f, mode", [(0.5, Mode.RIGHT), (3.0, Mode.FLIGHT)])
def test_bounce_test_closes_only_a_free_flight_bounce_within_gap(f, mode):
    """Rocking impact, e_N = 0.2, fast enough that every corner leaves (flight): the impacting corner bounces at
    e_N U- = f U_BOUNCE, the old pivot at about 5.6 times that. f = 0.5: the bounce would rise 0.25e-9 L, the
    corner is closed and the block rocks about it; f = 3 (9e-9 L): it bounces, the block flies."""
    phi_dot = -f * U_BOUNCE / (0.2 * 2.0 * B)
    got, impacts, U_N = _rocking_impact(phi_dot)
    assert got == mode and impacts == 1
    if mode == Mode.FLIGHT:
        assert U_N[1] == pytest.approx(f * U_BOUNCE, rel=0.01)     # (gravity: -1e-6 m/s by 0.1 us)


def _housner_reference(A, duration, e_N, t_max, all_closed=True):
    """Exact rigid rocking of the b = 0.2, h = 1 block under ag = A for 0 < t <= duration, then 0, from rest:
    Housner's nonlinear equations between impacts (solve_ivp, DOP853 at rtol 1e-13, impacts located as
    events) and Housner's plastic coefficient r at every impact. That is the impact law of the rigid model
    where the impacting corner bounces at e_N U- below U_BOUNCE (``all_closed``: checked at every impact), a
    bounce the Zeno rule closes; faster impacts send the rigid model into short flights that this reference
    leaves out. Returns (phi(t) callable, impact times, post-impact speed of the leaving corner
    2 b r |phi_dot-|)."""
    def rhs(t, y, ag, s):                   # s = +1: left pivot (phi > 0), -1: right pivot
        phi, w = y
        return [w, P2 * ((ag / G) * math.cos(ALPHA - s * phi) - s * math.sin(ALPHA - s * phi))]

    def hit(t, y, ag, s):
        return y[0]
    hit.terminal = True
    tol = dict(method="DOP853", rtol=1e-13, atol=1e-22, dense_output=True)
    first = solve_ivp(rhs, (0.0, duration), [0.0, 0.0], args=(A, 1), **tol)
    segments = [(0.0, duration, first.sol)]
    t, y, s = duration, first.y[:, -1], 1
    times, speeds = [], []
    while True:
        hit.direction = -s
        seg = solve_ivp(rhs, (t, t_max), y, args=(0.0, s), events=hit, **tol)
        te, w = seg.t_events[0][0], seg.y_events[0][0][1]
        assert e_N * 2.0 * B * abs(w) < U_BOUNCE or not all_closed
        segments.append((t, te, seg.sol))
        times.append(te)
        speeds.append(2.0 * B * R_HOUSNER * abs(w))
        t, y, s = te, np.array([0.0, R_HOUSNER * w]), -s
        if speeds[-1] < 1e-2 * V_ZENO:
            break

    def phi(tt):
        for a, b, sol in segments:
            if a <= tt <= b:
                return float(sol(tt)[0])
        return 0.0
    return phi, np.array(times), np.array(speeds)


@pytest.mark.parametrize("duration, amplitude, old_switch", [(0.01, 3.6e-7, 0.0269), (0.0673, 1.6e-5, 0.2214)])
def test_grazing_micro_rocking_follows_the_exact_solution(duration, amplitude, old_switch):
    """Grazing scenes: ag = 1.005 g tan(alpha) held for 10 ms (67.3 ms), e_N = 0.2: the block lifts by 3.6e-7 rad
    (1.6e-5 rad) and rocks down in an accumulation of about 80 (140) impacts. The event-driven scheme follows
    the exact solution (Housner's equations and coefficient, `_housner_reference`, its own solver) to 1e-3 of
    the amplitude (measured 1.2e-11 rad; 2.1e-9 rad where the first impacts of the longer pulse fly, which the
    reference leaves out) until the Zeno rule ends the accumulation where it says: at the impact whose leaving
    corner is slower than v_Zeno (at 0.0337 s; 0.2283 s). Under the old rule it switched to full contact at
    0.0269 s (0.2214 s), at 36-44.7 v_Zeno (the bounce test run on the old pivot)."""
    A = 1.005 * G * math.tan(ALPHA)
    phi_ref, times, speeds = _housner_reference(A, duration, 0.2, 1.0, all_closed=duration < 0.02)
    res = simulate(RigidBlock(b=B, h=H, e_N=0.2), RectangularPulse(A, duration), times[-1] + 2e-3,
                   scheme="event_driven", tolerance=1e-10, output_interval=1e-5 if duration < 0.02 else 1e-4)
    peak = np.max(np.abs(res.phi))
    assert peak == pytest.approx(amplitude, rel=0.05)
    err = max(abs(p - phi_ref(t)) for t, p in zip(res.t, res.phi))
    assert err < 1e-3 * peak, err
    full = res.t[(res.contact == Mode.FULL) & (res.t > duration)]
    t_switch = full[0]
    assert np.all(res.contact[res.t >= t_switch] == Mode.FULL)
    # between the exact impacts whose leaving corner is at 1.5 and at 0.67 v_Zeno (13 impacts apart)
    t_a = times[np.argmax(speeds < 1.5 * V_ZENO)]
    t_b = times[np.argmax(speeds < 0.67 * V_ZENO)]
    assert t_a - 1e-4 <= t_switch <= t_b + 1e-4
    # well past the impacts that the old rule ended on (leaving corner below 44.7 v_Zeno)
    assert t_switch > times[np.argmax(speeds < U_BOUNCE)] + 5e-3 and t_switch > old_switch + 5e-3


# ============================================================================================== Painleve
PHI_P = -0.59       #: right pivot tilted beyond alpha (theta = alpha + phi = -0.393 rad)


def _independent_delassus(phi, m=1.0):
    """(W_N, W_T, M^-1) of the right corner (physics.md, section 2), written out here, not the model's."""
    W_N = np.array([0.0, 1.0, B * math.cos(phi) + H * math.sin(phi)])
    W_T = np.array([1.0, 0.0, -B * math.sin(phi) + H * math.cos(phi)])
    Minv = np.diag([1.0 / m, 1.0 / m, 3.0 / (m * R ** 2)])
    return W_N, W_T, Minv


def critical_mu(phi):
    """Critical mu of the right corner sliding towards -x (sigma = -1): a_sigma = a + mu c < 0 for mu > -a/c,
    a = W_N M^-1 W_N = (1 + 3 sin^2(theta))/m, c = W_N M^-1 W_T = 3 sin(theta) cos(theta)/m, theta = alpha + phi."""
    W_N, W_T, Minv = _independent_delassus(phi)
    return -(W_N @ Minv @ W_N) / (W_N @ Minv @ W_T)


def test_critical_mu_of_the_scene():
    """b = 0.2, h = 1 at phi = -0.59: critical mu 1.357 (about 1.36; 1.35 at phi = -0.6, the minimum 4/3 at
    tan(theta) = 1/2 for any rectangle), so mu = 1.45 and 2 are above it, 1.2 below."""
    theta = ALPHA + PHI_P
    closed = (1 + 3 * math.sin(theta) ** 2) / (-3 * math.sin(theta) * math.cos(theta))
    assert critical_mu(PHI_P) == pytest.approx(closed, rel=1e-12) == pytest.approx(1.357, abs=1e-3)
    # the figure of docs/guide/contact-laws.md: at least 4/3, reached at tan(theta) = 1/2 (phi = -alpha - atan(1/2) = -0.661 rad)
    phis = np.linspace(-1.5, -ALPHA - 0.01, 3001)
    assert min(critical_mu(p) for p in phis) == pytest.approx(4.0 / 3.0, rel=1e-6)
    assert critical_mu(-ALPHA - math.atan(0.5)) == pytest.approx(4.0 / 3.0, rel=1e-12)


def _landing(mu, U_N, gap):
    """The block in flight at phi = -0.59 without rotation, its right corner ``gap`` above the ground, moving
    towards -x at 1 m/s and down at U_N: it lands on that corner while sliding. Returns (sim, v_minus at the
    corner's touch-down, state just after)."""
    block = RigidBlock(b=B, h=H, mu=mu)
    sim = Simulator(block, "event_driven", phi_0=PHI_P, on_report="raise")
    y = H * math.cos(PHI_P) - B * math.sin(PHI_P) + gap
    state = sim.get_state()
    state.update(mode=int(Mode.FLIGHT), y=[0.0, y, PHI_P, -1.0, U_N, 0.0])
    sim.set_state(state)
    # touch-down time and velocity of the free fall (no rotation: phi stays PHI_P)
    t_hit = (U_N + math.sqrt(U_N ** 2 + 2.0 * G * gap)) / G
    v_minus = np.array([-1.0, U_N - G * t_hit, 0.0])
    sim.advance(t_hit * 1.5, 0.0)
    return sim, v_minus


@pytest.mark.parametrize("U_N, gap, collides", [(-1e-6, 1e-15, False), (-1e-6, 1e-9, True)],
                         ids=["no-collision", "slow-collision"])
@pytest.mark.parametrize("mu", [1.2, 1.45, 2.0])
def test_painleve_landing_is_counted(mu, U_N, gap, collides):
    """A corner sliding at 1 m/s touches down at phi = -0.59, without collision (1e-6 m/s, 0.3 v_Zeno) or with a
    slow one (1.4e-4 m/s, counted in ``impacts``). Independent solution (the corner's 2 x 2 Delassus block
    from physics.md): with mu above the critical 1.357 a sliding impact needs P_N = -U_N- / a_sigma < 0, so the
    corner must stick, by a tangential percussion of about a |U_T-| / (a d - c^2) = 0.66 m|U_T-|, thousands of
    times what the collision needs; the scheme reaches that state and counts it in ``painleve`` (it stayed 0
    under the old rule: the impact LCP stuck the corner uncounted). Below the critical mu the corner keeps
    sliding (P_N >= 0), nothing is counted."""
    sim, v_minus = _landing(mu, U_N, gap)
    out = sim.outputs()
    W_N, W_T, Minv = _independent_delassus(PHI_P)
    a, c, d = W_N @ Minv @ W_N, W_N @ Minv @ W_T, W_T @ Minv @ W_T
    U_Nm, U_Tm = W_N @ v_minus, W_T @ v_minus
    assert U_Tm == pytest.approx(-1.0 + W_T[2] * 0.0) and (abs(U_Nm) > V_ZENO) == collides
    a_sigma = a + mu * c                                   # sigma = -1
    assert out["impacts"] == int(collides) and not sim.last_reports
    if mu < critical_mu(PHI_P):
        assert a_sigma > 0.0 and -U_Nm / a_sigma > 0.0    # it can slide through the impact
        assert out["painleve"] == 0 and out["contact"] == Mode.RIGHT_SLIDE_NEG
        return
    assert a_sigma < 0.0 and -U_Nm / a_sigma < 0.0        # sliding needs a pulling contact: it must stick
    P_N, P_T = np.linalg.solve([[a, c], [c, d]], [-U_Nm, -U_Tm])   # e_N = 0: U_N+ = 0, U_T+ = 0
    assert P_N > 0.0 and abs(P_T) <= mu * P_N and P_T > 1000.0 * abs(U_Nm)
    v_plus = v_minus + Minv @ (W_N * P_N + W_T * P_T)
    assert out["painleve"] == 1 and out["contact"] == Mode.RIGHT
    _, v = sim.state()
    # the same state (1.5 x t_hit later: gravity and the rocking moved it by at most g t_hit)
    np.testing.assert_allclose(v, v_plus, rtol=0, atol=2.0 * G * 1.5e-5 + 1e-9)


@pytest.mark.parametrize("mu, counted", [(1.2, 0), (1.45, 1), (2.0, 1)])
def test_painleve_while_sliding_is_counted(mu, counted):
    """The uplift-LCP path: the block set sliding on its right corner at phi = -0.59 (towards -x at 1 m/s). Above
    the critical mu no acceleration is consistent: the stick-making impulse is applied and counted once;
    below it the corner slides on."""
    block = RigidBlock(b=B, h=H, mu=mu)
    sim = Simulator(block, "event_driven", phi_0=PHI_P, on_report="raise")
    state = sim.get_state()
    state.update(mode=int(Mode.RIGHT_SLIDE_NEG), y=[PHI_P, 0.0, 0.0, -1.0])
    sim.set_state(state)
    e0 = block.energy(*sim.state())
    sim.advance(1e-6, 0.0)
    out = sim.outputs()
    assert out["painleve"] == counted and not sim.last_reports
    if counted:
        assert out["contact"] == Mode.RIGHT and block.energy(*sim.state()) < e0 - 0.1
    else:
        assert out["contact"] == Mode.RIGHT_SLIDE_NEG
    sim.advance(0.3, 0.0)
    assert sim.outputs()["painleve"] == counted and min(block.gaps(sim.state()[0])) > -1e-12
