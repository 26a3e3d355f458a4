"""Reference solutions of the two rocking models, written for reading: scipy's solve_ivp (DOP853, rtol 1e-12,
atol 1e-14) with event functions, one smooth phase at a time, the phases joined by the impact and uplift
rules of Giouvanidis & Dimitrakopoulos (2017) as docs/physics.md states them. Independent of the package:
nothing here imports rocking_model. SI units: m, s, kg, rad, m/s2.

Conventions (the paper's): phi > 0 counter-clockwise, pivoting on the left corner; ag horizontal, positive
along +x, ag_v vertical, positive upward (effective gravity g + ag_v); coordinates relative to the ground.
"""
from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np
import sympy as sp
from scipy.integrate import solve_ivp

RTOL, ATOL = 1e-12, 1e-14


@dataclass
class Trajectory:
    """Piecewise solution: dense outputs per phase, impact times, and the phases' (t0, t1, mode, sol)."""

    phases: list
    impact_times: list

    def at(self, t: float) -> tuple:
        """(mode, state) at time t [s]; the state of the phase that contains t (the later one at a switch)."""
        for t0, t1, mode, sol in reversed(self.phases):
            if t0 <= t <= t1:
                return mode, (sol(t) if sol is not None else None)
        raise ValueError(f"t = {t} outside the solution")


def integrate_phases(t_end, breaks, start, step):
    """Integrate phase after phase: ``step(t0, t1, state)`` integrates from t0 to at most t1 and returns
    (t_stop, mode, dense output, next state or None when t1 was reached); the integration is restarted at
    every time of ``breaks`` (kinks of the ground motion), never stepped across."""
    t, state, phases, impacts = 0.0, start, [], []
    stops = sorted(b for b in breaks if 0.0 < b < t_end) + [t_end]
    while t < t_end:
        t1 = next(b for b in stops if b > t)
        t_stop, mode, sol, nxt, impact = step(t, t1, state)
        phases.append((t, t_stop, mode, sol))
        if impact:
            impacts.append(t_stop)
        t = t_stop
        state = nxt
    return Trajectory(phases, impacts)


# ---------------------------------------------------------------------------------------------- rigid block
@dataclass(frozen=True)
class Block:
    """Rigid block: half-width b, half-height h [m]; e_N = 0 (Housner's impact: phi_dot+ = r phi_dot-)."""

    b: float
    h: float
    g: float = 9.81

    @property
    def R(self):
        return math.hypot(self.b, self.h)

    @property
    def alpha(self):
        return math.atan2(self.b, self.h)

    @property
    def r(self):
        """Housner's coefficient: angular momentum about the impacting corner conserved."""
        return 1.0 - 1.5 * math.sin(self.alpha) ** 2

    def phi_ddot(self, phi, s, ag, ag_v):
        """Rocking about the left (s = +1, phi > 0) or right (s = -1) corner: the moments of gravity and of the
        inertial force -m ag about the pivot divided by I_O = 4/3 m R^2."""
        k = 3.0 / (4.0 * self.R)
        return k * (ag * math.cos(self.alpha - s * phi) - s * (self.g + ag_v) * math.sin(self.alpha - s * phi))

    def uplift_acceleration(self, ag_v):
        """|ag| [m/s2] above which the block at rest lifts off: the moment of the inertial force m ag h about a
        corner exceeds that of the weight, m (g + ag_v) b."""
        return math.tan(self.alpha) * (self.g + ag_v)


@dataclass(frozen=True)
class TendonBlock(Block):
    """Post-tensioned block: the rigid block of mass m [kg] with a vertical unbonded tendon from the ground at
    the base centre (0, 0) to the top centre, of force T = max(0, P0 + k_t (L - 2h)) [N] (P0 [N], k_t [N/m])."""

    m: float = 1.0
    P0: float = 0.0
    k_t: float = 0.0

    def tendon_length(self, phi):
        """L [m] rocking on either corner: |top anchor - ground anchor|, the top anchor on a circle about the
        pivot (law of cosines): L^2 = 4h^2 + 2b^2 (1 - cos phi) + 4bh |sin phi|."""
        b, h = self.b, self.h
        return math.sqrt(4 * h * h + 2 * b * b * (1 - math.cos(phi)) + 4 * b * h * abs(math.sin(phi)))

    def tendon_force(self, phi):
        return max(0.0, self.P0 + self.k_t * (self.tendon_length(phi) - 2 * self.h))

    def phi_ddot(self, phi, s, ag, ag_v):
        """The free block's rocking plus the tendon's moment about the pivot, -T dL/dphi / I_O, with
        dL/dphi = (b^2 sin phi + 2 s b h cos phi)/L (its mirror image on the right corner, s = -1)."""
        b, h = self.b, self.h
        I_O = 4.0 / 3.0 * self.m * self.R ** 2
        dL = (b * b * math.sin(phi) + 2 * s * b * h * math.cos(phi)) / self.tendon_length(phi)
        return super().phi_ddot(phi, s, ag, ag_v) - self.tendon_force(phi) * dL / I_O

    def uplift_acceleration(self, ag_v):
        """At rest the tendon adds P0 to the weight (its line passes through the centroid, at b from a corner)."""
        return math.tan(self.alpha) * (self.g + ag_v + self.P0 / self.m)


