"""The contact LCPs of a model at a given state, shared by both integrators (any number of contacts).

- `impact`: velocity-level LCP with Newton's impact law (coefficient model.e_N) on the contacts at the ground;
- `uplift`: acceleration-level LCP on the contacts that touch the ground with zero normal velocity; its active
  set and stick / slide states are the contact mode that follows (`next_mode`: full contact, rocking on
  either corner, flight, sliding);
- `solve_with_friction`: the one place the friction law (mu) picks the LCP: sticking, its mu -> inf limit
  where sticking has no solution, or Coulomb;
- `project_to_ground`, `closed_candidates`, `mode_forces`: the geometry and forces around them;
- `sliding_delassus`, `painleve_sticks`: Painleve's configuration of a sliding contact, and the contacts an
  impact made stick in it (counted as Painleve resolutions by the event-driven scheme).
"""
from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from ._ordered import lstsq, matmul, matvec
from .lcp import OPEN, SLIDE_NEG, SLIDE_POS, SLIDE_SIGN, STICK, ContactSolution, solve_contact_lcp, solve_friction_lcp
from .tolerances import DEFAULT_TOLERANCES, ContactTolerances

if TYPE_CHECKING:                      # the models import this module (no import cycle at run time)
    from .models.base import RockingModel


def inverse_mass(model: "RockingModel", q: np.ndarray) -> np.ndarray:
    """M(q)^-1 of ``model`` (its closed form where it has one)."""
    return model.inverse_mass_matrix(q)


def impact(model: "RockingModel", q: np.ndarray, v_minus: np.ndarray, candidates, forced=(),
           e_N: float | None = None, e_T: float | None = None, prefer=None,
           tolerances: ContactTolerances = DEFAULT_TOLERANCES) -> ContactSolution:
    """Post-impact velocities from the impact LCP: Newton's law in the normal direction (coefficient e_N) and,
    on the contacts that take impulse, the tangential law of the model (`RockingModel.e_T`): the paper's
    sticking (e_T = 0, U_T+ = 0) or the tangential restitution U_T+ = -e_T U_T- of the energetically
    consistent law (e_T = e_N, Glocker 2013); with a finite ``model.mu`` Coulomb's law bounds the tangential
    impulse (|P_T| <= mu P_N, sliding at the bound). With mu = inf the sticking problem is solved, and where it
    has no solution its mu -> inf limit (`solve_with_friction`).

    ``forced`` contacts are closed plastically (w_N = 0, e_N = e_T = 0 on them): the Zeno rule. ``prefer``:
    the state (`rocking_model.lcp.STICK`, ...) tried first for every candidate where several solve it.
    ``tolerances``: the scheme's (`solve_with_friction`)."""
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
    return solve_with_friction(model, inverse_mass(model, q), W_N, W_T, v_minus, b_N, b_T, candidates, forced,
                               prefer=prefer, tolerances=tolerances)


def uplift(model: "RockingModel", q: np.ndarray, v: np.ndarray, ag: float, candidates,
           forced=(), slip_tol: float | None = None, count: bool = False, prefer=None,
           ag_v: float = 0.0, tolerances: ContactTolerances = DEFAULT_TOLERANCES) -> ContactSolution:
    """Acceleration-level LCP: which of ``candidates`` stay closed (active), whether they stick or slide
    (Coulomb, a finite ``model.mu``, or where sticking has no solution its mu -> inf limit), and their
    contact forces. Candidates whose tangential velocity exceeds ``slip_tol`` [m/s] already slide: they
    can only open or keep sliding that way (None: none slides). ``count``: count the solutions (Painleve,
    `FrictionSolution`); ``prefer``: the state tried first for every candidate. ag, ag_v [m/s2]: the ground
    accelerations (ag_v positive upward; where g + ag_v < 0 the free motion leaves the ground and the LCP
    returns flight). ``tolerances``: the scheme's (`solve_with_friction`)."""
    W_N, W_T = model.contact_jacobians(q)
    a_N, a_T = model.contact_drift(q, v)
    Minv = inverse_mass(model, q)
    acc_free = Minv @ model.forces(q, v, ag, ag_v)
    sliding = None
    if slip_tol is not None:
        U_T = W_T.T @ v
        sliding = {i: (1 if U_T[i] > 0.0 else -1) for i in set(candidates) | set(forced)
                   if abs(U_T[i]) > slip_tol}
    return solve_with_friction(model, Minv, W_N, W_T, acc_free, a_N, a_T, candidates, forced, sliding, count,
                               prefer=prefer, tolerances=tolerances)


