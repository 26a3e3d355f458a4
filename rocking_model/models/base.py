"""Common interface of the rocking models: what a model must provide, what it may provide.

A model bundles, in the Siconos sense,
- the dynamical system: generalized coordinates q (full description, ground frame), mass matrix M(q),
  non-contact generalized forces f(q, v, ag, ag_v) (gravity, elastic, damping, gyroscopic, and the inertial
  forces of the ground acceleration: ag [m/s2] horizontal, positive along +x, and ag_v [m/s2] vertical, positive
  upward, which adds -m_i ag_v along +y on every mass m_i: an effective gravity g + ag_v);
- the contact relation: ``n_contacts`` contacts (the rocking models: the two base corners, 0 = left,
  1 = right), their normal gaps g_N(q), the normal and tangential Jacobians W_N, W_T (one column per contact)
  and the drift terms W_dot^T v;
- the reduced coordinates r of each contact mode (a set of closed contacts), with the embedding q = q(r),
  v = J(r) r_dot.

The nonsmooth law (Newton impact, sticking) and the one-step problems (LCPs) live in `rocking_model.lcp` and
`rocking_model.contact`; the integrators only talk to this interface.

Contract (in the style of scipy's ``OdeSolver``)
-----------------------------------------------
A subclass must provide:

    dof_names, phi_index        names of q and the index of the rotation phi (overturning: |phi| = pi/2)
    slide_index, lift_index     indices of the base's horizontal and vertical translations (sliding moves the
                                first; their rows of M a - f carry the total tangential and normal forces)
    e_N, g, mu                  coefficient of restitution [1], gravity [m/s2], friction coefficient [1]
                                (inf: the paper's sticking law)
    mass_matrix(q), forces(q, v, ag, ag_v=0.0)
    gaps(q), contact_jacobians(q), contact_drift(q, v), contact_abscissae(q)
    mode_dofs(mode), embed(mode, r, r_dot), mode_jacobian(mode, r, r_dot)
    rest_position(), energy(q, v), outputs(q, v), initial_state(**initial)
    length_scale [m], time_scale [s]

A subclass may provide (the defaults here are generic and correct, the overrides are faster or add a rule):

    n_contacts = 2                              number of contacts
    mode_of(closed), closed_of(mode)            the contact mode of a set of closed contacts and back
                                                (default: `Mode`, the four modes of two corners)
    inverse_mass_matrix(q)                      default: inv(M(q))
    stiff_jacobians(q, v)                       (K, C) of a stiff linear part of f; default None
    step_limit                                  largest time-stepper step [s]; default inf
    dof_scales                                  scale of each coordinate for error control; default 1 for
                                                phi, length_scale for the others
    classical_impact_velocity(q, v_minus, mode) an impact rule replacing the impact LCP at a rocking impact;
                                                default None (the LCP with Newton's law)
    reduced_acceleration, contact_forces        per mode, from the numpy interface (each takes ag, ag_v=0.0)
    mode_functions, mode_outputs(_array)        float-level right-hand sides, event functions and outputs
    force_scale                                 scale of the contact forces [N]; default |f| at rest
    force_totals_of(mode, ag)                   float-level (sum lambda_N, sum lambda_T) of a mode (the
                                                friction demand and cone); default generic numpy
    mode_closures(mode, ag)                     (rhs, monitors, totals) built together (shared work)
    SHIFTED_OUTPUTS                             outputs that move with the base's horizontal offset

The functions that take a GroundMotion ``ag`` (mode_closures, mode_functions, functions_of, force_totals_of)
read its vertical component from ``ag.vertical`` (None: ag_v = 0; `vertical_of`, `effective_gravity`).

The sliding modes (`rocking_model.modes.SLIDING`) need nothing more: their coordinates, right-hand sides and
events are derived from the sticking modes' (`rocking_model.models.sliding`); the integrators reach every
mode through `dofs_of`, `embed_any`, `reduce_any`, `functions_of`, `outputs_of` and `outputs_array_of`.
    fields()                                    declared parameters (name, unit, range, description):
                                                the Python API, the CLI and the FMUs read them
"""
from __future__ import annotations

