"""Intensity measures (rocking_model.intensity) against closed forms on analytic signals, the exact integrals of
a piecewise-linear record, a fine-step integration of the oscillator, and eqsig where it computes a measure to
the same definition."""
import math

import numpy as np
import pytest
from scipy.integrate import quad, solve_ivp
from scipy.optimize import brentq

from rocking_model import PostTensionedBlock, RigidBlock
from rocking_model.intensity import (BASE_MEASURES, ROCKING_MEASURES, cumulative_arias, ground_velocity_displacement,
                                     intensity_measures, measure, measure_names, scale_exponent,
                                     sdof_peak_displacements)
from rocking_model.records import Record, synthetic_record

G = 9.81


def _record(duration=4.0, dt=0.01, seed=7):
    t, a = synthetic_record(duration=duration, dt=dt, pga_g=0.3, seed=seed, t_rise=0.5, t_strong=2.0)
    return t, a


# ------------------------------------------------------------------------------------- exact integrals
def test_piecewise_linear_integrals_are_exact():
    """A random piecewise-linear record, sign changes inside intervals included: every integral against
    adaptive quadrature of the interpolant (split at the samples and the zero crossings)."""
    rng = np.random.default_rng(3)
    h = 0.02
    t = 0.3 + h * np.arange(31)
    a = rng.normal(0.0, 2.0, t.size)
    f = lambda s: np.interp(s, t, a)
    cross = [t[i] - a[i] * h / (a[i + 1] - a[i]) for i in range(t.size - 1) if a[i] * a[i + 1] < 0]
    pts = sorted(list(t) + cross)
    m = intensity_measures((t, a))
    v, d = ground_velocity_displacement(t, a)
    v_q = [quad(f, t[0], s, points=[p for p in pts if p < s], limit=200)[0] for s in t]
    d_q = [quad(lambda u: (s - u) * f(u), t[0], s, points=[p for p in pts if p < s], limit=200)[0] for s in t]
    np.testing.assert_allclose(v, v_q, rtol=0, atol=1e-13 * max(np.abs(v_q)))
    np.testing.assert_allclose(d, d_q, rtol=0, atol=1e-13 * max(np.abs(d_q)))
    assert m["PGV"] == pytest.approx(np.max(np.abs(v_q)), rel=1e-13)
    assert m["PGD"] == pytest.approx(np.max(np.abs(d_q)), rel=1e-13)
    arias = math.pi / (2 * G) * quad(lambda s: f(s) ** 2, t[0], t[-1], points=pts, limit=200)[0]
    cav = quad(lambda s: abs(f(s)), t[0], t[-1], points=pts, limit=200)[0]
    assert len(cross) > 5
    assert m["Arias"] == pytest.approx(arias, rel=1e-13)
    assert m["CAV"] == pytest.approx(cav, rel=1e-13)
    assert m["PGA"] == np.max(np.abs(a))


def test_cav_zero_crossing_inside_an_interval():
    # three intervals of 1 s: 0 -> 1, 1 -> -1 (crossing at its middle: two triangles of 0.25), -1 -> 0
    m = intensity_measures(([0.0, 1.0, 2.0, 3.0], [0.0, 1.0, -1.0, 0.0]))
    assert m["CAV"] == pytest.approx(1.5, rel=1e-15)
    assert m["Arias"] == pytest.approx(math.pi / (2 * G) * (1 / 3 + 1 / 3 + 1 / 3), rel=1e-15)