def solve_with_friction(model: "RockingModel", Minv, W_N, W_T, v_free, b_N, b_T, candidates, forced=(),
                        sliding=None, count: bool = False, hint=None, prefer=None,
                        tolerances: ContactTolerances = DEFAULT_TOLERANCES) -> ContactSolution:
    """The contact LCP under the model's friction law: with mu = inf and nothing sliding, the sticking LCP
    (`solve_contact_lcp`, the paper's), and where it has no exact solution the frictional problem in its
    mu -> inf limit (a contact may then slide with a vanishing normal force) if that one has; with a finite
    mu (or contacts that already slide) the frictional LCP (`solve_friction_lcp`, which counts its solutions
    when ``count``). ``hint``: the contacts that were closed (a time-stepper's last step), tried first;
    ``prefer``: with friction, the state tried first for every candidate (a stuck contact that reached its
    friction cone: the slide). ``tolerances``: the scheme's (`Simulator(tolerances=...)`, both schemes): its
    ``lcp_exact`` tells an exact solution (and, with friction, which one is taken and how many are counted:
    Painleve), its ``lcp_hint`` when the ``hint`` is taken without enumerating."""
    rtol = tolerances.lcp_exact
    mu = model.mu
    if math.isinf(mu) and not sliding:
        sol = solve_contact_lcp(Minv, W_N, W_T, v_free, b_N, b_T, candidates, forced, rtol=rtol,
                                hint=hint, hint_tol=tolerances.lcp_hint)
        if sol.exact:
            return sol
        limit = solve_friction_lcp(Minv, W_N, W_T, v_free, b_N, b_T, candidates, mu, forced, rtol=rtol)
        return limit if limit.violation < sol.violation else sol
    states = None
    if prefer is not None or hint is not None:
        # the state tried first per candidate: ``prefer``, or stuck where the hint had it closed; a contact
        # that already slides keeps its direction
        sliding = sliding or {}
        states = []
        for i in sorted(set(candidates) | set(forced)):
            s = prefer if prefer is not None else STICK if i in hint else OPEN
            if s != OPEN and i in sliding:
                s = SLIDE_POS if sliding[i] > 0 else SLIDE_NEG
            states.append(s)
    return solve_friction_lcp(Minv, W_N, W_T, v_free, b_N, b_T, candidates, mu, forced, rtol=rtol,
                              sliding=sliding, count=count, hint=states)


def project_to_ground(model: "RockingModel", q: np.ndarray, corners) -> np.ndarray:
    """q moved onto g_N = 0 at ``corners`` (one Newton step of min |dq|_M subject to g_N(q + dq) = 0, as
    Siconos' MoreauJeanDirectProjectionOSI): undoes the drift of a closed corner off (or into) the ground."""
    corners = sorted(corners)
    g = model.gaps(q)[corners]
    W_N = model.contact_jacobians(q)[0][:, corners]
    MW = matmul(inverse_mass(model, q), W_N)
    A = matmul(W_N.T, MW)
    if len(corners) == 1:
        mu = -g / A[0, 0]
    elif len(corners) > 2:
        mu = lstsq(A, -g, rcond=1e-12)
    else:
        det = A[0, 0] * A[1, 1] - A[0, 1] * A[1, 0]
        if abs(det) > 1e-12 * abs(A[0, 0] * A[1, 1]):
            mu = np.array([A[1, 1] * -g[0] - A[0, 1] * -g[1], A[0, 0] * -g[1] - A[1, 0] * -g[0]]) / det
        else:
            mu = lstsq(A, -g, rcond=1e-12)
    return q + matvec(MW, mu)


def closed_candidates(model: "RockingModel", q: np.ndarray, v: np.ndarray, gap_tol: float,
                      v_tol: float) -> list[int]:
    """Contacts at the ground (g_N <= gap_tol [m]) with zero normal velocity (|U_N| <= v_tol [m/s])."""
    g = model.gaps(q)
    W_N, _ = model.contact_jacobians(q)
    U = W_N.T @ v
    return [i for i in range(model.n_contacts) if g[i] <= gap_tol and abs(U[i]) <= v_tol]


def sliding_delassus(model: "RockingModel", q: np.ndarray, i: int, sigma: float) -> float:
    """a_sigma = W_N,i . M^-1 (W_N,i - sigma mu W_T,i) [1/kg]: the normal velocity (or acceleration) that a unit
    normal percussion produces at contact i while it slides with direction sigma (+1, -1) and the friction
    -sigma mu P_N. Painleve's configuration where a_sigma <= 0: sliding would need a pulling contact
    (P_N < 0), so the contact cannot keep sliding pressed on the ground (mu above the critical
    W_N,i M^-1 W_N,i / (sigma W_N,i M^-1 W_T,i)); with mu = inf, wherever sigma W_N,i M^-1 W_T,i > 0."""
    W_N, W_T = model.contact_jacobians(q)
    Minv = inverse_mass(model, q)
    a = float(W_N[:, i] @ Minv @ W_N[:, i])
    c = float(W_N[:, i] @ Minv @ W_T[:, i])
    if math.isinf(model.mu):
        return -math.inf if sigma * c > 0.0 else a if c == 0.0 else math.inf
    return a - sigma * model.mu * c


