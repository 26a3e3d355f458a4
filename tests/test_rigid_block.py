"""Rigid rocking block: the uplift threshold, the closed-form rocking equation, free rocking against the energy relations,
Moreau-Jean convergence to the event-driven solution."""
import math

import numpy as np
import pytest
from scipy.integrate import quad

from rocking_model import RigidBlock, SampledMotion, Simulator, SinePulse, simulate
from rocking_model.models.base import RockingModel
from rocking_model.modes import Mode

SLENDER = dict(b=0.2, h=1.0)        # sin^2(alpha) = 0.038 < 2/3
SQUAT = dict(b=2.0, h=1.0)          # sin^2(alpha) = 0.8 > 2/3


@pytest.mark.parametrize("dims", [SLENDER, dict(b=0.5, h=0.8), SQUAT])
def test_uplift_threshold(dims):
    """A block at rest under a constant ag stays in full contact just below g tan(alpha) and rocks on the
    corner the inertial force tips it to just above (the engine's uplift LCP at the start)."""
    block = RigidBlock(**dims)
    ag_c = block.g * math.tan(block.alpha)
    for sign, pivot in ((1, Mode.LEFT), (-1, Mode.RIGHT)):
        below = Simulator(block)
        below.advance(0.05, sign * ag_c * (1 - 1e-6))
        assert below.outputs()["contact"] == Mode.FULL and below.outputs()["phi"] == 0.0
        above = Simulator(block)
        above.advance(0.05, sign * ag_c * (1 + 1e-3))
        out = above.outputs()
        assert out["contact"] == pivot and sign * out["phi"] > 0.0


def test_closed_form_rocking_equals_projection():
    block = RigidBlock(b=0.25, h=0.9)
    rng = np.random.default_rng(1)
    for _ in range(20):
        mode = Mode.LEFT if rng.random() < 0.5 else Mode.RIGHT
        r, rd = rng.uniform(-0.5, 0.5, 1), rng.uniform(-2, 2, 1)
        ag = rng.uniform(-5, 5)
        closed = block.reduced_acceleration(mode, r, rd, ag)
        generic = RockingModel.reduced_acceleration(block, mode, r, rd, ag)
        assert closed == pytest.approx(generic, rel=1e-12, abs=1e-12)


def test_rocking_sign_convention():
    block = RigidBlock(**SLENDER)
    # at rest on the left pivot (0 < phi < alpha) gravity restores
    assert block.rocking_acceleration(0.05, 0.0, -1) < 0
    # positive ag above g tan(alpha) drives phi positive
    assert block.rocking_acceleration(0.0, 1.01 * block.g * math.tan(block.alpha), -1) > 0


def free_rocking(block, phi_0, t_end, tol=1e-12):
    sim = Simulator(block, "event_driven", phi_0=phi_0, tolerance=tol)
    sim.advance(t_end, 0.0)
    return sim


@pytest.mark.parametrize("dims,phi_0", [(SLENDER, 0.1), (dict(b=0.15, h=0.6), 0.2)])
def test_free_rocking_against_energy_relations(dims, phi_0):
    block = RigidBlock(**dims)
    p, a, r = block.p, block.alpha, block.housner_r
    sim = free_rocking(block, phi_0, 4.0)
    log = sim.integrator.impact_log
    assert len(log) >= 4
    # first impact time: quarter period of the nonlinear pendulum equation
    E = math.cos(a - phi_0)
    # substitution phi = phi_0 (1 - s^2) removes the turning-point singularity
    t1 = quad(lambda s: 2 * phi_0 * s / (p * math.sqrt(2 * (E - math.cos(a - phi_0 * (1 - s * s))))),
              0.0, 1.0, limit=200, epsabs=0.0, epsrel=1e-12)[0]
    assert log[0][0] == pytest.approx(t1, abs=1e-8)
    w0 = p * math.sqrt(2 * (math.cos(a - phi_0) - math.cos(a)))
    for n, (t, v_minus, v_plus) in enumerate(log[:6]):
        # impact speed and amplitude recurrence: cos(a - phi_n) - cos a = r^2n [cos(a - phi_0) - cos a]
        assert abs(v_minus[2]) == pytest.approx(w0 * r ** n, rel=1e-8)
        assert v_plus[2] / v_minus[2] == pytest.approx(r, rel=1e-12)
        amp = a - math.acos(math.cos(a) + v_plus[2] ** 2 / (2 * p ** 2))
        expected = a - math.acos(math.cos(a) + r ** (2 * n + 2) * (math.cos(a - phi_0) - math.cos(a)))
        assert amp == pytest.approx(expected, rel=1e-8)


def test_free_rocking_amplitude_reached():
    block = RigidBlock(**SLENDER)
    phi_0 = 0.1
    res = simulate(block, 0.0, 1.4, phi_0=phi_0, output_interval=1e-4, tolerance=1e-12)
    # between the first and second impact the block rocks on the right pivot up to -phi_1
    p, a, r = block.p, block.alpha, block.housner_r
    phi_1 = a - math.acos(math.cos(a) + r ** 2 * (math.cos(a - phi_0) - math.cos(a)))
    assert -res.phi.min() == pytest.approx(phi_1, rel=1e-6)   # sampled peak: grid error ~ (p dt)^2


