"""`Simulator(tolerances=ContactTolerances(...))`: every field is read by the scheme(s) its docstring names, in
the Python reference and in the compiled engine alike (`rocking_model.tolerances`).

Before this test the event-driven scheme solved its contact LCPs (`contact.impact`, `contact.uplift`,
`contact.next_mode`) with the default ``lcp_exact`` / ``lcp_hint`` whatever the user passed, in both engines;
only Moreau-Jean passed the user's. Each scene below changes one field to a value on the other side of a
decision the scheme makes in it (far from that decision: margins stated per scene) and checks that the result
changes, in both engines, and that the compiled engine agrees with the Python with the non-default value.
Not here: ``rise`` and ``clearly_open`` (event-driven; both engines read them, rk_ed.c as event_driven.py): no
scene was found whose outcome they change -- ``clearly_open`` only spares an uplift LCP that keeps the mode,
``rise`` only tells a bounce above round-off.
"""
from __future__ import annotations

import dataclasses
import math
import warnings

import numpy as np
import pytest

from rocking_model import RigidBlock, Simulator, _engine, contact
from rocking_model.ground_motion import SinePulse
from rocking_model.integrators import event_driven
from rocking_model.lcp import solve_contact_lcp
from rocking_model.modes import Mode
from rocking_model.tolerances import DEFAULT_TOLERANCES, ContactTolerances

G = 9.81
B, H = 0.2, 1.0
#: [rad] a tilt at which the right corner is in Painleve's configuration above mu = 1.357 (test_zeno_painleve)
PHI_P = -0.59
ENGINES = ("python", "c")
#: far above the default 1e-9, far below 1: the violations it lets through are stated per scene
LOOSE = ContactTolerances(lcp_exact=0.5)


def _spec(block):
    return ("rigid", [float(getattr(block, p.name)) for p in type(block).parameters()])


def _landing(engine, tolerances, mu=0.5, e_N=0.5):
    """The block in flight at phi = -0.59 without rotation, its right corner 1 mm above the ground, moving at
    (-1, -0.1) m/s: the corner lands sliding (U_T- = -1 m/s) at U_N- = -0.172 m/s and the impact LCP decides.
    Returns (sim, block, t_hit)."""
    block = RigidBlock(b=B, h=H, mu=mu, e_N=e_N)
    sim = Simulator(block, "event_driven", phi_0=PHI_P, on_report="raise", engine=engine, tolerances=tolerances)
    gap, U_N = 1e-3, -0.1
    state = sim.get_state()
    state.update(mode=int(Mode.FLIGHT), y=[0.0, H * math.cos(PHI_P) - B * math.sin(PHI_P) + gap, PHI_P, -1.0, U_N, 0.0])
    sim.set_state(state)
    t_hit = (U_N + math.sqrt(U_N ** 2 + 2.0 * G * gap)) / G
    return sim, block, t_hit


def _pre_impact(block, t_hit):
    """(q, v_minus) at the touch-down of `_landing` (free fall, no rotation)."""
    q = np.array([-t_hit, H * math.cos(PHI_P) - B * math.sin(PHI_P), PHI_P])
    return q, np.array([-1.0, -0.1 - G * t_hit, 0.0])


# ------------------------------------------------------------------------------------ the contact functions
@pytest.mark.parametrize("engine", ENGINES)
def test_impact_lcp_reads_lcp_exact(engine):
    """The landing's impact LCP with friction takes the first state combination that violates the conditions
    by less than lcp_exact: with the default, the slide through the impact (exact to round-off); with 0.5, the
    combination without impulse already (its violation, the approach (1 + e_N) |U_N-| over the slip |U_T-|,
    is 0.26: between the two)."""
    sim, block, t_hit = _landing("python", DEFAULT_TOLERANCES)
    q, v = _pre_impact(block, t_hit)
    out = {}
    for tol in (DEFAULT_TOLERANCES, LOOSE):
        if engine == "python":
            sol = contact.impact(block, q, v, [1], tolerances=tol)
            out[tol.lcp_exact] = (tuple(sol.active), sol.exact, sol.violation, np.asarray(sol.v))
        else:
            c = _engine.contact_model_call("impact", _spec(block), q.tolist(), v.tolist(), [1], [], -1, None,
                                           tol.lcp_exact, tol.lcp_hint)
            out[tol.lcp_exact] = (tuple(c["active"]), c["exact"], c["violation"], np.asarray(c["v"]))
    strict, loose = out[1e-9], out[0.5]
    assert strict[0] == (1,) and strict[1] and strict[2] < 1e-12
    assert loose[0] == () and loose[1] and 0.2 < loose[2] < 0.3
    np.testing.assert_array_equal(loose[3], v)                  # no impulse


