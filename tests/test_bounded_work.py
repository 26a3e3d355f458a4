"""Bounded work per step (library side): every `Simulator.advance` finishes in bounded time for every
input inside the declared ranges, never returns NaN or inf, and a refused step leaves the simulator exactly as
it was (checked with the plain-data state, `Simulator.get_state`).

The measured hangs are each either refused at construction (ValueError naming the variable and
its range) or at advance (WorkLimitError naming the cause and the way out). Wall-clock limits appear only as
a watchdog (a generous 60 s, in a thread): they are not performance assertions.
"""
from __future__ import annotations

import json
import math
import threading

import numpy as np
import pytest

from rocking_model import (AG_MAX, FlexibleOscillator, RigidBlock, SampledMotion, Simulator, WorkLimitError,
                           simulate)
from rocking_model.cosim import MotionSource
from rocking_model.ground_motion import GroundMotion, SinePulse
from rocking_model.models import PostTensionedBlock
from rocking_model.models.flexible_oscillator import OMEGA_MAX
from rocking_model.models.linear_building import LinearStorey, StoreySimulator
from rocking_model.simulation import DT_MIN_REL, MAX_STEPS

WATCHDOG = 60.0      # [s] a refusal must come long before this (measured: milliseconds to a few seconds)
SMALL = 2000         # a small work budget: exercises the limit in milliseconds


def watchdog(fn, timeout=WATCHDOG):
    """Run fn() in a thread; fail if it has not finished within ``timeout`` [s]; return its result or raise
    its exception."""
    box = {}

    def target():
        try:
            box["value"] = fn()
        except BaseException as exc:          # handed to the test thread
            box["error"] = exc
    th = threading.Thread(target=target, daemon=True)
    th.start()
    th.join(timeout)
    assert not th.is_alive(), f"still running after {timeout} s: the work is not bounded"
    if "error" in box:
        raise box["error"]
    return box.get("value")


def snapshot(sim) -> str:
    return json.dumps(sim.get_state())


def advanced(model, scheme, n=3, ag=0.5, **kw):
    """A simulator after n steps of 0.01 s under ag (rocking when phi_0 is given)."""
    sim = Simulator(model, scheme, **kw)
    for k in range(1, n + 1):
        sim.advance(0.01 * k, ag)
    return sim


def assert_refused_and_kept(sim, t_end, ag, error, match):
    """advance(t_end, ag) raises ``error`` matching ``match`` within the watchdog; the state is bit-identical
    to before, and the simulator goes on exactly like an untouched twin."""
    before = snapshot(sim)
    twin = Simulator(sim.model, sim.scheme, **_opts(sim))
    twin.set_state(sim.get_state())
    with pytest.raises(error, match=match):
        watchdog(lambda: sim.advance(t_end, ag))
    assert snapshot(sim) == before
    for k in range(1, 4):
        t = sim.t + 0.01
        sim.advance(t, 0.3)
        twin.advance(t, 0.3)
        assert sim.outputs() == twin.outputs()


def _opts(sim):
    integ = sim.integrator
    opts = dict(max_steps=sim.max_steps, impact_log_size=integ.impact_times.maxlen)
    if sim.scheme == "moreau_jean":
        return dict(opts, dt_max=integ.dt_max, theta=integ.theta)
    return dict(opts, dt_max=0.0 if integ.dt_max == math.inf else integ.dt_max, tolerance=integ.tolerance,
                method=integ.method)


# ---------------------------------------------------------------------------------------------- the measured hangs
@pytest.mark.parametrize("model", [RigidBlock(), FlexibleOscillator()], ids=["rigid", "flexible"])
def test_moreau_jean_huge_step_is_refused_before_any_work(model):
    sim = advanced(model, "moreau_jean", phi_0=0.05)
    before = snapshot(sim)
    with pytest.raises(WorkLimitError) as info:
        watchdog(lambda: sim.advance(1e12, 0.0), timeout=5.0)
    msg = str(info.value)
    for part in ("moreau_jean", "1e+15 steps", f"max_steps = {MAX_STEPS}", "dt_max", "Way out",
                 "communication steps of at most"):
        assert part in msg, (part, msg)
    assert snapshot(sim) == before


