"""The compiled engine against the readable reference of tests/reference_models.py (scipy solve_ivp, DOP853,
rtol 1e-12, with events; equations of the flexible oscillator derived there from its Lagrangian).

Scenes are short (1.5-3 s) and chosen away from decision boundaries: every uplift and impact decision of
the reference is checked to be at least 10 % away from its threshold, so that round-off cannot flip it.
Event-driven (tolerance 1e-12): rotations to 1e-9 rad, impact times to 1e-9 s. Moreau-Jean: first order,
its error shrinks about as dt (slope fitted over three steps). SI units.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

import reference_models as ref
from rocking_model import FlexibleOscillator, RigidBlock, SinePulse, simulate

G = 9.81


def sine_pulse(A, omega):
    """ag(t) = A sin(omega t) for 0 <= t <= 2 pi/omega, else 0 [m/s2] (SinePulse's definition)."""
    t1 = 2.0 * math.pi / omega
    return (lambda t: A * math.sin(omega * t) if t <= t1 else 0.0), t1


RIGID_SCENES = {
    # free rocking from 0.5 alpha: 8 impacts in 3 s
    "free": dict(b=0.2, h=1.0, t_end=3.0, kw=dict(phi_0=0.5 * math.atan2(0.2, 1.0))),
    # one-sine pulse of 3 m/s2 (1.5 g tan(alpha)) at 2 Hz: uplift, rocking and impacts during and after it
    "pulse": dict(b=0.2, h=1.0, t_end=2.5, pulse=(3.0, 4.0 * math.pi)),
    # free rocking under a constant upward ground acceleration: effective gravity g + 3 m/s2
    "ag_v": dict(b=0.25, h=1.2, t_end=2.5, ag_v=3.0, kw=dict(phi_0=-0.05, phi_dot_0=0.1)),
}


def rigid_reference(scene):
    block = ref.Block(scene["b"], scene["h"])
    kw = dict(scene.get("kw", {}))
    ag_v = scene.get("ag_v", 0.0)
    breaks = ()
    if "pulse" in scene:
        ag, t1 = sine_pulse(*scene["pulse"])
        kw["ag"], breaks = ag, (t1,)
    traj = ref.rocking_block(block, scene["t_end"], ag_v=lambda t: ag_v, breaks=breaks, **kw)
    return block, traj


def engine_run(model, scene, **options):
    ag = SinePulse(*scene["pulse"]) if "pulse" in scene else 0.0
    kw = dict(scene.get("kw", {}))
    return simulate(model, ag, scene["t_end"], ag_v=scene.get("ag_v", 0.0), output_interval=0.01, **kw, **options)


@pytest.mark.parametrize("name", sorted(RIGID_SCENES))
def test_rigid_block_event_driven_matches_the_reference(name):
    """phi to 1e-9 rad, phi_dot to 1e-8 rad/s on a 0.01 s grid, every impact time to 1e-9 s."""
    scene = RIGID_SCENES[name]
    block, traj = rigid_reference(scene)
    assert len(traj.impact_times) >= 3
    res = engine_run(RigidBlock(b=scene["b"], h=scene["h"]), scene, tolerance=1e-12)
    np.testing.assert_allclose(res.impact_times, traj.impact_times, rtol=0, atol=1e-9)
    expected = [ref.outputs(traj, t, "rigid") for t in res.t]
    assert np.max(np.abs(res.phi - [e["phi"] for e in expected])) < 1e-9
    assert np.max(np.abs(res.phi_dot - [e["phi_dot"] for e in expected])) < 1e-8


@pytest.mark.parametrize("name", ["free", "pulse"])
def test_rigid_block_moreau_jean_converges_at_first_order(name):
    """Moreau-Jean's error in phi over the scene shrinks about as dt: at dt = 1e-3, 5e-4, 2.5e-4 s the
    largest error is below 20 dt rad*s^-1 (about 2 % of the amplitude at 1e-3 s) and the fitted slope of
    log(error) against log(dt) is between 0.7 and 1.5."""
    scene = RIGID_SCENES[name]
    block, traj = rigid_reference(scene)
    errors = []
    dts = [1e-3, 5e-4, 2.5e-4]
    for dt in dts:
        res = engine_run(RigidBlock(b=scene["b"], h=scene["h"]), scene, scheme="moreau_jean", dt_max=dt)
        err = np.max(np.abs(res.phi - [ref.outputs(traj, t, "rigid")["phi"] for t in res.t]))
        errors.append(err)
        assert err < 20.0 * dt, (dt, err)
    slope = np.polyfit(np.log(dts), np.log(errors), 1)[0]
    assert 0.7 < slope < 1.5, (errors, slope)


# ---------------------------------------------------------------------------------------------- flexible
DEFAULT = dict(m=500.0, m_c=30.0, m_b=100.0, rho=0.145, h=1.5, b=0.25, EI=9.45e5, zeta=0.02)
# a base heavy in rotation: u* = 0, every impact is immediate rocking on the new corner (its column makes the
# pivot unload: see the last test)
HEAVY_BASE = dict(m=1.0, m_c=0.2, m_b=1.0, rho=0.4, h=1.0, b=0.2, EI=30.0, zeta=0.01)

FLEXIBLE_SCENES = {
    # full contact only: a pulse at 60 % of the uplift threshold (about 1.99 m/s2)
    "full_contact": dict(params=DEFAULT, t_end=1.5, pulse=(1.2, 2.0 * math.pi * 2.0)),
    # released tilted: rocking, impacts into full contact (|u| << u*), re-uplift
    "free": dict(params=DEFAULT, t_end=1.5, kw=dict(phi_0=0.02)),
    # one-sine pulse above uplift (a more damped column: its pivot stays well loaded)
    "pulse": dict(params=dict(DEFAULT, zeta=0.1), t_end=2.0, pulse=(0.25 * G, 2.0 * math.pi)),
}


def flexible_reference(scene):
    osc = ref.Oscillator(**scene["params"])
    kw = dict(scene.get("kw", {}))
    breaks = ()
    if "pulse" in scene:
        ag, t1 = sine_pulse(*scene["pulse"])
        kw["ag"], breaks = ag, (t1,)
    return ref.rocking_oscillator(osc, scene["t_end"], breaks=breaks, **kw)


@pytest.mark.parametrize("name", sorted(FLEXIBLE_SCENES))
def test_flexible_oscillator_event_driven_matches_the_reference(name):
    """phi to 1e-9 rad and u to 1e-9 m on a 0.01 s grid, impact times to 1e-9 s; every decision of the
    reference at least 10 % from its threshold, and the pivot loaded by at least 5 % of the weight (the
    reference has no flight phase)."""
    scene = FLEXIBLE_SCENES[name]
    traj = flexible_reference(scene)
    for kind, ratio in traj.margins:
        assert ratio > 0.05 if kind == "pivot" else abs(ratio - 1.0) > 0.1, (kind, ratio)
    res = engine_run(FlexibleOscillator(**scene["params"]), scene, tolerance=1e-12)
    np.testing.assert_allclose(res.impact_times, traj.impact_times, rtol=0, atol=1e-9)
    expected = [ref.outputs(traj, t, "flexible") for t in res.t]
    assert np.max(np.abs(res.phi - [e["phi"] for e in expected])) < 1e-9
    assert np.max(np.abs(res.u - [e["u"] for e in expected])) < 1e-9
    if name != "full_contact":
        assert len(traj.impact_times) >= 2


# ---------------------------------------------------------------------------------------------- pivot lift-off
def test_flexible_pivot_lifts_off_when_its_force_turns_negative():
    """The heavy-base oscillator released at phi_0 = 0.08 rad rocks on its right corner after its first impact
    (t = 0.2407 s); between t = 0.2789 and 0.2870 s the sticking pivot would need tension (down to -0.13 M_t g)
    while its free-flight normal acceleration turns positive (+1.9 m/s2 at 0.283 s): the consistent motion is
    flight. At the zero of the pivot force (0.27891 s) that acceleration is still -0.10 m/s2, so the pivot first
    slides without normal force (mu = inf as the limit of the cone) for 0.1 ms, then lifts off; a landing impact
    follows near 0.2935 s. One advance and many small ones give this motion, with the same impact times."""
    params = dict(HEAVY_BASE, EI=1000.0)
    osc = ref.Oscillator(**params)
    traj = ref.rocking_oscillator(osc, 0.285, phi_0=0.08)
    mode, y = traj.at(0.283)
    assert mode == "right" and ref.pivot_force(osc, mode, y, 0.0, 0.0) < -0.1 * (1.0 + 1.0 + 0.2) * G
    from rocking_model import Simulator
    one = Simulator(FlexibleOscillator(**params), "event_driven", tolerance=1e-12, phi_0=0.08)
    one.advance(0.283, 0.0)
    steps = Simulator(FlexibleOscillator(**params), "event_driven", tolerance=1e-12, phi_0=0.08)
    for t in np.arange(0.01, 0.28, 0.01):
        steps.advance(t, 0.0)
    steps.advance(0.283, 0.0)
    assert steps.outputs()["contact"] == 3                     # flight
    assert one.outputs()["contact"] == 3, one.outputs()        # flight
    one.advance(0.3, 0.0)
    steps.advance(0.3, 0.0)
    assert len(one.impact_times) == 2 and 0.2934 < one.impact_times[-1] < 0.2936
    assert np.allclose(steps.impact_times, one.impact_times, rtol=0.0, atol=1e-9)


#: a one-sine pulse that overturns the slender block (the quickstart of earlier READMEs, as a SinePulse): in its
#: final fall on the right corner the pivot's normal force reaches zero at 1.959 s (phi = -1.34 rad), while the pivot's free
#: normal acceleration is negative (physics.md section 6): the mu = inf law slides the pivot from there
QUICK_PULSE = (3.0, 2.0 * math.pi)


def rigid_pivot_force(block: ref.Block, phi, phi_dot, ag, ag_v=0.0):
    """Normal force [N/kg] of the right pivot (phi < 0) of the rocking block: m (g + ag_v + y_G''), with
    y_G = R cos(alpha + phi) as long as the pivot sticks."""
    phi_ddot = block.phi_ddot(phi, -1.0, ag, ag_v)
    a = block.alpha + phi
    return block.g + ag_v - block.R * (math.sin(a) * phi_ddot + math.cos(a) * phi_dot ** 2)


def test_rigid_pivot_leaves_sticking_when_its_force_turns_negative():
    """The rigid block has the mechanism of the flexible lift-off above: rocking on its right corner under
    QUICK_PULSE, the pivot's normal force (from the reference's rocking solution) crosses zero at t0; inside
    one long advance the engine must leave sticking there (it used to keep the pivot in tension, with no event,
    until the end of the advance). Its free normal acceleration is negative there, so the pivot slides."""
    from scipy.optimize import brentq

    from rocking_model import Simulator

    block = ref.Block(0.2, 1.0)
    ag, t1 = sine_pulse(*QUICK_PULSE)
    # (restarts every 0.01 s until the uplift: its event function rises and falls inside one step of the full
    # contact phase otherwise)
    traj = ref.rocking_block(block, 1.99, ag=ag, breaks=tuple(np.arange(0.01, 0.2, 0.01)) + (t1,))
    force = lambda t: rigid_pivot_force(block, *traj.at(t)[1], ag(t))
    assert traj.at(1.95)[0] == "right" and force(1.95) > 0.0 > force(1.99)
    t0 = brentq(force, 1.95, 1.99, xtol=1e-12)
    assert 1.955 < t0 < 1.965
    sims = {}
    for name, grid in (("one", [t0 - 1e-3, t0 + 2e-3]), ("steps", list(np.arange(0.01, t0 - 1e-3, 0.01)))):
        sim = Simulator(RigidBlock(b=0.2, h=1.0), "event_driven", tolerance=1e-11)
        if name == "steps":
            for t in grid:
                sim.advance(t, SinePulse(*QUICK_PULSE))
            grid = [t0 - 1e-3, t0 + 2e-3]
        sim.advance(grid[0], SinePulse(*QUICK_PULSE))
        before = sim.outputs()
        assert before["contact"] == 2 and before["slip"] == 0.0, name       # sticking on the right corner
        assert abs(before["phi"] - traj.at(grid[0])[1][0]) < 1e-8
        sim.advance(grid[1], SinePulse(*QUICK_PULSE))
        sims[name] = sim.outputs()
        assert sims[name]["contact"] not in (0, 1, 2), (name, sims[name])   # no longer sticking
        assert sims[name]["slip"] != 0.0 and abs(sims[name]["slip"]) < 1e-6
    # (the fall towards overturning amplifies the round-off of the 0.01 s restarts: some 1e-9 rad/s by then)
    for key, tol in (("phi", 1e-9), ("phi_dot", 1e-8), ("slip", 1e-10), ("x", 1e-9), ("y", 1e-9)):
        assert sims["one"][key] == pytest.approx(sims["steps"][key], rel=0.0, abs=tol), key


def _heavy_base_oscillator():
    return FlexibleOscillator(**dict(HEAVY_BASE, EI=1000.0))


#: (model, initial state, ground motion, t_end [s]) of scenes with contact changes inside long advances
ADVANCE_SCENES = {
    "rigid_free": (lambda: RigidBlock(b=0.2, h=1.0), dict(phi_0=0.1), 0.0, 3.0),
    "rigid_quick_pulse": (lambda: RigidBlock(b=0.2, h=1.0), {}, SinePulse(*QUICK_PULSE), 1.99),
    "flexible_lift_off": (_heavy_base_oscillator, dict(phi_0=0.08), 0.0, 0.6),
    "flexible_pulse": (lambda: FlexibleOscillator(**DEFAULT), {}, SinePulse(0.8 * G, 2.0 * math.pi * 1.5), 2.5),
}


@pytest.mark.parametrize("name", sorted(ADVANCE_SCENES))
def test_one_advance_and_many_give_the_same_motion(name):
    """The event-driven motion does not depend on how the run is cut into advances: one `simulate` call (a
    single advance with its samples), 0.01 s advances and 0.001 s advances give the same contact state at every
    0.01 s sample, the same impact times (to 1e-9 s) and the same rotation (to 1e-8 rad)."""
    from rocking_model import Simulator

    make, initial, ag, t_end = ADVANCE_SCENES[name]
    res = simulate(make(), ag, t_end, output_interval=0.01, tolerance=1e-11, **initial)
    grid = np.asarray(res.t)
    for dt in (0.01, 0.001):
        sim = Simulator(make(), "event_driven", tolerance=1e-11, **initial)
        per = round(0.01 / dt)
        contact, phi = [sim.outputs()["contact"]], [sim.outputs()["phi"]]
        for k in range(1, round(t_end / dt) + 1):
            sim.advance(k * dt, ag)
            if k % per == 0:
                contact.append(sim.outputs()["contact"])
                phi.append(sim.outputs()["phi"])
        assert len(contact) == grid.size
        changed = np.nonzero(np.asarray(contact) != np.asarray(res.contact))[0]
        assert changed.size == 0, (dt, grid[changed], np.asarray(contact)[changed], np.asarray(res.contact)[changed])
        assert len(sim.impact_times) == len(res.impact_times) >= 1, (dt, sim.impact_times, res.impact_times)
        np.testing.assert_allclose(sim.impact_times, res.impact_times, rtol=0.0, atol=1e-9)
        assert np.max(np.abs(np.asarray(phi) - res.phi)) < 1e-8, dt
