"""Shared helpers of the hard-case tests (split by topic): the `Trace` of a run, the
output grid, the documented penetration tolerances and the sanity checks, and the round-off machinery
(`nominal`, `roundoff_tests`) of the named scenes. The topics: test_hard_rest.py (impact accumulation, exact
rest, communication steps), test_hard_blocks.py (slender and squat blocks, grazing uplift, scale),
test_hard_overturning.py (the overturning boundary, a pulse that overturns), test_hard_columns.py (stiff
columns, large steps, records, tilts and steps), test_hard_vertical.py (the vertical ground acceleration: a
three-component record, flight where g + ag_v < 0, overturning because of ag_v).

Every test checks physical invariants on the output grid (finite values, no penetration beyond a measured
and documented tolerance, rotation on the correct side of the pivot, |phi| < pi/2 unless overturning is
expected) plus a closed form or a comparison between the schemes. Tests that fail because of a known
integrator bug keep their strict assertion and are marked ``xfail(strict=True)`` with the bug's number
(the list in the report), so that a fix shows up as XPASS.

Round-off: the long and violent scenes (free rocking to rest under a long quiet input, large
steps, the stored 30 s record, a one-sine pulse that overturns) are named scenes of `roundoff`; they
are re-run 1 ulp off and under other arithmetic kernels and must give the same verdicts (section 9). Runs
that overturn are checked to the end, the final fall and the frozen overturned state included.

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

from rocking_model import FlexibleOscillator, RigidBlock, Simulator
from rocking_model.modes import Mode

import roundoff
from roundoff import Perturbation, check_bounds, describe_mismatch

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


def sanity_report(tr, overturn_ok=False, pen=None) -> dict:
    """The invariants of `assert_sane` as a dict: ``finite``, ``no_penetration``, ``right_side``,
    ``bounded_rotation`` (|phi| < pi/2 without overturning, or <= pi/2 + 0.05 when overturning is allowed),
    ``not_overturned`` (only when overturning is not allowed), each a bool, plus ``messages`` (why not) and
    the figures ``horizon`` (samples checked: all of them since friction filled the hole of the sticking law at
    an overturning body's lift-off), ``min_gap`` [m] over them and ``tol`` [m]."""
    q, v = np.array(tr.q), np.array(tr.v)
    out = {"finite": bool(np.all(np.isfinite(q)) and np.all(np.isfinite(v))), "messages": []}
    phi, modes = tr.phi, tr.modes
    n = len(phi)
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
    and no overturning unless overturning is allowed (the geometric checks then cover the final fall and the
    frozen overturned state too)."""
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


# ---------------------------------------------------------------------------------------------- round-off
#: the verdict of a scene that settles (free rocking to rest, large steps)
QUIET_VERDICT = dict(finite=True, no_penetration=True, right_side=True, bounded_rotation=True,
                     overturned=False, at_rest_at_end=True)


@functools.lru_cache(maxsize=None)
def nominal(key: str):
    """(trace, summary) of the nominal run of a registered scene (run once per session)."""
    return roundoff.run_scene(key)


def roundoff_tests(verdicts: dict, bounds: dict):
    """The two round-off tests of a module's re-run scenes (``verdicts``: key -> verdict, ``bounds``: key ->
    documented margins); assign them to test_* names at the end of the module."""
    keys = sorted(verdicts)

    @pytest.mark.parametrize("key", keys, ids=lambda k: k.partition(":")[2])
    def test_same_verdicts_one_ulp_off(key):
        """1-ulp perturbation of the initial state and of every input number, in-process: the same verdicts
        as the nominal run, and the documented margins hold."""
        _, ref = nominal(key)
        assert ref["verdict"] == verdicts[key], describe_mismatch(ref["verdict"], verdicts[key])
        _, got = roundoff.run_scene(key, Perturbation(roundoff.ULP_SEED))
        assert got["verdict"] == ref["verdict"], describe_mismatch(got["verdict"], ref["verdict"])
        check_bounds(got["figures"], bounds[key], f"{key} (1 ulp off)")

    @pytest.mark.parametrize("key", keys, ids=lambda k: k.partition(":")[2])
    def test_same_verdicts_under_other_kernels(key, kernel_rerun):
        """The scene re-run in a subprocess under `roundoff.kernel_env`: the same verdicts, margins hold."""
        roundoff.assert_kernel_rerun(key, kernel_rerun, nominal(key)[1], bounds[key])

    return test_same_verdicts_one_ulp_off, test_same_verdicts_under_other_kernels
