"""Intensity measures of a ground-motion record.

The record is integrated as sampled: the acceleration ag(t) [m/s2] is the straight line between the samples
(as the simulators read it, `rocking_model.ground_motion.SampledMotion`), the ground starts at rest at the
first sample, and every integral below is exact for that piecewise-linear ag. No baseline correction is made
unless asked for (``baseline="linear"``). Peaks are taken over the samples.

Definitions (t_0 the first sample, t_N the last, ag the horizontal component; a record's vertical component
is not used):

- ``PGA`` [m/s2]: max |ag(t_i)| over the samples.
- ``PGV`` [m/s]: max |v(t_i)|, v(t) = int_{t_0}^{t} ag ds (ground velocity).
- ``PGD`` [m]: max |d(t_i)|, d(t) = int_{t_0}^{t} v ds (ground displacement).
- ``Arias`` [m/s]: Arias intensity I_A = pi/(2 g) int_{t_0}^{t_N} ag^2 dt.
- ``CAV`` [m/s]: cumulative absolute velocity int_{t_0}^{t_N} |ag| dt (a sign change inside an interval is
  integrated exactly, at its zero crossing).
- ``D5_95`` [s]: significant duration t_95 - t_5, where the normalised cumulative Arias intensity
  I_A(t)/I_A(t_N), exact at the samples, is interpolated linearly between them and t_q is the first time it
  reaches q (NaN for a record without motion).
- ``Sa(T)`` [m/s2]: pseudo-spectral acceleration omega^2 max_i |u(t_i)|, omega = 2 pi/T, of the linear
  oscillator u'' + 2 zeta omega u' + omega^2 u = -ag(t) starting at rest at t_0, over the record's samples
  (no free vibration after the record's end), by the exact recurrence for a piecewise-linear input (Nigam and
  Jennings 1969). ``Sa(0)`` is its limit, PGA.
- ``PGA/(g tan alpha)`` [1]: PGA over the block's uplift acceleration (rigid block: Housner's static
  threshold), alpha the block's slenderness.
- ``PGV p/(g tan alpha)`` [1]: PGV times the block's frequency parameter p [rad/s] over g tan(alpha).

Nigam, N. C. and Jennings, P. C. (1969). Calculation of response spectra from strong-motion earthquake
records. Bulletin of the Seismological Society of America 59(2), 909-922.
"""
from __future__ import annotations

import math
import re
from typing import Iterable

import numpy as np

from .validation import check_real

#: the measures of every record, in this order; then one ``Sa(T)`` per period; then the rocking measures
BASE_MEASURES = ("PGA", "PGV", "PGD", "Arias", "CAV", "D5_95")
ROCKING_MEASURES = ("PGA/(g tan alpha)", "PGV p/(g tan alpha)")
#: units of the measures (``Sa(T)``: m/s2)
UNITS = {"PGA": "m/s2", "PGV": "m/s", "PGD": "m", "Arias": "m/s", "CAV": "m/s", "D5_95": "s", "Sa": "m/s2",
         "PGA/(g tan alpha)": "1", "PGV p/(g tan alpha)": "1"}
#: one-line definition of each measure (``Sa``: of every ``Sa(T)``), as the module docstring states them
DEFINITIONS = {
    "PGA": "peak ground acceleration [m/s2]: max |ag| over the samples",
    "PGV": "peak ground velocity [m/s]: max |v| over the samples, v the exact integral of ag from rest",
    "PGD": "peak ground displacement [m]: max |d| over the samples, d the exact integral of v from rest",
    "Arias": "Arias intensity [m/s]: pi/(2 g) times the integral of ag^2 over the record",
    "CAV": "cumulative absolute velocity [m/s]: the integral of |ag| over the record",
    "D5_95": "significant duration [s]: t_95 - t_5 of the normalised cumulative Arias intensity (linear "
             "between the samples)",
    "Sa": "pseudo-spectral acceleration [m/s2]: omega^2 max |u| over the samples of the damped linear "
          "oscillator of period T = 2 pi/omega under -ag, from rest (Sa(0) = PGA)",
    "PGA/(g tan alpha)": "PGA over the block's g tan(alpha) [1]",
    "PGV p/(g tan alpha)": "PGV times the block's frequency parameter p over its g tan(alpha) [1]",
}
#: [1, relative to the mean step] sample times within this of a uniform grid count as uniform (the tolerance
#: the records readers use for a time step: rocking_model.records.DT_RTOL)
DT_RTOL = 1e-6
#: [1] |x| below which phi_2(x) = (e^x - 1 - x)/x^2 is summed as its series (the closed form cancels there)
_PHI2_SERIES = 0.1

