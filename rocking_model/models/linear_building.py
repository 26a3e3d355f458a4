"""Linear building storey: a damped single-degree-of-freedom floor on a horizontally moving ground.

The storey is a floor mass on a massless, linear elastic frame with viscous damping (SI units throughout).
With u [m] the horizontal displacement of the floor relative to the ground, ag [m/s2] the ground
acceleration, omega = 2 pi / T [rad/s] the circular frequency of the fixed-base storey (period T [s]) and
zeta [1] its damping ratio::

    u'' + 2 zeta omega u' + omega^2 u = -ag(t)

The absolute (inertial) acceleration of the floor, the "ground" acceleration felt by equipment or a
rocking block standing on it, follows from the same equation without the input::

    a_floor = u'' + ag = -(2 zeta omega u' + omega^2 u)

so a_floor is a function of the state only (no direct feed-through from ag). The equipment is assumed
light compared with the floor (no feedback of the block on the storey).

Time integration is exact for a ground acceleration held constant over each step (the zero-order hold
of a co-simulation step): x_{n+1} = Phi x_n + Gamma ag_n with Phi = expm(A dt), Gamma = int_0^dt
expm(A s) ds B, both from the matrix exponential of the augmented 3x3 system (cached per step length).
The scheme is unconditionally stable, so a very stiff storey (small T) needs no small steps.

T = 0 is the infinitely stiff (rigid) storey: the floor moves with the ground, u = u' = 0 and
a_floor = ag (the value held over the last step).
"""
from __future__ import annotations

import math
from typing import Dict, Tuple

import numpy as np

from ..validation import check_ag, check_real, check_state_header, state_float, state_floats

__all__ = ["LinearStorey", "StoreySimulator", "T_MIN", "T_MAX", "ZETA_MAX", "U_MAX", "U_DOT_MAX"]


#: [s] shortest period of an elastic storey (T = 0 is the rigid one). Building storeys have periods of
#: 0.05 to 5 s; below 1 ms the storey follows the ground to within (omega^2)^-1 ag ~ 2.5e-8 ag m, i.e. it is
#: rigid (use T = 0), and omega^2 = (2 pi / T)^2 would overflow for T below ~1e-154 s.
T_MIN = 1e-3
#: [s] longest period: the storey is then practically free (a floor that does not follow the ground)
T_MAX = 1e4
#: [1] largest damping ratio (as the flexible oscillator's zeta): far past critical damping (1)
ZETA_MAX = 10.0
#: [m] largest initial floor displacement |u_0|: a kilometre is far beyond any storey drift, and it keeps
#: omega^2 u and the outputs finite for every period in range
U_MAX = 1e3
#: [m/s] largest initial floor velocity |u_dot_0| (the same reason)
U_DOT_MAX = 1e3


class LinearStorey:
    """Damped SDOF storey: period T [s] (0 = rigid, else in [T_MIN, T_MAX] = [1e-3, 1e4]), damping ratio
    zeta [1] in [0, ZETA_MAX = 10]."""

    def __init__(self, T: float = 0.5, zeta: float = 0.05):
        self.T = check_real("T", T, lo=0.0, hi=T_MAX)
        if 0.0 < self.T < T_MIN:
            raise ValueError(f"T = {self.T:g} is out of range; allowed values 0 (rigid storey) or "
                             f"[{T_MIN:g}, {T_MAX:g}] s: a storey stiffer than T = {T_MIN:g} s moves with the "
                             "ground (use T = 0)")
        self.zeta = check_real("zeta", zeta, lo=0.0, hi=ZETA_MAX)

    @property
    def rigid(self) -> bool:
        return self.T == 0.0

    @property
    def omega(self) -> float:
        """Circular frequency [rad/s] (inf for the rigid storey)."""
        return math.inf if self.rigid else 2.0 * math.pi / self.T

    def state_matrix(self) -> np.ndarray:
        """A of x' = A x + B ag, x = [u, u']."""
        w = self.omega
        return np.array([[0.0, 1.0], [-w * w, -2.0 * self.zeta * w]])

    def floor_acceleration(self, u: float, u_dot: float) -> float:
        """Absolute floor acceleration [m/s2] of the elastic storey at state (u, u')."""
        w = self.omega
        return -(2.0 * self.zeta * w * u_dot + w * w * u)

    def transition(self, dt: float) -> Tuple[np.ndarray, np.ndarray]:
        """(Phi, Gamma) of the exact zero-order-hold discretization over a step dt [s]."""
        M = np.zeros((3, 3))
        M[:2, :2] = self.state_matrix()
        M[1, 2] = -1.0  # B = [0, -1]
        from scipy.linalg import expm      # lazily: keeps scipy out of the FMUs' cold start

        E = expm(M * dt)
        return E[:2, :2], E[:2, 2]


