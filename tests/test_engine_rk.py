"""The C Runge-Kutta pairs and event location (issue 21, part C) pinned to the Python reference.

`rocking_model._engine.rk_*` runs the C steppers (src/rk_rk.c) and event functions (src/rk_events.c) on small
built-in test problems (rocking_model/engine/py/py_rk.c); the same problems are written below in Python with the
same operation order and run through `rocking_model.integrators.rk` / `events`. Same algorithm, same floating-
point operations: the steps (t, y, f, h_abs, rejections, failure texts), the dense output, the initial step,
the restarts and every event search must agree bit for bit, not to a tolerance.
"""
from __future__ import annotations

import math
import struct
import sys

import pytest

from rocking_model.integrators import events
from rocking_model.integrators.dop853 import DOP853
from rocking_model.integrators.dopri5 import DOPRI5

_engine = pytest.importorskip("rocking_model._engine")
if not hasattr(_engine, "rk_integrate"):
    pytest.skip("the C engine was built without part C's test entry points", allow_module_level=True)

from hypothesis import example, given, settings, strategies as st  # noqa: E402

METHODS = {0: DOP853, 1: DOPRI5}
DOP, DP5 = 0, 1
FRACTIONS = [0.0, 0.125, 0.5, 0.75, 0.999, 1.0]


# ---------------------------------------------------------------------------------------- the test problems
def python_rhs(problem, params, n):
    """The built-in C problems of py_rk.c, written with the same operations in the same order."""
    if problem == "harmonic":
        w, = params
        return lambda t, y: [y[1], -w * w * y[0]]
    if problem == "vdp":
        mu, = params
        return lambda t, y: [y[1], mu * (1.0 - y[0] * y[0]) * y[1] - y[0]]
    if problem == "rocking":
        p2, alpha, a = params
        return lambda t, y: [y[1], -p2 * (math.sin(alpha - y[0]) + a * math.cos(alpha - y[0]))]
    if problem == "chain":
        return lambda t, y: [math.sin(y[(j + 1) % n]) - 0.5 * (j + 1) * y[j] for j in range(n)]
    if problem == "forced":
        lam, = params
        return lambda t, y: [lam * (math.cos(t + j) - y[j]) for j in range(n)]
    if problem == "jump":
        K, = params
        return lambda t, y: [K if v < 1.0 else -K for v in y]
    if problem == "blowup":
        return lambda t, y: [v * v for v in y]
    if problem == "failing":
        T, = params

        def fun(t, y):
            if t > T:
                raise ValueError("failing test rhs")
            return [-v for v in y]
        return fun
    raise ValueError(problem)


def bits(x):
    """A float's bit pattern (so that == means bitwise, -0.0 and NaN included)."""
    return struct.unpack("<q", struct.pack("<d", float(x)))[0]


def same(a, b, path="value"):
    """Assert a == b bitwise, recursively through dicts, lists and tuples."""
    if isinstance(a, dict):
        assert isinstance(b, dict) and sorted(a) == sorted(b), f"{path}: keys {sorted(a)} != {sorted(b)}"
        for k in a:
            same(a[k], b[k], f"{path}[{k!r}]")
    elif isinstance(a, (list, tuple)):
        assert isinstance(b, (list, tuple)) and len(a) == len(b), f"{path}: {a!r} != {b!r}"
        for k, (u, v) in enumerate(zip(a, b)):
            same(u, v, f"{path}[{k}]")
    elif isinstance(a, float) or isinstance(b, float):
        assert isinstance(a, (int, float)) and isinstance(b, (int, float)), f"{path}: {a!r} != {b!r}"
        assert bits(a) == bits(b), f"{path}: C {a!r} != Python {b!r}"
    else:
        assert a == b, f"{path}: {a!r} != {b!r}"


def python_integrate(method, problem, params, t0, y0, rtol, atol, max_step=math.inf, first_step=None,
                     t_bounds=(), max_steps=1000, fractions=()):
    """What rk_integrate does in C, with the Python stepper."""
    fun = python_rhs(problem, params, len(y0))
    s = METHODS[method](fun, t0, y0, rtol, atol, max_step, first_step)
    out = {"h0": s.h_abs, "steps": []}
    count = 0
    for b in t_bounds:
        while s.t < b and count < max_steps:
            try:
                s.step(b)
            except FloatingPointError as exc:
                out["error"] = ("nonfinite", str(exc))
                return out
            except ValueError:
                out["error"] = ("value", "the right-hand side failed")
                return out
            count += 1
            dense = s.dense_output()
            out["steps"].append({
                "t_old": s.t_old, "t": s.t, "y": list(s.y), "f": list(s.f), "h_abs": s.h_abs,
                "n_steps": s.n_steps, "n_rejected": s.n_rejected, "failure": s.failure if s.failed else None,
                "dense": [dense(s.t_old + fr * (s.t - s.t_old)) for fr in fractions], "mid": s.hermite_mid()})
            s.failed = False
    return out


