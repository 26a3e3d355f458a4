"""Fragility fitting (rocking_model.fragility): the stripes' maximum likelihood recovers known parameters within
its confidence interval and equals a direct numerical optimisation of the binomial likelihood; IDA moments and
censored maximum likelihood; bootstrap bands; degenerate data; output and plots; bad input."""
import csv
import json
import math

import numpy as np
import pytest
from scipy import optimize
from scipy.stats import binom, norm

from rocking_model.fragility import (FragilityFit, bootstrap, fit_fragility, fit_ida, plot_fragility, stripe_counts,
                                     to_csv, to_json)

THETA, BETA = 0.6, 0.4
LEVELS = np.linspace(0.1, 1.5, 12)


def _stripes(rng, n, levels=LEVELS, theta=THETA, beta=BETA):
    return rng.binomial(n, norm.cdf(np.log(levels / theta) / beta))


# ------------------------------------------------------------------------------------- stripes
def test_mle_recovers_known_parameters_on_a_large_set():
    rng = np.random.default_rng(2015)
    k = _stripes(rng, 5000)
    fit = fit_fragility(LEVELS, 5000, k)
    ci = fit.interval(0.999)
    assert ci["theta"][0] < THETA < ci["theta"][1]
    assert ci["beta"][0] < BETA < ci["beta"][1]
    assert fit.theta == pytest.approx(THETA, rel=0.01) and fit.beta == pytest.approx(BETA, rel=0.03)
    theta, beta = fit
    assert (theta, beta) == (fit.theta, fit.beta) and fit.method == "mle" and fit.n == 12 * 5000


def test_mle_interval_coverage():
    """300 synthetic MSAs of 12 stripes x 20 records: the 90 % Wald intervals (observed information) cover the
    true theta and beta in about 90 % of them (binomial 3-sigma band of 300 trials: 0.85 to 0.95)."""
    rng = np.random.default_rng(7)
    hit_t = hit_b = 0
    fits = 0
    for _ in range(300):
        fit = fit_fragility(LEVELS, 20, _stripes(rng, 20))
        if fit.cov is None:
            continue
        fits += 1
        ci = fit.interval(0.90)
        hit_t += ci["theta"][0] < THETA < ci["theta"][1]
        hit_b += ci["beta"][0] < BETA < ci["beta"][1]
    assert fits >= 295
    assert 0.85 < hit_t / fits < 0.95
    assert 0.85 < hit_b / fits < 0.95


@pytest.mark.parametrize("seed,n", [(1, 10), (2, 3), (3, 40)])
def test_mle_likelihood_equals_a_direct_optimisation(seed, n):
    """The binomial log-likelihood (scipy.stats.binom) maximised over (theta, beta) themselves by Nelder-Mead
    from a grid of starts: the same maximum (to 1e-9) and parameters (to 1e-5)."""
    rng = np.random.default_rng(seed)
    levels = np.geomspace(0.05, 2.0, 8)
    k = _stripes(rng, n, levels)
    fit = fit_fragility(levels, n, k)

    def nll(p):
        th, b = p
        v = -np.sum(binom.logpmf(k, n, norm.cdf(np.log(levels / th) / b))) if th > 0 and b > 0 else math.inf
        return v if math.isfinite(v) else 1e300

    best = min((optimize.minimize(nll, [th, b], method="Nelder-Mead",
                                  options={"xatol": 1e-10, "fatol": 1e-13, "maxiter": 5000})
                for th in (0.1, 0.5, 1.5) for b in (0.1, 0.5, 1.5)), key=lambda r: r.fun)
    assert fit.loglik == pytest.approx(-best.fun, abs=1e-9)
    assert fit.loglik >= -best.fun - 1e-10
    assert fit.theta == pytest.approx(best.x[0], rel=1e-7)           # measured 5e-9
    assert fit.beta == pytest.approx(best.x[1], rel=1e-7)


def test_stripes_with_none_or_all_exceeded_and_degenerate_data():
    n = np.array([10, 10, 10, 10])
    x = np.array([0.2, 0.4, 0.6, 0.8])
    fit = fit_fragility(x, n, [0, 3, 10, 10])            # stripes with none and all: a proper fit
    assert 0.2 < fit.theta < 0.6 and 0 < fit.beta < 1 and fit.note == "" and fit.cov is not None
    f0 = fit_fragility(x, n, 0)
    assert f0.theta == math.inf and math.isnan(f0.beta) and "no case" in f0.note
    assert np.all(f0.probability([0.1, 10.0]) == 0)
    f1 = fit_fragility(x, n, n)
    assert f1.theta == 0.0 and "every case" in f1.note and np.all(f1.probability([0.1, 10.0]) == 1)
    fs = fit_fragility(x, n, [0, 0, 10, 10])
    assert fs.beta == 0.0 and fs.theta == pytest.approx(math.sqrt(0.4 * 0.6)) and "separated" in fs.note
    assert fs.loglik == 0.0                               # the supremum: every outcome certain
    np.testing.assert_array_equal(fs.probability([0.3, 0.5, 0.7]), [0, 1, 1])
    fd = fit_fragility(x, n, [9, 6, 3, 1])                # fractions falling with the IM
    assert "do not rise" in fd.note


