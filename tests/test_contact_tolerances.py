"""`Simulator(tolerances=ContactTolerances(...))`: every field is read by the scheme(s) its docstring names
(`rocking_model.tolerances`). Each scene below changes one field to a value on the other side of a decision the
scheme makes in it (far from that decision: margins stated per scene) and checks that the result changes.
Not here: ``rise`` and ``clearly_open`` (event-driven): no scene was found whose outcome they change --
``clearly_open`` only spares an uplift LCP that keeps the mode, ``rise`` only tells a bounce above round-off.
"""
from __future__ import annotations

import dataclasses
import math
import warnings

import numpy as np
import pytest

from rocking_model import RigidBlock, Simulator
from rocking_model.ground_motion import SinePulse
from rocking_model.modes import Mode
from rocking_model.tolerances import DEFAULT_TOLERANCES, ContactTolerances

G = 9.81
B, H = 0.2, 1.0
#: [rad] a tilt at which the right corner is in Painleve's configuration above mu = 1.357 (test_zeno_painleve)
PHI_P = -0.59
#: far above the default 1e-9, far below 1: the violations it lets through are stated per scene
LOOSE = ContactTolerances(lcp_exact=0.5)


def _landing(tolerances, mu=0.5, e_N=0.5):
    """The block in flight at phi = -0.59 without rotation, its right corner 1 mm above the ground, moving at
    (-1, -0.1) m/s: the corner lands sliding (U_T- = -1 m/s) at U_N- = -0.172 m/s and the impact LCP decides.
    Returns (sim, block, t_hit)."""
    block = RigidBlock(b=B, h=H, mu=mu, e_N=e_N)
    sim = Simulator(block, "event_driven", phi_0=PHI_P, on_report="raise", tolerances=tolerances)
    gap, U_N = 1e-3, -0.1
    state = sim.get_state()
    state.update(mode=int(Mode.FLIGHT), y=[0.0, H * math.cos(PHI_P) - B * math.sin(PHI_P) + gap, PHI_P, -1.0, U_N, 0.0])
    sim.set_state(state)
    t_hit = (U_N + math.sqrt(U_N ** 2 + 2.0 * G * gap)) / G
    return sim, block, t_hit


# ------------------------------------------------------------------------------------ the contact functions
# ------------------------------------------------------------------------------------------ the scheme
def test_landing_reads_lcp_exact():
    """The scheme on `_landing`: with the default lcp_exact the corner slides through the impact and bounces
    (Newton, e_N = 0.5: it leaves at about e_N |U_N-| = 0.086 m/s, flight); with 0.5 the impact LCP takes the
    combination without impulse (`test_impact_lcp_reads_lcp_exact`), the Zeno rule then closes the corner (it
    would leave at U_N- < 0) and the re-solved, plastic LCP leaves it on the ground: another motion."""
    res = {}
    for tol in (DEFAULT_TOLERANCES, LOOSE):
        sim, block, t_hit = _landing(tol)
        sim.advance(1.5 * t_hit, 0.0)
        q, v = sim.state()
        res[tol.lcp_exact] = (sim.outputs(), block.contact_jacobians(q)[0].T @ v)
    o, U_N = res[1e-9]
    assert o["contact"] == Mode.FLIGHT and o["impacts"] == 1 and U_N[1] > 0.04
    o, U_N = res[0.5]
    assert o["contact"] != Mode.FLIGHT and o["impacts"] == 1 and abs(U_N[1]) < 1e-12


# ------------------------------------------------------------------------------------- every other field
def _run(scheme, tolerances, mu=math.inf, amplitude=0.45, e_N=0.8, hz=2.0):
    """A 0.2 x 1 m block under a one-cycle sine pulse of ``amplitude`` g at ``hz``, 2 s sampled every 0.05 s:
    (phi, impacts, painleve, friction_demand, contact) per sample, and the scheme's step count."""
    block = RigidBlock(b=B, h=H, e_N=e_N, mu=mu)
    sim = Simulator(block, scheme, tolerances=tolerances, on_report="ignore",
                    dt_max=1e-3 if scheme == "moreau_jean" else None)
    pulse = SinePulse(amplitude * G, 2 * math.pi * hz)
    rows = []
    for k in range(1, 41):
        sim.advance(0.05 * k, pulse)
        o = sim.outputs()
        rows.append([o["phi"], o["impacts"], o["painleve"], o["friction_demand"], int(o["contact"])])
    return np.array(rows), sim.integrator.n_steps


#: (scheme, field, value, scene keywords of `_run`): a value on the other side of a decision of the scene from
#: the default (gap, rest_velocity, event, step_gap, step_rest_velocity, lcp_exact: corners counted at the
#: ground or at rest, events fired, impacts counted or solutions taken that the default does not; grazing:
#: landings put back onto the ground; stateless_step: the steps of the phase at rest under a pulse below uplift;
#: demand_floor: the friction demand of the instants when the block presses the ground with less than its weight;
#: sub_samples: a 25 ms pulse of 0.25 g (above uplift, 0.2 g) inside one 37 ms step of the phase at rest, whose
#: contact-force dip 2 samples miss and 3 to 64 find: 564 micro-uplift impacts)
FIELD_SCENES = [
    ("event_driven", "gap", 1e-3, {}),
    ("event_driven", "grazing", 1e-9, {}),
    ("event_driven", "rest_velocity", 1e-3, {}),
    ("event_driven", "event", 1e-2, {}),
    ("event_driven", "stateless_step", 1e-2, {"amplitude": 0.15}),
    ("event_driven", "sub_samples", 2, {"amplitude": 0.25, "hz": 40.0}),
    ("moreau_jean", "step_gap", 1e-3, {}),
    ("moreau_jean", "step_rest_velocity", 1e-3, {}),
    ("moreau_jean", "lcp_exact", 0.5, {"mu": 0.3}),
    ("event_driven", "demand_floor", 0.99, {"amplitude": 1.0, "e_N": 0.5, "hz": 1.0}),
    ("moreau_jean", "demand_floor", 0.99, {"amplitude": 1.0, "e_N": 0.5, "hz": 1.0}),
]


@pytest.mark.parametrize("scheme, field, value, scene", FIELD_SCENES,
                         ids=[f"{s}-{f}" for s, f, _, _ in FIELD_SCENES])
def test_each_field_changes_the_run(scheme, field, value, scene):
    """Each field, changed, changes the run of the scheme that reads it. (lcp_exact of the event-driven scheme:
    `test_landing_reads_lcp_exact`.)"""
    tol = dataclasses.replace(DEFAULT_TOLERANCES, **{field: value})
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        (base, n_base), (new, n_new) = (_run(scheme, t, **scene) for t in (DEFAULT_TOLERANCES, tol))
    assert np.all(np.isfinite(base)) and np.all(np.isfinite(new))
    assert n_new != n_base or np.max(np.abs(new - base)) > 1e-6, (n_new, n_base)

