"""The two integration schemes of the compiled engine, as declarations: name, integer code, summary, the fields
of their plain-data state, the check of the user's options (`settings`) and the typed reading of a saved state
(`read_state`). The schemes themselves run in C (rocking_model/engine/src/rk_ed.c, rk_mj.c), which checks a
loaded state's ranges and consistency with the model again; the checks here give the messages of a wrong type
or a missing field before anything reaches it."""
from __future__ import annotations

import math

from ..validation import check_choice, check_real, state_bool, state_float, state_floats, state_int, state_ints
from .base import Integrator, register_scheme
from .state import check_times

#: the Runge-Kutta pairs of the event-driven scheme: accepted spellings -> name
METHOD_CHOICES = {"DOP853": "DOP853", "DOPRI5": "DOPRI5", "RK45": "DOPRI5", 0: "DOP853", 1: "DOPRI5"}
#: [s] the Moreau-Jean scheme's default step
DT_DEFAULT = 1e-3


def _flat_rows(flat, n_dof) -> list:
    """impact_log rows (t, v_minus, v_plus) of a flat list, for `check_times`."""
    w = 1 + 2 * n_dof
    return [flat[i] for i in range(0, len(flat), w)]


# (registered in the order of their codes: the allowed values are listed in that order)
@register_scheme
class MoreauJean(Integrator):
    """Declaration of the Moreau-Jean time-stepper (run by rk_mj.c): steps of at most ``dt_max`` [s] and at
    most ``model.step_limit`` (0.25/omega for the flexible oscillator)."""

    name = "moreau_jean"
    code = 0
    summary = "Moreau-Jean time-stepping: one velocity-level LCP per step, order 1"
    STATE_KEYS = ("t", "q", "v", "mode", "closed", "impacts", "overturned", "n_steps", "impact_times",
                  "friction_demand", "painleve")

    @staticmethod
    def settings(model, options) -> dict:
        # (the method is unused here, but the engine reads it for both schemes: checked as the other scheme does)
        return {"theta": check_real("theta", options.theta, lo=0.5, hi=1.0),
                "dt_max": min(options.dt_max or DT_DEFAULT, model.step_limit), "tolerances": options.tolerances,
                "method": check_choice("method", options.method, METHOD_CHOICES)}

    @staticmethod
    def read_state(model, state, impact_log_size) -> dict:
        n = model.n_dof
        t = state_float(state, "t")
        q = state_floats(state, "q", length=n)
        v = state_floats(state, "v", length=n)
        mode = state_int(state, "mode", 0, model.n_modes - 1)
        nc = model.n_contacts
        closed = state_ints(state, "closed", lo=0, hi=nc - 1, max_len=nc)
        if closed != sorted(set(closed)):
            raise ValueError(f"state field 'closed' = {closed!r} must list distinct corners in increasing order")
        if model.closed_of(model.mode_code(mode)) != tuple(closed):
            raise ValueError(f"state field 'mode' = {mode} does not match 'closed' = {closed!r}; expected "
                             f"one of the modes with these closed corners, e.g. {int(model.mode_of(closed))}")
        impacts = state_int(state, "impacts")
        return {"t": t, "q": q, "v": v, "mode": mode, "closed": closed, "impacts": impacts,
                "overturned": state_bool(state, "overturned"), "n_steps": state_int(state, "n_steps"),
                "impact_times": check_times(state, "impact_times", state_floats(
                    state, "impact_times", max_len=impact_log_size), t, impacts),
                "friction_demand": state_float(state, "friction_demand", lo=0.0),
                "painleve": state_int(state, "painleve")}


@register_scheme
class EventDriven(Integrator):
    """Declaration of the event-driven scheme (run by rk_ed.c)."""

    name = "event_driven"
    code = 1
    summary = ("event-driven: Runge-Kutta phases in reduced coordinates, LCPs at events (the faster at equal "
               "error, see docs/performance.md)")
    STATE_KEYS = ("t", "mode", "y", "impacts", "overturned", "n_steps", "h", "impact_times", "impact_log",
                  "shift", "friction_demand", "painleve")

    @staticmethod
    def settings(model, options) -> dict:
        """The scheme's settings from the user's options, checked (ValueError naming the option)."""
        return {"tolerance": check_real("tolerance", options.tolerance, lo=1e-14, hi=1e-2),
                "zeno_tol": check_real("zeno_tol", options.zeno_tol, lo=0.0, hi=1e-2, lo_open=True),
                "method": check_choice("method", options.method, METHOD_CHOICES),
                "dt_max": options.dt_max or math.inf, "tolerances": options.tolerances}

    @staticmethod
    def read_state(model, state, impact_log_size) -> dict:
        """The fields of a `get_state` dict as plain values of the right types (ValueError naming the field)."""
        t = state_float(state, "t")
        mode = state_int(state, "mode", 0, model.n_modes - 1)
        y = state_floats(state, "y")
        impacts = state_int(state, "impacts")
        n = 1 + 2 * model.n_dof
        rows = None if impact_log_size is None else min(1000, impact_log_size)
        out = {"t": t, "mode": mode, "y": y, "impacts": impacts, "overturned": state_bool(state, "overturned"),
               "n_steps": state_int(state, "n_steps"),
               "h": state_float(state, "h", lo=0.0, lo_open=True, nan_ok=True),
               "impact_times": check_times(state, "impact_times", state_floats(
                   state, "impact_times", max_len=impact_log_size), t, impacts),
               "impact_log": state_floats(state, "impact_log", multiple=n, max_len=None if rows is None else n * rows)}
        check_times(state, "impact_log", _flat_rows(out["impact_log"], model.n_dof), t, impacts)
        out["shift"] = state_float(state, "shift")
        out["friction_demand"] = state_float(state, "friction_demand", lo=0.0)
        out["painleve"] = state_int(state, "painleve")
        return out
