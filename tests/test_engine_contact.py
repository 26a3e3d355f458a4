"""The C contact problems (rocking_model/engine/src/rk_lcp.c, rk_contact.c; issue 21 part B) pinned to the
Python reference (rocking_model/lcp.py, rocking_model/contact.py) on random problems.

What is asserted, and why so:
- the same active set / per-contact states, the same ``exact`` flag, the same number of solutions and
  Painleve flag; v, P_N, P_T, w_N, w_T within 1e-13 relative (scaled by the condition number of the Delassus
  matrix: the Python forms it with numpy's BLAS, the C with plain loops, DESIGN.md section 7.4);
- a different choice is accepted only where several active sets solve the problem to round-off (both
  violations below TIE, a problem that is not a P-matrix problem): which one wins the "least violation" ranking
  is then decided by the last bits of the Delassus matrix. The Python itself must accept the C's choice (it
  takes it as a hint and keeps it), and such ties must stay rare (TIE_SHARE). With parallel tangential rows
  (a singular Delassus matrix) a problem may have no exact solution and several sets of the same least
  violation: those count as ties too (seen under generic BLAS kernels, tests/roundoff.py:kernel_env);
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
        # a tie: both sets solve the problem to round-off, or (a singular problem without exact solution, the
        # parallel rows) both reach the same least violation to round-off. Which wins is decided by the last
        # bits of the Delassus matrix (CPU-dependent BLAS kernels); the Python keeps the C's set when it is
        # given as a hint with the C's violation as its tolerance
        same_least = abs(py.violation - c["violation"]) <= TIE * max(1.0, py.violation)
        assert (py.violation <= TIE and c["violation"] <= TIE) or (parallel and same_least), \
            (py.active, c["active"], py.violation, c["violation"])
        again = lcp.solve_contact_lcp(Minv, W_N, W_T, v, b_N, b_T, cand, forced, rtol=RTOL, hint=c["active"],
                                      hint_tol=max(TIE, c["violation"] * (1.0 + TIE)))
        assert tuple(again.active) == c["active"]
        assert abs(again.violation - c["violation"]) <= TIE * max(1.0, c["violation"])
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


@pytest.mark.parametrize("seed", range(2))
def test_sticking_pivoting(seed):
    """7 and 8 contacts on 8 dofs: more than ENUMERATE_MAX free candidates, the principal pivoting (Murty's
    rule, then the descent); many of its problems have several or no solutions (non-P-matrix)."""
    rng = np.random.default_rng(100 + seed)
    ties = 0
    for _ in range(100):
        n = int(rng.integers(7, 9))
        ties += check_sticking(rng, n, 8, n_max_forced=n - 7, all_candidates=True)
    assert ties <= TIE_SHARE * 100


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


# ---------------------------------------------------------------------------------------------- contact.py
from rocking_model import contact  # noqa: E402
from rocking_model.modes import CLOSED, mode_from_closed  # noqa: E402
from rocking_model.tolerances import DEFAULT_TOLERANCES  # noqa: E402


class ConstantModel:
    """The contact relation of a model with constant matrices (two contacts, the rocking models' modes): what
    contact.py reads of a RockingModel. Its C twin is the test model of py/py_contact.c, so that contact.py's
    port is pinned independently of the kernels (part A)."""

    n_contacts = 2

    def __init__(self, Minv, W_N, W_T, f, g, a_N, a_T, e_N, e_T, mu):
        self.Minv, self.W_N, self.W_T, self.f, self.g = Minv, W_N, W_T, f, g
        self.a_N, self.a_T, self.e_N, self.e_T, self.mu = a_N, a_T, e_N, e_T, mu

    def spec(self):
        return (self.Minv.tolist(), self.W_N.tolist(), self.W_T.tolist(), self.f.tolist(), self.g.tolist(),
                self.a_N.tolist(), self.a_T.tolist(), self.e_N, self.e_T, self.mu)

    def inverse_mass_matrix(self, q):
        return self.Minv

    def forces(self, q, v, ag, ag_v=0.0):
        return self.f

    def gaps(self, q):
        return self.g

    def contact_jacobians(self, q):
        return self.W_N, self.W_T

    def contact_drift(self, q, v):
        return self.a_N, self.a_T

    def mode_of(self, closed, sigma=0):
        return mode_from_closed(closed, sigma)

    def closed_of(self, mode):
        return CLOSED[mode]


def constant_model(rng, m=4, mu=None):
    Minv, W_N, W_T, _, _, _ = random_problem(rng, 2, m)
    e_N = float(rng.uniform(0.0, 1.0))
    e_T = e_N if rng.random() < 0.5 else 0.0
    if mu is None:
        mu = float(rng.choice([0.3, 1.0, math.inf]))
    g = rng.normal(size=2) * 1e-3 * (rng.random(2) < 0.5)
    return ConstantModel(Minv, W_N, W_T, rng.normal(size=m), g, rng.normal(size=2), rng.normal(size=2) * 0.1,
                         e_N, e_T, mu)


def parallel_rows(W_T, active):
    """Whether the tangential rows of the two contacts of ``active`` are parallel (the rigid block at phi = 0):
    then only the sum of their tangential percussions is unique (lcp.py's module docstring). The sticking
    problem splits it evenly in both engines; the frictional one with both contacts stuck takes numpy's LU
    solution of a singular system (an arbitrary split) where the C takes the minimum-norm one."""
    if W_T is None or len(active) != 2:
        return False
    a, b = W_T[:, active[0]], W_T[:, active[1]]
    return abs(abs(a @ b) - np.linalg.norm(a) * np.linalg.norm(b)) <= 1e-12 * np.linalg.norm(a) * np.linalg.norm(b)


def compare_solution(py, c, kappa=1e3, W_T=None):
    """1 for a tie of exact solutions, 0 for the same one (asserted to round-off)."""
    states = tuple(int(s) for s in py.states)
    if tuple(py.active) != c["active"] or states != c["states"]:
        assert py.violation <= TIE and c["violation"] <= TIE, (py.active, c["active"], states, c["states"])
        return 1
    assert py.exact == c["exact"]
    assert py.painleve == c["painleve"]
    assert getattr(py, "n_solutions", -1) == c["n_solutions"]
    s_P = max(float(np.max(np.abs(np.concatenate([py.P_N, py.P_T])))), 1e-300)
    s_v = max(float(np.max(np.abs(py.v))), 1.0)
    assert np.max(np.abs(py.v - c["v"])) <= VALUE_RTOL * kappa * s_v
    assert np.max(np.abs(py.P_N - c["P_N"])) <= VALUE_RTOL * kappa * s_P
    if parallel_rows(W_T, tuple(py.active)):
        assert abs(sum(py.P_T) - sum(c["P_T"])) <= VALUE_RTOL * kappa * s_P
    else:
        assert np.max(np.abs(py.P_T - c["P_T"])) <= VALUE_RTOL * kappa * s_P
    return 0


def subsets():
    return [(), (0,), (1,), (0, 1)]


def test_impact_on_constant_models():
    """contact.impact: Newton's law, both tangential laws (e_T = 0, e_T = e_N), mu finite and inf, the Zeno
    rule's forced contacts, e overrides, prefer."""
    rng = np.random.default_rng(300)
    ties = total = 0
    for _ in range(200):
        model = constant_model(rng)
        q = rng.normal(size=4)
        v = rng.normal(size=4)
        cand = list(subsets()[int(rng.integers(0, 4))])
        forced = [i for i in cand if rng.random() < 0.2]
        prefer = int(rng.choice([-1, 1, 2]))
        e = None if rng.random() < 0.7 else (float(rng.uniform(0, 1)), float(rng.uniform(0, 1)))
        py = contact.impact(model, q, v, cand, forced, e_N=None if e is None else e[0],
                            e_T=None if e is None else e[1], prefer=None if prefer < 0 else prefer)
        c = _engine.contact_model_call("impact", model.spec(), q.tolist(), v.tolist(), cand, forced, prefer, e)
        ties += compare_solution(py, c)
        total += 1
    assert ties <= TIE_SHARE * total


def test_uplift_and_next_mode_on_constant_models():
    """contact.uplift (slip_tol, counting, prefer) and next_mode (closed candidates, the mode of the solution's
    active set and sliding direction)."""
    rng = np.random.default_rng(301)
    ties = 0
    for _ in range(200):
        model = constant_model(rng)
        q = rng.normal(size=4)
        v = rng.normal(size=4) * (rng.random() < 0.5)
        ag = float(rng.normal())
        cand = list(subsets()[int(rng.integers(1, 4))])
        forced = [i for i in cand if rng.random() < 0.2]
        slip = None if rng.random() < 0.4 else float(rng.choice([1e-9, 0.5]))
        count = bool(rng.random() < 0.5)
        prefer = int(rng.choice([-1, 1, 2, 3]))
        py = contact.uplift(model, q, v, ag, cand, forced, slip_tol=slip, count=count,
                            prefer=None if prefer < 0 else prefer)
        c = _engine.contact_model_call("uplift", model.spec(), q.tolist(), v.tolist(), ag, cand, forced, slip, count,
                                       prefer)
        ties += compare_solution(py, c)
        # next_mode: a state whose normal velocities are zero at some contacts
        W_N = model.W_N
        v0 = v - W_N @ np.linalg.lstsq(W_N.T @ W_N, W_N.T @ v, rcond=None)[0] * (rng.random() < 0.7)
        gap_tol, v_tol = 1e-3, 1e-9
        mode, sol = contact.next_mode(model, q, v0, ag, gap_tol, v_tol, prefer=None if prefer < 0 else prefer)
        c_mode, c_sol = _engine.contact_model_call("next_mode", model.spec(), q.tolist(), v0.tolist(), ag, gap_tol,
                                                   v_tol, prefer)
        assert (sol is None) == (c_sol is None)
        if sol is not None and compare_solution(sol, c_sol):
            ties += 1
            continue
        assert int(mode) == c_mode
    assert ties <= TIE_SHARE * 200


def test_solve_with_friction_on_constant_models():
    """contact.solve_with_friction: the sticking LCP with mu = inf (hint, user tolerances), its mu -> inf limit
    where sticking has no exact solution, and Coulomb's problem with sliding contacts, hints and prefer."""
    rng = np.random.default_rng(302)
    ties = 0
    from rocking_model.tolerances import ContactTolerances
    for _ in range(300):
        model = constant_model(rng, mu=float(rng.choice([0.5, math.inf, math.inf])))
        v = rng.normal(size=4)
        b_N = rng.normal(size=2)
        b_T = rng.normal(size=2) * (rng.random() < 0.5)
        cand = list(subsets()[int(rng.integers(0, 4))])
        forced = [i for i in cand if rng.random() < 0.2]
        sliding = None if rng.random() < 0.6 else {i: int(rng.choice([-1, 1])) for i in cand if rng.random() < 0.7}
        count = bool(rng.random() < 0.5)
        hint = None if rng.random() < 0.5 else [i for i in range(2) if rng.random() < 0.5]
        prefer = int(rng.choice([-1, -1, 1, 2]))
        lcp_exact = float(rng.choice([1e-9, 1e-6]))
        tol = ContactTolerances(lcp_exact=lcp_exact, lcp_hint=1e-12)
        py = contact.solve_with_friction(model, model.Minv, model.W_N, model.W_T, v, b_N, b_T, cand, forced,
                                         sliding, count, hint, None if prefer < 0 else prefer, tolerances=tol)
        c = _engine.contact_model_call("solve_with_friction", model.spec(), v.tolist(), b_N.tolist(), b_T.tolist(),
                                       cand, forced, sliding, count, hint, prefer, lcp_exact, 1e-12)
        ties += compare_solution(py, c)
    assert ties <= TIE_SHARE * 300


def test_geometry_and_painleve_on_constant_models():
    """project_to_ground (one and two corners, the 2 x 2 Cramer rule and its lstsq fallback),
    closed_candidates, sliding_delassus (mu finite and inf), painleve_sticks, solution_sigma, mode_forces."""
    rng = np.random.default_rng(303)
    for k in range(300):
        m = int(rng.choice([3, 4]))
        model = constant_model(rng, m=m)
        if m == 3:
            # as the rigid block on its base: parallel tangential rows (else the 4 x 4 system of the two closed
            # contacts on 3 dofs is singular and its solution round-off)
            model.W_T[:, 1] = model.W_T[:, 0]
        if k % 10 == 0:
            model.W_N[:, 1] = model.W_N[:, 0]          # a singular 2 x 2 block: the lstsq fallback
        q = rng.normal(size=m)
        spec = model.spec()
        for corners in ([0], [1], [0, 1]):
            py = contact.project_to_ground(model, q, corners)
            c = np.array(_engine.contact_model_call("project_to_ground", spec, q.tolist(), corners))
            assert np.max(np.abs(py - c)) <= 1e-13 * max(1.0, float(np.max(np.abs(py))))
        v = rng.normal(size=m) * (rng.random() < 0.5)
        for gap_tol, v_tol in ((1e-3, 1e-9), (1e-2, 10.0)):
            assert tuple(contact.closed_candidates(model, q, v, gap_tol, v_tol)) == \
                _engine.contact_model_call("closed_candidates", spec, q.tolist(), v.tolist(), gap_tol, v_tol)
        for i in (0, 1):
            for sigma in (1.0, -1.0):
                a = contact.sliding_delassus(model, q, i, sigma)
                ca = _engine.contact_model_call("sliding_delassus", spec, q.tolist(), i, sigma)
                assert a == ca or abs(a - ca) <= 1e-13 * max(1.0, abs(a))
        v_minus = rng.normal(size=m)
        v_plus = v_minus.copy()
        # v_plus with zero tangential (and normal) velocity at some contacts: a stick after the impact
        cols = [i for i in (0, 1) if rng.random() < 0.6]
        if cols:
            J = np.concatenate([model.W_N[:, cols], model.W_T[:, cols]], axis=1)
            v_plus = v_minus - J @ np.linalg.lstsq(J, v_minus, rcond=None)[0]
        for v_tol in (1e-9, 1e-6):
            py = contact.painleve_sticks(model, q, v_minus, v_plus, [0, 1], v_tol)
            c = _engine.contact_model_call("painleve_sticks", spec, q.tolist(), v_minus.tolist(), v_plus.tolist(),
                                           [0, 1], v_tol)
            assert tuple(py) == c
        # (the forces of the closed contacts: a solve on the Delassus block, relative error ~ its condition
        # number times round-off; the rows of the parallel tangential contacts count once)
        rows = np.concatenate([model.W_N, model.W_T[:, :1] if m == 3 else model.W_T], axis=1)
        sv = np.linalg.svd(rows.T @ model.Minv @ rows, compute_uv=False)
        kappa = sv[0] / sv[-1] if sv[-1] > 0 else math.inf
        for mode in range(10):
            py = contact.mode_forces(model, mode, q, v, 0.3)
            c = _engine.contact_model_call("mode_forces", spec, mode, q.tolist(), v.tolist(), 0.3)
            assert np.max(np.abs(py - c)) <= VALUE_RTOL * max(1.0, kappa / 100.0) * max(1.0, float(np.max(np.abs(py))))


def test_solution_sigma():
    from types import SimpleNamespace
    for states in [(), (0, 0), (2, 2), (3, 0), (2, 1), (1, 3), (0, 3), (2, 3)]:
        sol = SimpleNamespace(states=states)
        assert contact.solution_sigma(sol) == _engine.contact_model_call(
            "solution_sigma", constant_model(np.random.default_rng(0)).spec(), list(states))


def test_inexact_message():
    from types import SimpleNamespace
    from rocking_model.integrators.moreau_jean import inexact_message
    for active, viol, t in [((), 0.5, 0.0), ((0,), 1.234e-5, 1.5), ((0, 1), 3e-9, 12.000000000000002)]:
        sol = SimpleNamespace(active=active, violation=viol)
        assert inexact_message(sol, t, "impact LCP") == _engine.contact_inexact_message(active, viol, 2, t,
                                                                                         "impact LCP")


# ---------------------------------------------------------------------------------------------- the models
from rocking_model.models import MODELS  # noqa: E402
from rocking_model.modes import Mode  # noqa: E402


def kernel_available(kind):
    try:
        _engine.contact_model_call("closed_candidates", (kind, real_params(MODELS[kind]())),
                                   [0.0] * len(MODELS[kind]().dof_names), [0.0] * len(MODELS[kind]().dof_names),
                                   1e-9, 1e-9)
    except NotImplementedError:
        return False
    return True


def real_params(model):
    return [float(getattr(model, p.name)) for p in type(model).parameters()]


def random_model(rng, kind):
    e_N = float(rng.uniform(0.0, 1.0))
    law = int(rng.integers(0, 2))
    mu = float(rng.choice([0.2, 0.6, 1.5, math.inf]))
    if kind == "rigid":
        return MODELS[kind](b=float(rng.uniform(0.1, 0.5)), h=float(rng.uniform(0.6, 3.0)),
                            m=float(rng.uniform(1.0, 100.0)), e_N=e_N, impact_law=law, mu=mu)
    return MODELS[kind](e_N=e_N, impact_law=law, mu=mu)


def random_state(rng, model, mode):
    """(q, v) of a sticking mode: the corners of the mode on the ground, the others above it."""
    k = len(model.dofs_of(mode))
    r = rng.normal(size=k) * 0.01
    r_dot = rng.normal(size=k) * 0.2
    i = list(model.dofs_of(mode)).index(model.phi_index) if model.phi_index in model.dofs_of(mode) else None
    if i is not None:
        r[i] = float(rng.uniform(0.01, 0.4)) * (1.0 if mode == Mode.LEFT else -1.0)
    q, v = model.embed(mode, r, r_dot)
    return q, v


KINDS = ["rigid", "flexible"]


@pytest.mark.parametrize("kind", KINDS)
def test_contact_functions_on_the_models(kind):
    """contact.py on both C kernels (part A) at random states of the sticking modes: impact (rocking and
    full-contact impacts, both impact laws, mu finite and inf, forced contacts), uplift, next_mode,
    project_to_ground, closed_candidates, sliding_delassus, painleve_sticks, mode_forces."""
    if not kernel_available(kind):
        pytest.skip(f"the C kernel of {kind} is not built (part A)")
    rng = np.random.default_rng(400 + KINDS.index(kind))
    ties = total = 0
    for _ in range(80):
        model = random_model(rng, kind)
        spec = (kind, real_params(model))
        for mode in (Mode.FULL, Mode.LEFT, Mode.RIGHT):
            q, v = random_state(rng, model, mode)
            closed = list(model.closed_of(mode))
            ag = float(rng.normal()) * 3.0
            # impact: the pre-impact velocity is any velocity (a landing corner approaches)
            v_minus = rng.normal(size=len(q)) * 0.3
            forced = [i for i in closed if rng.random() < 0.2]
            prefer = int(rng.choice([-1, 1, 2]))
            py = contact.impact(model, q, v_minus, closed, forced, prefer=None if prefer < 0 else prefer)
            c = _engine.contact_model_call("impact", spec, q.tolist(), v_minus.tolist(), closed, forced, prefer, None)
            ties += compare_solution(py, c, W_T=model.contact_jacobians(q)[1])
            # uplift at the consistent state, with and without sliding contacts
            for slip in (None, 1e-9):
                count = slip is not None
                py = contact.uplift(model, q, v, ag, closed, slip_tol=slip, count=count)
                c = _engine.contact_model_call("uplift", spec, q.tolist(), v.tolist(), ag, closed, [], slip, count, -1)
                ties += compare_solution(py, c, W_T=model.contact_jacobians(q)[1])
                total += 1
            v_rest = v.copy()
            mode_py, sol = contact.next_mode(model, q, v_rest, ag, 1e-9, 1e-9)
            mode_c, c_sol = _engine.contact_model_call("next_mode", spec, q.tolist(), v_rest.tolist(), ag, 1e-9, 1e-9,
                                                       -1)
            assert (sol is None) == (c_sol is None)
            if sol is None or not compare_solution(sol, c_sol, W_T=model.contact_jacobians(q)[1]):
                assert int(mode_py) == mode_c
            q_off = q + rng.normal(size=len(q)) * 1e-6
            py = contact.project_to_ground(model, q_off, closed)
            c = np.array(_engine.contact_model_call("project_to_ground", spec, q_off.tolist(), closed))
            assert np.max(np.abs(py - c)) <= 1e-13 * max(1.0, float(np.max(np.abs(py))))
            assert tuple(contact.closed_candidates(model, q, v, 1e-9, 1e-9)) == \
                _engine.contact_model_call("closed_candidates", spec, q.tolist(), v.tolist(), 1e-9, 1e-9)
            for i in (0, 1):
                for sigma in (1.0, -1.0):
                    a = contact.sliding_delassus(model, q, i, sigma)
                    ca = _engine.contact_model_call("sliding_delassus", spec, q.tolist(), i, sigma)
                    assert a == ca or abs(a - ca) <= 1e-13 * max(1.0, abs(a))
            v_plus = np.array(_engine.contact_model_call("impact", spec, q.tolist(), v_minus.tolist(), closed, [], -1,
                                                         None)["v"])
            for v_tol in (1e-9, 1e-6):
                assert tuple(contact.painleve_sticks(model, q, v_minus, v_plus, closed, v_tol)) == \
                    _engine.contact_model_call("painleve_sticks", spec, q.tolist(), v_minus.tolist(), v_plus.tolist(),
                                               closed, v_tol)
            py = contact.mode_forces(model, mode, q, v, ag)
            c = _engine.contact_model_call("mode_forces", spec, int(mode), q.tolist(), v.tolist(), ag)
            assert np.max(np.abs(py - np.array(c))) <= 1e-12 * max(1.0, float(np.max(np.abs(py))))
            total += 1
    assert ties <= TIE_SHARE * total


@pytest.mark.parametrize("kind", KINDS)
def test_contact_functions_with_a_vertical_ground_acceleration(kind):
    """uplift, next_mode and mode_forces under a vertical ground acceleration ag_v (issue 23) on both C kernels:
    the same active sets, stick/slide states and forces as contact.py, also where g + ag_v < 0 (the ground falls
    faster than g: the uplift LCP returns flight, every corner open)."""
    rng = np.random.default_rng(900 + KINDS.index(kind))
    ties = total = 0
    for _ in range(60):
        model = random_model(rng, kind)
        spec = (kind, real_params(model))
        for mode in (Mode.FULL, Mode.LEFT, Mode.RIGHT):
            q, v = random_state(rng, model, mode)
            closed = list(model.closed_of(mode))
            ag = float(rng.normal()) * 3.0
            ag_v = float(rng.uniform(-3.0, 3.0)) * model.g
            for slip in (None, 1e-9):
                count = slip is not None
                py = contact.uplift(model, q, v, ag, closed, slip_tol=slip, count=count, ag_v=ag_v)
                c = _engine.contact_model_call("uplift", spec, q.tolist(), v.tolist(), ag, closed, [], slip, count, -1,
                                               ag_v)
                ties += compare_solution(py, c, W_T=model.contact_jacobians(q)[1])
                total += 1
                if kind == "rigid" and model.g + ag_v < -0.1 * model.g and mode == Mode.FULL:
                    # far from the threshold g + ag_v = 0 the block at rest on the ground leaves it (the flexible
                    # column's elastic force may still press one corner down)
                    assert c["active"] == () and tuple(py.active) == ()
            mode_py, sol = contact.next_mode(model, q, v, ag, 1e-9, 1e-9, ag_v=ag_v)
            mode_c, c_sol = _engine.contact_model_call("next_mode", spec, q.tolist(), v.tolist(), ag, 1e-9, 1e-9, -1,
                                                       ag_v)
            assert (sol is None) == (c_sol is None)
            if sol is None or not compare_solution(sol, c_sol, W_T=model.contact_jacobians(q)[1]):
                assert int(mode_py) == mode_c
            py = contact.mode_forces(model, mode, q, v, ag, ag_v)
            c = _engine.contact_model_call("mode_forces", spec, int(mode), q.tolist(), v.tolist(), ag, ag_v)
            assert np.max(np.abs(py - np.array(c))) <= 1e-12 * max(1.0, float(np.max(np.abs(py))))
            # ag_v = 0 is the call without a vertical component, bit for bit
            assert _engine.contact_model_call("mode_forces", spec, int(mode), q.tolist(), v.tolist(), ag, 0.0) == \
                _engine.contact_model_call("mode_forces", spec, int(mode), q.tolist(), v.tolist(), ag)
            total += 1
    assert ties <= TIE_SHARE * total


def test_sources_compile_without_warnings(tmp_path):
    """rk_lcp.c, rk_contact.c and py_contact.c compile cleanly with -Wall -Wextra -pedantic -Werror (the
    engine's flags otherwise), so that warnings do not accumulate."""
    import shutil
    import subprocess
    import sysconfig
    from pathlib import Path
    cc = shutil.which("cc") or shutil.which("gcc") or shutil.which("clang")
    if cc is None:
        pytest.skip("no C compiler")
    engine = Path(__file__).resolve().parent.parent / "rocking_model" / "engine"
    for source in (engine / "src" / "rk_lcp.c", engine / "src" / "rk_contact.c", engine / "py" / "py_contact.c"):
        cmd = [cc, "-std=c99", "-O2", "-ffp-contract=off", "-fno-fast-math", "-Wall", "-Wextra", "-pedantic",
               "-Werror", "-I" + sysconfig.get_paths()["include"], "-c", str(source), "-o", str(tmp_path / "x.o")]
        done = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
        assert done.returncode == 0, done.stderr


def test_lstsq_is_numpy_minimum_norm():
    """rk_lstsq_square: np.linalg.lstsq(A, b, rcond=1e-12)[0] on square systems of full and deficient rank
    (the fallback of the singular trials and of project_to_ground)."""
    rng = np.random.default_rng(500)
    for _ in range(300):
        n = int(rng.integers(1, 17))
        rank = int(rng.integers(0, n + 1)) if rng.random() < 0.7 else n
        A = rng.normal(size=(n, rank)) @ rng.normal(size=(rank, n)) if rank else np.zeros((n, n))
        if rng.random() < 0.2 and n >= 2:
            A[:, 1] = A[:, 0]                                  # identical columns (parallel contact rows)
        b = rng.normal(size=n)
        py = np.linalg.lstsq(A, b, rcond=1e-12)[0]
        c = np.array(_engine.contact_lstsq(A.tolist(), b.tolist()))
        s = np.linalg.svd(A, compute_uv=False)
        kept = s[s > 1e-12 * s[0]] if s[0] > 0 else s[:0]
        kappa = kept[0] / kept[-1] if len(kept) else 1.0
        assert np.max(np.abs(py - c)) <= 1e-13 * max(1.0, kappa) * max(1.0, float(np.max(np.abs(py))))


# ---------------------------------------------------------------------------------------------- visited states
class ContactSpy:
    """Wraps the contact.py functions the integrators call: each call also runs the C function on the same
    arguments and compares (the Python result is returned, so the run is the Python's)."""

    def __init__(self, kind, model):
        self.kind, self.model = kind, model
        self.spec = (kind, real_params(model))
        self.calls = {}
        self.ties = 0

    def note(self, name):
        self.calls[name] = self.calls.get(name, 0) + 1

    def compare(self, py, c, q):
        self.ties += compare_solution(py, c, W_T=self.model.contact_jacobians(q)[1])

    def impact(self, model, q, v_minus, candidates, forced=(), e_N=None, e_T=None, prefer=None,
               tolerances=DEFAULT_TOLERANCES):
        py = contact.impact(model, q, v_minus, candidates, forced, e_N, e_T, prefer, tolerances=tolerances)
        e = None if e_N is None and e_T is None else (model.e_N if e_N is None else e_N,
                                                      model.e_T if e_T is None else e_T)
        c = _engine.contact_model_call("impact", self.spec, list(map(float, q)), list(map(float, v_minus)),
                                       [int(i) for i in candidates], [int(i) for i in forced],
                                       -1 if prefer is None else int(prefer), e, tolerances.lcp_exact,
                                       tolerances.lcp_hint)
        self.compare(py, c, q)
        self.note("impact")
        return py

    def next_mode(self, model, q, v, ag, gap_tol, v_tol, prefer=None, ag_v=0.0, tolerances=DEFAULT_TOLERANCES):
        mode, sol = contact.next_mode(model, q, v, ag, gap_tol, v_tol, prefer, ag_v=ag_v, tolerances=tolerances)
        c_mode, c_sol = _engine.contact_model_call("next_mode", self.spec, list(map(float, q)), list(map(float, v)),
                                                   float(ag), gap_tol, v_tol, -1 if prefer is None else int(prefer),
                                                   float(ag_v), tolerances.lcp_exact, tolerances.lcp_hint)
        assert (sol is None) == (c_sol is None)
        if sol is None or not compare_solution(sol, c_sol, W_T=model.contact_jacobians(q)[1]):
            assert int(mode) == c_mode
        self.note("next_mode")
        return mode, sol

    def painleve_sticks(self, model, q, v_minus, v_plus, candidates, v_tol):
        py = contact.painleve_sticks(model, q, v_minus, v_plus, candidates, v_tol)
        c = _engine.contact_model_call("painleve_sticks", self.spec, list(map(float, q)), list(map(float, v_minus)),
                                       list(map(float, v_plus)), [int(i) for i in candidates], v_tol)
        assert tuple(py) == c
        self.note("painleve_sticks")
        return py

    def project_to_ground(self, model, q, corners):
        py = contact.project_to_ground(model, q, corners)
        c = np.array(_engine.contact_model_call("project_to_ground", self.spec, list(map(float, q)),
                                                sorted(int(i) for i in corners)))
        assert np.max(np.abs(py - c)) <= 1e-13 * max(1.0, float(np.max(np.abs(py))))
        self.note("project_to_ground")
        return py

    def closed_candidates(self, model, q, v, gap_tol, v_tol):
        py = contact.closed_candidates(model, q, v, gap_tol, v_tol)
        assert tuple(py) == _engine.contact_model_call("closed_candidates", self.spec, list(map(float, q)),
                                                       list(map(float, v)), gap_tol, v_tol)
        self.note("closed_candidates")
        return py

    def solve_with_friction(self, model, Minv, W_N, W_T, v_free, b_N, b_T, candidates, forced=(), sliding=None,
                            count=False, hint=None, prefer=None, tolerances=None):
        from rocking_model.tolerances import DEFAULT_TOLERANCES
        tol = tolerances or DEFAULT_TOLERANCES
        py = contact.solve_with_friction(model, Minv, W_N, W_T, v_free, b_N, b_T, candidates, forced, sliding, count,
                                         hint, prefer, tol)
        c = _engine.contact_model_call("solve_with_friction", self.spec, list(map(float, v_free)),
                                       list(map(float, b_N)), list(map(float, b_T)), [int(i) for i in candidates],
                                       [int(i) for i in forced], sliding, count,
                                       None if hint is None else [int(i) for i in hint],
                                       -1 if prefer is None else int(prefer), tol.lcp_exact, tol.lcp_hint,
                                       np.asarray(Minv).tolist(), np.asarray(W_N).tolist(), np.asarray(W_T).tolist())
        self.ties += compare_solution(py, c, W_T=np.asarray(W_T))
        self.note("solve_with_friction")
        return py


SCENES = {
    # kind, model keywords, scheme, pulse amplitude [g], pulse frequency [Hz], t_end [s]
    "rigid free rocking and a pulse, mu = inf": ("rigid", {"e_N": 0.9}, "event_driven", 0.5, 2.0, 3.0),
    "rigid pulse with sliding, mu = 0.3": ("rigid", {"mu": 0.3, "e_N": 0.8}, "event_driven", 0.6, 3.0, 2.0),
    "rigid energy-consistent impacts, mu = 1.5": ("rigid", {"mu": 1.5, "impact_law": 1, "e_N": 0.9}, "event_driven",
                                                 0.4, 1.5, 3.0),
    "flexible pulse": ("flexible", {"e_N": 0.95}, "event_driven", 0.8, 1.0, 4.0),
    "rigid Moreau-Jean, mu = 0.4": ("rigid", {"mu": 0.4}, "moreau_jean", 0.6, 2.0, 1.0),
}


@pytest.mark.parametrize("scene", sorted(SCENES))
def test_contact_problems_of_python_runs(scene, monkeypatch):
    """Every contact problem a Python run meets (impacts, Zeno closures, uplifts, Painleve counts,
    projections, Moreau-Jean step LCPs) is solved alike by the C: the states that decide the scenes."""
    from rocking_model import simulate
    from rocking_model.ground_motion import SinePulse
    from rocking_model.integrators import event_driven, moreau_jean
    kind, kw, scheme, amp, freq, t_end = SCENES[scene]
    if not kernel_available(kind):
        pytest.skip(f"the C kernel of {kind} is not built (part A)")
    model = MODELS[kind](**kw)
    spy = ContactSpy(kind, model)
    for name in ("impact", "next_mode", "painleve_sticks", "project_to_ground", "closed_candidates"):
        monkeypatch.setattr(event_driven, name, getattr(spy, name))
    for name in ("project_to_ground", "solve_with_friction"):
        monkeypatch.setattr(moreau_jean, name, getattr(spy, name))
    simulate(model, SinePulse(amp * 9.81, 2.0 * math.pi * freq), t_end=t_end, scheme=scheme, output_interval=0.01,
             engine="python")           # (the Python reference's contact problems, spied on)
    main = "solve_with_friction" if scheme == "moreau_jean" else "impact"
    assert spy.calls.get(main, 0) >= 10, spy.calls
    assert spy.ties <= TIE_SHARE * sum(spy.calls.values())


@pytest.mark.parametrize("mu, U_N, gap", [(2.0, -1e-6, 1e-9), (1.45, -1e-6, 1e-15), (math.inf, -1e-6, 1e-9),
                                          (1.2, -0.05, 1e-9)])
def test_contact_problems_of_painleve_landings(mu, U_N, gap, monkeypatch):
    """The landing of a sliding corner in Painleve's configuration (tests/test_zeno_painleve.py's scene: b = 0.2,
    h = 1, phi = -0.59, 1 m/s towards -x): the impacts without collision, the Painleve counts and the uplifts
    with several or no solutions, solved alike by the C."""
    from rocking_model import Simulator
    from rocking_model.integrators import event_driven
    if not kernel_available("rigid"):
        pytest.skip("the C kernel of rigid is not built (part A)")
    b, h, phi_p, g = 0.2, 1.0, -0.59, 9.81
    model = MODELS["rigid"](b=b, h=h, mu=mu)
    spy = ContactSpy("rigid", model)
    for name in ("impact", "next_mode", "painleve_sticks", "project_to_ground", "closed_candidates"):
        monkeypatch.setattr(event_driven, name, getattr(spy, name))
    sim = Simulator(model, "event_driven", phi_0=phi_p, engine="python")     # (spied on)
    state = sim.get_state()
    state.update(mode=int(Mode.FLIGHT), y=[0.0, h * math.cos(phi_p) - b * math.sin(phi_p) + gap, phi_p, -1.0, U_N,
                                           0.0])
    sim.set_state(state)
    sim.advance(0.3, 0.0)
    assert spy.calls.get("next_mode", 0) >= 1 and spy.calls.get("painleve_sticks", 0) + spy.calls.get("impact", 0) >= 1
    assert spy.ties == 0
