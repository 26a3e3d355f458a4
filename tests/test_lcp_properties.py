"""The engine's contact LCPs checked by their definition on random well-posed problems.

A small harness is compiled at test time from the package's C sources (rocking_model/engine/src/*.c) with
cffi; only the two solvers and the fields of their problem and solution structs that these tests read are
declared (partial structs: the headers may gain fields). A problem has n contacts on m coordinates:

    v = v_free + M^-1 (W_N P_N + W_T P_T),   w_N = W_N^T v + b_N,   w_T = W_T^T v + b_T

- sticking (the paper's law): 0 <= w_N _|_ P_N >= 0 and w_T = 0 on the contacts that carry P_N > 0,
  P_T = 0 on the others;
- Coulomb (finite mu): the same normal law, |P_T| <= mu P_N, and w_T = 0 (stick) or P_T = -sign(w_T) mu P_N
  (slide) on closed contacts.

At the velocity level with v_free = v- (the pre-impact velocity) and b_N = e_N W_N^T v- the normal law is
Newton's: every contact with an impulse leaves with w_N = 0, i.e. U_N+ = -e_N U_N-. Whatever the law,
M (v - v_free) = W_N P_N + W_T P_T (momentum balance). Units: masses [kg], velocities [m/s], percussions
[N s] (the checks are scale-free: tolerances relative to the problem's scales).
"""
from __future__ import annotations

import hashlib
import importlib.util
import itertools
import shutil
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

SRC = Path(__file__).resolve().parent.parent / "rocking_model" / "engine" / "src"

# the few declarations the tests need; "..." lets cffi take the rest of each struct from the headers
CDEF = """
typedef int... rk_set;
typedef struct rk_error { char message[...]; ...; } rk_error;
typedef struct rk_lcp_problem {
    int n_dof; int n_contacts;
    const double *Minv; const double *W_N; const double *W_T;
    const double *v_free; const double *b_N; const double *b_T;
    rk_set candidates; rk_set forced; double rtol;
    int has_hint; double hint_tol; double mu; const int *sliding; int count; const int *hint_states;
    ...;
} rk_lcp_problem;
typedef struct rk_lcp_wide_solution {
    double v[...]; double P_N[...]; double P_T[...]; double w_N[...]; double w_T[...];
    int exact; double violation; int states[...];
    ...;
} rk_lcp_wide_solution;
int rk_solve_contact_lcp_wide(const rk_lcp_problem *p, rk_lcp_wide_solution *out, rk_error *err);
int rk_solve_friction_lcp_wide(const rk_lcp_problem *p, rk_lcp_wide_solution *out, rk_error *err);
#define RK_LCP_MAX_CONTACTS ...
#define RK_MAX_DOF ...
"""
HEADER = '#include "rk_contact.h"\n'


def _build(cache_dir: Path):
    """Compile (once per source version) and import the harness module."""
    cffi = pytest.importorskip("cffi", reason="cffi is needed to compile the LCP harness (the test extra)")
    sources = sorted(SRC.glob("*.c"))
    digest = hashlib.sha256(CDEF.encode() + b"".join(p.read_bytes() for p in sorted(SRC.glob("*.[ch]"))))
    name = "_lcp_harness_" + digest.hexdigest()[:12]
    cache_dir.mkdir(parents=True, exist_ok=True)
    found = list(cache_dir.glob(name + ".*.so")) + list(cache_dir.glob(name + ".*.pyd"))
    if not found:
        ffi = cffi.FFI()
        ffi.cdef(CDEF)
        ffi.set_source(name, HEADER, sources=[str(p) for p in sources], include_dirs=[str(SRC)],
                       extra_compile_args=["-std=c99", "-O1", "-ffp-contract=off"] if sys.platform != "win32"
                       else [], libraries=["m"] if sys.platform != "win32" else [])
        work = cache_dir / (name + "_build")
        try:
            built = ffi.compile(tmpdir=str(work))
        except Exception as exc:                                   # no compiler, no Python headers
            pytest.skip(f"cannot compile the LCP harness from {SRC} (a C compiler and the Python headers are "
                        f"needed): {type(exc).__name__}: {exc}")
        target = cache_dir / Path(built).name
        shutil.copy(built, target)
        shutil.rmtree(work, ignore_errors=True)
        found = [target]
    spec = importlib.util.spec_from_file_location(name, found[0])
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def lib(request, tmp_path_factory):
    cache = getattr(request.config, "cache", None)      # (None under -p no:cacheprovider)
    where = cache.mkdir("lcp_harness") if cache is not None else tmp_path_factory.mktemp("lcp_harness")
    return _build(Path(where))