_SA = re.compile(r"^\s*Sa\s*\(\s*([^()]*?)\s*\)\s*$")


def sa_name(period: float) -> str:
    """The name of the pseudo-spectral acceleration at ``period`` [s]: ``f"Sa({period:g})"``."""
    return f"Sa({float(period):g})"


def measure_names(periods: Iterable[float] = (), block=None) -> list[str]:
    """The names `intensity_measures` returns, in its order: PGA, PGV, PGD, Arias, CAV, D5_95, one
    ``Sa(T)`` per period [s] and, when ``block`` is given (a model, or True), the two rocking measures."""
    names = list(BASE_MEASURES) + [sa_name(T) for T in _periods(periods)]
    return names + (list(ROCKING_MEASURES) if block is not None and block is not False else [])


def scale_exponent(name: str) -> int:
    """How the measure ``name`` scales with a factor s on the record: measure(s ag) = s^k measure(ag); k = 1
    for the peaks, CAV, Sa and the rocking measures, 2 for Arias, 0 for D5_95 (a record scaled to a target
    value m* of a measure of value m takes s = (m*/m)^(1/k))."""
    kind = _parse(name)[0]
    return {"Arias": 2, "D5_95": 0}.get(kind, 1)


def _parse(name) -> tuple[str, float | None]:
    """(kind, period or None) of a measure's name, or ValueError listing the accepted names."""
    s = str(name).strip()
    if s in BASE_MEASURES or s in ROCKING_MEASURES:
        return s, None
    m = _SA.match(s)
    if m:
        try:
            T = float(m.group(1))
        except ValueError:
            T = math.nan
        if math.isfinite(T) and T >= 0.0:
            return "Sa", T
    accepted = ", ".join(list(BASE_MEASURES) + ["Sa(T) (T [s] >= 0, e.g. Sa(1))"] + list(ROCKING_MEASURES))
    raise ValueError(f"name = {name!r} is not a known intensity measure; accepted names: {accepted}")


def _periods(periods) -> list[float]:
    if isinstance(periods, (int, float, np.integer, np.floating)):
        periods = [periods]
    out = [check_real("periods", T, lo=0.0) for T in periods]
    labels = [sa_name(T) for T in out]
    if len(set(labels)) != len(labels):
        dup = next(n for n in labels if labels.count(n) > 1)
        raise ValueError(f"periods: two periods give the same name {dup!r} (names use 6 significant digits); "
                         "give each period once")
    return out


