"""Moreau-Jean time-stepper: theta-method on the full coordinates with a velocity-level LCP per step.

Per step of size dt (Acary & Brogliato 2008, Ch. 10; Siconos' MoreauJeanOSI):

    W_hat (v+ - v) = dt [(1 - theta) f(q, v, t) + theta f(q, v, t + dt)] - dt^2 theta K v + W_N P_N + W_T P_T

(f at t and t + dt under both ground accelerations, ag(t) and, for a `TwoComponentMotion`, ag_v(t)),
    W_hat = M(q) + dt theta C + dt^2 theta^2 K        (K, C: stiff linear part of -df/dq, -df/dv)
    q+ = q + dt [(1 - theta) v + theta v+]

A corner is active when its predicted gap g_N + (dt/2) U_N <= 0 (up to round-off) or when the free motion
would close it within the step, g_N + dt [(1 - theta) U_N + theta U_N,free] <= 0 (so a resting or pivoting
corner never free-falls for one step); on active corners Newton's law
0 <= U_N+ + e_N U_N ⊥ P_N >= 0 with sticking where P_N > 0 (the impact LCP of `rocking_model.lcp`).
theta = 1/2 keeps the stiff column free of numerical damping; theta = 1 damps it.
After the step, the positions of the corners that carried impulse are projected back onto the ground
(`_project`); a state with both corners stuck and no normal velocity is put exactly on the full-contact
manifold, so that phi is exactly 0 at rest. Global order 1 when impacts occur.
"""
from __future__ import annotations

import math

import numpy as np

from .._ordered import lu_inverse, matvec
from ..contact import inverse_mass, project_to_ground, solution_sigma, solve_with_friction
from ..modes import BoundedLog, bounded_log
from ..tolerances import DEFAULT_TOLERANCES, ContactTolerances
from ..validation import WorkLimitError, check_real, state_bool, state_float, state_floats, state_int, state_ints
from .base import Integrator, SolverOptions, register_scheme
from .state import check_configuration, check_times

#: [s] default step
DT_DEFAULT = 1e-3


