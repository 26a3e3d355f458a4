"""The generated model kernels against their symbolic derivation, and the derivation against the mechanics.

1. Every C kernel function generated from a model's declaration (rocking_model/engine/gen_models.py) equals the
   sympy expression it was generated from, evaluated in 40-digit arithmetic (mpmath), on random parameters and
   states: the printing, the parameter-only constants, the common subexpressions and the regrouping keep the
   value to 1e-13 relative (of the largest entry of the result). The post-tensioned block is checked at states
   with its tendon taut and slack, the base away from the anchor (x != 0 and a nonzero base offset m->offset,
   which its mode kernels read); where the tendon is near its rest length its expanded force and energy cancel
   terms of size k_t L, and its mode kernels are compared to 1e-13 of those terms (`_tendon_floor`).
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
from rocking_model import FlexibleOscillator, PostTensionedBlock, RigidBlock
from rocking_model.engine import gen_models

mpmath.mp.dps = 40
REL = 1e-13
FULL, LEFT, RIGHT, FLIGHT = 0, 1, 2, 3
CLOSED = {FULL: (0, 1), LEFT: (0,), RIGHT: (1,), FLIGHT: ()}


@pytest.fixture(scope="module")
def harness(tmp_path_factory):
    return kernels(tmp_path_factory.mktemp("kernels"))


@pytest.fixture(scope="module", params=[RigidBlock, FlexibleOscillator, PostTensionedBlock],
                ids=["rigid", "flexible", "post_tensioned"])
def code(request):
    return gen_models.ModelCode(request.param)


def _random_params(cls, rng):
    """Parameters well inside the declared ranges (a physical spread of sizes)."""
    if cls is PostTensionedBlock:
        # a tendon of stiffness 1 to 100 m g per metre, pre-stressed up to twice the weight but to less than
        # k_t h/2 (so that it can slacken); now and then none (the free block) or no pre-stress
        kw = _random_params(RigidBlock, rng)
        w = kw["m"] * kw["g"]
        k_t = 0.0 if rng.random() < 0.15 else rng.uniform(1.0, 100.0) * w
        P0 = 0.0 if rng.random() < 0.15 else rng.uniform(0.0, min(2.0 * w, 0.5 * k_t * kw["h"]) if k_t else 2.0 * w)
        return dict(kw, P0=P0, k_t=k_t)
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


def _close(c, ref, what, floor=0.0):
    """C values ``c`` equal ``ref`` to REL of the largest |ref| (or of ``floor``, when larger: `_tendon_floor`)."""
    ref = [float(x) for x in ref]
    scale = max(1e-300, max(abs(x) for x in ref), floor) if ref else 1.0
    err = max((abs(a - b) for a, b in zip(c, ref)), default=0.0)
    assert err <= REL * scale, f"{what}: |C - sympy| = {err:.3e} > {REL:g} x {scale:.3e}\nC   {list(c)}\nref {ref}"


def _arr(ffi, n):
    return ffi.new("double[]", max(1, n))


def _setup(harness, code, kw):
    ffi, lib = harness
    values = _values(code.cls, kw)
    msg = ffi.new("char[512]")
    assert lib.k_init(code.kind.encode(), ffi.new("double[]", values), len(values), msg) == 0, ffi.string(msg)
    lib.k_set_offset(0.0)
    return {code.psym[p.name]: v for p, v in zip(code.cls.parameters(), values)}


def _state(code, rng, P=None):
    """Random q, v; the post-tensioned block's q drawn by `_tendon_state` (P: its parameters)."""
    q = [rng.uniform(-0.3, 0.3) for _ in code.q]
    q[code.phi_i] = rng.uniform(-1.2, 1.2)
    v = [rng.uniform(-2, 2) for _ in code.v]
    if code.cls is PostTensionedBlock:
        q = _tendon_state(code, rng, P)
    return q, v


def _tendon_force(code, P, q):
    """The tendon's P0 + k_t (L - 2h) at q (negative: slack) and its scale P0 + k_t h [N]."""
    b, h, P0, k_t = (P[code.psym[n]] for n in ("b", "h", "P0", "k_t"))
    x, y, phi = q
    L = math.hypot(x - h * math.sin(phi), y + h * math.cos(phi))
    return P0 + k_t * (L - 2.0 * h), P0 + k_t * h


