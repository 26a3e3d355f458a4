"""Sliding phases of any rocking model, and the friction forces of its sticking phases (Coulomb friction).

A sliding mode (`rocking_model.modes.SLIDING`) has the closed corners of a sticking mode ("its stick mode")
and a base that moves along the ground with them. Horizontal translation is a symmetry of the contact
geometry, so the sliding mode's coordinates are the stick mode's reduced coordinates r plus one more, the
horizontal offset x_s of the base (``model.slide_index`` of q):

    q = q_stick(r) + x_s e_x,      v = v_stick(r, r_dot) + x_s_dot e_x,

and the slip velocity of every closed corner is x_s_dot (the stick embedding keeps the corners at rest).
The closed corners carry the normal forces lambda_N and the friction -sigma mu lambda_N (sigma = sign of the
slip velocity). The unknown of each closed corner is the friction magnitude tau = mu lambda_N >= 0 (the
force direction W_N / mu - sigma W_T), so that mu = inf is the limit of the finite-mu motion: a corner that
slides on the ground with lambda_N -> 0 and a finite tau (`rocking_model.lcp.solve_friction_lcp`).

    M a = f + sum_i (W_N,i / mu - sigma W_T,i) tau_i,   W_N,i . a + a_N,i = 0   (i closed)

gives a and tau, and r_ddot follows from a = J r_ddot + J_dot r_dot (J = [J_stick, e_x] spans every
velocity that keeps the closed corners on the ground). Generic numpy code: only finite-mu scenes and the
mu -> inf lift-offs pay for it.

`force_totals`: the total normal and tangential contact forces of a sticking mode, from the residual
M a - f of its motion (the rows of the base's vertical and horizontal translations carry only them).
"""
from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from .._ordered import lstsq, matmul, matvec, solve
from ..modes import SLIDING, stick_mode

if TYPE_CHECKING:
    from .base import RockingModel


def slide_dofs(model: "RockingModel", mode) -> tuple:
    """Indices in q of the reduced coordinates of sliding ``mode``: its stick mode's, then slide_index."""
    return tuple(model.mode_dofs(stick_mode(mode))) + (model.slide_index,)


def slide_embed(model: "RockingModel", mode, r, r_dot) -> tuple[np.ndarray, np.ndarray]:
    """Full (q, v) of the reduced state (r, x_s), (r_dot, x_s_dot) of sliding ``mode``."""
    q, v = model.embed(stick_mode(mode), np.asarray(r[:-1], dtype=float), np.asarray(r_dot[:-1], dtype=float))
    q, v = np.array(q, dtype=float), np.array(v, dtype=float)
    i = model.slide_index
    q[i] += float(r[-1])
    v[i] += float(r_dot[-1])
    return q, v


def slide_reduce(model: "RockingModel", mode, q, v) -> tuple[np.ndarray, np.ndarray]:
    """The reduced state of sliding ``mode`` read from a full state on its closed corners."""
    stick = stick_mode(mode)
    idx = list(model.mode_dofs(stick))
    r, rd = np.array(q, dtype=float)[idx], np.array(v, dtype=float)[idx]
    q0, v0 = model.embed(stick, r, rd)
    i = model.slide_index
    return np.append(r, float(q[i]) - float(q0[i])), np.append(rd, float(v[i]) - float(v0[i]))


def shift_of(model: "RockingModel", mode, q) -> float:
    """The horizontal offset of a full state on the closed corners of the sticking ``mode`` from the stick
    embedding (where the base has slid or landed off its rest position) [m]."""
    r, rd = model.reduce(mode, q, np.zeros_like(q))
    return float(q[model.slide_index]) - float(model.embed(mode, r, rd)[0][model.slide_index])