@register_scheme
class MoreauJean(Integrator):
    """LCP time-stepper on the full coordinates of ``model``; steps of at most ``dt_max`` [s] and at most
    ``model.step_limit`` (0.25/omega for the flexible oscillator)."""

    name = "moreau_jean"
    code = 0
    summary = "Moreau-Jean time-stepping: one velocity-level LCP per step, order 1"
    STATE_TOKEN = "v"
    LOGS = ("impact_times",)

    @classmethod
    def from_options(cls, model, mode, q, v, t0, options: SolverOptions) -> "MoreauJean":
        theta = check_real("theta", options.theta, lo=0.5, hi=1.0)
        return cls(model, mode, q, v, t0, dt_max=options.dt_max or DT_DEFAULT, theta=theta,
                   impact_log_size=options.impact_log_size, tolerances=options.tolerances)

    def __init__(self, model, mode, q: np.ndarray, v: np.ndarray, t0: float,
                 dt_max: float = DT_DEFAULT, theta: float = 0.5, impact_log_size: int | None = None,
                 tolerances: ContactTolerances = DEFAULT_TOLERANCES):
        self.model = model
        self.tolerances = tolerances
        tol = tolerances.for_model(model)
        #: [m] round-off margin of the candidate test (ContactTolerances.step_gap)
        self.gap_margin = tol.step_gap
        #: [m/s] closing slower than this is no impact; two closed corners this slow are at rest
        self.v_rest = tol.step_rest_velocity
        #: [N] a normal force below this carries no load (ContactTolerances.demand_floor)
        self.force_floor = tol.force_floor
        self.reports = []
        self.q = np.array(q, dtype=float)
        self.v = np.array(v, dtype=float)
        self.t = float(t0)
        self.dt_max = min(dt_max, model.step_limit)  # sub-step where the model needs it (stiff columns)
        self.theta = theta
        self.mode = model.mode_code(int(mode))
        self.impacts = 0
        self.impact_times: BoundedLog = BoundedLog(impact_log_size)
        self.overturned = False
        self.n_steps = 0
        # corners that carried impulse in the last step (impacts are counted on newly closing corners)
        self._closed = set(model.closed_of(self.mode))

    def advance(self, t_end: float, ag, max_steps: int | None = None) -> None:
        """Integrate to exactly t_end in equal steps of at most dt_max.

        max_steps: work budget of this call (None: unlimited). The number of steps is known before any
        work: more than max_steps raises `WorkLimitError` at once, with the state untouched."""
        span = t_end - self.t
        if span <= 0.0:
            return
        if self.overturned:
            self.t = t_end
            return
        steps = span / self.dt_max * (1.0 - 1e-12)       # a float: may exceed any int (refused below)
        if max_steps is not None and steps > max_steps:
            raise WorkLimitError(self.work_message(span, steps, max_steps))
        n = max(1, math.ceil(steps))
        t0 = self.t
        dt = span / n
        for k in range(n):
            t_next = t_end if k == n - 1 else t0 + (k + 1) * dt
            self._step(self.t, t_next - self.t, ag)
            self.t = t_next
            if self.overturned:
                self.t = t_end
                return

    def work_message(self, span: float, steps: float, max_steps: int) -> str:
        """Why a step of ``span`` [s] is refused and how to get it through."""
        model = self.model
        limit = model.step_limit
        why = (f"dt = min(dt_max, 0.25/omega) = {self.dt_max:.6g} s (the column's omega = "
               f"{0.25 / limit:.6g} rad/s)" if limit <= self.dt_max else f"dt_max = {self.dt_max:.6g} s")
        return (f"moreau_jean: advancing from t = {self.t:.17g} s by {span:.6g} s needs {math.ceil(steps) if math.isfinite(steps) else steps:.6g} "
                f"steps of {why}, more than max_steps = {max_steps} per advance; the step was refused and "
                f"the state kept. Way out: communication steps of at most {max_steps * self.dt_max:.6g} s, a "
                f"larger dt_max, or max_steps=None (unlimited, for trusted batch runs)")

    def _step(self, t, dt, ag):
        model, theta = self.model, self.theta
        q, v = self.q, self.v
        M = model.mass_matrix(q)
        vert = ag.vertical
        if vert is None:
            f0 = model.forces(q, v, ag(t))
            f1 = f0 if ag.constant else model.forces(q, v, ag(t + dt))
        else:
            # the vertical ground acceleration ag_v at both ends of the step too
            f0 = model.forces(q, v, ag(t), vert(t))
            f1 = f0 if ag.constant else model.forces(q, v, ag(t + dt), vert(t + dt))
        rhs = dt * ((1.0 - theta) * f0 + theta * f1)
        kc = model.stiff_jacobians(q, v)
        if kc is None:
            Winv = inverse_mass(model, q)
        else:
            K, C = kc
            rhs = rhs - dt * dt * theta * matvec(K, v)
            Winv = lu_inverse(M + dt * theta * C + dt * dt * theta * theta * K)
        v_free = v + matvec(Winv, rhs)
        g = model.gaps(q)
        W_N, W_T = model.contact_jacobians(q)
        U = matvec(W_N.T, v)
        rule_impact = False
        closed_now = model.closed_of(self.mode)
        if len(closed_now) == 1 and model.n_contacts == 2:
            hitting = 1 - closed_now[0]
            if g[hitting] + dt * U[hitting] <= 0.0 and U[hitting] < 0.0:
                # an impact rule of the model (the classical rule): replace the pre-impact velocity by the
                # rule's post-impact one; the step's LCP (e_N applied to the new, non-approaching velocity)
                # then keeps the contacts closed
                v_rule = model.classical_impact_velocity(q, v, self.mode)
                if v_rule is not None:
                    v = v_rule
                    v_free = v + (v_free - self.v)
                    U = matvec(W_N.T, v)
                    rule_impact = True
        # a corner enters the LCP if it closes by the classical prediction g + dt/2 U (with a round-off margin
        # for corners just projected onto the ground) or if the free motion would close it within the step;
        # a needless candidate only gets a zero percussion from the LCP
        g_half = g + 0.5 * dt * U
        g_free = g + dt * ((1.0 - theta) * U + theta * matvec(W_N.T, v_free))
        margin = self.gap_margin
        active = [i for i in range(model.n_contacts) if g_half[i] <= margin or g_free[i] <= 0.0]
        if active:
            b_N = model.e_N * np.minimum(U, 0.0)
            # tangential law: the paper's sticking (b_T = 0), or restitution e_T = e_N of the pre-step tangential
            # velocity on the closing contacts (the same coefficient as in the normal direction, per contact)
            b_T = np.where(U < 0.0, model.e_T * matvec(W_T.T, v), 0.0) if model.e_T else np.zeros(model.n_contacts)
            # the friction law picks the LCP: sticking (the paper's), its mu -> inf limit where sticking has no
            # solution, or Coulomb; the last step's closed contacts are tried first
            sol = solve_with_friction(model, Winv, W_N, W_T, v_free, b_N, b_T, active,
                                      hint=[i for i in self._closed if i in active], tolerances=self.tolerances)
            if not sol.exact:
                self.report("inexact_contact", t + dt, inexact_message(sol, t + dt, "step LCP"))
            v_new = sol.v
            closed = set(sol.active)
            sigma = solution_sigma(sol)
            # (the percussions are zero off the closed contacts)
            self.note_demand(sum(sol.P_N.tolist()), sum(sol.P_T.tolist()), self.force_floor * dt)
        else:
            v_new = v_free
            closed = set()
            sigma = 0
        v_scale = self.v_rest
        new = [i for i in closed - self._closed if U[i] < -v_scale]
        if new or rule_impact:
            self.impacts += 1
            self.impact_times.append(t + dt)
        self._closed = closed
        q_new = q + dt * ((1.0 - theta) * v + theta * v_new)
        if closed:
            q_new = self._project(q_new, sorted(closed))
        if len(closed) == model.n_contacts and np.all(np.abs(matvec(W_N.T, v_new)) <= v_scale):
            # all corners stuck and at rest in the normal direction: the state is on the full-contact
            # manifold up to round-off; put it there exactly so that phi stays 0 at rest (no drift)
            full = model.mode_of(closed)
            i = model.slide_index
            x, x_dot = q_new[i], v_new[i]
            q_new, v_new = model.embed(full, *model.reduce(full, q_new, v_new))
            # the embedding puts the base at its rest abscissa, at rest: keep a velocity where it slides, and an
            # offset where it has slid (or landed off its rest position) beyond round-off: the last step's where
            # it was already at rest (no drift by the round-off of a zero velocity)
            if abs(x_dot - v_new[i]) > v_scale:
                q_new[i], v_new[i] = x, x_dot
            elif abs(x - q_new[i]) > margin:
                q_new[i] = q[i] if self.mode == full else x
        self.q = q_new
        self.v = v_new
        self.mode = model.mode_of(closed, sigma)
        self.n_steps += 1
        if abs(self.q[model.phi_index]) >= 0.5 * math.pi:
            # the motion ends: the pose at the end of this step (|phi| past pi/2 by at most |phi_dot| dt), at
            # rest (the outputs after overturning must not describe a motion that is no longer computed)
            self.overturned = True
            self.v = np.zeros_like(self.v)

    def _project(self, q, closed):
        """Put the corners that carried impulse back on the ground (`project_to_ground`). Without it the
        pivot of a rocking body drifts off the ground by O(dt^2) per step (the constraint is nonlinear) and
        re-impacts spuriously."""
        return project_to_ground(self.model, q, closed)

    def state(self):
        """Full (q, v)."""
        return self.q, self.v

    # ------------------------------------------------------------------ plain-data state
    #: fields of `get_state` (the Simulator adds the header: version, scheme, model, n_dof)
    STATE_KEYS = ("t", "q", "v", "mode", "closed", "impacts", "overturned", "n_steps", "impact_times",
                  "friction_demand", "painleve")

    def get_state(self) -> dict:
        """What determines the future of this integrator, as plain data (see `Simulator.get_state`):
        ``closed`` lists the corners that carried impulse in the last step (an impact is counted when a
        corner outside it closes; the LCP starts from it)."""
        return {"t": float(self.t), "q": [float(a) for a in self.q], "v": [float(a) for a in self.v],
                "mode": int(self.mode), "closed": sorted(int(i) for i in self._closed),
                "impacts": int(self.impacts), "overturned": bool(self.overturned), "n_steps": int(self.n_steps),
                "impact_times": [float(a) for a in self.impact_times.tail()],
                "friction_demand": float(self.friction_demand), "painleve": int(self.painleve)}

    def set_state(self, state) -> None:
        """Load a `get_state` dict (header and keys checked by the caller); ValueError naming the field,
        nothing changed, on error."""
        model = self.model
        n = model.n_dof
        t = state_float(state, "t")
        q = np.array(state_floats(state, "q", length=n))
        v = np.array(state_floats(state, "v", length=n))
        mode = model.mode_code(state_int(state, "mode", 0, model.n_modes - 1))
        nc = model.n_contacts
        closed = state_ints(state, "closed", lo=0, hi=nc - 1, max_len=nc)
        if closed != sorted(set(closed)):
            raise ValueError(f"state field 'closed' = {closed!r} must list distinct corners in increasing order")
        if model.closed_of(mode) != tuple(closed):
            raise ValueError(f"state field 'mode' = {int(mode)} does not match 'closed' = {closed!r}; expected "
                             f"one of the modes with these closed corners, e.g. {int(model.mode_of(closed))}")
        impacts = state_int(state, "impacts")
        overturned = state_bool(state, "overturned")
        n_steps = state_int(state, "n_steps")
        times = check_times(state, "impact_times", state_floats(
            state, "impact_times", max_len=self.impact_times.maxlen), t, impacts)
        # the time-stepper lets corners sink by O(dt |v|) before the impulse stops them: only junk (a corner a
        # whole length scale below the ground) is refused
        check_configuration(model, state, "q", q, v, overturned, gap_tol=model.length_scale)
        demand = state_float(state, "friction_demand", lo=0.0)
        painleve = state_int(state, "painleve")
        self.t, self.q, self.v, self.mode, self._closed = t, q, v, mode, set(closed)
        self.friction_demand, self.painleve = demand, painleve
        self.impacts, self.overturned, self.n_steps = impacts, overturned, n_steps
        self.impact_times = bounded_log(self.impact_times.maxlen, times)

    def outputs(self) -> dict:
        """The model's outputs at the current time."""
        return self.model.outputs(self.q, self.v)


def inexact_message(sol, t: float, what: str) -> str:
    """Message of a `Report` of kind "inexact_contact"."""
    return (f"the {what} at t = {t:.17g} s has no exact solution (least violation {sol.violation:.3g}, "
            f"closed contacts {tuple(int(i) for i in sol.active)}): kept the least-violating one; a corner may "
            "sink or lift against the contact law")
