"""Event location on the dense output of a step, as small pure functions (used by the event-driven scheme).

An event function vector ``G(t, y)`` (a model's monitors, `RockingModel.mode_functions`) has one entry per
contact (positive inside the mode: the opening of an open contact, the normal force of a closed one,
normalised) and, last, the overturning margin pi/2 - |phi|. A function *fires* when it reaches zero from
above.

- `locate`: the root of one function in a bracket, to round-off in time (regula falsi, Anderson-Bjorck);
- `earliest_root`: the first of several functions to reach zero in a bracket;
- `first_negative`: the sub-sampling loop (the one place a step is cut into ``n`` sub-intervals): the
  first sub-interval at whose end one of the given functions is at or below zero;
- `dip_search`: a function positive at both ends of a step that may dip below zero inside it;
- `bounce_search`: a function that starts a step at zero and may rise above it briefly (a short bounce);
- `parabola_peak`, `brent_max`: the peak of a quantity inside a step (the friction demand).
"""
from __future__ import annotations

import math
from typing import Callable

def locate(fun: Callable, a: float, ga: float, b: float, gb: float, xtol: float) -> float:
    """Regula falsi with the Anderson-Bjorck modification on a bracket with ga > 0 >= gb; returns a time t
    with fun(t) <= 0 and t - t_root <= xtol.

    Each trial point keeps at least xtol/2 from the ends of the bracket, so that once the estimate has
    converged the next evaluation on the far side of the root closes the bracket: some 6 to 10 evaluations
    from a step-sized bracket to round-off (about 12 to 20 on average in the scenes, against 20 to 25 when
    every iteration also bisects). A bisection follows a trial point that had to be held off an end without
    closing the bracket (a function that starts tangent to zero) and two iterations that did not halve it."""
    side = 0
    half = 0.5 * xtol
    width = b - a
    n_slow = 0
    bisect = False
    while b - a > xtol:
        clamped = False
        if bisect:
            t = 0.5 * (a + b)
        else:
            t = a + (b - a) * (ga / (ga - gb))
            if t < a + half:
                t, clamped = a + half, True
            elif t > b - half:
                t, clamped = b - half, True
        gt = fun(t)
        if gt > 0.0:
            if side == 1:                     # a moved twice in a row: scale down the far value
                m = 1.0 - gt / ga
                gb *= m if m > 0.0 else 0.5
            a, ga = t, gt
            side = 1
        else:
            if side == -1:
                m = 1.0 - gt / gb if gb != 0.0 else 0.5
                ga *= m if m > 0.0 else 0.5
            b, gb = t, gt
            side = -1
        if bisect or b - a <= 0.5 * width:
            width = b - a
            n_slow = 0
        else:
            n_slow += 1
        bisect = clamped or n_slow >= 2
    return b


def earliest_root(G: Callable, dense: Callable, ids, shifts, starts: dict, ta: float, ga: list, tb: float,
                  gb: list, xtol: float) -> tuple[float, int]:
    """(t, i): the earliest root on [ta, tb] among the functions ``ids`` of G on the dense output, function i
    shifted up by ``shifts[i]`` (a disarmed function fires at -shift), each located to ``xtol`` (`locate`);
    ``starts`` gives a later left end (t, G(t)) for functions known to be positive only from there (a
    bounce found by `bounce_search`)."""
    best = None
    for i in ids:
        shift = shifts[i]

        def gi(t, i=i, shift=shift):
            return G(t, dense(t))[i] + shift
        ta_i, ga_i = starts[i] if i in starts and starts[i][0] > ta else (ta, ga)
        te = locate(gi, ta_i, ga_i[i] + shift, tb, gb[i] + shift, xtol)
        if best is None or te < best[0]:
            best = (te, i)
    return best


def first_negative(G: Callable, dense: Callable, t0: float, g0: list, t1: float, ids, n: int):
    """The first of the sub-intervals t0 + (t1 - t0) [j/n, (j+1)/n], j < n - 1, at whose end one of the
    functions ``ids`` of G is at or below zero: (those functions, t_a, g_a, t_b, g_b) of that sub-interval,
    or None. The end t1 itself is not sampled (the caller knows G there)."""
    ta, ga = t0, g0
    for j in range(1, n):
        tj = t0 + (t1 - t0) * j / float(n)
        gj = G(tj, dense(tj))
        neg = [i for i in ids if gj[i] <= 0.0]
        if neg:
            return neg, ta, ga, tj, gj
        ta, ga = tj, gj
    return None


def may_dip(g0: float, gm: float, g1: float) -> bool:
    """Whether a function positive at both ends of a step may reach zero inside: its midpoint lies
    below both ends, or the parabola through (0, g0), (1/2, gm), (1, g1) has its vertex inside the step
    and comes down to less than half the smaller end value."""
    lo = min(g0, g1)
    if gm < lo:
        return True
    c = 2.0 * (g0 + g1) - 4.0 * gm
    if c <= 0.0:
        return False
    b = g1 - g0 - c
    x = -b / (2.0 * c)
    return 0.0 < x < 1.0 and g0 + 0.5 * b * x < 0.5 * lo


