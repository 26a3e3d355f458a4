"""Closed-form impact of the flexible rocking oscillator: the Delassus matrix, the outcome boundary u*, the classical
rule and the input checks."""
from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from rocking_model.models.flexible_oscillator import FlexibleOscillator
from rocking_model.modes import Mode
from rocking_model.post_impact import Outcome, analytical_impact, classical_impact, impact_delassus

MODELS = {
    "default": dict(),                                                         # u* = 0.27 m
    "small_u_star": dict(m=1.0, m_c=0.5, m_b=2.0, rho=0.255, h=1.0, b=0.2, EI=20.0, zeta=0.02),
    "lumped": dict(m=1.0, m_c=0.0, m_b=0.5, rho=0.2, h=1.5, b=0.3, EI=10.0, zeta=0.0),
    "no_u_star": dict(m=1.0, m_c=0.5, m_b=3.0, rho=0.5, h=1.0, b=0.1, EI=20.0),  # M_t b^2 < J_eff
}
PIVOTS = ((Mode.LEFT, -1.0), (Mode.RIGHT, 1.0))        # pivot and the sign of an approaching phi_dot


def _u_grid(model):
    us = model.u_star
    if us == 0.0:
        return [-0.3, -0.01, 0.0, 0.02, 0.5]
    return [f * us for f in (-3.0, -1.5, -1.03, -0.97, -0.5, 0.0, 0.3, 0.96, 1.04, 2.0)]


def test_u_star_of_the_models():
    assert FlexibleOscillator(**MODELS["small_u_star"]).u_star < 0.05
    assert FlexibleOscillator(**MODELS["no_u_star"]).u_star == 0.0
    assert FlexibleOscillator(**MODELS["lumped"]).u_star > 0.0


@pytest.mark.parametrize("name", MODELS)
def test_delassus_closed_form(name):
    model = FlexibleOscillator(**MODELS[name])
    for u in _u_grid(model):
        M = model.mass_matrix(np.array([u, 0.0, 0.0, 0.0]))
        keep = [0, 2, 3]                                   # x_dot = 0 by sticking
        W = model.contact_jacobians(np.zeros(4))[0][keep]
        G = W.T @ np.linalg.solve(M[np.ix_(keep, keep)], W)
        np.testing.assert_allclose(impact_delassus(model, u), G, rtol=1e-10, atol=1e-12 * np.abs(G).max())
        if model.u_star > 0 and abs(abs(u) - model.u_star) > 1e-9:
            assert (G[0, 1] < 0) == (abs(u) < model.u_star)
        elif model.u_star == 0:
            assert G[0, 1] >= 0


def test_flexural_velocity_jump_lumped_mass():
    """m_c = 0, full contact: u_dot+ = u_dot- - h phi_dot- (the top mass keeps its horizontal velocity)."""
    model = FlexibleOscillator(**MODELS["lumped"])
    for (pivot, sgn), ud in itertools.product(PIVOTS, (-0.3, 0.0, 0.4)):
        w = sgn * 0.6
        u = 0.4 * model.u_star
        assert analytical_impact(model, u, ud, w, pivot, e_N=0.0).v_plus[0] == pytest.approx(ud - model.h * w)
        # every outcome: horizontal velocity of the top mass x_dot + u_dot - h phi_dot is continuous at phi = 0
        for u2, e in itertools.product((0.4 * model.u_star, 2 * model.u_star), (0.0, 0.5)):
            vp = analytical_impact(model, u2, ud, w, pivot, e_N=e).v_plus
            assert vp[1] + vp[0] - model.h * vp[3] == pytest.approx(ud - model.h * w, abs=1e-12)


def test_continuity_at_u_star():
    model = FlexibleOscillator(**MODELS["small_u_star"])
    for e, (pivot, sgn) in itertools.product((0.0, 0.4), PIVOTS):
        below = analytical_impact(model, model.u_star * (1 - 1e-9), 0.1, sgn * 0.5, pivot, e_N=e)
        above = analytical_impact(model, model.u_star * (1 + 1e-9), 0.1, sgn * 0.5, pivot, e_N=e)
        assert below.outcome != above.outcome
        np.testing.assert_allclose(below.v_plus, above.v_plus, atol=1e-7)
        np.testing.assert_allclose(below.P_N, above.P_N, atol=1e-7 * above.P_N.max())


