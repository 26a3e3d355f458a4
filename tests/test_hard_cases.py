"""Hard cases of numerical stability (issue 5), both schemes and both models where they apply.

Every test checks physical invariants on the output grid (finite values, no penetration beyond a measured
and documented tolerance, rotation on the correct side of the pivot, |phi| < pi/2 unless overturning is
expected) plus a closed form or a comparison between the schemes. Tests that fail because of a known
integrator bug keep their strict assertion and are marked ``xfail(strict=True)`` with the bug's number
(the list in the issue / the report), so that a fix shows up as XPASS.

Round-off (issue 12): the long and violent scenes (free rocking to rest under a long quiet input, large
steps, the stored 30 s record, the README quickstart that overturns) are named scenes of `roundoff`; they
are re-run 1 ulp off and under other arithmetic kernels and must give the same verdicts (section 9). Runs
that overturn are checked up to `sane_horizon`, where the documented limitation starts (docs/limitations.md).

Tolerances (measured first, then set with a margin):
- event-driven (ED): corners in contact are exact in the reduced coordinates; a corner at an event is taken
  a round-off beyond the root, so penetration <= PEN_ED = 1e-9 L (the scheme's gap_tol); a grazing chatter
  (a corner released by an infeasible sticking LCP, bug 7) lands at most GRAZE_CAP = 1e-7 L below it.
- Moreau-Jean (MJ): corners that carried impulse are projected onto the ground (round-off), a corner that
  closes inside a step penetrates by at most ~dt * |U_N| (the closing speed); PEN_MJ(dt, v) = 2 dt v.
"""
from __future__ import annotations

import functools
import math
import pathlib
import time

import numpy as np
import pytest

from rocking_model import (ConstantMotion, FlexibleOscillator, FunctionMotion, RigidBlock, SampledMotion,
                           Simulator, SinePulse, simulate)
from rocking_model.contact import inverse_mass
from rocking_model.modes import Mode

import roundoff
from roundoff import Perturbation, check_bounds, describe_mismatch, scene

G = 9.81
MOD = __name__
DATA = pathlib.Path(__file__).parent / "data" / "hard_cases"

ED = ("event_driven", dict(tolerance=1e-10))
MJ = ("moreau_jean", dict(dt_max=1e-3))
SCHEMES = {"ED": ED, "MJ": MJ}

SLENDER = dict(b=0.2, h=1.0)                       # alpha = 0.197, p = 2.69 rad/s, r = 0.942
VERY_SLENDER = dict(b=math.tan(0.02), h=1.0)       # alpha = 0.02, r = 0.9994
SQUAT = dict(b=1.5, h=1.0)                          # b/h = 1.5, sin^2(alpha) = 0.69 > 2/3


def flex(**kw):
    return FlexibleOscillator(**kw)


def stiff_flex(**kw):
    """Flexible oscillator whose column frequency is 100 p."""
    base = FlexibleOscillator(**kw)
    return FlexibleOscillator(EI=base.EI * (100 * base.p / base.omega) ** 2, **kw)


# ---------------------------------------------------------------------------------------------- helpers
class Trace:
    """States of a Simulator run on an output grid (what a co-simulation master sees)."""

    def __init__(self, model, scheme, gm, times, **kw):
        name, defaults = scheme if isinstance(scheme, tuple) else SCHEMES[scheme]
        opts = dict(defaults)
        opts.update(kw)
        self.model = model
        self.sim = Simulator(model, name, **opts)
        self.scheme = name
        q, v = self.sim.state()
        self.t = [self.sim.t]
        self.q, self.v = [np.array(q)], [np.array(v)]
        self.mode, self.impacts, self.overturned = [self.sim.integrator.mode], [0], [False]
        t0 = time.perf_counter()
        self.extend(gm, times)
        self.wall = time.perf_counter() - t0

    def extend(self, gm, times):
        for tk in times:
            self.sim.advance(float(tk), gm)
            q, v = self.sim.state()
            I = self.sim.integrator
            self.t.append(self.sim.t)
            self.q.append(np.array(q))
            self.v.append(np.array(v))
            self.mode.append(int(I.mode))
            self.impacts.append(int(I.impacts))
            self.overturned.append(bool(I.overturned))
        return self

    @property
    def T(self):
        return np.array(self.t)

    @property
    def phi(self):
        return np.array(self.q)[:, self.model.phi_index]

    @property
    def phi_dot(self):
        return np.array(self.v)[:, self.model.phi_index]

    @property
    def modes(self):
        return np.array(self.mode)

    @property
    def energy(self):
        return np.array([self.model.energy(q, v) for q, v in zip(self.q, self.v)])

    @property
    def min_gap(self):
        return min(float(self.model.gaps(q).min()) for q in self.q)

    @property
    def n_steps(self):
        return self.sim.integrator.n_steps


def grid(t_end, dt=0.01, t0=0.0):
    n = int(round((t_end - t0) / dt))
    return t0 + dt * np.arange(1, n + 1)


def pen_tol(tr, dt=None, v=None):
    """Documented penetration tolerance of a run: ED 1e-9 L; MJ 2 dt v (v: the largest closing speed of a
    corner, default the largest corner speed seen on the grid)."""
    L = tr.model.length_scale
    if tr.scheme == "event_driven":
        return 1e-9 * L
    dt = tr.sim.integrator.dt_max if dt is None else dt
    if v is None:
        v = max(float(np.max(np.abs(tr.model.contact_jacobians(q)[0].T @ w))) for q, w in zip(tr.q, tr.v))
    return max(2.0 * dt * v, 1e-12 * L)