def rocking_block(block: Block, t_end, ag=lambda t: 0.0, ag_v=lambda t: 0.0, phi_0=0.0, phi_dot_0=0.0,
                  breaks=()):
    """Rigid block from (phi_0, phi_dot_0) (phi_0 = 0, at rest: full contact): uplift when |ag| exceeds
    tan(alpha) (g + ag_v) (`Block.uplift_acceleration`; a `TendonBlock` adds its tendon), rocking on one corner,
    Housner impacts at phi = 0. Modes: 'full', 'left', 'right'. States: [phi, phi_dot]."""

    def step(t0, t1, state):
        mode, y0 = state
        if mode == "full":
            # the ground pushes until |ag| = tan(alpha) (g + ag_v); the block then lifts on the driven side
            ev = lambda t, y: abs(ag(t)) - block.uplift_acceleration(ag_v(t))
            ev.terminal, ev.direction = True, 1
            sol = solve_ivp(lambda t, y: [0.0], (t0, t1), [0.0], events=ev, rtol=RTOL, atol=ATOL,
                            dense_output=True)
            zero = lambda t: np.zeros(2)
            if sol.status == 1:
                te = sol.t_events[0][0]
                return te, "full", zero, ("left" if ag(te) > 0 else "right", [0.0, 0.0]), False
            return t1, "full", zero, ("full", None), False
        s = 1.0 if mode == "left" else -1.0
        ev = lambda t, y: y[0]                       # the other corner reaches the ground
        ev.terminal, ev.direction = True, -s
        rhs = lambda t, y: [y[1], block.phi_ddot(y[0], s, ag(t), ag_v(t))]
        sol = solve_ivp(rhs, (t0, t1), y0, method="DOP853", events=ev, rtol=RTOL, atol=ATOL, dense_output=True)
        if sol.status == 1:
            te, ye = sol.t_events[0][0], sol.y_events[0][0]
            nxt = ("right" if s > 0 else "left", [0.0, block.r * ye[1]])
            return te, mode, sol.sol, nxt, True
        return t1, mode, sol.sol, (mode, sol.y[:, -1]), False

    mode = "left" if phi_0 > 0 or (phi_0 == 0 and phi_dot_0 > 0) else "right" if phi_0 or phi_dot_0 else "full"
    return integrate_phases(t_end, breaks, (mode, [phi_0, phi_dot_0]), step)


# ---------------------------------------------------------------------------------------------- flexible
@dataclass(frozen=True)
class Oscillator:
    """Flexible rocking oscillator (paper's appendix): top mass m, column mass m_c, base mass m_b with radius
    of gyration rho, column height h, base half-width b [m, kg], flexural rigidity EI [N m2], damping ratio
    zeta; e_N = 0."""

    m: float
    m_c: float
    m_b: float
    rho: float
    h: float
    b: float
    EI: float
    zeta: float
    g: float = 9.81

    @property
    def params(self):
        return (self.m, self.m_c, self.m_b, self.rho, self.h, self.b, self.EI, self.zeta, self.g)


