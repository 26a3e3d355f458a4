"""Property-based invariants (hypothesis; derandomized and bounded so that the file runs in well under
60 s): random geometry, e_N, initial states and ground-motion pulses give finite outputs, no penetration
beyond the documented tolerance, no energy increase with ag = 0 (zeta >= 0, e_N = 0), and the FMU agrees
with the Python API bit for bit.

Round-off: the runs are short (0.6 s) but can be violent (pulses up to 1.5 g). `run` runs every
example a second time with a 1-ulp perturbation of its initial state and of a non-zero input amplitude
(`roundoff.Perturbation`, in-process) and asserts that the verdicts of the three invariants (finite, no
penetration beyond PEN_TOL, energy not increasing when ag = 0) are the same. (The test functions are left
as they were: hypothesis derives the derandomized examples from their source.)"""
from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rocking_model import FlexibleOscillator, RigidBlock, Simulator
from roundoff import ULP_SEED, Perturbation, describe_mismatch

SETTINGS = dict(deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow], database=None)
#: documented penetration tolerance asserted for both schemes: max over the corners of -g_N <= PEN_TOL * L
#: (L = R for the block, the base half-diagonal for the flexible oscillator), at every communication point
PEN_TOL = 1e-6
#: energy may not grow by more than this fraction of m g L between communication points when ag = 0:
#: event-driven, round-off of the RK steps and the LCPs; Moreau-Jean, its first-order drift between impacts
#: (theta = 1/2 on the nonlinear pendulum; over a grid of the strategies' ranges with e_N = 0 at dt = 1e-3 s
#: the largest growth was 1.1e-6 (block) and 3.1e-6 m g L (oscillator) per 0.02 s, falling linearly with dt)
ENERGY_TOL = {1: 1e-9, 0: 2e-5}
N_STEPS, H = 30, 0.02


#: the friction coefficient: the paper's sticking law (and its mu -> inf limit), or Coulomb's
MU = st.one_of(st.just(math.inf), st.floats(0.1, 2.0))


@st.composite
def rigid_case(draw, e_N=st.floats(0.0, 1.0)):
    b = draw(st.floats(0.05, 1.0))
    h = draw(st.floats(0.2, 3.0))
    model = RigidBlock(b=b, h=h, e_N=draw(e_N), mu=draw(MU))
    init = dict(phi_0=draw(st.floats(-0.9, 0.9)) * model.alpha, phi_dot_0=draw(st.floats(-1.0, 1.0)))
    return model, init


@st.composite
def flexible_case(draw, e_N=st.floats(0.0, 1.0)):
    model = FlexibleOscillator(b=draw(st.floats(0.15, 0.4)), EI=9.45e5 * draw(st.floats(0.2, 2.0)),
                               zeta=draw(st.floats(0.0, 0.1)), e_N=draw(e_N), mu=draw(MU))
    init = dict(phi_0=draw(st.floats(-0.05, 0.05)), u_0=draw(st.floats(-5e-4, 5e-4)))
    return model, init


def scale(model):
    mass = model.m if isinstance(model, RigidBlock) else model.M_t
    return mass * model.g * model.length_scale


def run(model, init, scheme, amplitude):
    """N_STEPS communication steps of H with a one-sine pulse of period 1 s held over each step: (rows of
    outputs, penetrations / L). The example is run again 1 ulp off; its verdicts must be the same."""
    rows, pens = run_once(model, init, scheme, amplitude)
    rows_p, pens_p = run_once(model, init, scheme, amplitude, Perturbation(ULP_SEED))
    ref = verdicts(model, amplitude, rows, pens, scheme)
    got = verdicts(model, amplitude, rows_p, pens_p, scheme)
    assert got == ref, f"1 ulp off: {describe_mismatch(got, ref)}"
    return rows, pens


def verdicts(model, amplitude, rows, pens, scheme) -> dict:
    out = {"finite": all(math.isfinite(float(v)) for row in rows for v in row.values()),
           "no_penetration": max(pens) <= PEN_TOL}
    if amplitude == 0.0:
        energy = np.array([r["energy"] for r in rows])
        out["energy_not_increasing"] = bool(np.all(np.diff(energy) <= ENERGY_TOL[scheme] * scale(model)))
    return out


