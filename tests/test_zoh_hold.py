"""simulate(hold="zoh") on the compiled engine is one call into C (rk_engine_sample_held): the same results as the
loop it replaces, a `Simulator.advance` per output interval under the numbers ag(t_k) (and ag_v(t_k)), with the
outputs read after each. That loop is the public API, kept here as the reference."""
from __future__ import annotations

import math

import numpy as np
import pytest

from benchmarks import scenes as S
from rocking_model import SampledMotion, Simulator, SinePulse, simulate
from rocking_model.ground_motion import as_ground_motion, checked_motion

SCHEMES = ("event_driven", "moreau_jean")
#: the benchmark scenes, shortened (the record's first 8 s hold most of its impacts)
SCENES = {s.name: s for s in S.rigid_scenes(quick=True) + S.flexible_scenes(quick=True)}
T_END = {"free": 3.0, "pulse_below": 4.0, "pulse_above": 4.0, "record": 8.0, "flex_soft": 3.0, "flex_stiff": 3.0}
#: a vertical component: zero before 0.3 s, then a pulse of 0.3 g (the held value switches between none and some)
VERTICAL = SinePulse(-0.3 * 9.81, 2 * math.pi * 3.0, t0=0.3)


def _loop(model, ground_motion, t_end, scheme, output_interval=0.01, ag_v=None, **kw):
    """The zero-order hold as a loop over Simulator.advance (what simulate ran before, on the same grid)."""
    gm = checked_motion(as_ground_motion(ground_motion))
    vert = None if ag_v is None else checked_motion(as_ground_motion(ag_v), "ag_v")
    sim = Simulator(model, scheme, impact_log_size=None, **kw)
    n = max(1, int(math.ceil((t_end - sim.t) / output_interval - 1e-9)))
    times = np.minimum(sim.t + output_interval * np.arange(n + 1, dtype=float), t_end).tolist()
    rows = [sim.outputs()]
    for k in range(n):
        if vert is None:
            sim.advance(times[k + 1], gm(times[k]))
        else:
            sim.advance(times[k + 1], gm(times[k]), ag_v=vert(times[k]))
        rows.append(sim.outputs())
    return np.array(times), {name: np.array([r[name] for r in rows]) for name in rows[0]}, sim


def _same(res, ref) -> None:
    times, values, sim = ref
    assert np.array_equal(res.t, times)
    assert list(res.values) == list(values)                 # the same outputs, in the same order
    for name, col in values.items():
        got = res[name]
        assert got.dtype == col.dtype or (col.dtype == np.float64 and got.dtype == np.float64), name
        if col.dtype == np.float64:
            assert np.max(np.abs(got - col)) <= 1e-12, name
        else:
            assert np.array_equal(got, col), name
    assert np.array_equal(res.impact_times, np.array(sim.impact_times))
    assert res.n_steps == sim.integrator.n_steps


@pytest.mark.parametrize("vertical", [False, True], ids=["horizontal", "vertical"])
@pytest.mark.parametrize("scheme", SCHEMES)
@pytest.mark.parametrize("name", list(T_END))
def test_zoh_equals_the_advance_loop(name, scheme, vertical):
    scene = SCENES[name]
    kw = dict(scene.initial, **({"tolerance": 1e-8} if scheme == "event_driven" else {"dt_max": 1e-3}))
    ag_v = VERTICAL if vertical else None
    t_end = T_END[name]
    res = simulate(scene.model(), scene.ground_motion(), t_end, scheme=scheme, hold="zoh", ag_v=ag_v, **kw)
    ref = _loop(scene.model(), scene.ground_motion(), t_end, scheme, ag_v=ag_v, **kw)
    _same(res, ref)
    if name != "free":
        assert res["impacts"][-1] > 0


@pytest.mark.parametrize("scheme", SCHEMES)
def test_zoh_of_callbacks_and_uneven_grids(scheme):
    """A plain callable (evaluated through a callback), a record whose samples are not on the output grid, a
    start time other than 0 and a last interval clipped to t_end."""
    scene = SCENES["record"]
    t, a = scene.motion[1], scene.motion[2]
    rec = SampledMotion(t[:800] + 0.0037, 1.3 * a[:800])
    f = lambda tt: 2.0 * math.sin(7.0 * tt)           # noqa: E731
    for gm, ag_v in ((rec, None), (f, None), (rec, f), (f, lambda tt: 0.0 if tt < 1.0 else 1.5)):
        kw = dict(t0=0.25, **({"tolerance": 1e-9} if scheme == "event_driven" else {}))
        res = simulate(scene.model(), gm, 5.003, scheme=scheme, hold="zoh", output_interval=0.007, ag_v=ag_v, **kw)
        _same(res, _loop(scene.model(), gm, 5.003, scheme, output_interval=0.007, ag_v=ag_v, **kw))


def test_zoh_errors_are_the_loops():
    """A callback's exception and a work limit stop the run with the loop's exception."""
    from rocking_model import RigidBlock
    from rocking_model.validation import WorkLimitError

    def bad(t):
        if t > 0.5:
            raise ZeroDivisionError("bad ag at t")
        return 1.0

    with pytest.raises(ZeroDivisionError, match="bad ag at t"):
        simulate(RigidBlock(), bad, 1.0, hold="zoh")
    with pytest.raises(ValueError, match="ag"):
        simulate(RigidBlock(), lambda t: 1e6 if t > 0.2 else 0.0, 1.0, hold="zoh")
    with pytest.raises(WorkLimitError, match="max_steps = 3"):
        simulate(RigidBlock(), SinePulse(8.0, 12.0), 1.0, hold="zoh", max_steps=3, output_interval=0.1)