def test_stripe_counts_with_missing_runs():
    e = np.array([[0, 1, 1], [0, 0, 1], [np.nan, 1, 1]])
    n, k = stripe_counts(e)
    assert n.tolist() == [2, 3, 3] and k.tolist() == [0, 2, 3]
    assert [a.tolist() for a in stripe_counts(np.array([[True, False]]))] == [[1, 1], [1, 0]]


# ------------------------------------------------------------------------------------- IDA
def test_fit_ida_moments():
    rng = np.random.default_rng(3)
    c = np.exp(rng.normal(math.log(THETA), BETA, 25))
    fit = fit_ida(c)
    assert fit.theta == pytest.approx(math.exp(np.mean(np.log(c))), rel=1e-14)
    assert fit.beta == pytest.approx(np.std(np.log(c), ddof=1), rel=1e-14)
    assert fit.method == "ida_moments" and fit.n == 25 and fit.note == ""
    c2 = np.concatenate([c, [np.inf, np.inf]])
    f2 = fit_ida(c2)
    assert (f2.theta, f2.beta, f2.n) == (fit.theta, fit.beta, 25) and "2 of 27" in f2.note and "excluded" in f2.note


def test_fit_ida_censored():
    rng = np.random.default_rng(4)
    c = np.exp(rng.normal(math.log(THETA), BETA, 40))
    # without censoring: the normal MLE of the logs, std with ddof = 0
    f = fit_ida(c, method="censored")
    assert f.theta == pytest.approx(math.exp(np.mean(np.log(c))), rel=1e-9)
    assert f.beta == pytest.approx(np.std(np.log(c)), rel=1e-8)
    # censored at the highest IM run (per record): against a direct Nelder-Mead on scipy.stats terms
    top = np.where(rng.random(40) < 0.5, 0.8, 1.0)
    cc = np.where(c > top, np.inf, c)
    assert np.isinf(cc).sum() >= 5
    fc = fit_ida(cc, method="censored", censored_at=top)
    fin = np.isfinite(cc)

    def nll(p):
        m, b = p
        if b <= 0:
            return 1e300
        return -(np.sum(norm.logpdf(np.log(cc[fin]), m, b)) + np.sum(norm.logsf(np.log(top[~fin]), m, b)))

    r = optimize.minimize(nll, [0.0, 1.0], method="Nelder-Mead", options={"xatol": 1e-11, "fatol": 1e-13})
    assert fc.loglik == pytest.approx(-r.fun, abs=1e-9)
    assert math.log(fc.theta) == pytest.approx(r.x[0], abs=1e-6) and fc.beta == pytest.approx(r.x[1], rel=1e-6)
    assert fc.n == 40 and "censored" in fc.note and fc.cov is not None


def test_fit_ida_censored_recovers_known_parameters():
    """4000 records censored at IM = 0.7 (about 64 % never reach it below): the censored fit within its 99.9 %
    interval of the truth, the moments of the finite ones far below."""
    rng = np.random.default_rng(5)
    c = np.exp(rng.normal(math.log(THETA), BETA, 4000))
    c[c > 0.7] = np.inf
    fc = fit_ida(c, method="censored", censored_at=0.7)
    ci = fc.interval(0.999)
    assert ci["theta"][0] < THETA < ci["theta"][1] and ci["beta"][0] < BETA < ci["beta"][1]
    assert fit_ida(c).theta < 0.9 * THETA


# ------------------------------------------------------------------------------------- bootstrap
def test_bootstrap_stripes_reproducible_with_a_seed():
    rng = np.random.default_rng(11)
    e = rng.random((30, LEVELS.size)) < norm.cdf(np.log(LEVELS / THETA) / BETA)
    a = bootstrap(e, LEVELS, n_boot=200, seed=42)
    b = bootstrap(e, LEVELS, n_boot=200, seed=42)
    c = bootstrap(e, LEVELS, n_boot=200, seed=43)
    np.testing.assert_array_equal(a.thetas, b.thetas)
    np.testing.assert_array_equal(a.curve_hi, b.curve_hi)
    assert not np.array_equal(a.thetas, c.thetas)
    assert a.fit == fit_fragility(LEVELS, *stripe_counts(e))
    assert a.theta_band[0] < a.fit.theta < a.theta_band[1]
    assert a.beta_band[0] < a.fit.beta < a.beta_band[1]
    assert np.all(a.curve_lo <= a.curve_median) and np.all(a.curve_median <= a.curve_hi)
    assert a.thetas.shape == (200,) and a.n_boot == 200 and a.im_grid.size == 100