# ------------------------------------------------------------------------------------- sine pulse
def test_one_sine_pulse_closed_forms():
    """ag = A sin(W t) over one period Tp, 4000 samples per period: PGA = A, PGV = 2A/W, PGD = 2 pi A/W^2 (at the
    end), Arias = pi/(2g) A^2 Tp/2, CAV = 4A/W, D5-95 from the closed-form cumulative Arias. The integrals of the
    sampled (piecewise-linear) record differ from the sine's by -(W h)^2/12 = -2.1e-7 relative (Arias: twice
    that), the trapezoidal rule's leading term, which they match to 1e-4 of itself."""
    A, f = 3.0, 2.0
    W, Tp = 2 * math.pi * f, 1 / f
    n = 4000
    t = np.linspace(0.0, Tp, n + 1)
    a = A * np.sin(W * t)
    m = intensity_measures((t, a))
    assert m["PGA"] == pytest.approx(A, rel=1e-15)
    eps = (W * Tp / n) ** 2 / 12
    # the leading error term of the sampled sine, to 1e-4 of itself: the integrals are exact for the samples
    for name, exact, c in [("PGV", 2 * A / W, 1), ("PGD", 2 * math.pi * A / W ** 2, 1), ("CAV", 4 * A / W, 1),
                           ("Arias", math.pi / (2 * G) * A ** 2 * Tp / 2, 2)]:
        assert m[name] / exact - 1 == pytest.approx(-c * eps, rel=1e-4), name
    cum = lambda s: (s / 2 - math.sin(2 * W * s) / (4 * W)) / (Tp / 2)
    t5 = brentq(lambda s: cum(s) - 0.05, 0, Tp)
    t95 = brentq(lambda s: cum(s) - 0.95, 0, Tp)
    assert m["D5_95"] == pytest.approx(t95 - t5, rel=2 * eps)        # measured 0.75 eps


def test_significant_duration_of_known_cumulative_arias():
    # constant ag: the cumulative Arias intensity is linear, so the interpolation is exact: 0.9 of the record
    t = np.linspace(1.0, 11.0, 101)
    assert intensity_measures((t, np.full(t.size, 2.0)))["D5_95"] == pytest.approx(9.0, rel=1e-13)
    # ag = c t from 0: cumulative Arias ~ t^3, t_q = T q^(1/3) (linear interpolation of a cubic: O(h^2))
    t = np.linspace(0.0, 10.0, 4001)
    d = intensity_measures((t, 0.5 * t))["D5_95"]
    assert d == pytest.approx(10.0 * (0.95 ** (1 / 3) - 0.05 ** (1 / 3)), rel=1e-6)
    # no motion: undefined
    assert math.isnan(intensity_measures((t, 0 * t))["D5_95"])


# ------------------------------------------------------------------------------------- spectral acceleration
def _harmonic_from_rest(A, W, w, z, t):
    """u(t) of u'' + 2 z w u' + w^2 u = -A sin(W t), u(0) = u'(0) = 0."""
    M = np.array([[w * w - W * W, -2 * z * w * W], [2 * z * w * W, w * w - W * W]])
    C, D = np.linalg.solve(M, [-A, 0.0])              # u_p = C sin + D cos
    wd = w * math.sqrt(1 - z * z)
    E = -D
    F = (z * w * E - C * W) / wd
    return C * np.sin(W * t) + D * np.cos(W * t) + np.exp(-z * w * t) * (E * np.cos(wd * t) + F * np.sin(wd * t))


@pytest.mark.parametrize("T", [0.3, 1.0, 2.5])
def test_sa_of_a_harmonic_against_the_closed_form(T):
    """Steady state + transient from rest under ag = A sin(W t), 8 s at h = 2e-4 s (W h = 0.0025): the
    piecewise-linear input departs from the sine by O((W h)^2) relative."""
    A, W, z = 2.0, 2 * math.pi * 1.3, 0.05
    t = np.arange(0.0, 8.0 + 1e-9, 2e-4)
    w = 2 * math.pi / T
    u = _harmonic_from_rest(A, W, w, z, t)
    sa = intensity_measures((t, A * np.sin(W * t)), [T], zeta=z)[f"Sa({T:g})"]
    assert sa == pytest.approx(w * w * np.max(np.abs(u)), rel=5e-7)     # measured -(W h)^2/12 = -2.2e-7