import math
from abc import ABC, abstractmethod

import numpy as np

from .._ordered import inverse

from ..contact import mode_forces
from ..modes import CLOSED, MODE_DESCRIPTIONS, OVERTURNED, OVERTURNED_DESCRIPTION, SLIDING, Mode, mode_from_closed
from ..params import Param, declared_parameters, param
from . import sliding

#: [rad] the overturning angle: |phi| = pi/2 ends the motion (the last event function is HALF_PI - |phi|)
HALF_PI = 0.5 * math.pi

#: the initial rotation and rate, declared once for every rocking model (their `INITIAL` starts with them)
PHI_0 = Param("phi_0", 0.0, "rad", "Initial rotation (positive: pivoting on the left corner), |phi_0| < pi/2",
              lo=-math.pi / 2, hi=math.pi / 2, lo_open=True, hi_open=True)
PHI_DOT_0 = Param("phi_dot_0", 0.0, "rad/s", "Initial angular velocity", lo=-1e4, hi=1e4)


def _zero(t: float) -> float:
    return 0.0


def vertical_of(ag):
    """t -> ag_v(t) [m/s2] of the GroundMotion ``ag``: its vertical component (positive upward), its value when
    constant, or 0.0 when it has none (``ag.vertical`` is None)."""
    vert = ag.vertical
    if vert is None:
        return _zero
    if vert.constant:
        value = vert.value
        return lambda t: value
    return vert


def effective_gravity(ag, g: float):
    """(g_e0, vert) for closed forms under the effective gravity g_e = g + ag_v(t) [m/s2] of the GroundMotion
    ``ag`` and the gravity ``g`` [m/s2]: vert None means the constant g_e = g_e0 (g itself without a vertical
    component, so that g_e / g == 1.0 exactly; g + ag_v for a constant one), else g_e = g + vert(t)."""
    vert = ag.vertical
    if vert is None:
        return g, None
    if vert.constant:
        return g + vert.value, None
    return 0.0, vert


def body_outputs(body: str, point: str) -> tuple:
    """The declared outputs of the rocking body's motion: rotation and rate of ``body``, displacement and
    velocity of its reference ``point`` (e.g. "the centroid")."""
    return (
        Param("phi", 0.0, "rad", f"Rotation of the {body}"),
        Param("phi_dot", 0.0, "rad/s", f"Angular velocity of the {body} (0 once overturned: the pose reached "
              "at |phi| = pi/2 is reported at rest)"),
        Param("x", 0.0, "m", f"Horizontal displacement of {point} relative to the ground"),
        Param("y", 0.0, "m", f"Vertical displacement of {point} from rest"),
        Param("x_dot", 0.0, "m/s", f"Horizontal velocity of {point} relative to the ground (0 once overturned)"),
        Param("y_dot", 0.0, "m/s", f"Vertical velocity of {point} (0 once overturned)"),
        Param("slip", 0.0, "m", "Base sliding displacement: horizontal displacement of the lower base corner from "
              "its rest position (0 while the corners stick)"),
    )


#: the tangential impact law, a parameter of every rocking model (`RockingModel.e_T`)
IMPACT_LAW_ITEMS = (
    ("newton", 0, "the paper's: Newton's law normal, sticking tangential; it can create energy when e_N > 0 "
                  "and a corner slips (docs/limitations.md)"),
    ("energy_consistent", 1, "Newton's law normal and tangential restitution e_T = e_N (Glocker 2013): "
                             "never creates energy"),
)


#: [1] smallest friction coefficient: below those of real surfaces (lubricated or superlubric contacts reach
#: 1e-3), while 1/mu enters the sliding equations and the frictional LCPs (the force direction W_N/mu - sigma
#: W_T): at mu = 5e-324 it is inf and the solvers fail or hang in LAPACK; mu >= 1e-3 keeps their entries
#: within 1e3 of the frictionless ones.
MU_MIN = 1e-3


