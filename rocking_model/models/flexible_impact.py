"""Closed-form impact of the flexible rocking oscillator (Giouvanidis & Dimitrakopoulos 2017).

Setting: the oscillator (`FlexibleOscillator`) rocks on one base corner (the *old* pivot, sign s_o: -1 left,
+1 right) and reaches phi = 0 with flexural state (u, u_dot) and rotation rate phi_dot^- (phi_dot^- < 0 on
the left pivot, > 0 on the right one); the other corner (the *new* one, s_n = -s_o) hits the ground with
normal velocity -V, V = 2 b |phi_dot^-|. Impact law: Newton (coefficient e_N) in the normal direction,
sticking at every corner that takes an impulse (the impact LCP the engine solves).

Derivation (by hand, from the structure of the impact LCP)
----------------------------------------------------------
At phi = 0 both tangential Jacobians are the unit vector of x and the pre-impact x_dot is zero, so x_dot
stays zero and the tangential impulse only closes the x row. What is left acts on r = [u_dot, y_dot,
phi_dot] with the mass matrix

    M_r = [[m_tilde, 0, -C], [0, M_t, D u], [-C, D u, J0 + m_tilde u^2]]

and normal directions w_s = [0, 1, s b] (corner at abscissa s b). The u row carries no impulse, hence for
every outcome

    m_tilde u_dot^+ - C phi_dot^+ = m_tilde u_dot^- - C phi_dot^-   (u_dot jumps with phi_dot).       (1)

Condensing u gives the (y, phi) matrix S = [[M_t, D u], [D u, J_eff + m_tilde u^2]], J_eff = J0 - C^2/m_tilde,
det S = Delta = M_t (J_eff + m_tilde u^2) - D^2 u^2 > 0, and the Delassus matrix G = W^T S^-1 W of the two
corners

    G_ss = N_s / Delta,  N_s = J_eff + m_tilde u^2 - 2 s b D u + M_t b^2,
    G_LR = N_c / Delta,  N_c = J_eff + m_tilde u^2 - M_t b^2      (the D u terms cancel),

so the coupling changes sign at u*^2 = (M_t b^2 - J_eff)/m_tilde (no sign change, u* = 0, when
M_t b^2 <= J_eff). Enumerating the 4 active sets of the LCP with pre-impact normal velocities (0, -V):
{} and {old} leave the new corner penetrating; {new} is valid iff G_on >= 0 (|u| >= u*); {old, new} iff
G_on <= 0 (|u| <= u*). The outcome depends only on u and e_N:

* |u| > u*, impulse at the new corner only, Lambda_n = (1 + e_N) V Delta / N_n:

      phi_dot^+ / phi_dot^- = 1 - (1 + e_N) 2 (M_t b^2 - s_n b D u) / N_n                          (2)
      y_dot^+ = e_N V - s_n b phi_dot^+,  u_dot^+ from (1).

  e_N = 0: immediate rocking on the new corner (then (2) reads
  (J_eff + m_tilde u^2 - M_t b^2)/(J_eff + m_tilde u^2 + M_t b^2 - 2 s_n b D u) > 0); equivalently the
  generalized momenta of the new rocking mode, the angular momentum about the new corner and the u
  momentum, are both conserved. e_N > 0: flight (bouncing), the old corner lifts with G_on Lambda_n.

* |u| < u*, both corners take impulse; the kinematics follow from the Newton conditions alone:

      phi_dot^+ = -e_N phi_dot^-,  y_dot^+ = -e_N y_dot^-,  u_dot^+ = u_dot^- - (1 + e_N) (C/m_tilde) phi_dot^-
      Lambda_o = (1 + e_N) V (-N_c) / (4 b^2),  Lambda_n = (1 + e_N) V N_o / (4 b^2).

  e_N = 0: full contact (the uplift LCP then decides at once whether the structure stays down or
  re-uplifts); e_N > 0: rocking back on the old corner with phi_dot^+ = -e_N phi_dot^-.

For m_c = 0, C/m_tilde = h and (1) says that the top mass keeps its horizontal velocity; in full contact
u_dot^+ = u_dot^- - h phi_dot^-. The total tangential impulse is P_T = D (u_dot^+ - u_dot^-) -
A_h (phi_dot^+ - phi_dot^-) (the x row).

The classical rule of the earlier literature (e.g. Acikgoz & DeJong 2012, Vassiliou et al. 2015) instead
conserves only the angular momentum about the impacting corner and keeps u_dot continuous; the structure
rocks on about the new corner with

      phi_dot^+ / phi_dot^- = (J0 + m_tilde u^2 - M_t b^2) / (J0 + m_tilde u^2 + M_t b^2 - 2 s_n b D u),   (3)

which violates (1): it needs a generalized impulse P_u = C (phi_dot^- - phi_dot^+) on the flexural
coordinate that no contact force provides (reported as `P_u`).
"""
from __future__ import annotations

