"""Hard cases: stiff columns and large steps, long records, constant tilts and steps of the
input. Helpers and tolerances: tests/hard_cases.py."""
from __future__ import annotations

import functools
import math

import numpy as np
import pytest

from rocking_model import ConstantMotion, FlexibleOscillator, RigidBlock, SampledMotion, SinePulse, simulate
from rocking_model.modes import Mode

import roundoff
from hard_cases import (DATA, G, MODELS, QUIET_VERDICT, SLENDER, Trace, assert_sane, grid, nominal, pen_tol,
                        roundoff_tests, stiff_flex)
from roundoff import Perturbation, check_bounds, describe_mismatch, scene

MOD = __name__

#: verdicts of the scenes of this module that are re-run 1 ulp off and under other kernels, and the
#: documented margins of their figures (filled next to each scene)
VERDICTS: dict[str, dict] = {}
BOUNDS: dict[str, dict] = {}
kernel_rerun = roundoff.kernel_rerun_fixture(VERDICTS)


# ================================================================================================
# 6. Stiff columns and large steps
# ================================================================================================
@pytest.mark.parametrize("scheme,kw", [("ED", {}), ("MJ", dict(dt_max=1e-3)), ("MJ", dict(dt_max=0.05))],
                         ids=["ED", "MJ-dt1e-3", "MJ-dt0.05"])
def test_stiff_column_fixed_base_vibration(scheme, kw):
    """Column frequency 100 p (omega = 255 rad/s), no damping, in full contact from u_0 below uplift:
    u(t) = u_0 cos(omega t). ED: 1e-5 u_0. MJ (theta = 1/2, trapezoidal on the stiff part): no amplitude
    error, phase error omega^3 dt^2 t / 12 (dt = 1e-3: 0.35 rad over 1 s; dt = 0.05, omega dt = 12.8: the
    amplitude stays, the frequency collapses to 2/dt atan(omega dt/2)): amplitude bounded by u_0."""
    model = stiff_flex(zeta=0.0)
    u_0 = 1e-5
    tr = Trace(model, scheme, 0.0, grid(1.0, 0.05), u_0=u_0, **kw)
    assert_sane(tr)
    assert np.all(tr.modes == Mode.FULL) and np.max(np.abs(tr.phi)) < 1e-12   # exactness: bug 5 tests
    u = np.array(tr.q)[:, 0]
    w = model.omega
    if scheme == "ED":
        assert np.max(np.abs(u - u_0 * np.cos(w * tr.T))) < 1e-5 * u_0        # measured 2.1e-6 u_0
    else:
        # the step the time-stepper takes: at most model.step_limit, each 0.05 s output interval split evenly
        dt = 0.05 / math.ceil(0.05 / min(kw["dt_max"], model.step_limit) - 1e-9)
        wd = 2.0 / dt * math.atan(w * dt / 2.0)       # trapezoidal rule: exact amplitude, shifted frequency
        assert np.max(np.abs(u)) <= u_0 * (1 + 1e-9)
        assert np.max(np.abs(u - u_0 * np.cos(wd * tr.T))) < 1e-6 * u_0


@pytest.mark.parametrize("model_name,scheme", [
    ("rigid", "ED"), ("rigid", "MJ"), ("stiff-flexible", "ED"), ("stiff-flexible", "MJ")])