@pytest.mark.parametrize("engine", ENGINES)
def test_uplift_and_next_mode_read_lcp_exact(engine):
    """A corner sliding at 1 m/s (mu = 0.5, phi = -0.59) under ag = 30 m/s2: the uplift LCP's solution is the
    slide (exact to round-off); its open combination violates the conditions by 0.327 (the corner's free normal
    acceleration over its tangential one): the mode that follows is the slide with the default lcp_exact and
    flight with 0.5."""
    block = RigidBlock(b=B, h=H, mu=0.5)
    sim = Simulator(block, "event_driven", phi_0=PHI_P, engine="python")
    state = sim.get_state()
    state.update(mode=int(Mode.RIGHT_SLIDE_NEG), y=[PHI_P, 0.0, 0.0, -1.0])
    sim.set_state(state)
    q, v = sim.state()
    gap_tol, v_tol = 1e-9 * block.length_scale, 1e-10 * math.sqrt(G * block.length_scale)
    for tol, mode, states in ((DEFAULT_TOLERANCES, Mode.RIGHT_SLIDE_NEG, (0, 3)), (LOOSE, Mode.FLIGHT, (0, 0))):
        if engine == "python":
            m, sol = contact.next_mode(block, q, v, 30.0, gap_tol, v_tol, tolerances=tol)
            up = contact.uplift(block, q, v, 30.0, [1], slip_tol=v_tol, count=True, tolerances=tol)
            got = [(int(m), tuple(sol.states), sol.exact, sol.violation), (tuple(up.states), up.violation)]
        else:
            m, sol = _engine.contact_model_call("next_mode", _spec(block), q.tolist(), v.tolist(), 30.0, gap_tol,
                                                v_tol, -1, 0.0, tol.lcp_exact, tol.lcp_hint)
            up = _engine.contact_model_call("uplift", _spec(block), q.tolist(), v.tolist(), 30.0, [1], [], v_tol,
                                            True, -1, 0.0, tol.lcp_exact, tol.lcp_hint)
            got = [(m, tuple(sol["states"]), sol["exact"], sol["violation"]), (tuple(up["states"]), up["violation"])]
        (m, st, exact, viol), (up_states, up_viol) = got
        assert m == mode and st == states == up_states and exact and viol == up_viol
        assert viol < 1e-12 if tol is DEFAULT_TOLERANCES else 0.3 < viol < 0.35


def test_mode_forces_need_no_tolerance():
    """`contact.mode_forces` forces every closed contact: one active set, whose forces do not depend on
    lcp_exact (only its exact flag would, which nobody reads) nor on lcp_hint: why it takes no tolerances."""
    block = RigidBlock(b=B, h=H)
    q, v = block.initial_state()[1:]
    W_N, W_T = block.contact_jacobians(q)
    Minv = block.inverse_mass_matrix(q)
    f = Minv @ block.forces(q, v, 3.0)
    a_N, a_T = block.contact_drift(q, v)
    P = [solve_contact_lcp(Minv, W_N, W_T, f, a_N, a_T, (0, 1), (0, 1), rtol=r, hint_tol=h).P_N
         for r, h in ((1e-300, 1e-300), (1e-9, 1e-12), (0.999, 0.999))]
    assert np.array_equal(P[0], P[1]) and np.array_equal(P[1], P[2])
    np.testing.assert_array_equal(contact.mode_forces(block, Mode.FULL, q, v, 3.0), P[1])


