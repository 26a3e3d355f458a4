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


_SETS_CACHE: dict = {}


def _active_sets(candidates, forced) -> list:
    """The active sets to try: ``forced`` plus every subset of the other candidates, smallest first."""
    key = (tuple(candidates), tuple(forced))
    sets = _SETS_CACHE.get(key)
    if sets is None:
        cand = sorted(set(candidates) | set(forced))
        free = [i for i in cand if i not in forced]
        sets = []
        for k in range(len(free) + 1):
            for extra in combinations(free, k):
                sets.append(tuple(sorted(set(forced) | set(extra))))
        _SETS_CACHE[key] = sets
    return sets


def _solve_small(A, b):
    """Solve the small dense system A x = b (lists of floats) by Gaussian elimination with partial
    pivoting; None if A is singular to round-off. (Plain loops: called a few times per LCP.)"""
    n = len(b)
    M = [list(row) + [bi] for row, bi in zip(A, b)]
    big = 0.0
    for row in A:
        for a in row:
            if abs(a) > big:
                big = abs(a)
    big = big or 1.0
    for c in range(n):
        p, best = c, abs(M[c][c])
        for r in range(c + 1, n):
            if abs(M[r][c]) > best:
                p, best = r, abs(M[r][c])
        if best <= 1e-13 * big:
            return None
        if p != c:
            M[c], M[p] = M[p], M[c]
        piv = M[c]
        for r in range(c + 1, n):
            f = M[r][c] / piv[c]
            if f != 0.0:
                row = M[r]
                for j in range(c, n + 1):
                    row[j] -= f * piv[j]
    x = [0.0] * n
    for c in range(n - 1, -1, -1):
        row = M[c]
        acc = 0
        for j in range(c + 1, n):
            acc += row[j] * x[j]
        x[c] = (row[n] - acc) / row[c]
    return x


def solve_contact_lcp(Minv: np.ndarray, W_N: np.ndarray, W_T: np.ndarray, v_free: np.ndarray,
                      b_N: np.ndarray, b_T: np.ndarray, candidates, forced=(),
                      rtol: float = 1e-9, hint=None) -> ContactSolution:
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
    hint : an active set to try first (a time-stepper's last one); taken if it violates the conditions
        by less than 1e-12 (round-off), which spares the enumeration in the common persistent case.

    The whole problem lives in the 4 x 4 Delassus matrix D = G^T M^-1 G of G = [W_N, W_T]: every active
    set's system is a sub-block of it, solved on floats (at most 4 unknowns).
    """
    v_free = np.asarray(v_free, dtype=float)
    cand = sorted(set(candidates) | set(forced))
    G = np.concatenate([W_N, W_T], axis=1)          # columns N0, N1, T0, T1
    MG = Minv @ G
    GT = G.T
    D = (GT @ MG).tolist()
    w0 = (GT @ v_free + np.concatenate([b_N, b_T])).tolist()   # [w_N0, w_N1, w_T0, w_T1] without percussions
    scale_v = 1e-300
    for i in cand:
        scale_v = max(scale_v, abs(w0[i]), abs(w0[2 + i]))
    # parallel tangential directions (the rigid block at phi = 0): the two sticking rows are one condition
    parallel = abs(D[2][2] * D[3][3] - D[2][3] * D[3][2]) <= 1e-12 * max(D[2][2] * D[3][3], 1e-300)
    best = None
    sets = _active_sets(cand, forced)
    if hint is not None:
        hint = tuple(sorted(hint))
        if hint in sets:
            sets = [hint] + [S for S in sets if S != hint]
    for n_tried, S in enumerate(sets):
        P = [0.0, 0.0, 0.0, 0.0]
        if S:
            rows = list(S) + [2 + i for i in S]
            merged = len(S) == 2 and parallel
            if merged:
                rows = rows[:3]
            A = [[D[r][c] for c in rows] for r in rows]
            rhs = [-w0[r] for r in rows]
            if merged:
                # one tangential unknown acting through both contacts, split evenly (minimum-norm split)
                for r in range(3):
                    A[r][2] = 0.5 * (D[rows[r]][2] + D[rows[r]][3])
            x = _solve_small(A, rhs)
            if x is None:
                sub = np.array(A)
                x = np.linalg.lstsq(sub, np.array(rhs), rcond=1e-12)[0].tolist()
            for r, xr in zip(rows, x):
                P[r] = xr
            if merged:
                P[2] = P[3] = 0.5 * x[2]
        nz = [c for c in range(4) if P[c] != 0.0]
        w = []
        for r in range(4):
            Dr, acc = D[r], 0
            for c in nz:
                acc += Dr[c] * P[c]
            w.append(w0[r] + acc)
        # violations, relative to the problem's scales
        scale_P = max(abs(P[0]), abs(P[1]), 1e-300)
        viol = 0.0
        for i in cand:
            if i in S:
                if i not in forced:
                    viol = max(viol, -P[i] / scale_P)
                viol = max(viol, abs(w[i]) / scale_v, abs(w[2 + i]) / scale_v)
            else:
                viol = max(viol, -w[i] / scale_v)
        if best is None or viol < best[0]:
            best = (viol, S, P, w)
            if viol == 0.0 or (n_tried == 0 and hint is not None and viol <= 1e-12):
                break
    viol, S, P, w = best
    v = v_free + MG @ np.array(P)
    w_out = np.full(2, np.nan)
    for i in cand:
        w_out[i] = w[i]
    # the exact solution violates the conditions by round-off only; near-degenerate sets (a force that is
    # zero to 1e-9) are told apart by their violations rather than by a tolerance
    return ContactSolution(v=v, P_N=np.array(P[:2]), P_T=np.array(P[2:]), active=S, w_N=w_out,
                           exact=viol <= rtol)
