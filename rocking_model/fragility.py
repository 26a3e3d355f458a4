"""Lognormal fragility curves: fits from multiple-stripe analysis (maximum likelihood over stripes) and from
incremental dynamic analysis (moments of the log capacities, or a censored maximum likelihood), bootstrap
confidence bands over records, plots, and the parameters as JSON or CSV.

A fragility curve is the probability that a damage state is reached or exceeded at an intensity measure IM = x,

    P(DS | IM = x) = Phi(ln(x/theta)/beta),

with theta the median capacity [the IM's units] and beta the dispersion [1] (the standard deviation of the log
capacity). Baker, J. W. (2015). Efficient analytical fragility function fitting using dynamic structural
analysis. Earthquake Spectra 31(1), 579-599.
"""
from __future__ import annotations

import csv
import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Mapping

import numpy as np

#: [1] bounds on beta of the maximum-likelihood fits: a fit at the upper bound means the exceedance fractions
#: do not rise with the IM (no lognormal fragility describes them); the lower one only keeps the logarithms
#: finite (perfectly separated data are recognised before the fit and given beta = 0)
BETA_BOUNDS = (1e-4, 1e3)


@dataclass(frozen=True)
class FragilityFit:
    """A fitted lognormal fragility P(DS | IM = x) = Phi(ln(x/theta)/beta); unpacks as ``theta, beta = fit``.

    theta: median [IM units] (inf: the damage state was never reached; 0: always reached).
    beta: dispersion [1] (0: a step at theta, perfectly separated stripes; NaN when theta is 0 or inf).
    method: ``"mle"`` (stripes, binomial likelihood), ``"ida_moments"`` or ``"ida_censored_mle"``.
    n: cases used (stripes: the sum of the cases over the stripes; IDA: the records).
    loglik: the maximised log-likelihood (stripes: binomial, with its binomial coefficients; IDA: of the log
        capacities ln C, normal densities, plus ln P(C > c) for each censored record).
    cov: asymptotic covariance of (ln theta, ln beta) (inverse observed information; ida_moments: the normal
        sampling variances beta^2/n and 1/(2 (n - 1))), or None when degenerate.
    name: a label (e.g. the damage state). note: what was degenerate or excluded, "" otherwise."""

    theta: float
    beta: float
    method: str
    n: int
    loglik: float
    cov: tuple | None = field(default=None, compare=False)
    name: str = ""
    note: str = ""

    def __iter__(self):
        yield self.theta
        yield self.beta

    def probability(self, im) -> np.ndarray:
        """P(DS | IM = im) [1] at the IM values ``im`` (array-like, >= 0)."""
        x = np.asarray(im, dtype=float)
        return _curve(self.theta, self.beta, x)

    def interval(self, confidence: float = 0.95) -> dict:
        """Asymptotic (Wald, on the logarithms) intervals {"theta": (lo, hi), "beta": (lo, hi)} from ``cov``
        (NaN without one)."""
        from scipy.stats import norm

        c = _check_fraction("confidence", confidence)
        if self.cov is None:
            return {"theta": (math.nan, math.nan), "beta": (math.nan, math.nan)}
        zq = float(norm.ppf(0.5 + c / 2))
        st, sb = math.sqrt(self.cov[0][0]), math.sqrt(self.cov[1][1])
        return {"theta": (self.theta * math.exp(-zq * st), self.theta * math.exp(zq * st)),
                "beta": (self.beta * math.exp(-zq * sb), self.beta * math.exp(zq * sb))}


def _curve(theta: float, beta: float, x: np.ndarray) -> np.ndarray:
    from scipy.special import ndtr

    if theta == math.inf:
        return np.zeros_like(x)
    if theta == 0.0:
        return np.ones_like(x)
    if beta == 0.0:
        return (x >= theta).astype(float)
    with np.errstate(divide="ignore"):
        return ndtr(np.log(x / theta) / beta)


# --------------------------------------------------------------------------------------------- checks
def _check_fraction(name: str, value) -> float:
    from .validation import check_real

    return check_real(name, value, lo=0.0, hi=1.0, lo_open=True, hi_open=True)