def test_large_steps_stay_physical(model_name, scheme):
    """dt = 0.05 s (p dt = 0.13 for the block; omega dt = 13 for the stiff column): a 0.25 g, 1.5 Hz pulse
    (ED: max |phi| 0.039 rad = 0.20 alpha block, 0.028 rad = 0.14 alpha column, no overturning, the same in
    14 runs 1 ulp off and under other kernels) and free rocking to rest. Finite, no
    penetration beyond 2 dt v, no overturning, at rest at the end. (MJ at dt = 0.05 s under-resolves the
    block, max |phi| 0.003 rad, 0 impacts: accuracy, not stability.) With the stiff column MJ overturned
    spuriously at dt = 0.05, 0.02, 0.01 and 0.005 s (bug 9: first flight at 0.5 / 0.36 / 0.40 / 0.39 s with
    |u_dot| up to 8 m/s) until it sub-stepped to model.step_limit = 0.25/omega (max |phi| 0.031 rad)."""
    key = f"{MOD}:large_steps_{model_name}_{scheme}"
    tr, summary = nominal(key)
    assert_sane(tr)
    assert np.max(np.abs(tr.phi)) > 1e-3
    assert tr.modes[-1] == Mode.FULL and abs(tr.phi[-1]) < 1e-12
    assert tr.impacts[-1] < 300
    if key in VERDICTS:
        assert summary["verdict"] == VERDICTS[key], describe_mismatch(summary["verdict"], VERDICTS[key])
        check_bounds(summary["figures"], BOUNDS[key], key)


def large_steps_scene(model_name: str, scheme: str, pert: Perturbation):
    """0.25 g, 1.5 Hz one-sine pulse, 25 s on a 0.05 s grid with dt_max = 0.05 s: max |phi| 0.2 alpha
    (rigid ED), far from overturning; at rest over the last second."""
    model = RigidBlock(**SLENDER) if model_name == "rigid" else stiff_flex()
    gm = SinePulse(pert.scalar(0.25 * G, 1), pert.scalar(2 * math.pi * 1.5, 2))
    tr = Trace(model, scheme, gm, grid(25.0, 0.05), dt_max=0.05, phi_0=pert.scalar(0.0))
    return tr, dict(rest_after=24.0)


for _m in ("rigid", "stiff-flexible"):
    for _s in ("ED", "MJ"):
        scene(f"large_steps_{_m}_{_s}")(functools.partial(large_steps_scene, _m, _s))
# re-run: both rigid runs and the stiff column ED (its MJ run, 9 s, is not repeated)
for _k, _b in (("rigid_ED", (0.1, 0.5)), ("rigid_MJ", (0.005, 0.5)), ("stiff-flexible_ED", (0.05, 0.5))):
    VERDICTS[f"{MOD}:large_steps_{_k}"] = dict(QUIET_VERDICT, **({"energy_below_tipping": True}
                                                                if _k.startswith("rigid") else {}))
    BOUNDS[f"{MOD}:large_steps_{_k}"] = dict(max_phi_over_alpha=_b)


# ================================================================================================
# 7. Long records and extreme input
# ================================================================================================
def flexible_record_scene(pert: Perturbation):
    """The stored 30 s record scaled to PGA 0.15 g, held per 0.01 s step (exactly what simulate(...,
    hold="zoh") does), default FlexibleOscillator, ED at tolerance 1e-10."""
    t, a = np.load(DATA / "synthetic_record_30s_0.4g.npy")
    gm = SampledMotion(t, pert.array(a * 0.15 / 0.4, 1))
    times = np.minimum(0.01 * np.arange(3001), 30.0)
    tr = Trace(FlexibleOscillator(), ("event_driven", dict(tolerance=1e-10)), 0.0, [], phi_0=pert.scalar(0.0))
    for k in range(times.size - 1):
        tr.extend(ConstantMotion(gm(times[k])), [times[k + 1]])
    return tr, {}


scene("flexible_record_ED")(flexible_record_scene)
VERDICTS[f"{MOD}:flexible_record_ED"] = dict(finite=True, no_penetration=True, right_side=True,
                                             bounded_rotation=True, overturned=False)
# measured: max |phi| = 0.0120 rad = 0.060 alpha (alpha = 0.201 rad), against the 0.05 rad asserted
BOUNDS[f"{MOD}:flexible_record_ED"] = dict(max_phi_over_alpha=(0.02, 0.05 / FlexibleOscillator().alpha))


