"""The C contact problems (rocking_model/engine/src/rk_lcp.c, rk_contact.c; issue 21 part B) pinned to the
Python reference (rocking_model/lcp.py, rocking_model/contact.py) on random problems.

What is asserted, and why so:
- the same active set / per-contact states, the same ``exact`` flag, the same number of solutions and
  Painleve flag; v, P_N, P_T, w_N, w_T within 1e-13 relative (scaled by the condition number of the Delassus
  matrix: the Python forms it with numpy's BLAS, the C with plain loops, DESIGN.md section 7.4);
- a different choice is accepted only where several active sets solve the problem to round-off (both
  violations below TIE, a problem that is not a P-matrix problem): which one wins the "least violation" ranking
  is then decided by the last bits of the Delassus matrix. The Python itself must accept the C's choice (it
  takes it as a hint and keeps it), and such ties must stay rare (TIE_SHARE);
- the random problems are well posed where a decision depends on a linear solve (m >= 2n: every principal
  block of the Delassus matrix is regular), except the pivoting and descent cases, built so that their
  systems stay small enough to be regular, and the parallel tangential rows of the merged sticking case.
"""
import math

import numpy as np
import pytest

from rocking_model import lcp

_engine = pytest.importorskip("rocking_model._engine")
if not hasattr(_engine, "contact_solve_lcp"):
    pytest.skip("the C contact problems are not built", allow_module_level=True)

#: [1] relative agreement of values on a well-conditioned problem (BLAS vs plain loops)
VALUE_RTOL = 1e-13
#: [1] a violation below this is round-off: two active sets that both reach it are a tie of exact solutions
TIE = 1e-12
#: [1] largest share of ties among the random problems (they need a degenerate, non-P-matrix problem)
TIE_SHARE = 0.1
#: [1] largest share of the frictional descent's problems whose path a tie of violations decides
DESCENT_SHARE = 0.15
#: [1] the Python's lcp_exact default
RTOL = 1e-9


def random_problem(rng, n, m, parallel=False):
    """(Minv, W_N, W_T, v_free, b_N, b_T) of a random contact problem over n contacts and m dofs."""
    Q, _ = np.linalg.qr(rng.normal(size=(m, m)))
    M = Q @ np.diag(rng.uniform(0.5, 2.0, size=m)) @ Q.T
    Minv = np.linalg.inv(M)
    W_N = rng.normal(size=(m, n))
    W_T = rng.normal(size=(m, n))
    if parallel and n >= 2:
        W_T[:, 1] = W_T[:, 0] * rng.choice([1.0, 2.0, -1.0])
    v = rng.normal(size=m)
    b_N = rng.normal(size=n) * (rng.random() < 0.5)
    b_T = rng.normal(size=n) * (rng.random() < 0.3)
    return Minv, W_N, W_T, v, b_N, b_T


def condition(Minv, W_N, W_T):
    G = np.concatenate([W_N, W_T], axis=1)
    D = G.T @ Minv @ G
    s = np.linalg.svd(D, compute_uv=False)
    return float(s[0] / s[-1]) if s[-1] > 0 else math.inf


def scales(py, Minv, W_N, W_T, v, b_N, b_T):
    """The scale of each compared quantity: velocities, percussions, residuals (a residual that is zero to
    round-off is compared with the problem's free residuals)."""
    G = np.concatenate([W_N, W_T], axis=1)
    w0 = G.T @ v + np.concatenate([b_N, b_T])
    big = lambda *xs: max(float(np.max(np.abs(np.nan_to_num(np.asarray(x, dtype=float))), initial=0.0))
                          for x in xs)
    s_P = big(py.P_N, py.P_T)
    s_w = big(w0, py.w_N, getattr(py, "w_T", None) if getattr(py, "w_T", None) is not None else w0)
    return {"v": big(py.v, v), "P_N": s_P, "P_T": s_P, "w_N": s_w, "w_T": s_w}


def assert_close(py, c, name, kappa, scale):
    a = np.asarray(py, dtype=float)
    b = np.asarray(c, dtype=float)
    assert a.shape == b.shape, name
    assert np.array_equal(np.isnan(a), np.isnan(b)), name
    a, b = np.nan_to_num(a), np.nan_to_num(b)
    scale = max(scale, 1e-300)
    tol = VALUE_RTOL * max(1.0, kappa / 100.0) * scale
    assert np.max(np.abs(a - b), initial=0.0) <= tol, (name, a, b)


def lists(*arrays):
    return [x.tolist() for x in arrays]