# --------------------------------------------------------------------------------------------- the record
def _samples(record) -> tuple[np.ndarray, np.ndarray, float]:
    """(t [s], ag [m/s2], dt [s]) of a Record/SampledMotion or of a pair (t, ag) on a uniform grid."""
    if hasattr(record, "t") and hasattr(record, "ag"):
        t, ag, tn, an = record.t, record.ag, "record.t", "record.ag"
    else:
        try:
            t, ag = record
        except (TypeError, ValueError):
            raise ValueError("record must be a Record (rocking_model.records) or a pair of arrays (t, ag), got "
                             f"{type(record).__name__}") from None
        tn, an = "t", "ag"
    t = np.asarray(t, dtype=float)
    ag = np.asarray(ag, dtype=float)
    if t.ndim != 1 or t.size < 2:
        raise ValueError(f"{tn}: must be a 1-D array of at least 2 sample times [s], got shape {t.shape}")
    if ag.shape != t.shape:
        raise ValueError(f"{an}: must have one value per sample time, shape {t.shape}, got {ag.shape}")
    if not np.all(np.isfinite(t)):
        raise ValueError(f"{tn}: sample times must be finite")
    if not np.all(np.isfinite(ag)):
        raise ValueError(f"{an}: accelerations must be finite")
    h = np.diff(t)
    if np.any(h <= 0.0):
        raise ValueError(f"{tn}: sample times must be strictly increasing")
    dt = (t[-1] - t[0]) / (t.size - 1)
    if np.max(np.abs(h - dt)) > DT_RTOL * dt:
        k = int(np.argmax(np.abs(h - dt)))
        raise ValueError(f"{tn}: the samples must be uniform (one time step), but t[{k + 1}] - t[{k}] = {h[k]:.9g} s "
                         f"against the mean step {dt:.9g} s; resample the record first (Record.resampled(dt))")
    return t, ag, float(dt)


def _baseline(t, ag, baseline):
    if baseline is None:
        return ag
    if baseline == "linear":
        # the least-squares straight line through the acceleration samples, removed (as SeismoSignal's
        # polynomial baseline correction of order 1)
        c = np.polyfit(t - t[0], ag, 1)
        return ag - np.polyval(c, t - t[0])
    raise ValueError(f"baseline = {baseline!r} is not supported; allowed values: None, 'linear'")


def ground_velocity_displacement(t, ag) -> tuple[np.ndarray, np.ndarray]:
    """Ground velocity v [m/s] and displacement d [m] at the samples, exact for ag [m/s2] linear between the
    samples t [s], from rest at t[0]: v_{i+1} = v_i + h (a_i + a_{i+1})/2, d_{i+1} = d_i + h v_i +
    h^2 (a_i/3 + a_{i+1}/6)."""
    t = np.asarray(t, dtype=float)
    ag = np.asarray(ag, dtype=float)
    h = np.diff(t)
    v = np.concatenate(([0.0], np.cumsum(0.5 * h * (ag[:-1] + ag[1:]))))
    d = np.concatenate(([0.0], np.cumsum(h * v[:-1] + h * h * (ag[:-1] / 3.0 + ag[1:] / 6.0))))
    return v, d


def cumulative_arias(t, ag, g: float = 9.81) -> np.ndarray:
    """Arias intensity [m/s] accumulated up to each sample, pi/(2 g) int ag^2 dt, exact for ag linear between
    the samples: each interval adds h (a_i^2 + a_i a_{i+1} + a_{i+1}^2)/3."""
    t = np.asarray(t, dtype=float)
    a0, a1 = ag[:-1], ag[1:]
    inc = np.diff(t) * (a0 * a0 + a0 * a1 + a1 * a1) / 3.0
    return (math.pi / (2.0 * g)) * np.concatenate(([0.0], np.cumsum(inc)))


def _cav(t, ag) -> float:
    a0, a1 = ag[:-1], ag[1:]
    s0, s1 = np.abs(a0), np.abs(a1)
    total = s0 + s1
    same = a0 * a1 >= 0.0
    # a sign change inside the interval: two triangles meeting at the zero crossing, h (a0^2 + a1^2)/(2 (|a0| + |a1|))
    safe = np.where(total > 0.0, total, 1.0)
    per = np.where(same, 0.5 * total, 0.5 * (a0 * a0 + a1 * a1) / safe)
    return float(np.sum(np.diff(t) * per))


def _crossing(t, c, q) -> float:
    """First time the nondecreasing samples c reach q, linear between the samples."""
    k = int(np.searchsorted(c, q, side="left"))
    if k == 0:
        return float(t[0])
    if k >= c.size:
        return float(t[-1])
    c0, c1 = c[k - 1], c[k]
    return float(t[k - 1] + (t[k] - t[k - 1]) * (q - c0) / (c1 - c0))