def sane_horizon(phi, modes, overturned, alpha: float) -> int:
    """Number of leading output samples on which the geometric invariants are the model's own promise.

    The no-sliding contact law has no consistent solution once an overturning body has fallen past its
    tipping point and its pivot unloads (lambda_N -> 0 while the sticking force is not 0: the pivot's free
    normal acceleration is negative, so 'closed' needs tension and 'open' penetrates; physics.md section 6),
    nor for a landing at a steep angle on a sliding corner (bug 7). Both happen only in the *final fall*
    of an overturning run: the samples after the last one within the tipping angle (|phi| <= alpha) before
    the overturning flag is set. The checks therefore cover
    - every sample of a run that does not overturn;
    - in a run that overturns: everything up to its final fall, and the final fall as long as the body
      still rocks on its outer pivot (phi > 0: LEFT); they stop at the first sample of the final fall off
      that pivot (lift-off or flight: from there on the corner may sink, which docs/limitations.md
      measures; test_overturning_lift_off_sinks_a_corner_as_documented).
    The frozen samples after overturning repeat the overturning state and are checked with it when it was
    reached on the pivot."""
    phi, modes, overturned = np.asarray(phi), np.asarray(modes), np.asarray(overturned, dtype=bool)
    n = len(phi)
    if not overturned.any():
        return n
    k_ov = int(np.argmax(overturned))
    inside = np.nonzero(np.abs(phi[:k_ov]) <= alpha)[0]
    k_fall = int(inside[-1]) + 1 if inside.size else 0
    pivot = Mode.LEFT if phi[k_ov] > 0 else Mode.RIGHT
    off = np.nonzero(modes[k_fall:k_ov + 1] != pivot)[0]
    return k_fall + int(off[0]) if off.size else n


def sanity_report(tr, overturn_ok=False, pen=None) -> dict:
    """The invariants of `assert_sane` as a dict: ``finite``, ``no_penetration``, ``right_side``,
    ``bounded_rotation`` (|phi| < pi/2 without overturning, or <= pi/2 + 0.05 when overturning is allowed),
    ``not_overturned`` (only when overturning is not allowed), each a bool, plus ``messages`` (why not) and
    the figures ``horizon`` (samples checked, see `sane_horizon`), ``min_gap`` [m] over them and ``tol`` [m]."""
    q, v = np.array(tr.q), np.array(tr.v)
    out = {"finite": bool(np.all(np.isfinite(q)) and np.all(np.isfinite(v))), "messages": []}
    phi, modes = tr.phi, tr.modes
    n = sane_horizon(phi, modes, tr.overturned, tr.model.alpha) if overturn_ok else len(phi)
    tol = pen_tol(tr) if pen is None else pen
    min_gap = min(float(tr.model.gaps(qk).min()) for qk in tr.q[:n]) if n else 0.0
    out["no_penetration"] = bool(min_gap >= -tol)
    if not out["no_penetration"]:
        out["messages"].append(f"penetration {min_gap:.3g} m > {tol:.3g} m")
    phi_n, modes_n = phi[:n], modes[:n]
    # MJ reports the corners that carried impulse in the last step: at an impact step phi may still be on
    # the old side by up to dt |phi_dot|
    side = 1e-9 if tr.scheme == "event_driven" else \
        2 * tr.sim.integrator.dt_max * float(np.max(np.abs(tr.phi_dot))) + 1e-12
    left = (modes_n == Mode.LEFT) & (phi_n < -side)
    right = (modes_n == Mode.RIGHT) & (phi_n > side)
    bad = np.nonzero(left | right)[0]
    out["right_side"] = not bad.size
    if bad.size:
        out["messages"].append(f"rocking through the ground: t = {tr.T[bad[0]]:.6g} s, contact = "
                               f"{modes_n[bad[0]]}, phi = {phi_n[bad[0]]:.3g} rad")
    if overturn_ok:
        out["bounded_rotation"] = bool(np.all(np.abs(phi) <= 0.5 * math.pi + 0.05))
    else:
        out["not_overturned"] = not any(tr.overturned)
        if not out["not_overturned"]:
            out["messages"].append(f"overturned at t = {tr.T[np.argmax(tr.overturned)]:.6g} s")
        out["bounded_rotation"] = bool(np.all(np.abs(phi_n) < 0.5 * math.pi))
    if not out["bounded_rotation"]:
        out["messages"].append(f"max |phi| = {np.max(np.abs(phi)):.6g} rad")
    out.update(horizon=n, min_gap=min_gap, tol=tol)
    return out


SANITY_KEYS = ("finite", "no_penetration", "right_side", "bounded_rotation", "not_overturned")


def assert_sane(tr, overturn_ok=False, pen=None):
    """Finite, no penetration beyond the documented tolerance, each pivot on its own side, |phi| < pi/2
    and no overturning unless overturning is allowed (then the geometric checks stop where the documented
    limitation starts, see `sane_horizon`)."""
    rep = sanity_report(tr, overturn_ok, pen)
    failed = [k for k in SANITY_KEYS if k in rep and not rep[k]]
    assert not failed, f"{failed}: {'; '.join(rep['messages'])}"
    return rep


def rigid_energy_ratio(block, v_minus, v_plus):
    T = lambda v: 0.5 * (block.m * (v[0] ** 2 + v[1] ** 2) + block.I_c * v[2] ** 2)  # noqa: E731
    return T(v_plus) / T(v_minus)


MODELS = {
    "rigid": lambda: RigidBlock(**SLENDER),
    "flexible": lambda: FlexibleOscillator(),
}


# ================================================================================================
# 1. Impact accumulation at the end of free rocking; rest is exact and stays exact
# ================================================================================================
# Rigid block b = 0.3, h = 1 (r = 0.876) from phi_0 = 0.15 comes to rest at ~5.7 s; the flexible default
# specimen from phi_0 = 0.05 at ~10.4 s. Then a long quiet input below the uplift threshold follows.
FREE = {
    "rigid": (lambda: RigidBlock(b=0.3, h=1.0), dict(phi_0=0.15), 8.0),
    "flexible": (lambda: FlexibleOscillator(), dict(phi_0=0.05), 14.0),
}
QUIET_T = {"event_driven": 60.0, "moreau_jean": 20.0}
MJ_SETTLE = ("moreau_jean", dict(dt_max=2e-3))


def quiet_input(model, pert: Perturbation = Perturbation()):
    """Low-level input: 0.3 g tan(alpha) for the block; 0.03 g for the column (static u = 2e-4 m, uplift
    needs ~1.2e-3 m), two incommensurate sines."""
    A = 0.3 * model.g * math.tan(model.alpha) if isinstance(model, RigidBlock) else 0.03 * G
    A = pert.scalar(A, 3)
    return FunctionMotion(lambda t: A * (0.6 * math.sin(2 * math.pi * 1.3 * t) + 0.4 * math.sin(7.1 * t)))