from dataclasses import dataclass
from enum import Enum

import numpy as np

from ..modes import Mode, pivot_sign
from ..validation import check_choice, check_real


class Outcome(str, Enum):
    """Post-impact state."""

    FULL_CONTACT = "full_contact"   #: both corners stay on the ground
    ROCKING_NEW = "rocking_new"     #: immediate rocking on the impacting corner
    ROCKING_OLD = "rocking_old"     #: rocking back on the old pivot (impacting corner bounces)
    FLIGHT = "flight"               #: bouncing: both corners leave the ground


@dataclass(frozen=True)
class ImpactResult:
    """Closed-form post-impact state."""

    outcome: Outcome
    mode: Mode                #: contact mode that follows the impact
    v_plus: np.ndarray        #: post-impact [u_dot, x_dot, y_dot, phi_dot]
    P_N: np.ndarray           #: normal impulses [left, right] [N s]
    P_T: float                #: total tangential impulse (sum over the corners) [N s]
    ratio: float              #: phi_dot^+ / phi_dot^-
    P_u: float = 0.0          #: generalized impulse on u the rule needs (0 for a consistent impact) [kg m/s]


_PIVOTS = {Mode.LEFT: Mode.LEFT, Mode.RIGHT: Mode.RIGHT, "left": Mode.LEFT, "right": Mode.RIGHT}


def _other(mode: Mode) -> Mode:
    return Mode.RIGHT if mode == Mode.LEFT else Mode.LEFT


def _inputs(model, u, u_dot, phi_dot_minus, pivot):
    pivot = check_choice("pivot", pivot, _PIVOTS)
    u = check_real("u", u)
    u_dot = check_real("u_dot", u_dot)
    phi_dot_minus = check_real("phi_dot_minus", phi_dot_minus)
    s_o = pivot_sign(pivot)
    s_n = -s_o
    if not s_n * phi_dot_minus < 0.0:
        rng = "(-inf, 0)" if pivot == Mode.LEFT else "(0, inf)"
        raise ValueError(f"phi_dot_minus = {phi_dot_minus:g} does not close the gap of the other corner when "
                         f"rocking on the {pivot.name.lower()} corner; allowed range {rng}")
    return pivot, u, u_dot, phi_dot_minus, s_o, s_n


def impact_delassus(model, u: float) -> np.ndarray:
    """Delassus matrix G (left, right) of the two corners at phi = 0 with sticking, closed form [1/kg]."""
    a = model.J_eff + model.m_tilde * u * u
    Mb2 = model.M_t * model.b ** 2
    two_bDu = 2.0 * model.b * model.D * u
    delta = model.M_t * a - (model.D * u) ** 2
    return np.array([[a + two_bDu + Mb2, a - Mb2], [a - Mb2, a - two_bDu + Mb2]]) / delta


def _pre_impact_velocity(model, u_dot, phi_dot_minus, s_o):
    # rocking on pivot s_o at phi = 0: x_dot = 0, y_dot = -s_o b phi_dot
    return np.array([u_dot, 0.0, -s_o * model.b * phi_dot_minus, phi_dot_minus])


def _x_impulse(model, dv):
    # x row of M(phi = 0): [D, M_t, 0, -A_h]; x_dot does not jump
    return model.D * dv[0] - model.A_h * dv[3]


