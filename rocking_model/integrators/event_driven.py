"""Event-driven scheme: smooth phases in the reduced coordinates of their contact mode, LCPs at events.

- Each smooth phase is integrated with DOP853 (order 8, 7th-order dense output) on the reduced state
  y = [r, r_dot] of the current mode (full contact: the model's free DOFs only, none for the rigid block;
  rocking: phi, plus u for the flexible oscillator; flight: all).
- Event functions are positive inside the mode and fall through zero at an event: the approaching corner's
  gap (impact), the normal force of a closed corner (release/uplift), pi/2 - |phi| (overturning). Events are
  located on the dense output by a bracketing root finder to round-off in time; the state is taken on the
  far side of the root, so the LCP that follows sees the event as happened.
- At an impact the velocity-level LCP (Newton's law) gives the post-impact velocities; at every mode entry
  the acceleration-level LCP decides which corners stay closed. An event just handled starts disarmed and is
  re-armed only once its function is positive again (masking), so a restart never re-triggers it.
- Zeno rule (end of impact accumulation): after an impact, a corner at the ground whose post-impact
  separation velocity is below v_Zeno = zeno_tol * sqrt(g L) (L the model's length scale) is closed
  plastically and the impact LCP is solved again with that corner held closed. The kinetic energy this
  removes is at most of the order of 1/2 m v_Zeno^2.
"""
from __future__ import annotations

import math

import numpy as np

from ..contact import closed_candidates, impact, uplift
from ..modes import CLOSED, Mode, mode_from_closed, pivot_sign
from .rk import DOP853

_KIND_IMPACT, _KIND_RELEASE, _KIND_OVERTURN = "impact", "release", "overturn"


def _locate(fun, a: float, ga: float, b: float, gb: float, xtol: float) -> float:
    """Illinois regula falsi on a bracket with ga > 0 >= gb; returns a time t with fun(t) <= 0 and
    t - t_root <= xtol."""
    side = 0
    while b - a > xtol:
        t = (a * gb - b * ga) / (gb - ga) if ga != gb else 0.5 * (a + b)
        if not (a < t < b):
            t = 0.5 * (a + b)
        gt = fun(t)
        if gt > 0.0:
            a, ga = t, gt
            if side == 1:
                gb *= 0.5
            side = 1
        else:
            b, gb = t, gt
            if side == -1:
                ga *= 0.5
            side = -1
        if b - a <= xtol:
            break
        # guard against slow one-sided convergence: bisect every so often
        mid = 0.5 * (a + b)
        gm = fun(mid)
        if gm > 0.0:
            a, ga = mid, gm
        else:
            b, gb = mid, gm
    return b