def settle_scene(model_name: str, scheme_name: str, pert: Perturbation):
    """Free rocking from phi_0 to rest, then the quiet input (60 s ED, 20 s MJ): the outcome (exact rest
    from t_rest on) is far from a boundary, the quiet input being 0.3 of the uplift threshold."""
    make, ini, t_rest = FREE[model_name]
    model = make()
    scheme = ED if scheme_name == "ED" else MJ_SETTLE
    ini = {k: pert.scalar(v, 5 + i) for i, (k, v) in enumerate(ini.items())}
    tr = Trace(model, scheme, 0.0, grid(t_rest), **ini)
    tr.k_rest = len(tr.t) - 1
    tr.extend(quiet_input(model, pert), grid(t_rest + QUIET_T[tr.scheme], 0.01, t_rest))
    return tr, dict(rest_after=t_rest)


#: verdicts of the scenes of this module that are re-run 1 ulp off and under other kernels, and the
#: documented margins of their figures (filled next to each scene)
VERDICTS: dict[str, dict] = {}
BOUNDS: dict[str, dict] = {}
QUIET_VERDICT = dict(finite=True, no_penetration=True, right_side=True, bounded_rotation=True,
                     overturned=False, at_rest_at_end=True)
for _m in ("rigid", "flexible"):
    for _s in ("ED", "MJ"):
        scene(f"settle_{_m}_{_s}")(functools.partial(settle_scene, _m, _s))
    # (the MJ runs cost 4 s each: the long MJ records of test_extreme_inputs cover that scheme)
    VERDICTS[f"{MOD}:settle_{_m}_ED"] = dict(QUIET_VERDICT, **({"energy_below_tipping": True}
                                                               if _m == "rigid" else {}))
    # released at 0.51 alpha (rigid, E/E_tip = 0.76) / 0.25 alpha (flexible); the quiet input keeps it down
    BOUNDS[f"{MOD}:settle_{_m}_ED"] = dict(max_phi_over_alpha=(0.45, 0.6) if _m == "rigid" else (0.2, 0.3))


@functools.lru_cache(maxsize=None)
def nominal(key: str):
    return roundoff.run_scene(key)


@functools.lru_cache(maxsize=None)
def settle_run(model_name, scheme_name):
    tr, _ = nominal(f"{MOD}:settle_{model_name}_{scheme_name}")
    return tr, tr.k_rest


kernel_rerun = roundoff.kernel_rerun_fixture(VERDICTS)


@pytest.mark.parametrize("scheme", ["ED", "MJ"])
@pytest.mark.parametrize("model_name", ["rigid", "flexible"])
def test_impact_accumulation_reaches_full_contact(model_name, scheme, kernel_rerun):
    """Free rocking from 0.51 alpha (block) / 0.25 alpha (column) ends in full contact before t_rest and stays
    there under the quiet input (below the uplift threshold): a verdict far from any boundary, the same 1 ulp
    off and under other kernels (ED scenes, section 9)."""
    tr, k = settle_run(model_name, scheme)
    assert_sane(tr)
    key = f"{MOD}:settle_{model_name}_{scheme}"
    if key in VERDICTS:
        summary = nominal(key)[1]
        assert summary["verdict"] == VERDICTS[key], describe_mismatch(summary["verdict"], VERDICTS[key])
        check_bounds(summary["figures"], BOUNDS[key], key)
    modes = tr.modes
    assert modes[k] == Mode.FULL, f"not at rest after {tr.t[k]} s"
    # full contact is reached once and for all: no spurious rocking afterwards, not under the quiet input
    first = int(np.nonzero(modes != Mode.FULL)[0][-1]) + 1
    assert first <= k and np.all(modes[first:] == Mode.FULL)
    assert tr.impacts[-1] == tr.impacts[first]
    assert np.max(np.abs(tr.phi[first:])) < 1e-12
    # bounded work: impacts and steps
    assert 2 <= tr.impacts[-1] < 200
    if tr.scheme == "event_driven":
        assert tr.n_steps < 20 * len(tr.t)          # the quiet input costs ~1 step per output interval
    else:
        assert tr.n_steps == pytest.approx(tr.t[-1] / 2e-3, rel=1e-9)


@pytest.mark.parametrize("scheme", ["ED", "MJ"])
@pytest.mark.parametrize("model_name", ["rigid", "flexible"])
def test_rest_is_exact_under_long_quiet_input(model_name, scheme):
    tr, k = settle_run(model_name, scheme)
    modes = tr.modes
    first = int(np.nonzero(modes != Mode.FULL)[0][-1]) + 1
    phi, phi_dot = tr.phi[first:], tr.phi_dot[first:]
    q = np.array(tr.q[first:])
    assert np.all(phi == 0.0) and np.all(phi_dot == 0.0), (np.abs(phi).max(), np.abs(phi_dot).max())
    # the base does not drift: x = 0 and y at rest exactly
    rest = tr.model.rest_position()
    dofs = [1, 2] if model_name == "flexible" else [0, 1]
    assert np.all(q[:, dofs] == rest[dofs])


def test_event_driven_zeno_count_matches_its_rule():
    """The Zeno rule stops the accumulation once the separation speed 2 b |phi_dot+| of the lifting corner
    falls below v_Zeno = zeno_tol sqrt(g R): with Housner's r the impact count is a closed form."""
    block = RigidBlock(b=0.3, h=1.0)
    phi_0 = 0.15
    sim = Simulator(block, "event_driven", tolerance=1e-12, phi_0=phi_0)
    sim.advance(10.0, 0.0)
    assert sim.integrator.mode == Mode.FULL
    p, a, r = block.p, block.alpha, block.housner_r
    w1 = p * math.sqrt(2 * (math.cos(a - phi_0) - math.cos(a)))      # first impact speed
    v_z = 1e-6 * math.sqrt(block.g * block.R)
    # impacts n = 1, 2, ... leave the old pivot at 2 b w1 r^n; the first one below v_Zeno closes it
    n = math.ceil(math.log(v_z / (2 * block.b * w1)) / math.log(r))
    assert abs(sim.integrator.impacts - n) <= 1, (sim.integrator.impacts, n)
    # the accumulation time is the geometric sum of the half periods (linearised: sum ~ r^n)
    t_acc = sim.integrator.impact_times[-1]
    assert t_acc < 10.0


