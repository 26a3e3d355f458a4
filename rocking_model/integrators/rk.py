"""Explicit Runge-Kutta scheme for the smooth phases: Dormand-Prince 8(5,3) with 7th-order dense output.

The tableau is scipy's (Hairer, Norsett & Wanner, 'Solving ODEs I', DOP853); the stepper is a lean
re-implementation without the per-call checks of `scipy.integrate.DOP853`, for the small reduced systems
of the contact modes (0 to 8 states). Interface in the style of scipy's `_ivp`: `step()` and
`dense_output()`.
"""
from __future__ import annotations

import math
from typing import Callable

import numpy as np
from scipy.integrate._ivp import dop853_coefficients as _c

_A = _c.A
_B = _c.B
_C = _c.C
_E3 = _c.E3
_E5 = _c.E5
_D = _c.D
_NS = _c.N_STAGES
_NSX = _c.N_STAGES_EXTENDED
_A_STAGES = [np.ascontiguousarray(_A[s, :s]) for s in range(_NSX)]

SAFETY = 0.9
MIN_FACTOR = 0.2
MAX_FACTOR = 10.0
ERROR_EXPONENT = -1.0 / 8.0


class DenseOutput:
    """Interpolant of one DOP853 step on [t_old, t_new]."""

    __slots__ = ("t_old", "t", "h", "y_old", "F")

    def __init__(self, t_old: float, t: float, y_old: np.ndarray, F: np.ndarray):
        self.t_old, self.t, self.h = t_old, t, t - t_old
        self.y_old, self.F = y_old, F

    def __call__(self, t: float) -> np.ndarray:
        x = (t - self.t_old) / self.h if self.h != 0.0 else 0.0
        y = np.zeros_like(self.y_old)
        for i, f in enumerate(self.F[::-1]):
            y += f
            y *= x if i % 2 == 0 else 1.0 - x
        return y + self.y_old


class DOP853:
    """Adaptive DOP853 stepper for y' = fun(t, y).

    Parameters: rtol, atol (mixed error control per component), max_step [s], first_step [s] (a guess;
    estimated when None). `step(t_bound)` takes one accepted step not beyond t_bound.
    """

    def __init__(self, fun: Callable, t0: float, y0: np.ndarray, rtol: float, atol,
                 max_step: float = math.inf, first_step: float | None = None):
        self.fun = fun
        self.t = float(t0)
        self.y = np.array(y0, dtype=float)
        self.n = self.y.size
        self.rtol, self.atol = rtol, atol
        self.max_step = max_step
        self.f = np.asarray(fun(self.t, self.y), dtype=float)
        self.K = np.empty((_NSX, self.n))
        self.h_abs = first_step if first_step is not None else self._initial_step()
        self.h_abs = min(self.h_abs, max_step)
        self.t_old = self.t
        self.y_old = self.y
        self.f_old = self.f
        self.n_steps = 0
        self.n_rejected = 0

    def _initial_step(self) -> float:
        # Hairer's heuristic (scipy.integrate._ivp.common.select_initial_step)
        if self.n == 0:
            return self.max_step if math.isfinite(self.max_step) else 1.0
        scale = self.atol + np.abs(self.y) * self.rtol
        d0 = np.sqrt(np.mean((self.y / scale) ** 2))
        d1 = np.sqrt(np.mean((self.f / scale) ** 2))
        h0 = 1e-6 if d0 < 1e-5 or d1 < 1e-5 else 0.01 * d0 / d1
        y1 = self.y + h0 * self.f
        f1 = np.asarray(self.fun(self.t + h0, y1), dtype=float)
        d2 = np.sqrt(np.mean(((f1 - self.f) / scale) ** 2)) / h0
        if d1 <= 1e-15 and d2 <= 1e-15:
            h1 = max(1e-6, h0 * 1e-3)
        else:
            h1 = (0.01 / max(d1, d2)) ** (1.0 / 8.0)
        return min(100 * h0, h1)

    def _rk_step(self, t, y, f, h):
        K = self.K
        K[0] = f
        fun = self.fun
        for s in range(1, _NS):
            K[s] = fun(t + _C[s] * h, y + h * (_A_STAGES[s] @ K[:s]))
        y_new = y + h * (_B @ K[:_NS])
        f_new = np.asarray(fun(t + h, y_new), dtype=float)
        K[_NS] = f_new
        return y_new, f_new

    def _error_norm(self, h, scale):
        K = self.K[:_NS + 1]
        err5 = (_E5 @ K) / scale
        err3 = (_E3 @ K) / scale
        e5 = float(err5 @ err5)
        e3 = float(err3 @ err3)
        if e5 == 0.0 and e3 == 0.0:
            return 0.0
        return abs(h) * e5 / math.sqrt((e5 + 0.01 * e3) * scale.size)

    def step(self, t_bound: float) -> None:
        """Advance by one accepted step, ending at t_bound at the latest."""
        t, y = self.t, self.y
        if self.n == 0:
            h = min(self.max_step, t_bound - t)
            self.t_old, self.y_old, self.f_old = t, y, self.f
            self.t = t_bound if h >= t_bound - t else t + h
            self.n_steps += 1
            return
        min_step = 10.0 * abs(np.nextafter(t, math.inf) - t)
        h_abs = min(self.h_abs, self.max_step)
        rejected = False
        while True:
            if h_abs < min_step:
                h_abs = min_step
            h = h_abs
            t_new = t + h
            if t_new >= t_bound:
                t_new = t_bound
                h = t_new - t
                h_abs = abs(h)
            y_new, f_new = self._rk_step(t, y, self.f, h)
            scale = self.atol + np.maximum(np.abs(y), np.abs(y_new)) * self.rtol
            err = self._error_norm(h, scale)
            if err < 1.0 or h_abs <= min_step:
                factor = MAX_FACTOR if err == 0.0 else min(MAX_FACTOR, SAFETY * err ** ERROR_EXPONENT)
                if rejected:
                    factor = min(1.0, factor)
                self.h_abs = h_abs * factor
                break
            h_abs *= max(MIN_FACTOR, SAFETY * err ** ERROR_EXPONENT)
            rejected = True
            self.n_rejected += 1
        self.t_old, self.y_old, self.f_old = t, y, self.f
        self.t, self.y, self.f = t_new, y_new, f_new
        self.n_steps += 1

    def dense_output(self) -> DenseOutput:
        """Interpolant of the last step (7th order)."""
        h = self.t - self.t_old
        if self.n == 0:
            return DenseOutput(self.t_old, self.t, self.y_old, np.zeros((0, 0)))
        K = self.K
        for s in range(_NS + 1, _NSX):
            K[s] = self.fun(self.t_old + _C[s] * h, self.y_old + h * (_A_STAGES[s] @ K[:s]))
        F = np.empty((_c.INTERPOLATOR_POWER, self.n))
        dy = self.y - self.y_old
        F[0] = dy
        F[1] = h * self.f_old - dy
        F[2] = 2.0 * dy - h * (self.f + self.f_old)
        F[3:] = h * (_D @ K)
        return DenseOutput(self.t_old, self.t, self.y_old, F)