def _counts(name: str, values, size: int) -> np.ndarray:
    a = np.asarray(values, dtype=float)
    if a.ndim == 0:
        a = np.full(size, float(a))
    if a.shape != (size,):
        raise ValueError(f"{name}: one count per stripe ({size}) expected, got shape {a.shape}")
    if not np.all(np.isfinite(a)) or np.any(a != np.round(a)) or np.any(a < 0):
        raise ValueError(f"{name}: counts must be integers >= 0, got {values!r}")
    return a.astype(np.int64)


def _levels(name: str, values) -> np.ndarray:
    x = np.asarray(values, dtype=float)
    if x.ndim == 0:
        x = x.reshape(1)
    if x.ndim != 1 or x.size == 0:
        raise ValueError(f"{name}: a 1-D array of IM levels expected, got shape {x.shape}")
    if not np.all(np.isfinite(x)) or np.any(x <= 0):
        raise ValueError(f"{name}: IM levels must be finite and > 0; allowed range (0, inf)")
    return x


# --------------------------------------------------------------------------------------------- stripes
def _minimise(nll_grad, x0):
    """argmin over (ln theta, ln beta) with ln beta inside BETA_BOUNDS, analytic gradient: SLSQP (a few times
    faster than L-BFGS-B on two parameters: it matters in the bootstrap), L-BFGS-B if it fails."""
    from scipy.optimize import minimize

    bounds = [(None, None), (math.log(BETA_BOUNDS[0]), math.log(BETA_BOUNDS[1]))]
    r = minimize(nll_grad, x0, jac=True, method="SLSQP", bounds=bounds, options={"ftol": 1e-14, "maxiter": 500})
    if not r.success:
        r = minimize(nll_grad, x0, jac=True, method="L-BFGS-B", bounds=bounds,
                     options={"ftol": 1e-15, "gtol": 1e-10, "maxiter": 1000})
    return r


def _exp(m: float) -> float:
    # a median beyond the float range (beta at its upper bound) is inf or 0, not an OverflowError
    return math.exp(min(max(m, -745.0), 709.0)) if abs(m) < 709.0 else (math.inf if m > 0 else 0.0)


def _hessian_cov(nll_grad, x) -> tuple | None:
    """Inverse of the observed information at x (central differences of the analytic gradient)."""
    H = np.empty((2, 2))
    for j in range(2):
        e = np.zeros(2)
        e[j] = 1e-5 * max(1.0, abs(x[j]))
        H[:, j] = (nll_grad(x + e)[1] - nll_grad(x - e)[1]) / (2 * e[j])
    H = 0.5 * (H + H.T)
    try:
        C = np.linalg.inv(H)
    except np.linalg.LinAlgError:
        return None
    if not (np.all(np.isfinite(C)) and C[0, 0] > 0 and C[1, 1] > 0):
        return None
    return ((float(C[0, 0]), float(C[0, 1])), (float(C[1, 0]), float(C[1, 1])))


def _stripes_nll(lx, n, k):
    from scipy.special import log_ndtr

    def f(p):
        m, s = p
        b = math.exp(s)
        z = (lx - m) / b
        lp, lq = log_ndtr(z), log_ndtr(-z)
        # d ln Phi(z)/dz = phi(z)/Phi(z), in logs so that it stays finite far in the tails
        lphi = -0.5 * z * z - 0.5 * math.log(2 * math.pi)
        dz = k * np.exp(lphi - lp) - (n - k) * np.exp(lphi - lq)
        return -float(np.sum(k * lp + (n - k) * lq)), np.array([float(np.sum(dz)) / b, float(np.sum(dz * z))])
    return f