def test_bootstrap_ida_and_missing_runs():
    rng = np.random.default_rng(12)
    c = np.exp(rng.normal(math.log(THETA), BETA, 20))
    bm = bootstrap(capacities=c, n_boot=100, seed=1, im_grid=[0.3, 0.6, 1.2], confidence=0.8)
    assert bm.fit == fit_ida(c) and bm.im_grid.tolist() == [0.3, 0.6, 1.2] and bm.n_degenerate == 0
    assert bm.theta_band[0] < THETA < bm.theta_band[1]
    cc = np.where(c > 0.9, np.inf, c)
    bc = bootstrap(capacities=cc, n_boot=50, seed=1, ida_method="censored", censored_at=0.9)
    assert bc.fit.method == "ida_censored_mle"
    e = (rng.random((15, 4)) < 0.5).astype(float)
    e[0, 0] = np.nan
    bs = bootstrap(e, [0.2, 0.4, 0.6, 0.8], n_boot=50, seed=2)
    assert bs.fit.n == 59


# ------------------------------------------------------------------------------------- output, plots
def test_json_csv_and_plot(tmp_path):
    rng = np.random.default_rng(13)
    e = rng.random((20, LEVELS.size)) < norm.cdf(np.log(LEVELS / THETA) / BETA)
    bands = bootstrap(e, LEVELS, n_boot=50, seed=0)
    fits = {"DS1": bands.fit, "overturning": fit_fragility(LEVELS, 20, 0)}
    j = json.loads(to_json(fits, tmp_path / "f.json", bands={"DS1": bands}).read_text())
    assert [r["name"] for r in j] == ["DS1", "overturning"]
    assert j[0]["theta"] == bands.fit.theta and j[0]["theta_lo"] == bands.theta_band[0]
    assert j[1]["theta"] is None and j[1]["beta"] is None and "no case" in j[1]["note"]
    rows = list(csv.DictReader((to_csv(fits, tmp_path / "f.csv")).open()))
    assert float(rows[0]["beta"]) == bands.fit.beta and rows[1]["theta"] == "inf"
    one = json.loads(to_json(FragilityFit(1.0, 0.5, "mle", 10, -3.0, name="x"), tmp_path / "g.json").read_text())
    assert one[0]["name"] == "x" and one[0]["se_ln_theta"] is None
    pytest.importorskip("matplotlib")
    n, k = stripe_counts(e)
    ax = plot_fragility(fits, observed={"DS1": (LEVELS, n, k)}, bands={"DS1": bands}, im_label="PGA [m/s2]",
                        path=tmp_path / "f.png")
    assert (tmp_path / "f.png").stat().st_size > 1000
    assert len(ax.lines) == 3
    import matplotlib.pyplot as plt
    plt.close(ax.figure)


# ------------------------------------------------------------------------------------- bad input
@pytest.mark.parametrize("call,match", [
    (lambda: fit_fragility([0.1, -0.2], 10, [1, 2]), r"^im_levels: .*> 0"),
    (lambda: fit_fragility([0.1, 0.2], 10, [1, 2, 3]), r"^n_exceeded: one count per stripe"),
    (lambda: fit_fragility([0.1, 0.2], [10, 0], [1, 0]), r"^n_cases: every stripe"),
    (lambda: fit_fragility([0.1, 0.2], 10, [1, 11]), r"^n_exceeded: stripe 1 has 11 .*\[0, n_cases\]"),
    (lambda: fit_fragility([0.1, 0.2], 10.5, [1, 2]), r"^n_cases: counts must be integers"),
    (lambda: fit_fragility([0.1, 0.1], 10, [1, 2]), r"^im_levels: at least two distinct"),
    (lambda: fit_ida([0.5, np.nan]), r"^capacities: "),
    (lambda: fit_ida([0.5, np.inf]), r"^capacities: at least two records"),
    (lambda: fit_ida([0.5, 0.6, np.inf], method="censored"), r"^censored_at: needed"),
    (lambda: fit_ida([0.5, 0.6], method="mle"), r"^method = 'mle'"),
    (lambda: fit_ida([0.5, 0.6], method="censored", censored_at=[1.0]), r"^censored_at: one value per record"),
    (lambda: bootstrap(capacities=[0.5, 0.6], n_boot=0), r"^n_boot = 0 is out of range"),
    (lambda: bootstrap(capacities=[0.5, 0.6], confidence=1.0), r"^confidence = 1 is out of range"),
    (lambda: bootstrap([[1, 0]], [0.1, 0.2], capacities=[0.5]), r"^exceeded, capacities: give either"),
    (lambda: bootstrap([[1, 0]]), r"^im_levels: needed"),
    (lambda: bootstrap([[1, 0]], [0.1, 0.2, 0.3]), r"^im_levels: one level per column"),
    (lambda: bootstrap([[1, 2]], [0.1, 0.2]), r"^exceeded: outcomes must be"),
    (lambda: FragilityFit(1.0, 0.5, "mle", 1, 0.0).interval(0.0), r"^confidence = 0 is out of range"),
])
def test_bad_input_names_the_variable(call, match):
    with pytest.raises(ValueError, match=match):
        call()
