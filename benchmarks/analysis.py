"""Closed forms (free rocking), error measures, work-precision interpolation and order fits."""
from __future__ import annotations

import math
import warnings

import numpy as np
from scipy.integrate import quad


# ---------------------------------------------------------------------------------------------- closed forms
def housner_half_swing(p: float, alpha: float, phi_m: float) -> float:
    """Time from |phi| = phi_m (at rest) to phi = 0 of the nonlinear Housner block, by quadrature:
    integral_0^phi_m dphi / (p sqrt(2 [cos(alpha - phi_m) - cos(alpha - phi)])), with phi = phi_m - s^2
    to remove the inverse-square-root singularity and the difference of cosines written as a product."""
    if phi_m <= 0.0:
        return 0.0
    a = alpha - phi_m

    def f(s):
        if s == 0.0:
            return 2.0 / (p * math.sqrt(2.0 * math.sin(a)))
        d = 2.0 * math.sin(a + 0.5 * s * s) * math.sin(0.5 * s * s)
        return 2.0 * s / (p * math.sqrt(2.0 * d))

    with warnings.catch_warnings():     # quad warns that it cannot certify 1e-14; the result is checked
        warnings.simplefilter("ignore")  # against the event-driven impact times to ~1e-13 s in the report
        val, _ = quad(f, 0.0, math.sqrt(phi_m), epsabs=1e-15, epsrel=1e-14, limit=200)
    return val


def free_rocking_closed_form(p: float, alpha: float, r: float, phi_0: float, n: int):
    """Impact times t_1..t_n and pre-impact speeds |phi_dot| of Housner's block released at rest from
    phi_0: t_1 = T(phi_0), t_{k+1} = t_k + 2 T(phi_k) with cos(alpha - phi_k) - cos(alpha) =
    r^(2k) [cos(alpha - phi_0) - cos(alpha)], speeds p sqrt(2[cos(alpha - phi_0) - cos(alpha)]) r^k."""
    e0 = math.cos(alpha - phi_0) - math.cos(alpha)
    w1 = p * math.sqrt(2.0 * e0)
    times, speeds = [], []
    t = housner_half_swing(p, alpha, phi_0)
    for k in range(n):
        times.append(t)
        speeds.append(w1 * r ** k)
        ek = r ** (2 * (k + 1)) * e0
        phi_k = alpha - math.acos(min(1.0, math.cos(alpha) + ek))
        t += 2.0 * housner_half_swing(p, alpha, phi_k)
    return np.array(times), np.array(speeds)


# ---------------------------------------------------------------------------------------------- errors
def first_impact_error(times, ref_times, k: int = 3) -> float:
    """max |t_i - t_i,ref| over the first k impacts of the reference (inf if impacts are missing; nan if
    the reference has none)."""
    ref = np.asarray(ref_times, dtype=float)[:k]
    if ref.size == 0:
        return math.nan
    t = np.asarray(times, dtype=float)
    if t.size < ref.size:
        return math.inf
    return float(np.max(np.abs(t[:ref.size] - ref)))


def errors(sol: dict, ref: dict, names=("phi",), window: int | None = None) -> dict:
    """Errors against the reference on the common grid: ``<name>_end`` = |x(T) - x_ref(T)| and
    ``<name>_max`` = max over the grid points [0, window) of |x - x_ref| (window None: all), for every output
    in ``names``; ``impact3`` = max error of the first three impact times."""
    out = {}
    for name in names:
        a, b = np.asarray(sol[name], float), np.asarray(ref[name], float)
        n = min(a.size, b.size)
        d = np.abs(a[:n] - b[:n])
        d[~np.isfinite(d)] = np.inf
        out[f"{name}_end"] = float(d[-1])
        out[f"{name}_max"] = float(np.max(d[:window] if window else d))
    if "impact_times" in sol and "impact_times" in ref:
        out["impact3"] = first_impact_error(sol["impact_times"], ref["impact_times"])
    return out


# ---------------------------------------------------------------------------------------------- work-precision
def pareto(points):
    """The work-precision front of (time, error) points: sorted by time, each kept point has a smaller
    error than every cheaper point. Points with non-finite error are dropped; errors are floored at 1e-16."""
    pts = sorted((t, max(e, 1e-16)) for t, e in points if math.isfinite(e) and math.isfinite(t) and t > 0)
    front, best = [], math.inf
    for t, e in pts:
        if e < best:
            front.append((t, e))
            best = e
    return front


def time_at_error(points, level: float):
    """Wall time a contender needs to reach error ``level``, interpolated linearly in log-log on its
    work-precision front. Returns (time, how): how = "interp", "cheapest" (its cheapest run is already
    below the level: the time is an upper bound) or "not reached" (time nan)."""
    front = pareto(points)
    if not front:
        return math.nan, "not reached"
    if front[0][1] <= level:
        return front[0][0], "cheapest"
    for (t0, e0), (t1, e1) in zip(front, front[1:]):
        if e1 <= level <= e0:
            x = (math.log(level) - math.log(e0)) / (math.log(e1) - math.log(e0))
            return math.exp(math.log(t0) + x * (math.log(t1) - math.log(t0))), "interp"
    return math.nan, "not reached"


def fit_order(h, err, floor: float = 1e-13):
    """Least-squares slope of log(err) against log(h) over the points with floor < err (and finite).
    Returns (slope, n_points)."""
    h = np.asarray(h, float)
    e = np.asarray(err, float)
    ok = np.isfinite(e) & (e > floor) & np.isfinite(h) & (h > 0)
    if ok.sum() < 2:
        return math.nan, int(ok.sum())
    slope = np.polyfit(np.log(h[ok]), np.log(e[ok]), 1)[0]
    return float(slope), int(ok.sum())