class Solved:
    """One solve of the harness: the problem (numpy) and the solution's arrays."""

    def __init__(self, mod, M, W_N, W_T, v_free, b_N, b_T, mu=None):
        ffi, clib = mod.ffi, mod.lib
        m, n = W_N.shape
        self.M, self.W_N, self.W_T, self.v_free, self.b_N, self.b_T, self.mu = M, W_N, W_T, v_free, b_N, b_T, mu
        Minv = np.linalg.inv(M)
        keep = [np.ascontiguousarray(a, dtype=float) for a in (Minv, W_N, W_T, v_free, b_N, b_T)]
        bufs = [ffi.from_buffer("double[]", a) for a in keep]
        p = ffi.new("rk_lcp_problem *")
        p.n_dof, p.n_contacts = m, n
        p.Minv, p.W_N, p.W_T, p.v_free, p.b_N, p.b_T = bufs
        p.candidates = (1 << n) - 1
        p.forced = 0
        p.rtol = 1e-9
        p.hint_tol = 1e-12
        p.mu = float("inf") if mu is None else mu
        out = ffi.new("rk_lcp_wide_solution *")
        err = ffi.new("rk_error *")
        status = (clib.rk_solve_contact_lcp_wide if mu is None else clib.rk_solve_friction_lcp_wide)(p, out, err)
        assert status == 0, ffi.string(err.message).decode()
        self.v = np.array(list(out.v[0:m]))
        self.P_N, self.P_T = np.array(list(out.P_N[0:n])), np.array(list(out.P_T[0:n]))
        self.w_N_reported = np.array(list(out.w_N[0:n]))
        self.exact = bool(out.exact)
        self.violation = out.violation
        # recomputed from v: the checks below do not trust the solver's own residuals
        self.w_N = W_N.T @ self.v + b_N
        self.w_T = W_T.T @ self.v + b_T

    def scales(self):
        """(velocity scale [m/s], percussion scale [N s]) of the problem, for relative tolerances."""
        w0 = np.concatenate([self.W_N.T @ self.v_free + self.b_N, self.W_T.T @ self.v_free + self.b_T])
        P = np.concatenate([self.P_N, self.P_T])
        return max(np.max(np.abs(w0)), 1e-300), max(np.max(np.abs(P)), 1e-300)

    def check_momentum(self, rtol=1e-10):
        """M (v - v_free) = W_N P_N + W_T P_T."""
        lhs = self.M @ (self.v - self.v_free)
        rhs = self.W_N @ self.P_N + self.W_T @ self.P_T
        scale = np.max(np.abs(self.M)) * max(np.max(np.abs(self.v)), np.max(np.abs(self.v_free)))
        assert np.max(np.abs(lhs - rhs)) <= rtol * scale, (lhs, rhs)

    def check_normal(self, tol=1e-8):
        """0 <= w_N _|_ P_N >= 0 (relative to the problem's scales)."""
        sv, sp = self.scales()
        assert np.all(self.w_N >= -tol * sv), self.w_N
        assert np.all(self.P_N >= -tol * sp), self.P_N
        assert np.all(np.abs(self.w_N * self.P_N) <= tol * sv * sp), self.w_N * self.P_N
        np.testing.assert_allclose(self.w_N_reported, self.w_N, rtol=0, atol=tol * sv)

    def check_sticking(self, tol=1e-8):
        sv, sp = self.scales()
        loaded = self.P_N > tol * sp
        assert np.all(np.abs(self.w_T[loaded]) <= tol * sv), self.w_T
        assert np.all(np.abs(self.P_T[~loaded]) <= tol * sp), self.P_T

    def check_coulomb(self, tol=1e-8):
        """|P_T| <= mu P_N; a slipping contact (|w_T| > 0) takes friction against the slip, at the cone
        (mu = inf, the sticking limit: a contact may slip only with P_N -> 0 and a finite friction)."""
        sv, sp = self.scales()
        mu = self.mu
        finite = np.isfinite(mu)
        if finite:
            assert np.all(np.abs(self.P_T) <= mu * np.maximum(self.P_N, 0.0) + tol * sp), (self.P_T, self.P_N)
        for i in range(len(self.P_N)):
            if abs(self.w_T[i]) > tol * sv:
                assert self.P_T[i] * np.sign(self.w_T[i]) <= tol * sp, i
                if finite:
                    assert abs(self.P_T[i] + np.sign(self.w_T[i]) * mu * self.P_N[i]) <= tol * sp, i
                else:
                    assert abs(self.P_N[i]) <= tol * sp, i
            # (sticking, |w_T| ~ 0: any P_T inside the cone, checked above)

