"""The contact LCPs of a model at a given state, shared by both integrators (any number of contacts).

- `impact`: velocity-level LCP with Newton's impact law (coefficient model.e_N) on the contacts at the ground;
- `uplift`: acceleration-level LCP on the contacts that touch the ground with zero normal velocity; its active
  set is the contact mode that follows (`next_closed`: full contact, rocking on either corner, flight);
- `project_to_ground`, `closed_candidates`, `mode_forces`: the geometry and forces around them.
"""
from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from .lcp import ContactSolution, solve_contact_lcp
from .tolerances import DEFAULT_TOLERANCES

if TYPE_CHECKING:                      # the models import this module (no import cycle at run time)
    from .models.base import RockingModel


def inverse_mass(model: "RockingModel", q: np.ndarray) -> np.ndarray:
    """M(q)^-1 of ``model`` (its closed form where it has one)."""
    return model.inverse_mass_matrix(q)


def impact(model: "RockingModel", q: np.ndarray, v_minus: np.ndarray, candidates, forced=(),
           e_N: float | None = None, e_T: float | None = None) -> ContactSolution:
    """Post-impact velocities from the impact LCP: Newton's law in the normal direction (coefficient e_N) and,
    on the contacts that take impulse, the tangential law of the model (`RockingModel.e_T`): the paper's
    sticking (e_T = 0, U_T+ = 0) or the tangential restitution U_T+ = -e_T U_T- of the energetically
    consistent law (e_T = e_N, Glocker 2013).

    ``forced`` contacts are closed plastically (w_N = 0, e_N = e_T = 0 on them): the Zeno rule."""
    e = model.e_N if e_N is None else e_N
    et = model.e_T if e_T is None else e_T
    W_N, W_T = model.contact_jacobians(q)
    U_minus = W_N.T @ v_minus
    b_N = e * np.minimum(U_minus, 0.0)
    for i in forced:
        b_N[i] = 0.0
    if et:
        # one coefficient per contact in both directions (Glocker's standard impact): e on the closing
        # contacts, 0 on the forced ones; a contact that separates takes no part in the impact
        b_T = np.where(U_minus < 0.0, et * (W_T.T @ v_minus), 0.0)
        for i in forced:
            b_T[i] = 0.0
        candidates = [i for i in candidates if i in forced or U_minus[i] <= 0.0]
    else:
        b_T = np.zeros(model.n_contacts)
    return solve_contact_lcp(inverse_mass(model, q), W_N, W_T, v_minus, b_N, b_T,
                             candidates, forced, rtol=DEFAULT_TOLERANCES.lcp_exact)


def uplift(model: "RockingModel", q: np.ndarray, v: np.ndarray, ag: float, candidates,
           forced=()) -> ContactSolution:
    """Acceleration-level LCP: which of ``candidates`` stay closed (active) and their contact forces."""
    W_N, W_T = model.contact_jacobians(q)
    a_N, a_T = model.contact_drift(q, v)
    Minv = inverse_mass(model, q)
    acc_free = Minv @ model.forces(q, v, ag)
    return solve_contact_lcp(Minv, W_N, W_T, acc_free, a_N, a_T, candidates, forced,
                             rtol=DEFAULT_TOLERANCES.lcp_exact)


def project_to_ground(model: "RockingModel", q: np.ndarray, corners) -> np.ndarray:
    """q moved onto g_N = 0 at ``corners`` (one Newton step of min |dq|_M subject to g_N(q + dq) = 0, as
    Siconos' MoreauJeanDirectProjectionOSI): undoes the drift of a closed corner off (or into) the ground."""
    corners = sorted(corners)
    g = model.gaps(q)[corners]
    W_N = model.contact_jacobians(q)[0][:, corners]
    MW = inverse_mass(model, q) @ W_N
    A = W_N.T @ MW
    if len(corners) == 1:
        mu = -g / A[0, 0]
    elif len(corners) > 2:
        mu = np.linalg.lstsq(A, -g, rcond=1e-12)[0]
    else:
        det = A[0, 0] * A[1, 1] - A[0, 1] * A[1, 0]
        if abs(det) > 1e-12 * abs(A[0, 0] * A[1, 1]):
            mu = np.array([A[1, 1] * -g[0] - A[0, 1] * -g[1], A[0, 0] * -g[1] - A[1, 0] * -g[0]]) / det
        else:
            mu = np.linalg.lstsq(A, -g, rcond=1e-12)[0]
    return q + MW @ mu


def closed_candidates(model: "RockingModel", q: np.ndarray, v: np.ndarray, gap_tol: float,
                      v_tol: float) -> list[int]:
    """Contacts at the ground (g_N <= gap_tol [m]) with zero normal velocity (|U_N| <= v_tol [m/s])."""
    g = model.gaps(q)
    W_N, _ = model.contact_jacobians(q)
    U = W_N.T @ v
    return [i for i in range(model.n_contacts) if g[i] <= gap_tol and abs(U[i]) <= v_tol]


def next_closed(model: "RockingModel", q: np.ndarray, v: np.ndarray, ag: float, gap_tol: float,
                v_tol: float) -> tuple[tuple, ContactSolution | None]:
    """(closed contacts, uplift solution) that follow a consistent state (q, v): the active set of the
    uplift LCP on the contacts at the ground at rest (`closed_candidates`); ((), None) when there is none."""
    cand = closed_candidates(model, q, v, gap_tol, v_tol)
    if not cand:
        return (), None
    sol = uplift(model, q, v, ag, cand)
    return sol.active, sol


def mode_forces(model: "RockingModel", mode, q: np.ndarray, v: np.ndarray, ag: float) -> np.ndarray:
    """Normal contact forces [N] of the closed contacts of ``mode`` (bilateral), shape (n_contacts,)."""
    closed = model.closed_of(mode)
    if not closed:
        return np.zeros(model.n_contacts)
    return uplift(model, q, v, ag, closed, forced=closed).P_N
