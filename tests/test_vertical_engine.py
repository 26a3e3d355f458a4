"""The compiled engine under a vertical ground acceleration ag_v: ag_v = 0 is bit-identical to no vertical
component; the extension's `Engine.advance` reads ag_v and its slope (the first-order hold) and refuses bad
values naming ag_v; the engine's pair of motions equals `TwoComponentMotion` (the physics under ag_v:
tests/test_vertical_physics.py)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from c_motion import motion_eval
from rocking_model import SampledMotion, Simulator, SinePulse, TwoComponentMotion, _engine
from rocking_model.ground_motion import ConstantMotion, RectangularPulse
from rocking_model.models import FlexibleOscillator, RigidBlock

G = 9.81


def _record_pair(seed=7, dt=0.01, T=3.0):
    """(t, ag, ag_v): a smooth synthetic three-component-like record (horizontal about 0.4 g, vertical 0.3 g)."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, T + dt / 2, dt)
    env = np.sin(np.pi * t / T) ** 2
    ag = env * sum(a * np.sin(2.0 * np.pi * f * t + p) for a, f, p in
                   zip(rng.uniform(0.1, 0.2, 3) * G, (1.3, 2.1, 3.7), rng.uniform(0, 2 * np.pi, 3)))
    ag_v = env * sum(a * np.sin(2.0 * np.pi * f * t + p) for a, f, p in
                     zip(rng.uniform(0.05, 0.1, 3) * G, (4.0, 6.5, 9.0), rng.uniform(0, 2 * np.pi, 3)))
    return t, ag, ag_v


SCHEMES = ["event_driven", "moreau_jean"]
BLOCK = dict(b=0.2, h=1.0)


# ---------------------------------------------------------------------------------------------- rigid scenes
# ---------------------------------------------------------------------------------------------- flexible scenes
# ---------------------------------------------------------------------------------------------- ag_v = 0
@pytest.mark.parametrize("scheme", SCHEMES)
@pytest.mark.parametrize("kind", ["rigid", "flexible"])
def test_zero_vertical_is_bit_identical_to_none(scheme, kind):
    """ag_v = 0 as a number, as a constant vertical component of a TwoComponentMotion and through the extension
    (advance(ag_v=0.0), advance_motion / sample with vspec ('constant', 0.0)) gives the very numbers of a run
    without vertical component."""
    model = RigidBlock(**BLOCK, e_N=0.3) if kind == "rigid" else FlexibleOscillator(EI=9.45e4)
    pulse = SinePulse(0.45 * G, 2.0 * math.pi * 2.0)
    times = np.arange(1, 21) * 0.1
    runs = []
    for variant in ("none", "number", "two"):
        sim = Simulator(model, scheme, engine="c")
        rows = []
        for t in times:
            if variant == "none":
                sim.advance(float(t), pulse)
            elif variant == "number":
                sim.advance(float(t), pulse, ag_v=0.0)
            else:
                sim.advance(float(t), TwoComponentMotion(pulse, ConstantMotion(0.0)))
            rows.append(list(sim.outputs().values()) + [sim.integrator.n_steps])
        runs.append(np.array(rows))
    assert runs[0][-1, -1] > 0 and np.max(np.abs(runs[0][:, 0])) > 1e-3
    for other in runs[1:]:
        assert np.array_equal(runs[0], other)
    # the extension's entry points
    eng = [Simulator(model, scheme, engine="c").integrator._engine for _ in range(3)]
    spec = ("sine", pulse.A, pulse.omega_p, pulse.t0)
    eng[0].advance_motion(1.0, spec)
    eng[1].advance_motion(1.0, spec, vspec=("constant", 0.0))
    eng[2].advance_motion(1.0, spec, None, 0, None)
    for e in eng:
        e.advance(1.5, 0.7, 0.0, None, ag_v=0.0, ag_v_slope=0.0)
    for e in eng[1:]:
        assert e.full_state() == eng[0].full_state() and e.n_steps == eng[0].n_steps


# ---------------------------------------------------------------------------------------------- state
# ---------------------------------------------------------------------------------------------- extension
def _engine_of(scheme="event_driven", **kw):
    return Simulator(RigidBlock(**BLOCK), scheme, engine="c", **kw).integrator._engine