# ---------------------------------------------------------------------------------------------- random problems
MAX_DOF = 8          # the engine's RK_MAX_DOF


def random_problem(rng: np.random.Generator, n: int, extra_dof: int):
    """A well-posed problem: M symmetric positive definite (condition number < 1e3), m = min(2 n + extra_dof,
    8) coordinates, a random free velocity; entries O(1). Up to 4 contacts G = [W_N, W_T] has full column
    rank (Delassus matrix positive definite); beyond, more constraints than coordinates (G^T M^-1 G only
    semi-definite, as a body with many contacts)."""
    m = min(2 * n + extra_dof, MAX_DOF)
    Q, _ = np.linalg.qr(rng.standard_normal((m, m)))
    M = Q @ np.diag(rng.uniform(1.0, 1e3 ** 0.5, m) ** 2 / 10.0) @ Q.T
    M = 0.5 * (M + M.T)
    W_N, W_T = rng.standard_normal((m, n)), rng.standard_normal((m, n))
    return M, W_N, W_T, rng.standard_normal(m)


def sticking_solution_exists(M, W_N, W_T, v_free, b_N, b_T, tol=1e-11):
    """Brute force over the 2^n active sets from the definition (the test's own oracle of existence):
    True if one of them meets every sticking condition with margin-free round-off ``tol``."""
    n = W_N.shape[1]
    Minv = np.linalg.inv(M)
    w0N, w0T = W_N.T @ v_free + b_N, W_T.T @ v_free + b_T
    sv = max(np.max(np.abs(np.concatenate([w0N, w0T]))), 1e-300)
    for k in range(n + 1):
        for S in itertools.combinations(range(n), k):
            S = list(S)
            G = np.concatenate([W_N[:, S], W_T[:, S]], axis=1)
            x = np.zeros(0)
            if S:
                rhs = -np.concatenate([w0N[S], w0T[S]])
                x = np.linalg.lstsq(G.T @ Minv @ G, rhs, rcond=1e-12)[0]
            v = v_free + Minv @ G @ x
            P_N = x[:k]
            w_N, w_T = W_N.T @ v + b_N, W_T.T @ v + b_T
            closed = np.all(np.abs(np.concatenate([w_N[S], w_T[S]])) <= tol * sv)   # (lstsq: consistent?)
            if closed and np.all(P_N >= -tol * max(np.max(np.abs(x), initial=0.0), 1e-300)) \
                    and np.all(w_N >= -tol * sv):
                return True
    return False


