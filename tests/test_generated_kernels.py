"""The generated model kernels against their symbolic derivation, and the derivation against the mechanics.

1. Every C kernel function generated from a model's declaration (rocking_model/engine/gen_models.py) equals the
   sympy expression it was generated from, evaluated in 40-digit arithmetic (mpmath), on random parameters and
   states: the printing, the parameter-only constants, the common subexpressions and the regrouping keep the
   value to 1e-13 relative (of the largest entry of the result).
2. The reduced dynamics of every contact mode satisfy the full equations of motion with the contact forces the
   kernels report (M q_dd - f = W_N lambda_N + W_T lambda_T in every row, not only the rows the forces were
   solved from), the embedding satisfies the mode's contacts, and the kinetic energy is 1/2 v^T M v.
"""
from __future__ import annotations

import math
import random

import mpmath
import numpy as np
import pytest
import sympy as sp

from c_kernels import kernels
from rocking_model import FlexibleOscillator, RigidBlock
from rocking_model.engine import gen_models

mpmath.mp.dps = 40
REL = 1e-13
FULL, LEFT, RIGHT, FLIGHT = 0, 1, 2, 3
CLOSED = {FULL: (0, 1), LEFT: (0,), RIGHT: (1,), FLIGHT: ()}


@pytest.fixture(scope="module")
def harness(tmp_path_factory):
    return kernels(tmp_path_factory.mktemp("kernels"))


@pytest.fixture(scope="module", params=[RigidBlock, FlexibleOscillator], ids=["rigid", "flexible"])
def code(request):
    return gen_models.ModelCode(request.param)


def _random_params(cls, rng):
    """Parameters well inside the declared ranges (a physical spread of sizes)."""
    if cls is RigidBlock:
        return dict(b=rng.uniform(0.05, 2.0), h=rng.uniform(0.2, 5.0), m=rng.uniform(0.5, 5e3),
                    g=rng.uniform(5.0, 15.0), e_N=rng.uniform(0, 1), mu=rng.choice([math.inf, 0.5]))
    return dict(m=rng.uniform(10, 1e4), m_c=rng.choice([0.0, rng.uniform(1, 500)]), m_b=rng.uniform(1, 1e3),
                rho=rng.uniform(0.05, 1.0), h=rng.uniform(0.5, 5.0), b=rng.uniform(0.1, 1.0),
                EI=rng.uniform(1e4, 1e6), zeta=rng.uniform(0, 0.2), g=rng.uniform(5.0, 15.0),
                impact_rule=rng.choice([0, 1]))


def _values(cls, kw):
    model = cls(**kw)
    return [float(getattr(model, p.name)) for p in cls.parameters()]


def _mp(expr, subs):
    """expr evaluated in 40 digits with the symbols of ``subs``."""
    val = sp.sympify(expr).xreplace({k: sp.Float(v, 45) for k, v in subs.items()})
    return mpmath.mpf(sp.N(val, 40)) if not isinstance(val, (int, float)) else mpmath.mpf(val)


def _close(c, ref, what):
    ref = [float(x) for x in ref]
    scale = max(1e-300, max(abs(x) for x in ref)) if ref else 1.0
    err = max((abs(a - b) for a, b in zip(c, ref)), default=0.0)
    assert err <= REL * scale, f"{what}: |C - sympy| = {err:.3e} > {REL:g} x {scale:.3e}\nC   {list(c)}\nref {ref}"


def _arr(ffi, n):
    return ffi.new("double[]", max(1, n))


def _setup(harness, code, kw):
    ffi, lib = harness
    values = _values(code.cls, kw)
    msg = ffi.new("char[512]")
    assert lib.k_init(code.kind.encode(), ffi.new("double[]", values), len(values), msg) == 0, ffi.string(msg)
    return {code.psym[p.name]: v for p, v in zip(code.cls.parameters(), values)}


