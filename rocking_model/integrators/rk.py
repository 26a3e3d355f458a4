"""Adaptive explicit Runge-Kutta steppers for the smooth phases, on Python floats.

The reduced systems of the contact modes are tiny (0 to 8 states), so numpy's per-call overhead (about a
microsecond per operation) would dominate a step. The stage arithmetic of each tableau is therefore
generated once per state size as straight-line Python on floats (`_compile`), which makes a DOP853 step
about 5x cheaper than the same step on numpy arrays. Interface in the style of scipy's ``_ivp``: ``step()``
and ``dense_output()``; states are lists of floats and ``fun(t, y) -> sequence of floats``.

Schemes (one module each, sharing this base): `rocking_model.integrators.dop853` (order 8, 7th-order
dense output) and `rocking_model.integrators.dopri5` (order 5, 4th-order dense output).
"""
from __future__ import annotations

import linecache
import math
from typing import Callable, Sequence

SAFETY = 0.9
MIN_FACTOR = 0.2
MAX_FACTOR = 10.0


def _lincomb(coefs, stage_names, j) -> str:
    """Source of sum_i coefs[i] * k{i}_{j} with the zero coefficients left out."""
    terms = [f"{float(c)!r}*{stage_names[i]}_{j}" for i, c in enumerate(coefs) if c != 0.0]
    return "(" + " + ".join(terms) + ")" if terms else "0.0"


class Tableau:
    """Butcher tableau of an embedded explicit pair with dense output; subclasses give the numbers."""

    name = ""
    order = 0                 #: order of the propagated solution
    error_order = 0           #: order of the embedded error estimate
    n_stages = 0              #: stages of a step; the last one is f(t + h, y_new) (FSAL)
    A: Sequence = ()          #: A[s][:s] for all stages (incl. the extra dense-output stages)
    B: Sequence = ()
    C: Sequence = ()

    def error_sources(self, K, j) -> list[str]:
        """Source of the error-estimate combinations of component j (one or two expressions)."""
        raise NotImplementedError

    def error_norm_source(self, n: int) -> list[str]:
        """Source lines that set ``err`` (the scaled error norm of the step) from the error estimates
        ``er0, er1, ...`` (as listed by `error_sources`), the scales ``s0, s1, ...`` and the step h."""
        raise NotImplementedError

    def dense_sources(self, j) -> list[str]:
        """Source of the dense-output coefficients of component j (given the names of the stages)."""
        raise NotImplementedError

    def interpolant_source(self, n: int) -> str:
        """Source of ``make_interpolant(h, y_old, Q, y_new, f_old, f_new)``, which returns the interpolant
        x -> y (x in [0, 1] across the step) of a state of size n from the coefficients Q of `dense`."""
        raise NotImplementedError