def dip_search(stepper, G: Callable, armed, g_prev: list, g_new: list, n: int):
    """A contact function that dips below zero and comes back within the last step of ``stepper`` (a short
    excursion of the base of a vibrating column, the pivot force of a block about to lift off): looked for
    inside the step when a cubic Hermite estimate of the midpoint value says it may (`may_dip`), on ``n``
    sub-intervals. Returns (hits, t_a, t_b, g_a, g_b, dense) of the first sub-interval with a sign change,
    or ([], t_old, t, g_prev, g_new, dense or None)."""
    t0, t1 = stepper.t_old, stepper.t
    tm = 0.5 * (t0 + t1)
    gm = G(tm, stepper.hermite_mid())
    n_contacts = len(g_prev) - 1
    dip = [i for i in range(n_contacts) if armed[i] and may_dip(g_prev[i], gm[i], g_new[i])]
    if not dip:
        return [], t0, t1, g_prev, g_new, None
    dense = stepper.dense_output()
    found = first_negative(G, dense, t0, g_prev, t1, dip, n)
    if found is None:
        return [], t0, t1, g_prev, g_new, dense
    neg, ta, ga, tb, gb = found
    return neg, ta, tb, ga, gb, dense


def sinks(dense: Callable, G: Callable, ids, t0: float, t1: float, n: int, level: float) -> bool:
    """Whether one of the functions ``ids`` of G, which start the step at the ground (watched), goes below
    -``level`` inside the step on its interpolant: at the ``n`` - 1 inner sub-samples and, where such a function
    starts (its value then ~ t^2), at t0 + (t1 - t0) 4^-k down to round-off in time."""
    d = t1 - t0
    for j in range(1, n):
        tj = t0 + d * j / float(n)
        gj = G(tj, dense(tj))
        if any(gj[i] < -level for i in ids):
            return True
    xtol = 4.0 * math.ulp(max(abs(t1), 1.0))
    while d > xtol:
        d *= 0.25
        gt = G(t0 + d, dense(t0 + d))
        if any(gt[i] < -level for i in ids):
            return True
    return False


def bounce_search(dense: Callable, G: Callable, i: int, t0: float, t1: float, level: float):
    """(t, G(t)) of a time in (t0, t1) where function i is above ``level`` (> 0, above round-off), sampled
    at t0 + (t1 - t0) 4^-n down to round-off in time (it starts at zero with a positive slope), or None."""
    d = t1 - t0
    xtol = 4.0 * math.ulp(max(abs(t1), 1.0))
    while d > xtol:
        d *= 0.25
        t = t0 + d
        gt = G(t, dense(t))
        if gt[i] > level:
            return t, gt
        # (below level: closer to the start)
    return None


def parabola_peak(f0: float, fm: float, f1: float):
    """(x, value) of the vertex of the parabola through (0, f0), (1/2, fm), (1, f1) when it is a maximum
    inside (0, 1), else None (the largest value on [0, 1] is then at an end, up to the parabola's error)."""
    c = 2.0 * (f0 + f1) - 4.0 * fm
    if c >= 0.0:
        return None
    b = f1 - f0 - c
    x = -b / (2.0 * c)
    if not 0.0 < x < 1.0:
        return None
    return x, f0 + (b + c * x) * x


#: Brent's golden-section fraction
_CGOLD = 0.3819660112501051


def brent_max(f: Callable, a: float, b: float, x: float, fx, xtol: float, max_iter: int = 60):
    """Brent's method (parabolic steps safeguarded by golden sections) for the largest value of ``f`` on
    [a, b] from an inner point x with value fx; ``f`` may return None (no value: below everything). Returns
    (t, f(t)) of the best point found, its abscissa to about ``xtol`` (a smooth peak's value then to about
    f'' xtol^2 / 2)."""
    inf = math.inf
    gx = -fx if fx is not None else inf          # minimises g = -f
    w = v = x
    gw = gv = gx
    d = e = 0.0
    for _ in range(max_iter):
        xm = 0.5 * (a + b)
        tol2 = 2.0 * xtol
        if abs(x - xm) <= tol2 - 0.5 * (b - a):
            break
        golden = True
        if abs(e) > xtol:
            r = (x - w) * (gx - gv)
            q = (x - v) * (gx - gw)
            p = (x - v) * q - (x - w) * r
            q = 2.0 * (q - r)
            if q > 0.0:
                p = -p
            q = abs(q)
            e_old, e = e, d
            if q != 0.0 and abs(p) < abs(0.5 * q * e_old) and q * (a - x) < p < q * (b - x):
                d = p / q
                golden = False
                if (x + d) - a < tol2 or b - (x + d) < tol2:
                    d = xtol if xm >= x else -xtol
        if golden:
            e = (a - x) if x >= xm else (b - x)
            d = _CGOLD * e
        u = x + d if abs(d) >= xtol else x + (xtol if d >= 0.0 else -xtol)
        fu = f(u)
        gu = -fu if fu is not None else inf
        if gu <= gx:
            if u >= x:
                a = x
            else:
                b = x
            v, gv, w, gw, x, gx = w, gw, x, gx, u, gu
        else:
            if u < x:
                a = u
            else:
                b = u
            if gu <= gw or w == x:
                v, gv, w, gw = w, gw, u, gu
            elif gu <= gv or v == x or v == w:
                v, gv = u, gu
    return x, (-gx if gx != inf else None)
