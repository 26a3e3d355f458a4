"""DOP853: Dormand-Prince 8(5,3) with 7th-order dense output (Hairer, Norsett & Wanner, 'Solving ODEs I').

Coefficients from scipy (`scipy.integrate._ivp.dop853_coefficients`); the stepper is the float-level
`rocking_model.integrators.rk.ExplicitRK`. The default scheme of the event-driven integrator: cheapest per
accepted digit at tolerances of 1e-7 and tighter.
"""
from __future__ import annotations

import math

from scipy.integrate._ivp import dop853_coefficients as _c

from .rk import ExplicitRK, Tableau, _lincomb


class _DOP853Tableau(Tableau):
    name = "DOP853"
    order = 8
    error_order = 7
    n_stages = _c.N_STAGES + 1          # 12 stages + f(t + h, y_new)
    A = [[float(a) for a in _c.A[s, :s]] for s in range(_c.N_STAGES_EXTENDED)]
    B = [float(b) for b in _c.B]
    C = [float(c) for c in _c.C]
    E3 = [float(e) for e in _c.E3]
    E5 = [float(e) for e in _c.E5]
    D = [[float(d) for d in row] for row in _c.D]

    def error_sources(self, names, j):
        return [_lincomb(self.E5, names, j), _lincomb(self.E3, names, j)]

    def error_norm(self, errs, scale, h):
        e5 = e3 = 0.0
        for j, s in enumerate(scale):
            a, b = errs[2 * j] / s, errs[2 * j + 1] / s
            e5 += a * a
            e3 += b * b
        if e5 == 0.0 and e3 == 0.0:
            return 0.0
        return abs(h) * e5 / math.sqrt((e5 + 0.01 * e3) * len(scale))

    def dense_sources(self, j):
        names = [f"k{s}" for s in range(len(self.A))]
        return [f"h*{_lincomb(row, names, j)}" for row in self.D]

    @staticmethod
    def make_interpolant(h, y_old, Q, y_new, f_old, f_new):
        F = []
        for j, y0 in enumerate(y_old):
            dy = y_new[j] - y0
            F.append((y0, dy, h * f_old[j] - dy, 2.0 * dy - h * (f_new[j] + f_old[j]), *Q[j]))

        def ev(x):
            xm = 1.0 - x
            return [y0 + (((((((F6 * x + F5) * xm + F4) * x + F3) * xm + F2) * x + F1) * xm + F0) * x)
                    for y0, F0, F1, F2, F3, F4, F5, F6 in F]
        return ev


class DOP853(ExplicitRK):
    """Adaptive DOP853 stepper (order 8, error estimate of order 7, dense output of order 7)."""

    tableau = _DOP853Tableau()
