"""Flexible rocking oscillator (Giouvanidis & Dimitrakopoulos 2017, appendix, Eqs. 48-55).

A cantilever column of height h [m], flexural rigidity EI [N m2] and uniformly distributed mass m_c [kg]
carries a lumped top mass m [kg] (no rotary inertia) and stands on a rigid base of mass m_b [kg], radius of
gyration rho [m] (I_mb = m_b rho^2) and half-width b [m]; the base has negligible thickness and its corners
sit at +-b from the base midpoint along the base. The column deforms with the cubic shape function
psi(xi) = 3 xi^2/(2 h^2) - xi^3/(2 h^3) (Eq. 48) and generalized coordinate u (tip deflection), so that

    m_tilde = m + 33/140 m_c,   k_tilde = 3 EI / h^3,   damping on u only: Q_u = -2 zeta sqrt(m_tilde k_tilde) u_dot.

Full coordinates q = [u, x, y, phi] (ground frame): u flexural coordinate, (x, y) base midpoint (y = 0 at
rest), phi rotation, positive counter-clockwise (phi > 0 pivots on the left corner). Ground acceleration ag
[m/s2] is horizontal, positive along +x; it enters as the inertial force of the ground-frame formulation. The
vertical ground acceleration ag_v [m/s2], positive upward, adds the inertial force -m_i ag_v along +y on every
mass: gravity g becomes the effective gravity g + ag_v in Eq. (55) (the strain energy and the geometry stay).

Shorthands used below and in `rocking_model.post_impact` (moments of the mass distribution):
    D   = m + 3/8 m_c        (first moment of the shape function, integral of psi dm / 1)
    A_h = (m + 1/2 m_c) h    (first moment of the mass about the base)
    C   = (m + 11/40 m_c) h  (integral of xi psi dm: coupling u <-> phi)
    J0  = I_mb + m h^2 + m_c h^2/3   (moment of inertia about the base midpoint, u = 0)
    J_eff = J0 - C^2/m_tilde          (rotary inertia left once u is condensed out)
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np

from ..modes import Mode, pivot_sign
from ..params import Param, check_parameters, param
from ..validation import check_real
from .base import (PHI_0, PHI_DOT_0, RockingModel, body_outputs, friction_param,
                   impact_law_param)
from .declare import ENERGY, SLIP, Check, ClassicalImpact, Mechanics


#: [rad/s] largest fixed-base circular frequency omega = sqrt(k_tilde/m_tilde) of the column (1.6 kHz).
#: Rocking structures have columns of 1 to 100 Hz; at omega = 1e4 rad/s the column's deflection under a
#: lateral 1 g is g/omega^2 ~ 1e-7 m and omega/p exceeds 300 for any structure taller than 1 cm: it rocks
#: as a rigid body (use `RigidBlock`). The cost of resolving the column grows with omega (Moreau-Jean
#: sub-steps to 0.25/omega: 4e4 steps per second of motion at the bound), so an unbounded EI lets one
#: co-simulation step take minutes (EI = 1e15 measured at ~10 s per 0.01 s step).
OMEGA_MAX = 1e4


def _classical_velocity(sp, m_tilde, D, M_t, J0, b, q, v_minus, s_new):
    """The classical impact rule's post-impact velocity (rocking_model.post_impact.classical_impact): the
    angular momentum about the landing corner (pivot sign s_new) conserved, u_dot continuous, rocking on about
    that corner."""
    u = q[0]
    a0 = J0 + m_tilde * u ** 2
    w_plus = (a0 - M_t * b ** 2) / (a0 + M_t * b ** 2 - 2 * s_new * b * D * u) * v_minus[3]
    return (v_minus[0], 0, -s_new * b * w_plus, w_plus)


@dataclass(frozen=True)
class FlexibleOscillator(RockingModel):
    """Flexible rocking oscillator of Giouvanidis & Dimitrakopoulos (2017), appendix.

    Parameters (SI units): m top mass [kg] (> 0), m_c column mass [kg] (>= 0), m_b base mass [kg] (>= 0),
    rho radius of gyration of the base [m] (>= 0), h column height [m] (> 0), b base half-width [m] (> 0),
    EI flexural rigidity [N m2] (> 0, and omega = sqrt(3 EI/(h^3 m_tilde)) <= OMEGA_MAX = 1e4 rad/s),
    zeta damping ratio of u [1] (>= 0), e_N coefficient of restitution
    [1] in [0, 1], g gravity [m/s2] (> 0), impact_rule 0 (LCP with Newton's law, default) or 1 (classical
    rule of the earlier literature: angular momentum about the impacting corner conserved, u_dot continuous,
    rocking on about the new corner; `rocking_model.post_impact.classical_impact`). The mass matrix must be non-singular, which needs rotary inertia
    besides the top mass: m_c > 0 or m_b rho^2 > 0 (with m_c = 0 and I_mb = 0 the base rotation and u both
    move the top mass only, and M is singular at u = 0).

    Defaults: a representative laboratory-scale specimen in the range of the shake-table tests on flexible
    rocking oscillators (Truniger, Vassiliou & Stojadinovic 2015; Vassiliou, Mackie & Stojadinovic 2015) --
    plausible values chosen for this library, not the data of a published specimen: a 1.5 m steel column
    HEB 100 (E I = 210 GPa x 450 cm^4 = 9.45e5 N m2, 20.4 kg/m, m_c = 30 kg) carrying m = 500 kg, on a
    steel base plate 0.5 x 0.5 x 0.05 m (b = 0.25 m, m_b = 100 kg, rho = sqrt((2b)^2 + t^2)/sqrt(12) =
    0.145 m), zeta = 2 %, e_N = 0 (plastic impact, as the rigid block default). Derived: m_tilde = 507 kg,
    k_tilde = 8.4e5 N/m, fixed-base column frequency omega = 40.7 rad/s (6.5 Hz), rocking frequency parameter
    p = 2.55 rad/s (omega/p = 16), slenderness b/h_cg = 0.20.
    """

    # supported ranges (SI): generous, but they keep every derived quantity finite (no overflow)
    m: float = param(500.0, "kg", "Lumped top mass (> 0)", lo=1e-9, hi=1e12)
    m_c: float = param(30.0, "kg", "Column mass, uniformly distributed (>= 0)", lo=0.0, hi=1e12)
    m_b: float = param(100.0, "kg", "Base mass (>= 0)", lo=0.0, hi=1e12)
    rho: float = param(0.145, "m", "Radius of gyration of the base (>= 0)", lo=0.0, hi=1e3)
    h: float = param(1.5, "m", "Column height (> 0)", lo=1e-6, hi=1e3)
    b: float = param(0.25, "m", "Half-width of the base (> 0)", lo=1e-6, hi=1e3)
    EI: float = param(9.45e5, "N.m2", "Flexural rigidity of the column (> 0; the column's omega at most "
                      "OMEGA_MAX = 1e4 rad/s)", lo=0.0, lo_open=True, hi=1e15)
    zeta: float = param(0.02, "1", "Damping ratio of the flexural mode (>= 0)", lo=0.0, hi=10.0)
    e_N: float = param(0.0, "1", "Newton coefficient of restitution at the base corners, in [0, 1]",
                       lo=0.0, hi=1.0)
    impact_law: int = impact_law_param()
    mu: float = friction_param()
    impact_rule: int = param(0, None, "Impact rule at a rocking impact", items=(
        ("lcp", 0, "the impact LCP with Newton's law (the paper's formulation)"),
        ("classical", 1, "the classical rule: angular momentum about the impacting corner conserved, "
                         "flexural velocity continuous")))
    g: float = param(9.81, "m/s2", "Gravitational acceleration", lo=1e-3, hi=1e3)
    dof_names: tuple = field(default=("u", "x", "y", "phi"), init=False, repr=False)
    slide_index: int = field(default=1, init=False, repr=False)
    lift_index: int = field(default=2, init=False, repr=False)
    phi_index: int = field(default=3, init=False, repr=False)

    SHIFTED_OUTPUTS: ClassVar[tuple] = ("x", "slip", "top_displacement")
    kind: ClassVar[str] = "flexible"
    fmu_name: ClassVar[str] = "FlexibleRockingOscillator"
    title: ClassVar[str] = "flexible rocking oscillator"

    #: initial values (`initial_state`)
    INITIAL: ClassVar[tuple] = (
        PHI_0, PHI_DOT_0,
        Param("u_0", 0.0, "m", "Initial flexural coordinate (tip deflection), |u_0| <= h"),
        Param("u_dot_0", 0.0, "m/s", "Initial flexural velocity", lo=-1e4, hi=1e4),
    )
    #: outputs (`outputs`)
    OUTPUTS: ClassVar[tuple] = (
        Param("u", 0.0, "m", "Flexural coordinate (tip deflection relative to the base)"),
        Param("u_dot", 0.0, "m/s", "Flexural velocity (0 once overturned)"),
    ) + body_outputs("base", "the base midpoint") + (
        Param("top_displacement", 0.0, "m", "Horizontal displacement of the top mass relative to the ground"),
        Param("energy", 0.0, "J", "Mechanical energy relative to rest (kinetic relative to the ground + "
              "potential + strain); once overturned, the potential + strain energy of the pose reached"),
    )

    @staticmethod
    def mechanics(sp, p, q, v) -> Mechanics:
        """The oscillator's mechanics (the paper's Eqs. 48-54) for the engine's code generator
        (`rocking_model.models.declare`): the column's deflection u psi(xi) with Eq. (48)'s shape function,
        its kinetic energy and first moment integrated over the height."""
        u, x, y, phi = q
        u_dot, x_dot, y_dot, phi_dot = v
        m, m_c, m_b, rho, h, b, EI, zeta, g = p.m, p.m_c, p.m_b, p.rho, p.h, p.b, p.EI, p.zeta, p.g
        xi = sp.Symbol("xi", nonnegative=True)
        psi = 3 * xi ** 2 / (2 * h ** 2) - xi ** 3 / (2 * h ** 3)
        sin, cos = sp.sin(phi), sp.cos(phi)

        def point(along, across):          # a point of the column, (along, across) in the body frame
            return x - along * sin + across * cos, y + along * cos + across * sin

        def rate(e):
            return sum(sp.diff(e, qi) * vi for qi, vi in zip(q, v))

        def column(e):                     # integral of a polynomial in xi over the column's height
            return sp.integrate(sp.expand(e), (xi, 0, h))

        X_top, Y_top = point(h, u)
        X_c, Y_c = point(xi, u * psi)
        kinetic = (m * (rate(X_top) ** 2 + rate(Y_top) ** 2) / 2
                   + column(m_c / h * (rate(X_c) ** 2 + rate(Y_c) ** 2) / 2)
                   + m_b * (x_dot ** 2 + y_dot ** 2) / 2 + m_b * rho ** 2 * phi_dot ** 2 / 2)
        m_tilde = m + sp.Rational(33, 140) * m_c
        k_tilde = 3 * EI / h ** 3
        omega = sp.sqrt(k_tilde / m_tilde)
        M_t = m + m_b + m_c
        A_h = (m + m_c / 2) * h
        J0 = m_b * rho ** 2 + m * h ** 2 + m_c * h ** 2 / 3
        h_cg = A_h / M_t
        R = sp.sqrt(b ** 2 + h_cg ** 2)
        p_freq = sp.sqrt(M_t * g * R / (J0 + M_t * b ** 2))
        singular = "NAME is out of range when m_c = 0: the mass matrix is singular unless m_c > 0 " \
                   "or m_b*rho^2 > 0; allowed range with m_c = 0: m_b in (0, 1e+12] and rho in (0, 1000]"
        return Mechanics(
            kinetic=kinetic,
            first_moment=(m * X_top + column(m_c / h * X_c) + m_b * x, m * Y_top + column(m_c / h * Y_c) + m_b * y),
            potential=k_tilde * u ** 2 / 2,
            dissipation=zeta * sp.sqrt(m_tilde * k_tilde) * u_dot ** 2,      # c u_dot^2 / 2, c = 2 zeta sqrt(m k)
            contacts=[(x + s * b * cos, y + s * b * sin) for s in (-1, 1)],
            rest=(0, 0, 0, 0),
            derived={"omega": omega, "R": R, "alpha": sp.atan2(b, h_cg), "p": p_freq,
                     "EI_max": OMEGA_MAX ** 2 * m_tilde * h ** 3 / 3},
            length_scale=sp.sqrt(b ** 2 + h ** 2), time_scale=1 / p_freq, force_scale=M_t * g,
            step_limit=sp.Rational(1, 4) / omega,
            outputs={"u": u, "u_dot": u_dot, "phi": phi, "phi_dot": phi_dot, "x": x, "y": y, "x_dot": x_dot,
                     "y_dot": y_dot, "slip": SLIP, "top_displacement": x - h * sin + u * cos, "energy": ENERGY},
            initial_bounds={"u_0": (-h, h)},
            checks=[
                Check(sp.And(sp.Eq(m_c, 0), sp.Eq(m_b, 0)), singular.replace("NAME", "m_b = {m_b:g}")),
                Check(sp.And(sp.Eq(m_c, 0), sp.Ne(m_b, 0), sp.Eq(m_b * rho ** 2, 0)),
                      singular.replace("NAME", "rho = {rho:g}")),
                Check(omega > OMEGA_MAX,
                      "EI = {EI:g} is out of range for m = {m:g}, m_c = {m_c:g}, h = {h:g}; allowed range "
                      "(0, {EI_max:.6g}] N m2: the column's circular frequency omega = sqrt(3 EI/(h^3 m_tilde)) = "
                      "{omega:.4g} rad/s exceeds OMEGA_MAX = " + f"{OMEGA_MAX:g}" + " rad/s; a column this stiff "
                      "rocks as a rigid body: use RigidBlock"),
            ],
            work_note="column omega = {omega:.6g} rad/s",
            classical_impact=ClassicalImpact("impact_rule", 1, lambda q_, v_, s_new: _classical_velocity(
                sp, m_tilde, m + sp.Rational(3, 8) * m_c, M_t, J0, b, q_, v_, s_new)),
        )

    def __post_init__(self):
        check_parameters(self)
        if self.m_c == 0.0 and self.m_b * (self.rho * self.rho) == 0.0:
            bad = "m_b" if self.m_b == 0.0 else "rho"  # rho > 0 can still give m_b*rho^2 = 0 (underflow)
            raise ValueError(
                f"{bad} = {getattr(self, bad):g} is out of range when m_c = 0: the mass matrix is singular unless m_c > 0 or "
                f"m_b*rho^2 > 0; allowed range with m_c = 0: m_b in (0, 1e+12] and rho in (0, 1000]")
        m, m_c, h = self.m, self.m_c, self.h
        d = dict(
            m_tilde=m + 33.0 / 140.0 * m_c,
            k_tilde=3.0 * self.EI / h ** 3,
            M_t=m + self.m_b + m_c,
            D=m + 3.0 / 8.0 * m_c,
            A_h=(m + 0.5 * m_c) * h,
            C=(m + 11.0 / 40.0 * m_c) * h,
            I_mb=self.m_b * (self.rho * self.rho),
        )
        d["J0"] = d["I_mb"] + m * (h * h) + m_c * (h * h) / 3.0
        d["J_eff"] = d["J0"] - d["C"] * d["C"] / d["m_tilde"]
        d["c"] = 2.0 * self.zeta * math.sqrt(d["m_tilde"] * d["k_tilde"])
        omega = math.sqrt(d["k_tilde"] / d["m_tilde"])
        if omega > OMEGA_MAX:
            EI_max = OMEGA_MAX * OMEGA_MAX * d["m_tilde"] * h ** 3 / 3.0
            raise ValueError(
                f"EI = {self.EI:g} is out of range for m = {m:g}, m_c = {m_c:g}, h = {h:g}; allowed range "
                f"(0, {EI_max:.6g}] N m2: the column's circular frequency omega = sqrt(3 EI/(h^3 m_tilde)) = "
                f"{omega:.4g} rad/s exceeds OMEGA_MAX = {OMEGA_MAX:g} rad/s; a column this stiff rocks as a "
                "rigid body: use RigidBlock")
        for k, val in d.items():
            object.__setattr__(self, k, val)

    # ------------------------------------------------------------------ derived parameters
    # (set in __post_init__ as plain attributes; documented here)
    #: m_tilde = m + 33/140 m_c [kg], k_tilde = 3 EI/h^3 [N/m], M_t = m + m_b + m_c [kg],
    #: c = 2 zeta sqrt(m_tilde k_tilde) [N s/m], D, A_h, C, I_mb, J0, J_eff: see the module docstring.

    @property
    def omega(self) -> float:
        """Fixed-base circular frequency of the column sqrt(k_tilde/m_tilde) [rad/s]."""
        return math.sqrt(self.k_tilde / self.m_tilde)

    @property
    def work_note(self) -> str:
        return f"column omega = {self.omega:.6g} rad/s"

    @property
    def step_limit(self) -> float:
        """0.25/omega [s]: Moreau-Jean with an unresolved column (omega dt >~ 0.6) lets the pivot impulses pump
        the column until it flies off and "overturns" (measured with a column at 100 p, theta = 1/2 and 1);
        resolving the column keeps it stable."""
        return 0.25 / self.omega

    @property
    def h_cg(self) -> float:
        """Height of the centre of mass of the undeformed structure above the base [m]."""
        return self.A_h / self.M_t

    @property
    def R(self) -> float:
        """Distance from a base corner to the centre of mass of the undeformed structure [m]."""
        return math.hypot(self.b, self.h_cg)

    @property
    def alpha(self) -> float:
        """Slenderness angle atan(b/h_cg) of the undeformed structure [rad]."""
        return math.atan2(self.b, self.h_cg)

    @property
    def I_O(self) -> float:
        """Moment of inertia of the undeformed structure about a base corner J0 + M_t b^2 [kg m2]."""
        return self.J0 + self.M_t * (self.b * self.b)

    @property
    def p(self) -> float:
        """Rocking frequency parameter of the equivalent rigid structure sqrt(M_t g R / I_O) [rad/s]."""
        return math.sqrt(self.M_t * self.g * self.R / self.I_O)

    @property
    def u_star(self) -> float:
        """Flexural deformation u* [m] at which the two corners decouple at impact (see post_impact).

        u*^2 = (M_t b^2 - J_eff)/m_tilde; 0 when M_t b^2 <= J_eff (no full-contact regime)."""
        return math.sqrt(max(self.M_t * self.b ** 2 - self.J_eff, 0.0) / self.m_tilde)

    @property
    def length_scale(self) -> float:
        return math.hypot(self.b, self.h)

    @property
    def time_scale(self) -> float:
        return 1.0 / self.p

    # ------------------------------------------------------------------ dynamical system
    def _M_phi_xy(self, u, sp, cp):
        """(M_x_phi, M_y_phi)."""
        return -(self.A_h * cp + self.D * u * sp), -self.A_h * sp + self.D * u * cp

    def mass_matrix(self, q):
        u, phi = float(q[0]), float(q[3])
        sp, cp = math.sin(phi), math.cos(phi)
        D, Mt = self.D, self.M_t
        Mxp, Myp = self._M_phi_xy(u, sp, cp)
        return np.array([
            [self.m_tilde, D * cp, D * sp, -self.C],
            [D * cp, Mt, 0.0, Mxp],
            [D * sp, 0.0, Mt, Myp],
            [-self.C, Mxp, Myp, self.J0 + self.m_tilde * u * u],
        ])

    def forces(self, q, v, ag, ag_v=0.0):
        """Right-hand sides of Eq. (55): damping, elastic, centrifugal/Coriolis, ground inertia, gravity [N,
        N m]; ag, ag_v [m/s2] (ag_v positive upward: the effective gravity g + ag_v)."""
        u, phi = float(q[0]), float(q[3])
        ud, w = float(v[0]), float(v[3])
        sp, cp = math.sin(phi), math.cos(phi)
        D, Mt, g = self.D, self.M_t, self.g + ag_v
        Mxp, Myp = self._M_phi_xy(u, sp, cp)
        return np.array([
            -self.c * ud - self.k_tilde * u + self.m_tilde * u * w * w - D * cp * ag - D * sp * g,
            Myp * w * w + 2.0 * D * sp * ud * w - Mt * ag,
            -Mxp * w * w - 2.0 * D * cp * ud * w - Mt * g,
            -2.0 * self.m_tilde * u * ud * w - Mxp * ag - g * Myp,
        ])

    def stiff_jacobians(self, q, v):
        K = np.zeros((4, 4))
        C = np.zeros((4, 4))
        K[0, 0] = self.k_tilde
        C[0, 0] = self.c
        return K, C

    # ------------------------------------------------------------------ contact relation
    def gaps(self, q):
        y, sp = float(q[2]), math.sin(float(q[3]))
        return np.array([y - self.b * sp, y + self.b * sp])

    def contact_jacobians(self, q):
        phi = float(q[3])
        bs, bc = self.b * math.sin(phi), self.b * math.cos(phi)
        W_N = np.array([[0.0, 0.0], [0.0, 0.0], [1.0, 1.0], [-bc, bc]])
        W_T = np.array([[0.0, 0.0], [1.0, 1.0], [0.0, 0.0], [bs, -bs]])
        return W_N, W_T

    def contact_abscissae(self, q):
        x, bc = float(q[1]), self.b * math.cos(float(q[3]))
        return np.array([x - bc, x + bc])

    def contact_drift(self, q, v):
        phi, w = float(q[3]), float(v[3])
        bs, bc = self.b * math.sin(phi) * w * w, self.b * math.cos(phi) * w * w
        return np.array([bs, -bs]), np.array([bc, -bc])

    # ------------------------------------------------------------------ contact modes
    def mode_dofs(self, mode):
        if mode == Mode.FULL:
            return (0,)
        if mode == Mode.FLIGHT:
            return (0, 1, 2, 3)
        return (0, 3)

    def embed(self, mode, r, r_dot):
        if mode == Mode.FULL:
            return np.array([float(r[0]), 0.0, 0.0, 0.0]), np.array([float(r_dot[0]), 0.0, 0.0, 0.0])
        if mode == Mode.FLIGHT:
            return np.array(r, dtype=float), np.array(r_dot, dtype=float)
        s = pivot_sign(mode)
        u, phi = float(r[0]), float(r[1])
        ud, w = float(r_dot[0]), float(r_dot[1])
        sp, cp = math.sin(phi), math.cos(phi)
        b = self.b
        q = np.array([u, s * b * (1.0 - cp), -s * b * sp, phi])
        v = np.array([ud, s * b * sp * w, -s * b * cp * w, w])
        return q, v

    def mode_jacobian(self, mode, r, r_dot):
        if mode == Mode.FULL:
            return np.array([[1.0], [0.0], [0.0], [0.0]]), np.zeros(4)
        if mode == Mode.FLIGHT:
            return np.eye(4), np.zeros(4)
        s = pivot_sign(mode)
        phi, w = float(r[1]), float(r_dot[1])
        sp, cp = math.sin(phi), math.cos(phi)
        b = self.b
        J = np.array([[1.0, 0.0], [0.0, s * b * sp], [0.0, -s * b * cp], [0.0, 1.0]])
        jd = np.array([0.0, s * b * cp * w * w, s * b * sp * w * w, 0.0])
        return J, jd

    def reduced_acceleration(self, mode, r, r_dot, ag, ag_v=0.0):
        """Closed forms for FULL and rocking (equal to the projection J^T M J of the base class).

        Rocking on pivot s (-1 left, +1 right), r = [u, phi]: the reduced mass is
        [[m_tilde, -C], [-C, K(u)]] with K = J0 + m_tilde u^2 + M_t b^2 - 2 s b D u (independent of phi), and
            m_tilde u_dd - C phi_dd = -c u_d - k_tilde u - g D sin(phi) - D cos(phi) ag + E phi_d^2
            -C u_dd + K phi_dd = -2 E u_d phi_d - g (D u - M_t s b) cos(phi) + g A_h sin(phi)
                                 + ag (A_h cos(phi) + (D u - M_t s b) sin(phi))
        with E = m_tilde u - s b D = K'(u)/2, and g the effective gravity g + ag_v (ag_v [m/s2], positive upward;
        full contact does not depend on it: phi = 0).
        """
        if mode == Mode.FULL:
            u, ud = float(r[0]), float(r_dot[0])
            return np.array([(-self.c * ud - self.k_tilde * u - self.D * ag) / self.m_tilde])
        if mode == Mode.FLIGHT:
            return super().reduced_acceleration(mode, r, r_dot, ag, ag_v)
        s = pivot_sign(mode)
        u, phi = float(r[0]), float(r[1])
        ud, w = float(r_dot[0]), float(r_dot[1])
        sp, cp = math.sin(phi), math.cos(phi)
        mt, C, D, g = self.m_tilde, self.C, self.D, self.g + ag_v
        sbM = s * self.b * self.M_t
        K = self.J0 + mt * u * u + self.M_t * (self.b * self.b) - 2.0 * s * self.b * D * u
        E = mt * u - s * self.b * D
        f_u = -self.c * ud - self.k_tilde * u - g * D * sp - D * cp * ag + E * w * w
        f_p = (-2.0 * E * ud * w - g * (D * u - sbM) * cp + g * self.A_h * sp
               + ag * (self.A_h * cp + (D * u - sbM) * sp))
        det = mt * K - C * C
        return np.array([(K * f_u + C * f_p) / det, (C * f_u + mt * f_p) / det])

    def contact_forces(self, mode, q, v, ag, ag_v=0.0):
        """Normal forces [N] of the closed corners of ``mode`` (bilateral), closed form.

        The y row of M v_dot = f + W_N lambda_N + W_T lambda_T carries only the normal forces (the tangential
        direction is horizontal), so sum(lambda_N) = (M v_dot - f)_y with v_dot = J r_ddot + J_dot r_dot. In
        full contact (phi = 0) the phi row adds b (lambda_R - lambda_L) = (M v_dot - f)_phi."""
        if mode == Mode.FLIGHT:
            return np.zeros(2)
        r, r_dot = self.reduce(mode, q, v)
        J, jd = self.mode_jacobian(mode, r, r_dot)
        resid = self.mass_matrix(q) @ (J @ self.reduced_acceleration(mode, r, r_dot, ag, ag_v) + jd) \
            - self.forces(q, v, ag, ag_v)
        if mode == Mode.FULL:
            d = resid[3] / self.b
            return np.array([0.5 * (resid[2] - d), 0.5 * (resid[2] + d)])
        out = np.zeros(2)
        out[0 if mode == Mode.LEFT else 1] = resid[2]
        return out

    # ------------------------------------------------------------------ quantities
    def rest_position(self):
        return np.zeros(4)

    def initial_state(self, phi_0=0.0, phi_dot_0=0.0, u_0=0.0, u_dot_0=0.0, **extra):
        self.check_initial_names(extra)
        phi_0, phi_dot_0, _, u_dot_0 = (p.check(value) for p, value in
                                        zip(self.INITIAL, (phi_0, phi_dot_0, 0.0, u_dot_0)))
        u_0 = check_real("u_0", u_0, lo=-self.h, hi=self.h)  # tip deflection at most the column height
        mode = self.mode_of_initial_state(phi_0, phi_dot_0)
        if mode == Mode.FULL:
            q, v = self.embed(mode, np.array([u_0]), np.array([u_dot_0]))
        else:
            q, v = self.embed(mode, np.array([u_0, phi_0]), np.array([u_dot_0, phi_dot_0]))
        return mode, q, v

    def potential_energy(self, q) -> float:
        """Eq. (53) minus its rest value (m g h + m_c g h/2) [J]."""
        u, y, phi = float(q[0]), float(q[2]), float(q[3])
        sp, cp = math.sin(phi), math.cos(phi)
        return (0.5 * self.k_tilde * u * u
                + self.g * (self.M_t * y + self.A_h * (cp - 1.0) + self.D * u * sp))

    def kinetic_energy(self, q, v) -> float:
        """Eq. (52) without the ground-velocity terms: 1/2 v^T M(q) v [J]."""
        v = np.asarray(v, dtype=float)
        return 0.5 * float(v @ self.mass_matrix(q) @ v)

    def energy(self, q, v):
        return self.kinetic_energy(q, v) + self.potential_energy(q)

    def outputs(self, q, v):
        return self._outputs(*(float(a) for a in q), *(float(a) for a in v))

    def _outputs(self, u, x, y, phi, ud, xd, yd, w, sin=math.sin, cos=math.cos) -> dict:
        sp, cp = sin(phi), cos(phi)
        D = self.D
        Mxp, Myp = self._M_phi_xy(u, sp, cp)
        # 1/2 v^T M v written out (no 4x4 product per output sample)
        kin = 0.5 * (self.m_tilde * ud * ud + self.M_t * (xd * xd + yd * yd) + (self.J0 + self.m_tilde * u * u) * w * w) \
            + D * cp * ud * xd + D * sp * ud * yd - self.C * ud * w + Mxp * xd * w + Myp * yd * w
        pot = 0.5 * self.k_tilde * u * u + self.g * (self.M_t * y + self.A_h * (cp - 1.0) + D * u * sp)
        return {
            "u": u, "u_dot": ud,
            "phi": phi, "phi_dot": w,
            "x": x, "y": y, "x_dot": xd, "y_dot": yd,
            # the lower corner's displacement (s = -1, the left one, for phi > 0): exactly 0 while rocking
            "slip": x + ((phi > 0.0) * -2.0 + 1.0) * self.b * (cp - 1.0),
            "top_displacement": x - self.h * sp + u * cp,
            "energy": kin + pot,
        }

    @property
    def force_scale(self) -> float:
        """The weight M_t g [N]."""
        return self.M_t * self.g
