"""Rigid rocking block (Giouvanidis & Dimitrakopoulos 2017, Sect. 2; Housner 1963).

Rectangular block of half-width b [m], half-height h [m] and mass m [kg] on a rigid ground moving
horizontally with acceleration ag [m/s2] (positive along +x) and vertically with ag_v [m/s2] (positive upward:
in the ground frame the inertial force -m ag_v along +y, an effective gravity g + ag_v). Full coordinates
q = [x, y, phi]: centroid position in the ground frame (y absolute, y = h at rest) and rotation phi, positive
counter-clockwise; phi > 0 pivots on the left corner. Corner i sits at body coordinates (s_i b, -h), s = (-1, +1).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import ClassVar

from ..modes import Mode
from ..params import Param, param
from .base import PHI_0, PHI_DOT_0, RockingModel, body_outputs, friction_param, impact_law_param
from .declare import ENERGY, SLIP, Mechanics


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
        """The block's mechanics, from which the engine's kernels are generated (`rocking_model.models.declare`).

        Derived quantities (attributes of an instance): R = sqrt(b^2 + h^2) [m] the half-diagonal, alpha =
        atan(b/h) [rad] the slenderness, I_c = m R^2/3 and I_O = 4/3 m R^2 [kg m2] the moments of inertia about
        the centroid and a corner, p = sqrt(3 g/(4 R)) [rad/s] the frequency parameter, housner_r =
        1 - 3/2 sin^2(alpha) [1] Housner's coefficient of restitution."""
        x, y, phi = q
        x_dot, y_dot, phi_dot = v
        b, h, m, g = p.b, p.h, p.m, p.g
        R = sp.sqrt(b ** 2 + h ** 2)
        I_c = m * R ** 2 / 3
        p_freq = sp.sqrt(3 * g / (4 * R))
        alpha = sp.atan2(b, h)
        # corner s (-1 left, +1 right) at body coordinates (s b, -h)
        corners = [(x + s * b * sp.cos(phi) + h * sp.sin(phi), y + s * b * sp.sin(phi) - h * sp.cos(phi))
                   for s in (-1, 1)]
        return Mechanics(
            kinetic=m * (x_dot ** 2 + y_dot ** 2) / 2 + I_c * phi_dot ** 2 / 2,
            first_moment=(m * x, m * y),
            contacts=corners,
            rest=(0, h, 0),
            derived={"R": R, "alpha": alpha, "p": p_freq, "I_c": I_c, "I_O": 4 * I_c,
                     "housner_r": 1 - sp.Rational(3, 2) * b ** 2 / R ** 2},
            length_scale=R, time_scale=1 / p_freq, force_scale=m * g,
            outputs={"phi": phi, "phi_dot": phi_dot, "x": x, "y": y - h, "x_dot": x_dot, "y_dot": y_dot,
                     "slip": SLIP, "energy": ENERGY},
        )

    def rocking_acceleration(self, phi: float, ag: float, s: int, ag_v: float = 0.0) -> float:
        """phi_ddot [rad/s2] rocking on pivot s (-1 left, +1 right) at rotation phi [rad] under ag, ag_v [m/s2]:
        p^2 [(ag/g) cos(alpha + s phi) + (1 + ag_v/g) s sin(alpha + s phi)] (the kernel's rocking mode)."""
        mode = Mode.LEFT if s < 0 else Mode.RIGHT
        return float(self.reduced_acceleration(mode, [phi], [0.0], ag, ag_v)[0])
