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

from dataclasses import dataclass, field
from typing import ClassVar

from ..params import Param, param
from .base import PHI_0, PHI_DOT_0, RockingModel, body_outputs, friction_param, impact_law_param
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
        """The oscillator's mechanics (the paper's Eqs. 48-54), from which the engine's kernels are generated
        (`rocking_model.models.declare`): the column's deflection u psi(xi) with Eq. (48)'s shape function,
        its kinetic energy and first moment integrated over the height.

        Derived quantities (attributes of an instance, SI units): the module docstring's shorthands m_tilde,
        k_tilde, M_t, D, A_h, C, I_mb, J0, J_eff, c = 2 zeta sqrt(m_tilde k_tilde), omega = sqrt(k_tilde/m_tilde)
        the fixed-base column frequency, h_cg = A_h/M_t, R = sqrt(b^2 + h_cg^2), alpha = atan(b/h_cg), I_O = J0 +
        M_t b^2, p = sqrt(M_t g R/I_O) of the equivalent rigid structure, u_star = sqrt(max(M_t b^2 - J_eff, 0)/
        m_tilde) the deflection at which the corners decouple at impact (`rocking_model.post_impact`), EI_max."""
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
        D = m + sp.Rational(3, 8) * m_c
        A_h = (m + m_c / 2) * h
        C = (m + sp.Rational(11, 40) * m_c) * h
        J0 = m_b * rho ** 2 + m * h ** 2 + m_c * h ** 2 / 3
        J_eff = J0 - C ** 2 / m_tilde
        c = 2 * zeta * sp.sqrt(m_tilde * k_tilde)
        h_cg = A_h / M_t
        R = sp.sqrt(b ** 2 + h_cg ** 2)
        I_O = J0 + M_t * b ** 2
        p_freq = sp.sqrt(M_t * g * R / I_O)
        singular = "NAME is out of range when m_c = 0: the mass matrix is singular unless m_c > 0 " \
                   "or m_b*rho^2 > 0; allowed range with m_c = 0: m_b in (0, 1e+12] and rho in (0, 1000]"
        return Mechanics(
            kinetic=kinetic,
            first_moment=(m * X_top + column(m_c / h * X_c) + m_b * x, m * Y_top + column(m_c / h * Y_c) + m_b * y),
            potential=k_tilde * u ** 2 / 2,
            dissipation=c * u_dot ** 2 / 2,
            contacts=[(x + s * b * cos, y + s * b * sin) for s in (-1, 1)],
            rest=(0, 0, 0, 0),
            derived={"m_tilde": m_tilde, "k_tilde": k_tilde, "M_t": M_t, "D": D, "A_h": A_h, "C": C,
                     "I_mb": m_b * rho ** 2, "J0": J0, "J_eff": J_eff, "c": c, "omega": omega, "h_cg": h_cg,
                     "R": R, "alpha": sp.atan2(b, h_cg), "I_O": I_O, "p": p_freq,
                     "u_star": sp.sqrt(sp.Max(M_t * b ** 2 - J_eff, 0) / m_tilde),
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
                sp, m_tilde, D, M_t, J0, b, q_, v_, s_new)),
        )

    @property
    def work_note(self) -> str:
        return f"column omega = {self.omega:.6g} rad/s"