def check_integrate(method, problem, params, t0, y0, rtol, atol, **kw):
    c = _engine.rk_integrate(method, problem, params, t0, y0, rtol, atol, **kw)
    p = python_integrate(method, problem, params, t0, y0, rtol, atol, **kw)
    if "error" in p:
        assert "error" in c, f"the Python stopped with {p['error']}, the C did not"
        assert c["error"][0] == p["error"][0]
        if p["error"][0] == "nonfinite":
            assert c["error"][1] == p["error"][1]
        c = dict(c)
        del c["error"]
        del p["error"]
    same(c, p)
    return c


# ---------------------------------------------------------------------------------------- tableaux
@pytest.mark.parametrize("method", [DOP, DP5])
def test_generated_tableau_equals_the_python_lists(method):
    """gen_rk.py wrote the Python's lists, with the nonzero terms rk._lincomb writes, in its order."""
    tab = METHODS[method].tableau
    c = _engine.rk_tableau(method)

    def nz(coefs):
        idx = [i for i, v in enumerate(coefs) if v != 0.0]
        return (idx, [float(coefs[i]) for i in idx])

    assert c["name"] == tab.name and c["order"] == tab.order and c["error_order"] == tab.error_order
    assert c["n_stages"] == tab.n_stages and c["n_all"] == len(tab.A)
    same(c["C"], [float(v) for v in tab.C[:len(tab.A)]])
    same(c["A"], [nz(row[:s]) for s, row in enumerate(tab.A)])
    same(c["B"], nz(tab.B))
    errors = [tab.E5, tab.E3] if tab.name == "DOP853" else [tab.E]
    same(c["E"], [nz(e) for e in errors])
    same(c["D"], [nz(row) for row in (tab.D if tab.name == "DOP853" else tab.P)])


def test_generator_is_deterministic_and_rewrites_only_on_change(tmp_path):
    import importlib.util
    import os
    path = os.path.join(os.path.dirname(_engine.__file__), "engine", "gen_rk.py")
    spec = importlib.util.spec_from_file_location("gen_rk_under_test", path)
    gen = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(gen)
    out = str(tmp_path / "rk_tableaux.h")
    assert gen.generate(out) is True
    first = open(out, encoding="utf-8").read()
    assert gen.generate(out) is False
    assert open(out, encoding="utf-8").read() == first
    assert f"#define RK_PY_SUM_COMPENSATED {1 if sys.version_info >= (3, 12) else 0}\n" in first
    assert "0x1.aee6838dae63ap-5" in first          # DOP853's C[1] = 0.05260015195876773, exact


# ---------------------------------------------------------------------------------------- steps
@pytest.mark.parametrize("method", [DOP, DP5])
@pytest.mark.parametrize("problem,params,y0", [
    ("harmonic", [1.0], [1.0, 0.0]),
    ("harmonic", [7.3], [0.2, -1.5]),
    ("vdp", [1.0], [2.0, 0.0]),
    ("vdp", [10.0], [2.0, 0.0]),
    ("rocking", [3 * 9.81 / (4 * 1.0307764064044151), 0.24497866312686414, 0.15], [0.01, 0.0]),
])
@pytest.mark.parametrize("rtol", [1e-3, 1e-8, 1e-12])
def test_steps_and_dense_output_bitwise(method, problem, params, y0, rtol):
    atol = [rtol * 1e-2] * len(y0)
    c = check_integrate(method, problem, params, 0.0, y0, rtol, atol, t_bounds=[0.7, 0.7000001, 3.0],
                        max_steps=400, fractions=FRACTIONS)
    assert len(c["steps"]) > 2


@pytest.mark.parametrize("method", [DOP, DP5])
@pytest.mark.parametrize("n", range(1, 17))
def test_state_sizes_1_to_16(method, n):
    """Every state size up to RK_MAX_Y (the models use 0 to 8)."""
    y0 = [0.3 * (j + 1) * (-1) ** j for j in range(n)]
    atol = [1e-9 * (j + 1) for j in range(n)]
    check_integrate(method, "chain", [], 0.25, y0, 1e-7, atol, t_bounds=[2.0], max_steps=300, fractions=FRACTIONS)
    check_integrate(method, "forced", [2.5], -1.0, y0, 1e-6, atol, t_bounds=[0.5, 1.5], max_steps=300,
                    fractions=FRACTIONS, max_step=0.05)


