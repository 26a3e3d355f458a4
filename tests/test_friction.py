"""Coulomb friction (issue 15, first part): the frictional contact LCP and the Moreau-Jean scheme with a
finite mu. Closed forms (a sliding block under constant ag, the sliding threshold |ag| = mu g), the initiation
map from rest (slide first for mu < tan(alpha), rock first for mu > tan(alpha); Shenton 1996), mu above the
friction demand gives the mu = inf results, and growing mu converges to the mu = inf motion of an overturning
block without its corner ever sinking (the hole of the sticking law)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from rocking_model import RigidBlock, Simulator, simulate
from rocking_model.lcp import OPEN, SLIDE_NEG, SLIDE_POS, STICK, solve_friction_lcp

G = 9.81


# ---------------------------------------------------------------------------------------------- the LCP
def _point_mass_on_ground(v_free, mu, b_N=0.0):
    """One contact, a unit point mass in the plane: normal = y, tangent = x."""
    W_N = np.array([[0.0], [1.0]])
    W_T = np.array([[1.0], [0.0]])
    return solve_friction_lcp(np.eye(2), W_N, W_T, np.asarray(v_free, float), np.array([b_N]), np.zeros(1),
                              [0], mu)


@pytest.mark.parametrize("vx, state", [(0.3, STICK), (-0.3, STICK), (2.0, SLIDE_POS), (-2.0, SLIDE_NEG)])
def test_friction_lcp_point_mass(vx, state):
    """A point mass landing with U_N = -1 and tangential velocity vx, mu = 0.5, e_N = 0: it sticks when
    |vx| <= mu * 1, else slides with the tangential impulse at the cone's edge."""
    sol = _point_mass_on_ground([vx, -1.0], 0.5)
    assert sol.exact and sol.states == (state,)
    assert sol.P_N[0] == pytest.approx(1.0) and sol.v[1] == pytest.approx(0.0, abs=1e-15)
    if state == STICK:
        assert sol.v[0] == pytest.approx(0.0, abs=1e-15) and abs(sol.P_T[0]) <= 0.5 * sol.P_N[0]
    else:
        assert sol.P_T[0] == pytest.approx(-math.copysign(0.5, vx))
        assert sol.v[0] == pytest.approx(vx - math.copysign(0.5, vx))


def test_friction_lcp_separating_contact_is_open():
    sol = _point_mass_on_ground([5.0, 1.0], 0.5)
    assert sol.exact and sol.states == (OPEN,) and sol.P_N[0] == 0.0 and sol.P_T[0] == 0.0