def test_moreau_jean_step_count_beyond_any_integer_is_a_work_limit():
    # 1e308 s / 1e-3 s overflows to inf steps: still the work limit, with its message, not an OverflowError
    sim = advanced(RigidBlock(), "moreau_jean", phi_0=0.05)
    before = snapshot(sim)
    with pytest.raises(WorkLimitError, match=r"needs inf steps .* Way out"):
        sim.advance(1e308, 0.0)
    assert snapshot(sim) == before


def test_moreau_jean_names_the_column_when_it_sets_the_step():
    model = FlexibleOscillator(EI=FlexibleOscillator().EI * 100.0)      # omega = 407 rad/s: dt = 0.25/omega
    sim = Simulator(model, "moreau_jean")
    with pytest.raises(WorkLimitError, match=r"0\.25/omega.*omega = 407"):
        sim.advance(1e3, 0.0)


@pytest.mark.parametrize("ag", [1.0, -1.5])           # below uplift (2 m/s2): it stays in full contact
def test_event_driven_flexible_huge_step_is_refused_and_state_kept(ag):
    # the column vibrates in full contact: explicit steps are limited to ~6/omega, 1e12 s would take 1e13
    sim = advanced(FlexibleOscillator(), "event_driven", max_steps=SMALL)
    assert_refused_and_kept(sim, 1e12, ag, WorkLimitError,
                            r"event_driven: .*max_steps = 2000 internal steps.*column omega = 40\.7.*Way out")


def test_event_driven_budget_counts_events():
    # a bouncing block (e_N = 1) keeps hitting the ground: events use the budget too
    sim = Simulator(RigidBlock(b=0.5, h=1.0, e_N=1.0), "event_driven", phi_0=0.4, max_steps=50)
    with pytest.raises(WorkLimitError):
        sim.advance(100.0, 0.0)


@pytest.mark.parametrize("scheme, dt_max", [("moreau_jean", 1e-300), ("event_driven", 1e-9),
                                            ("moreau_jean", 1e-7), ("event_driven", -1e-3)])
@pytest.mark.parametrize("model", [RigidBlock(), FlexibleOscillator()], ids=["rigid", "flexible"])
def test_tiny_dt_max_is_refused_at_construction(model, scheme, dt_max):
    lo = "0" if dt_max < 0 else f"{DT_MIN_REL * model.time_scale:.3g}"
    with pytest.raises(ValueError, match=rf"dt_max = {dt_max:g} is out of range; allowed .*{lo}"):
        Simulator(model, scheme, dt_max=dt_max)


@pytest.mark.parametrize("scheme", ["moreau_jean", "event_driven"])
def test_smallest_allowed_dt_max_works(scheme):
    model = RigidBlock()
    sim = Simulator(model, scheme, dt_max=DT_MIN_REL * model.time_scale, phi_0=0.05, max_steps=None)
    sim.advance(1e-3, 0.0)
    assert all(math.isfinite(v) for v in sim.outputs().values())
    # 0 is the scheme's default
    assert Simulator(model, scheme, dt_max=0.0).integrator.dt_max in (1e-3, math.inf)


def test_stiff_column_is_refused_at_construction():
    with pytest.raises(ValueError) as info:
        FlexibleOscillator(EI=1e15)
    msg = str(info.value)
    assert msg.startswith("EI = 1e+15 is out of range for m = 500, m_c = 30, h = 1.5; allowed range (0, ")
    assert f"OMEGA_MAX = {OMEGA_MAX:g}" in msg and "RigidBlock" in msg
    # the bound itself is accepted, just above it is not
    base = FlexibleOscillator()
    EI_max = OMEGA_MAX ** 2 * base.m_tilde * base.h ** 3 / 3.0
    assert FlexibleOscillator(EI=EI_max * (1 - 1e-12)).omega <= OMEGA_MAX
    with pytest.raises(ValueError, match="EI = "):
        FlexibleOscillator(EI=EI_max * (1 + 1e-9))