def test_recurrence_against_solve_ivp_on_the_same_piecewise_linear_input():
    """Interval by interval with DOP853 at rtol 1e-13 (no kink inside a step), a coarse harmonic (h = 0.02 s):
    the recurrence is exact for the piecewise-linear input, whatever the step."""
    h, z = 0.02, 0.03
    t = np.arange(0.0, 3.0 + 1e-9, h)
    a = 1.5 * np.sin(2 * math.pi * 1.1 * t) + 0.5 * np.cos(2 * math.pi * 3.7 * t)
    for T in (0.15, 0.9, 4.0):
        w = 2 * math.pi / T
        y = np.zeros(2)
        umax = 0.0
        for i in range(t.size - 1):
            a0, a1 = a[i], a[i + 1]
            rhs = lambda s, q: [q[1], -(a0 + (a1 - a0) * s / h) - 2 * z * w * q[1] - w * w * q[0]]
            y = solve_ivp(rhs, (0.0, h), y, method="DOP853", rtol=1e-13, atol=1e-16).y[:, -1]
            umax = max(umax, abs(y[0]))
        assert sdof_peak_displacements(a, h, [T], z)[0] == pytest.approx(umax, rel=1e-10)


def test_recurrence_against_fine_step_integration():
    """A synthetic record (3 s at 0.01 s), 12 periods from 0.02 s (2 dt) to 10 s, zeta 0 and 0.05: RK4 with 25
    and 50 substeps per sample interval on the same piecewise-linear input converges to the recurrence at
    fourth order (the error falls 16-fold; below 2e-6 at 50 substeps, largest at 0.02 s)."""
    t, a = _record(duration=3.0)
    h = t[1] - t[0]
    T = np.geomspace(0.02, 10.0, 12)
    w = 2 * math.pi / T
    for z in (0.0, 0.05):
        exact = sdof_peak_displacements(a, h, T, z)
        errors = []
        for k in (25, 50):
            u, v = np.zeros(T.size), np.zeros(T.size)
            umax = np.zeros(T.size)
            s = h / k
            for i in range(t.size - 1):
                a0, a1 = a[i], a[i + 1]
                f = lambda tau, u, v: (v, -(a0 + (a1 - a0) * tau / h) - 2 * z * w * v - w * w * u)
                for j in range(k):
                    tau = j * s
                    k1u, k1v = f(tau, u, v)
                    k2u, k2v = f(tau + s / 2, u + s / 2 * k1u, v + s / 2 * k1v)
                    k3u, k3v = f(tau + s / 2, u + s / 2 * k2u, v + s / 2 * k2v)
                    k4u, k4v = f(tau + s, u + s * k3u, v + s * k3v)
                    u, v = u + s / 6 * (k1u + 2 * k2u + 2 * k3u + k4u), v + s / 6 * (k1v + 2 * k2v + 2 * k3v + k4v)
                umax = np.maximum(umax, np.abs(u))
            errors.append(np.abs(umax / exact - 1))
        e25, e50 = errors
        assert np.all(e50 < 2e-6)
        big = e25 > 1e-11                   # above round-off: fourth order
        assert big.sum() >= 3 and np.all(e25[big] / np.maximum(e50[big], 1e-300) > 12)


@pytest.mark.parametrize("T,z", [(0.5, 0.05), (2.0, 0.0), (1.0, 0.2)])
def test_sa_of_an_impulse(T, z):
    """A triangular pulse of area I over two samples (h = T/20000) against the impulse response
    u = -(I/wd) e^(-z w t) sin(wd t): max |u| = (I/w) exp(-z/sqrt(1-z^2) atan(sqrt(1-z^2)/z))."""
    I = 0.7
    w = 2 * math.pi / T
    h = T / 20000
    t = np.arange(0.0, 1.5 * T, h)
    a = np.zeros(t.size)
    a[1] = I / h
    r = math.sqrt(1 - z * z)
    umax = I / w * math.exp(-z / r * math.atan2(r, z))
    assert measure((t, a), f"Sa({T:g})", zeta=z) == pytest.approx(w * w * umax, rel=5e-8)   # measured < 1e-8


def test_sa_short_period_limit_and_zero_period():
    t, a = _record()
    m = intensity_measures((t, a), [0.0, 1e-4])
    assert m["Sa(0)"] == m["PGA"]
    assert m["Sa(0.0001)"] == pytest.approx(m["PGA"], rel=1e-4)