def test_flexible_record_stays_on_the_right_side_event_driven():
    """Bug 2 (fixed in 7e74133, kept as regression): default FlexibleOscillator under the 30 s synthetic record
    scaled by 0.15/0.4 (PGA 0.15 g), zero-order hold per 0.01 s, tolerance 1e-10: rocked on pivot 2 (right)
    with phi > 0 from 13.57 s and 'overturned'. MJ at dt = 2e-4 s: max |phi| ~ 0.02 rad. The outcome was
    round-off sensitive (synthetic_record(pga_g=0.15) did not show it), hence the stored record; the verdict
    (right side, no overturning, max |phi| < 0.05 rad; measured 0.012 rad in all 14 runs 1 ulp off and under
    other kernels) is re-run 1 ulp off and under other kernels."""
    key = f"{MOD}:flexible_record_ED"
    tr, summary = nominal(key)
    wrong = ((tr.modes == 1) & (tr.phi < -1e-9)) | ((tr.modes == 2) & (tr.phi > 1e-9))
    assert not wrong.any(), tr.T[wrong][:3]
    assert not tr.overturned[-1]
    assert np.abs(tr.phi).max() < 0.05
    assert summary["verdict"] == VERDICTS[key], describe_mismatch(summary["verdict"], VERDICTS[key])
    check_bounds(summary["figures"], BOUNDS[key], key)


def test_flexible_lift_off_independent_of_step_cap():
    """Bug 3 (fixed, regression): FlexibleOscillator(EI = 9.45e4) under a 0.25 g, 1.5 Hz pulse: with dt_max =
    1.25e-3 the lift-off after the impact at 1.7812 s was missed (release root a round-off past zero, event
    disarmed), 9.7e-3 rad away from the reference. All settings must agree to the tolerance."""
    model = FlexibleOscillator(EI=9.45e4)
    gm = SinePulse(0.25 * G, 3 * math.pi)
    ref = simulate(model, gm, 3.0, scheme="event_driven", tolerance=1e-12, dt_max=3.125e-4, output_interval=0.01)
    for kw in (dict(tolerance=1e-10), dict(tolerance=1e-10, dt_max=1.25e-3)):
        res = simulate(model, gm, 3.0, scheme="event_driven", output_interval=0.01, **kw)
        assert np.max(np.abs(res.phi - ref.phi)) < 1e-7, kw


@functools.lru_cache(maxsize=None)
def tilt_run(model_name, scheme):
    model = MODELS[model_name]()
    if model_name == "rigid":
        ag = 0.999 * model.g * math.tan(model.alpha)
    else:
        ag = 0.1 * G        # overshoot 2 u_s = 1.2e-4 m < uplift deformation 1.2e-3 m
    return Trace(model, scheme, ConstantMotion(ag), grid(10.0)), ag


@pytest.mark.parametrize("scheme", ["ED", "MJ"])
@pytest.mark.parametrize("model_name", ["rigid", "flexible"])
def test_constant_tilt_below_threshold_stays_at_rest(model_name, scheme):
    """Constant ag below the uplift threshold: the base stays down, no impact, |phi| < 1e-12; the column
    deflects to its static u_s = -D ag / k_tilde (damped free vibration around it)."""
    tr, ag = tilt_run(model_name, scheme)
    model = tr.model
    assert_sane(tr)
    assert np.all(tr.modes == Mode.FULL) and tr.impacts[-1] == 0
    assert np.max(np.abs(tr.phi)) < 1e-12
    if model_name == "flexible":
        u_s = -model.D * ag / model.k_tilde
        assert np.array(tr.q)[-1, 0] == pytest.approx(u_s, rel=1e-3)