def analytical_impact(model, u: float, u_dot: float, phi_dot_minus: float, pivot, e_N: float | None = None
                      ) -> ImpactResult:
    """Closed-form post-impact state of `FlexibleOscillator` ``model`` (formulas in the module docstring).

    u [m], u_dot [m/s]: flexural state at impact; phi_dot_minus [rad/s]: pre-impact rotation rate (< 0 on
    the left pivot, > 0 on the right one); pivot: the pre-impact pivot (Mode.LEFT / Mode.RIGHT or 'left' /
    'right'); e_N: coefficient of restitution (model.e_N when None). At |u| = u* exactly the two solutions
    coincide; the single-impulse branch is returned (as the LCP's enumeration does)."""
    pivot, u, u_dot, phi_dot_minus, s_o, s_n = _inputs(model, u, u_dot, phi_dot_minus, pivot)
    e = model.e_N if e_N is None else check_real("e_N", e_N, lo=0.0, hi=1.0)
    b, mt, D, Mt = model.b, model.m_tilde, model.D, model.M_t
    a = model.J_eff + mt * u * u
    N_c = a - Mt * b * b
    V = 2.0 * b * abs(phi_dot_minus)
    v_minus = _pre_impact_velocity(model, u_dot, phi_dot_minus, s_o)
    P_N = np.zeros(2)
    i_o, i_n = (0, 1) if pivot == Mode.LEFT else (1, 0)
    if N_c >= 0.0:
        N_n = a - 2.0 * s_n * b * D * u + Mt * b * b
        ratio = 1.0 - (1.0 + e) * 2.0 * (Mt * b * b - s_n * b * D * u) / N_n
        w_plus = ratio * phi_dot_minus
        y_plus = e * V - s_n * b * w_plus
        P_N[i_n] = (1.0 + e) * V * (Mt * a - (D * u) ** 2) / N_n
        if e == 0.0:
            outcome, mode = Outcome.ROCKING_NEW, _other(pivot)
        else:
            outcome, mode = Outcome.FLIGHT, Mode.FLIGHT
    else:
        N_o = a - 2.0 * s_o * b * D * u + Mt * b * b
        ratio = -e
        w_plus = -e * phi_dot_minus
        y_plus = -e * v_minus[2]
        P_N[i_o] = (1.0 + e) * V * (-N_c) / (4.0 * b * b)
        P_N[i_n] = (1.0 + e) * V * N_o / (4.0 * b * b)
        if e == 0.0:
            outcome, mode = Outcome.FULL_CONTACT, Mode.FULL
        else:
            outcome, mode = Outcome.ROCKING_OLD, pivot
    u_dot_plus = u_dot + model.C / mt * (w_plus - phi_dot_minus)
    v_plus = np.array([u_dot_plus, 0.0, y_plus, w_plus])
    return ImpactResult(outcome, mode, v_plus, P_N, _x_impulse(model, v_plus - v_minus), ratio, 0.0)


def classical_impact(model, u: float, u_dot: float, phi_dot_minus: float, pivot) -> ImpactResult:
    """Classical rule: angular momentum about the impacting corner conserved, u_dot continuous, rocking on
    about the new corner (Eq. (3) of the module docstring). Same conventions as `analytical_impact`.

    P_N is the impulse at the new corner from the y row, P_T the x-row impulse, and P_u the generalized
    impulse on u the rule implicitly applies (non-zero whenever phi_dot jumps)."""
    pivot, u, u_dot, phi_dot_minus, s_o, s_n = _inputs(model, u, u_dot, phi_dot_minus, pivot)
    b, mt, D, Mt = model.b, model.m_tilde, model.D, model.M_t
    a0 = model.J0 + mt * u * u
    ratio = (a0 - Mt * b * b) / (a0 + Mt * b * b - 2.0 * s_n * b * D * u)
    w_plus = ratio * phi_dot_minus
    v_minus = _pre_impact_velocity(model, u_dot, phi_dot_minus, s_o)
    v_plus = np.array([u_dot, 0.0, -s_n * b * w_plus, w_plus])
    dv = v_plus - v_minus
    P_N = np.zeros(2)
    P_N[0 if pivot == Mode.RIGHT else 1] = Mt * dv[2] + D * u * dv[3]
    P_u = mt * dv[0] - model.C * dv[3]
    return ImpactResult(Outcome.ROCKING_NEW, _other(pivot), v_plus, P_N, _x_impulse(model, dv), ratio, P_u)


def classify_post_impact(model, q: np.ndarray, v_plus: np.ndarray, pivot, v_ref: float,
                         rtol: float = 1e-9) -> Outcome:
    """Outcome of a post-impact velocity (e.g. from the impact LCP) at phi = 0.

    A corner counts as closed when its normal velocity is at most rtol * v_ref (v_ref: a velocity scale,
    e.g. the impact speed 2 b |phi_dot^-|); pivot is the pre-impact pivot."""
    pivot = check_choice("pivot", pivot, _PIVOTS)
    W_N, _ = model.contact_jacobians(q)
    gamma = W_N.T @ np.asarray(v_plus, dtype=float)
    closed = np.abs(gamma) <= rtol * v_ref
    i_o = 0 if pivot == Mode.LEFT else 1
    if closed.all():
        return Outcome.FULL_CONTACT
    if closed[i_o]:
        return Outcome.ROCKING_OLD
    if closed[1 - i_o]:
        return Outcome.ROCKING_NEW
    return Outcome.FLIGHT