def check_sticking(rng, n, m, n_max_forced=None, parallel=False, narrow=False, all_candidates=False):
    """One random sticking problem; returns 1 for a tie, 0 for the same choice."""
    Minv, W_N, W_T, v, b_N, b_T = random_problem(rng, n, m, parallel)
    if all_candidates:
        cand = list(range(n))
    else:
        cand = sorted(int(i) for i in rng.choice(n, size=int(rng.integers(0, n + 1)), replace=False))
    forced = [i for i in cand if rng.random() < 0.25]
    if n_max_forced is not None:
        forced = forced[:n_max_forced]
    hint = None if rng.random() < 0.5 else [i for i in range(n) if rng.random() < 0.5]
    py = lcp.solve_contact_lcp(Minv, W_N, W_T, v, b_N, b_T, cand, forced, rtol=RTOL, hint=hint)
    c = _engine.contact_solve_lcp(*lists(Minv, W_N, W_T, v, b_N, b_T), cand, forced, RTOL, hint, 1e-12,
                                  narrow=narrow)
    assert c["states"] == () and c["n_solutions"] == -1 and not c["painleve"]
    if tuple(py.active) != c["active"]:
        # a tie of exact solutions: the Python keeps the C's set when it is given as a hint
        assert py.violation <= TIE and c["violation"] <= TIE, (py.active, c["active"], py.violation, c["violation"])
        again = lcp.solve_contact_lcp(Minv, W_N, W_T, v, b_N, b_T, cand, forced, rtol=RTOL, hint=c["active"],
                                      hint_tol=TIE)
        assert tuple(again.active) == c["active"]
        return 1
    assert py.exact == c["exact"]
    kappa = condition(Minv, W_N, W_T) if not parallel else 1e3
    sc = scales(py, Minv, W_N, W_T, v, b_N, b_T)
    for name in ("v", "P_N", "P_T", "w_N"):
        assert_close(getattr(py, name), c[name], name, kappa, sc[name])
    assert abs(py.violation - c["violation"]) <= 1e-12 * max(1.0, kappa / 100.0) * max(1.0, py.violation)
    return 0


@pytest.mark.parametrize("seed", range(4))
def test_sticking_enumeration(seed):
    """1 to 4 contacts, m >= 2n dofs: enumeration with forced sets and hints."""
    rng = np.random.default_rng(seed)
    ties = 0
    for _ in range(300):
        n = int(rng.integers(1, 5))
        ties += check_sticking(rng, n, int(rng.integers(2 * n, 9)))
    assert ties <= TIE_SHARE * 300


def test_sticking_parallel_tangential_rows():
    """Two contacts whose tangential rows are parallel (the rigid block at phi = 0): one tangential unknown,
    split evenly; the singular larger sets go through the least-squares solve."""
    rng = np.random.default_rng(10)
    ties = 0
    for _ in range(300):
        n = int(rng.integers(2, 5))
        ties += check_sticking(rng, n, int(rng.integers(2 * n, 9)), parallel=True)
    assert ties <= TIE_SHARE * 300


def test_sticking_narrow_equals_wide():
    """rk_solve_contact_lcp (RK_MAX_CONTACTS) is the wide solver's result."""
    rng = np.random.default_rng(11)
    for _ in range(100):
        n = int(rng.integers(1, 5))
        check_sticking(rng, n, int(rng.integers(2 * n, 9)), narrow=True)


@pytest.mark.parametrize("seed", range(3))
def test_sticking_pivoting(seed):
    """7 and 8 contacts on 8 dofs: more than ENUMERATE_MAX free candidates, the principal pivoting (Murty's
    rule, then the descent); many of its problems have several or no solutions (non-P-matrix)."""
    rng = np.random.default_rng(100 + seed)
    ties = 0
    for _ in range(150):
        n = int(rng.integers(7, 9))
        ties += check_sticking(rng, n, 8, n_max_forced=n - 7, all_candidates=True)
    assert ties <= TIE_SHARE * 150