@pytest.mark.parametrize("scheme", ["ED", "MJ"])
@pytest.mark.parametrize("model_name", ["rigid", "flexible"])
def test_constant_tilt_rest_is_exact(model_name, scheme):
    """... and the rigid block does not move at all: phi = phi_dot = 0 exactly, x = 0, y = h exactly."""
    tr, ag = tilt_run(model_name, scheme)
    assert np.all(tr.phi == 0.0) and np.all(tr.phi_dot == 0.0), np.abs(tr.phi).max()
    rest = tr.model.rest_position()
    dofs = [1, 2] if model_name == "flexible" else [0, 1]
    assert np.all(np.array(tr.q)[:, dofs] == rest[dofs])


@pytest.mark.parametrize("scheme", ["ED", "MJ"])
@pytest.mark.parametrize("sign", [1, -1], ids=["positive", "negative"])
def test_step_above_threshold_uplifts_at_once(sign, scheme):
    """ag jumps at t = 0 to 1.5 g tan(alpha): positive ag lifts the right corner (rocking on the left pivot,
    contact = 1, phi > 0), negative ag the left one; phi(t) = 1/2 phi_dd0 t^2 at first with
    phi_dd0 = p^2 (1.5 tan(alpha) cos(alpha) - sin(alpha)); the block then keeps rotating one way (it
    overturns at ~1.3 s; checked up to 1 s, before the pivot unloads, see the next test)."""
    block = RigidBlock(**SLENDER)
    ag = sign * 1.5 * block.g * math.tan(block.alpha)
    tr = Trace(block, scheme, ConstantMotion(ag), grid(1.0, 0.005))
    assert_sane(tr)
    assert tr.modes[1] == (Mode.LEFT if sign > 0 else Mode.RIGHT)
    assert np.all(tr.modes[1:] == tr.modes[1])
    phi_dd0 = block.p ** 2 * (1.5 * math.cos(block.alpha) * math.tan(block.alpha) - math.sin(block.alpha))
    t1 = tr.T[1]
    # Taylor: phi = 1/2 phi_dd0 t^2 (1 + O(p^2 t^2)); MJ: O(dt/t1) = 20 % at the first output point
    tol = 2 * (block.p * t1) ** 2 + (1e-9 if scheme == "ED" else 0.25)
    assert tr.phi[1] == pytest.approx(sign * 0.5 * phi_dd0 * t1 ** 2, rel=tol)
    assert tr.impacts[-1] == 0
    assert np.all(np.sign(tr.phi[1:]) == sign) and np.all(np.diff(sign * tr.phi) > 0)
    assert sign * tr.phi[-1] > 0.5


@pytest.mark.parametrize("scheme", ["ED", "MJ"])
def test_sustained_step_lift_off_keeps_corners_above_ground(scheme):
    """Constant ag = 1.5 g tan(alpha) until overturning: at phi = 0.93 rad (t = 1.130 s) the pivot's normal
    force reaches 0 while the sticking force is 2.9 N (m g = 9.8 N): with no sliding the contact problem has
    no solution (flight accelerates the pivot into the ground at -4.4 m/s2, contact needs lambda_N < 0). Both
    schemes used to take the least-violating answer (flight) and the pivot sank through the ground while the
    block fell (ED -0.16 m, MJ -0.10 m before |phi| = pi/2). Now they take the mu -> inf limit of
    Coulomb friction there (the pivot slides with a vanishing normal force): no corner below the ground."""
    block = RigidBlock(**SLENDER)
    ag = 1.5 * block.g * math.tan(block.alpha)
    tr = Trace(block, scheme, ConstantMotion(ag), grid(2.0))
    tol = pen_tol(tr)
    assert tr.min_gap >= -tol, f"penetration {tr.min_gap:.3g} m > {tol:.3g} m"


# ================================================================================================
# Round-off: the re-run scenes of this module give the same verdicts 1 ulp off and under other kernels
# ================================================================================================
test_same_verdicts_one_ulp_off, test_same_verdicts_under_other_kernels = roundoff_tests(VERDICTS, BOUNDS)