def significant_duration(t, arias, start: float = 0.05, end: float = 0.95) -> float:
    """t_end - t_start [s] of a cumulative Arias intensity given at the samples t (linear between them)."""
    total = arias[-1]
    if not total > 0.0:
        return math.nan
    c = arias / total
    return _crossing(t, c, end) - _crossing(t, c, start)


def _phi(x):
    """phi_1(x) = (e^x - 1)/x and phi_2(x) = (e^x - 1 - x)/x^2 (complex x != 0), accurate for small |x|."""
    em1 = np.expm1(x)
    phi1 = em1 / x
    small = np.abs(x) < _PHI2_SERIES
    xs = np.where(small, x, 0.0)
    # series sum_k x^k/(k+2)!: 14 terms leave < 1e-17 for |x| < 0.1
    term = np.full_like(xs, 0.5)
    series = term.copy()
    for k in range(1, 14):
        term = term * xs / (k + 2)
        series = series + term
    xl = np.where(small, 1.0, x)
    phi2 = np.where(small, series, (em1 - xl) / (xl * xl))
    return phi1, phi2


def sdof_peak_displacements(ag, dt: float, periods, zeta: float = 0.05) -> np.ndarray:
    """max_i |u(t_i)| [m] of linear oscillators u'' + 2 zeta omega u' + omega^2 u = -ag(t), omega = 2 pi/T, for
    each period T > 0 [s], from rest, under ag [m/s2] sampled every dt [s] and linear in between.

    The exact recurrence for a piecewise-linear input (Nigam and Jennings 1969), written in the oscillator's
    complex modal coordinate z (u = 2 Re z): z_{n+1} = lambda z_n - (dt/(2 i omega_d)) (a_n (phi_1 - phi_2) +
    a_{n+1} phi_2), lambda = e^x, x = (-zeta omega + i omega_d) dt, phi_1 = (e^x - 1)/x, phi_2 = (e^x - 1 -
    x)/x^2, one first-order filter per period (scipy.signal.lfilter)."""
    from scipy.signal import lfilter

    ag = np.asarray(ag, dtype=float)
    T = np.asarray(periods, dtype=float).reshape(-1)
    w = 2.0 * math.pi / T
    wd = w * math.sqrt(1.0 - zeta * zeta)
    mu = -zeta * w + 1j * wd
    x = mu * dt
    lam = np.exp(x)
    phi1, phi2 = _phi(x)
    c = -dt / (2j * wd)
    b0, b1 = c * (phi1 - phi2), c * phi2
    out = np.empty(T.size)
    a0, a1 = ag[:-1], ag[1:]
    for j in range(T.size):
        z = lfilter([1.0], [1.0, -lam[j]], b0[j] * a0 + b1[j] * a1)    # z_1 .. z_N (z_0 = 0)
        out[j] = 2.0 * float(np.max(np.abs(z.real))) if z.size else 0.0
    return out


# --------------------------------------------------------------------------------------------- measures
def _block_terms(block, g: float) -> tuple[float, float]:
    """(g tan alpha [m/s2], p [rad/s]) of a model with attributes alpha and p (its own g when it has one)."""
    try:
        alpha, p = float(block.alpha), float(block.p)
    except (AttributeError, TypeError, ValueError):
        raise ValueError("block must be a model with the attributes alpha [rad] and p [rad/s] (e.g. RigidBlock, "
                         f"PostTensionedBlock), got {type(block).__name__}") from None
    gb = float(getattr(block, "g", g))
    if not (0.0 < alpha < math.pi / 2 and p > 0.0 and gb > 0.0):
        raise ValueError(f"block: alpha = {alpha:g} rad must be in (0, pi/2), p = {p:g} rad/s and g = {gb:g} m/s2 > 0")
    return gb * math.tan(alpha), p


def _check_common(zeta, g):
    zeta = check_real("zeta", zeta, lo=0.0, hi=1.0, hi_open=True)
    g = check_real("g", g, lo=0.0, lo_open=True)
    return zeta, g