# ------------------------------------------------------------------------------------- eqsig
def test_against_eqsig():
    """eqsig 1.2.17: velocity by the trapezoidal rule (exact for piecewise-linear ag), displacement by the
    trapezoidal rule of the velocity (differs from the exact integral by h^2 (a_0 - a_k)/12), Arias and CAV
    by the trapezoidal rule of ag^2 and |ag| (differ by the known per-interval terms), Sa by the same
    Nigam-Jennings recurrence (with 2 pi rounded to 6.2831853), D5-95 at the samples (not interpolated)."""
    eqsig = pytest.importorskip("eqsig")
    t, a = _record(duration=10.0, dt=0.005, seed=11)
    h = 0.005
    sig = eqsig.AccSignal(a, h)
    v, d = ground_velocity_displacement(t, a)
    ve, de = eqsig.displacements.calc_velo_and_disp_from_accel_arr(a, h)
    np.testing.assert_allclose(v, ve, rtol=0, atol=1e-13 * np.max(np.abs(v)))
    np.testing.assert_allclose(d, de + h * h * (a[0] - a) / 12, rtol=0, atol=1e-12 * np.max(np.abs(d)))
    m = intensity_measures((t, a), [0.05, 0.2, 0.5, 1.0, 2.0, 4.0])
    assert m["PGV"] == pytest.approx(sig.pgv, rel=1e-12)
    ai = eqsig.im.calc_arias_intensity(sig)[-1] - math.pi / (2 * G) * h / 6 * np.sum(np.diff(a) ** 2)
    assert m["Arias"] == pytest.approx(ai, rel=1e-12)
    a0, a1 = a[:-1], a[1:]
    cross = a0 * a1 < 0
    cav = eqsig.im.calc_cav(sig)[-1] - np.sum(h * np.abs(a0 * a1)[cross] / (np.abs(a0) + np.abs(a1))[cross])
    assert m["CAV"] == pytest.approx(cav, rel=1e-12)
    periods = np.array([0.05, 0.2, 0.5, 1.0, 2.0, 4.0])
    _, _, sa = eqsig.sdof.pseudo_response_spectra(a, h, periods, 0.05)
    np.testing.assert_allclose([m[f"Sa({T:g})"] for T in periods], sa, rtol=3e-8)
    assert m["D5_95"] == pytest.approx(eqsig.im.calc_sig_dur(sig), abs=2 * h)


# ------------------------------------------------------------------------------------- API
def test_names_order_measure_and_scaling():
    t, a = _record()
    block = RigidBlock(b=0.15, h=0.6)
    periods = [0.0, 0.5, 1.0, 2.0]
    m = intensity_measures(Record(t, a), periods, block=block)
    assert list(m) == measure_names(periods, block=block)
    assert measure_names() == list(BASE_MEASURES)
    assert list(m)[-2:] == list(ROCKING_MEASURES)
    assert m == intensity_measures((t, a), periods, block=block)         # a Record and a pair alike
    for name, value in m.items():
        assert measure((t, a), name, block=block) == pytest.approx(value, rel=1e-14), name
    gta = block.g * math.tan(block.alpha)
    assert m["PGA/(g tan alpha)"] == pytest.approx(m["PGA"] / gta, rel=1e-15)
    assert m["PGV p/(g tan alpha)"] == pytest.approx(m["PGV"] * block.p / gta, rel=1e-15)
    assert "PGA/(g tan alpha)" in intensity_measures((t, a), block=PostTensionedBlock())
    s = 1.7
    ms = intensity_measures((t, s * a), periods, block=block)
    for name in m:
        if math.isfinite(m[name]):
            assert ms[name] == pytest.approx(s ** scale_exponent(name) * m[name], rel=1e-12), name
    assert measure((t, a), "Sa(1.0)") == m["Sa(1)"]


def test_vertical_component_is_not_used():
    t, a = _record()
    assert intensity_measures(Record(t, a, vertical=3 * a), [1.0]) == intensity_measures((t, a), [1.0])