@functools.lru_cache(maxsize=None)
def lagrangian_equations():
    """Equations of motion of the flexible oscillator, derived here from its kinetic and potential energy
    (paper's Eqs. 48-54) with sympy, for the full coordinates q = [u, x, y, phi] and for each contact mode's
    reduced coordinates. Returns {mode: (M(r, params), F(r, r_dot, ag, ag_v, params)) as numeric functions}
    plus 'full_M' (the 4 x 4 mass matrix), where M r_ddot = F."""
    m, m_c, m_b, rho, h, b, EI, zeta, g = P = sp.symbols("m m_c m_b rho h b EI zeta g", positive=True)
    ag, ag_v, xi = sp.symbols("ag ag_v xi")
    t = sp.Symbol("t")
    u, x, y, phi = (sp.Function(n)(t) for n in ("u", "x", "y", "phi"))
    psi = 3 * xi ** 2 / (2 * h ** 2) - xi ** 3 / (2 * h ** 3)            # Eq. (48)
    m_tilde = m + sp.Rational(33, 140) * m_c
    k_tilde = 3 * EI / h ** 3                                            # Eq. (49)
    # positions relative to the ground (Eq. 50 without u_g; the ground's acceleration enters as the
    # inertial force -m_i ag along x, i.e. the potential ag * m_i X_i)
    top = (x - h * sp.sin(phi) + u * sp.cos(phi), y + h * sp.cos(phi) + u * sp.sin(phi))
    col = (x - xi * sp.sin(phi) + u * psi * sp.cos(phi), y + xi * sp.cos(phi) + u * psi * sp.sin(phi))
    speed2 = lambda P_: sp.diff(P_[0], t) ** 2 + sp.diff(P_[1], t) ** 2
    T = (m * speed2(top) / 2 + sp.integrate(m_c / h * speed2(col), (xi, 0, h)) / 2
         + m_b * (sp.diff(x, t) ** 2 + sp.diff(y, t) ** 2) / 2 + m_b * rho ** 2 * sp.diff(phi, t) ** 2 / 2)
    first_moment = lambda i: m * top[i] + sp.integrate(m_c / h * col[i], (xi, 0, h)) + m_b * (x, y)[i]
    V = k_tilde * u ** 2 / 2 + (g + ag_v) * first_moment(1) + ag * first_moment(0)      # Eq. (53) + ground
    c = 2 * zeta * sp.sqrt(m_tilde * k_tilde)                            # Eq. (54): Q_u = -c u_dot

    # base corners at (x -+ b cos phi, y -+ b sin phi); a pivot stays at its rest position
    modes = {
        "left": {x: b * sp.cos(phi) - b, y: b * sp.sin(phi)},
        "right": {x: b - b * sp.cos(phi), y: -b * sp.sin(phi)},
        "full": {x: 0, y: 0, phi: 0},
        "flight": {},
    }
    coords = {"left": [u, phi], "right": [u, phi], "full": [u], "flight": [u, x, y, phi]}
    out = {}
    for mode, sub in modes.items():
        q = coords[mode]
        Lm = (T - V).subs(sub).doit()
        qd = [sp.diff(qi, t) for qi in q]
        # plain symbols for the coordinates and velocities (sympy differentiates with respect to them)
        r = sp.symbols(f"r0:{len(q)}")
        rd = sp.symbols(f"rd0:{len(q)}")
        rdd = sp.symbols(f"rdd0:{len(q)}")
        to_sym = {}
        for qi, ri, rdi, rddi in zip(q, r, rd, rdd):
            to_sym[sp.diff(qi, t, 2)] = rddi
            to_sym[sp.diff(qi, t)] = rdi
        eqs = []
        for i, qi in enumerate(q):
            lhs = sp.diff(sp.diff(Lm, qd[i]), t) - sp.diff(Lm, qi)
            Q = -c * qd[i] if qi is u else 0
            eqs.append(sp.expand((lhs - Q).subs(to_sym).subs(dict(zip(q, r)))))
        Mm = sp.Matrix([[e.coeff(a) for a in rdd] for e in eqs])
        F = -sp.Matrix([e.subs({a: 0 for a in rdd}) for e in eqs])
        out[mode] = (sp.lambdify((r, P), Mm.tolist(), "math", cse=True),
                     sp.lambdify((r, rd, ag, ag_v, P), list(F), "math", cse=True))
    return out


def flexible_constants(osc: Oscillator) -> dict:
    m, m_c, m_b, rho, h, b, EI, zeta, g = osc.params
    mt = m + 33.0 / 140.0 * m_c
    kt = 3.0 * EI / h ** 3
    return dict(mt=mt, kt=kt, c=2.0 * zeta * math.sqrt(mt * kt), Mt=m + m_b + m_c, D=m + 3.0 / 8.0 * m_c,
                A_h=(m + 0.5 * m_c) * h, C=(m + 11.0 / 40.0 * m_c) * h)


def uplift_moment(osc: Oscillator, u, u_dot, ag, ag_v):
    """Q [N m] of full contact: b (lambda_R - lambda_L); the left corner lifts when Q > b M_t (g + ag_v) (from
    the phi and y rows of the equations with x = y = phi = 0 held and u_ddot from the u row)."""
    k = flexible_constants(osc)
    u_ddot = (-k["c"] * u_dot - k["kt"] * u - k["D"] * ag) / k["mt"]
    return -k["C"] * u_ddot - k["A_h"] * ag + (osc.g + ag_v) * k["D"] * u