class EventDriven:
    """Event-driven integration of ``model`` with relative/absolute tolerance ``tolerance``."""

    name = "event_driven"

    def __init__(self, model, mode: Mode, q: np.ndarray, v: np.ndarray, t0: float,
                 tolerance: float = 1e-8, dt_max: float = math.inf, zeno_tol: float = 1e-6,
                 max_events: int = 100000):
        self.model = model
        self.t = float(t0)
        self.tolerance = tolerance
        self.dt_max = dt_max
        L = model.length_scale
        self.gap_tol = 1e-9 * L
        self.v_tol = 1e-10 * math.sqrt(model.g * L)
        self.v_zeno = zeno_tol * math.sqrt(model.g * L)
        #: [1] how far below zero a disarmed (normalised) event function may go before it fires
        self.event_tol = 1e-10
        q_rest = model.rest_position()
        self.force_scale = float(np.linalg.norm(model.forces(q_rest, np.zeros_like(q_rest), 0.0)))
        self.max_events = max_events
        self.impacts = 0
        self.impact_times: list[float] = []
        #: (t, v_minus, v_plus) of every impact, full velocities
        self.impact_log: list[tuple] = []
        self.overturned = False
        self.n_steps = 0
        self._h = None
        self.mode = Mode(mode)
        q, v = np.asarray(q, float), np.asarray(v, float)
        self._set_state(self.mode, q, v)
        self._full = (q, v)

    # ------------------------------------------------------------------ state
    def _set_state(self, mode, q, v):
        self.mode = mode
        r, rd = self.model.reduce(mode, q, v)
        self.k = len(r)
        self.y = np.concatenate([r, rd])
        self._full = None

    def state(self):
        """Full (q, v) at the current time."""
        if self._full is None:
            k = self.k
            self._full = self.model.embed(self.mode, self.y[:k], self.y[k:])
        return self._full

    def _scales(self, mode):
        dof_scales = getattr(self.model, "dof_scales", None)
        idx = self.model.mode_dofs(mode)
        if dof_scales is None:
            s = [1.0 if i == self.model.phi_index else self.model.length_scale for i in idx]
        else:
            s = [dof_scales[i] for i in idx]
        s = np.array(s, dtype=float)
        return np.concatenate([s, s / self.model.time_scale])

    # ------------------------------------------------------------------ driver
    def advance(self, t_end: float, ag) -> None:
        """Integrate to exactly t_end; ``ag`` is a GroundMotion."""
        if t_end <= self.t:
            return
        if self.overturned:
            self.t = t_end
            return
        n_events = 0
        while not self.overturned:
            span = t_end - self.t
            if span <= 4.0 * math.ulp(max(abs(t_end), 1.0)):
                break
            t_stop = min(t_end, ag.next_breakpoint(self.t))
            if self.mode != Mode.FLIGHT:
                self._settle(self.t, ag(self.t))
            if self._segment(t_stop, ag):
                n_events += 1
                if n_events > self.max_events:
                    raise RuntimeError(f"event-driven scheme: more than {self.max_events} events in one "
                                       f"step at t = {self.t:.17g}; the motion does not settle")
        self.t = t_end
        self._full = None

    def _settle(self, t, ag_t):
        """Re-decide the mode of the current state by the acceleration LCP (after an input change)."""
        q, v = self.state()
        closed = CLOSED[self.mode]
        if all(i in closed for i in closed_candidates(self.model, q, v, self.gap_tol, self.v_tol)):
            lam = self.model.contact_forces(self.mode, q, v, ag_t)
            if all(lam[i] > 0.0 for i in closed):
                return      # the current active set solves the uplift LCP
        mode = self._select_mode(q, v, ag_t)
        if mode != self.mode:
            self._set_state(mode, q, v)

    def _rhs(self, mode, ag):
        model, k = self.model, self.k
        if ag.constant:
            a = ag.value

            def fun(t, y):
                return np.concatenate([y[k:], model.reduced_acceleration(mode, y[:k], y[k:], a)])
        else:
            def fun(t, y):
                return np.concatenate([y[k:], model.reduced_acceleration(mode, y[:k], y[k:], ag(t))])
        return fun

    def _event_functions(self, mode, ag):
        """(G(t, y) -> array, kinds, contacts) of ``mode``; every G_i > 0 inside the mode."""
        model, k = self.model, self.k
        F, L = self.force_scale, model.length_scale
        ip = model.mode_dofs(mode).index(model.phi_index) if mode != Mode.FULL else None
        if mode == Mode.FULL:
            def G(t, y):
                q, v = model.embed(mode, y[:k], y[k:])
                return model.contact_forces(mode, q, v, ag(t)) / F
            return G, (_KIND_RELEASE, _KIND_RELEASE), (0, 1)
        if mode == Mode.FLIGHT:
            def G(t, y):
                q = model.embed(mode, y[:k], y[k:])[0]
                g = model.gaps(q) / L
                return np.array([g[0], g[1], 0.5 * math.pi - abs(y[ip])])
            return G, (_KIND_IMPACT, _KIND_IMPACT, _KIND_OVERTURN), (0, 1, None)
        s = pivot_sign(mode)
        pivot = CLOSED[mode][0]

        def G(t, y):
            q, v = model.embed(mode, y[:k], y[k:])
            lam = model.contact_forces(mode, q, v, ag(t))[pivot] / F
            phi = y[ip]
            return np.array([-s * phi, lam, 0.5 * math.pi - abs(phi)])
        return G, (_KIND_IMPACT, _KIND_RELEASE, _KIND_OVERTURN), (1 - pivot, pivot, None)

    def _segment(self, t_stop: float, ag) -> bool:
        """Integrate the current mode towards t_stop; returns True if an event ended the segment."""
        mode, k = self.mode, self.k
        if k == 0 and ag.constant:
            # nothing moves and the (positive) contact forces cannot change
            self.t = t_stop
            self._full = None
            return False
        G, kinds, contacts = self._event_functions(mode, ag)
        fun = self._rhs(mode, ag)
        scales = self._scales(mode)
        stepper = DOP853(fun, self.t, self.y, self.tolerance, self.tolerance * scales,
                         max_step=self.dt_max, first_step=self._h)
        g_prev = G(self.t, self.y)
        armed = g_prev > 0.0
        # a disarmed event (zero at the segment start: just handled, or a grazing mode entry) still fires
        # once its function falls clearly below zero, e.g. a block that enters rocking with zero acceleration
        # at the uplift threshold and then turns back towards the ground
        tol = self.event_tol
        watch = ~armed & (g_prev > -tol)
        dip_ids = [i for i, kind in enumerate(kinds) if kind != _KIND_OVERTURN]
        while stepper.t < t_stop:
            stepper.step(t_stop)
            self.n_steps += 1
            g_new = G(stepper.t, stepper.y)
            hits = np.nonzero(armed & (g_new <= 0.0) | watch & (g_new <= -tol))[0]
            dense = None
            t0, t_hit = stepper.t_old, stepper.t
            if not hits.size and dip_ids:
                # a gap or a contact force can dip below zero and come back within one step (a short
                # excursion of the base of a vibrating column): look inside the step when its midpoint dips
                dense = stepper.dense_output()
                tm = 0.5 * (t0 + stepper.t)
                gm = G(tm, dense(tm))
                dip = [i for i in dip_ids if armed[i] and gm[i] < min(g_prev[i], g_new[i])]
                if dip:
                    ts = np.linspace(t0, stepper.t, 17)[1:-1]
                    for j, tj in enumerate(ts):
                        gj = G(tj, dense(tj))
                        neg = [i for i in dip if gj[i] <= 0.0]
                        if neg:
                            ta = t0 if j == 0 else ts[j - 1]
                            ga = g_prev if j == 0 else G(ta, dense(ta))
                            hits = np.array(neg)
                            g_prev, g_new = ga, gj
                            t0, t_hit = ta, tj
                            break
            if hits.size:
                if dense is None:
                    dense = stepper.dense_output()
                xtol = 4.0 * math.ulp(max(abs(stepper.t), 1.0))
                best = None
                for i in hits:
                    shift = 0.0 if armed[i] else tol

                    def gi(t, i=i, shift=shift):
                        return G(t, dense(t))[i] + shift
                    te = _locate(gi, t0, g_prev[i] + shift, t_hit, g_new[i] + shift, xtol)
                    if best is None or te < best[0]:
                        best = (te, i)
                te, i = best
                if self._h is None or stepper.h_abs > 0:
                    self._h = stepper.h_abs
                self.t = te
                self.y = dense(te)
                self._full = None
                self._handle(kinds[i], contacts[i], te, ag)
                return True
            armed |= g_new > 0.0
            watch &= ~armed
            g_prev = g_new
        self.t = stepper.t
        self.y = stepper.y
        self._h = stepper.h_abs
        self._full = None
        return False

    # ------------------------------------------------------------------ events
    def _handle(self, kind, contact, t, ag):
        q, v = self.state()
        if kind == _KIND_OVERTURN:
            self.overturned = True
            return
        if kind == _KIND_IMPACT:
            self._impact(q, v, t, ag(t))
        else:
            self._enter(q, v, ag(t))

    def _impact(self, q, v, t, ag_t):
        model = self.model
        g = model.gaps(q)
        cand = [i for i in (0, 1) if g[i] <= self.gap_tol]
        classical = getattr(model, "classical_impact_velocity", None)
        if classical is not None and self.mode in (Mode.LEFT, Mode.RIGHT) and len(cand) == 2:
            v_plus = classical(q, v, self.mode)
            if v_plus is not None:
                self._record_impact(t, v, v_plus)
                self._enter(q, v_plus, ag_t)
                return
        sol = impact(model, q, v, cand)
        W_N, _ = model.contact_jacobians(q)
        U_plus = W_N.T @ sol.v
        zeno = tuple(i for i in cand if i not in sol.active and U_plus[i] < self.v_zeno)
        if zeno:
            sol = impact(model, q, v, cand, forced=zeno)
        U_minus = W_N.T @ v
        if any(U_minus[i] < -self.v_zeno for i in cand):
            self._record_impact(t, v, sol.v)
        self._enter(q, sol.v, ag_t)

    def _record_impact(self, t, v_minus, v_plus):
        self.impacts += 1
        self.impact_times.append(t)
        self.impact_log.append((t, np.array(v_minus), np.array(v_plus)))

    def _select_mode(self, q, v, ag_t) -> Mode:
        """The mode that the acceleration LCP selects at the consistent state (q, v)."""
        cand = closed_candidates(self.model, q, v, self.gap_tol, self.v_tol)
        return mode_from_closed(uplift(self.model, q, v, ag_t, cand).active) if cand else Mode.FLIGHT

    def _enter(self, q, v, ag_t):
        self._set_state(self._select_mode(q, v, ag_t), q, v)
