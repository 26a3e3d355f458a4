"""One-step nonsmooth problems at the contacts: the impact LCP and the uplift (acceleration) LCP.

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
whose matrix depends on the active set. It is solved for any number n of contacts on the 2n x 2n Delassus
matrix D = G^T M^-1 G of G = [W_N, W_T] (columns N_0..N_{n-1}, T_0..T_{n-1}); every active set's system is
a sub-block of it:

- up to ENUMERATE_MAX candidate contacts (the rocking models have two), by enumerating the active sets and
  keeping the one that violates the conditions least (round-off only when a solution exists): exact, and
  it finds the solution of a problem whose matrix is not a P-matrix (several or no solutions);
- beyond, by principal pivoting on the active set (Murty's least-index rule, `_pivot`): from the hint, then
  from all candidates closed, the contact with the lowest index that violates its condition changes side,
  until none does (at most MAX_PIVOTS changes, then a descent over single changes); finite for P-matrices,
  reported inexact when it finds no solution.

Either way a solution that still violates the conditions beyond ``rtol`` comes back with ``exact=False``,
which the integrators report. Tangential rows of two contacts can be parallel (the rigid block at phi = 0);
the reduced system is then solved in the least-squares sense: the velocities and normal percussions stay
unique, only the split of the tangential percussion is not (the minimum-norm split is returned).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from itertools import combinations, product

import numpy as np

from ._ordered import lstsq, matmul, matvec, solve

#: [contacts] largest number of candidate contacts solved by enumeration (2^n active sets)
ENUMERATE_MAX = 6
#: [pivots] most active-set changes of the pivoting method before it gives up (reported inexact)
MAX_PIVOTS = 200
#: [1] a pivot of the small dense solves below this times the largest entry counts as singular (round-off
#: of a Delassus matrix whose entries are O(1/m))
SINGULAR_RTOL = 1e-13
#: [1] two tangential rows whose 2 x 2 Delassus block has a determinant below this times the product of
#: its diagonal are parallel (the rigid block at phi = 0)
PARALLEL_RTOL = 1e-12


@dataclass
class ContactSolution:
    """Result of a contact LCP over n contacts."""

    v: np.ndarray            #: solution velocity (impact) or acceleration (uplift)
    P_N: np.ndarray          #: normal percussion per contact (0 off the active set), shape (n,)
    P_T: np.ndarray          #: tangential percussion per contact, shape (n,)
    active: tuple            #: contacts carrying a normal percussion (sticking)
    w_N: np.ndarray          #: w_N = W_N^T v + b_N, shape (n,) (nan for non-candidates)
    exact: bool = True       #: False when no active set met every condition (least-violating returned)
    violation: float = 0.0   #: [1] largest violation of the conditions, relative to the problem's scales
    states: tuple = ()       #: per-contact states of a frictional solution (`FrictionSolution`); () : stuck

    #: Painleve's paradox (`FrictionSolution`): never in the sticking problem
    painleve = False


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
        if best <= SINGULAR_RTOL * big:
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


class _Problem:
    """One contact LCP on floats: the Delassus matrix D (2n x 2n), the free residuals w0 and the scales;
    `trial(S)` solves active set S and measures how much it violates the conditions."""

    def __init__(self, D, w0, n, cand, forced):
        self.D, self.w0, self.n, self.cand, self.forced = D, w0, n, cand, forced
        # trial(S) by S: the pivoting and its descent come back to the same sets many times (on 7 and 8
        # contacts some 25 trials per distinct set), each a least-squares solve when the set is singular
        self._trials: dict = {}
        scale_v = 1e-300
        for i in cand:
            scale_v = max(scale_v, abs(w0[i]), abs(w0[n + i]))
        self.scale_v = scale_v

    def parallel(self, i, j) -> bool:
        """Whether the tangential rows of contacts i and j are parallel (one sticking condition)."""
        D, n = self.D, self.n
        a, b = n + i, n + j
        return abs(D[a][a] * D[b][b] - D[a][b] * D[b][a]) <= PARALLEL_RTOL * max(D[a][a] * D[b][b], 1e-300)

    def trial(self, S):
        """(violation, S, P, w) of active set S (a pure function of S: computed once per problem; the lists are
        not to be changed by the caller)."""
        res = self._trials.get(S)
        if res is None:
            res = self._trials[S] = self._trial(S)
        return res

    def _trial(self, S):
        D, w0, n = self.D, self.w0, self.n
        m = 2 * n
        P = [0.0] * m
        if S:
            rows = list(S) + [n + i for i in S]
            merged = len(S) == 2 and self.parallel(S[0], S[1])
            if merged:
                rows = rows[:3]
            A = [[D[r][c] for c in rows] for r in rows]
            rhs = [-w0[r] for r in rows]
            if merged:
                # one tangential unknown acting through both contacts, split evenly (minimum-norm split)
                t0, t1 = n + S[0], n + S[1]
                for r in range(3):
                    A[r][2] = 0.5 * (D[rows[r]][t0] + D[rows[r]][t1])
            x = _solve_small(A, rhs)
            if x is None:
                x = lstsq(A, rhs, rcond=1e-12).tolist()
            for r, xr in zip(rows, x):
                P[r] = xr
            if merged:
                P[n + S[0]] = P[n + S[1]] = 0.5 * x[2]
        nz = [c for c in range(m) if P[c] != 0.0]
        w = []
        for r in range(m):
            Dr, acc = D[r], 0
            for c in nz:
                acc += Dr[c] * P[c]
            w.append(w0[r] + acc)
        # violations, relative to the problem's scales
        scale_P = 1e-300
        for i in range(n):
            scale_P = max(scale_P, abs(P[i]))
        scale_v, forced = self.scale_v, self.forced
        viol = 0.0
        for i in self.cand:
            if i in S:
                if i not in forced:
                    viol = max(viol, -P[i] / scale_P)
                viol = max(viol, abs(w[i]) / scale_v, abs(w[n + i]) / scale_v)
            else:
                viol = max(viol, -w[i] / scale_v)
        return viol, S, P, w

    def violators(self, S, P, w, rtol) -> list:
        """Candidates whose condition S violates beyond rtol: a pulling contact in S, a sinking one outside."""
        n, scale_v = self.n, self.scale_v
        scale_P = max([abs(P[i]) for i in range(n)] + [1e-300])
        return [i for i in self.cand if i not in self.forced and
                ((i in S and -P[i] / scale_P > rtol) or (i not in S and -w[i] / scale_v > rtol))]


def _enumerate(prob: _Problem, sets, hint_first: bool, hint_tol: float):
    best = None
    for n_tried, S in enumerate(sets):
        res = prob.trial(S)
        if best is None or res[0] < best[0]:
            best = res
            if res[0] == 0.0 or (n_tried == 0 and hint_first and res[0] <= hint_tol):
                break
    return best


def _pivot(prob: _Problem, start, rtol: float):
    """Principal pivoting on the active set, for more candidates than enumeration can afford.

    Murty's least-index rule: the violating contact of lowest index changes side until no contact violates
    its condition beyond rtol -- from ``start`` (the hint), then from all candidates closed. The matrix of
    this problem changes with the active set, so the rule can cycle; the pivoting is then capped at
    MAX_PIVOTS and followed by a descent over single changes of the least-violating set met. On random
    problems of 3 to 7 contacts that have a solution, this finds one in 96 % of the cases (tests/
    test_contact_lcp.py); the others come back inexact and are reported."""
    best = None
    for first in (tuple(start), tuple(prob.cand)):
        S = tuple(sorted(set(first) | set(prob.forced)))
        for _ in range(MAX_PIVOTS):
            res = prob.trial(S)
            if best is None or res[0] < best[0]:
                best = res
            bad = prob.violators(S, res[2], res[3], rtol)
            if not bad:
                return res
            i = bad[0]
            S = tuple(sorted(set(S) - {i})) if i in S else tuple(sorted(set(S) | {i}))
    S, improved = best[1], True
    while improved:
        improved = False
        for i in prob.cand:
            if i in prob.forced:
                continue
            res = prob.trial(tuple(sorted(set(S) ^ {i})))
            if res[0] < best[0]:
                best, S, improved = res, res[1], True
                if res[0] <= rtol:
                    return res
    return best


def solve_contact_lcp(Minv: np.ndarray, W_N: np.ndarray, W_T: np.ndarray, v_free: np.ndarray,
                      b_N: np.ndarray, b_T: np.ndarray, candidates, forced=(),
                      rtol: float = 1e-9, hint=None, hint_tol: float = 1e-12) -> ContactSolution:
    """Solve the sticking-contact LCP described in the module docstring.

    Parameters
    ----------
    Minv : (m, m) inverse (effective) mass matrix.
    W_N, W_T : (m, n) normal / tangential Jacobians of the n contacts.
    v_free : (m,) velocity (or acceleration) without contact percussions.
    b_N, b_T : (n,) offsets of the normal / tangential conditions.
    candidates : contacts (indices in 0..n-1) taking part in the problem.
    forced : candidates whose normal condition is an equality w_N = 0 whatever the sign of P_N (used by the
        Zeno rule to close a contact).
    rtol : [1] relative violation below which the returned solution is flagged ``exact``
        (`ContactTolerances.lcp_exact`).
    hint : an active set to try first (a time-stepper's last one); taken if it violates the conditions
        by less than ``hint_tol`` (round-off, `ContactTolerances.lcp_hint`), which spares the enumeration in
        the common persistent case.
    """
    v_free = np.asarray(v_free, dtype=float)
    n = W_N.shape[1]
    cand = sorted(set(candidates) | set(forced))
    G = np.concatenate([W_N, W_T], axis=1)          # columns N_0..N_{n-1}, T_0..T_{n-1}
    MG = matmul(Minv, G)                            # (index-order sums, as the C's: rocking_model/_ordered.py)
    GT = G.T
    D = matmul(GT, MG).tolist()
    w0 = (matvec(GT, v_free) + np.concatenate([b_N, b_T])).tolist()   # residuals without percussions
    prob = _Problem(D, w0, n, cand, tuple(forced))
    if hint is not None:
        hint = tuple(sorted(hint))
    if len(cand) - len(set(forced)) <= ENUMERATE_MAX:
        sets = _active_sets(cand, forced)
        if hint is not None and hint in sets:
            sets = [hint] + [S for S in sets if S != hint]
        viol, S, P, w = _enumerate(prob, sets, hint is not None, hint_tol)
    else:
        start = [i for i in (hint or ()) if i in cand]
        viol, S, P, w = _pivot(prob, start, rtol)
    v = v_free + matvec(MG, P)
    w_out = np.full(n, np.nan)
    for i in cand:
        w_out[i] = w[i]
    # the exact solution violates the conditions by round-off only; near-degenerate sets (a force that is
    # zero to 1e-9) are told apart by their violations rather than by a tolerance
    return ContactSolution(v=v, P_N=np.array(P[:n]), P_T=np.array(P[n:]), active=S, w_N=w_out,
                           exact=viol <= rtol, violation=viol)


# ---------------------------------------------------------------------------------------------------- friction
#: per-contact states of the frictional problem (the order in which they are tried)
OPEN, STICK, SLIDE_POS, SLIDE_NEG = 0, 1, 2, 3
#: the direction sigma of each sliding state (its tangential velocity's sign; friction acts against it)
SLIDE_SIGN = {SLIDE_POS: 1.0, SLIDE_NEG: -1.0}
#: [contacts] largest number of candidates whose 4^n state combinations are enumerated; beyond, a descent over
#: single-contact state changes from the hint (reported inexact when it finds no solution)
FRICTION_ENUMERATE_MAX = 4


@dataclass
class FrictionSolution(ContactSolution):
    """Result of a frictional contact LCP: `ContactSolution` plus the state of each contact (OPEN, STICK,
    SLIDE_POS: sliding with positive tangential velocity, friction against it; SLIDE_NEG), w_T, and (when
    asked for with ``count=True``) the number of state combinations that solve the problem exactly: 0 or
    more than 1 at the acceleration level is Painleve's paradox."""

    w_T: np.ndarray = None
    n_solutions: int = -1
    sliding: dict = None       #: the ``sliding`` argument: contacts that already slid, and their direction

    @property
    def painleve(self) -> bool:
        """Painleve's paradox: with a contact sliding, no or several motions solve the problem (counted)."""
        return self.n_solutions not in (-1, 1) and bool(self.sliding or any(s in SLIDE_SIGN for s in self.states))


def solve_friction_lcp(Minv: np.ndarray, W_N: np.ndarray, W_T: np.ndarray, v_free: np.ndarray,
                       b_N: np.ndarray, b_T: np.ndarray, candidates, mu: float, forced=(),
                       rtol: float = 1e-9, hint=None, sliding=None, count: bool = False) -> FrictionSolution:
    """The contact problem of `solve_contact_lcp` with Coulomb friction of coefficient ``mu`` (> 0, finite or
    inf) in place of sticking: for every candidate contact, with w = G^T v + b,

        0 <= w_N  _|_  P_N >= 0,
        stick:          w_T = 0,   |P_T| <= mu P_N
        slide forward:  w_T > 0,   P_T = -mu P_N
        slide back:     w_T < 0,   P_T = +mu P_N

    the planar Coulomb law, exact in 2D (the complementarity form of Glocker & Pfeiffer: w_T = w_T+ - w_T-,
    0 <= w_T+ _|_ mu P_N + P_T >= 0, 0 <= w_T- _|_ mu P_N - P_T >= 0). At the velocity level with
    b_N = e_N U_N- it is Newton's impact law with Coulomb's law for the tangential impulse; at the acceleration
    level it gives the forces and the states that follow (stick, slide, lift-off).

    A sliding contact's unknown is the friction magnitude tau = mu P_N >= 0 (P_T = -sigma tau), so that
    ``mu = inf`` is the limit of the finite-mu problem, not a special case: sticking where it has a solution
    (the sticking LCP's), and where it has none (a pivot whose sticking needs tension) a contact that slides
    on the ground with P_N -> 0 and a finite friction force tau, as every finite mu -> inf does.

    ``sliding``: {contact: sigma} for contacts that already slide with tangential velocity of sign sigma (the
    acceleration level of a sliding contact): their states are OPEN or the slide in that direction, with no
    condition on the sign of their w_T (a tangential acceleration: the sliding may slow down). ``forced`` candidates
    stay closed (normal equality, as in the Zeno rule). ``hint``: the state of each candidate to try first.

    Solved like the sticking problem: every combination of states of the (at most FRICTION_ENUMERATE_MAX)
    candidates is a small linear system on the Delassus matrix; the combination that violates the conditions
    least is returned (``exact`` when by round-off only). Where the problem has several solutions (Painleve's
    paradox at the acceleration level) the first exact combination in the order hint, then states (open,
    stick, slide forward, slide back) per contact in contact order, is taken; where it has none the least
    violating is returned, flagged inexact. ``count``: enumerate every combination and count the exact ones
    (``n_solutions``: distinct motions v, as the split of the tangential force between two contacts whose
    tangential rows are parallel is not unique)."""
    v_free = np.asarray(v_free, dtype=float)
    n = W_N.shape[1]
    cand = sorted(set(candidates) | set(forced))
    sliding = sliding or {}
    G = np.concatenate([W_N, W_T], axis=1)
    MG = matmul(Minv, G)                            # (index-order sums, as the C's: rocking_model/_ordered.py)
    D = matmul(G.T, MG)
    w0 = matvec(G.T, v_free) + np.concatenate([b_N, b_T])
    scale_v = max([abs(w0[i]) for i in cand] + [abs(w0[n + i]) for i in cand] + [1e-300])
    forced = set(forced)
    inv_mu = 0.0 if math.isinf(mu) else 1.0 / mu

    def trial(states):
        cols, rows = [], []
        for i, s in zip(cand, states):
            if s == OPEN:
                continue
            rows.append(i)                                          # w_N,i = 0
            if s == STICK:
                cols += [D[:, i], D[:, n + i]]
                rows.append(n + i)                                  # w_T,i = 0
            else:
                cols.append(inv_mu * D[:, i] - SLIDE_SIGN[s] * D[:, n + i])   # unknown tau = mu P_N
        P = np.zeros(2 * n)
        if cols:
            A = np.stack(cols, axis=1)[rows]
            rhs = -w0[rows]
            try:
                x = solve(A, rhs)
            except np.linalg.LinAlgError:
                x = lstsq(A, rhs, rcond=1e-12)
            k = 0
            for i, s in zip(cand, states):
                if s == STICK:
                    P[i], P[n + i] = x[k], x[k + 1]
                    k += 2
                elif s != OPEN:
                    P[i], P[n + i] = inv_mu * x[k], -SLIDE_SIGN[s] * x[k]
                    k += 1
        w = w0 + matvec(D, P)
        scale_P = max(float(np.max(np.abs(P))), 1e-300)
        viol = 0.0
        for i, s in zip(cand, states):
            if s == OPEN:
                viol = max(viol, -w[i] / scale_v)
                continue
            viol = max(viol, abs(w[i]) / scale_v)
            if s == STICK:
                if i not in forced:
                    viol = max(viol, -P[i] / scale_P)
                cone = abs(P[n + i]) - mu * max(P[i], 0.0) if inv_mu else 0.0
                viol = max(viol, abs(w[n + i]) / scale_v, cone / scale_P)
            else:
                sigma = SLIDE_SIGN[s]
                if i not in forced:
                    viol = max(viol, sigma * P[n + i] / scale_P)    # tau >= 0
                if i not in sliding:
                    # (a contact that already slides may decelerate: its w_T, an acceleration, has any sign)
                    viol = max(viol, -sigma * w[n + i] / scale_v)
        return viol, states, P, w

    def options(i):
        if i in sliding:
            slide = SLIDE_POS if sliding[i] > 0 else SLIDE_NEG
            return (slide,) if i in forced else (OPEN, slide)
        return (STICK, SLIDE_POS, SLIDE_NEG) if i in forced else (OPEN, STICK, SLIDE_POS, SLIDE_NEG)

    k = len(cand)
    opts = [options(i) for i in cand]
    first = tuple(hint) if hint is not None and len(hint) == k else None
    best, n_exact, motions = None, 0, []
    if k <= FRICTION_ENUMERATE_MAX:
        combos = list(product(*opts))
        if first is not None and first in combos:
            combos.remove(first)
            combos.insert(0, first)
        for states in combos:
            res = trial(states)
            if count and res[0] <= rtol:
                v = v_free + matvec(MG, res[2])
                scale = max(float(np.max(np.abs(v))), float(np.max(np.abs(v_free))), 1e-300)
                if not any(np.max(np.abs(v - u)) <= rtol * scale for u in motions):
                    motions.append(v)
                n_exact = len(motions)
                if best is None or best[0] > rtol:
                    best = res                # the first exact one in the order of preference
                continue
            if best is None or (res[0] < best[0] and best[0] > rtol):
                best = res                    # an exact one is kept: the first in the order of preference
                if not count and res[0] <= rtol:
                    break
    else:
        states = first or tuple(o[0] for o in opts)
        best = trial(states)
        improved = True
        while improved and best[0] > rtol:
            improved = False
            for j in range(k):
                for s in opts[j]:
                    if s == best[1][j]:
                        continue
                    res = trial(best[1][:j] + (s,) + best[1][j + 1:])
                    if res[0] < best[0]:
                        best, improved = res, True
        n_exact = int(best[0] <= rtol)
    viol, states, P, w = best
    v = v_free + matvec(MG, P)
    w_N = np.full(n, np.nan)
    w_T = np.full(n, np.nan)
    full = [OPEN] * n
    for i, s in zip(cand, states):
        w_N[i], w_T[i], full[i] = w[i], w[n + i], s
    active = tuple(i for i, s in zip(cand, states) if s != OPEN)
    return FrictionSolution(v=v, P_N=P[:n].copy(), P_T=P[n:].copy(), active=active, w_N=w_N,
                            exact=viol <= rtol, violation=viol, states=tuple(full), w_T=w_T,
                            n_solutions=n_exact if count else -1, sliding=dict(sliding))