def fit_fragility(im_levels, n_cases, n_exceeded, *, name: str = "", _cov: bool = True) -> FragilityFit:
    """Lognormal fragility by maximum likelihood over stripes (Baker 2015): at each IM level x_j, n_j cases of
    which k_j reached the damage state, the k_j binomial with probability Phi(ln(x_j/theta)/beta).

    im_levels: the stripes' IM values x_j (> 0, at least two distinct).
    n_cases: cases per stripe n_j (integers >= 1; a scalar for all).
    n_exceeded: cases per stripe that reached the damage state, 0 <= k_j <= n_j (0 and all are fine).

    The likelihood is maximised over (ln theta, ln beta) (scipy.optimize, SLSQP) from a probit least-squares
    start. One
    start suffices: in (a, b) = (-ln theta/beta, 1/beta) the log-likelihood is concave (probit regression),
    and the map to (ln theta, ln beta) is one-to-one, so its one stationary point is the maximum. Degenerate
    data are answered without a fit (``note`` says which): no exceedance anywhere, theta = inf; every case
    exceeded, theta = 0 (beta NaN for both); perfectly separated stripes (every stripe with an exceedance
    above every stripe with a non-exceedance), beta = 0 and theta the geometric mean of the two stripes that
    bound the step. Fractions that fall with the IM end at the upper bound of beta (BETA_BOUNDS), noted.
    ValueError naming the argument for bad input."""
    from scipy.special import gammaln

    x = _levels("im_levels", im_levels)
    n = _counts("n_cases", n_cases, x.size)
    k = _counts("n_exceeded", n_exceeded, x.size)
    if np.any(n < 1):
        raise ValueError(f"n_cases: every stripe needs at least one case, got {n.tolist()}")
    if np.any(k > n):
        j = int(np.argmax(k > n))
        raise ValueError(f"n_exceeded: stripe {j} has {k[j]} exceedances of {n[j]} cases; allowed range "
                         "[0, n_cases]")
    if np.unique(x).size < 2:
        raise ValueError("im_levels: at least two distinct IM levels are needed to fit theta and beta")
    N = int(n.sum())
    lc = float(np.sum(gammaln(n + 1) - gammaln(k + 1) - gammaln(n - k + 1)))
    some, short = x[k > 0], x[k < n]
    if some.size == 0:
        return FragilityFit(math.inf, math.nan, "mle", N, lc, None, name,
                            "no case reached the damage state: the median is above every stripe")
    if short.size == 0:
        return FragilityFit(0.0, math.nan, "mle", N, lc, None, name,
                            "every case reached the damage state: the median is below every stripe")
    if some.min() > short.max():
        theta = math.sqrt(some.min() * short.max())
        return FragilityFit(theta, 0.0, "mle", N, lc, None, name,
                            f"perfectly separated stripes: a step between {short.max():g} and {some.min():g}")
    lx = np.log(x)
    # start: probit least squares on the (continuity-corrected) fractions, weighted by the cases
    from scipy.special import ndtri

    y = ndtri((k + 0.5) / (n + 1.0))
    w = n / n.sum()
    mx, my = np.sum(w * lx), np.sum(w * y)
    sxx = np.sum(w * (lx - mx) ** 2)
    slope = np.sum(w * (lx - mx) * (y - my)) / sxx if sxx > 0 else 0.0
    if slope > 0:
        b0 = min(max(1.0 / slope, 0.05), 5.0)
        m0 = mx - my / slope
    else:
        b0, m0 = 1.0, mx
    f = _stripes_nll(lx, n, k)
    r = _minimise(f, np.array([m0, math.log(b0)]))
    m, s = r.x
    note = ""
    if s >= math.log(BETA_BOUNDS[1]) - 1e-6:
        note = "the exceedance fractions do not rise with the IM: beta at its upper bound (BETA_BOUNDS)"
    cov = _hessian_cov(f, r.x) if (_cov and not note) else None
    return FragilityFit(_exp(m), math.exp(s), "mle", N, lc - float(r.fun), cov, name, note)


def stripe_counts(exceeded) -> tuple[np.ndarray, np.ndarray]:
    """(n_cases, n_exceeded) per stripe of a records x stripes matrix of outcomes: True/1 reached the damage
    state, False/0 not, NaN not run (not counted)."""
    e = _outcomes("exceeded", exceeded)
    run = ~np.isnan(e)
    return run.sum(axis=0), np.nansum(e, axis=0).astype(np.int64)


def _outcomes(name: str, exceeded) -> np.ndarray:
    e = np.asarray(exceeded, dtype=float)
    if e.ndim != 2 or e.shape[0] < 1 or e.shape[1] < 1:
        raise ValueError(f"{name}: a records x stripes matrix expected, got shape {e.shape}")
    ok = np.isnan(e) | (e == 0.0) | (e == 1.0)
    if not np.all(ok):
        raise ValueError(f"{name}: outcomes must be True/1 (reached), False/0 (not) or NaN (not run)")
    return e