def test_stiffest_column_steps_in_bounded_time():
    model = FlexibleOscillator(EI=FlexibleOscillator().EI * (OMEGA_MAX / FlexibleOscillator().omega) ** 2 * 0.999)
    for scheme in ("moreau_jean", "event_driven"):
        sim = Simulator(model, scheme, phi_0=0.01)
        watchdog(lambda: [sim.advance(0.01 * k, 2.0) for k in range(1, 4)])
        assert all(math.isfinite(v) for v in sim.outputs().values())


# ---------------------------------------------------------------------------------------------- ground acceleration
@pytest.mark.parametrize("ag", [1.79e308, -1e150, 1e12, AG_MAX * (1 + 1e-12), math.inf, math.nan])
@pytest.mark.parametrize("scheme", ["moreau_jean", "event_driven"])
@pytest.mark.parametrize("model", [RigidBlock(), FlexibleOscillator()], ids=["rigid", "flexible"])
def test_ag_out_of_range_is_refused_naming_it(model, scheme, ag):
    sim = advanced(model, scheme, phi_0=0.05)
    kind = "is not finite" if not math.isfinite(ag) else "is out of range"
    assert_refused_and_kept(sim, sim.t + 0.01, ag, ValueError,
                            rf"^ag = .* {kind}; allowed range \[-1000, 1000\]$")


@pytest.mark.parametrize("scheme", ["moreau_jean", "event_driven"])
@pytest.mark.parametrize("model", [RigidBlock(), FlexibleOscillator(),
                                   PostTensionedBlock(m=1000.0, P0=2e4, k_t=2e6)],
                         ids=["rigid", "flexible", "post_tensioned"])