def slide_motion(model: "RockingModel", mode, q, v, ag: float, ag_v: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """(a, tau): the full acceleration of sliding ``mode`` at (q, v) and the friction magnitude
    tau = mu lambda_N of each closed corner (in the order of ``model.closed_of(mode)``); ag, ag_v [m/s2] the
    ground accelerations (ag_v positive upward: the normal forces, hence the friction, carry g + ag_v)."""
    stick, sigma = SLIDING[mode]
    closed = list(model.closed_of(stick))
    W_N, W_T = model.contact_jacobians(q)
    a_N = model.contact_drift(q, v)[0]
    Minv = model.inverse_mass_matrix(q)
    inv_mu = 0.0 if math.isinf(model.mu) else 1.0 / model.mu
    C = inv_mu * W_N[:, closed] - sigma * W_T[:, closed]
    # index-order sums, as the C's (rocking_model/_ordered.py)
    a_free = matvec(Minv, model.forces(q, v, ag, ag_v))
    MC = matmul(Minv, C)
    A = matmul(W_N[:, closed].T, MC)
    rhs = -(matvec(W_N[:, closed].T, a_free) + a_N[closed])
    try:
        tau = solve(A, rhs)
    except np.linalg.LinAlgError:
        tau = lstsq(A, rhs, rcond=1e-12)
    return a_free + matvec(MC, tau), tau


def slide_acceleration(model: "RockingModel", mode, r, r_dot, ag: float, ag_v: float = 0.0) -> np.ndarray:
    """r_ddot of sliding ``mode`` (see the module docstring); ag, ag_v [m/s2]."""
    q, v = slide_embed(model, mode, r, r_dot)
    a, _ = slide_motion(model, mode, q, v, ag, ag_v)
    J, jd = slide_jacobian(model, mode, r, r_dot)
    return lstsq(J, a - jd, rcond=None)


def slide_jacobian(model: "RockingModel", mode, r, r_dot) -> tuple[np.ndarray, np.ndarray]:
    """(J, J_dot r_dot) of sliding ``mode``: the stick mode's with the column e_x of the offset appended."""
    J, jd = model.mode_jacobian(stick_mode(mode), np.asarray(r[:-1], dtype=float),
                                np.asarray(r_dot[:-1], dtype=float))
    e = np.zeros((J.shape[0], 1))
    e[model.slide_index, 0] = 1.0
    return np.hstack([J, e]), jd


def slide_functions(model: "RockingModel", mode, ag):
    """(rhs, monitors) of sliding ``mode`` on lists of floats (`RockingModel.mode_functions`). Monitors:
    per contact the friction magnitude tau / force_scale of a closed corner (>= 0: it stays on the ground)
    or the stick mode's opening measure of an open one; then the slip velocity sigma x_s_dot / sqrt(g L)
    (it stops or reverses at zero); last the overturning margin. ``ag`` is a GroundMotion; its vertical
    component (``ag.vertical``, ag_v [m/s2] positive upward) enters too."""
    from .base import vertical_of

    stick, sigma = SLIDING[mode]
    closed = model.closed_of(stick)
    nc = model.n_contacts
    F, V = model.force_scale, math.sqrt(model.g * model.length_scale)
    a_of = (lambda t: ag.value) if ag.constant else ag
    av_of = vertical_of(ag)
    _, stick_monitors = model.mode_functions(stick, ag)
    k = len(slide_dofs(model, mode))

    def rhs(t, y):
        r, rd = np.array(y[:k]), np.array(y[k:])
        return list(y[k:]) + slide_acceleration(model, mode, r, rd, a_of(t), av_of(t)).tolist()

    def monitors(t, y):
        q, v = slide_embed(model, mode, y[:k], y[k:])
        _, tau = slide_motion(model, mode, q, v, a_of(t), av_of(t))
        # the open corners' opening measures of the stick mode do not depend on the offset
        base = stick_monitors(t, list(y[:k - 1]) + list(y[k:2 * k - 1]))
        out = [float(tau[closed.index(i)]) / F if i in closed else base[i] for i in range(nc)]
        return out + [sigma * float(y[2 * k - 1]) / V, base[-1]]
    return rhs, monitors


def force_totals(model: "RockingModel", mode, q, v, ag: float, ag_v: float = 0.0) -> tuple[float, float]:
    """(sum lambda_N, sum lambda_T) [N] of the closed corners of the sticking ``mode`` at (q, v); ag, ag_v
    [m/s2]."""
    r, rd = model.reduce(mode, q, v)
    J, jd = model.mode_jacobian(mode, r, rd)
    a = J @ model.reduced_acceleration(mode, r, rd, ag, ag_v) + jd if len(r) else jd
    resid = model.mass_matrix(q) @ a - model.forces(q, v, ag, ag_v)
    return float(resid[model.lift_index]), float(resid[model.slide_index])