def _tendon_state(code, rng, P):
    """q = [x, y, phi] of the post-tensioned block anywhere around its rest pose (x up to 1.5 (b + h) either side:
    the ground anchor under the base or well outside it; y from h/2 to 1.3 h), with the tendon taut or slack
    (each half of the time when k_t > 0), at least 5 % of P0 + k_t h from the kink of its force law."""
    b, h, k_t = (P[code.psym[n]] for n in ("b", "h", "k_t"))
    slack = k_t > 0 and rng.random() < 0.5
    for _ in range(10000):
        q = [rng.uniform(-1.5, 1.5) * (b + h), h * rng.uniform(0.5, 1.3), rng.uniform(-1.2, 1.2)]
        T, scale = _tendon_force(code, P, q)
        if abs(T) > 0.05 * scale and (T < 0.0) == slack:
            return q
    raise AssertionError(f"no {'slack' if slack else 'taut'} state found for {P}")


def _tendon_floor(code, P, q):
    """The post-tensioned block's round-off floor at the full state q: the generator expands the tendon's force
    P0 + k_t (L - 2h) into P0 + k_t L - 2h k_t and its energy into terms such as k_t L^2/2 - 2h k_t L + 2h^2 k_t,
    whose terms cancel near the tendon's rest length (at rest in full contact: a force P0, an energy 0). An
    evaluation in doubles then errs by a few ulps of those terms, F = P0 + k_t (L + 2h) [N] in a force, F l in a
    moment (l = 2 (b + h) + |x|, the largest lever arm), F l / b in a contact force (a moment over the half-width)
    and F (L + 2h) in the energy: returns (moment floor [N m], contact-force floor [N], energy floor [J]); zeros
    for the other models."""
    if code.cls is not PostTensionedBlock:
        return 0.0, 0.0, 0.0
    b, h, P0, k_t = (P[code.psym[n]] for n in ("b", "h", "P0", "k_t"))
    x, y, phi = (float(v) for v in q)
    L = math.hypot(x - h * math.sin(phi), y + h * math.cos(phi))
    F = P0 + k_t * (L + 2.0 * h)
    lever = 2.0 * (b + h) + abs(x)
    return F * lever, F * lever / b, F * (L + 2.0 * h)


def _set_offset(harness, code, P, rng, seed):
    """The base offset m->offset [m] of a model whose mode kernels read it (a ground-anchored tendon): 0 for every
    third seed (the driver's value until the base slides), else up to 1.5 (b + h) either side (the ground anchor
    under the base or outside it); 0 for the other models."""
    off = 0.0
    if code.offset is not None and seed % 3:
        b, h = P[code.psym["b"]], P[code.psym["h"]]
        off = rng.uniform(-1.5, 1.5) * (b + h)
    harness[1].k_set_offset(off)
    return off


SEEDS = range(6)