def _state(code, rng):
    q = [rng.uniform(-0.3, 0.3) for _ in code.q]
    q[code.phi_i] = rng.uniform(-1.2, 1.2)
    return q, [rng.uniform(-2, 2) for _ in code.v]


SEEDS = range(6)


@pytest.mark.parametrize("seed", SEEDS)
def test_full_coordinate_kernels_equal_their_expressions(harness, code, seed):
    ffi, lib = harness
    rng = random.Random(seed)
    P = _setup(harness, code, _random_params(code.cls, rng))
    n, nc = code.n, code.nc
    q, v = _state(code, rng)
    ag, ag_v = rng.uniform(-8, 8), rng.uniform(-3, 3)
    subs = {**P, **dict(zip(code.q, q)), **dict(zip(code.v, v)), code.ag: ag, code.ag_v: ag_v}
    qa, va = ffi.new("double[]", q), ffi.new("double[]", v)
    out, out2 = _arr(ffi, 64), _arr(ffi, 64)

    lib.k_call(b"mass_matrix", 0, qa, va, 0, 0, out, out2)
    _close(out[0:n * n], [_mp(code.M[i, j], subs) for i in range(n) for j in range(n)], "mass_matrix")
    lib.k_call(b"forces", 0, qa, va, ag, ag_v, out, out2)
    _close(out[0:n], [_mp(code.f[i], subs) for i in range(n)], "forces")
    if lib.k_call(b"inverse_mass_matrix", 0, qa, va, 0, 0, out, out2) == 0:
        Minv = sp.Matrix(n, n, lambda i, j: _mp(code.M[i, j], subs)).inv()
        _close(out[0:n * n], list(Minv), "inverse_mass_matrix")
    if lib.k_call(b"stiff_jacobians", 0, qa, va, 0, 0, out, out2) == 1:
        _close(out[0:n * n], [_mp(code.K[i, j], subs) for i in range(n) for j in range(n)], "K")
        _close(out2[0:n * n], [_mp(code.C[i, j], subs) for i in range(n) for j in range(n)], "C")
    lib.k_call(b"gaps", 0, qa, va, 0, 0, out, out2)
    _close(out[0:nc], [_mp(code.Y[c], subs) for c in range(nc)], "gaps")
    lib.k_call(b"contact_abscissae", 0, qa, va, 0, 0, out, out2)
    _close(out[0:nc], [_mp(code.X[c], subs) for c in range(nc)], "contact_abscissae")
    lib.k_call(b"contact_jacobians", 0, qa, va, 0, 0, out, out2)
    _close(out[0:n * nc], [_mp(code.WN[i, c], subs) for i in range(n) for c in range(nc)], "W_N")
    _close(out2[0:n * nc], [_mp(code.WT[i, c], subs) for i in range(n) for c in range(nc)], "W_T")
    lib.k_call(b"contact_drift", 0, qa, va, 0, 0, out, out2)
    _close(out[0:nc], [_mp(code.aN[c], subs) for c in range(nc)], "a_N")
    _close(out2[0:nc], [_mp(code.aT[c], subs) for c in range(nc)], "a_T")
    lib.k_call(b"energy", 0, qa, va, 0, 0, out, out2)
    _close(out[0:1], [_mp(code.energy, subs)], "energy")


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("mode", [FULL, LEFT, RIGHT, FLIGHT], ids=["full", "left", "right", "flight"])
def test_mode_kernels_equal_their_expressions(harness, code, seed, mode):
    ffi, lib = harness
    rng = random.Random(100 * seed + mode)
    P = _setup(harness, code, _random_params(code.cls, rng))
    md = code.modes[mode]
    n, nc, k = code.n, code.nc, md["k"]
    out, out2 = _arr(ffi, 64), _arr(ffi, 64)
    assert lib.k_call(b"mode_dofs", mode, ffi.NULL, ffi.NULL, 0, 0, out, out2) == k
    assert [int(x) for x in out[0:k]] == md["idx"]
    r = [rng.uniform(-0.3, 0.3) for _ in range(k)]
    if code.phi_i in md["idx"]:
        j = md["idx"].index(code.phi_i)
        r[j] = {LEFT: 1, RIGHT: -1, FLIGHT: rng.choice([-1, 1])}[mode] * rng.uniform(0.01, 1.2)
    rd = [rng.uniform(-2, 2) for _ in range(k)]
    ag, ag_v = rng.uniform(-8, 8), rng.uniform(-3, 3)
    subs = {**P, **dict(zip(md["r"], r)), **dict(zip(md["rd"], rd)), code.ag: ag, code.ag_v: ag_v}
    ra, rda, y = ffi.new("double[]", r or [0.0]), ffi.new("double[]", rd or [0.0]), ffi.new("double[]", (r + rd) or [0.0])

    lib.k_call(b"embed", mode, ra, rda, 0, 0, out, out2)
    _close(out[0:n], [_mp(e, subs) for e in md["q_r"]], "embed q")
    _close(out2[0:n], [_mp(e, subs) for e in md["v_r"]], "embed v")
    lib.k_call(b"mode_jacobian", mode, ra, rda, 0, 0, out, out2)
    _close(out[0:n * k], [_mp(md["J"][i, j], subs) for i in range(n) for j in range(k)], "J")
    _close(out2[0:n], [_mp(e, subs) for e in md["jd"]], "J_dot r_dot")
    # the reduced acceleration: M_r r_dd = f_r solved in 40 digits
    Mr = mpmath.matrix([[_mp(md["Mr"][i, j], subs) for j in range(k)] for i in range(k)]) if k else None
    fr = mpmath.matrix([_mp(md["fr"][i], subs) for i in range(k)]) if k else None
    rdd = list(mpmath.lu_solve(Mr, fr)) if k else []
    if k:
        # backward error of the reduced acceleration: M_r r_dd - f_r against the scale of its terms (a dense
        # solve is exact to the conditioning of M_r, a faithful evaluation to round-off in the terms)
        lib.k_call(b"mode_rhs", mode, y, ffi.NULL, ag, ag_v, out, out2)
        assert list(out[0:k]) == rd
        c_rdd = [mpmath.mpf(x) for x in out[k:2 * k]]
        resid = Mr * mpmath.matrix(c_rdd) - fr
        for i in range(k):
            scale = sum(abs(Mr[i, j] * c_rdd[j]) for j in range(k)) + abs(fr[i])
            assert abs(resid[i]) <= REL * scale, f"mode_rhs row {i}: backward error {float(abs(resid[i]) / scale):.3e}"
    subs.update(dict(zip(md["rdd"], rdd)))
    lib.k_call(b"mode_monitors", mode, y, ffi.NULL, ag, ag_v, out, out2)
    fs, L = _mp(code.mech.force_scale, P), _mp(code.mech.length_scale, P)
    ref = [(_mp(md["lam"][c], subs) / fs) if c in CLOSED[mode] else _mp(md["gaps"][c], subs) / L
           for c in range(nc)] + [math.pi / 2 - abs(float(_mp(md["phi"], subs)))]
    for c in range(nc + 1):           # each event function on its own scale
        _close([out[c]], [ref[c]], f"monitor {c}")
    if CLOSED[mode]:
        _close(out2[0:2], [_mp(md["totals"][0], subs), _mp(md["totals"][1], subs)], "totals")
    for i in range(nc + 1):
        if lib.k_call(b"mode_monitor_one", mode, y, ffi.NULL, float(i), 0, out2, out2) == 1:
            assert out2[0] == out[i], f"monitor_one {i} is not the monitors' value bit for bit"
    lib.k_call(b"mode_outputs", mode, y, ffi.NULL, 0, 0, out, out2)
    refs = md["outs"] if mode != FLIGHT else None
    if refs is not None:
        _close(out[0:len(refs)], [_mp(e, subs) for e in refs], "mode_outputs")


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("mode", [FULL, LEFT, RIGHT], ids=["full", "left", "right"])
def test_modes_satisfy_the_full_dynamics_with_their_contact_forces(harness, code, seed, mode):
    """The derivation itself: the kernels' reduced acceleration and contact forces balance M q_dd - f in every
    row, and the embedding keeps the closed corners on the ground at their rest abscissae."""
    ffi, lib = harness
    rng = random.Random(1000 + 10 * seed + mode)
    _setup(harness, code, _random_params(code.cls, rng))
    n, nc = code.n, code.nc
    out, out2 = _arr(ffi, 64), _arr(ffi, 64)
    k = lib.k_call(b"mode_dofs", mode, ffi.NULL, ffi.NULL, 0, 0, out, out2)
    idx = [int(x) for x in out[0:k]]
    r = [rng.uniform(-0.3, 0.3) for _ in range(k)]
    if code.phi_i in idx:
        r[idx.index(code.phi_i)] = (1 if mode == LEFT else -1) * rng.uniform(0.01, 1.2)
    rd = [rng.uniform(-2, 2) for _ in range(k)]
    ag, ag_v = rng.uniform(-8, 8), rng.uniform(-3, 3)
    lib.k_call(b"embed", mode, ffi.new("double[]", r or [0.0]), ffi.new("double[]", rd or [0.0]), 0, 0, out, out2)
    q, v = np.array(list(out[0:n])), np.array(list(out2[0:n]))
    qa, va = ffi.new("double[]", list(q)), ffi.new("double[]", list(v))
    lib.k_call(b"gaps", 0, qa, va, 0, 0, out, out2)
    gaps = np.array(list(out[0:nc]))
    lib.k_call(b"contact_abscissae", 0, qa, va, 0, 0, out, out2)
    absc = np.array(list(out[0:nc]))
    lib.k_call(b"rest_position", 0, ffi.NULL, ffi.NULL, 0, 0, out, out2)
    rest = ffi.new("double[]", list(out[0:n]))
    lib.k_call(b"contact_abscissae", 0, rest, va, 0, 0, out, out2)
    absc0 = np.array(list(out[0:nc]))
    L = max(1.0, float(np.max(np.abs(absc0))))
    for c in CLOSED[mode]:
        assert abs(gaps[c]) <= 1e-14 * L and abs(absc[c] - absc0[c]) <= 1e-14 * L
    for c in set(range(nc)) - set(CLOSED[mode]):
        assert gaps[c] > 0
    # q_dd = J r_dd + J_dot r_dot
    y = ffi.new("double[]", (r + rd) or [0.0])
    rdd = []
    if k:
        lib.k_call(b"mode_rhs", mode, y, ffi.NULL, ag, ag_v, out, out2)
        rdd = list(out[k:2 * k])
    lib.k_call(b"mode_jacobian", mode, ffi.new("double[]", r or [0.0]), ffi.new("double[]", rd or [0.0]), 0, 0,
               out, out2)
    J = np.array(list(out[0:n * k])).reshape(n, k) if k else np.zeros((n, 0))
    qdd = J @ np.array(rdd) + np.array(list(out2[0:n]))
    lib.k_call(b"mass_matrix", 0, qa, va, 0, 0, out, out2)
    M = np.array(list(out[0:n * n])).reshape(n, n)
    lib.k_call(b"forces", 0, qa, va, ag, ag_v, out, out2)
    f = np.array(list(out[0:n]))
    lib.k_call(b"contact_jacobians", 0, qa, va, 0, 0, out, out2)
    WN, WT = np.array(list(out[0:n * nc])).reshape(n, nc), np.array(list(out2[0:n * nc])).reshape(n, nc)
    lib.k_call(b"contact_forces", mode, qa, va, ag, ag_v, out, out2)
    lam = np.array(list(out[0:nc]))
    lib.k_call(b"mode_monitors", mode, y, ffi.NULL, ag, ag_v, out, out2)
    lam_T = out2[1]
    assert abs(out2[0] - lam.sum()) <= 1e-12 * max(1.0, abs(lam).max())
    residual = M @ qdd - f - WN @ lam - WT[:, CLOSED[mode][0]] * lam_T
    scale = max(np.abs(M @ qdd).max(), np.abs(f).max(), np.abs(WN @ lam).max())
    assert np.abs(residual).max() <= 1e-11 * scale, (residual, scale)
    # the kinetic energy is 1/2 v^T M v
    lib.k_call(b"energy", 0, qa, ffi.new("double[]", [0.0] * n), 0, 0, out, out2)
    e0 = out[0]
    lib.k_call(b"energy", 0, qa, va, 0, 0, out, out2)
    assert abs((out[0] - e0) - 0.5 * v @ M @ v) <= 1e-12 * max(1.0, abs(0.5 * v @ M @ v))