# ================================================================================================
# 2. Very slender and squat blocks, e_N = 0 and e_N = 1
# ================================================================================================
@pytest.mark.parametrize("dims", [VERY_SLENDER, SLENDER, dict(b=0.5, h=1.0)], ids=["alpha0.02", "alpha0.2",
                                                                                    "alpha0.46"])
def test_housner_restitution_every_impact_event_driven(dims):
    block = RigidBlock(**dims)
    phi_0 = 0.5 * block.alpha
    sim = Simulator(block, "event_driven", tolerance=1e-11, phi_0=phi_0)
    sim.advance(6.0, 0.0)
    log = sim.integrator.impact_log
    assert len(log) >= 3
    p, a, r = block.p, block.alpha, block.housner_r
    w0 = p * math.sqrt(2 * (math.cos(a - phi_0) - math.cos(a)))
    for n, (t, vm, vp) in enumerate(log[:10]):
        assert vp[2] / vm[2] == pytest.approx(r, rel=1e-11)
        assert abs(vm[2]) == pytest.approx(w0 * r ** n, rel=1e-7)
        assert rigid_energy_ratio(block, vm, vp) == pytest.approx(r ** 2, rel=1e-11)


@pytest.mark.parametrize("scheme,kw,tol", [("ED", {}, 1e-9), ("MJ", dict(dt_max=2.5e-4), 0.03)],
                         ids=["ED", "MJ-dt2.5e-4"])
def test_very_slender_block_energy_decay(scheme, kw, tol):
    """alpha = 0.02, e_N = 0: each impact keeps r^2 = 0.9988 of the energy (Housner); after n impacts
    E/E0 = r^(2n). Moreau-Jean's extra dissipation per impact is O(dt) but large against alpha: measured
    E/E0 after 5 s = 0.771 (dt 1e-3), 0.976 (2.5e-4), 0.988 (1e-4) against r^(2n) = 0.993..0.994, so the
    run uses dt = 2.5e-4 s (p dt = alpha/30) and 3 s."""
    block = RigidBlock(**VERY_SLENDER)
    tr = Trace(block, scheme, 0.0, grid(3.0), phi_0=0.5 * block.alpha, **kw)
    assert_sane(tr)
    E = tr.energy
    n = tr.impacts[-1]
    assert n == 3
    expected = block.housner_r ** (2 * n)
    assert E[-1] / E[0] == pytest.approx(expected, abs=tol)


@pytest.mark.parametrize("scheme", ["ED", "MJ"])
def test_squat_block_stops_at_first_impact(scheme):
    """b/h = 1.5, e_N = 0: the first impact brings the block to full contact for good."""
    block = RigidBlock(**SQUAT)
    tr = Trace(block, scheme, 0.0, grid(3.0), phi_0=0.5 * block.alpha)
    assert_sane(tr)
    assert tr.impacts[-1] == 1
    k = int(np.argmax(np.array(tr.impacts) == 1))
    assert np.all(tr.modes[k:] == Mode.FULL)
    assert np.max(np.abs(tr.energy[k:])) < 1e-12 * tr.energy[0]


@pytest.mark.parametrize("scheme", ["ED", "MJ"])
def test_squat_block_elastic_rocking_conserves_energy(scheme):
    """b/h = 1.5, e_N = 1: every impact is at phi = 0 with both corners at the ground and sends the block back
    on its old pivot with phi_dot+ = -phi_dot- (no flight, pure rocking): energy is conserved exactly by the
    impact law, to the scheme's accuracy by the run."""
    block = RigidBlock(**SQUAT, e_N=1.0)
    tr = Trace(block, scheme, 0.0, grid(5.0), phi_0=0.5 * block.alpha)
    assert_sane(tr)
    assert tr.impacts[-1] >= 3
    assert np.all(np.isin(tr.modes, [Mode.LEFT, Mode.FULL]))
    E = tr.energy
    if tr.scheme == "event_driven":
        assert np.max(np.abs(E / E[0] - 1)) < 1e-9
        for _, vm, vp in tr.sim.integrator.impact_log:
            assert vp[2] == pytest.approx(-vm[2], rel=1e-12)
    else:
        # O(dt) per impact: measured 1.4 % loss over 4 impacts at dt = 1e-3 s
        assert np.max(np.abs(E / E[0] - 1)) < 0.03


@pytest.mark.parametrize("dims", [SLENDER, SQUAT], ids=["slender", "squat"])
def test_elastic_impact_energy_balance(dims):
    """e_N = 1: Newton's law with sticking changes the kinetic energy by exactly the work of the sticking
    percussion, Delta T = sum_i P_T,i (U_T,i+ + U_T,i-)/2 = 1/2 sum_i P_T,i U_T,i- (normal: U_N+ = -U_N-;
    tangential: U_T+ = 0 where P_N > 0).
    - flat impacts (rocking into phi = 0, both corners at the ground): the impacting corner moves vertically,
      U_T- = 0, so Delta T = 0 exactly: energy is conserved (slender: flight; squat: rock back);
    - a single-corner landing at phi != 0 from flight: Delta T = 1/2 P_T U_T- != 0, of either sign: the
      impact law itself can add energy (Kane-type paradox of Newton's law with sticking), independent of the
      scheme."""
    from rocking_model.contact import impact
    block = RigidBlock(**dims, e_N=1.0)
    M = block.mass_matrix(None)
    T = lambda v: 0.5 * float(v @ M @ v)  # noqa: E731
    # flat impact
    for pivot, w in ((Mode.LEFT, -0.7), (Mode.RIGHT, 0.7)):
        q, v = block.embed(pivot, np.array([0.0]), np.array([w]))
        sol = impact(block, q, v, (0, 1))
        assert T(sol.v) == pytest.approx(T(v), rel=1e-12)
    # tilted landings from flight on one corner: sweep the pre-impact velocities
    rng = np.random.default_rng(5)
    gains = []
    for _ in range(200):
        phi = rng.uniform(-0.1, 0.1)
        q = np.array([0.0, 0.0, phi])
        q[1] -= block.gaps(q).min()             # lower corner (left for phi > 0) exactly at the ground
        v = np.array([rng.uniform(-1, 1), rng.uniform(-1, -0.1), rng.uniform(-1, 1)])
        W_N, W_T = block.contact_jacobians(q)
        cand = [i for i in (0, 1) if block.gaps(q)[i] <= 1e-12 and W_N[:, i] @ v < 0]
        if not cand:
            continue
        sol = impact(block, q, v, cand)
        if not sol.exact:
            continue            # no sticking solution: see test_single_corner_landing_lcp_is_solvable
        U_T = W_T.T @ v
        work = 0.5 * float(sol.P_T @ U_T)
        assert T(sol.v) - T(v) == pytest.approx(work, abs=1e-12 * T(v))
        gains.append((T(sol.v) - T(v)) / T(v))
    gains = np.array(gains)
    assert gains.size > 100
    # the energy gain exists (this is a property of the impact law, reported in issue 5)
    assert gains.max() > 1e-3