# ---------------------------------------------------------------------------------------------- closed forms
@pytest.mark.parametrize("dt", [1e-3, 2.5e-4])
@pytest.mark.parametrize("ag", [5.0, -4.0])
def test_sliding_block_under_constant_ag(ag, dt):
    """b = h (tan alpha = 1), mu = 0.3 < |ag|/g < tan(alpha): the block slides without rocking, relative to
    the ground x(t) = 1/2 (-ag + sign(ag) mu g) t^2 (the theta-method is exact for a constant acceleration)."""
    block = RigidBlock(b=0.5, h=0.5, mu=0.3)
    res = simulate(block, ag, 1.0, scheme="moreau_jean", dt_max=dt, output_interval=0.05)
    a_rel = -ag + math.copysign(0.3 * G, ag)
    np.testing.assert_allclose(res.x, 0.5 * a_rel * res.t ** 2, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(res.x_dot, a_rel * res.t, rtol=1e-9, atol=1e-12)
    assert np.all(res.phi == 0.0) and np.all(res.contact == 0)


@pytest.mark.parametrize("factor, slides", [(0.98, False), (1.02, True)])
def test_sliding_threshold_is_mu_g(factor, slides):
    block = RigidBlock(b=0.5, h=0.5, mu=0.4)
    res = simulate(block, factor * 0.4 * G, 1.0, scheme="moreau_jean", output_interval=0.1)
    moved = np.max(np.abs(res.x))
    assert (moved > 1e-3) == slides, moved
    if not slides:
        assert moved < 1e-15


@pytest.mark.parametrize("mu, ag_over_g, first", [
    (0.2, 0.25, "slide"),      # mu < tan(alpha) = 0.5 and mu g < ag < g tan(alpha): slides, does not rock
    (0.8, 0.6, "rock"),        # mu > tan(alpha): rocks at ag > g tan(alpha) = 0.5 g while mu g = 0.8 g holds
    (0.8, 0.45, "rest"),       # below both thresholds
])
def test_initiation_from_rest(mu, ag_over_g, first):
    """Shenton (1996): from rest under a horizontal ag the block slides first if mu < tan(alpha) (at |ag| =
    mu g) and rocks first if mu > tan(alpha) (at |ag| = g tan(alpha)). Here tan(alpha) = 0.5."""
    block = RigidBlock(b=0.25, h=0.5, mu=mu)
    res = simulate(block, ag_over_g * G, 0.3, scheme="moreau_jean", dt_max=1e-4, output_interval=0.01)
    rocked = np.max(np.abs(res.phi)) > 1e-6
    slid = np.max(np.abs(res.x)) > 1e-6 and not rocked
    assert {"slide": slid and not rocked, "rock": rocked, "rest": not rocked and not slid}[first], \
        (np.max(np.abs(res.phi)), np.max(np.abs(res.x)))
    if first == "rock":
        # rocking on a corner that sticks: the pivot does not move horizontally
        q, v = Simulator(block, "moreau_jean", dt_max=1e-4).state()
        assert res.contact[-1] in (1, 2)


def test_mu_above_the_friction_demand_gives_the_sticking_results():
    """A rocking scene whose contacts never need more than about 0.3 of friction: mu = 5 gives the mu = inf
    motion (the friction LCP and the sticking LCP agree to round-off)."""
    kw = dict(scheme="moreau_jean", dt_max=1e-3, output_interval=0.01, phi_0=0.1)
    inf = simulate(RigidBlock(b=0.3, h=1.0), 0.0, 3.0, **kw)
    five = simulate(RigidBlock(b=0.3, h=1.0, mu=5.0), 0.0, 3.0, **kw)
    assert inf.impacts[-1] == five.impacts[-1] >= 3
    np.testing.assert_allclose(five.phi, inf.phi, rtol=0, atol=1e-9)
    np.testing.assert_allclose(five.x, inf.x, rtol=0, atol=1e-9)


def test_growing_mu_converges_to_the_sticking_law_without_its_hole():
    """The one-sine pulse that overturns a slender block (3 m/s2, 1 Hz): with the sticking law the pivot's
    lift-off has no consistent contact state (inexact solves, the corner sinks); with any finite mu the pivot
    slides instead -- no corner below the ground, no inexact solve -- and the base's final x converges to the
    sticking law's as mu grows."""
    t = np.linspace(0.0, 5.0, 501)
    ag = 3.0 * np.sin(2 * np.pi * t) * (t < 1)
    out = {}
    for mu in (1.0, 5.0, 20.0, math.inf):
        sim = Simulator(RigidBlock(b=0.2, h=1.0, mu=mu), "moreau_jean", dt_max=1e-3, on_report="ignore")
        lowest, inexact = 0.0, 0
        for k in range(500):
            sim.advance((k + 1) * 0.01, (t, ag))
            lowest = min(lowest, float(min(sim.model.gaps(sim.state()[0]))))
            inexact += len(sim.last_reports)
        out[mu] = (lowest, inexact, sim.outputs()["x"], sim.outputs()["overturned"])
    for mu in (1.0, 5.0, 20.0):
        assert out[mu][0] > -1e-12 and out[mu][1] == 0 and out[mu][3], out[mu]
    assert out[math.inf][0] < -1e-5 and out[math.inf][1] > 0
    gaps = [abs(out[mu][2] - out[math.inf][2]) for mu in (1.0, 5.0, 20.0)]
    assert gaps[0] > gaps[1] > gaps[2] and gaps[2] < 0.005, gaps


def test_event_driven_refuses_finite_mu_by_name():
    with pytest.raises(ValueError, match=r"mu = 0.5: Coulomb friction is integrated by scheme 'moreau_jean'"):
        Simulator(RigidBlock(mu=0.5), "event_driven")
    with pytest.raises(ValueError, match=r"mu = 0 is out of range; allowed range \(0, inf\]"):
        RigidBlock(mu=0.0)