def friction_param():
    """The declared field ``mu``: Coulomb's friction coefficient at the contacts, inf (the default) being the
    paper's sticking law, its mu -> inf limit; at least `MU_MIN`."""
    return param(math.inf, "1", "Coulomb friction coefficient at the corners (inf: the paper's sticking law, "
                 f"no sliding; at least {MU_MIN:g})", lo=MU_MIN, inf_ok=True)


def impact_law_param():
    """The declared field ``impact_law`` (a `rocking_model.params.param`)."""
    return param(0, None, "Tangential impact law", items=IMPACT_LAW_ITEMS)


#: the keyword arguments of `rocking_model.simulation.Simulator` besides the initial values (named in the
#: message of a misspelt keyword)
SOLVER_KEYWORDS = ("scheme", "dt_max", "tolerance", "theta", "zeno_tol", "t0", "method", "impact_log_size",
                   "max_steps", "tolerances", "on_report")


class RockingModel(ABC):
    """Abstract planar body with two base corners on a horizontally moving rigid ground."""

    #: names of the full generalized coordinates, in order
    dof_names: tuple[str, ...] = ()
    #: index of the rotation phi in q
    phi_index: int = -1
    #: coefficient of restitution of Newton's impact law [1]
    e_N: float = 0.0
    #: tangential impact law (0: the paper's, sticking; 1: tangential restitution e_T = e_N)
    impact_law: int = 0
    #: Coulomb friction coefficient [1]; inf: the paper's sticking law
    mu: float = math.inf

    @property
    def e_T(self) -> float:
        """Tangential coefficient of restitution of the impact law [1]: 0 for the paper's law (Newton normal,
        sticking tangential), e_N for the energetically consistent law (Glocker 2013: Newton's law in both
        directions with one coefficient dissipates energy at every impact)."""
        return self.e_N if self.impact_law == 1 else 0.0

    #: gravity [m/s2]
    g: float = 9.81

    #: index in q of the horizontal translation of the base (the coordinate a sliding base moves along)
    slide_index: int = 0
    #: index in q of the vertical translation of the base (its row of M a - f carries only normal forces)
    lift_index: int = 1
    #: outputs that move with a horizontal offset of the whole structure (a slid or landed-off base)
    SHIFTED_OUTPUTS: tuple = ("x", "slip")
    #: registry name of the model (`rocking_model.models.MODELS`), its FMU's name and a title
    kind: str = ""
    fmu_name: str = ""
    title: str = ""
    #: number of contacts (columns of W_N, W_T; entries of g_N)
    n_contacts: int = 2
    #: declared initial values (`rocking_model.params.Param`, the keywords of `initial_state`)
    INITIAL: tuple = ()
    #: declared outputs (the keys of `outputs`, with unit and description)
    OUTPUTS: tuple = ()

    @classmethod
    def parameters(cls) -> tuple:
        """The declared parameters (`rocking_model.params.Param`) of the model, in constructor order."""
        return declared_parameters(cls)

    def check_initial_names(self, names) -> None:
        """ValueError for keywords that are not initial values of this model, with the closest names."""
        if not names:
            return
        import difflib

        allowed = [p.name for p in self.INITIAL]
        hints = []
        for name in sorted(names):
            close = difflib.get_close_matches(str(name), allowed + list(SOLVER_KEYWORDS), n=1)
            hints.append(f"{name!r}" + (f" (did you mean {close[0]!r}?)" if close else ""))
        raise ValueError(f"unknown keyword argument(s) {', '.join(hints)} for {type(self).__name__}; allowed "
                         f"initial values: {', '.join(allowed)}; solver options: {', '.join(SOLVER_KEYWORDS)}")

    @property
    def n_dof(self) -> int:
        return len(self.dof_names)

    # ------------------------------------------------------------------ contact modes (may override)
    def mode_of(self, closed, sigma: int = 0) -> Mode:
        """The contact mode whose closed contacts are ``closed`` (an iterable of contact indices), sliding in
        direction ``sigma`` (+1 towards +x, -1 towards -x, 0: sticking)."""
        return mode_from_closed(closed, sigma)

    def closed_of(self, mode) -> tuple:
        """The closed contacts of ``mode``, in increasing order."""
        return CLOSED[mode]

    def mode_code(self, value: int):
        """The mode of an integer code (a saved state, the FMU output ``contact``); ValueError if none."""
        return Mode(value)

    @property
    def n_modes(self) -> int:
        """Number of contact modes (integer codes 0 .. n_modes - 1)."""
        return len(self.contact_codes())

    @classmethod
    def contact_codes(cls) -> tuple:
        """The contact modes, by integer code."""
        return tuple(Mode)

    @classmethod
    def contact_description(cls) -> str:
        """What the integer codes of the output ``contact`` mean: the contact modes, then `OVERTURNED`."""
        return ", ".join([f"{int(m)} {MODE_DESCRIPTIONS[m]}" for m in Mode]
                         + [f"{OVERTURNED} {OVERTURNED_DESCRIPTION}"])

    @classmethod
    def max_contact_code(cls) -> int:
        """The largest value of the output ``contact`` (`OVERTURNED`, after the contact modes' codes)."""
        return OVERTURNED

    # ------------------------------------------------------------------ dynamical system
    @abstractmethod
    def mass_matrix(self, q: np.ndarray) -> np.ndarray:
        """M(q), shape (n, n)."""

    # Every caller passes ag_v (0.0 without a vertical component), so a model must take it. There is no shim
    # calling forces(q, v, ag) for models written before ag_v: such a model would run where ag_v = 0 and break
    # only under a vertical motion, deep inside a contact problem; a TypeError at its first call is honest.
    @abstractmethod
    def forces(self, q: np.ndarray, v: np.ndarray, ag: float, ag_v: float = 0.0) -> np.ndarray:
        """Non-contact generalized forces f(q, v, ag, ag_v), shape (n,), so that M q_ddot = f + contact forces;
        ag [m/s2] horizontal ground acceleration (+x), ag_v [m/s2] vertical (positive upward: gravity g becomes
        the effective gravity g + ag_v on every mass)."""

    def inverse_mass_matrix(self, q: np.ndarray) -> np.ndarray:
        """M(q)^-1, shape (n, n); override with a closed form where there is one. (Gauss-Jordan in the C
        engine's operation order: rocking_model/_ordered.py.)"""
        return inverse(self.mass_matrix(q))

    def stiff_jacobians(self, q: np.ndarray, v: np.ndarray):
        """(K, C) = (-df/dq, -df/dv) of the stiff linear part of f, treated implicitly by the time-stepper.

        None when f has no stiff part (the rigid block)."""
        return None

    # ------------------------------------------------------------------ contact relation
    @abstractmethod
    def gaps(self, q: np.ndarray) -> np.ndarray:
        """Normal gaps g_N of the contacts [m], shape (n_contacts,)."""

    @abstractmethod
    def contact_jacobians(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(W_N, W_T), each shape (n, n_contacts): normal and tangential velocity of contact i is W[:, i] . v."""

    @abstractmethod
    def contact_drift(self, q: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(a_N, a_T), each shape (n_contacts,): the terms (d/dt W)^T v of the contact accelerations."""

    @abstractmethod
    def contact_abscissae(self, q: np.ndarray) -> np.ndarray:
        """Horizontal positions of the contacts relative to the ground [m], shape (n_contacts,)."""

    def slip(self, q: np.ndarray) -> float:
        """Base sliding displacement [m]: the horizontal displacement of the lower corner from its rest
        position (0 while the corners stick; continuous through rocking, flight and landing, as the lower
        corner is the pivot, the one that lands, and the corners swap at phi = 0 where both agree)."""
        g = self.gaps(q)
        i = int(np.argmin(g))
        return float(self.contact_abscissae(q)[i] - self._rest_abscissae[i])

    @property
    def _rest_abscissae(self) -> np.ndarray:
        cached = self.__dict__.get("_rest_x")
        if cached is None:
            cached = self.contact_abscissae(self.rest_position())
            object.__setattr__(self, "_rest_x", cached)
        return cached

    def classical_impact_velocity(self, q: np.ndarray, v_minus: np.ndarray, mode) -> np.ndarray | None:
        """Post-impact velocities of an impact rule that replaces the impact LCP when the open contact of a
        rocking ``mode`` hits the ground; None (the default): the impact LCP with Newton's law decides."""
        return None

    # ------------------------------------------------------------------ contact modes
    @abstractmethod
    def mode_dofs(self, mode: Mode) -> tuple[int, ...]:
        """Indices in q of the reduced coordinates r integrated in ``mode``."""

    @abstractmethod
    def embed(self, mode: Mode, r: np.ndarray, r_dot: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Full (q, v) from the reduced state of ``mode`` (closed contacts stuck to the ground)."""

    @abstractmethod
    def mode_jacobian(self, mode: Mode, r: np.ndarray, r_dot: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(J, J_dot r_dot): v = J r_dot and v_dot = J r_ddot + J_dot r_dot for ``mode``."""

    def reduce(self, mode: Mode, q: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Reduced state of ``mode`` read from a full state that satisfies the mode's constraints."""
        idx = list(self.mode_dofs(mode))
        return np.array(q, dtype=float)[idx], np.array(v, dtype=float)[idx]

    def reduced_acceleration(self, mode: Mode, r: np.ndarray, r_dot: np.ndarray, ag: float,
                             ag_v: float = 0.0) -> np.ndarray:
        """r_ddot of ``mode``: (J^T M J) r_ddot = J^T (f - M J_dot r_dot) (Lagrange on the constrained system);
        ag, ag_v [m/s2] as in `forces`."""
        if len(r) == 0:
            return np.zeros(0)
        q, v = self.embed(mode, r, r_dot)
        J, jd = self.mode_jacobian(mode, r, r_dot)
        M = self.mass_matrix(q)
        rhs = J.T @ (self.forces(q, v, ag, ag_v) - M @ jd)
        return np.linalg.solve(J.T @ M @ J, rhs)

    def contact_forces(self, mode: Mode, q: np.ndarray, v: np.ndarray, ag: float, ag_v: float = 0.0) -> np.ndarray:
        """Normal forces [N] of the closed corners of ``mode`` held closed (bilateral), shape (2,); ag, ag_v
        [m/s2] as in `forces`.

        Generic: the acceleration-level problem with the mode's corners forced closed; models may override
        with a closed form."""
        return mode_forces(self, mode, q, v, ag, ag_v)

    @property
    def work_note(self) -> str:
        """What drives the cost of a step of this model, for the messages of a refused step (e.g. a stiff
        column's frequency); "" when nothing particular."""
        return ""

    @property
    def dof_scales(self) -> tuple:
        """Scale of each coordinate of q for the error control of the smooth phases: 1 [rad] for phi,
        length_scale [m] for the others (velocities are scaled by 1 / time_scale on top)."""
        L = self.length_scale
        return tuple(1.0 if i == self.phi_index else L for i in range(self.n_dof))

    @property
    def step_limit(self) -> float:
        """Largest Moreau-Jean step [s] the model tolerates (inf: no limit); the time-stepper sub-steps to it."""
        return math.inf

    # ------------------------------------------------------------------ any mode, sliding ones included
    # The models implement their sticking modes (above, closed forms); the sliding modes are generic
    # (`rocking_model.models.sliding`). The event-driven scheme calls these.
    def dofs_of(self, mode) -> tuple:
        """`mode_dofs` of any mode."""
        return sliding.slide_dofs(self, mode) if mode in SLIDING else self.mode_dofs(mode)

    def embed_any(self, mode, r, r_dot) -> tuple[np.ndarray, np.ndarray]:
        """`embed` of any mode."""
        return sliding.slide_embed(self, mode, r, r_dot) if mode in SLIDING else self.embed(mode, r, r_dot)

    def reduce_any(self, mode, q, v) -> tuple[np.ndarray, np.ndarray]:
        """`reduce` of any mode."""
        return sliding.slide_reduce(self, mode, q, v) if mode in SLIDING else self.reduce(mode, q, v)

    def functions_of(self, mode, ag):
        """(rhs, monitors, totals) of any mode: `mode_closures`, where with a finite mu a closed sticking mode
        gets one more event function before the overturning margin, (mu sum lambda_N - |sum lambda_T|) /
        force_scale, positive while the corners stick (the friction cone); a sliding mode's are those of
        `sliding.slide_functions` and its `force_totals_of`."""
        if mode in SLIDING:
            return sliding.slide_functions(self, mode, ag) + (self.force_totals_of(mode, ag),)
        rhs, monitors, totals = self.mode_closures(mode, ag)
        if math.isinf(self.mu) or not self.closed_of(mode):
            return rhs, monitors, totals
        mu, F = self.mu, self.force_scale

        def cone_monitors(t, y):
            out = monitors(t, y)
            lam_N, lam_T = totals(t, y)
            return out[:-1] + [(mu * lam_N - abs(lam_T)) / F, out[-1]]
        return rhs, cone_monitors, totals

    def mode_closures(self, mode, ag):
        """(rhs, monitors, totals) of the sticking ``mode``: `mode_functions` and, with closed corners,
        `force_totals_of` (None in flight). Models override it to share work between the monitors and the
        totals (the event-driven scheme evaluates both at the end of every step)."""
        return self.mode_functions(mode, ag) + (self.force_totals_of(mode, ag) if self.closed_of(mode) else None,)

    def force_totals_of(self, mode, ag):
        """float-level (t, y) -> (sum lambda_N, sum lambda_T) [N] of the closed corners of ``mode`` (the
        friction demand); generic numpy code, models may override with closed forms for sticking modes."""
        a_of = (lambda t: ag.value) if ag.constant else ag
        av_of = vertical_of(ag)
        if mode in SLIDING:
            k = len(sliding.slide_dofs(self, mode))
            sigma, inv_mu = SLIDING[mode][1], 0.0 if math.isinf(self.mu) else 1.0 / self.mu

            def slide_totals(t, y):
                q, v = sliding.slide_embed(self, mode, y[:k], y[k:])
                tau = float(np.sum(sliding.slide_motion(self, mode, q, v, a_of(t), av_of(t))[1]))
                return inv_mu * tau, -sigma * tau
            return slide_totals
        k = len(self.mode_dofs(mode))

        def totals(t, y):
            q, v = self.embed(mode, np.array(y[:k]), np.array(y[k:]))
            return sliding.force_totals(self, mode, q, v, a_of(t), av_of(t))
        return totals

    def outputs_of(self, mode, y, shift: float = 0.0) -> dict:
        """`mode_outputs` of any mode; ``shift`` [m]: the horizontal offset of a sticking mode's base."""
        if mode in SLIDING:
            k = len(y) // 2
            return self.outputs(*sliding.slide_embed(self, mode, y[:k], y[k:]))
        out = self.mode_outputs(mode, y)
        if shift:
            for name in self.SHIFTED_OUTPUTS:
                out[name] += shift
        return out

    def outputs_array_of(self, mode, Y, shift=None) -> dict:
        """`mode_outputs_array` of any mode; ``shift``: offsets per row (sticking modes)."""
        if mode in SLIDING:
            rows = [self.outputs_of(mode, list(y)) for y in Y]
            return {name: np.array([r[name] for r in rows], dtype=float) for name in rows[0]} if rows else {}
        out = self.mode_outputs_array(mode, Y)
        if shift is not None and np.any(shift):
            for name in self.SHIFTED_OUTPUTS:
                out[name] = out[name] + shift
        return out

    # ------------------------------------------------------------------ float-level mode functions
    @property
    def force_scale(self) -> float:
        """Scale of the contact forces [N] (the weight): normalises the force events."""
        q = self.rest_position()
        return float(np.linalg.norm(self.forces(q, np.zeros_like(q), 0.0)))

    def mode_functions(self, mode: Mode, ag):
        """(rhs, monitors) of ``mode`` under the ground motion ``ag`` (a GroundMotion), on lists of floats.

        rhs(t, y) -> [r_dot..., r_ddot...] for the reduced state y = [r..., r_dot...];
        monitors(t, y) -> [e_0, .., e_{n-1}, pi/2 - |phi|]: the event functions, positive inside the mode (the
        last one is the overturning margin [rad]); e_i of a closed corner is its normal force / force_scale, of an
        open corner a measure of its opening, positive while open (gap / length_scale; while rocking, the
        tilt -s phi [rad] of the lifted corner, exact where the gap loses digits).

        Generic version on top of the numpy interface; models override it with closed forms (the event-driven
        scheme calls these some twenty times per step)."""
        k = len(self.mode_dofs(mode))
        closed = self.closed_of(mode)
        nc = self.n_contacts
        F, L, ip = self.force_scale, self.length_scale, self.phi_index
        a_of = (lambda t: ag.value) if ag.constant else ag
        av_of = vertical_of(ag)

        def rhs(t, y):
            if k == 0:
                return []
            r, rd = np.array(y[:k]), np.array(y[k:])
            return list(y[k:]) + self.reduced_acceleration(mode, r, rd, a_of(t), av_of(t)).tolist()

        def monitors(t, y):
            q, v = self.embed(mode, np.array(y[:k]), np.array(y[k:]))
            lam = self.contact_forces(mode, q, v, a_of(t), av_of(t)) if closed else None
            g = self.gaps(q)
            phi = float(q[ip])
            out = []
            for i in range(nc):
                if i in closed:
                    out.append(float(lam[i]) / F)
                elif not closed:
                    out.append(float(g[i]) / L)
                else:
                    out.append(-phi if mode == Mode.RIGHT else phi)
            return out + [HALF_PI - abs(phi)]
        return rhs, monitors

    def mode_outputs(self, mode: Mode, y) -> dict[str, float]:
        """`outputs` of the reduced state y = [r..., r_dot...] of ``mode``."""
        k = len(y) // 2
        return self.outputs(*self.embed(mode, np.array(y[:k], dtype=float), np.array(y[k:], dtype=float)))

    def mode_outputs_array(self, mode: Mode, Y: np.ndarray) -> dict[str, np.ndarray]:
        """`mode_outputs` of many reduced states at once: Y has shape (N, 2k); arrays of length N."""
        rows = [self.mode_outputs(mode, list(y)) for y in Y]
        return {name: np.array([r[name] for r in rows], dtype=float) for name in rows[0]} if rows else {}

    # ------------------------------------------------------------------ quantities
    @abstractmethod
    def rest_position(self) -> np.ndarray:
        """q at rest in full contact."""

    @abstractmethod
    def energy(self, q: np.ndarray, v: np.ndarray) -> float:
        """Kinetic + potential energy relative to rest, in the ground frame [J]."""

    @abstractmethod
    def outputs(self, q: np.ndarray, v: np.ndarray) -> dict[str, float]:
        """Named outputs of a full state (the FMU output names)."""

    @property
    @abstractmethod
    def length_scale(self) -> float:
        """Characteristic length for tolerances [m]."""

    @property
    @abstractmethod
    def time_scale(self) -> float:
        """Characteristic time of the rocking motion, 1/p [s]."""

    @abstractmethod
    def initial_state(self, phi_0: float = 0.0, phi_dot_0: float = 0.0, **extra) -> tuple[Mode, np.ndarray, np.ndarray]:
        """(mode, q, v) of an initial condition; a non-zero tilt starts on the corresponding pivot.

        Raises ValueError naming the variable and its allowed range for unphysical values."""

    def mode_of_initial_state(self, phi_0: float, phi_dot_0: float) -> Mode:
        """Mode of an initial tilt: phi > 0 (or phi = 0 rotating positive) pivots on the left corner."""
        if phi_0 > 0.0 or (phi_0 == 0.0 and phi_dot_0 > 0.0):
            return Mode.LEFT
        if phi_0 < 0.0 or (phi_0 == 0.0 and phi_dot_0 < 0.0):
            return Mode.RIGHT
        return Mode.FULL