# --------------------------------------------------------------------------------------------- IDA
def _ida_inputs(capacities, censored_at):
    c = np.asarray(capacities, dtype=float).reshape(-1) if np.ndim(capacities) <= 1 else None
    if c is None or c.size == 0:
        raise ValueError(f"capacities: a 1-D array of IM capacities expected, got shape {np.shape(capacities)}")
    if np.any(np.isnan(c)) or np.any(c <= 0) or np.any(c == -math.inf):
        raise ValueError("capacities: IM capacities must be > 0 (inf: never reached); allowed range (0, inf]")
    cens = None
    if censored_at is not None:
        cens = np.asarray(censored_at, dtype=float)
        if cens.ndim == 0:
            cens = np.full(c.size, float(cens))
        if cens.shape != c.shape:
            raise ValueError(f"censored_at: one value per record ({c.size}) or one for all, got shape {cens.shape}")
        if not np.all(np.isfinite(cens)) or np.any(cens <= 0):
            raise ValueError("censored_at: the highest IM run per record must be finite and > 0")
    return c, cens


def fit_ida(capacities, *, method: str = "moments", censored_at=None, name: str = "") -> FragilityFit:
    """Lognormal fragility from IDA capacities: the IM [its units] at which each record first reaches the
    damage state, inf for a record that never reaches it (up to the highest IM run).

    method "moments" (default): theta = exp(mean ln C), beta = std(ln C) with ddof = 1 over the records that
    reach the damage state; the others (inf) are excluded (counted in ``note``), which biases theta low when
    many never reach it. At least two finite capacities.
    method "censored": maximum likelihood with the records that never reach it right-censored at
    ``censored_at`` (the highest IM run for each record, or one value for all; required when a capacity is
    inf): each such record contributes P(C > censored_at) = 1 - Phi(ln(c/theta)/beta).
    ValueError naming the argument for bad input."""
    from scipy.special import log_ndtr

    c, cens = _ida_inputs(capacities, censored_at)
    if method not in ("moments", "censored"):
        raise ValueError(f"method = {method!r} is not supported; allowed values: 'moments', 'censored'")
    fin = np.isfinite(c)
    lc = np.log(c[fin])
    if method == "moments":
        if lc.size < 2:
            raise ValueError(f"capacities: at least two records must reach the damage state (finite capacities), "
                             f"got {lc.size}")
        m, b = float(np.mean(lc)), float(np.std(lc, ddof=1))
        note = f"{int((~fin).sum())} of {c.size} records never reached the damage state: excluded" if not fin.all() else ""
        if b == 0.0:
            return FragilityFit(math.exp(m), 0.0, "ida_moments", int(lc.size), math.nan, None, name,
                                (note + "; " if note else "") + "equal capacities: beta = 0")
        z = (lc - m) / b
        ll = float(np.sum(-0.5 * z * z - 0.5 * math.log(2 * math.pi) - math.log(b)))
        cov = ((b * b / lc.size, 0.0), (0.0, 1.0 / (2.0 * (lc.size - 1))))
        return FragilityFit(math.exp(m), b, "ida_moments", int(lc.size), ll, cov, name, note)
    if not fin.all() and cens is None:
        raise ValueError("censored_at: needed by method 'censored' when a capacity is inf (the highest IM run for "
                         "each record that never reached the damage state)")
    lcc = np.log(cens[~fin]) if cens is not None else np.zeros(0)
    if lc.size < 1 or (lc.size < 2 and lcc.size == 0):
        raise ValueError(f"capacities: at least two records (one reaching the damage state) are needed, "
                         f"got {lc.size} finite of {c.size}")

    def f(p):
        m, s = p
        b = math.exp(s)
        z = (lc - m) / b
        zc = (lcc - m) / b
        lq = log_ndtr(-zc)
        rc = np.exp(-0.5 * zc * zc - 0.5 * math.log(2 * math.pi) - lq)     # phi/(1 - Phi) at the censoring
        nll = float(np.sum(0.5 * z * z) + lc.size * (0.5 * math.log(2 * math.pi) + s) - np.sum(lq))
        gm = -float(np.sum(z)) / b - float(np.sum(rc)) / b
        gs = lc.size - float(np.sum(z * z)) - float(np.sum(rc * zc))
        return nll, np.array([gm, gs])

    if lc.size >= 2 and np.std(lc) > 0:
        x0 = np.array([np.mean(lc), math.log(np.std(lc, ddof=1))])
    else:
        x0 = np.array([float(np.mean(np.concatenate([lc, lcc]))), math.log(0.5)])
    r = _minimise(f, x0)
    note = f"{int((~fin).sum())} of {c.size} records never reached the damage state: censored" if not fin.all() else ""
    if r.x[1] >= math.log(BETA_BOUNDS[1]) - 1e-6:
        note = (note + "; " if note else "") + "beta at its upper bound (BETA_BOUNDS)"
    return FragilityFit(_exp(r.x[0]), math.exp(r.x[1]), "ida_censored_mle", int(c.size), -float(r.fun),
                        _hessian_cov(f, r.x), name, note)