def test_linear_baseline():
    t = np.linspace(0.0, 5.0, 501)
    t_, a = _record(duration=5.0)
    line = 0.3 + 0.1 * t
    m = intensity_measures((t, line), [1.0], baseline="linear")
    assert m["PGA"] < 1e-13 and m["Sa(1)"] < 1e-13
    c = np.polyfit(t, a, 1)
    m0 = intensity_measures((t, a - np.polyval(c, t)), [1.0])
    m1 = intensity_measures((t, a + line), [1.0], baseline="linear")
    for k in m0:
        assert m1[k] == pytest.approx(m0[k], rel=1e-9, abs=1e-12), k


@pytest.mark.parametrize("call,name", [
    (lambda: intensity_measures(([0.0, 0.1, 0.25, 0.3], [0, 1, 0, 1])), r"^t: the samples must be uniform"),
    (lambda: intensity_measures(([0.0, 0.1, 0.2], [0, 1])), r"^ag: "),
    (lambda: intensity_measures(([0.0, 0.2, 0.1], [0, 1, 0])), r"^t: .*increasing"),
    (lambda: intensity_measures(([0.0, 0.1, 0.2], [0, np.nan, 0])), r"^ag: .*finite"),
    (lambda: intensity_measures(Record([0.0, 0.1, 0.25], [0, 1, 0])), r"^record\.t: the samples must be uniform"),
    (lambda: intensity_measures(3.0), r"^record must be"),
    (lambda: intensity_measures(([0.0, 0.1], [0, 1]), zeta=1.0), r"^zeta = 1 is out of range"),
    (lambda: intensity_measures(([0.0, 0.1], [0, 1]), g=0.0), r"^g = 0 is out of range"),
    (lambda: intensity_measures(([0.0, 0.1], [0, 1]), [-1.0]), r"^periods = -1 is out of range"),
    (lambda: intensity_measures(([0.0, 0.1], [0, 1]), [1.0, 1.0000001]), r"^periods: two periods"),
    (lambda: intensity_measures(([0.0, 0.1], [0, 1]), block=object()), r"^block must be"),
    (lambda: intensity_measures(([0.0, 0.1], [0, 1]), baseline="cubic"), r"^baseline = 'cubic'"),
    (lambda: measure(([0.0, 0.1], [0, 1]), "PGA/(g tan alpha)"), r"needs block"),
    (lambda: measure(([0.0, 0.1], [0, 1]), "Sa(x)"), r"^name = 'Sa\(x\)' is not a known .*accepted names: PGA"),
    (lambda: measure(([0.0, 0.1], [0, 1]), "pga"), r"^name = 'pga' is not a known"),
])
def test_bad_input_names_the_variable(call, name):
    with pytest.raises(ValueError, match=name):
        call()


def test_cumulative_arias_is_nondecreasing_and_ends_at_arias():
    t, a = _record()
    c = cumulative_arias(t, a)
    assert c[0] == 0.0 and np.all(np.diff(c) >= 0)
    assert c[-1] == intensity_measures((t, a))["Arias"]


# ------------------------------------------------------------------------------------- CLI
def test_cli_im_prints_the_measures(tmp_path, capsys):
    import json

    from rocking_model.cli import main
    from rocking_model.records import read_record, write_csv

    t, a = _record()
    path = write_csv(tmp_path / "rec.csv", t, a, units="m/s2")
    assert main(["im", str(path), "--periods", "0.5", "1", "--b", "0.2", "--h", "1.0", "--json"]) == 0
    got = json.loads(capsys.readouterr().out)
    ref = intensity_measures(read_record(path), [0.5, 1.0], block=RigidBlock(b=0.2, h=1.0))
    assert got == pytest.approx(ref, rel=1e-15)
    assert main(["im", str(path), "--periods", "0.2:1:3", "--scale", "2"]) == 0
    out = capsys.readouterr().out
    assert "Sa(0.6)" in out and f"{2 * ref['PGA']:12.6g} m/s2" in out
    assert main(["im", str(path), "--b", "0.2"]) == 2
    assert "rocking im: error: --b and --h go together" in capsys.readouterr().err
    assert main(["im", str(path), "--zeta", "-0.1"]) == 2
    assert "rocking im: error: zeta = -0.1 is out of range" in capsys.readouterr().err