@pytest.mark.parametrize("method", [DOP, DP5])
def test_rejected_steps_and_first_step_given(method):
    """A stiff forced problem: the controller rejects steps (and never grows h after a rejection)."""
    c = check_integrate(method, "forced", [3000.0], 0.0, [2.0, -1.0, 0.5], 1e-6, [1e-9] * 3, first_step=0.5,
                        t_bounds=[0.2], max_steps=600, fractions=[0.5])
    assert c["steps"][-1]["n_rejected"] > 0
    check_integrate(method, "forced", [3000.0], 0.0, [2.0], 1e-6, [1e-9], first_step=1e-5, max_step=1e-3,
                    t_bounds=[0.01], max_steps=600)


@pytest.mark.parametrize("method", [DOP, DP5])
def test_failed_steps_carry_the_python_text(method):
    """A discontinuous rhs at a tolerance below round-off: steps accepted at the smallest step size."""
    c = check_integrate(method, "jump", [1e6], 0.9, [0.999999], 1e-14, [1e-300], t_bounds=[1.0], max_steps=80)
    failures = [s["failure"] for s in c["steps"] if s["failure"]]
    assert failures and "accepted at the smallest step size" in failures[0]


@pytest.mark.parametrize("method", [DOP, DP5])
def test_overflow_gives_the_python_floating_point_message(method):
    c = _engine.rk_integrate(method, "blowup", [], 0.0, [1.0, 0.5], 1e-8, [1e-10, 1e-10], t_bounds=[3.0],
                             max_steps=20000)
    p = python_integrate(method, "blowup", [], 0.0, [1.0, 0.5], 1e-8, [1e-10, 1e-10], t_bounds=[3.0],
                         max_steps=20000)
    assert p["error"][0] == "nonfinite" and "is not finite after a step" in p["error"][1]
    assert c["error"] == p["error"]
    assert len(c["steps"]) == len(p["steps"])
    same(c["steps"][-1], p["steps"][-1])


def test_underflowing_error_estimate_is_a_zero_error_in_both():
    """A state near 1e-155 of its scale: DOP853's e5 is 0.0 and 0.01 e3 underflows, so Hairer's norm is 0 / 0;
    both the C and the Python take it as the zero estimate it is (err = 0.0) and go on to t_bound, step for step
    bit for bit (the Python divided by zero here: ZeroDivisionError)."""
    c = check_integrate(DOP, "chain", [], 0.0, [6.702559824942551e-155], 0.01, [0.01], t_bounds=[1.5],
                        max_steps=60, fractions=FRACTIONS)
    assert "error" not in c and c["steps"][-1]["t"] == 1.5


@pytest.mark.parametrize("method", [DOP, DP5])
def test_failing_rhs_stops_at_the_same_step(method):
    c = check_integrate(method, "failing", [0.5], 0.0, [1.0], 1e-8, [1e-10], t_bounds=[2.0])
    assert c["steps"][-1]["t"] <= 0.5


@pytest.mark.parametrize("method", [DOP, DP5])
def test_zero_size_state_only_advances_time(method):
    check_integrate(method, "chain", [], 0.0, [], 1e-8, [], max_step=0.3, t_bounds=[1.0, 1.05])
    check_integrate(method, "chain", [], 0.0, [], 1e-8, [], t_bounds=[1.0])


@pytest.mark.parametrize("method", [DOP, DP5])
@pytest.mark.parametrize("first_step", [None, 0.01])
def test_restart_under_a_new_state(method, first_step):
    fun = python_rhs("vdp", [2.0], 2)
    s = METHODS[method](fun, 0.0, [1.0, 0.5], 1e-9, [1e-11, 1e-11], 0.4)
    for _ in range(5):
        s.step(math.inf)
    s.restart(fun, 1.25, [0.3, -0.7], first_step)
    h_after = s.h_abs
    s.step(math.inf)
    h_c, rec = _engine.rk_restart(method, "vdp", [2.0], 0.0, [1.0, 0.5], 1e-9, [1e-11, 1e-11], 0.4, 5, 1.25,
                                  [0.3, -0.7], first_step)
    assert bits(h_c) == bits(h_after)
    same({k: rec[k] for k in ("t_old", "t", "y", "f", "h_abs", "n_steps", "n_rejected")},
         {"t_old": s.t_old, "t": s.t, "y": s.y, "f": s.f, "h_abs": s.h_abs, "n_steps": s.n_steps,
          "n_rejected": s.n_rejected})