# ------------------------------------------------------------------------------------------ the scheme
def test_event_driven_passes_its_tolerances_to_every_contact_problem(monkeypatch):
    """Every impact and uplift LCP the Python event-driven scheme solves gets the user's `ContactTolerances`
    (a value that changes nothing here, 2e-9, so that the run is the default one)."""
    seen = []

    def spy(fn):
        def wrapper(*args, **kwargs):
            seen.append((fn.__name__, kwargs.get("tolerances")))
            return fn(*args, **kwargs)
        return wrapper

    for name in ("impact", "next_mode"):
        monkeypatch.setattr(event_driven, name, spy(getattr(contact, name)))
    mine = ContactTolerances(lcp_exact=2e-9)
    sim, _, t_hit = _landing("python", mine, mu=1.45, e_N=0.0)       # an impact, then a Painleve stick
    sim.advance(3 * t_hit, 0.0)
    Simulator(RigidBlock(b=B, h=H, e_N=0.8, impact_law=1), engine="python", tolerances=mine).advance(
        2.0, SinePulse(0.45 * G, 4 * math.pi))                          # uplifts and impact LCPs
    names = {n for n, _ in seen}
    assert names == {"impact", "next_mode"} and len(seen) > 5
    assert all(t is mine for _, t in seen), [n for n, t in seen if t is not mine]


@pytest.mark.parametrize("engine", ENGINES)
def test_landing_reads_lcp_exact(engine):
    """The scheme on `_landing`: with the default lcp_exact the corner slides through the impact and bounces
    (Newton, e_N = 0.5: it leaves at about e_N |U_N-| = 0.086 m/s, flight); with 0.5 the impact LCP takes the
    combination without impulse (`test_impact_lcp_reads_lcp_exact`), the Zeno rule then closes the corner (it
    would leave at U_N- < 0) and the re-solved, plastic LCP leaves it on the ground: another motion. The
    compiled engine equals the Python in both."""
    res = {}
    for tol in (DEFAULT_TOLERANCES, LOOSE):
        for eng in ENGINES:
            sim, block, t_hit = _landing(eng, tol)
            sim.advance(1.5 * t_hit, 0.0)
            q, v = sim.state()
            res[tol.lcp_exact, eng] = (sim.outputs(), q, v, block.contact_jacobians(q)[0].T @ v)
    for lcp_exact in (1e-9, 0.5):
        (o_py, q_py, v_py, _), (o_c, q_c, v_c, _) = res[lcp_exact, "python"], res[lcp_exact, "c"]
        assert (o_py["contact"], o_py["impacts"]) == (o_c["contact"], o_c["impacts"])
        np.testing.assert_allclose(q_c, q_py, rtol=0, atol=1e-12)
        np.testing.assert_allclose(v_c, v_py, rtol=0, atol=1e-12)
    o, _, _, U_N = res[1e-9, engine]
    assert o["contact"] == Mode.FLIGHT and o["impacts"] == 1 and U_N[1] > 0.04
    o, _, _, U_N = res[0.5, engine]
    assert o["contact"] != Mode.FLIGHT and o["impacts"] == 1 and abs(U_N[1]) < 1e-12


