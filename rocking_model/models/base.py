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

The simulations run in the compiled engine (rocking_model/engine/src: rk_rigid.c, rk_flexible.c implement the
same model per kind, with the contact problems and both schemes); the classes here declare the models
(parameters and their checks, initial values, outputs, derived quantities) and give their mechanics as numpy
functions for analysis: the closed-form impact maps (`rocking_model.post_impact`) and the tests use them.

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
    reduced_acceleration, contact_forces        per mode, from the numpy interface (each takes ag, ag_v=0.0)
    force_scale                                 scale of the contact forces [N]; default |f| at rest
    SHIFTED_OUTPUTS                             outputs that move with the base's horizontal offset

    fields()                                    declared parameters (name, unit, range, description):
                                                the Python API, the CLI and the FMUs read them
"""
from __future__ import annotations

import math
from abc import ABC, abstractmethod

import numpy as np

from ..modes import CLOSED, MODE_DESCRIPTIONS, OVERTURNED, OVERTURNED_DESCRIPTION, Mode, mode_from_closed
from ..params import Param, declared_parameters, param

#: [rad] the overturning angle: |phi| = pi/2 ends the motion (the last event function is HALF_PI - |phi|)
HALF_PI = 0.5 * math.pi

#: the initial rotation and rate, declared once for every rocking model (their `INITIAL` starts with them)
PHI_0 = Param("phi_0", 0.0, "rad", "Initial rotation (positive: pivoting on the left corner), |phi_0| < pi/2",
              lo=-math.pi / 2, hi=math.pi / 2, lo_open=True, hi_open=True)
PHI_DOT_0 = Param("phi_dot_0", 0.0, "rad/s", "Initial angular velocity", lo=-1e4, hi=1e4)


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

    # ------------------------------------------------------------------ scales
    @property
    def force_scale(self) -> float:
        """Scale of the contact forces [N] (the weight): normalises the force events."""
        q = self.rest_position()
        return float(np.linalg.norm(self.forces(q, np.zeros_like(q), 0.0)))

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