def test_advance_arguments():
    """The hand-written parser of Engine.advance: positional and keyword arguments as the signature says, the
    errors of the generic parser, bad ag_v values refused naming ag_v with the state unchanged."""
    eng = _engine_of(phi_0=0.05)
    eng.advance(0.1, 0.0, 0.0, None)
    eng.advance(0.2, ag0=0.1, slope=0.0, max_steps=1000, continuous=False, linear=True, ag_v=1.0, ag_v_slope=0.5,
                linear_v=False)
    eng.advance(t_end=0.25)
    eng.advance(0.3, 1, 0, 50)                          # ints as reals
    eng.advance(0.35, np.float64(0.2), ag_v=np.float64(-2.0))
    before = eng.full_state(), eng.t
    for bad, pattern in ((float("nan"), r"ag_v = nan is not finite"), (1500.0, r"ag_v = 1500 is out of range"),
                         (float("inf"), r"ag_v = inf is not finite")):
        with pytest.raises(ValueError, match=pattern):
            eng.advance(0.5, 0.0, ag_v=bad)
    with pytest.raises(ValueError, match=r"ag_v rate = nan"):
        eng.advance(0.5, 0.0, ag_v=1.0, ag_v_slope=float("nan"))
    with pytest.raises(ValueError, match=r"peak \|ag_v\|"):
        eng.advance(0.5, 0.0, ag_v=900.0, ag_v_slope=1e4)
    with pytest.raises(TypeError, match="unexpected keyword argument 'agv'"):
        eng.advance(0.5, agv=1.0)
    with pytest.raises(TypeError, match="multiple values for argument 'ag0'"):
        eng.advance(0.5, 0.0, ag0=1.0)
    with pytest.raises(TypeError, match="missing required argument 't_end'"):
        eng.advance(ag0=1.0)
    with pytest.raises(TypeError, match="at most 9 arguments"):
        eng.advance(0.5, 0.0, 0.0, None, False, False, 0.0, 0.0, False, 1.0)
    with pytest.raises(TypeError, match="'ag_v' must be a real number"):
        eng.advance(0.5, 0.0, ag_v="1")
    with pytest.raises(ValueError, match="max_steps"):
        eng.advance(0.5, 0.0, 0.0, -3)
    assert (eng.full_state(), eng.t) == before


def test_vspec_of_a_callback_vertical_motion():
    """A vertical component the engine does not describe natively runs as a Python callback (exact): the same
    numbers as its native description."""
    from rocking_model.engine import motion_spec, vertical_spec

    class Wrapped(SinePulse):
        """A subclass: not one of the classes the engine evaluates itself."""

    native = TwoComponentMotion(SinePulse(0.5 * G, 12.0), SinePulse(-0.7 * G, 20.0, 0.05))
    wrapped = TwoComponentMotion(SinePulse(0.5 * G, 12.0), Wrapped(-0.7 * G, 20.0, 0.05))
    assert vertical_spec(wrapped)[0] == "callback" and vertical_spec(native)[0] == "sine"
    assert motion_spec(native) == ("sine", 0.5 * G, 12.0, 0.0)
    assert vertical_spec(SinePulse(1.0, 1.0)) is None
    runs = []
    for gm in (native, wrapped):
        sim = Simulator(RigidBlock(**BLOCK), "event_driven", engine="c")
        sim.advance(1.0, gm)
        runs.append((sim.outputs(), sim.integrator.n_steps))
    assert runs[0] == runs[1]


def _pair_cases():
    t, ag, ag_v = _record_pair(dt=0.05, T=2.0)
    record = SampledMotion(t, ag)
    vrecord = SampledMotion(t, ag_v)
    shifted = SampledMotion(t[:20] + 0.025, ag_v[:20])         # samples between the horizontal record's
    return {
        "record pair (same samples)": TwoComponentMotion(record, vrecord),
        "records on interleaved samples": TwoComponentMotion(record, shifted),
        "record and a rectangular drop": TwoComponentMotion(record, RectangularPulse(-1.5 * G, 0.3, 0.4)),
        "sine pulses": TwoComponentMotion(SinePulse(2.0, 5.0, 0.1), SinePulse(-3.0, 9.0, 0.35)),
        "constant and a record": TwoComponentMotion(ConstantMotion(0.5), vrecord),
        "record and a constant": TwoComponentMotion(record, ConstantMotion(-2.0)),
        "a sine and its own start": TwoComponentMotion(SinePulse(2.0, 5.0, 0.5), RectangularPulse(1.0, 0.2, 0.5)),
    }


@pytest.mark.parametrize("case", sorted(_pair_cases()))
def test_the_pair_of_motions_equals_two_component_motion(case):
    """rk_motion_pair_*: the values of both components, the next breakpoint (the earlier of both) and the
    continuity at a breakpoint (both continuous, a component without a breakpoint there continuous) equal
    TwoComponentMotion's at the breakpoints of both, their neighbours and a grid."""
    from rocking_model.engine import motion_spec, vertical_spec
    gm = _pair_cases()[case]
    times = list(np.linspace(-0.3, 2.5, 701))
    bps, t = [], -1.0
    while len(bps) < 200:
        t = gm.next_breakpoint(t)
        if not math.isfinite(t):
            break
        bps.append(t)
    times += bps + [float(np.nextafter(b, 9.0)) for b in bps] + [float(np.nextafter(b, -9.0)) for b in bps]
    values, nb, cont, vvalues = motion_eval(motion_spec(gm), times, vertical_spec(gm))
    assert values == [float(gm(x)) for x in times]
    assert vvalues == [float(gm.vertical(x)) for x in times]
    assert nb == [float(gm.next_breakpoint(x)) for x in times]
    assert cont == [bool(gm.continuous_at(x)) for x in times]