# ------------------------------------------------------------------------------------- every other field
def _run(scheme, engine, tolerances, mu=math.inf, amplitude=0.45, e_N=0.8, hz=2.0):
    """A 0.2 x 1 m block under a one-cycle sine pulse of ``amplitude`` g at ``hz``, 2 s sampled every 0.05 s:
    (phi, impacts, painleve, friction_demand, contact) per sample, and the scheme's step count."""
    block = RigidBlock(b=B, h=H, e_N=e_N, mu=mu)
    sim = Simulator(block, scheme, tolerances=tolerances, engine=engine, on_report="ignore",
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
def test_each_field_changes_the_run_in_both_engines(scheme, field, value, scene):
    """Each field, changed, changes the run of the scheme that reads it, in the Python and in the compiled
    engine, and both engines still agree: the same impacts, contact modes, Painleve counts and steps, phi to
    1e-9 rad. (lcp_exact of the event-driven scheme: `test_landing_reads_lcp_exact`.)"""
    tol = dataclasses.replace(DEFAULT_TOLERANCES, **{field: value})
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        runs = {(t is tol, e): _run(scheme, e, t, **scene) for t in (DEFAULT_TOLERANCES, tol) for e in ENGINES}
    for changed in (False, True):
        (py, n_py), (c, n_c) = runs[changed, "python"], runs[changed, "c"]
        assert n_py == n_c and np.array_equal(py[:, [1, 2, 4]], c[:, [1, 2, 4]])
        np.testing.assert_allclose(c, py, rtol=0, atol=1e-9)
    for engine in ENGINES:
        (base, n_base), (new, n_new) = runs[False, engine], runs[True, engine]
        assert n_new != n_base or np.max(np.abs(new - base)) > 1e-6, (engine, n_new, n_base)


@pytest.mark.parametrize("engine", ENGINES)
def test_lcp_hint_takes_the_hint_within_it(engine):
    """lcp_hint (Moreau-Jean: its last closed set is the hint of the next step's LCP): the block in full contact
    under ag = 3 m/s2 (above uplift, g b / h = 1.96 m/s2) has one corner lift; the hint "both closed" violates the
    conditions by 0.21 (the pull on the lifting corner). With lcp_exact = 0.5 (so that the hint counts as exact;
    an inexact one is superseded by the mu -> inf limit) it is taken with lcp_hint = 0.5, not with the default,
    in both engines (the least-violating set, one corner closed, otherwise). The event-driven scheme gives no
    hint."""
    block = RigidBlock(b=B, h=H)
    q, v = block.initial_state()[1:]
    W_N, W_T = block.contact_jacobians(q)
    Minv = block.inverse_mass_matrix(q)
    acc = Minv @ block.forces(q, v, 3.0)
    a_N, a_T = block.contact_drift(q, v)
    got = {}
    for tol in (LOOSE, dataclasses.replace(LOOSE, lcp_hint=0.5)):
        if engine == "python":
            sol = contact.solve_with_friction(block, Minv, W_N, W_T, acc, a_N, a_T, [0, 1], hint=[0, 1],
                                              tolerances=tol)
            got[tol.lcp_hint] = (tuple(sol.active), sol.violation)
        else:
            c = _engine.contact_model_call("solve_with_friction", _spec(block), acc.tolist(), a_N.tolist(),
                                           a_T.tolist(), [0, 1], [], None, False, [0, 1], -1, tol.lcp_exact,
                                           tol.lcp_hint, Minv.tolist(), W_N.tolist(), W_T.tolist())
            got[tol.lcp_hint] = (tuple(c["active"]), c["violation"])
    assert got[1e-12][0] == (0,) and got[1e-12][1] < 1e-12
    assert got[0.5][0] == (0, 1) and 0.15 < got[0.5][1] < 0.3


def test_paradox_scene_reads_lcp_exact_in_both_engines():
    """The uplift LCP in the scheme: the right corner sliding at 1 m/s at phi = -0.59 with mu = 1.45 (Painleve's
    configuration) under ag = 30 m/s2. With the default lcp_exact no sliding or open motion is consistent (the
    least violating, the open one, by 0.33): the stick-making impulse is applied (counted) and the block rocks
    on the corner; with 0.5 the open combination counts as a solution and the corner leaves the ground (it
    comes back at once: an impact, whose stick is the Painleve count).
    The compiled engine takes the same decisions and reaches the same state as the Python in both."""
    res = {}
    for tol in (DEFAULT_TOLERANCES, LOOSE):
        for engine in ENGINES:
            block = RigidBlock(b=B, h=H, mu=1.45)
            sim = Simulator(block, "event_driven", phi_0=PHI_P, on_report="raise", engine=engine, tolerances=tol)
            state = sim.get_state()
            state.update(mode=int(Mode.RIGHT_SLIDE_NEG), y=[PHI_P, 0.0, 0.0, -1.0])
            sim.set_state(state)
            if engine == "python":
                q, v = sim.state()
                sol = contact.next_mode(block, q, v, 30.0, 1e-9 * block.length_scale,
                                        1e-10 * math.sqrt(G * block.length_scale), tolerances=tol)[1]
                assert sol.exact == (tol is LOOSE) and 0.3 < sol.violation < 0.35 and sol.painleve != sol.exact
            sim.advance(1e-4, 30.0)
            res[tol.lcp_exact, engine] = (sim.outputs(), *sim.state())
    for lcp_exact, contact_mode, impacts in ((1e-9, Mode.RIGHT, 0), (0.5, Mode.FLIGHT, 1)):
        (o_py, q_py, v_py), (o_c, q_c, v_c) = res[lcp_exact, "python"], res[lcp_exact, "c"]
        for o in (o_py, o_c):
            assert (o["contact"], o["impacts"], o["painleve"]) == (contact_mode, impacts, 1)
        np.testing.assert_allclose(q_c, q_py, rtol=0, atol=1e-12)
        np.testing.assert_allclose(v_c, v_py, rtol=0, atol=1e-12)