# --------------------------------------------------------------------------------------------- bootstrap
@dataclass(frozen=True, eq=False)
class FragilityBands:
    """Bootstrap over records of a fragility fit (`bootstrap`).

    fit: the fit of all the records. thetas, betas: the replicates' parameters (n_boot; NaN beta for a
    replicate where no or every case reached the damage state). confidence: the band's level.
    theta_band, beta_band: (lo, hi) percentile bands. im_grid: IM values; curve_lo, curve_median, curve_hi:
    percentile bands and median of the replicates' curves there. n_degenerate: replicates without a proper
    fit (no, every, or perfectly separated exceedances; IDA: fewer than two capacities)."""

    fit: FragilityFit
    thetas: np.ndarray
    betas: np.ndarray
    confidence: float
    theta_band: tuple
    beta_band: tuple
    im_grid: np.ndarray
    curve_lo: np.ndarray
    curve_median: np.ndarray
    curve_hi: np.ndarray
    n_boot: int
    n_degenerate: int


def _band(values, q_lo, q_hi):
    """Order-statistic band (no interpolation: safe with inf, never narrower than the interpolated one)."""
    v = np.asarray(values, dtype=float)
    v = v[~np.isnan(v)]
    if v.size == 0:
        return (math.nan, math.nan)
    return (float(np.quantile(v, q_lo, method="lower")), float(np.quantile(v, q_hi, method="higher")))


