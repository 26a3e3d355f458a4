"""The post-tensioned rocking block (`PostTensionedBlock`): the rigid block held by a vertical unbonded tendon from
the ground anchor (0, 0) to the block's top centre, T = max(0, P0 + k_t (L - 2h)) [N], tendon energy
P0 e + k_t e^2/2 with e = L - 2h while taut (constant once slack).

What is checked, against closed forms and an independent reference (tests/reference_models.py, `TendonBlock`:
scipy solve_ivp of the rocking equation with the tendon's moment -T dL/dphi):

1. uplift from rest needs |ag| > tan(alpha) (g + ag_v + P0/m), bracketed at 1 -+ 1e-9 in both schemes;
2. with P0 = k_t = 0 the model is the free `RigidBlock` to round-off;
3. free rocking conserves the energy output (the tendon's included) between impacts;
4. an impact's outcome is the free block's at the same pre-impact state (the tendon transmits no impulse);
5. the tendon_force output is max(0, P0 + k_t (L - 2h)) with L from the outputs x, y, phi, in every mode
   (flight, sliding, sticking on a slid base);
6. a block whose base has slid past its footprint (shift 0.89 m) rocks towards the anchor, the tendon slackens
   and re-tensions: force 0 while slack, energy conserved across both switches, the two schemes agree;
7. the rocking motion against the reference, event-driven to 1e-9 rad, Moreau-Jean at first order;
8. the same outcome 1 ulp off and under other arithmetic kernels (tests/roundoff.py).

Units SI: m, s, kg, rad, N, J.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

import reference_models as ref
import roundoff
from hard_cases import Trace, grid, nominal, roundoff_tests
from rocking_model import ConstantMotion, PostTensionedBlock, RigidBlock, Simulator, SinePulse, simulate
from rocking_model.modes import Mode
from roundoff import Perturbation, scene

G = 9.81
MOD = __name__
#: a 0.6 x 3 m block of 1 t with a tendon pre-stressed to about half its weight (tan(alpha) = 0.2, alpha = 0.197)
BLOCK = dict(b=0.3, h=1.5, m=1000.0)
TENDON = dict(P0=5000.0, k_t=2e5)
TIGHT = 1e-12            # event-driven tolerance of the comparisons with the reference


def make(**kw) -> PostTensionedBlock:
    return PostTensionedBlock(**{**BLOCK, **TENDON, **kw})


def tendon_force_of(model, x, y, phi):
    """T [N] from the centroid's displacement from rest (x, y) and the rotation phi: the top anchor sits at the
    centroid (x, h + y) plus (-h sin phi, h cos phi), the ground anchor at the origin."""
    h = model.h
    L = np.hypot(x - h * np.sin(phi), h + y + h * np.cos(phi))
    return np.maximum(0.0, model.P0 + model.k_t * (L - 2.0 * h))


def uplift_threshold(model, ag_v):
    """|ag| [m/s2] at which the block at rest lifts off: m ag h = (m (g + ag_v) + P0) b, the tendon adding P0 along
    the centreline (at b from either corner) to the weight."""
    return (model.b / model.h) * (model.g + ag_v + model.P0 / model.m)


# ---------------------------------------------------------------------------------------------- 1. uplift
@pytest.mark.parametrize("scheme", ["event_driven", "moreau_jean"])
@pytest.mark.parametrize("ag_v", [0.0, 3.0, -4.0])
@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_uplift_threshold_includes_the_pretension(sign, ag_v, scheme):
    """A constant ag = +-(1 -+ 1e-9) tan(alpha) (g + ag_v + P0/m) from rest: just below, full contact with phi = 0
    exactly; just above, the block uplifts on the corner ag drives, and its rotation is that of the excess
    acceleration, phi(t) = a0 (cosh(sqrt(kappa) t) - 1)/kappa with a0 = m h (ag - threshold)/I_O and the
    linearised stiffness kappa = (m ag b + m (g + ag_v) h - k_t b^2)/I_O (dL/dphi = b, d2L/dphi2 = 0 at phi = 0):
    to 2e-3 (measured: 1.3e-4 event-driven, the cancellation of the moments at 1e-9 of each other; 4.5e-4
    Moreau-Jean, its first-order error)."""
    model = make()
    thr = uplift_threshold(model, ag_v)
    I_O = 4.0 / 3.0 * model.m * (model.b ** 2 + model.h ** 2)
    for excess in (-1e-9, 1e-9):
        ag = sign * (1.0 + excess) * thr
        res = simulate(model, ConstantMotion(ag), 0.3, ag_v=ag_v, scheme=scheme, output_interval=0.05)
        if excess < 0.0:
            assert np.all(res.phi == 0.0) and np.all(res.contact == Mode.FULL)
            assert np.all(res.tendon_force == model.P0)
            continue
        assert np.all(res.contact[1:] == (Mode.LEFT if sign > 0 else Mode.RIGHT))
        a0 = model.m * model.h * excess * thr / I_O
        kappa = (model.m * abs(ag) * model.b + model.m * (G + ag_v) * model.h - model.k_t * model.b ** 2) / I_O
        t = res.t[1:]
        arg = np.sqrt(abs(kappa)) * t
        expected = a0 * ((np.cosh(arg) if kappa > 0 else np.cos(arg)) - 1.0) / kappa
        np.testing.assert_allclose(sign * res.phi[1:], expected, rtol=2e-3, atol=0.0)


# ---------------------------------------------------------------------------------------------- 2. P0 = k_t = 0
#: (ground motion, friction, t_end): a pulse that rocks the free block through 6 impacts (mu = inf), and one whose
#: pivot slides as the block rocks (mu = 0.21, modes 7 and 8; 4 impacts, 0.04 m of slip) and that then rocks on
#: its slid base
FREE_LIMIT_SCENES = {
    "rocking": (SinePulse(4.0, 2.0 * math.pi * 3.0), math.inf, 3.0),
    "sliding": (SinePulse(5.0, 2.0 * math.pi * 2.0), 0.21, 3.0),
}


@pytest.mark.parametrize("scheme", ["event_driven", "moreau_jean"])
@pytest.mark.parametrize("name", sorted(FREE_LIMIT_SCENES))
def test_without_tendon_it_is_the_rigid_block(name, scheme):
    """P0 = k_t = 0: every output common with `RigidBlock` (rotation, centroid, slip, energy, contact mode, impact
    times) equals the rigid block's to round-off (1e-11 of the output's scale; measured below 2e-12), and the
    tendon force is 0 throughout (its slackening switch, identically zero, is no event)."""
    ag, mu, t_end = FREE_LIMIT_SCENES[name]
    kw = dict(BLOCK, mu=mu)
    opts = dict(scheme=scheme, output_interval=0.01)
    rigid = simulate(RigidBlock(**kw), ag, t_end, **opts)
    pt = simulate(PostTensionedBlock(**kw, P0=0.0, k_t=0.0), ag, t_end, **opts)
    assert len(rigid.impact_times) >= (3 if name == "rocking" else 1)
    if name == "sliding":
        assert np.any(rigid.contact >= Mode.FULL_SLIDE_POS) and np.max(np.abs(rigid.slip)) > 0.01
    np.testing.assert_array_equal(pt.contact, rigid.contact)
    np.testing.assert_allclose(pt.impact_times, rigid.impact_times, rtol=0.0, atol=1e-12)
    assert np.all(pt.tendon_force == 0.0)
    for key in ("phi", "phi_dot", "x", "y", "x_dot", "y_dot", "slip", "energy"):
        a, b = np.asarray(rigid[key], float), np.asarray(pt[key], float)
        scale = max(np.max(np.abs(a)), 1e-300)
        assert np.max(np.abs(a - b)) <= 1e-11 * scale, (key, np.max(np.abs(a - b)), scale)


# ---------------------------------------------------------------------------------------------- 3. energy
def test_free_rocking_conserves_the_energy_between_impacts():
    """Released at 0.5 alpha, no ground motion: the energy output (kinetic + gravity + the tendon's
    P0 e + k_t e^2/2) is constant between impacts to the scheme's tolerance, and each impact multiplies it by r^2
    (Housner's r; at phi = 0, where the impacts happen, the potential and the tendon's energy are zero): after
    impact n it is E0 r^(2n). At tolerance 1e-10, 2e-8 of E0 (measured: 3.4e-9 peak to peak within a phase, 3.0e-9
    from E0 r^(2n); 2.7e-9 and 3.5e-9 for the free block; 2e-7 at tolerance 1e-8, 6e-11 at 1e-12)."""
    model = make()
    alpha = math.atan2(model.b, model.h)
    r = 1.0 - 1.5 * math.sin(alpha) ** 2
    res = simulate(model, 0.0, 3.0, phi_0=0.5 * alpha, tolerance=1e-10, output_interval=0.002)
    impacts = np.asarray(res.impact_times)
    assert len(impacts) >= 4
    E0 = res.energy[0]
    assert E0 > 0.01 * model.m * G * model.h
    phase = np.searchsorted(impacts, res.t, side="left")          # number of impacts before each sample
    for n in range(len(impacts) + 1):
        e = res.energy[phase == n]
        assert e.size > 10
        assert np.ptp(e) < 2e-8 * E0, (n, np.ptp(e) / E0)
        assert np.max(np.abs(e - E0 * r ** (2 * n))) < 2e-8 * E0, (n, np.max(np.abs(e - E0 * r ** (2 * n))) / E0)


# ---------------------------------------------------------------------------------------------- 4. impacts
def free_block_impact(q, v_minus, corner):
    """The free `RigidBlock`'s impact at (q, v-) when ``corner`` (0 left, 1 right) lands with e_N = 0 and sticks:
    M (v+ - v-) = W P with W the landing corner's normal and tangential columns and W^T v+ = 0 (a slender block,
    sin^2(alpha) < 2/3: the impulse is at the landing corner only, the other one leaves)."""
    block = RigidBlock(**BLOCK)
    W_N, W_T = block.contact_jacobians(q)
    W = np.column_stack([W_N[:, corner], W_T[:, corner]])
    Minv_W = np.linalg.solve(block.mass_matrix(q), W)
    P = np.linalg.solve(W.T @ Minv_W, -W.T @ v_minus)
    return v_minus + Minv_W @ P


def test_impact_outcome_is_the_free_blocks():
    """The tendon's force is finite: it transmits no impulse, and an impact's outcome is the free block's. At every
    impact of a free-rocking run of the post-tensioned block, the engine's post-impact velocity (impact log: v-, v+)
    is the free block's impact at the same pre-impact state (`free_block_impact` at phi = 0, from the free block's
    mass matrix and contact Jacobians, which the tendon leaves unchanged) in all three components to 1e-12
    relative, phi_dot+ = r phi_dot- with Housner's r, and the other corner leaves the ground."""
    model = make()
    block = RigidBlock(**BLOCK)
    alpha = math.atan2(model.b, model.h)
    r = 1.0 - 1.5 * math.sin(alpha) ** 2
    q0 = np.array([0.0, model.h, 0.0])
    np.testing.assert_array_equal(model.mass_matrix(q0), block.mass_matrix(q0))
    for a, b in zip(model.contact_jacobians(q0), block.contact_jacobians(q0)):
        np.testing.assert_array_equal(a, b)
    sim = Simulator(model, "event_driven", tolerance=1e-10, phi_0=0.5 * alpha)
    sim.advance(2.5, 0.0)
    log = sim.integrator.impact_log
    assert len(log) >= 3
    for t, v_minus, v_plus in log:
        landing = 1 if v_minus[2] < 0.0 else 0          # rocking on the left corner (phi > 0) the right one lands
        expected = free_block_impact(q0, np.asarray(v_minus), landing)
        np.testing.assert_allclose(v_plus, expected, rtol=1e-12, atol=1e-12 * abs(v_minus[2]))
        assert v_plus[2] == pytest.approx(r * v_minus[2], rel=1e-12)
        W_N = block.contact_jacobians(q0)[0]
        assert W_N[:, 1 - landing] @ v_plus > 0.1 * model.b * abs(v_minus[2])
