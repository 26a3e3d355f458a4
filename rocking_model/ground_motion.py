"""Horizontal ground accelerations ag(t) [m/s2], positive in +x.

Every ground motion is a callable ag(t) that also tells the integrators where it has kinks or jumps
(`next_breakpoint`), so that the event-driven scheme never integrates across one, and whether it is
constant (`constant`).
"""
from __future__ import annotations

import math
from typing import Callable

import numpy as np

from .validation import check_real


class GroundMotion:
    """Base class: a callable t [s] -> ag [m/s2]."""

    #: True when ag does not depend on t
    constant = False

    def __call__(self, t: float) -> float:
        raise NotImplementedError

    def next_breakpoint(self, t: float) -> float:
        """First time > t at which ag is not smooth (math.inf if none)."""
        return math.inf


class ConstantMotion(GroundMotion):
    """ag(t) = value (the zero-order hold of a co-simulation step)."""

    constant = True

    def __init__(self, value: float):
        self.value = check_real("ag", value)

    def __call__(self, t):
        return self.value


class FunctionMotion(GroundMotion):
    """Wrap a user callable ag(t); `breakpoints` lists its known kinks [s]."""

    def __init__(self, fun: Callable[[float], float], breakpoints=()):
        self.fun = fun
        self._bp = np.sort(np.asarray(breakpoints, dtype=float))

    def __call__(self, t):
        value = float(self.fun(t))
        if not math.isfinite(value):
            raise ValueError(f"ag({t:g}) = {value!r} is not finite; allowed range (-inf, inf)")
        return value

    def next_breakpoint(self, t):
        i = np.searchsorted(self._bp, t, side="right")
        return float(self._bp[i]) if i < self._bp.size else math.inf


class SampledMotion(GroundMotion):
    """Record sampled at times t [s] (strictly increasing), values ag [m/s2]; linear in between,
    zero outside [t[0], t[-1]]."""

    def __init__(self, t, ag):
        t = np.asarray(t, dtype=float)
        ag = np.asarray(ag, dtype=float)
        if t.ndim != 1 or t.shape != ag.shape or t.size < 2:
            raise ValueError("ground motion: t and ag must be 1-D arrays of equal length >= 2, got shapes "
                             f"{t.shape} and {ag.shape}")
        if not (np.all(np.isfinite(t)) and np.all(np.isfinite(ag))):
            raise ValueError("ground motion: t and ag must be finite; allowed range (-inf, inf)")
        if np.any(np.diff(t) <= 0.0):
            raise ValueError("ground motion: t must be strictly increasing")
        self.t, self.ag = t, ag
        self._tl, self._al = t.tolist(), ag.tolist()

    def __call__(self, t):
        tl = self._tl
        if t < tl[0] or t > tl[-1]:
            return 0.0
        i = int(np.searchsorted(self.t, t, side="right")) - 1
        if i >= len(tl) - 1:
            return self._al[-1]
        t0, t1 = tl[i], tl[i + 1]
        a0, a1 = self._al[i], self._al[i + 1]
        return a0 + (a1 - a0) * (t - t0) / (t1 - t0)

    def next_breakpoint(self, t):
        i = int(np.searchsorted(self.t, t, side="right"))
        return float(self.t[i]) if i < self.t.size else math.inf


class SinePulse(GroundMotion):
    """One-sine pulse ag = A sin(omega_p (t - t0)) for t0 <= t <= t0 + 2 pi / omega_p, else 0.

    A [m/s2] amplitude, omega_p [rad/s] circular frequency, t0 [s] start."""

    def __init__(self, A: float, omega_p: float, t0: float = 0.0):
        self.A = check_real("A", A)
        self.omega_p = check_real("omega_p", omega_p, lo=0.0, lo_open=True)
        self.t0 = check_real("t0", t0)
        self.t1 = self.t0 + 2.0 * math.pi / self.omega_p

    def __call__(self, t):
        if t < self.t0 or t > self.t1:
            return 0.0
        return self.A * math.sin(self.omega_p * (t - self.t0))

    def next_breakpoint(self, t):
        for tb in (self.t0, self.t1):
            if tb > t:
                return tb
        return math.inf


def as_ground_motion(ag) -> GroundMotion:
    """Accept a GroundMotion, a number, a callable or a (t, ag) pair of arrays."""
    if isinstance(ag, GroundMotion):
        return ag
    if ag is None:
        return ConstantMotion(0.0)
    if isinstance(ag, (int, float)):
        return ConstantMotion(ag)
    if callable(ag):
        return FunctionMotion(ag)
    if isinstance(ag, (tuple, list)) and len(ag) == 2:
        return SampledMotion(*ag)
    raise ValueError("ground_motion must be a number, a callable ag(t), a (t, ag) pair of arrays or a "
                     f"GroundMotion, got {type(ag).__name__}")