def bootstrap(exceeded=None, im_levels=None, *, capacities=None, n_boot: int = 1000, seed=None, im_grid=None,
              confidence: float = 0.90, ida_method: str = "moments", censored_at=None) -> FragilityBands:
    """Confidence bands of a fragility by bootstrap over records: ``n_boot`` resamples of the records with
    replacement, each fitted as the data.

    Stripes: ``exceeded``, a records x stripes matrix of outcomes (True/1 reached the damage state, False/0
    not, NaN not run), and ``im_levels``, the stripes' IM values; each replicate is fitted by `fit_fragility`.
    IDA: ``capacities`` (one per record, inf never reached), fitted by `fit_ida` with ``ida_method`` (and
    ``censored_at``, resampled with its record).

    seed: an int or numpy Generator (the same seed, the same bands). im_grid: IM values of the curve bands
    (default 100 geometrically spaced values over the stripes or the finite capacities, widened by 1.5 on
    each side). confidence: the bands' level, in (0, 1): the (1 - confidence)/2 and (1 + confidence)/2
    order statistics (the lower and the higher sample, not interpolated) of the replicates."""
    from .validation import check_real

    conf = _check_fraction("confidence", confidence)
    n_boot = int(check_real("n_boot", n_boot, lo=1))
    rng = seed if isinstance(seed, np.random.Generator) else np.random.default_rng(seed)
    if (exceeded is None) == (capacities is None):
        raise ValueError("exceeded, capacities: give either exceeded (with im_levels) or capacities")
    if exceeded is not None:
        e = _outcomes("exceeded", exceeded)
        if im_levels is None:
            raise ValueError("im_levels: needed with exceeded (one IM level per column)")
        x = _levels("im_levels", im_levels)
        if x.size != e.shape[1]:
            raise ValueError(f"im_levels: one level per column of exceeded ({e.shape[1]}), got {x.size}")
        fit = fit_fragility(x, *stripe_counts(e))
        R = e.shape[0]
        span = x

        def one(idx):
            n, k = stripe_counts(e[idx])
            keep = n > 0
            return fit_fragility(x[keep], n[keep], k[keep], _cov=False)
    else:
        c, cens = _ida_inputs(capacities, censored_at)
        fit = fit_ida(c, method=ida_method, censored_at=cens)
        R = c.size
        span = c[np.isfinite(c)]

        def one(idx):
            return fit_ida(c[idx], method=ida_method, censored_at=None if cens is None else cens[idx])
    if im_grid is None:
        im_grid = np.geomspace(span.min() / 1.5, span.max() * 1.5, 100)
    grid = np.asarray(im_grid, dtype=float).reshape(-1)
    if grid.size == 0 or not np.all(np.isfinite(grid)) or np.any(grid < 0):
        raise ValueError("im_grid: finite IM values >= 0 expected")
    thetas, betas = np.empty(n_boot), np.empty(n_boot)
    curves = np.empty((n_boot, grid.size))
    bad = 0
    for i in range(n_boot):
        try:
            f = one(rng.integers(0, R, R))
        except ValueError:              # too few distinct stripes or capacities in this resample
            f = None
        if f is None or not (f.beta > 0.0 and 0.0 < f.theta < math.inf):
            bad += 1
        if f is None:
            thetas[i], betas[i] = math.nan, math.nan
            curves[i] = math.nan
            continue
        thetas[i], betas[i] = f.theta, f.beta
        curves[i] = f.probability(grid)
    lo, hi = (1 - conf) / 2, (1 + conf) / 2
    ok = ~np.isnan(curves[:, 0])
    cl = np.quantile(curves[ok], lo, axis=0, method="lower") if ok.any() else np.full(grid.size, math.nan)
    ch = np.quantile(curves[ok], hi, axis=0, method="higher") if ok.any() else np.full(grid.size, math.nan)
    cm = np.median(curves[ok], axis=0) if ok.any() else np.full(grid.size, math.nan)
    return FragilityBands(fit, thetas, betas, conf, _band(thetas, lo, hi), _band(betas, lo, hi), grid, cl, cm, ch,
                          n_boot, bad)


# --------------------------------------------------------------------------------------------- output
def _named(fits) -> list[tuple[str, FragilityFit]]:
    if isinstance(fits, FragilityFit):
        return [(fits.name or "fit", fits)]
    if isinstance(fits, Mapping):
        items = list(fits.items())
    else:
        items = [(f.name or f"fit {i}", f) for i, f in enumerate(fits)]
    for label, f in items:
        if not isinstance(f, FragilityFit):
            raise ValueError(f"fits: FragilityFit values expected, got {type(f).__name__} for {label!r}")
    return [(str(label), f) for label, f in items]


def _aligned(name: str, values, labels: list[str], single: bool):
    """Per-fit values (observed, bands) in the order of labels: a mapping by label, a sequence, or one value
    when there is one fit."""
    if values is None:
        return [None] * len(labels)
    if isinstance(values, Mapping):
        return [values.get(k) for k in labels]
    if single:
        return [values]
    values = list(values)
    if len(values) != len(labels):
        raise ValueError(f"{name}: one entry per fit ({len(labels)}), got {len(values)}")
    return values


def _finite(x):
    return x if isinstance(x, float) and math.isfinite(x) or isinstance(x, int) else None


def _rows(fits, bands=None) -> list[dict]:
    named = _named(fits)
    bs = _aligned("bands", bands, [k for k, _ in named], isinstance(fits, FragilityFit))
    rows = []
    for (label, f), b in zip(named, bs):
        se = (math.sqrt(f.cov[0][0]), math.sqrt(f.cov[1][1])) if f.cov is not None else (math.nan, math.nan)
        row = {"name": label, "method": f.method, "theta": f.theta, "beta": f.beta, "n": f.n, "loglik": f.loglik,
               "se_ln_theta": se[0], "se_ln_beta": se[1]}
        if b is not None:
            row.update({"confidence": b.confidence, "theta_lo": b.theta_band[0], "theta_hi": b.theta_band[1],
                        "beta_lo": b.beta_band[0], "beta_hi": b.beta_band[1], "n_boot": b.n_boot,
                        "n_degenerate": b.n_degenerate})
        row["note"] = f.note
        rows.append(row)
    return rows