@settings(max_examples=60, deadline=None)
@given(method=st.sampled_from([DOP, DP5]), n=st.integers(1, 8),
       y=st.lists(st.floats(-3.0, 3.0, allow_nan=False).filter(lambda v: v == 0.0 or abs(v) > 1e-100), min_size=8,
                  max_size=8),
       t0=st.floats(-100.0, 100.0, allow_nan=False), rtol=st.sampled_from([1e-2, 1e-5, 1e-8, 1e-11, 1e-14]),
       atol_exp=st.integers(-14, -2), first=st.one_of(st.none(), st.floats(1e-6, 1.0)))
# a square whose libm pow(x, 2) is not x * x rounded (the heuristic's squares are products on both sides)
@example(method=DOP, n=8, y=[2.0, 1.375, 0.7845560223984096, 0.875, 1.25, 0.5, 2.9296875, -2.5471979005067054],
         t0=0.0, rtol=1e-5, atol_exp=-11, first=None)
def test_random_states_bitwise(method, n, y, t0, rtol, atol_exp, first):
    """Random states, tolerances and initial steps: the initial-step heuristic (with its sums) and every step."""
    check_integrate(method, "chain", [], t0, y[:n], rtol, [10.0 ** atol_exp] * n, first_step=first,
                    t_bounds=[t0 + 1.5], max_steps=60, fractions=[0.3, 1.0])


# ---------------------------------------------------------------------------------------- events
def python_events(setup):
    """The stepper and event functions of a setup tuple, in Python (what py_rk.c's event_setup builds)."""
    method, problem, params, t0, y0, rtol, atol, first, n_steps, W, c, d = setup
    s = METHODS[method](python_rhs(problem, params, len(y0)), t0, y0, rtol, atol, math.inf, first)
    for _ in range(n_steps):
        s.step(math.inf)

    def G(t, y):
        out = []
        for i in range(len(c)):
            v = c[i] + d[i] * t
            for j in range(len(y)):
                v = v + W[i][j] * y[j]
            out.append(v)
        return out
    return s, G


# the harmonic oscillator y = (cos t, -sin t) from t = 0 in long steps, and three contact-like functions plus a
# last (overturning-like) one: cos t - 0.3 crosses zero near 1.27 and 5.02; 0.9 - sin t dips below zero on
# (1.12, 2.02); sin t + 0.2 t - 0.1 starts negative; the last stays positive
W3 = [[1.0, 0.0], [0.0, 1.0], [0.0, -1.0], [0.0, 0.0]]
C3 = [-0.3, 0.9, -0.1, 1.0]
D3 = [0.0, 0.0, 0.2, 0.0]


def harmonic_setup(method, n_steps, rtol=1e-4, first=1.5, t0=0.0):
    return (method, "harmonic", [1.0], t0, [math.cos(t0), -math.sin(t0)], rtol, [rtol * 1e-2] * 2, first, n_steps,
            W3, C3, D3)


def brackets(setup, samples=40):
    """(i, a, ga, b, gb): every sign change from > 0 to <= 0 of each function on a grid of the last step."""
    s, G = python_events(setup)
    dense = s.dense_output()
    ts = [s.t_old + (s.t - s.t_old) * k / samples for k in range(samples)] + [s.t]
    gs = [G(t, dense(t)) for t in ts]
    out = []
    for i in range(len(gs[0])):
        for k in range(samples):
            if gs[k][i] > 0.0 >= gs[k + 1][i]:
                out.append((i, ts[k], gs[k][i], ts[k + 1], gs[k + 1][i]))
    return out


SETUPS = [harmonic_setup(m, k) for m in (DOP, DP5) for k in (1, 2, 3, 4)] + [
    harmonic_setup(m, k, rtol=1e-2, first=2.0) for m in (DOP, DP5) for k in (1, 2, 3)] + [
    harmonic_setup(DOP, 1, rtol=1e-9, first=0.4, t0=1.0), harmonic_setup(DP5, 2, rtol=1e-7, first=0.3, t0=4.7)]


@pytest.mark.parametrize("setup", SETUPS)
def test_event_values_on_the_dense_output(setup):
    s, G = python_events(setup)
    dense = s.dense_output()
    for fr in FRACTIONS:
        t = s.t_old + fr * (s.t - s.t_old)
        same(_engine.rk_events_eval(setup, t), G(t, dense(t)))


