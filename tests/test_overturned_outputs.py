"""Outputs after overturning: they describe no motion the model no longer computes.

Convention (docs/guide/schemes.md, "Overturning"): from the first output at which ``overturned`` is true, the outputs are
those of the pose reached at |phi| = pi/2 (event-driven: located to round-off; Moreau-Jean: the end of the
step that crossed it) at rest: every velocity 0, ``energy`` the potential (and strain) energy of that pose
relative to rest (a rigid block on its side: m g (b - h)), ``contact`` = OVERTURNED (10), and none of them
changes over later steps. The command line's plot draws the overturn as such (no "sliding" after it).
"""
from __future__ import annotations

import json
import math

import numpy as np
import pytest

from rocking_model import FlexibleOscillator, RigidBlock, Simulator, SinePulse, simulate
from rocking_model.modes import OVERTURNED, Mode

G = 9.81
#: scenes far from any overturning boundary: the slender block under a 4.5 m/s2 one-sine pulse of 0.5 s
#: (overturns at 2.98 s, ED), with mu = 0.5 its pivot slides in the final fall (the case first reported: the last
#: mode before overturning is a sliding one); the flexible oscillator under a 5 g one-sine pulse of 0.5 s
SCENES = {
    "rigid": (lambda: RigidBlock(b=0.2, h=1.0), SinePulse(4.5, 4 * math.pi), 5.0),
    "rigid_mu": (lambda: RigidBlock(b=0.2, h=1.0, mu=0.5), SinePulse(4.5, 4 * math.pi), 5.0),
    "flexible": (lambda: FlexibleOscillator(), SinePulse(5.0 * G, 4 * math.pi), 3.0),
}
VELOCITIES = ("phi_dot", "x_dot", "y_dot", "u_dot")


@pytest.mark.parametrize("scheme", ["event_driven", "moreau_jean"])
@pytest.mark.parametrize("scene", sorted(SCENES))
@pytest.mark.parametrize("hold", ["exact", "zoh"])
def test_outputs_after_overturning_are_the_pose_at_rest(scene, scheme, hold):
    make, motion, t_end = SCENES[scene]
    model = make()
    res = simulate(model, motion, t_end, scheme=scheme, hold=hold, output_interval=0.01, on_report="ignore")
    over = np.asarray(res.overturned, dtype=bool)
    assert over[-1], "the scene must overturn"
    k = int(np.argmax(over))
    assert np.all(over[k:]) and k < len(over) - 50          # stays overturned, and later steps are checked
    assert abs(res.phi[k]) >= 0.5 * math.pi - 1e-9 and abs(res.phi[k]) < 0.5 * math.pi + 0.01
    # before: a motion (the last mode a contact mode); from k on: the overturned code and no velocity
    assert res.contact[k - 1] in set(int(m) for m in Mode) and abs(res.phi_dot[k - 1]) > 1.0
    assert np.all(res.contact[k:] == OVERTURNED)
    for name in VELOCITIES:
        if name in res.values:
            assert np.all(res.values[name][k:] == 0.0), name
    # nothing changes over the later steps
    for name, arr in res.values.items():
        assert np.all(arr[k:] == arr[k]), name
    # the energy is that of the reported state: the potential (and strain) energy of the pose reached
    if isinstance(model, RigidBlock):
        q = np.array([res.x[k], res.y[k] + model.h, res.phi[k]])
    else:
        q = np.array([res.u[k], res.x[k], res.y[k], res.phi[k]])
    assert res.energy[k] == pytest.approx(model.energy(q, np.zeros_like(q)), rel=1e-12, abs=1e-12)
    if isinstance(model, RigidBlock):
        # lying on its side (the pivot on the ground): the centroid at height b
        expected = model.m * model.g * (model.b - model.h)
        tol = 1e-9 if scheme == "event_driven" else 0.01          # MJ: |phi| past pi/2 by |phi_dot| dt
        assert res.energy[-1] == pytest.approx(expected, rel=tol)


@pytest.mark.parametrize("scheme", ["event_driven", "moreau_jean"])
def test_simulator_outputs_and_state_after_overturning(scheme):
    """Stepwise (as the FMUs drive it): the outputs freeze at the pose at rest, the state holds it, a moving
    state marked overturned is refused by name."""
    model = RigidBlock(b=0.1, h=1.0)
    sim = Simulator(model, scheme, phi_0=0.12)                      # tips over (phi_0 > alpha = 0.0997)
    outs = []
    for k in range(1, 401):
        sim.advance(0.01 * k, 0.0)
        outs.append(sim.outputs())
    k = next(i for i, o in enumerate(outs) if o["overturned"])
    assert k < 300
    first = outs[k]
    assert first["contact"] == OVERTURNED and first["phi_dot"] == first["x_dot"] == first["y_dot"] == 0.0
    assert all(o == first for o in outs[k:])
    state = json.loads(json.dumps(sim.get_state()))
    twin = Simulator(model, scheme)
    twin.set_state(state)
    assert twin.outputs() == first
    moving = dict(state)
    if scheme == "event_driven":
        moving["y"] = list(state["y"][:1]) + [1.0]
    else:
        moving["v"] = [0.0, 0.0, 1.0]
    with pytest.raises(ValueError, match=r"velocities must be 0 once 'overturned' is True"):
        Simulator(model, scheme).set_state(moving)


def test_contact_code_is_declared_with_its_name():
    from rocking_model.modes import OVERTURNED_DESCRIPTION
    for cls in (RigidBlock, FlexibleOscillator):
        text = cls.contact_description()
        assert text.endswith(f"{OVERTURNED} {OVERTURNED_DESCRIPTION}")
        assert cls.max_contact_code() == OVERTURNED == 10 and OVERTURNED not in {int(m) for m in Mode}
    described = {p.name: p.description for p in RigidBlock.OUTPUTS}
    assert "0 once overturned" in described["phi_dot"] and "m g (b - h)" in described["energy"]


def test_the_fmu_reports_the_overturned_pose(built_fmus):
    """The FMUs read the same outputs: contact 10 (declared max 10), no velocity, frozen."""
    fmpy = pytest.importorskip("fmpy")
    from rocking_model.fmi import run_fmu
    path = built_fmus["RigidRockingBlock"]
    md = fmpy.read_model_description(str(path))
    contact = next(v for v in md.modelVariables if v.name == "contact")
    assert int(contact.max) == OVERTURNED and "10 overturned" in contact.description
    t = np.linspace(0.0, 2.0, 201)
    ag = np.where(t < 1.0, 6.0 * np.sin(2 * np.pi * t), 0.0)
    table = np.array(list(zip(t, ag)), dtype=[("time", np.float64), ("ag", np.float64)])
    res = run_fmu(path, stop_time=2.0, output_interval=0.01, input=table, start_values={"scheme": 1})
    over = np.flatnonzero(res["overturned"])
    assert over.size > 10
    k = over[0]
    assert np.all(res["contact"][k:] == OVERTURNED) and np.all(res["phi_dot"][k:] == 0.0)
    assert np.all(res["energy"][k:] == res["energy"][k]) and res["energy"][k] < 0.0