class StoreySimulator:
    """Stepwise integration of a `LinearStorey` (the interface the FMU plumbing expects: ``t``,
    ``advance(t_end, ag)``, ``outputs()``, ``get_state()`` / ``set_state()``). Each step costs one 3x3
    matrix exponential at most (cached per step length): bounded work for any step length."""

    def __init__(self, storey: LinearStorey, t0: float = 0.0, u_0: float = 0.0, u_dot_0: float = 0.0):
        self.storey = storey
        self.t = check_real("t0", t0)
        u_0 = check_real("u_0", u_0, lo=-U_MAX, hi=U_MAX)
        u_dot_0 = check_real("u_dot_0", u_dot_0, lo=-U_DOT_MAX, hi=U_DOT_MAX)
        if storey.rigid and (u_0 != 0.0 or u_dot_0 != 0.0):
            raise ValueError("u_0 and u_dot_0 must be 0 for a rigid storey (T = 0); allowed range [0, 0]")
        self.x = np.array([u_0, u_dot_0])
        self.ag = 0.0        # ground acceleration held over the last step (rigid storey output)
        self._cache: Dict[float, Tuple[np.ndarray, np.ndarray]] = {}
        self._check(self.x, 0.0, "u_0, u_dot_0")

    def _check(self, x, ag, cause) -> None:
        """The outputs of state x are finite, or ValueError naming ``cause``."""
        a = ag if self.storey.rigid else self.storey.floor_acceleration(float(x[0]), float(x[1]))
        if not (math.isfinite(float(x[0])) and math.isfinite(float(x[1])) and math.isfinite(a)):
            raise ValueError(f"the storey's state is not finite ({cause}: u = {float(x[0])!r}, u_dot = "
                             f"{float(x[1])!r}, a_floor = {a!r}); the values are too large for the storey")

    def advance(self, t_end: float, ag: float) -> None:
        """Integrate exactly to t_end [s] with ag [m/s2] held constant, |ag| <= AG_MAX. Raises ValueError
        (state kept) for a bad t_end or ag, or outputs that would not be finite."""
        ag = check_ag(ag)
        t_end = check_real("t_end", t_end)
        dt = t_end - self.t
        if dt < 0.0:
            raise ValueError(f"t_end = {t_end!r} is before the current time {self.t!r}")
        x = self.x
        if dt > 0.0 and not self.storey.rigid:
            if dt not in self._cache:
                if len(self._cache) > 16:
                    self._cache.clear()
                self._cache[dt] = self.storey.transition(dt)
            Phi, Gamma = self._cache[dt]
            x = Phi @ self.x + Gamma * ag
            self._check(x, ag, f"step of {dt:g} s to t = {t_end!r} with ag = {ag:g}")
        self.x, self.ag, self.t = x, ag, t_end

    def outputs(self) -> dict:
        u, u_dot = float(self.x[0]), float(self.x[1])
        if self.storey.rigid:
            a_floor = self.ag
        else:
            a_floor = self.storey.floor_acceleration(u, u_dot)
        return {"u": u, "u_dot": u_dot, "a_floor": float(a_floor)}

    #: the `get_state` fields
    STATE_KEYS = ("version", "model", "t", "x", "ag")

    def get_state(self) -> dict:
        """t [s], x = [u [m], u_dot [m/s]] and the ag [m/s2] held over the last step (the rigid storey's
        output) as a flat dict of plain values with a version and the model's name; the storey's T and zeta
        are parameters (rebuild the simulator from them, then `set_state`)."""
        return {"version": 1, "model": "LinearStorey", "t": float(self.t),
                "x": [float(a) for a in self.x], "ag": float(self.ag)}

    def set_state(self, state) -> None:
        """Load a `get_state` dict: every field checked (ValueError naming it, nothing changed on error)."""
        check_state_header(state, "LinearStorey", self.STATE_KEYS)
        t = state_float(state, "t")
        x = np.array(state_floats(state, "x", length=2))
        ag = state_float(state, "ag")
        try:
            check_ag(ag)
        except ValueError as exc:
            raise ValueError(f"state field 'ag': {exc}") from None
        if self.storey.rigid and (x[0] != 0.0 or x[1] != 0.0):
            raise ValueError("state field 'x' must be [0, 0] for a rigid storey (T = 0)")
        try:
            self._check(x, ag, "state field 'x'")
        except ValueError as exc:
            raise ValueError(f"state field 'x': {exc}") from None
        self.t, self.x, self.ag = t, x, ag