@pytest.mark.parametrize("setup", SETUPS)
@pytest.mark.parametrize("xtol", [1e-14, 1e-10, 1e-4])
def test_locate_same_roots(setup, xtol):
    s, G = python_events(setup)
    dense = s.dense_output()
    found = brackets(setup)
    for shift in (0.0, 1e-9):
        for i, a, ga, b, gb in found:
            def gi(t, i=i):
                return G(t, dense(t))[i] + shift
            t_py = events.locate(gi, a, ga + shift, b, gb + shift, xtol)
            t_c = _engine.rk_events_locate(setup, i, shift, a, ga + shift, b, gb + shift, xtol)
            assert bits(t_c) == bits(t_py), (i, a, b, t_c, t_py)
    # whole-step brackets, too (the usual call: the step's ends)
    g0, g1 = G(s.t_old, dense(s.t_old)), G(s.t, dense(s.t))
    for i in range(len(g0)):
        if g0[i] > 0.0 >= g1[i]:
            t_py = events.locate(lambda t, i=i: G(t, dense(t))[i], s.t_old, g0[i], s.t, g1[i], xtol)
            assert bits(_engine.rk_events_locate(setup, i, 0.0, s.t_old, g0[i], s.t, g1[i], xtol)) == bits(t_py)


def test_event_searches_are_exercised():
    """The setups hold brackets of several functions, sub-intervals that first_negative finds and bounces that
    bounce_search finds (and misses): the comparisons below compare real searches, not two Nones."""
    found = [b for setup in SETUPS for b in brackets(setup)]
    assert len(found) >= 8 and len({b[0] for b in found}) >= 3
    assert len([su for su in SETUPS if brackets(su, samples=8)]) >= 8
    negatives = bounces = misses = 0
    for setup in SETUPS:
        s, G = python_events(setup)
        dense = s.dense_output()
        negatives += events.first_negative(G, dense, s.t_old, G(s.t_old, dense(s.t_old)), s.t, [0, 1, 2], 16) is not None
        y_old = dense(s.t_old)
        _, Gb = python_events(setup[:9] + ([[1.0, 0.0]], [-y_old[0]], [0.0]))
        for level in (1e-6, 10.0):
            hit = events.bounce_search(dense, Gb, 0, s.t_old, s.t, level) is not None
            bounces += hit
            misses += not hit
    assert negatives >= 4 and bounces >= 4 and misses >= 4


@pytest.mark.parametrize("setup", [su for su in SETUPS if brackets(su, samples=8)])
def test_earliest_root_same_time_and_index(setup):
    s, G = python_events(setup)
    dense = s.dense_output()
    found = brackets(setup, samples=8)
    # the first sub-interval with a sign change, all functions that change sign there
    i0, a, _, b, _ = min(found, key=lambda f: f[1])
    ga, gb = G(a, dense(a)), G(b, dense(b))
    ids = [i for i in range(len(ga)) if ga[i] > 0.0 >= gb[i]]
    shifts = [0.0, 1e-12, 0.0, 0.0]
    ids_all = ids + [i for i in range(len(ga)) if i not in ids and ga[i] + shifts[i] > 0.0 >= gb[i] + shifts[i]]
    t_py, i_py = events.earliest_root(G, dense, ids_all, shifts, {}, a, ga, b, gb, 1e-13)
    t_c, i_c = _engine.rk_events_earliest_root(setup, ids_all, shifts, {}, a, ga, b, gb, 1e-13)
    assert (bits(t_c), i_c) == (bits(t_py), i_py)
    # a later left end for the first function (as after bounce_search), and one that is not later
    tm = a + 0.25 * (b - a)
    gm = G(tm, dense(tm))
    for starts in ({ids_all[0]: (tm, gm)}, {ids_all[0]: (a - 1.0, ga)}):
        if starts[ids_all[0]][1][ids_all[0]] + shifts[ids_all[0]] <= 0.0:
            continue
        t_py, i_py = events.earliest_root(G, dense, ids_all, shifts, starts, a, ga, b, gb, 1e-13)
        t_c, i_c = _engine.rk_events_earliest_root(setup, ids_all, shifts, starts, a, ga, b, gb, 1e-13)
        assert (bits(t_c), i_c) == (bits(t_py), i_py)


@pytest.mark.parametrize("setup", SETUPS)
@pytest.mark.parametrize("n", [2, 5, 16])
def test_first_negative_same_sub_interval(setup, n):
    s, G = python_events(setup)
    dense = s.dense_output()
    g0 = G(s.t_old, dense(s.t_old))
    for ids in ([0, 1, 2], [1], [2, 0], [3]):
        py = events.first_negative(G, dense, s.t_old, g0, s.t, ids, n)
        c = _engine.rk_events_first_negative(setup, s.t_old, g0, s.t, ids, n)
        if py is None:
            assert c is None
        else:
            same(c, py)


@pytest.mark.parametrize("setup", SETUPS)
@pytest.mark.parametrize("armed", [[1, 1, 1], [0, 1, 0], [1, 0, 1]])
def test_dip_search_same_hits(setup, armed):
    s, G = python_events(setup)
    dense = s.dense_output()
    g_prev, g_new = G(s.t_old, dense(s.t_old)), G(s.t, dense(s.t))
    for n in (4, 16):
        hits, ta, tb, ga, gb, d = events.dip_search(s, G, armed, g_prev, g_new, n)
        c = _engine.rk_events_dip_search(setup, armed, g_prev, g_new, n)
        same(c, (hits, ta, tb, ga, gb, d is not None))