SETTINGS = settings(max_examples=60, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.function_scoped_fixture])


@SETTINGS
@given(seed=st.integers(0, 2 ** 32 - 1), n=st.integers(1, 8), extra=st.integers(0, 2),
       e_N=st.sampled_from([0.0, 0.3, 1.0]))
def test_impact_lcp_with_sticking_is_solved_by_definition(lib, seed, n, extra, e_N):
    """Impact LCP (sticking law), v_free = v-: the normal law, Newton's law on the contacts with an impulse
    (U_N+ = -e_N U_N-), sticking of loaded contacts and the momentum balance, to 1e-8 of the problem's
    scales. Where the test's brute force finds a solution, the enumeration (n <= 6) must report one; the
    pivoting beyond (7, 8 contacts) must report exact only when it meets the conditions."""
    rng = np.random.default_rng(seed)
    M, W_N, W_T, v_minus = random_problem(rng, n, extra)
    U_minus = W_N.T @ v_minus
    b_N, b_T = e_N * U_minus, np.zeros(n)
    sol = Solved(lib, M, W_N, W_T, v_minus, b_N, b_T)
    exists = sticking_solution_exists(M, W_N, W_T, v_minus, b_N, b_T)
    if n <= 6 and exists:
        assert sol.exact, sol.violation
    if sol.exact:
        sol.check_normal()
        sol.check_sticking()
        sv, sp = sol.scales()
        loaded = sol.P_N > 1e-8 * sp
        U_plus = W_N.T @ sol.v
        assert np.all(np.abs(U_plus[loaded] + e_N * U_minus[loaded]) <= 1e-8 * sv)
    sol.check_momentum()


@SETTINGS
@given(seed=st.integers(0, 2 ** 32 - 1), n=st.integers(1, 8), extra=st.integers(0, 2),
       e_N=st.sampled_from([0.0, 0.5]), mu=st.sampled_from([0.1, 0.5, 2.0]))
def test_impact_lcp_with_coulomb_friction_is_solved_by_definition(lib, seed, n, extra, e_N, mu):
    """Frictional impact LCP: the normal law with Newton's impact law, the Coulomb cone |P_T| <= mu P_N and
    its complementarity (a contact that slips takes P_T = -sign(w_T) mu P_N), the momentum balance. At the
    velocity level with a positive definite Delassus matrix this problem always has a solution (planar
    Coulomb in complementarity form), so the enumeration (n <= 4, full rank here) must find it."""
    rng = np.random.default_rng(seed)
    M, W_N, W_T, v_minus = random_problem(rng, n, extra)
    U_minus = W_N.T @ v_minus
    sol = Solved(lib, M, W_N, W_T, v_minus, e_N * U_minus, np.zeros(n), mu=mu)
    if n <= 4:
        assert sol.exact, sol.violation
    if sol.exact:
        sol.check_normal()
        sol.check_coulomb()
        sv, sp = sol.scales()
        loaded = sol.P_N > 1e-8 * sp
        assert np.all(np.abs(W_N.T @ sol.v + e_N * U_minus)[loaded] <= 1e-8 * sv)
    sol.check_momentum()


def test_frictionless_limit_of_the_coulomb_problem_is_the_normal_lcp(lib):
    """A tiny mu (1e-3, the package's smallest) leaves almost the frictionless LCP, whose matrix
    W_N^T M^-1 W_N is positive definite: its unique solution, computed here by brute force, is what the
    frictional solver returns to O(mu)."""
    rng = np.random.default_rng(7)
    for n in (1, 2, 3, 4):
        M, W_N, W_T, v = random_problem(rng, n, 1)
        Minv = np.linalg.inv(M)
        A, q = W_N.T @ Minv @ W_N, W_N.T @ v
        best = None
        for k in range(n + 1):
            for S in map(list, itertools.combinations(range(n), k)):
                P = np.zeros(n)
                if S:
                    P[S] = np.linalg.solve(A[np.ix_(S, S)], -q[S])
                w = A @ P + q
                if np.all(P >= -1e-12) and np.all(w >= -1e-12):
                    best = P
        sol = Solved(lib, M, W_N, W_T, v, np.zeros(n), np.zeros(n), mu=1e-3)
        assert sol.exact
        np.testing.assert_allclose(sol.P_N, best, rtol=0, atol=1e-2 * np.max(np.abs(best)) + 1e-12)