def run_once(model, init, scheme, amplitude, pert: Perturbation = Perturbation()):
    """One run; ``pert`` moves the initial values and a non-zero amplitude by one ulp (ag = 0 stays 0)."""
    init = {k: pert.scalar(v, 5 + i) for i, (k, v) in enumerate(init.items())}
    if amplitude != 0.0:
        amplitude = pert.scalar(amplitude, 1)
    sim = Simulator(model, scheme, dt_max=1e-3, **init)
    rows, pens = [sim.outputs()], [0.0]
    for k in range(N_STEPS):
        # the FMU ends a step at t + dt: the same float end time gives bit-identical results
        sim.advance(H * k + H, amplitude * math.sin(2 * math.pi * k * H) if k * H < 1.0 else 0.0)
        rows.append(sim.outputs())
        q, _ = sim.state()
        pens.append(float(-model.gaps(q).min()) / model.length_scale)
    return rows, pens


CASES = st.one_of(rigid_case(), flexible_case())
#: plastic impacts (e_N = 0) only: with e_N > 0, Newton's law with sticking can create energy at impacts in
#: flight with tangential slip (a Kane-type paradox of the paper's law, measured up to 1e-3 m g L per 0.02 s
#: with e_N = 1; the energy-consistent impact law avoids it), so "energy never increases" is no invariant
PLASTIC_CASES = st.one_of(rigid_case(e_N=st.just(0.0)), flexible_case(e_N=st.just(0.0)))


@settings(max_examples=8, **SETTINGS)
@given(case=CASES, scheme=st.sampled_from([0, 1]), amplitude=st.floats(-1.5, 1.5))
def test_outputs_are_finite(case, scheme, amplitude):
    model, init = case
    rows, _ = run(model, init, scheme, amplitude * model.g)
    for row in rows:
        assert all(math.isfinite(float(v)) for v in row.values()), row


@settings(max_examples=8, **SETTINGS)
@given(case=PLASTIC_CASES, scheme=st.sampled_from([0, 1]))
def test_energy_never_increases_without_ground_motion(case, scheme):
    model, init = case
    rows, _ = run(model, init, scheme, 0.0)
    energy = np.array([r["energy"] for r in rows])
    assert np.all(np.diff(energy) <= ENERGY_TOL[scheme] * scale(model)), np.diff(energy).max() / scale(model)


@settings(max_examples=8, **SETTINGS)
@given(case=CASES, scheme=st.sampled_from([0, 1]), amplitude=st.floats(-1.5, 1.5))
def test_no_penetration_beyond_tolerance(case, scheme, amplitude):
    model, init = case
    _, pens = run(model, init, scheme, amplitude * model.g)
    assert max(pens) <= PEN_TOL, max(pens)


def test_penetration_reproducer_rigid_event_driven_bouncing():
    model = RigidBlock(b=0.23441271273593012, h=0.49238782395624286, e_N=0.6659575282786826)
    sim = Simulator(model, "event_driven", dt_max=1e-3, phi_0=-0.14497559626374124,
                    phi_dot_0=-0.00040015552639682817)
    worst = 0.0
    for k in range(1, 601):
        sim.advance(0.001 * k, 0.0)
        worst = max(worst, float(-model.gaps(sim.state()[0]).min()) / model.length_scale)
    assert worst <= PEN_TOL, worst


def test_penetration_reproducer_flexible_event_driven_start():
    model = FlexibleOscillator(b=0.28535311819837417, EI=1780742.3217688156, zeta=0.00254458609934608,
                               e_N=0.030589983033553536)
    sim = Simulator(model, "event_driven", dt_max=1e-3, phi_0=-0.02375915246235752,
                    u_0=-0.0005668012057387733)
    sim.advance(0.02, 0.0)
    assert float(-model.gaps(sim.state()[0]).min()) / model.length_scale <= PEN_TOL


@settings(max_examples=4, **SETTINGS)
@given(case=CASES, scheme=st.sampled_from([0, 1]), amplitude=st.floats(-1.5, 1.5))
def test_fmu_agrees_with_python_api(fmus, case, scheme, amplitude):
    from test_bad_input import FLEX, RIGID, Instance

    model, init = case
    kind = RIGID if isinstance(model, RigidBlock) else FLEX
    names = [f.name for f in __import__("dataclasses").fields(model) if f.init]
    params = {n: getattr(model, n) for n in names}
    inst = Instance(fmus[kind])
    inst.init(scheme=scheme, dt_max=1e-3, tolerance=1e-8, **params, **init)
    rows, _ = run(model, init, scheme, amplitude * model.g)
    out = list(rows[0])
    assert inst.get(*out) == [rows[0][n] for n in out]
    for k in range(N_STEPS):
        inst.set(ag=amplitude * model.g * math.sin(2 * math.pi * k * H) if k * H < 1.0 else 0.0)
        assert inst.step(H, t=k * H) == 0
        inst.t = H * k + H
        assert inst.get(*out) == [rows[k + 1][n] for n in out], k
    inst.free()


@pytest.fixture(scope="module")
def fmus(extracted_fmus):
    return extracted_fmus
