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

A model is declared once, in its own file (RigidBlock: rigid_block.py, FlexibleOscillator:
flexible_oscillator.py): its parameters, initial values and outputs (`rocking_model.params.Param`) and its
mechanics (``mechanics``: kinetic energy, first moment of mass, elastic energy, dissipation, contact points;
`rocking_model.models.declare`). The engine's C kernels are generated from that declaration
(rocking_model/engine/gen_models.py); every numeric method of this class (mass matrix, forces, contact
relation, embedding of the contact modes, initial state, outputs, derived quantities) reads the same kernels.

Contract (in the style of scipy's ``OdeSolver``)
-----------------------------------------------
A subclass (a frozen dataclass) must provide:

    kind                        its registry name (`rocking_model.models.register_model`)
    parameters                  dataclass fields made by `rocking_model.params.param`, among them e_N,
                                impact_law, mu and g (`impact_law_param`, `friction_param`)
    dof_names, phi_index        names of q and the index of the rotation phi (overturning: |phi| = pi/2)
    slide_index, lift_index     indices of the base's horizontal and vertical translations
    INITIAL                     the initial values: phi_0, phi_dot_0 (`PHI_0`, `PHI_DOT_0`) and, for any other
                                coordinate c, c_0 and c_dot_0 (they set the initial mode's reduced state)
    OUTPUTS                     the outputs (`Param`s; `body_outputs` for the usual ones)
    mechanics(sp, p, q, v)      a `rocking_model.models.declare.Mechanics` (sympy, at build time)

A subclass may provide:

    SHIFTED_OUTPUTS             outputs that move with the base's horizontal offset (default x, slip)
    work_note                   what drives the cost of a step, for the messages of a refused step
    fmu_name, title             its FMU's name and a title

Everything else (mass matrix, forces, contact relation, the contact modes' embedding and dynamics, initial
state, outputs, scales, derived quantities) comes from the kernel generated from the declaration.
"""
from __future__ import annotations

import math
import operator
from abc import ABC

import numpy as np

from ..modes import CLOSED, MODE_DESCRIPTIONS, OVERTURNED, OVERTURNED_DESCRIPTION, Mode, mode_from_closed
from ..params import Param, check_parameters, declared_parameters, param

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


class _Info:
    """What the kernel says of one parameter set: scales, derived quantities, the default initial state."""

    __slots__ = ("length_scale", "time_scale", "force_scale", "step_limit", "dof_scales", "derived", "start")

    def __init__(self, info: dict):
        self.length_scale = info["length_scale"]
        self.time_scale = info["time_scale"]
        self.force_scale = info["force_scale"]
        self.step_limit = info["step_limit"]
        self.dof_scales = tuple(info["dof_scales"])
        self.derived = info["derived"]
        self.start = None


#: class -> the attrgetter of its declared parameters; (class, values) -> _Info (bounded)
_VALUES: dict = {}
_INFO: dict = {}
_CACHE_SIZE = 4096
#: rocking_model.engine.kernel_call, imported on first use
_KERNEL_CALL = [None]


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

    # ------------------------------------------------------------------ the kernel
    # Every quantity below is computed by the model's C kernel, generated from its declaration
    # (``mechanics``, rocking_model.models.declare): the formulas live in the declaration alone.
    def __post_init__(self):
        check_parameters(self)
        # the kernel's own checks (parameter combinations the declaration refuses), scales and derived
        # quantities: one call per distinct parameter set (a study builds many equal models)
        cls = type(self)
        getter = _VALUES.get(cls)
        if getter is None:
            getter = _VALUES[cls] = operator.attrgetter(*(p.name for p in cls.parameters()))
        values = getter(self)
        key = (cls, values)
        info = _INFO.get(key)
        if info is None:
            info = _Info(self._kernel("info", a=None, values=values))
            if len(_INFO) >= _CACHE_SIZE:
                _INFO.clear()
            _INFO[key] = info
        self.__dict__["_info"] = info

    def _param_values(self) -> tuple:
        return _VALUES[type(self)](self)

    def _kernel(self, fn: str, mode=0, a=None, b=None, ag: float = 0.0, ag_v: float = 0.0, values=None):
        call = _KERNEL_CALL[0]
        if call is None:
            from ..engine import kernel_call
            call = _KERNEL_CALL[0] = kernel_call
        return call(type(self), self._param_values() if values is None else values, fn, int(mode), a, b,
                    float(ag), float(ag_v))

    def __getattr__(self, name: str):
        # the declared derived quantities (R, alpha, p, ...) read as attributes
        if not name.startswith("_"):
            info = self.__dict__.get("_info")
            if info is not None and name in info.derived:
                return info.derived[name]
        raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")

    @property
    def derived(self) -> dict:
        """The declared derived quantities of this instance (name -> value, SI units)."""
        return dict(self._info.derived)

    @staticmethod
    def _vec(x) -> list:
        return [float(a) for a in np.asarray(x, dtype=float).ravel()]

    # ------------------------------------------------------------------ dynamical system
    def mass_matrix(self, q: np.ndarray) -> np.ndarray:
        """M(q), shape (n, n)."""
        n = self.n_dof
        return np.array(self._kernel("mass_matrix", 0, self._vec(q))).reshape(n, n)

    def inverse_mass_matrix(self, q: np.ndarray) -> np.ndarray:
        """M(q)^-1, shape (n, n)."""
        n = self.n_dof
        return np.array(self._kernel("inverse_mass_matrix", 0, self._vec(q))).reshape(n, n)

    def forces(self, q: np.ndarray, v: np.ndarray, ag: float, ag_v: float = 0.0) -> np.ndarray:
        """Non-contact generalized forces f(q, v, ag, ag_v), shape (n,), so that M q_ddot = f + contact forces;
        ag [m/s2] horizontal ground acceleration (+x), ag_v [m/s2] vertical (positive upward: gravity g becomes
        the effective gravity g + ag_v on every mass)."""
        return np.array(self._kernel("forces", 0, self._vec(q), self._vec(v), ag, ag_v))

    def stiff_jacobians(self, q: np.ndarray, v: np.ndarray):
        """(K, C) = (-df/dq, -df/dv) of the stiff linear part of f (the Hessians of the elastic energy and of the
        dissipation), treated implicitly by the time-stepper; None when f has none (the rigid block)."""
        out = self._kernel("stiff_jacobians", 0, self._vec(q), self._vec(v))
        if out is None:
            return None
        n = self.n_dof
        return np.array(out[0]).reshape(n, n), np.array(out[1]).reshape(n, n)

    # ------------------------------------------------------------------ contact relation
    def gaps(self, q: np.ndarray) -> np.ndarray:
        """Normal gaps g_N of the contacts [m], shape (n_contacts,)."""
        return np.array(self._kernel("gaps", 0, self._vec(q)))

    def contact_jacobians(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(W_N, W_T), each shape (n, n_contacts): normal and tangential velocity of contact i is W[:, i] . v."""
        W_N, W_T = self._kernel("contact_jacobians", 0, self._vec(q))
        shape = (self.n_dof, self.n_contacts)
        return np.array(W_N).reshape(shape), np.array(W_T).reshape(shape)

    def contact_drift(self, q: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(a_N, a_T), each shape (n_contacts,): the terms (d/dt W)^T v of the contact accelerations."""
        a_N, a_T = self._kernel("contact_drift", 0, self._vec(q), self._vec(v))
        return np.array(a_N), np.array(a_T)

    def contact_abscissae(self, q: np.ndarray) -> np.ndarray:
        """Horizontal positions of the contacts relative to the ground [m], shape (n_contacts,)."""
        return np.array(self._kernel("contact_abscissae", 0, self._vec(q)))

    def slip(self, q: np.ndarray) -> float:
        """Base sliding displacement [m]: the horizontal displacement of the lower corner from its rest
        position (0 while the corners stick; continuous through rocking, flight and landing, as the lower
        corner is the pivot, the one that lands, and the corners swap at phi = 0 where both agree)."""
        return self._kernel("slip", 0, self._vec(q))

    # ------------------------------------------------------------------ contact modes
    def mode_dofs(self, mode: Mode) -> tuple[int, ...]:
        """Indices in q of the reduced coordinates r integrated in ``mode``."""
        return tuple(self._kernel("mode_dofs", mode))

    def embed(self, mode: Mode, r: np.ndarray, r_dot: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Full (q, v) from the reduced state of ``mode`` (closed contacts stuck to the ground at their rest
        abscissae)."""
        q, v = self._kernel("embed", mode, self._vec(r), self._vec(r_dot))
        return np.array(q), np.array(v)

    def mode_jacobian(self, mode: Mode, r: np.ndarray, r_dot: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(J, J_dot r_dot): v = J r_dot and v_dot = J r_ddot + J_dot r_dot for ``mode``."""
        J, jd = self._kernel("mode_jacobian", mode, self._vec(r), self._vec(r_dot))
        return np.array(J).reshape(self.n_dof, -1) if J else np.zeros((self.n_dof, 0)), np.array(jd)

    def reduce(self, mode: Mode, q: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Reduced state of ``mode`` read from a full state that satisfies the mode's constraints."""
        idx = list(self.mode_dofs(mode))
        return np.array(q, dtype=float)[idx], np.array(v, dtype=float)[idx]

    def reduced_acceleration(self, mode: Mode, r: np.ndarray, r_dot: np.ndarray, ag: float,
                             ag_v: float = 0.0) -> np.ndarray:
        """r_ddot of ``mode``: (J^T M J) r_ddot = J^T (f - M J_dot r_dot) (Lagrange on the constrained system);
        ag, ag_v [m/s2] as in `forces`."""
        k = len(r)
        if k == 0:
            return np.zeros(0)
        dy = self._kernel("mode_rhs", mode, self._vec(r) + self._vec(r_dot), None, ag, ag_v)
        return np.array(dy[k:])

    def contact_forces(self, mode: Mode, q: np.ndarray, v: np.ndarray, ag: float, ag_v: float = 0.0) -> np.ndarray:
        """Normal forces [N] of the closed contacts of ``mode`` held closed (0 for the open ones)."""
        return np.array(self._kernel("contact_forces", mode, self._vec(q), self._vec(v), ag, ag_v))

    @property
    def work_note(self) -> str:
        """What drives the cost of a step of this model, for the messages of a refused step (e.g. a stiff
        column's frequency); "" when nothing particular."""
        return ""

    # ------------------------------------------------------------------ scales
    @property
    def length_scale(self) -> float:
        """Characteristic length for tolerances [m]."""
        return self._info.length_scale

    @property
    def time_scale(self) -> float:
        """Characteristic time of the rocking motion, 1/p [s]."""
        return self._info.time_scale

    @property
    def force_scale(self) -> float:
        """Scale of the contact forces [N] (the weight): normalises the force events."""
        return self._info.force_scale

    @property
    def step_limit(self) -> float:
        """Largest Moreau-Jean step [s] the model tolerates (inf: no limit); the time-stepper sub-steps to it."""
        return self._info.step_limit

    @property
    def dof_scales(self) -> tuple:
        """Scale of each coordinate of q for the error control of the smooth phases: 1 [rad] for phi,
        length_scale [m] for the others (velocities are scaled by 1 / time_scale on top)."""
        return self._info.dof_scales

    # ------------------------------------------------------------------ quantities
    def rest_position(self) -> np.ndarray:
        """q at rest in full contact."""
        return np.array(self._kernel("rest_position"))

    def energy(self, q: np.ndarray, v: np.ndarray) -> float:
        """Kinetic + potential energy relative to rest, in the ground frame [J]."""
        return self._kernel("energy", 0, self._vec(q), self._vec(v))

    def outputs(self, q: np.ndarray, v: np.ndarray) -> dict[str, float]:
        """Named outputs of a full state (the FMU output names)."""
        values = self._kernel("outputs", 0, self._vec(q), self._vec(v))
        return dict(zip((p.name for p in self.OUTPUTS), values))

    def initial_state(self, **initial) -> tuple[Mode, np.ndarray, np.ndarray]:
        """(mode, q, v) of the initial values (the keywords of `INITIAL`); a non-zero tilt starts on the
        corresponding pivot. Raises ValueError naming the variable and its allowed range for unphysical values."""
        mode, q, v = self._start_state(**initial)
        return mode, np.array(q), np.array(v)

    def _start_state(self, **initial) -> tuple:
        """`initial_state` with q and v as tuples of floats (what the engine reads: no arrays made and converted
        back per run; the default start is computed once per model)."""
        if not initial:
            start = self._info.start
            if start is None:
                mode, q, v = self._kernel("initial_state", 0, [float(p.default) for p in self.INITIAL])
                start = self._info.start = (Mode(mode), tuple(map(float, q)), tuple(map(float, v)))
            return start
        names = {p.name for p in self.INITIAL}
        self.check_initial_names([k for k in initial if k not in names])
        # numbers go to the kernel, which checks their ranges (some depend on the parameters: the declaration's
        # initial_bounds); anything else is converted or refused by its declaration's message
        values = []
        for p in self.INITIAL:
            x = initial.get(p.name, p.default)
            values.append(float(x) if isinstance(x, (int, float)) and not isinstance(x, bool) else float(p.check(x)))
        mode, q, v = self._kernel("initial_state", 0, values)
        return Mode(mode), tuple(map(float, q)), tuple(map(float, v))

    def mode_of_initial_state(self, phi_0: float, phi_dot_0: float) -> Mode:
        """Mode of an initial tilt: phi > 0 (or phi = 0 rotating positive) pivots on the left corner."""
        if phi_0 > 0.0 or (phi_0 == 0.0 and phi_dot_0 > 0.0):
            return Mode.LEFT
        if phi_0 < 0.0 or (phi_0 == 0.0 and phi_dot_0 < 0.0):
            return Mode.RIGHT
        return Mode.FULL