def random_landings(block, n, seed=5):
    """Single-corner landings from flight: |phi| < 0.1, the lower corner at the ground and approaching."""
    rng = np.random.default_rng(seed)
    for _ in range(n):
        phi = rng.uniform(-0.1, 0.1)
        q = np.array([0.0, 0.0, phi])
        q[1] -= block.gaps(q).min()
        v = np.array([rng.uniform(-1, 1), rng.uniform(-1, -0.1), rng.uniform(-1, 1)])
        W_N = block.contact_jacobians(q)[0]
        cand = [i for i in (0, 1) if block.gaps(q)[i] <= 1e-12 and W_N[:, i] @ v < 0]
        if cand:
            yield q, v, cand


@pytest.mark.xfail(strict=True, reason="bug 7 (model): sticking impact LCP has no solution for some single-corner "
                                       "landings (P_N < 0 needed); 94/1400 squat e_N=0")
@pytest.mark.parametrize("dims,e_N", [(SQUAT, 0.0), (SQUAT, 1.0), (SLENDER, 0.0)],
                         ids=["squat-eN0", "squat-eN1", "slender-eN0"])
def test_single_corner_landing_lcp_is_solvable(dims, e_N):
    """The impact LCP with sticking only on contacts that carry a normal percussion has no solution when the
    approaching corner slides fast enough: sticking needs P_N < 0, no percussion leaves U_N+ < 0. Measured
    on 2000 random landings (seed 5): squat e_N = 0: 94 of 1400, squat e_N = 1: 30 of 1400, slender e_N = 0:
    2 of 1991. Reproducer (squat, e_N = 0): q = [0, 1.0300783529746902, 0.02018947388005939],
    v = [0.7721503228607063, -0.6854465730944519, -0.26719040218723555], candidates (0,): sticking gives
    P_N = -0.031, the fallback (no percussion) leaves U_N = -0.29 m/s. The limit mu -> inf of Coulomb
    friction has a solution (P_N -> 0+, finite P_T, sliding, U_N+ = -e_N U_N-): the law needs that case."""
    from rocking_model.contact import impact
    block = RigidBlock(**dims, e_N=e_N)
    bad = [(q, v) for q, v, cand in random_landings(block, 2000) if not impact(block, q, v, cand).exact]
    assert not bad, f"{len(bad)} landings without a solution, first q = {bad[0][0]!r}, v = {bad[0][1]!r}"


@pytest.mark.parametrize("scheme", ["ED", "MJ"])
def test_elastic_flat_impact_conserves_energy_to_scheme_accuracy(scheme):
    """b = 0.2, h = 1, e_N = 1, released from phi_0 = alpha/2: the first impact is flat (phi = 0, both corners
    at the ground, U_T- = 0), so the impact law conserves the energy exactly. ED: 1e-12. MJ: the impact is
    taken at phi ~ dt phi_dot/2 != 0, where the sticking percussion works: first-order loss, measured 1.2 %
    at dt = 1e-3 s and 0.10 % at 1e-4 s."""
    block = RigidBlock(**SLENDER, e_N=1.0)
    losses = {}
    for dt in ((None,) if scheme == "ED" else (1e-3, 1e-4)):
        kw = {} if dt is None else dict(dt_max=dt)
        tr = Trace(block, scheme, 0.0, grid(0.51, 0.001), phi_0=0.5 * block.alpha, **kw)
        assert tr.impacts[-1] == 1                     # the second impact comes at 0.529 s
        E = tr.energy
        losses[dt] = 1.0 - E[-1] / E[0]
    if scheme == "ED":
        assert abs(losses[None]) < 1e-11
    else:
        assert 0 <= losses[1e-3] < 0.025 and 0 <= losses[1e-4] < 0.0025
        assert losses[1e-3] / losses[1e-4] > 5              # first order


@pytest.mark.parametrize("scheme", ["ED", "MJ"])
def test_elastic_very_slender_block_bounces_above_ground(scheme):
    """alpha = 0.02, e_N = 1: after the first (flat) impact the block bounces on its corners (ED: hundreds of
    impacts 0.4 ms apart). Corners must stay above the ground. ED once lost this (bug 10): after an impact at
    t = 0.48596 s the right corner restarted flight at g = -1e-10 m (a grazing landing fired event_tol below
    the ground) with U_N = +1.9 mm/s, rose 2e-7 m and came back down within the first DOP853 step; its event
    was never armed (not seen > 0 at a step end, the 'watch' margin used up at the start), so it sank to
    -4.0e-4 m (4e-4 R) at 1.14 s, in flight. Now a bounce inside the first step is searched for and a
    grazing landing is put back onto the ground."""
    block = RigidBlock(**VERY_SLENDER, e_N=1.0)
    tr = Trace(block, scheme, 0.0, grid(1.5), phi_0=0.5 * block.alpha)
    assert_sane(tr)
    E = tr.energy
    assert np.all(E <= E[0] * (1 + 1e-6))


# ================================================================================================
# 3. Grazing uplift and near-threshold pulses (uplift at g tan(alpha))
# ================================================================================================
@pytest.mark.parametrize("scheme", ["ED", "MJ"])
@pytest.mark.parametrize("factor", [1.0, 1.00005, 1.001], ids=["A=gtan", "A=1.00005gtan", "A=1.001gtan"])
def test_grazing_uplift_at_threshold(scheme, factor):
    """One-sine pulse whose amplitude is g tan(alpha) (or barely above): the block lifts by a hair at most and
    must neither overturn nor rock through the ground (bug 1)."""
    block = RigidBlock(**SLENDER)
    A = factor * block.g * math.tan(block.alpha)
    tr = Trace(block, scheme, SinePulse(A, 2 * math.pi), grid(3.0))
    assert_sane(tr)
    assert np.max(np.abs(tr.phi)) < 1e-3
    if factor == 1.0:
        assert np.max(np.abs(tr.phi)) < 1e-9