def to_json(fits, path, bands=None) -> Path:
    """Write the fits' parameters to ``path`` as a JSON list of objects (name, method, theta, beta, n, loglik,
    the standard errors of ln theta and ln beta, with ``bands`` the bootstrap bands, note); non-finite numbers
    (theta = inf, NaN) as null. ``fits``: a FragilityFit, a sequence (named by their ``name``) or a mapping
    {label: fit}; ``bands``: FragilityBands aligned likewise."""
    path = Path(path)
    rows = [{k: (_finite(v) if isinstance(v, (int, float)) else v) for k, v in r.items()} for r in _rows(fits, bands)]
    path.write_text(json.dumps(rows, indent=2) + "\n")
    return path


def to_csv(fits, path, bands=None) -> Path:
    """Write the fits' parameters to ``path`` as CSV, one row per fit (the columns of `to_json`; non-finite
    numbers as inf/nan)."""
    return write_rows(_rows(fits, bands), path)


def write_rows(rows: list, path) -> Path:
    """Write dicts as CSV rows to ``path``: the union of their keys as columns (in order of appearance), floats
    by repr (exact, inf/nan as such)."""
    path = Path(path)
    cols: list[str] = []
    for r in rows:
        cols += [k for k in r if k not in cols]
    with path.open("w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=cols)
        w.writeheader()
        for r in rows:
            w.writerow({k: (repr(v) if isinstance(v, float) else v) for k, v in r.items()})
    return path


def plot_fragility(fits, im_grid=None, *, observed=None, bands=None, ax=None, im_label: str = "IM",
                   title: str | None = None, path=None):
    """Plot fragility curves (matplotlib, imported here): each fit's curve, its bootstrap band (shaded) and the
    observed fractions of its stripes (markers). Returns the Axes (and saves the figure to ``path`` if given).

    fits: a FragilityFit, a sequence or a mapping {label: fit}. observed: per fit, (im_levels, n_cases,
    n_exceeded) or (im_levels, fractions), aligned with fits (a mapping by label, a sequence, or one tuple for
    one fit). bands: FragilityBands per fit, aligned likewise. im_grid: IM values of the curves (default:
    0 to 1.5 times the largest median or stripe)."""
    if ax is None:
        from .plotting import _pyplot

        fig, ax = _pyplot().subplots(figsize=(6.4, 4.4))
    named = _named(fits)
    labels = [k for k, _ in named]
    single = isinstance(fits, FragilityFit)
    obs = _aligned("observed", observed, labels, single)
    bs = _aligned("bands", bands, labels, single)
    if im_grid is None:
        pts = [f.theta for _, f in named if 0 < f.theta < math.inf]
        for o in obs:
            if o is not None:
                pts += list(np.asarray(o[0], dtype=float))
        pts = [p for p in pts if 0 < p < math.inf] or [float(b.im_grid.max()) / 1.5 for b in bs if b is not None]
        im_grid = np.linspace(0.0, 1.5 * max(pts) if pts else 1.0, 301)
    grid = np.asarray(im_grid, dtype=float)
    for i, ((label, f), o, b) in enumerate(zip(named, obs, bs)):
        color = f"C{i % 10}"
        text = label if not math.isfinite(f.theta) or math.isnan(f.beta) else \
            f"{label}: theta = {f.theta:.3g}, beta = {f.beta:.2f}"
        ax.plot(grid, f.probability(grid), color=color, label=text)
        if b is not None:
            ax.fill_between(b.im_grid, b.curve_lo, b.curve_hi, color=color, alpha=0.2, lw=0)
        if o is not None:
            xs = np.asarray(o[0], dtype=float)
            frac = np.asarray(o[1], dtype=float) if len(o) == 2 else \
                np.asarray(o[2], dtype=float) / np.asarray(o[1], dtype=float)
            ax.plot(xs, frac, "o", color=color, ms=4, mfc="none")
    ax.set_xlabel(im_label)
    ax.set_ylabel("P(DS | IM)")
    ax.set_ylim(-0.02, 1.02)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="lower right")
    if title:
        ax.set_title(title)
    if path is not None:
        ax.figure.tight_layout()
        ax.figure.savefig(path, dpi=120)
    return ax