def full_coordinates(osc: Oscillator, mode, r, rd):
    """(q, v) = ([u, x, y, phi], rates) of a reduced state of ``mode`` (the pivot at its rest position)."""
    b = osc.b
    if mode == "full":
        return np.array([r[0], 0, 0, 0.0]), np.array([rd[0], 0, 0, 0.0])
    u, phi = r
    ud, w = rd
    s = 1.0 if mode == "left" else -1.0
    q = np.array([u, s * (b * math.cos(phi) - b), s * b * math.sin(phi), phi])
    v = np.array([ud, -s * b * math.sin(phi) * w, s * b * math.cos(phi) * w, w])
    return q, v


def pivot_force(osc: Oscillator, mode, y, ag, ag_v):
    """Normal force [N] on the pivot while rocking on ``mode``'s corner at the reduced state y: the full
    equations M a = F + W_N lambda_N + W_T lambda_T with the corner's acceleration held at zero,
    W^T a + (dW/dt)^T v = 0 (corner (x + s_c b cos phi, y + s_c b sin phi), s_c = -1 left, +1 right).
    The sticking pivot is valid while it is positive (else the structure takes off)."""
    eqs = lagrangian_equations()
    q, v = full_coordinates(osc, mode, y[:2], y[2:])
    M = np.array(eqs["flight"][0](list(q), osc.params), dtype=float)
    F = np.array(eqs["flight"][1](list(q), list(v), ag, ag_v, osc.params), dtype=float).ravel()
    sc, b, (sphi, cphi), w = (-1.0 if mode == "left" else 1.0), osc.b, (math.sin(q[3]), math.cos(q[3])), v[3]
    W = np.array([[0, 0, 1.0, sc * b * cphi], [0, 1.0, 0, -sc * b * sphi]]).T
    drift = np.array([-sc * b * sphi * w * w, -sc * b * cphi * w * w])
    K = np.block([[M, -W], [W.T, np.zeros((2, 2))]])
    return np.linalg.solve(K, np.concatenate([F, -drift]))[4]


def impact(osc: Oscillator, mode, u, u_dot, phi_dot):
    """Impact at phi = 0 while rocking on ``mode``'s pivot, e_N = 0, sticking on the corners that take an
    impulse: the active set {new} or {old, new} whose impulses are non-negative and which leaves no corner
    approaching (the LCP of docs/physics.md, solved by enumeration). Returns (mode after, u_dot+, phi_dot+)."""
    eqs = lagrangian_equations()
    q, v_minus = full_coordinates(osc, mode, [u, 0.0], [u_dot, phi_dot])
    M = np.array(eqs["flight"][0](list(q), osc.params), dtype=float)
    b = osc.b
    W_N = {"left": np.array([0, 0, 1.0, -b]), "right": np.array([0, 0, 1.0, b])}
    W_T = np.array([0, 1.0, 0, 0])                 # both corners at phi = 0 (parallel rows: one is enough)
    new = "right" if mode == "left" else "left"
    for active in ([new], [new, mode]):
        G = np.column_stack([W_N[c] for c in active] + [W_T])
        # M (v+ - v-) = G P,  G^T v+ = 0 (normal: e_N = 0; tangential: sticking)
        K = np.block([[M, -G], [G.T, np.zeros((G.shape[1], G.shape[1]))]])
        sol = np.linalg.solve(K, np.concatenate([M @ v_minus, np.zeros(G.shape[1])]))
        v_plus, P = sol[:4], sol[4:]
        others = [c for c in W_N if c not in active]
        if np.all(P[:len(active)] >= 0) and all(W_N[c] @ v_plus >= 0 for c in others):
            if len(active) == 1:
                return new, v_plus[0], v_plus[3]
            return "full", v_plus[0], 0.0
    raise AssertionError(f"no active set solves the impact problem at u = {u}, u_dot = {u_dot}, "
                         f"phi_dot = {phi_dot} on the {mode} pivot")