def test_dip_search_finds_a_dip():
    """0.9 - sin t, positive at both ends of a step across pi/2, dips below zero inside: both find it."""
    setup = (DOP, "harmonic", [1.0], 1.0, [math.cos(1.0), -math.sin(1.0)], 1e-2, [1e-4] * 2, 1.3, 1,
             W3, C3, D3)
    s, G = python_events(setup)
    dense = s.dense_output()
    assert s.t > 2.1, "the step must cross the dip of 0.9 - sin t on (1.12, 2.02)"
    g_prev, g_new = G(s.t_old, dense(s.t_old)), G(s.t, dense(s.t))
    assert g_prev[1] > 0.0 and g_new[1] > 0.0
    hits, ta, tb, ga, gb, d = events.dip_search(s, G, [0, 1, 0], g_prev, g_new, 16)
    assert hits == [1]
    same(_engine.rk_events_dip_search(setup, [0, 1, 0], g_prev, g_new, 16), (hits, ta, tb, ga, gb, True))


@pytest.mark.parametrize("setup", SETUPS)
def test_bounce_search_same_time(setup):
    s, G0 = python_events(setup)
    dense = s.dense_output()
    # a function that starts the step at zero exactly: y0(t) - y0(t_old) (rising where cos rises)
    y_old = dense(s.t_old)
    for sign in (1.0, -1.0):
        W = [[sign, 0.0], [0.0, sign]]
        c = [-sign * y_old[0], -sign * y_old[1]]
        su = setup[:9] + (W, c, [0.0, 0.0])
        _, G = python_events(su)
        for i in (0, 1):
            # the tiny levels are reached only near the end of the 4^-n sampling (its round-off xtol)
            for level in (1e-16, 1e-15, 4e-15, 1e-14, 1e-12, 1e-6, 1e-2, 10.0):
                py = events.bounce_search(dense, G, i, s.t_old, s.t, level)
                cc = _engine.rk_events_bounce_search(su, i, s.t_old, s.t, level)
                if py is None:
                    assert cc is None
                else:
                    same(cc, py)


@settings(max_examples=300, deadline=None)
@given(st.floats(-10, 10, allow_nan=False), st.floats(-10, 10, allow_nan=False), st.floats(-10, 10, allow_nan=False))
def test_may_dip(g0, gm, g1):
    assert _engine.rk_events_may_dip(g0, gm, g1) == events.may_dip(g0, gm, g1)
    # (0.125, 0.125, 0.625) and (0.25, 0.625, 3.25): the vertex exactly at half the smaller end (strict <)
    for a, b, c in ((1.0, 0.25, 1.0), (1.0, 0.9, 2.0), (1.0, 1.0, 1.0), (0.5, 0.6, 0.5), (g0, g0, g0),
                    (0.125, 0.125, 0.625), (0.25, 0.625, 3.25), (0.25, 0.2, 3.25)):
        assert _engine.rk_events_may_dip(a, b, c) == events.may_dip(a, b, c)


def test_locate_with_a_bad_tolerance_is_an_error_not_a_hang():
    setup = harmonic_setup(DOP, 1)
    i, a, ga, b, gb = brackets(setup)[0]
    with pytest.raises(RuntimeError, match="no convergence"):
        _engine.rk_events_locate(setup, i, 0.0, a, ga, b, gb, 0.0)


def test_sources_compile_without_warnings(tmp_path):
    """rk_rk.c and rk_events.c compile cleanly with -Wall -Wextra -pedantic -Werror and the build's flags."""
    import os
    import shutil
    import subprocess
    cc = shutil.which("gcc") or shutil.which("cc") or shutil.which("clang")
    src = os.path.join(os.path.dirname(_engine.__file__), "engine", "src")
    if cc is None or not os.path.exists(os.path.join(src, "rk_tableaux.h")):
        pytest.skip("no C compiler or no generated header next to the sources (installed without them)")
    for name in ("rk_rk.c", "rk_events.c"):
        res = subprocess.run([cc, "-std=c99", "-O2", "-ffp-contract=off", "-fno-fast-math", "-Wall", "-Wextra",
                              "-pedantic", "-Werror", "-c", os.path.join(src, name), "-o", str(tmp_path / (name + ".o"))],
                             capture_output=True, text=True, timeout=120)
        assert res.returncode == 0, res.stderr