@pytest.mark.parametrize("seed", SEEDS)
def test_full_coordinate_kernels_equal_their_expressions(harness, code, seed):
    ffi, lib = harness
    rng = random.Random(seed)
    P = _setup(harness, code, _random_params(code.cls, rng))
    n, nc = code.n, code.nc
    q, v = _state(code, rng, P)
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
    if code.cls is PostTensionedBlock and mode == FLIGHT:
        r = _tendon_state(code, rng, P)                 # around the rest pose, the tendon taut or slack
    rd = [rng.uniform(-2, 2) for _ in range(k)]
    ag, ag_v = rng.uniform(-8, 8), rng.uniform(-3, 3)
    subs = {**P, **dict(zip(md["r"], r)), **dict(zip(md["rd"], rd)), code.ag: ag, code.ag_v: ag_v}
    off = _set_offset(harness, code, P, rng, seed)
    if code.offset is not None:
        subs[code.offset] = off
    ra, rda, y = ffi.new("double[]", r or [0.0]), ffi.new("double[]", rd or [0.0]), ffi.new("double[]", (r + rd) or [0.0])

    # (the embedding at a zero offset: the driver adds it)
    lib.k_call(b"embed", mode, ra, rda, 0, 0, out, out2)
    _close(out[0:n], [_mp(code._at_zero(e), subs) for e in md["q_r"]], "embed q")
    _close(out2[0:n], [_mp(code._at_zero(e), subs) for e in md["v_r"]], "embed v")
    lib.k_call(b"mode_jacobian", mode, ra, rda, 0, 0, out, out2)
    _close(out[0:n * k], [_mp(code._at_zero(md["J"][i, j]), subs) for i in range(n) for j in range(k)], "J")
    _close(out2[0:n], [_mp(code._at_zero(e), subs) for e in md["jd"]], "J_dot r_dot")
    # the reduced acceleration: M_r r_dd = f_r solved in 40 digits
    Mr = mpmath.matrix([[_mp(md["Mr"][i, j], subs) for j in range(k)] for i in range(k)]) if k else None
    fr = mpmath.matrix([_mp(md["fr"][i], subs) for i in range(k)]) if k else None
    rdd = list(mpmath.lu_solve(Mr, fr)) if k else []
    q_full = [float(_mp(e, subs)) for e in md["q_r"]]       # (with the offset)
    moment_floor, force_floor, energy_floor = _tendon_floor(code, P, q_full)
    if k:
        # backward error of the reduced acceleration: M_r r_dd - f_r against the scale of its terms (a dense
        # solve is exact to the conditioning of M_r, a faithful evaluation to round-off in the terms)
        lib.k_call(b"mode_rhs", mode, y, ffi.NULL, ag, ag_v, out, out2)
        assert list(out[0:k]) == rd
        c_rdd = [mpmath.mpf(x) for x in out[k:2 * k]]
        resid = Mr * mpmath.matrix(c_rdd) - fr
        for i in range(k):
            scale = sum(abs(Mr[i, j] * c_rdd[j]) for j in range(k)) + abs(fr[i]) + moment_floor
            assert abs(resid[i]) <= REL * scale, f"mode_rhs row {i}: backward error {float(abs(resid[i]) / scale):.3e}"
    subs.update(dict(zip(md["rdd"], rdd)))
    lib.k_call(b"mode_monitors", mode, y, ffi.NULL, ag, ag_v, out, out2)
    fs, L = _mp(code.mech.force_scale, P), _mp(code.mech.length_scale, P)
    ref = [(_mp(md["lam"][c], subs) / fs) if c in CLOSED[mode] else _mp(md["gaps"][c], subs) / L
           for c in range(nc)] + [math.pi / 2 - abs(float(_mp(md["phi"], subs)))]
    for c in range(nc + 1):           # each event function on its own scale
        _close([out[c]], [ref[c]], f"monitor {c}", force_floor / float(fs) if c in CLOSED[mode] else 0.0)
    if CLOSED[mode]:
        _close(out2[0:2], [_mp(md["totals"][0], subs), _mp(md["totals"][1], subs)], "totals", force_floor)
    for i in range(nc + 1):
        if lib.k_call(b"mode_monitor_one", mode, y, ffi.NULL, float(i), 0, out2, out2) == 1:
            assert out2[0] == out[i], f"monitor_one {i} is not the monitors' value bit for bit"
    lib.k_call(b"mode_outputs", mode, y, ffi.NULL, 0, 0, out, out2)
    refs = md["outs"] if mode != FLIGHT else None
    if refs is not None:
        _close(out[0:len(refs)], [_mp(e, subs) for e in refs], "mode_outputs", max(force_floor, energy_floor))


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("mode", [FULL, LEFT, RIGHT], ids=["full", "left", "right"])
def test_modes_satisfy_the_full_dynamics_with_their_contact_forces(harness, code, seed, mode):
    """The derivation itself: the kernels' reduced acceleration and contact forces balance M q_dd - f in every
    row, and the embedding keeps the closed corners on the ground at their rest abscissae."""
    ffi, lib = harness
    rng = random.Random(1000 + 10 * seed + mode)
    P = _setup(harness, code, _random_params(code.cls, rng))
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
    # the base where the driver keeps it: the embedding moved by the offset (that the mode kernels read)
    off = _set_offset(harness, code, P, rng, seed)
    q[code.slide_i] += off
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
        assert abs(gaps[c]) <= 1e-14 * L and abs(absc[c] - absc0[c] - off) <= 1e-14 * max(L, abs(off))
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
