"""DOPRI5: Dormand-Prince 5(4) with 4th-order dense output (scipy's RK45 coefficients).

Seven function evaluations per step (FSAL) against DOP853's twelve: the cheaper scheme at loose tolerances
(1e-6 and looser), e.g. one step per 0.01 s communication step of an FMU.
"""
from __future__ import annotations

import math

from scipy.integrate._ivp.rk import RK45 as _RK45

from .rk import ExplicitRK, Tableau, _lincomb


class _DOPRI5Tableau(Tableau):
    name = "DOPRI5"
    order = 5
    error_order = 4
    n_stages = 7                       # 6 stages + f(t + h, y_new)
    A = [[float(a) for a in _RK45.A[s, :s]] for s in range(6)] + [[float(b) for b in _RK45.B]]
    B = [float(b) for b in _RK45.B]
    C = [float(c) for c in _RK45.C] + [1.0]
    E = [float(e) for e in _RK45.E]
    P = [[float(_RK45.P[s, r]) for s in range(7)] for r in range(_RK45.P.shape[1])]

    def error_sources(self, names, j):
        return [_lincomb(self.E, names, j)]

    def error_norm(self, errs, scale, h):
        acc = 0.0
        for e, s in zip(errs, scale):
            a = e / s
            acc += a * a
        return abs(h) * math.sqrt(acc / len(scale))

    def dense_sources(self, j):
        names = [f"k{s}" for s in range(7)]
        return [f"h*{_lincomb(row, names, j)}" for row in self.P]

    @staticmethod
    def make_interpolant(h, y_old, Q, y_new, f_old, f_new):
        rows = list(zip(y_old, Q))

        def ev(x):
            return [y0 + x * (q0 + x * (q1 + x * (q2 + x * q3))) for y0, (q0, q1, q2, q3) in rows]
        return ev


class DOPRI5(ExplicitRK):
    """Adaptive Dormand-Prince 5(4) stepper (order 5, dense output of order 4)."""

    tableau = _DOPRI5Tableau()