@settings(max_examples=300, deadline=None)
@given(st.floats(-10, 10, allow_nan=False), st.floats(-10, 10, allow_nan=False), st.floats(-10, 10, allow_nan=False))
def test_parabola_peak(f0, fm, f1):
    for args in ((f0, fm, f1), (0.0, 1.0, 0.5), (1.0, 1.0, 1.0), (0.0, 0.25, 1.0), (1.0, 0.0, 1.0)):
        c, py = _engine.rk_events_parabola_peak(*args), events.parabola_peak(*args)
        if py is None:
            assert c is None
        else:
            same(c, py)


def python_brent(setup, i, a, b, x, fx, xtol, max_iter, none_below):
    s, G = python_events(setup)
    dense = s.dense_output()

    def f(t):
        v = G(t, dense(t))[i]
        return None if v < none_below else v
    return events.brent_max(f, a, b, x, fx, xtol, max_iter)


@settings(max_examples=80, deadline=None)
@given(k=st.integers(0, len(SETUPS) - 1), i=st.integers(0, 2), frac=st.floats(0.01, 0.99),
       xtol_exp=st.integers(-14, -2), max_iter=st.sampled_from([3, 60]),
       none_below=st.sampled_from([-math.inf, 0.0, 0.3]), fx_none=st.booleans())
def test_brent_max_same_peak(k, i, frac, xtol_exp, max_iter, none_below, fx_none):
    """Brent's peak search on G_i over the step (smooth peaks, ends, and None values below a floor)."""
    setup = SETUPS[k]
    s, G = python_events(setup)
    dense = s.dense_output()
    a, b = s.t_old, s.t
    x = a + frac * (b - a)
    v = G(x, dense(x))[i]
    fx = None if fx_none or v < none_below else v
    xtol = 10.0 ** xtol_exp * (b - a)
    py = python_brent(setup, i, a, b, x, fx, xtol, max_iter, none_below)
    same(_engine.rk_events_brent_max(setup, i, a, b, x, fx, xtol, max_iter, none_below), py)


def test_brent_max_finds_an_inner_peak():
    """cos t - 0.3 over a step across t = 2 pi peaks inside (a real parabolic search, not an end)."""
    setup = harmonic_setup(DOP, 3, rtol=1e-2, first=2.0)
    s, G = python_events(setup)
    assert s.t_old < 2 * math.pi < s.t
    x = s.t_old + 0.3 * (s.t - s.t_old)
    dense = s.dense_output()
    py = python_brent(setup, 0, s.t_old, s.t, x, G(x, dense(x))[0], 1e-9, 60, -math.inf)
    assert abs(py[0] - 2 * math.pi) < 0.05     # the interpolant of a step at rtol 1e-2: a coarse peak
    same(_engine.rk_events_brent_max(setup, 0, s.t_old, s.t, x, G(x, dense(x))[0], 1e-9, 60, -math.inf), py)


def cpython_sum(xs):
    """CPython >= 3.12's sum() of floats from the int start 0 (bltinmodule.c: 0 + x0, then Neumaier's
    compensated loop, the compensation added at the end when nonzero and finite)."""
    f = 0.0 + xs[0] if xs else 0.0
    c = 0.0
    for x in xs[1:]:
        t = f + x
        if abs(f) >= abs(x):
            c += (f - t) + x
        else:
            c += (x - t) + f
        f = t
    if c and math.isfinite(c):
        f += c
    return f


def plain_sum(xs):
    f = 0
    for x in xs:
        f = f + x
    return float(f)