class _Compiled:
    """Straight-line float code of one tableau for one state size n."""

    _cache: dict = {}

    def __init__(self, tab: Tableau, n: int):
        ns = tab.n_stages
        names = [f"k{s}" for s in range(len(tab.A))]
        ys = [f"y{j}" for j in range(n)]
        # t_new is the end of the step as the stepper stores it (t + h up to round-off when the step is
        # clipped to t_bound): the FSAL derivative is evaluated there, so that a restart at (t_new, y_new)
        # computes the same f and goes on bit-identically (`EventDriven` restarts after a state restore)
        lines = ["def rk_step(fun, t, y, f, h, atol, rtol, t_new):"]
        lines.append(f"    {', '.join(ys)}, = y")
        lines.append(f"    {', '.join(f'k0_{j}' for j in range(n))}, = f")
        for s in range(1, ns - 1):
            args = ", ".join(f"y{j} + h*{_lincomb(tab.A[s][:s], names, j)}" for j in range(n))
            lines.append(f"    {', '.join(f'k{s}_{j}' for j in range(n))}, = fun(t + {float(tab.C[s])!r}*h, [{args}])")
        for j in range(n):
            lines.append(f"    yn{j} = y{j} + h*{_lincomb(tab.B, names, j)}")
        lines.append(f"    y_new = [{', '.join(f'yn{j}' for j in range(n))}]")
        last = ns - 1
        lines.append(f"    {', '.join(f'k{last}_{j}' for j in range(n))}, = f_new = fun(t_new, y_new)")
        errs = []
        for j in range(n):
            errs.extend(tab.error_sources(names, j))
        for m, src in enumerate(errs):
            lines.append(f"    er{m} = {src}")
        # mixed error scale atol_j + rtol max(|y_j|, |y_new_j|), then the tableau's norm
        lines.append(f"    {', '.join(f'a{j}' for j in range(n))}, = atol")
        for j in range(n):
            lines.append(f"    s{j} = a{j} + max(abs(y{j}), abs(yn{j})) * rtol")
        lines.extend("    " + line for line in tab.error_norm_source(n))
        allk = ", ".join(f"k{s}_{j}" for s in range(ns) for j in range(n))
        lines.append(f"    return y_new, list(f_new), err, ({allk},)")
        # dense output: the extra stages (if any) and the coefficients
        d = ["def dense(fun, t, y, h, K):"]
        d.append(f"    {', '.join(ys)}, = y")
        d.append(f"    {', '.join(f'k{s}_{j}' for s in range(ns) for j in range(n))}, = K")
        for s in range(ns, len(tab.A)):
            args = ", ".join(f"y{j} + h*{_lincomb(tab.A[s][:s], names, j)}" for j in range(n))
            d.append(f"    {', '.join(f'k{s}_{j}' for j in range(n))}, = fun(t + {float(tab.C[s])!r}*h, [{args}])")
        rows = [tab.dense_sources(j) for j in range(n)]
        d.append("    return [" + ", ".join("[" + ", ".join(r) + "]" for r in rows) + "]")
        src = "\n".join(lines) + "\n\n" + "\n".join(d) + "\n\n" + tab.interpolant_source(n) + "\n"
        scope: dict = {"sqrt": math.sqrt}
        filename = f"<rocking_model generated {tab.name} n={n}>"
        # registered with linecache so that tracebacks and debuggers show the generated lines
        linecache.cache[filename] = (len(src), None, src.splitlines(True), filename)
        exec(compile(src, filename, "exec"), scope)
        self.filename = filename
        self.rk_step = scope["rk_step"]
        self.dense = scope["dense"]
        self.make_interpolant = scope["make_interpolant"]
        self.source = src

    @classmethod
    def get(cls, tab: Tableau, n: int) -> "_Compiled":
        key = (tab.name, n)
        c = cls._cache.get(key)
        if c is None:
            c = cls._cache[key] = cls(tab, n)
        return c