def test_energy_conserved_between_impacts_and_lost_at_impacts():
    block = RigidBlock(**SLENDER)
    res = simulate(block, 0.0, 2.0, phi_0=0.1, output_interval=0.005, tolerance=1e-12)
    E = res.energy
    assert np.all(np.diff(E) <= 1e-9 * E[0])
    assert E[-1] < E[0] * block.housner_r ** 2 * 1.0000001


def test_free_rocking_ends_in_full_contact():
    block = RigidBlock(**SLENDER)
    sim = free_rocking(block, 0.05, 30.0, tol=1e-10)
    assert sim.integrator.mode == Mode.FULL
    out = sim.outputs()
    assert out["phi"] == 0.0 and out["phi_dot"] == 0.0 and out["contact"] == 0
    assert 20 < out["impacts"] < 1000
    # after settling nothing moves any more
    sim.advance(60.0, 0.0)
    assert sim.outputs()["phi"] == 0.0 and sim.outputs()["impacts"] == out["impacts"]


def test_moreau_jean_settles_and_stays_at_rest():
    block = RigidBlock(**SLENDER)
    sim = Simulator(block, "moreau_jean", phi_0=0.05, dt_max=2e-3)
    sim.advance(20.0, 0.0)
    out = sim.outputs()
    assert out["contact"] == 0
    assert abs(out["phi"]) < 1e-12


def _max_error(res, ref):
    return float(np.max(np.abs(res.phi - ref.phi)))


def test_moreau_jean_converges_to_event_driven_order_one():
    block = RigidBlock(**SLENDER)
    kw = dict(phi_0=0.1, output_interval=0.01)
    ref = simulate(block, 0.0, 1.5, scheme="event_driven", tolerance=1e-12, **kw)
    dts = np.array([4e-3, 2e-3, 1e-3, 5e-4, 2.5e-4])
    errs = np.array([_max_error(simulate(block, 0.0, 1.5, scheme="moreau_jean", dt_max=dt, **kw), ref)
                     for dt in dts])
    slope = np.polyfit(np.log(dts), np.log(errs), 1)[0]
    assert 0.75 < slope < 1.4, (slope, errs)
    assert errs[-1] < 5e-3


def test_forced_response_schemes_agree_and_overturning():
    block = RigidBlock(**SLENDER)
    g = block.g
    weak = SinePulse(A=0.4 * g, omega_p=2 * math.pi * 2.0)
    ed = simulate(block, weak, 3.0, scheme="event_driven", tolerance=1e-10, output_interval=0.01)
    mj = simulate(block, weak, 3.0, scheme="moreau_jean", dt_max=2.5e-4, output_interval=0.01)
    assert ed.phi.max() > 0.01 and not ed.overturned[-1] and not mj.overturned[-1]
    # first order: the phase error after two impacts is about 8 ms at dt = 2.5e-4 s and halves with dt
    assert _max_error(mj, ed) < 0.1 * np.abs(ed.phi).max()
    assert abs(mj.impact_times[0] - ed.impact_times[0]) < 2 * 2.5e-4
    assert len(mj.impact_times) == len(ed.impact_times)
    strong = SinePulse(A=1.5 * g, omega_p=2 * math.pi * 0.5)
    for scheme in ("event_driven", "moreau_jean"):
        res = simulate(block, strong, 4.0, scheme=scheme, output_interval=0.01)
        assert res.overturned[-1]
        k = int(np.argmax(res.overturned))
        # frozen after overturning, at |phi| = pi/2
        assert np.all(res.phi[k:] == res.phi[k])
        assert abs(res.phi[k]) >= 0.5 * math.pi - 1e-9
        assert abs(res.phi[k]) < 0.5 * math.pi + 0.05


def test_sampled_ground_motion_linear_interpolation():
    gm = SampledMotion([0.0, 1.0, 2.0], [0.0, 2.0, -2.0])
    assert gm(0.5) == pytest.approx(1.0)
    assert gm(1.5) == pytest.approx(0.0)
    assert gm(3.0) == 0.0
    assert gm.next_breakpoint(0.2) == 1.0
    block = RigidBlock(**SLENDER)
    t = np.linspace(0, 1, 101)
    ag = 3.0 * np.sin(2 * math.pi * t)
    a = simulate(block, (t, ag), 2.0, tolerance=1e-10)
    b = simulate(block, SampledMotion(t, ag), 2.0, tolerance=1e-10)
    assert np.array_equal(a.phi, b.phi)
    assert a.phi.max() > 0


@pytest.mark.parametrize("kwargs,name", [
    (dict(b=-1.0), "b"), (dict(h=0.0), "h"), (dict(m=float("nan")), "m"), (dict(g=0.0), "g"),
    (dict(e_N=1.5), "e_N"), (dict(e_N=-0.1), "e_N")])
def test_bad_parameters_name_variable(kwargs, name):
    with pytest.raises(ValueError, match=rf"^{name}\b.*allowed range"):
        RigidBlock(**kwargs)


def test_bad_simulator_input():
    block = RigidBlock()
    with pytest.raises(ValueError, match="phi_0"):
        Simulator(block, phi_0=2.0)
    with pytest.raises(ValueError, match="scheme"):
        Simulator(block, scheme=7)
    sim = Simulator(block)
    sim.advance(1.0, 0.0)
    with pytest.raises(ValueError, match="t_end"):
        sim.advance(0.5, 0.0)
    with pytest.raises(ValueError, match="ag"):
        sim.advance(2.0, float("inf"))

