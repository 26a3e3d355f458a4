"""Coulomb friction : the frictional contact LCP and the Moreau-Jean scheme with a
finite mu. Closed forms (a sliding block under constant ag, the sliding threshold |ag| = mu g), the initiation
map from rest (slide first for mu < tan(alpha), rock first for mu > tan(alpha); Shenton 1996), mu above the
friction demand gives the mu = inf results, and growing mu converges to the mu = inf motion of an overturning
block without its corner ever sinking (the hole of the sticking law)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from rocking_model import RigidBlock, Simulator, simulate
from rocking_model.modes import Mode


G = 9.81



# ---------------------------------------------------------------------------------------------- closed forms
@pytest.mark.parametrize("scheme, dt", [("moreau_jean", 1e-3), ("moreau_jean", 2.5e-4), ("event_driven", 0.0)])
@pytest.mark.parametrize("ag", [5.0, -4.0])
def test_sliding_block_under_constant_ag(ag, scheme, dt):
    """b = h (tan alpha = 1), mu = 0.3 < |ag|/g < tan(alpha): the block slides without rocking, relative to
    the ground x(t) = 1/2 (-ag + sign(ag) mu g) t^2 (the theta-method and the Runge-Kutta steps are exact for
    a constant acceleration), in the sliding full-contact mode against the ground's push."""
    block = RigidBlock(b=0.5, h=0.5, mu=0.3)
    res = simulate(block, ag, 1.0, scheme=scheme, dt_max=dt, output_interval=0.05)
    a_rel = -ag + math.copysign(0.3 * G, ag)
    np.testing.assert_allclose(res.x, 0.5 * a_rel * res.t ** 2, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(res.x_dot, a_rel * res.t, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(res.slip, res.x, rtol=0, atol=1e-15)
    sliding = Mode.FULL_SLIDE_NEG if ag > 0 else Mode.FULL_SLIDE_POS
    assert np.all(res.phi == 0.0) and np.all(res.contact[1:] == sliding)
    assert np.all(res.friction_demand[1:] == pytest.approx(0.3, rel=1e-12)) and np.all(res.painleve == 0)


@pytest.mark.parametrize("factor, slides", [(0.98, False), (1.02, True)])
def test_sliding_threshold_is_mu_g(factor, slides):
    block = RigidBlock(b=0.5, h=0.5, mu=0.4)
    res = simulate(block, factor * 0.4 * G, 1.0, scheme="moreau_jean", output_interval=0.1)
    moved = np.max(np.abs(res.x))
    assert (moved > 1e-3) == slides, moved
    if not slides:
        assert moved < 1e-15


@pytest.mark.parametrize("scheme", ["moreau_jean", "event_driven"])
@pytest.mark.parametrize("factor, slides", [(0.98, False), (1.02, True)])
def test_sliding_threshold_is_mu_g(factor, slides, scheme):
    block = RigidBlock(b=0.5, h=0.5, mu=0.4)
    res = simulate(block, factor * 0.4 * G, 1.0, scheme=scheme, output_interval=0.1)
    moved = np.max(np.abs(res.x))
    assert (moved > 1e-3) == slides, moved
    if not slides:
        assert moved < 1e-15
        assert res.friction_demand[-1] == pytest.approx(0.98 * 0.4, rel=1e-12)


@pytest.mark.parametrize("scheme", ["moreau_jean", "event_driven"])
@pytest.mark.parametrize("mu, ag_over_g, first", [
    (0.2, 0.25, "slide"),      # mu < tan(alpha) = 0.5 and mu g < ag < g tan(alpha): slides, does not rock
    (0.3, 0.55, "slide"),      # mu < tan(alpha), ag above both thresholds: slides (Shenton: slide, not rock)
    (0.8, 0.6, "rock"),        # mu > tan(alpha): rocks at ag > g tan(alpha) = 0.5 g while mu g = 0.8 g holds
    (0.8, 0.45, "rest"),       # below both thresholds
])
def test_initiation_from_rest(mu, ag_over_g, first, scheme):
    """Shenton (1996): from rest under a horizontal ag the block slides first if mu < tan(alpha) (at |ag| =
    mu g) and rocks first if mu > tan(alpha) (at |ag| = g tan(alpha)). Here tan(alpha) = 0.5. A block that
    slides carries the friction mu m g, whose moment about the trailing corner never exceeds the restoring
    one when mu < tan(alpha): it slides without rocking (his slide mode, no slide-rock from rest)."""
    block = RigidBlock(b=0.25, h=0.5, mu=mu)
    res = simulate(block, ag_over_g * G, 0.3, scheme=scheme, dt_max=1e-4 if scheme == "moreau_jean" else 0.0,
                   output_interval=0.01)
    rocked = np.max(np.abs(res.phi)) > 1e-6
    # (Moreau-Jean's pivot drifts by O(dt) along the ground while it rocks: some 1e-6 m here)
    slid = np.max(np.abs(res.slip)) > 1e-4
    assert {"slide": slid and not rocked, "rock": rocked and not slid, "rest": not rocked and not slid}[first], \
        (np.max(np.abs(res.phi)), np.max(np.abs(res.slip)))
    if first == "rock":
        # rocking on a corner that sticks
        assert set(res.contact[1:]) <= {Mode.LEFT, Mode.RIGHT}
    if first == "slide":
        assert set(res.contact[1:]) == {Mode.FULL_SLIDE_NEG}


@pytest.mark.parametrize("scheme", ["moreau_jean", "event_driven"])
def test_mu_above_the_friction_demand_gives_the_sticking_results(scheme):
    """A rocking scene whose contacts never need more than about 0.3 of friction: mu = 5 gives the mu = inf
    motion (the friction LCP and the sticking LCP agree to round-off), and the friction demand says so."""
    kw = dict(scheme=scheme, dt_max=1e-3 if scheme == "moreau_jean" else 0.0, output_interval=0.01, phi_0=0.1)
    inf = simulate(RigidBlock(b=0.3, h=1.0), 0.0, 3.0, **kw)
    five = simulate(RigidBlock(b=0.3, h=1.0, mu=5.0), 0.0, 3.0, **kw)
    assert inf.impacts[-1] == five.impacts[-1] >= 3
    np.testing.assert_allclose(five.phi, inf.phi, rtol=0, atol=1e-9)
    np.testing.assert_allclose(five.x, inf.x, rtol=0, atol=1e-9)
    assert 0.05 < inf.friction_demand[-1] < 1.0
    np.testing.assert_allclose(five.slip, inf.slip, rtol=0, atol=1e-9)
    # the pivot does not slide; Moreau-Jean's drifts along the ground by O(dt) (0.1 mm over the 3 s here)
    assert np.max(np.abs(five.slip)) == 0.0 if scheme == "event_driven" else np.max(np.abs(five.slip)) < 1e-3
    np.testing.assert_allclose(five.friction_demand, inf.friction_demand, rtol=1e-6)


def _overturning_pulse_run(scheme, mu):
    """The first pulse of an earlier README quickstart (3 m/s2 one-sine of 1 s) that overturns a slender block b = 0.2,
    h = 1: (lowest corner over the run [m], inexact reports, final outputs)."""
    t = np.linspace(0.0, 5.0, 501)
    ag = 3.0 * np.sin(2 * np.pi * t) * (t < 1)
    sim = Simulator(RigidBlock(b=0.2, h=1.0, mu=mu), scheme, dt_max=1e-3 if scheme == "moreau_jean" else None,
                    on_report="ignore")
    lowest, inexact = 0.0, 0
    for k in range(500):
        sim.advance((k + 1) * 0.01, (t, ag))
        lowest = min(lowest, float(min(sim.model.gaps(sim.state()[0]))))
        inexact += len(sim.last_reports)
    return lowest, inexact, sim.outputs()


@pytest.mark.parametrize("scheme", ["moreau_jean", "event_driven"])
def test_growing_mu_converges_to_the_sticking_law_without_its_hole(scheme):
    """Tipping over its right corner the pivot's normal force reaches zero at phi ~ -1.34 rad, where sticking
    would need tension (the hole of the paper's law: no consistent contact state, a corner sank 20 mm). With
    any finite mu the pivot slides first; mu = inf takes the limit (the pivot slides with a vanishing normal
    force). No corner goes below the ground, no contact solve is inexact, up to the frozen overturned state,
    and the slip of the base converges to the mu = inf one as mu grows."""
    out = {mu: _overturning_pulse_run(scheme, mu) for mu in (1.0, 5.0, 20.0, 100.0, math.inf)}
    for mu, (lowest, inexact, o) in out.items():
        assert lowest > -1e-12 and inexact == 0 and o["overturned"], (mu, lowest, inexact)
        assert o["friction_demand"] <= mu * (1 + 1e-9)
    slip_inf = out[math.inf][2]["slip"]
    gaps = [abs(out[mu][2]["slip"] - slip_inf) for mu in (1.0, 5.0, 20.0, 100.0)]
    assert gaps[0] > gaps[1] > gaps[2] > gaps[3] and gaps[3] < 0.2 * gaps[1], gaps
    assert out[math.inf][2]["friction_demand"] > 10.0      # sticking needed far more than any surface gives


def test_mu_is_checked_by_name():
    with pytest.raises(ValueError, match=r"mu = 0 is out of range; allowed range \[0.001, inf\]"):
        RigidBlock(mu=0.0)


def test_painleve_is_resolved_by_an_impact_without_collision():
    """A slender block on its right corner tilted by phi = -0.6 rad, sliding towards -x at 1 m/s with mu = 2:
    above the critical mu of this configuration (W_N^T M^-1 (W_N - sigma mu W_T) < 0 for mu > 1.35) the
    acceleration problem of the sliding corner has no solution (gravity presses it into the ground, the
    friction would lift it): Painleve's paradox. The documented rule: an impact without collision (the
    tangential impulse that makes the corner stick), counted in ``painleve``; it dissipates energy, no
    corner goes below the ground and no contact solve is reported inexact."""
    block = RigidBlock(b=0.2, h=1.0, mu=2.0)
    W_N, W_T = block.contact_jacobians(np.array([0.0, 1.0, -0.6]))
    Minv = block.inverse_mass_matrix(None)
    assert W_N[:, 1] @ Minv @ (W_N[:, 1] + 2.0 * W_T[:, 1]) < 0.0          # sigma = -1: Painleve
    sim = Simulator(block, "event_driven", phi_0=-0.6, on_report="raise")
    state = sim.get_state()
    state.update(mode=int(Mode.RIGHT_SLIDE_NEG), y=[-0.6, 0.0, 0.0, -1.0])
    sim.set_state(state)
    e0 = block.energy(*sim.state())
    sim.advance(1e-6, 0.0)
    out = sim.outputs()
    assert out["painleve"] == 1 and out["contact"] == Mode.RIGHT and not sim.last_reports
    assert block.energy(*sim.state()) < e0 - 0.1
    sim.advance(0.5, 0.0)
    assert min(block.gaps(sim.state()[0])) > -1e-12 and sim.outputs()["painleve"] == 1


@pytest.mark.parametrize("mu, amplitude, rocks", [(0.3, 0.6, False), (0.52, 0.8, True)])
def test_moreau_jean_converges_to_the_event_driven_solution(mu, amplitude, rocks):
    """A slide scene (mu < tan(alpha) = 0.5: slide, stop, slide back, stop) and a slide-rock scene (mu just
    above tan(alpha): rocking with sliding phases on either corner) of a b = 0.3, h = 0.6 block under a
    one-sine pulse of 0.5 s: Moreau-Jean's error against the event-driven solution (tolerance 1e-11) falls
    with dt, by more than 8x over a 16x finer step (order one, not monotone at the stick-slip transitions)."""
    block = RigidBlock(b=0.3, h=0.6, mu=mu)

    def ag(t):
        return amplitude * G * math.sin(4 * math.pi * t) if t < 0.5 else 0.0
    ref = simulate(block, ag, 2.0, scheme="event_driven", tolerance=1e-11, output_interval=0.01)
    sliding = [c for c in set(ref.contact) if c >= Mode.FULL_SLIDE_POS]
    assert sliding and (np.max(np.abs(ref.phi)) > 0.1) == rocks and abs(ref.slip[-1]) > 1e-3
    errors = []
    for dt in (2e-3, 1.25e-4):
        r = simulate(block, ag, 2.0, scheme="moreau_jean", dt_max=dt, output_interval=0.01)
        errors.append(max(np.max(np.abs(r.phi - ref.phi)), np.max(np.abs(r.slip - ref.slip)) / block.R))
    assert errors[1] < errors[0] / 8.0, errors


@pytest.mark.parametrize("scheme", ["moreau_jean", "event_driven"])
def test_flexible_oscillator_slides_and_rocks(scheme):
    """The paper's flexible oscillator with mu = 0.2 under a 0.35 g one-sine pulse: it rocks and slides on
    either corner (slide-rock) and bounces, never below the ground, with the friction demand at mu; both
    schemes agree on the final slip to 1 mm."""
    from rocking_model import FlexibleOscillator

    def ag(t):
        return 0.35 * G * math.sin(2 * math.pi * t / 0.6) if t < 0.6 else 0.0
    res = simulate(FlexibleOscillator(mu=0.2), ag, 3.0, scheme=scheme, output_interval=0.005)
    modes = set(res.contact)
    assert {Mode.LEFT_SLIDE_NEG, Mode.RIGHT_SLIDE_POS} <= modes and Mode.FLIGHT in modes
    assert res.friction_demand[-1] == pytest.approx(0.2, rel=1e-9)
    assert res.slip[-1] == pytest.approx(-0.0226, abs=1e-3) and not res.overturned[-1]


def test_docs_friction_example_shows_what_it_says():
    """The contact-laws page's example (docs/guide/contact-laws.md): b = 0.3, h = 0.6, mu = 0.52 under a 0.8 g one-sine pulse of 0.5 s
    rocks, slides on its pivot and ends about 9.6 mm off, at a friction demand equal to mu."""
    from pathlib import Path
    text = (Path(__file__).resolve().parent.parent / "docs" / "guide" / "contact-laws.md").read_text()
    assert "RigidBlock(b=0.3, h=0.6, mu=0.52)" in text and "about -9.6 mm, 0.52" in text
    block = RigidBlock(b=0.3, h=0.6, mu=0.52)
    res = simulate(block, lambda t: 0.8 * G * math.sin(4 * math.pi * t) if t < 0.5 else 0.0, 2.0)
    assert res.slip[-1] == pytest.approx(-9.6e-3, abs=0.1e-3) and res.friction_demand[-1] == pytest.approx(0.52)
    assert {Mode.LEFT, Mode.RIGHT} <= set(res.contact) and set(res.contact) & set(range(4, 10))
