"""DOPRI5: Dormand-Prince 5(4) with 4th-order dense output (scipy's RK45 coefficients).

Seven function evaluations per step (FSAL) against DOP853's twelve: the cheaper scheme at loose tolerances
(1e-6 and looser), e.g. one step per 0.01 s communication step of an FMU.
"""
from __future__ import annotations


from .rk import ExplicitRK, Tableau, _lincomb

# Dormand-Prince 5(4) (scipy's RK45 coefficients), written out so that importing the stepper does not
# import scipy (cold start of the FMUs).
_A = [
    [],
    [0.2],
    [0.075, 0.225],
    [0.9777777777777777, -3.7333333333333334, 3.5555555555555554],
    [2.9525986892242035, -11.595793324188385, 9.822892851699436, -0.2908093278463649],
    [2.8462752525252526, -10.757575757575758, 8.906422717743473, 0.2784090909090909, -0.2735313036020583],
]
_B = [0.09114583333333333, 0.0, 0.44923629829290207, 0.6510416666666666, -0.322376179245283, 0.13095238095238096]
_C = [0.0, 0.2, 0.3, 0.8, 0.8888888888888888, 1.0]
_E = [-0.0012326388888888888, 0.0, 0.0042527702905061394, -0.03697916666666667, 0.05086379716981132, -0.0419047619047619, 0.025]
_P = [
    [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [-2.8535800653862835, 0.0, 4.023133379230305, -3.7324019615885042, 2.5548038301849423, -1.3744241142186024, 1.3824689317781436],
    [3.0717434641059005, 0.0, -6.249321565289, 10.068970589843675, -6.399112377351017, 3.272657752246729, -3.764937863556287],
    [-1.1270175653862835, 0.0, 2.675424484351598, -5.685526961588504, 3.5219323679207912, -1.7672812570757455, 2.382468931778144],
]



class _DOPRI5Tableau(Tableau):
    name = "DOPRI5"
    order = 5
    error_order = 4
    n_stages = 7                       # 6 stages + f(t + h, y_new)
    A = _A + [_B]
    B = _B
    C = _C + [1.0]
    E = _E
    P = _P

    def error_sources(self, names, j):
        return [_lincomb(self.E, names, j)]

    def error_norm_source(self, n):
        lines = [f"p{j} = er{j} / s{j}" for j in range(n)]
        lines.append("err = abs(h) * sqrt((" + " + ".join(f"p{j}*p{j}" for j in range(n)) + f") / {n})")
        return lines

    def dense_sources(self, j):
        names = [f"k{s}" for s in range(7)]
        return [f"h*{_lincomb(row, names, j)}" for row in self.P]

    def interpolant_source(self, n):
        # y0 + x (q0 + x (q1 + x (q2 + x q3))) per component, q the dense-output coefficients
        lines = ["def make_interpolant(h, y_old, Q, y_new, f_old, f_new):"]
        for j in range(n):
            lines += [f"    y0_{j} = y_old[{j}]", f"    q0_{j}, q1_{j}, q2_{j}, q3_{j} = Q[{j}]"]
        terms = ", ".join(f"y0_{j} + x * (q0_{j} + x * (q1_{j} + x * (q2_{j} + x * q3_{j})))" for j in range(n))
        lines += ["    def ev(x):", f"        return [{terms}]", "    return ev"]
        return "\n".join(lines)


class DOPRI5(ExplicitRK):
    """Adaptive Dormand-Prince 5(4) stepper (order 5, dense output of order 4)."""

    tableau = _DOPRI5Tableau()