@pytest.mark.parametrize("compensated", [0, 1])
def test_both_forms_of_pythons_sum(tmp_path, compensated):
    """The C py_sum in both forms (CPython < 3.12 plain, >= 3.12 compensated), on sums where they differ;
    and the form built into the module is the running interpreter's (sum() itself agrees)."""
    import os
    import random
    import shutil
    import subprocess
    cc = shutil.which("gcc") or shutil.which("cc") or shutil.which("clang")
    src = os.path.join(os.path.dirname(_engine.__file__), "engine", "src")
    if cc is None or not os.path.exists(os.path.join(src, "rk_tableaux.h")):
        pytest.skip("no C compiler or no generated header next to the sources")
    prog = tmp_path / "sum.c"
    prog.write_text('#include <stdio.h>\n#include <stdlib.h>\n#include "rk_rk.c"\n'
                    'int main(int argc, char **argv) { double x[64]; int i;\n'
                    '  for (i = 1; i < argc; i++) x[i - 1] = strtod(argv[i], NULL);\n'
                    '  printf("%a\\n", py_sum(x, argc - 1)); return 0; }\n')
    exe = tmp_path / "sum"
    res = subprocess.run([cc, "-std=c99", "-O2", "-ffp-contract=off", "-fno-fast-math", f"-DRK_PY_SUM_COMPENSATED={compensated}",
                          "-I", src, str(prog), os.path.join(src, "rk_common.c"), "-lm", "-o", str(exe)],
                         capture_output=True, text=True, timeout=120)
    assert res.returncode == 0, res.stderr
    rng = random.Random(7)
    cases = [[1.0, 1e-16, 1e-16, 1e-16], [1e16, 1.0, -1e16], [0.1] * 10, [-0.0], [3.5]]
    cases += [[rng.uniform(-1, 1) * 10.0 ** rng.randint(-8, 8) for _ in range(rng.randint(1, 16))] for _ in range(20)]
    ref = cpython_sum if compensated else plain_sum
    differ = 0
    for xs in cases:
        out = subprocess.run([str(exe)] + [x.hex() for x in xs], capture_output=True, text=True, timeout=60)
        got = float.fromhex(out.stdout.strip())
        assert bits(got) == bits(ref(xs)), xs
        differ += cpython_sum(xs) != plain_sum(xs)
        if (sys.version_info >= (3, 12)) == bool(compensated):
            assert bits(got) == bits(sum(xs)), xs
    assert differ >= 3


@pytest.mark.parametrize("method", [DOP, DP5])
def test_restart_from_its_own_point_goes_on_bit_identically(method):
    """EventDriven restarts a stepper at its own (t, y) with the last step size (after a state restore): the
    next step equals the one the stepper would have taken (FSAL derivative re-evaluated at the stored t_new);
    the C restart reads the stepper's own arrays (aliasing) safely."""
    fun = python_rhs("vdp", [2.0], 2)
    s = METHODS[method](fun, 0.0, [1.0, 0.5], 1e-9, [1e-11, 1e-11], 0.4)
    for _ in range(4):
        s.step(math.inf)
    h = s.h_abs
    s.step(math.inf)
    ref = (s.t, list(s.y), s.h_abs)
    h_c, rec = _engine.rk_restart(method, "vdp", [2.0], 0.0, [1.0, 0.5], 1e-9, [1e-11, 1e-11], 0.4, 4, 0.0, None, h)
    assert bits(h_c) == bits(h)
    same((rec["t"], rec["y"], rec["h_abs"]), ref)


def test_python_repr_of_floats_in_the_overflow_message(tmp_path):
    """The state in the FloatingPointError text is Python's list repr: the C's py_repr equals repr(float) on
    every kind of value (shortest round trip, fixed / exponent switch at 1e-4 and 1e16, -0.0, inf, nan)."""
    import os
    import random
    import shutil
    import subprocess
    cc = shutil.which("gcc") or shutil.which("cc") or shutil.which("clang")
    src = os.path.join(os.path.dirname(_engine.__file__), "engine", "src")
    if cc is None or not os.path.exists(os.path.join(src, "rk_tableaux.h")):
        pytest.skip("no C compiler or no generated header next to the sources")
    prog = tmp_path / "repr.c"
    prog.write_text('#include <stdio.h>\n#include <stdlib.h>\n#include "rk_rk.c"\n'
                    'int main(int argc, char **argv) { char buf[64]; int i;\n'
                    '  for (i = 1; i < argc; i++) { py_repr(strtod(argv[i], NULL), buf, sizeof buf); puts(buf); }\n'
                    '  return 0; }\n')
    exe = tmp_path / "repr"
    res = subprocess.run([cc, "-std=c99", "-O2", "-ffp-contract=off", "-fno-fast-math", "-I", src, str(prog),
                          os.path.join(src, "rk_common.c"), "-lm", "-o", str(exe)], capture_output=True, text=True,
                         timeout=120)
    assert res.returncode == 0, res.stderr
    rng = random.Random(11)
    values = [0.0, -0.0, 1.0, -1.5, 0.1, 1e-4, 9.999e-5, 1e-5, 1e15, 1e16, 9999999999999998.0, 1.2345e16, 123.0,
              5e-324, 1.7976931348623157e308, math.inf, -math.inf, math.nan, 2.0 ** 60, 1 / 3, 100.0, 1e22, 1e-7]
    values += [rng.uniform(-1, 1) * 10.0 ** rng.randint(-30, 30) for _ in range(300)]
    values += [float(rng.randint(-10 ** 6, 10 ** 6)) for _ in range(20)]
    out = subprocess.run([str(exe)] + [v.hex() if math.isfinite(v) else repr(v) for v in values],
                         capture_output=True, text=True, timeout=60).stdout.split("\n")
    for v, got in zip(values, out):
        assert got == repr(v), (v, got)