@pytest.mark.parametrize("scheme", ["ED", "MJ"])
def test_near_threshold_pulse_small_rocking(scheme):
    """A = 2.0 m/s2 against g tan(alpha) = 1.962: the block rocks with |phi| ~ 6e-5 rad. Each impact scales
    the corner speed by r = 1 - 1.5 sin^2(alpha) (Housner), and impacts slower than v_Zeno end the
    accumulation, so one rocking episode has at most ln(v_1 / v_Zeno) / -ln r + 1 impacts, v_1 = 2 b
    max|phi_dot|; two episodes (one per lobe). ED resolves them (228 here, against a bound of 2 x 109);
    MJ at dt = 1e-3 s sees 2 (it cannot resolve a 6e-5 rad rocking: accuracy, not stability)."""
    block = RigidBlock(**SLENDER)
    tr = Trace(block, scheme, SinePulse(2.0, 2 * math.pi), grid(4.0))
    assert_sane(tr)
    assert 1e-5 < np.max(np.abs(tr.phi)) < 2e-4
    assert tr.modes[-1] == Mode.FULL
    r = 1.0 - 1.5 * math.sin(block.alpha) ** 2
    v_1 = 2.0 * block.b * np.max(np.abs(tr.phi_dot))
    v_zeno = 1e-6 * math.sqrt(block.g * block.length_scale)
    per_episode = math.log(v_1 / v_zeno) / -math.log(r) + 1.0
    assert 1 <= tr.impacts[-1] <= 2.0 * 1.1 * per_episode


# ================================================================================================
# 4. Near the overturning boundary: classification agrees between the schemes outside a band
# ================================================================================================
# One-sine pulses on b = 0.2, h = 1 (p = 2.69 rad/s), amplitude f g tan(alpha). Boundaries of the
# event-driven scheme (tolerance 1e-10, bisection to 2e-4) and of Moreau-Jean at dt = 2e-3 / 1e-3 / 5e-4 s:
#   omega_p = 2p: 1.2198 (MJ +0.65 / +0.39 / +0.14 %), 2.3366 (-0.35 / -0.15 / -0.08 %),
#                 3.6810 (+0.36 / +0.17 / +0.08 %)   [overturn in (1.22, 2.34) and above 3.68: not monotone]
#   omega_p = 4p: 1.7255 (MJ dt 1e-3 +2.0 %, 5e-4 +1.1 %), 5.1048 (-1.3 %, -0.6 %)  [overturn in between]
#   omega_p = 6p: 4.0991 (MJ dt 1e-3 +7.1 %, 5e-4 +2.5 %)
# The band where the schemes disagree shrinks with dt (first order); at dt = 1e-3 s it is documented as
# BAND[k] (relative), about twice the measured offset.
OVERTURN_BLOCK = SLENDER
ED_BOUNDARIES = {2: (1.2198, 2.3366, 3.6810), 4: (1.7255, 5.1048), 6: (4.0991,)}
BAND = {2: 0.01, 4: 0.04, 6: 0.12}


def classify_overturn(scheme, f, k, pert: Perturbation = Perturbation(), **kw):
    """(overturned, sanity message or None) of a one-sine pulse f g tan(alpha), omega_p = k p (``pert``:
    1 ulp on the amplitude and the frequency). Safe once the pulse is over and the block is in full contact
    or its energy is below the overturning energy m g R (1 - cos alpha) (no input, e_N = 0: the energy
    cannot grow)."""
    block = RigidBlock(**OVERTURN_BLOCK)
    gm = SinePulse(pert.scalar(f * block.g * math.tan(block.alpha), 1), pert.scalar(k * block.p, 2))
    e_crit = block.m * block.g * block.R * (1 - math.cos(block.alpha))
    name, opts = SCHEMES[scheme]
    sim = Simulator(block, name, **dict(opts, **kw))
    tol = 1e-9 if scheme == "ED" else 2e-3 * 2 * block.b * 5
    t = 0.0
    times, phi, modes, gaps, over = [], [], [], [], []
    while t < gm.t1 + 10.0:
        t += 0.05
        sim.advance(t, gm)
        q, v = sim.state()
        I = sim.integrator
        times.append(t)
        phi.append(q[2])
        modes.append(int(I.mode))
        gaps.append(float(block.gaps(q).min()))
        over.append(I.overturned)
        done = I.overturned or (t > gm.t1 and (I.mode == Mode.FULL or block.energy(q, v) < e_crit * (1 - 1e-6)))
        if done:
            # the geometric check stops where the documented limitation starts (sane_horizon)
            n = sane_horizon(phi, modes, over, block.alpha)
            bad = [j for j in range(n) if gaps[j] < -tol]
            if bad:
                return None, f"penetration {gaps[bad[0]]:.3g} m at t = {times[bad[0]]:.2f} s"
            return I.overturned, None
    raise AssertionError(f"no classification for f = {f}, omega_p = {k} p")


@pytest.mark.parametrize("k", [2, 4, 6], ids=["wp=2p", "wp=4p", "wp=6p"])
def test_overturning_boundaries_are_far_from_round_off(k):
    """The regression points of the next test sit 3e-4 (in units of g tan(alpha)) on either side of the
    measured ED boundaries: a margin round-off cannot cross. 1 ulp off (pulse amplitude and frequency) they
    classify the same. (Measured: 1-ulp seeds 1 to 4, and the generic kernels of `roundoff.kernel_env`
    without and with seeds 1 to 4: all 9 perturbed runs classify the 12 points as the nominal run.)"""
    pert = Perturbation(roundoff.ULP_SEED)
    for fb in ED_BOUNDARIES[k]:
        for f in (fb - 3e-4, fb + 3e-4):
            ref, got = classify_overturn("ED", f, k), classify_overturn("ED", f, k, pert)
            assert got == ref and ref[1] is None, (k, f, ref, got)