# ---------------------------------------------------------------------- classical rule
def _angular_momentum_about(model, q, v, corner_x, n_gauss=8):
    """Angular momentum about the ground point (corner_x, 0), summed over the top mass, the column
    (Gauss-Legendre quadrature of the positions of Eq. 50) and the base, from the positions directly."""
    u, x, y, phi = q
    ud, xd, yd, w = v
    c, s = math.cos(phi), math.sin(phi)
    h = model.h

    def point(xi, psi, dpsi_dummy=None):
        X = x - xi * s + u * psi * c
        Y = y + xi * c + u * psi * s
        Xd = xd - xi * c * w + ud * psi * c - u * psi * s * w
        Yd = yd - xi * s * w + ud * psi * s + u * psi * c * w
        return (X - corner_x) * Yd - Y * Xd

    H = model.m * point(h, 1.0)
    nodes, weights = np.polynomial.legendre.leggauss(n_gauss)
    for t, wt in zip(nodes, weights):
        xi = h * (t + 1) / 2
        psi = 3 * xi ** 2 / (2 * h ** 2) - xi ** 3 / (2 * h ** 3)
        H += model.m_c / h * point(xi, psi) * wt * h / 2
    H += model.m_b * ((x - corner_x) * yd - y * xd) + model.I_mb * w
    return H


@pytest.mark.parametrize("name", ["default", "small_u_star", "lumped"])
def test_classical_rule(name):
    model = FlexibleOscillator(**MODELS[name])
    for (pivot, sgn), u, ud in itertools.product(PIVOTS, (0.3 * model.u_star, 2.5 * model.u_star, -0.02),
                                                 (0.0, 0.2)):
        w = sgn * 0.4
        corner_x = model.b if pivot == Mode.LEFT else -model.b       # the impacting corner
        q, v_minus = model.embed(pivot, np.array([u, 0.0]), np.array([ud, w]))
        cl = classical_impact(model, u, ud, w, pivot)
        H_minus = _angular_momentum_about(model, q, v_minus, corner_x)
        assert _angular_momentum_about(model, q, cl.v_plus, corner_x) == pytest.approx(H_minus, rel=1e-10)
        assert cl.v_plus[0] == ud and cl.outcome == Outcome.ROCKING_NEW
        W_N, W_T = model.contact_jacobians(q)
        i_n = 1 if pivot == Mode.LEFT else 0
        assert (W_N.T @ cl.v_plus)[i_n] == pytest.approx(0, abs=1e-14)
        # it is not the LCP's answer: it needs a generalized impulse on u
        assert abs(cl.P_u) > 1e-6 * model.C * abs(w)
        exact = analytical_impact(model, u, ud, w, pivot, e_N=0.0)
        assert exact.P_u == 0.0
        assert not np.allclose(cl.v_plus, exact.v_plus)
        if exact.outcome == Outcome.ROCKING_NEW:
            # the consistent rocking solution conserves H about the new corner and the u momentum
            assert _angular_momentum_about(model, q, exact.v_plus, corner_x) == pytest.approx(H_minus, rel=1e-10)
            M = model.mass_matrix(q)
            assert (M @ exact.v_plus)[0] == pytest.approx((M @ v_minus)[0], rel=1e-10, abs=1e-12)


def test_invalid_inputs():
    model = FlexibleOscillator()
    with pytest.raises(ValueError, match="phi_dot_minus"):
        analytical_impact(model, 0.0, 0.0, 0.3, Mode.LEFT)          # separating, not impacting
    with pytest.raises(ValueError, match="phi_dot_minus"):
        classical_impact(model, 0.0, 0.0, -0.3, "right")
    with pytest.raises(ValueError, match="pivot"):
        analytical_impact(model, 0.0, 0.0, -0.3, Mode.FULL)
    with pytest.raises(ValueError, match="e_N"):
        analytical_impact(model, 0.0, 0.0, -0.3, "left", e_N=1.2)
    with pytest.raises(ValueError, match="u"):
        analytical_impact(model, float("nan"), 0.0, -0.3, "left")