def check_friction(rng, n, m, all_sliding=False, narrow=False):
    Minv, W_N, W_T, v, b_N, b_T = random_problem(rng, n, m)
    if all_sliding:
        cand = list(range(n))
    else:
        cand = sorted(int(i) for i in rng.choice(n, size=int(rng.integers(0, n + 1)), replace=False))
    forced = [i for i in cand if rng.random() < 0.2]
    mu = float(rng.choice([0.2, 0.7, 2.0, math.inf]))
    sliding = None
    if all_sliding:
        sliding = {i: int(rng.choice([-1, 1])) for i in cand[1:]}
    elif rng.random() < 0.4:
        sliding = {i: int(rng.choice([-1, 1])) for i in cand if rng.random() < 0.5}
    count = bool(rng.random() < 0.5)
    if rng.random() < 0.5:
        hint = None
    elif all_sliding:
        # a state each candidate may take (a stuck hint on a sliding contact starts the descent on a plateau
        # of violations equal to round-off, where the path depends on the last bit)
        hint = [int(rng.choice([0, 1 if s > 0 else 3]) if s else rng.integers(0, 4))
                for s in [(sliding or {}).get(i, 0) for i in cand]]
        hint = [h if not (sliding or {}).get(i) else (0 if h == 0 else 2 if sliding[i] > 0 else 3)
                for i, h in zip(cand, hint)]
    else:
        hint = [int(rng.integers(0, 4)) for _ in cand]
    py = lcp.solve_friction_lcp(Minv, W_N, W_T, v, b_N, b_T, cand, mu, forced, rtol=RTOL, hint=hint,
                                sliding=sliding, count=count)
    c = _engine.contact_solve_friction(*lists(Minv, W_N, W_T, v, b_N, b_T), cand, mu, forced, RTOL, hint, sliding,
                                       count, narrow=narrow)
    states = tuple(int(s) for s in py.states)
    if all_sliding and (states, py.n_solutions) != (c["states"], c["n_solutions"]):
        # the descent (more than FRICTION_ENUMERATE_MAX candidates) ranks states by their violation; where the
        # worst violation is a negative friction magnitude of the largest percussion it equals mu or 1 exactly
        # (in exact arithmetic) for many states, and the last bit picks the path (traced by hand: the same
        # trials, 0.2 against 0.19999999999999998). Counted with the ties; both ends are inexact or exact
        # by the engines' own measures
        assert c["exact"] == (c["violation"] <= RTOL)
        return 1
    assert c["n_solutions"] == py.n_solutions
    assert c["painleve"] == py.painleve
    if states != c["states"]:
        assert py.violation <= TIE and c["violation"] <= TIE, (states, c["states"], py.violation, c["violation"])
        again = lcp.solve_friction_lcp(Minv, W_N, W_T, v, b_N, b_T, cand, mu, forced, rtol=RTOL,
                                       hint=[c["states"][i] for i in cand], sliding=sliding)
        assert tuple(int(s) for s in again.states) == c["states"]
        return 1
    assert tuple(py.active) == c["active"]
    assert py.exact == c["exact"]
    kappa = condition(Minv, W_N, W_T)
    sc = scales(py, Minv, W_N, W_T, v, b_N, b_T)
    for name in ("v", "P_N", "P_T", "w_N", "w_T"):
        assert_close(getattr(py, name), c[name], name, kappa, sc[name])
    assert abs(py.violation - c["violation"]) <= 1e-12 * max(1.0, kappa / 100.0) * max(1.0, py.violation)
    return 0


@pytest.mark.parametrize("seed", range(4))
def test_friction_enumeration(seed):
    """1 to 4 candidates: the 4^n states in product order, mu finite and inf, sliding contacts, counting,
    hints, forced contacts."""
    rng = np.random.default_rng(200 + seed)
    ties = 0
    for _ in range(250):
        n = int(rng.integers(1, 5))
        ties += check_friction(rng, n, int(rng.integers(2 * n, 9)))
    assert ties <= TIE_SHARE * 250


def test_friction_narrow_equals_wide():
    rng = np.random.default_rng(210)
    for _ in range(100):
        n = int(rng.integers(1, 5))
        check_friction(rng, n, int(rng.integers(2 * n, 9)), narrow=True)


def test_friction_descent():
    """5 and 6 candidates (beyond FRICTION_ENUMERATE_MAX): the descent over single state changes. All but one
    already slide (one unknown each), so that every trial system stays regular on 8 dofs."""
    rng = np.random.default_rng(220)
    ties = 0
    for _ in range(200):
        ties += check_friction(rng, int(rng.integers(5, 7)), 8, all_sliding=True)
    assert ties <= DESCENT_SHARE * 200


def test_painleve_counted():
    """A sliding contact with two exact solutions is Painleve's paradox in both engines (and a problem with
    several solutions is met at all: the counting test above is not vacuous)."""
    rng = np.random.default_rng(230)
    found = 0
    for _ in range(400):
        n = int(rng.integers(1, 3))
        Minv, W_N, W_T, v, b_N, b_T = random_problem(rng, n, int(rng.integers(2 * n, 9)))
        cand = list(range(n))
        py = lcp.solve_friction_lcp(Minv, W_N, W_T, v, b_N, b_T, cand, 5.0, count=True,
                                    sliding={0: 1})
        c = _engine.contact_solve_friction(*lists(Minv, W_N, W_T, v, b_N, b_T), cand, 5.0, None, RTOL, None,
                                           {0: 1}, True)
        assert (py.n_solutions, py.painleve) == (c["n_solutions"], c["painleve"])
        found += py.painleve
    assert found > 0


def test_bad_problems_raise():
    rng = np.random.default_rng(240)
    Minv, W_N, W_T, v, b_N, b_T = random_problem(rng, 2, 4)
    with pytest.raises(ValueError, match="candidates and forced"):
        _engine.contact_solve_lcp(*lists(Minv, W_N, W_T, v, b_N, b_T), [0], [3])
    with pytest.raises(ValueError, match="mu = "):
        _engine.contact_solve_friction(*lists(Minv, W_N, W_T, v, b_N, b_T), [0], -1.0)
    Minv, W_N, W_T, v, b_N, b_T = random_problem(rng, 6, 8)
    with pytest.raises(ValueError, match="n_contacts = 6"):
        _engine.contact_solve_lcp(*lists(Minv, W_N, W_T, v, b_N, b_T), [0], narrow=True)