@pytest.mark.parametrize("k", [2, 4, 6], ids=["wp=2p", "wp=4p", "wp=6p"])
def test_overturning_classification_agrees_outside_band(k):
    bounds = ED_BOUNDARIES[k]
    band = BAND[k]
    # the event-driven boundaries are where they were measured (regression, +-3e-4)
    for fb in bounds:
        lo, hi = classify_overturn("ED", fb - 3e-4, k)[0], classify_overturn("ED", fb + 3e-4, k)[0]
        assert lo is not None and hi is not None and lo != hi, (k, fb)
    # points just outside the band on both sides of each boundary, and one inside each region
    edges = [0.85] + list(bounds) + [bounds[-1] * 1.4]
    points = sorted({fb * (1 - band) for fb in bounds} | {fb * (1 + band) for fb in bounds}
                    | {0.5 * (a + b) for a, b in zip(edges[:-1], edges[1:])} - {0.85})
    points = [f for f in points if f > 1.0]
    for f in points:
        ed, msg_ed = classify_overturn("ED", f, k)
        mj, msg_mj = classify_overturn("MJ", f, k)
        assert msg_ed is None and msg_mj is None, (f, msg_ed, msg_mj)
        assert ed == mj, f"omega_p = {k} p, A = {f:.4f} g tan(alpha): ED overturned = {ed}, MJ = {mj}"


# ================================================================================================
# 5. Small and large blocks: the response in tau = p t depends only on alpha, ag/g and omega_p/p
# ================================================================================================
SIZES = {"R=4cm": 0.04, "R=1m": 1.0, "R=20m": 20.0}


@functools.lru_cache(maxsize=None)
def scaled_run(R, scheme_name):
    alpha = math.atan(0.2)
    block = RigidBlock(b=R * math.sin(alpha), h=R * math.cos(alpha))
    p = block.p
    # 1.5 g tan(alpha) at omega_p = 4 p rocks to ~0.1 rad without overturning (boundary at ~1.75 g tan(alpha))
    gm = SinePulse(1.5 * G * math.tan(alpha), 4.0 * p)
    tau = np.arange(1, 201) * 0.05          # tau up to 10
    if scheme_name == "ED":
        tr = Trace(block, ED, gm, tau / p)
    else:
        tr = Trace(block, "MJ", gm, tau / p, dt_max=2.5e-3 / p)
    return tr


@pytest.mark.parametrize("scheme", ["ED", "MJ"])
@pytest.mark.parametrize("size", ["R=4cm", "R=20m"])
def test_small_and_large_blocks_are_similar(size, scheme):
    R = SIZES[size]
    tr = scaled_run(R, scheme)
    ref = scaled_run(1.0, scheme)
    assert tr.model.p > 10 if R < 0.1 else tr.model.p < 1
    assert_sane(tr)
    assert np.max(np.abs(ref.phi)) > 0.05
    assert tr.impacts[-1] == ref.impacts[-1]
    tol = 1e-7 if scheme == "ED" else 1e-9
    assert np.max(np.abs(tr.phi - ref.phi)) < tol
    assert np.max(np.abs(tr.phi_dot / tr.model.p - ref.phi_dot / ref.model.p)) < 10 * tol


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


@pytest.mark.parametrize("scheme", [
    pytest.param("ED", marks=pytest.mark.xfail(strict=True, reason="bug 7: sticking LCP infeasible when the driven "
                                                                  "pivot unloads; corner sinks 0.16 m")),
    pytest.param("MJ", marks=pytest.mark.xfail(strict=True, reason="bug 7: sticking LCP infeasible when the driven "
                                                                  "pivot unloads; corner sinks 0.10 m"))])
def test_sustained_step_lift_off_keeps_corners_above_ground(scheme):
    """Constant ag = 1.5 g tan(alpha) until overturning: at phi = 0.93 rad (t = 1.130 s) the pivot's normal
    force reaches 0 while the sticking force is 2.9 N (m g = 9.8 N): with no sliding the contact problem has
    no solution (flight accelerates the pivot into the ground at -4.4 m/s2, contact needs lambda_N < 0). Both
    schemes take the least-violating answer (flight) and the pivot sinks through the ground while the block
    falls: ED -0.16 m, MJ -0.10 m before |phi| = pi/2. Whatever the resolution (sliding, an impulsive
    'impact without collision', or stopping with a diagnostic), corners must not go below the ground."""
    block = RigidBlock(**SLENDER)
    ag = 1.5 * block.g * math.tan(block.alpha)
    tr = Trace(block, scheme, ConstantMotion(ag), grid(2.0))
    tol = pen_tol(tr)
    assert tr.min_gap >= -tol, f"penetration {tr.min_gap:.3g} m > {tol:.3g} m"


#: the README's FMU quickstart: b = 0.2, h = 1, ag = 3 sin(2 pi t) m/s2 for t < 1 s (a table on a 0.01 s
#: grid, held per 0.01 s communication step as fmpy does), 5 s; the FMU's default settings
QUICKSTART_T = np.linspace(0.0, 5.0, 501)
QUICKSTART_AG = 3.0 * np.sin(2 * np.pi * QUICKSTART_T) * (QUICKSTART_T < 1)
QUICKSTART_SCHEMES = {"ED": ("event_driven", dict(tolerance=1e-8)), "MJ": ("moreau_jean", dict(dt_max=1e-3))}
#: [m] how deep a corner sinks after the pivot's lift-off in the final fall (docs/limitations.md), as
#: measured (ED 20.42 mm at the frozen state; MJ 0.277 mm, then projected back onto the ground), +-25 %
QUICKSTART_SINK = {"ED": (0.0153, 0.0255), "MJ": (0.21e-3, 0.35e-3)}


def quickstart_scene(scheme: str, pert: Perturbation):
    a = pert.array(QUICKSTART_AG, 1)
    tr = Trace(RigidBlock(**SLENDER), QUICKSTART_SCHEMES[scheme], 0.0, [], phi_0=pert.scalar(0.0))
    for k in range(1, QUICKSTART_T.size):
        tr.extend(ConstantMotion(float(a[k - 1])), [QUICKSTART_T[k]])
    tr.ag = a
    return tr, {}