def painleve_sticks(model: "RockingModel", q: np.ndarray, v_minus: np.ndarray, v_plus: np.ndarray, candidates,
                    v_tol: float) -> list[int]:
    """The contacts of ``candidates`` that an impact (v_minus -> v_plus) made stick by Painleve's paradox rather
    than by their collision (the impact without collision of Genot & Brogliato 1999, reached through an impact
    event). Contact i counts when

    - it slid before (|U_T-| > v_tol [m/s]) and is closed and stuck after (U_N+ and |U_T+| <= v_tol);
    - it is in Painleve's configuration, a_sigma <= 0 (`sliding_delassus`, sigma = sign U_T-): it could not
      slide through the impact (that needs P_N < 0), so it had to stick;
    - its stick is made by the slip, not by the approach: with its Delassus block [[a, c], [c, d]]
      (a = W_N M^-1 W_N, c = W_N M^-1 W_T, d = W_T M^-1 W_T), the normal percussion of its stick
      P_N = (d (1 + e_N) |U_N-| + c U_T-) / (a d - c^2) is mostly the part that stopping the slip induces:
      c U_T- >= d (1 + e_N) |U_N-|. (A collision of a corner with little slip also sticks it in this
      configuration, as with mu = inf; that is an impact, not the paradox.)"""
    W_N, W_T = model.contact_jacobians(q)
    Minv = inverse_mass(model, q)
    U_N_minus, U_T_minus = W_N.T @ v_minus, W_T.T @ v_minus
    U_T_plus, U_N_plus = W_T.T @ v_plus, W_N.T @ v_plus
    out = []
    for i in candidates:
        if not (abs(U_T_minus[i]) > v_tol and abs(U_T_plus[i]) <= v_tol and U_N_plus[i] <= v_tol):
            continue
        if sliding_delassus(model, q, i, 1.0 if U_T_minus[i] > 0.0 else -1.0) > 0.0:
            continue
        c = float(W_N[:, i] @ Minv @ W_T[:, i])
        d = float(W_T[:, i] @ Minv @ W_T[:, i])
        if c * U_T_minus[i] >= d * (1.0 + model.e_N) * max(-U_N_minus[i], 0.0):
            out.append(i)
    return out


def next_mode(model: "RockingModel", q: np.ndarray, v: np.ndarray, ag: float, gap_tol: float,
              v_tol: float, prefer=None, ag_v: float = 0.0, tolerances: ContactTolerances = DEFAULT_TOLERANCES):
    """(mode, uplift solution) that follow a consistent state (q, v): the active set and the stick / slide
    states of the uplift LCP on the contacts at the ground at rest (`closed_candidates`); (FLIGHT-like mode
    of no closed contact, None) when there is none. ``v_tol`` [m/s] also tells a sliding contact. With
    friction the solutions are counted (Painleve: `FrictionSolution.n_solutions`); ``prefer``: see
    `solve_with_friction`. ag, ag_v [m/s2]: the ground accelerations (ag_v positive upward). ``tolerances``: the
    scheme's (`solve_with_friction`)."""
    cand = closed_candidates(model, q, v, gap_tol, v_tol)
    if not cand:
        return model.mode_of(()), None
    sol = uplift(model, q, v, ag, cand, slip_tol=v_tol, count=True, prefer=prefer, ag_v=ag_v, tolerances=tolerances)
    return model.mode_of(sol.active, solution_sigma(sol)), sol


def solution_sigma(sol: ContactSolution) -> int:
    """The direction of sliding of the closed contacts of a contact solution: +1, -1, or 0 (they stick).

    The corners of a rigid base that are closed together slide together; where one sticks they all do (a
    stuck corner and one at its friction cone, with no slip, is the same motion with another split of the
    tangential force between them, which the per-corner law does not fix)."""
    states = [s for s in sol.states if s != OPEN]   # (a sticking solution has none: it sticks)
    if states and all(s in SLIDE_SIGN for s in states):
        return int(SLIDE_SIGN[states[0]])
    return 0


def mode_forces(model: "RockingModel", mode, q: np.ndarray, v: np.ndarray, ag: float,
                ag_v: float = 0.0) -> np.ndarray:
    """Normal contact forces [N] of the closed contacts of the sticking ``mode`` held closed (bilateral, stuck),
    shape (n_contacts,); ag, ag_v [m/s2] the ground accelerations (ag_v positive upward).

    No tolerance to pass: every closed contact is forced, so the LCP has one active set and its forces do not
    depend on ``lcp_exact`` (which would only flag them exact, a flag not read here) nor on ``lcp_hint``."""
    closed = model.closed_of(mode)
    if not closed:
        return np.zeros(model.n_contacts)
    W_N, W_T = model.contact_jacobians(q)
    a_N, a_T = model.contact_drift(q, v)
    Minv = inverse_mass(model, q)
    return solve_contact_lcp(Minv, W_N, W_T, Minv @ model.forces(q, v, ag, ag_v), a_N, a_T, closed, closed,
                             rtol=DEFAULT_TOLERANCES.lcp_exact).P_N