def test_ag_at_the_bound_gives_finite_outputs(model, scheme):
    """(The post-tensioned block with its tendon acting: the tendon's kinks, events of the event-driven scheme,
    under the largest accepted input.)"""
    sim = Simulator(model, scheme)
    for k in range(1, 30):
        watchdog(lambda: sim.advance(0.01 * k, AG_MAX * (-1) ** (k // 3)))
        out = sim.outputs()
        assert all(math.isfinite(float(v)) for v in out.values()), out
        if out["overturned"]:
            break


def test_a_record_beyond_ag_max_is_refused_naming_ag():
    t = np.linspace(0.0, 1.0, 101)
    rec = SampledMotion(t, 2000.0 * np.sin(2 * np.pi * t))       # e.g. cm/s2 read as m/s2
    for scheme in ("moreau_jean", "event_driven"):
        sim = Simulator(RigidBlock(), scheme)
        assert_refused_and_kept(sim, 0.5, rec, ValueError, r"^ag: the ground motion's peak \|ag\| = 2000")
        with pytest.raises(ValueError, match=r"^ag: .*peak"):
            simulate(RigidBlock(), rec, 1.0, scheme=scheme)
    for pulse in (SinePulse(1500.0, 3.0), SinePulse(800.0, 3.0).scaled(2.0)):
        with pytest.raises(ValueError, match=r"^ag: .*peak \|ag\| = 1[56]00"):
            Simulator(RigidBlock()).advance(1.0, pulse)


@pytest.mark.parametrize("bad, match", [
    (lambda t: 2000.0 if t > 0.015 else 0.0, r"^ag\(0\.01.*\) = 2000 is out of range; allowed range \[-1000, 1000\]"),
    (lambda t: math.nan if t > 0.015 else 0.0, r"^ag\(0\.01.*\) = nan is not finite"),
    (lambda t: "x", r"^ag\(.*\) must be a real number"),
])
@pytest.mark.parametrize("scheme", ["moreau_jean", "event_driven"])
@pytest.mark.parametrize("model", [RigidBlock(), FlexibleOscillator()], ids=["rigid", "flexible"])
def test_a_callable_out_of_range_stops_the_step_and_keeps_the_state(model, scheme, bad, match):
    sim = advanced(model, scheme, n=1, phi_0=0.05)
    assert_refused_and_kept(sim, 0.03, bad, ValueError, match)


def test_a_user_ground_motion_is_checked_value_by_value():
    class Wild(GroundMotion):
        def __call__(self, t):
            return 1e200 * t

    for scheme in ("moreau_jean", "event_driven"):
        sim = advanced(RigidBlock(), scheme, n=1)
        assert_refused_and_kept(sim, 0.05, Wild(), ValueError, r"^ag\(.*\) = .* is out of range")


# ---------------------------------------------------------------------------------------------- the budget itself
@pytest.mark.parametrize("value", [0, -1, 1.5, "many", math.inf, 2.0 ** 60])
def test_max_steps_is_checked(value):
    with pytest.raises(ValueError, match="max_steps"):
        Simulator(RigidBlock(), max_steps=value)


def test_max_steps_none_is_unlimited_and_the_default_is_documented():
    assert Simulator(RigidBlock()).max_steps == MAX_STEPS == 10_000
    for max_steps, refused in ((149, True), (150, False), (None, False)):
        sim = Simulator(RigidBlock(), "moreau_jean", max_steps=max_steps, dt_max=1e-3, phi_0=0.05)
        if refused:
            with pytest.raises(WorkLimitError, match="needs 150 steps"):
                sim.advance(0.15, 0.0)
        else:
            sim.advance(0.15, 0.0)
            assert sim.integrator.n_steps == 150


def test_simulate_applies_the_budget_per_output_interval():
    # 3 s of a column vibrating in full contact under a weak pulse (no events; |u| <= 4e-4 m, a third of the
    # deflection that uplifts the base): some 10^2 steps in all, one or two per 0.01 s output interval
    model = FlexibleOscillator()
    pulse = SinePulse(0.3, 2 * math.pi * 0.5)
    res = simulate(model, pulse, 3.0, scheme="event_driven", tolerance=1e-12, max_steps=20, u_0=3e-4)
    assert res.n_steps > 100 and np.all(res["contact"] == 0)
    with pytest.raises(WorkLimitError):
        simulate(model, pulse, 3.0, scheme="event_driven", tolerance=1e-12, max_steps=20, u_0=3e-4,
                 output_interval=3.0)
    model = FlexibleOscillator()
    with pytest.raises(WorkLimitError):
        simulate(model, 1.0, 1e6, scheme="event_driven", max_steps=200, output_interval=1e5)
    with pytest.raises(WorkLimitError):
        simulate(model, 1.0, 1e6, scheme="moreau_jean", max_steps=200, output_interval=1e5)


# ---------------------------------------------------------------------------------------------- components
def test_motion_source_refuses_out_of_range_values_and_keeps_its_time():
    with pytest.raises(ValueError, match=r"^ag: .*peak \|ag\| = 5000"):
        MotionSource(SinePulse(5000.0, 1.0))
    src = MotionSource(SampledMotion([0.0, 1.0, 2.0], [0.0, 10.0, 0.0]))

    class Ramp(GroundMotion):
        def __call__(self, t):
            return 600.0 * t
    src = MotionSource(Ramp())
    src.advance(1.0)
    assert src.outputs() == {"ag": 600.0, "ag_v": 0.0}      # no vertical component: ag_v = 0
    with pytest.raises(ValueError, match=r"^ag\(2\) = 1200 is out of range"):
        src.advance(2.0)
    assert src.t == 1.0 and src.outputs() == {"ag": 600.0, "ag_v": 0.0}
    for t_end in (math.nan, 0.5):
        with pytest.raises(ValueError, match="t_end"):
            src.advance(t_end)
    assert src.t == 1.0


def test_storey_bounds_and_bounded_steps():
    for T, zeta, name in ((1e-300, 0.05, "T"), (1e-4, 0.05, "T"), (1e5, 0.05, "T"), (0.5, 1e300, "zeta")):
        with pytest.raises(ValueError, match=rf"^{name} = "):
            LinearStorey(T=T, zeta=zeta)
    for T, zeta in ((1e-3, 0.0), (1e-3, 10.0), (1e4, 0.0), (0.5, 0.05)):
        sim = StoreySimulator(LinearStorey(T=T, zeta=zeta))
        for t in (0.01, 1e3, 1e12):
            watchdog(lambda: sim.advance(t, AG_MAX))
            assert all(math.isfinite(v) for v in sim.outputs().values())
    sim = StoreySimulator(LinearStorey())
    sim.advance(0.01, 1.0)
    before = sim.get_state()
    for ag in (AG_MAX * 2, math.nan):
        with pytest.raises(ValueError, match=r"^ag = "):
            sim.advance(0.02, ag)
    assert sim.get_state() == before