for _s in ("ED", "MJ"):
    scene(f"quickstart_{_s}")(functools.partial(quickstart_scene, _s))
    VERDICTS[f"{MOD}:quickstart_{_s}"] = dict(finite=True, no_penetration=True, right_side=True,
                                              bounded_rotation=True, overturned=True,
                                              frozen_after_overturning=True)
    # overturns at 2.05 s (1 s after the pulse); the sink is deterministic (no chaos in 2 s)
    BOUNDS[f"{MOD}:quickstart_{_s}"] = dict(t_overturn=(1.9, 2.2), sink_after_horizon=QUICKSTART_SINK[_s])


@pytest.mark.parametrize("scheme", ["ED", "MJ"])
def test_overturning_lift_off_sinks_a_corner_as_documented(scheme, record_property):
    """The documented limitation, measured (docs/limitations.md). The README quickstart overturns the block
    at 2.05 s. In its final fall the pivot's normal force reaches 0 at phi = -1.34 rad while the pivot's free
    normal acceleration is -6 m/s2 (the sticking force is not 0): with no sliding there is no consistent
    contact state (physics.md section 6). Up to that lift-off the run is sane (`sane_horizon`); after it the
    schemes take flight and the pivot corner sinks: ED 20.4 mm at the frozen state, MJ 0.28 mm (then
    projected back). The figures are pinned (+-25 %) so that the day friction lands (issue 15) this test
    fails, and the document and `sane_horizon` get updated."""
    key = f"{MOD}:quickstart_{scheme}"
    tr, summary = nominal(key)
    block = tr.model
    rep = assert_sane(tr, overturn_ok=True)
    assert summary["verdict"] == VERDICTS[key], describe_mismatch(summary["verdict"], VERDICTS[key])
    # where the checks stop: the last sample on the pivot, in the final fall, its normal force nearly gone
    k = rep["horizon"] - 1
    q, v = tr.q[k], tr.v[k]
    pivot = tr.modes[k]
    assert pivot == Mode.RIGHT and abs(tr.phi[k]) > block.alpha and tr.phi[k] * tr.phi_dot[k] > 0
    ag = float(tr.ag[k])
    i = 1                                                     # right corner
    lam = float(block.contact_forces(Mode.RIGHT, q, v, ag)[i]) / block.force_scale
    acc = inverse_mass(block, q) @ block.forces(q, v, ag)
    a_free = float(block.contact_jacobians(q)[0][:, i] @ acc + block.contact_drift(q, v)[0][i])
    print(f"{scheme}: last sample on the pivot t = {tr.T[k]:.2f} s, phi = {tr.phi[k]:.4f} rad, "
          f"lambda_N / (m g) = {lam:.4f}, free a_N = {a_free:.3f} m/s2")
    # measured at the last sample on the pivot (ED 1.96 s, MJ 1.98 s): lambda_N / (m g) = 0.004 (ED; MJ
    # -0.008: its last step on the pivot already needed a pull), free normal acceleration -6.1 (ED) / -6.2
    # (MJ) m/s2
    assert lam < 0.05 and a_free < -0.5 * block.g, (lam, a_free)
    # and beyond it the contact law does not hold: the corner is found below the ground
    sink = summary["figures"]["sink_after_horizon"]
    record_property("phi_lift_off_rad", float(tr.phi[k]))
    record_property("sink_after_lift_off_m", sink)
    check_bounds(summary["figures"], BOUNDS[key], key)


# ================================================================================================
# 8. Zero-length, tiny and variable communication steps
# ================================================================================================
@pytest.mark.parametrize("scheme", ["ED", "MJ"])
@pytest.mark.parametrize("model_name", ["rigid", "flexible"])
def test_zero_and_tiny_communication_steps(model_name, scheme):
    """advance(t) to the current time changes nothing and takes no step; 1e-9 s steps (as a master's
    round-off or an event-locating master produces) interleaved with 0.01 s steps leave the ED solution
    unchanged to its tolerance and cost O(1) steps each; MJ takes one tiny step each and stays within its
    accuracy of the uniform run."""
    model = MODELS[model_name]()
    gm = SinePulse(0.3 * G, 2 * math.pi * 1.5)
    ref = Trace(model, scheme, gm, grid(2.0))
    name, opts = SCHEMES[scheme]
    sim = Simulator(model, name, **opts)
    rows = [sim.outputs()["phi"]]
    for tk in grid(2.0):
        n0 = sim.integrator.n_steps
        q0 = np.array(sim.state()[0])
        sim.advance(sim.t, gm)                              # zero-length step
        assert sim.integrator.n_steps == n0 and np.array_equal(sim.state()[0], q0)
        for _ in range(3):
            sim.advance(sim.t + 1e-9, gm)
        assert sim.integrator.n_steps - n0 <= 3 * (2 if scheme == "ED" else 1)
        sim.advance(float(tk), gm)
        rows.append(sim.outputs()["phi"])
    phi = np.array(rows)
    assert np.all(np.isfinite(phi))
    tol = 1e-7 if scheme == "ED" else 0.02 * np.abs(ref.phi).max()
    assert np.max(np.abs(phi - ref.phi)) < tol


# ================================================================================================
# 9. Round-off: the re-run scenes of this module give the same verdicts 1 ulp off and under other kernels
# ================================================================================================
ROUNDOFF_SCENES = sorted(VERDICTS)



@pytest.mark.parametrize("key", ROUNDOFF_SCENES, ids=lambda k: k.partition(":")[2])
def test_same_verdicts_one_ulp_off(key):
    """1-ulp perturbation of the initial state and of every input number, in-process: the same verdicts
    as the nominal run, and the documented margins hold."""
    _, ref = nominal(key)
    assert ref["verdict"] == VERDICTS[key], describe_mismatch(ref["verdict"], VERDICTS[key])
    _, got = roundoff.run_scene(key, Perturbation(roundoff.ULP_SEED))
    assert got["verdict"] == ref["verdict"], describe_mismatch(got["verdict"], ref["verdict"])
    check_bounds(got["figures"], BOUNDS[key], f"{key} (1 ulp off)")


@pytest.mark.parametrize("key", ROUNDOFF_SCENES, ids=lambda k: k.partition(":")[2])
def test_same_verdicts_under_other_kernels(key, kernel_rerun):
    """The scene re-run in a subprocess under `roundoff.kernel_env`: the same verdicts, the margins hold."""
    roundoff.assert_kernel_rerun(key, kernel_rerun, nominal(key)[1], BOUNDS[key])
