"""Rigid rocking block (Giouvanidis & Dimitrakopoulos 2017, Sect. 2; Housner 1963).

Rectangular block of half-width b [m], half-height h [m] and mass m [kg] on a rigid ground moving
horizontally with acceleration ag [m/s2] (positive along +x) and vertically with ag_v [m/s2] (positive upward:
in the ground frame the inertial force -m ag_v along +y, an effective gravity g + ag_v). Full coordinates
q = [x, y, phi]: centroid position in the ground frame (y absolute, y = h at rest) and rotation phi, positive
counter-clockwise; phi > 0 pivots on the left corner. Corner i sits at body coordinates (s_i b, -h), s = (-1, +1).
"""
from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np

from ..modes import Mode, pivot_sign
from ..params import Param, check_parameters, param
from .base import (PHI_0, PHI_DOT_0, RockingModel, body_outputs, friction_param,
                   impact_law_param)
from .declare import ENERGY, SLIP, Mechanics

_S = (-1.0, 1.0)


@dataclass(frozen=True)
class RigidBlock(RockingModel):
    """Rigid block: b, h [m] half-dimensions, m [kg], g [m/s2], e_N [1] in [0, 1]."""

    # supported ranges (SI): generous, but they keep every derived quantity finite (no overflow)
    b: float = param(0.2, "m", "Half-width of the block", lo=1e-6, hi=1e3)
    h: float = param(1.0, "m", "Half-height of the block", lo=1e-6, hi=1e3)
    m: float = param(1.0, "kg", "Mass of the block", lo=1e-9, hi=1e12)
    g: float = param(9.81, "m/s2", "Gravitational acceleration", lo=1e-3, hi=1e3)
    e_N: float = param(0.0, "1", "Newton coefficient of restitution at the corners (0: Housner's "
                       "angular-momentum impact)", lo=0.0, hi=1.0)
    impact_law: int = impact_law_param()
    mu: float = friction_param()
    dof_names: tuple = field(default=("x", "y", "phi"), init=False, repr=False)
    slide_index: int = field(default=0, init=False, repr=False)
    phi_index: int = field(default=2, init=False, repr=False)

    kind: ClassVar[str] = "rigid"
    fmu_name: ClassVar[str] = "RigidRockingBlock"
    title: ClassVar[str] = "rigid rocking block"

    #: initial values (`initial_state`)
    INITIAL: ClassVar[tuple] = (PHI_0, PHI_DOT_0)
    #: outputs (`outputs`)
    OUTPUTS: ClassVar[tuple] = body_outputs("block", "the centroid") + (
        Param("energy", 0.0, "J", "Mechanical energy relative to rest (kinetic relative to the ground + "
              "potential); once overturned, the potential energy of the pose reached, m g (b - h) lying on a side"),
    )

    @staticmethod
    def mechanics(sp, p, q, v) -> Mechanics:
        """The block's mechanics for the engine's code generator (`rocking_model.models.declare`)."""
        x, y, phi = q
        x_dot, y_dot, phi_dot = v
        b, h, m, g = p.b, p.h, p.m, p.g
        R = sp.sqrt(b ** 2 + h ** 2)
        I_c = m * R ** 2 / 3
        p_freq = sp.sqrt(3 * g / (4 * R))
        # corner s (-1 left, +1 right) at body coordinates (s b, -h)
        corners = [(x + s * b * sp.cos(phi) + h * sp.sin(phi), y + s * b * sp.sin(phi) - h * sp.cos(phi))
                   for s in (-1, 1)]
        return Mechanics(
            kinetic=m * (x_dot ** 2 + y_dot ** 2) / 2 + I_c * phi_dot ** 2 / 2,
            first_moment=(m * x, m * y),
            contacts=corners,
            rest=(0, h, 0),
            derived={"R": R, "alpha": sp.atan2(b, h), "p": p_freq},
            length_scale=R, time_scale=1 / p_freq, force_scale=m * g,
            outputs={"phi": phi, "phi_dot": phi_dot, "x": x, "y": y - h, "x_dot": x_dot, "y_dot": y_dot,
                     "slip": SLIP, "energy": ENERGY},
        )

    def __post_init__(self):
        check_parameters(self)
        # derived parameters, computed once (the integrators read them in their inner loops)
        # (a frozen dataclass: written into the instance's dict, as object.__setattr__ would, in one call)
        R = math.hypot(self.b, self.h)
        self.__dict__.update(_R=R, _alpha=math.atan2(self.b, self.h), _I_c=self.m * (R * R) / 3.0,
                             _p=math.sqrt(3.0 * self.g / (4.0 * R)))

    # the mass matrix and its inverse, made on first use (the compiled engine never reads them)
    @functools.cached_property
    def _M(self) -> np.ndarray:
        m = self.m
        return np.array(((m, 0.0, 0.0), (0.0, m, 0.0), (0.0, 0.0, self._I_c)))

    @functools.cached_property
    def _Minv(self) -> np.ndarray:
        return np.array(((1.0 / self.m, 0.0, 0.0), (0.0, 1.0 / self.m, 0.0), (0.0, 0.0, 1.0 / self._I_c)))

    # ------------------------------------------------------------------ derived parameters
    @property
    def R(self) -> float:
        """Half-diagonal sqrt(b^2 + h^2) [m]."""
        return self._R

    @property
    def alpha(self) -> float:
        """Slenderness angle atan(b/h) [rad]."""
        return self._alpha

    @property
    def I_c(self) -> float:
        """Centroidal moment of inertia m R^2 / 3 [kg m2]."""
        return self._I_c

    @property
    def I_O(self) -> float:
        """Moment of inertia about a corner 4/3 m R^2 [kg m2]."""
        return 4.0 * self._I_c

    @property
    def p(self) -> float:
        """Frequency parameter sqrt(3 g / (4 R)) [rad/s]."""
        return self._p

    @property
    def force_scale(self) -> float:
        """The weight m g [N]."""
        return self.m * self.g

    @property
    def housner_r(self) -> float:
        """Housner's coefficient of restitution 1 - 1.5 sin^2(alpha) [1]."""
        return 1.0 - 1.5 * math.sin(self.alpha) ** 2

    @property
    def length_scale(self) -> float:
        return self.R

    @property
    def time_scale(self) -> float:
        return 1.0 / self.p

    # ------------------------------------------------------------------ dynamical system
    def mass_matrix(self, q):
        return self._M

    def inverse_mass_matrix(self, q):
        return self._Minv

    def forces(self, q, v, ag, ag_v=0.0):
        """[N]: ground frame: inertial force -m ag along x, gravity and the inertial force of the vertical
        ground acceleration, -m (g + ag_v), along y (ag, ag_v [m/s2]; ag_v positive upward)."""
        return np.array([-self.m * ag, -self.m * (self.g + ag_v), 0.0])

    # ------------------------------------------------------------------ contact relation
    def gaps(self, q):
        y, phi = q[1], q[2]
        sp, cp = math.sin(phi), math.cos(phi)
        return np.array([y + s * self.b * sp - self.h * cp for s in _S])

    def contact_jacobians(self, q):
        phi = float(q[2])
        last = self.__dict__.get("_jac_last")
        if last is not None and last[0] == phi:
            return last[1]                 # an event asks for them several times at the same state
        sp, cp = math.sin(phi), math.cos(phi)
        b, h = self.b, self.h
        W_N = np.array([[0.0, 0.0], [1.0, 1.0], [-b * cp + h * sp, b * cp + h * sp]])
        W_T = np.array([[1.0, 1.0], [0.0, 0.0], [b * sp + h * cp, -b * sp + h * cp]])
        W_N.flags.writeable = W_T.flags.writeable = False      # shared by the callers
        object.__setattr__(self, "_jac_last", (phi, (W_N, W_T)))
        return W_N, W_T

    def contact_abscissae(self, q):
        x, phi = float(q[0]), float(q[2])
        bc, hs = self.b * math.cos(phi), self.h * math.sin(phi)
        return np.array([x - bc + hs, x + bc + hs])

    def contact_drift(self, q, v):
        phi, w = q[2], v[2]
        sp, cp = math.sin(phi), math.cos(phi)
        b, h = self.b, self.h
        a_N = np.array([(-s * b * sp + h * cp) * w * w for s in _S])
        a_T = np.array([(-s * b * cp - h * sp) * w * w for s in _S])
        return a_N, a_T

    # ------------------------------------------------------------------ contact modes
    def mode_dofs(self, mode):
        if mode == Mode.FULL:
            return ()
        if mode == Mode.FLIGHT:
            return (0, 1, 2)
        return (2,)

    def embed(self, mode, r, r_dot):
        if mode == Mode.FULL:
            return np.array([0.0, self.h, 0.0]), np.zeros(3)
        if mode == Mode.FLIGHT:
            return np.array(r, dtype=float), np.array(r_dot, dtype=float)
        s = pivot_sign(mode)
        phi, w = float(r[0]), float(r_dot[0])
        sp, cp = math.sin(phi), math.cos(phi)
        b, h = self.b, self.h
        q = np.array([s * b * (1.0 - cp) - h * sp, -s * b * sp + h * cp, phi])
        v = np.array([(s * b * sp - h * cp) * w, (-s * b * cp - h * sp) * w, w])
        return q, v

    def mode_jacobian(self, mode, r, r_dot):
        if mode == Mode.FULL:
            return np.zeros((3, 0)), np.zeros(3)
        if mode == Mode.FLIGHT:
            return np.eye(3), np.zeros(3)
        s = pivot_sign(mode)
        phi, w = float(r[0]), float(r_dot[0])
        sp, cp = math.sin(phi), math.cos(phi)
        b, h = self.b, self.h
        J = np.array([[s * b * sp - h * cp], [-s * b * cp - h * sp], [1.0]])
        jd = np.array([(s * b * cp + h * sp) * w * w, (s * b * sp - h * cp) * w * w, 0.0])
        return J, jd

    def rocking_acceleration(self, phi: float, ag: float, s: int, ag_v: float = 0.0) -> float:
        """phi_ddot [rad/s2] on pivot s (-1 left, +1 right):
        p^2 [(ag/g) cos(alpha + s phi) + (1 + ag_v/g) s sin(alpha + s phi)], ag and ag_v [m/s2] (ag_v positive
        upward: the effective gravity g + ag_v scales the restoring moment)."""
        a = self._alpha + s * phi
        # ((g + ag_v) / g) is exactly 1 for ag_v = 0: the same result as without the vertical component
        return self._p * self._p * ((ag / self.g) * math.cos(a) + ((self.g + ag_v) / self.g) * s * math.sin(a))

    def reduced_acceleration(self, mode, r, r_dot, ag, ag_v=0.0):
        if mode == Mode.FULL:
            return np.zeros(0)
        if mode == Mode.FLIGHT:
            return np.array([-ag, -(self.g + ag_v), 0.0])
        return np.array([self.rocking_acceleration(float(r[0]), ag, pivot_sign(mode), ag_v)])

    def contact_forces(self, mode, q, v, ag, ag_v=0.0):
        m, g = self.m, self.g + ag_v       # the effective gravity
        if mode == Mode.FULL:
            # vertical and moment equilibrium with the horizontal sticking force m ag at y = -h
            d = 0.5 * m * ag * self.h / self.b
            return np.array([0.5 * m * g + d, 0.5 * m * g - d])
        if mode == Mode.FLIGHT:
            return np.zeros(2)
        # vertical Newton's law of the centroid: lambda_N = m (y_ddot + g)
        s = pivot_sign(mode)
        phi, w = float(q[2]), float(v[2])
        acc = self.rocking_acceleration(phi, ag, s, ag_v)
        y_dd = (-s * self.b * math.cos(phi) - self.h * math.sin(phi)) * acc + \
            (s * self.b * math.sin(phi) - self.h * math.cos(phi)) * w * w
        out = np.zeros(2)
        out[0 if s < 0 else 1] = m * (y_dd + g)
        return out

    # ------------------------------------------------------------------ quantities
    def rest_position(self):
        return np.array([0.0, self.h, 0.0])

    def initial_state(self, phi_0=0.0, phi_dot_0=0.0, **extra):
        self.check_initial_names(extra)
        p_phi, p_phi_dot = self.INITIAL
        # (a value the check would return unchanged skips it: the common case of every run)
        if not p_phi.accepts_as_is(phi_0):
            phi_0 = p_phi.check(phi_0)
        if not p_phi_dot.accepts_as_is(phi_dot_0):
            phi_dot_0 = p_phi_dot.check(phi_dot_0)
        mode = self.mode_of_initial_state(phi_0, phi_dot_0)
        if mode == Mode.FULL:
            q, v = self.embed(mode, (), ())       # (full contact: no reduced coordinates)
        else:
            q, v = self.embed(mode, (phi_0,), (phi_dot_0,))
        return mode, q, v

    def energy(self, q, v):
        kin = 0.5 * (self.m * (v[0] * v[0] + v[1] * v[1]) + self.I_c * (v[2] * v[2]))
        return kin + self.m * self.g * (q[1] - self.h)

    def outputs(self, q, v):
        return {
            "phi": float(q[2]), "phi_dot": float(v[2]),
            "x": float(q[0]), "y": float(q[1] - self.h),
            "x_dot": float(v[0]), "y_dot": float(v[1]),
            # the lower corner's displacement (the left one, s = -1, for phi > 0), as `slip`
            "slip": float(q[0]) + (-1.0 if q[2] > 0.0 else 1.0) * self.b * (math.cos(q[2]) - 1.0)
            + self.h * math.sin(q[2]),
            "energy": float(self.energy(q, v)),
        }
