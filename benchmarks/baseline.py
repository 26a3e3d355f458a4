"""The scipy baseline: the rigid rocking block written the way a user writes it with `solve_ivp`.

Housner's single-degree-of-freedom rocking equation, one `solve_ivp` call per contact phase (DOP853 by
default), terminal events for the impact (phi = 0) and for overturning (|phi| = pi/2), Housner's
restitution r = 1 - 1.5 sin^2(alpha) applied to phi_dot at each impact, and a restart loop:

    rocking on the pivot sigma (+1: phi > 0, left corner):
        phi_ddot = p^2 [ (ag/g) cos(alpha - sigma phi) - sigma sin(alpha - sigma phi) ]
    impact at phi = 0:     phi_dot <- r phi_dot, sigma <- -sigma (rocking goes on about the other corner)
    at rest:               wait (event |ag(t)| = g tan(alpha)) for the uplift, sigma = sign(ag)

The impact accumulation is ended as the package does: a post-impact corner separation speed
|phi_dot| 2 b below zeno_tol sqrt(g R) puts the block at rest. The output is the dense output of each
phase on the common grid. Nothing is tuned for speed beyond what the scipy documentation suggests.
"""
from __future__ import annotations

import math

import numpy as np
from scipy.integrate import solve_ivp

from rocking_model import RigidBlock


def rigid_solve_ivp(block: RigidBlock, ag, t_end: float, grid: np.ndarray, *, phi_0: float = 0.0,
                    phi_dot_0: float = 0.0, rtol: float = 1e-8, atol: float | None = None,
                    method: str = "DOP853", zeno_tol: float = 1e-6, max_phases: int = 200000,
                    rest_max_step: float = 0.01, samples=None, max_step: float = math.inf):
    """Simulate the rigid block with solve_ivp; return dict(phi=array on grid, impact_times, n_steps,
    overturned).

    ag: callable ag(t) [m/s2]. samples: optional (t, ag) arrays of a piecewise-linear record that ag
    interpolates; then the uplift from rest is found from the samples (first sample beyond g tan(alpha),
    crossing by linear interpolation), which cannot miss a short exceedance as an event checked at the
    solver's steps can. max_step: solve_ivp's max_step in the rocking phases (a user who knows the record
    is piecewise linear may set it to the sampling step)."""
    p2 = block.p ** 2
    alpha, g = block.alpha, block.g
    r = block.housner_r
    ag_c = g * math.tan(alpha)
    v_zeno = zeno_tol * math.sqrt(g * block.R) / (2.0 * block.b)
    atol = rtol if atol is None else atol
    agf = ag if callable(ag) else (lambda t, a=float(ag): a)

    phi_out = np.zeros_like(grid)
    impacts: list[float] = []
    n_steps = 0
    t = float(grid[0])
    y = np.array([phi_0, phi_dot_0], dtype=float)
    if phi_0 > 0 or (phi_0 == 0 and phi_dot_0 > 0):
        sigma = 1.0
    elif phi_0 < 0 or (phi_0 == 0 and phi_dot_0 < 0):
        sigma = -1.0
    else:
        sigma = 0.0                                       # at rest
    overturned = False

    def rocking(t, y):
        a = alpha - sigma * y[0]
        return [y[1], p2 * (agf(t) / g * math.cos(a) - sigma * math.sin(a))]

    def impact(t, y):
        return sigma * y[0]
    impact.terminal = True
    impact.direction = -1

    def overturn(t, y):
        return 0.5 * math.pi - abs(y[0])
    overturn.terminal = True
    overturn.direction = -1

    def uplift(t, y):
        return abs(agf(t)) - ag_c
    uplift.terminal = True
    uplift.direction = 1

    def fill(sol_t0, sol_t1, dense):
        i0 = np.searchsorted(grid, sol_t0, side="left")
        i1 = np.searchsorted(grid, sol_t1, side="right")
        if i1 > i0:
            phi_out[i0:i1] = dense(grid[i0:i1])

    for _ in range(max_phases):
        if t >= t_end:
            break
        if sigma == 0.0:
            if abs(agf(t)) > ag_c:
                sigma = math.copysign(1.0, agf(t))
                continue
            if samples is not None:
                t_new = _next_exceedance(samples[0], samples[1], t, ag_c, t_end)
                found = t_new < t_end
            else:
                sol = solve_ivp(lambda t, y: [0.0], (t, t_end), [0.0], method="RK23", events=uplift,
                                max_step=rest_max_step, rtol=1e-3, atol=1.0)
                n_steps += sol.t.size - 1
                found = sol.t_events[0].size > 0
                t_new = float(sol.t_events[0][0]) if found else t_end
            i0 = np.searchsorted(grid, t, side="left")
            i1 = np.searchsorted(grid, t_new, side="right")
            phi_out[i0:i1] = 0.0
            if found:
                # step just past the crossing so that |ag| > g tan(alpha) holds at the restart
                t_new = np.nextafter(t_new, math.inf)
                sigma = math.copysign(1.0, agf(t_new))
                y = np.zeros(2)
            t = t_new
            continue
        sol = solve_ivp(rocking, (t, t_end), y, method=method, rtol=rtol, atol=atol, events=(impact, overturn),
                        dense_output=True, max_step=max_step)
        n_steps += sol.t.size - 1
        fill(t, sol.t[-1], lambda tt: sol.sol(tt)[0])
        t = float(sol.t[-1])
        y = sol.y[:, -1].copy()
        if sol.status == 1 and sol.t_events[1].size:       # overturned: freeze
            overturned = True
            i0 = np.searchsorted(grid, t, side="left")
            phi_out[i0:] = math.copysign(0.5 * math.pi, y[0])
            break
        if sol.status == 1 and sol.t_events[0].size:       # impact
            impacts.append(t)
            y = np.array([0.0, r * y[1]])
            sigma = -sigma
            if abs(y[1]) < v_zeno:
                sigma, y = 0.0, np.zeros(2)
            continue
        break
    else:
        raise RuntimeError("solve_ivp baseline: too many contact phases")
    return {"phi": phi_out, "impact_times": np.array(impacts), "n_steps": n_steps, "overturned": overturned}


def _next_exceedance(ts, a, t, level, t_end):
    """First time > t at which |a(t)| (linear between the samples) rises through ``level`` (t_end if never)."""
    i = max(int(np.searchsorted(ts, t, side="right")), 1)
    over = np.nonzero(np.abs(a[i:]) > level)[0]
    if over.size == 0:
        return t_end
    j = i + int(over[0])                     # first sample beyond the level; the crossing is in (ts[j-1], ts[j]]
    a0, a1 = a[j - 1], a[j]
    s = math.copysign(1.0, a1)
    x0 = s * a0
    tc = ts[j - 1] + (level - x0) / (s * a1 - x0) * (ts[j] - ts[j - 1]) if s * a1 != x0 else ts[j]
    return float(min(max(tc, t), t_end))
