"""One-step nonsmooth problems at the corners: the impact LCP and the uplift (acceleration) LCP.

Both have the same structure. Unknown contact percussions (impulses or forces) P_N, P_T on the candidate
contacts act on the velocity-like unknown

    v = v_free + M^-1 (W_N P_N + W_T P_T)

with, for every candidate contact i,

    0 <= w_N,i = W_N,i . v + b_N,i   _|_   P_N,i >= 0          (unilateral normal law)
    w_T,i = W_T,i . v + b_T,i = 0      if P_N,i > 0             (sticking: no sliding under load)

- impact (velocity level, Newton's law): v = post-impact velocity, b_N = e_N * (pre-impact normal velocity),
  b_T = 0;
- uplift (acceleration level): v = acceleration, v_free = M^-1 f, b = the drift terms (dW/dt)^T v.

The sticking row applies only on contacts that carry a normal percussion: a bilateral tangential row on a
lifting contact would glue it to the ground. That makes the problem an LCP in the normal percussions
whose matrix depends on the active set, so it is solved exactly by enumerating the active sets of the (at
most two) candidate contacts and keeping the one that violates the conditions least (round-off only). Tangential rows of two contacts can be parallel (the rigid block at phi = 0);
the reduced system is then solved in the least-squares sense: the velocities and normal percussions stay
unique, only the split of the tangential percussion is not (the minimum-norm split is returned).
"""
from __future__ import annotations

from dataclasses import dataclass
from itertools import combinations

import numpy as np


@dataclass
class ContactSolution:
    """Result of a contact LCP."""

    v: np.ndarray            #: solution velocity (impact) or acceleration (uplift)
    P_N: np.ndarray          #: normal percussion per contact (0 off the active set), shape (2,)
    P_T: np.ndarray          #: tangential percussion per contact, shape (2,)
    active: tuple            #: contacts carrying a normal percussion (sticking)
    w_N: np.ndarray          #: w_N = W_N^T v + b_N, shape (2,) (nan for non-candidates)
    exact: bool = True       #: False when no active set met every condition (least-violating returned)


def _active_sets(candidates, forced):
    cand = sorted(set(candidates) | set(forced))
    free = [i for i in cand if i not in forced]
    for k in range(len(free) + 1):
        for extra in combinations(free, k):
            yield tuple(sorted(set(forced) | set(extra)))


def solve_contact_lcp(Minv: np.ndarray, W_N: np.ndarray, W_T: np.ndarray, v_free: np.ndarray,
                      b_N: np.ndarray, b_T: np.ndarray, candidates, forced=(),
                      rtol: float = 1e-9) -> ContactSolution:
    """Solve the sticking-contact LCP described in the module docstring.

    Parameters
    ----------
    Minv : (n, n) inverse (effective) mass matrix.
    W_N, W_T : (n, 2) normal / tangential Jacobians of the two corners.
    v_free : (n,) velocity (or acceleration) without contact percussions.
    b_N, b_T : (2,) offsets of the normal / tangential conditions.
    candidates : contacts (0 left, 1 right) taking part in the problem.
    forced : candidates whose normal condition is an equality w_N = 0 whatever the sign of P_N (used by the
        Zeno rule to close a contact).
    rtol : relative violation below which the returned solution is flagged ``exact``.
    """
    v_free = np.asarray(v_free, dtype=float)
    cand = sorted(set(candidates) | set(forced))
    w_free = W_N.T @ v_free + b_N
    scale_v = max(np.max(np.abs(w_free[cand])) if cand else 0.0,
                  np.max(np.abs(W_T.T @ v_free + b_T)[cand]) if cand else 0.0, 1e-300)
    best = None
    for S in _active_sets(cand, forced):
        if S:
            cols = list(S)
            G = np.concatenate([W_N[:, cols], W_T[:, cols]], axis=1)
            MG = Minv @ G
            D = G.T @ MG
            rhs = -(G.T @ v_free + np.concatenate([b_N[cols], b_T[cols]]))
            P, *_ = np.linalg.lstsq(D, rhs, rcond=1e-12)
            v = v_free + MG @ P
            k = len(cols)
            P_N = np.zeros(2)
            P_T = np.zeros(2)
            P_N[cols] = P[:k]
            P_T[cols] = P[k:]
        else:
            v = v_free.copy()
            P_N = np.zeros(2)
            P_T = np.zeros(2)
        w_N = W_N.T @ v + b_N
        # violations, relative to the problem's scales
        scale_P = max(np.max(np.abs(P_N)), 1e-300)
        viol = 0.0
        for i in cand:
            if i in S:
                if i not in forced:
                    viol = max(viol, -P_N[i] / scale_P)
                viol = max(viol, abs(w_N[i]) / scale_v)
            else:
                viol = max(viol, -w_N[i] / scale_v)
        if S:
            w_T = W_T.T @ v + b_T
            viol = max(viol, np.max(np.abs(w_T[list(S)])) / scale_v)
        w_out = np.full(2, np.nan)
        w_out[cand] = w_N[cand]
        sol = ContactSolution(v=v, P_N=P_N, P_T=P_T, active=S, w_N=w_out, exact=viol <= rtol)
        if viol == 0.0:
            return sol
        if best is None or viol < best[0]:
            best = (viol, sol)
    # the exact solution violates the conditions by round-off only; near-degenerate sets (a force that is
    # zero to 1e-9) are told apart by their violations rather than by a tolerance
    return best[1]