def rocking_oscillator(osc: Oscillator, t_end, ag=lambda t: 0.0, ag_v=lambda t: 0.0, phi_0=0.0, u_0=0.0,
                       breaks=()):
    """Flexible oscillator from rest at (phi_0, u_0): full contact (u) until the uplift criterion, rocking
    (u, phi) on one corner until phi = 0, impacts by `impact`. Reduced states: full [u, u_dot], rocking
    [u, phi, u_dot, phi_dot]. Also records, at every decision, how far it was from its boundary
    (``margins``: |Q|/(b M_t g) at the entry into full contact, |u|/u* at impacts, and the smallest pivot
    force of each rocking phase over M_t g, which must stay positive: the reference has no flight)."""
    eqs = lagrangian_equations()
    k = flexible_constants(osc)
    margins = []

    def rhs_of(mode):
        Mf, Ff = eqs[mode]
        n = 1 if mode == "full" else 2

        def rhs(t, y):
            r, rd = list(y[:n]), list(y[n:])
            acc = np.linalg.solve(np.array(Mf(r, osc.params), dtype=float),
                                  np.array(Ff(r, rd, ag(t), ag_v(t), osc.params), dtype=float).ravel())
            return np.concatenate([rd, acc])
        return rhs

    def after_full(t, u, u_dot):
        """The mode that follows a full-contact state (uplift criterion)."""
        Q = uplift_moment(osc, u, u_dot, ag(t), ag_v(t))
        limit = osc.b * k["Mt"] * (osc.g + ag_v(t))
        margins.append(("uplift", abs(Q) / limit))
        if Q > limit:
            return "right"
        if Q < -limit:
            return "left"
        return "full"

    def step(t0, t1, state):
        mode, y0 = state
        if mode == "full":
            def ev(sign):
                f = lambda t, y: sign * uplift_moment(osc, y[0], y[1], ag(t), ag_v(t)) \
                    - osc.b * k["Mt"] * (osc.g + ag_v(t))
                f.terminal, f.direction = True, 1
                return f
            sol = solve_ivp(rhs_of("full"), (t0, t1), y0, method="DOP853", events=[ev(1.0), ev(-1.0)],
                            rtol=RTOL, atol=ATOL, dense_output=True)
            if sol.status == 1:
                i = 0 if len(sol.t_events[0]) else 1
                te, ye = sol.t_events[i][0], sol.y_events[i][0]
                return te, "full", sol.sol, ("right" if i == 0 else "left", [ye[0], 0.0, ye[1], 0.0]), False
            return t1, "full", sol.sol, ("full", sol.y[:, -1]), False
        s = 1.0 if mode == "left" else -1.0
        ev = lambda t, y: y[1]
        ev.terminal, ev.direction = True, -s
        sol = solve_ivp(rhs_of(mode), (t0, t1), y0, method="DOP853", events=ev, rtol=RTOL, atol=ATOL,
                        dense_output=True)
        t_last = sol.t[-1]
        lam = min(pivot_force(osc, mode, sol.sol(ts), ag(ts), ag_v(ts)) for ts in np.linspace(t0, t_last, 40))
        margins.append(("pivot", lam / (k["Mt"] * osc.g)))
        if sol.status != 1:
            return t1, mode, sol.sol, (mode, sol.y[:, -1]), False
        te, (u, _, ud, w) = sol.t_events[0][0], sol.y_events[0][0]
        new, ud_plus, w_plus = impact(osc, mode, u, ud, w)
        u_star2 = (k["Mt"] * osc.b ** 2 - (flexible_J0(osc) - k["C"] ** 2 / k["mt"])) / k["mt"]
        margins.append(("impact", abs(u) / math.sqrt(u_star2) if u_star2 > 0 else math.inf))
        if new == "full":
            new = after_full(te, u, ud_plus)
            if new == "full":
                return te, mode, sol.sol, ("full", [u, ud_plus]), True
        return te, mode, sol.sol, (new, [u, 0.0, ud_plus, w_plus]), True

    if phi_0 == 0.0:
        start = ("full", [u_0, 0.0])
    else:
        start = ("left" if phi_0 > 0 else "right", [u_0, phi_0, 0.0, 0.0])
    traj = integrate_phases(t_end, breaks, start, step)
    traj.margins = margins
    return traj


def flexible_J0(osc: Oscillator) -> float:
    """Moment of inertia of the undeformed structure about the base midpoint [kg m2]."""
    return osc.m_b * osc.rho ** 2 + osc.m * osc.h ** 2 + osc.m_c * osc.h ** 2 / 3.0


def outputs(traj: Trajectory, t: float, kind: str) -> dict:
    """phi, phi_dot (and u, u_dot for the oscillator) of a reference trajectory at t [s]."""
    mode, y = traj.at(t)
    if kind == "rigid":
        return {"phi": float(y[0]), "phi_dot": float(y[1])}
    if mode == "full":
        return {"u": float(y[0]), "u_dot": float(y[1]), "phi": 0.0, "phi_dot": 0.0}
    return {"u": float(y[0]), "phi": float(y[1]), "u_dot": float(y[2]), "phi_dot": float(y[3])}