def intensity_measures(record, periods: Iterable[float] = (), zeta: float = 0.05, g: float = 9.81, block=None,
                       baseline: str | None = None) -> dict[str, float]:
    """The intensity measures of ``record`` (module docstring: their definitions), as {name: value}.

    record: a `Record` (its horizontal component; the vertical one is not used) or a pair of arrays (t [s],
        ag [m/s2]), uniformly sampled (within 1e-6 of the step; else ValueError naming t).
    periods: oscillator periods T [s] (>= 0), one ``Sa(T)`` [m/s2] each, named ``f"Sa({T:g})"``.
    zeta: damping ratio of the oscillators [1], in [0, 1).
    g: gravity [m/s2] of the Arias intensity (and of the rocking measures when the block has no g of its own).
    block: a model with attributes alpha [rad] and p [rad/s] (RigidBlock, PostTensionedBlock, ...): adds
        ``PGA/(g tan alpha)`` and ``PGV p/(g tan alpha)`` [1], with the block's g.
    baseline: None (default: the record as sampled) or "linear" (the least-squares straight line through the
        acceleration samples is removed first, and every measure is of the corrected record).

    Names in the order of `measure_names`."""
    zeta, g = _check_common(zeta, g)
    Ts = _periods(periods)
    t, ag, dt = _samples(record)
    ag = _baseline(t, ag, baseline)
    v, d = ground_velocity_displacement(t, ag)
    arias = cumulative_arias(t, ag, g)
    pga = float(np.max(np.abs(ag)))
    out = {"PGA": pga, "PGV": float(np.max(np.abs(v))), "PGD": float(np.max(np.abs(d))),
           "Arias": float(arias[-1]), "CAV": _cav(t, ag), "D5_95": significant_duration(t, arias)}
    if Ts:
        pos = [T for T in Ts if T > 0.0]
        peaks = dict(zip(pos, sdof_peak_displacements(ag, dt, pos, zeta))) if pos else {}
        for T in Ts:
            out[sa_name(T)] = pga if T == 0.0 else float((2.0 * math.pi / T) ** 2 * peaks[T])
    if block is not None:
        gta, p = _block_terms(block, g)
        out["PGA/(g tan alpha)"] = pga / gta
        out["PGV p/(g tan alpha)"] = out["PGV"] * p / gta
    return out


def measure(record, name: str, zeta: float = 0.05, g: float = 9.81, block=None,
            baseline: str | None = None) -> float:
    """One intensity measure of ``record`` by its name (``"PGA"``, ``"Sa(1)"``, ``"PGV p/(g tan alpha)"``...;
    `intensity_measures` for the definitions, units and arguments); ValueError listing the accepted names for
    an unknown one. Computes only what the measure needs."""
    kind, T = _parse(name)
    zeta, g = _check_common(zeta, g)
    if kind in ROCKING_MEASURES and block is None:
        raise ValueError(f"name = {name!r} needs block (a model with alpha and p, e.g. RigidBlock)")
    t, ag, dt = _samples(record)
    ag = _baseline(t, ag, baseline)
    if kind == "PGA":
        return float(np.max(np.abs(ag)))
    if kind == "Sa":
        if T == 0.0:
            return float(np.max(np.abs(ag)))
        return float((2.0 * math.pi / T) ** 2 * sdof_peak_displacements(ag, dt, [T], zeta)[0])
    if kind == "CAV":
        return _cav(t, ag)
    if kind in ("Arias", "D5_95"):
        arias = cumulative_arias(t, ag, g)
        return float(arias[-1]) if kind == "Arias" else significant_duration(t, arias)
    if kind == "PGA/(g tan alpha)":
        return float(np.max(np.abs(ag))) / _block_terms(block, g)[0]
    v, d = ground_velocity_displacement(t, ag)
    if kind == "PGV":
        return float(np.max(np.abs(v)))
    if kind == "PGD":
        return float(np.max(np.abs(d)))
    gta, p = _block_terms(block, g)          # PGV p/(g tan alpha)
    return float(np.max(np.abs(v))) * p / gta