@SETTINGS
@given(seed=st.integers(0, 2 ** 32 - 1), n=st.integers(1, 4), mu=st.sampled_from([0.2, 1.0]))
def test_acceleration_lcp_with_friction_is_solved_by_definition(lib, seed, n, mu):
    """Acceleration level (uplift): v = acceleration, v_free = M^-1 f, b = random drift terms. The same
    conditions hold for the forces; the enumeration reports exact only when they are met."""
    rng = np.random.default_rng(seed)
    M, W_N, W_T, f = random_problem(rng, n, 2)
    a_free = np.linalg.solve(M, f)
    b_N, b_T = rng.standard_normal(n), rng.standard_normal(n)
    sol = Solved(lib, M, W_N, W_T, a_free, b_N, b_T, mu=mu)
    if sol.exact:
        sol.check_normal()
        sol.check_coulomb()
    sol.check_momentum()


# ---------------------------------------------------------------------------------------------- degenerate
@pytest.mark.parametrize("e_N", [0.0, 0.5])
@pytest.mark.parametrize("mu", [None, 0.01, 0.4, float("inf")])
def test_two_parallel_contacts_still_give_a_solution(lib, e_N, mu):
    """The rigid block at phi = 0 lands flat on both corners: (x, y, phi), W_N,i = [0, 1, s_i b], and both
    tangential rows equal [1, 0, h] (parallel: the Delassus matrix is singular, only the sum of P_T is
    unique). Also with the right corner doubled (identical columns). The result must still meet every
    condition and be the flat landing's: both corners leave at e_N |y_dot-|, no spin, total normal impulse
    m (1 + e_N) |y_dot-|; the small horizontal drift (0.02 m/s, too small to tip the block) is stopped
    where the cone allows it (mu (1 + e_N) |y_dot-| > 0.02), else reduced by mu (1 + e_N) |y_dot-|."""
    b, h, m = 0.2, 1.0, 1.0
    M = np.diag([m, m, m * (b * b + h * h) / 3.0])
    W_N = np.array([[0.0, 0.0], [1.0, 1.0], [-b, b]])
    W_T = np.array([[1.0, 1.0], [0.0, 0.0], [h, h]])
    drift = 0.02
    v_minus = np.array([drift, -1.0, 0.0])
    for cols in ([0, 1], [0, 1, 1]):
        Wn, Wt = W_N[:, cols], W_T[:, cols]
        U = Wn.T @ v_minus
        sol = Solved(lib, M, Wn, Wt, v_minus, e_N * U, np.zeros(len(cols)), mu=mu)
        assert sol.exact, sol.violation
        sol.check_normal()
        if mu is None:
            sol.check_sticking()
        else:
            sol.check_coulomb()
        sol.check_momentum()
        assert np.sum(sol.P_N) == pytest.approx(m * (1.0 + e_N), rel=1e-10)
        assert sol.v[1] == pytest.approx(e_N, abs=1e-10)
        assert sol.v[2] == pytest.approx(0.0, abs=1e-10)
        if mu is None or mu * (1.0 + e_N) > drift:
            assert sol.v[0] == pytest.approx(0.0, abs=1e-10)
        else:
            assert sol.v[0] == pytest.approx(drift - mu * (1.0 + e_N), abs=1e-10)