def test_classical_impact_rule_conserves_the_angular_momentum_about_the_landing_corner(harness):
    """The flexible oscillator's classical rule (declared in its file): u_dot continuous, the base rocks on the
    landing corner afterwards, and the angular momentum about that corner is conserved."""
    ffi, lib = harness
    code = gen_models.ModelCode(FlexibleOscillator)
    rng = random.Random(7)
    kw = _random_params(FlexibleOscillator, rng)
    kw["impact_rule"] = 1
    _setup(harness, code, kw)
    n = code.n
    out, out2 = _arr(ffi, 64), _arr(ffi, 64)
    for mode, s_new in ((LEFT, 1), (RIGHT, -1)):
        u, ud, w = rng.uniform(-0.05, 0.05), rng.uniform(-1, 1), -s_new * rng.uniform(0.1, 2)
        lib.k_call(b"embed", mode, ffi.new("double[]", [u, 0.0]), ffi.new("double[]", [ud, w]), 0, 0, out, out2)
        q, v_minus = list(out[0:n]), list(out2[0:n])
        assert lib.k_call(b"classical_impact_velocity", mode, ffi.new("double[]", q), ffi.new("double[]", v_minus),
                          0, 0, out, out2) == 1
        v_plus = np.array(list(out[0:n]))
        assert v_plus[0] == ud
        # rocking on the landing corner: its velocity (the columns of W) is zero after the impact
        lib.k_call(b"contact_jacobians", 0, ffi.new("double[]", q), ffi.NULL, 0, 0, out, out2)
        c = 1 if s_new > 0 else 0
        WN, WT = np.array(list(out[0:2 * n])).reshape(n, 2), np.array(list(out2[0:2 * n])).reshape(n, 2)
        assert abs(WN[:, c] @ v_plus) <= 1e-12 * np.abs(v_plus).max()
        assert abs(WT[:, c] @ v_plus) <= 1e-12 * np.abs(v_plus).max()
        # the angular momentum about the landing corner: the phi row of M v with the corner's moment arm,
        # i.e. the generalized momentum of phi in the new rocking mode minus the u part (u_dot continuous)
        lib.k_call(b"mass_matrix", 0, ffi.new("double[]", q), ffi.NULL, 0, 0, out, out2)
        M = np.array(list(out[0:n * n])).reshape(n, n)
        lib.k_call(b"mode_jacobian", 3 - mode, ffi.new("double[]", [u, 0.0]), ffi.new("double[]", [ud, 0.0]), 0, 0,
                   out, out2)
        J = np.array(list(out[0:2 * n])).reshape(n, 2)
        H = lambda vel: (J[:, 1] @ M @ vel)  # noqa: E731
        assert abs(H(v_plus) - H(np.array(v_minus))) <= 1e-10 * abs(H(np.array(v_minus)))