class ExplicitRK:
    """Adaptive stepper for y' = fun(t, y) with mixed error control ``atol[i] + rtol |y_i|``.

    ``step(t_bound)`` takes one accepted step ending at ``t_bound`` at the latest; ``dense_output()`` is the
    interpolant of the last step. ``first_step`` is a guess (estimated when None)."""

    tableau: Tableau
    #: set by `step` when it had to accept a step at the smallest step size with its error above the
    #: tolerance (``failure`` says where); the caller reports it and clears the flag
    failed: bool = False
    failure: str = ""

    def __init__(self, fun: Callable, t0: float, y0, rtol: float, atol, max_step: float = math.inf,
                 first_step: float | None = None, f0=None):
        self.fun = fun
        self.t = float(t0)
        self.y = [float(a) for a in y0]
        self.n = len(self.y)
        self.rtol = rtol
        self.atol = list(atol)
        self.max_step = max_step
        self._code = _Compiled.get(self.tableau, self.n) if self.n else None
        self.f = list(f0) if f0 is not None else (list(fun(self.t, self.y)) if self.n else [])
        self._K = None
        self.h_abs = first_step if first_step is not None else self._initial_step()
        self.h_abs = min(self.h_abs, max_step)
        self.t_old, self.y_old, self.f_old = self.t, self.y, self.f
        self.n_steps = 0
        self.n_rejected = 0
        self._err_exp = -1.0 / (self.tableau.error_order + 1.0)

    def restart(self, fun: Callable, t0: float, y0, first_step: float | None) -> None:
        """Start again at (t0, y0) under a new right-hand side (same size, tolerances and step limit): what
        a new stepper would do, without re-building it."""
        self.fun = fun
        self.t = t0
        self.y = y0
        self.f = list(fun(t0, y0)) if self.n else []
        self._K = None
        if first_step is not None:
            self.h_abs = min(first_step, self.max_step)
        elif self.n:
            self.h_abs = min(self._initial_step(), self.max_step)
        self.t_old, self.y_old, self.f_old = self.t, self.y, self.f

    def _initial_step(self) -> float:
        # Hairer's heuristic (scipy.integrate._ivp.common.select_initial_step)
        if self.n == 0:
            return self.max_step if math.isfinite(self.max_step) else 1.0
        y, f, n = self.y, self.f, self.n
        scale = [a + abs(v) * self.rtol for a, v in zip(self.atol, y)]
        d0 = math.sqrt(sum((v / s) * (v / s) for v, s in zip(y, scale)) / n)
        d1 = math.sqrt(sum((v / s) * (v / s) for v, s in zip(f, scale)) / n)
        h0 = 1e-6 if d0 < 1e-5 or d1 < 1e-5 else 0.01 * d0 / d1
        f1 = self.fun(self.t + h0, [v + h0 * fv for v, fv in zip(y, f)])
        d2 = math.sqrt(sum(((a - b) / s) * ((a - b) / s) for a, b, s in zip(f1, f, scale)) / n) / h0
        if d1 <= 1e-15 and d2 <= 1e-15:
            h1 = max(1e-6, h0 * 1e-3)
        else:
            h1 = (0.01 / max(d1, d2)) ** (1.0 / (self.tableau.order + 1.0))
        return min(100 * h0, h1)

    def step(self, t_bound: float) -> None:
        """Advance by one accepted step, ending at t_bound at the latest."""
        t, y = self.t, self.y
        if self.n == 0:
            h = min(self.max_step, t_bound - t)
            self.t_old, self.y_old, self.f_old = t, y, self.f
            self.t = t_bound if h >= t_bound - t else t + h
            self.n_steps += 1
            return
        min_step = 10.0 * abs(math.nextafter(t, math.inf) - t)
        h_abs = min(self.h_abs, self.max_step)
        rk_step, rtol, atol = self._code.rk_step, self.rtol, self.atol
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
            y_new, f_new, err, K = rk_step(self.fun, t, y, self.f, h, atol, rtol, t_new)
            if err < 1.0 or h_abs <= min_step:
                if not err < 1.0:
                    if not math.isfinite(err):
                        # even the smallest step does not give a finite state: the motion has overflowed
                        raise FloatingPointError(f"{self.tableau.name}: the state is not finite after a step "
                                                 f"of {h:.3g} s from t = {t:.17g} s (y = {y!r})")
                    # accepted only because no smaller step exists: the caller reports it
                    self.failed = True
                    self.failure = (f"{self.tableau.name}: the step of {h:.3g} s from t = {t:.17g} s was accepted "
                                    f"at the smallest step size with its error estimate {err:.3g} times the "
                                    "tolerance: the solution may be inaccurate there")
                factor = MAX_FACTOR if err == 0.0 else min(MAX_FACTOR, SAFETY * err ** self._err_exp)
                if rejected:
                    factor = min(1.0, factor)
                self.h_abs = h_abs * factor
                break
            if not math.isfinite(err):
                err = 1e10
            h_abs *= max(MIN_FACTOR, SAFETY * err ** self._err_exp)
            rejected = True
            self.n_rejected += 1
        self.t_old, self.y_old, self.f_old = t, y, self.f
        self.t, self.y, self.f = t_new, y_new, f_new
        self._K = K
        self.n_steps += 1

    def hermite_mid(self) -> list[float]:
        """Cubic Hermite estimate of y at the middle of the last step (no extra function evaluation)."""
        h = self.t - self.t_old
        return [0.5 * (a + b) + 0.125 * h * (fa - fb)
                for a, b, fa, fb in zip(self.y_old, self.y, self.f_old, self.f)]

    def dense_output(self) -> "DenseOutput":
        """Interpolant of the last step. Built on its first use inside the step (DOP853's needs three more
        function evaluations): read at the end of the step only, e.g. an output time that the step was
        clipped to, it costs nothing."""
        if self.n == 0:
            return DenseOutput(self.t_old, self.t, self.y_old, self.y_old, None)
        code, fun, t_old, y_old, h, K = self._code, self.fun, self.t_old, self.y_old, self.t - self.t_old, self._K
        y_new, f_old, f_new = self.y, self.f_old, self.f

        def make():
            return code.make_interpolant(h, y_old, code.dense(fun, t_old, y_old, h, K), y_new, f_old, f_new)
        return DenseOutput(t_old, self.t, y_old, y_new, make)


class DenseOutput:
    """Interpolant of one step on [t_old, t]: a callable t -> list of floats (exact end values at t)."""

    __slots__ = ("t_old", "t", "h", "y_old", "y_new", "_eval", "_make")

    def __init__(self, t_old, t, y_old, y_new, make):
        self.t_old, self.t, self.h = t_old, t, t - t_old
        self.y_old, self.y_new = y_old, y_new
        self._eval, self._make = None, make

    def __call__(self, t: float) -> list[float]:
        if t == self.t:
            return list(self.y_new)
        ev = self._eval
        if ev is None:
            if self._make is None:               # no state (nothing moves)
                return list(self.y_old)
            ev = self._eval = self._make()
            self._make = None
        x = (t - self.t_old) / self.h if self.h != 0.0 else 0.0
        return ev(x)
