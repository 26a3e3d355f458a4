"""What a model declares about its mechanics, for the code generator (`rocking_model.engine.gen_models`).

A rocking model is declared once, in its own file: its parameters, initial values and outputs (`Param`
declarations on the class) and a static method ``mechanics(sp, p, q, v)`` that returns a `Mechanics`. The
build step calls it with sympy (``sp``), the parameters as symbols (``p.b``, ``p.h``, ...), the generalized
coordinates ``q`` and velocities ``v`` (symbols, in the order of ``dof_names``), and writes every C kernel
the engine needs from it: mass matrix, forces, gaps, contact Jacobians and drifts, and the reduced dynamics,
event functions and contact forces of every contact mode. Nothing here imports sympy or numpy: the package
reads these declarations at run time without them.

Conventions (SI units): the ground frame moves with the ground; ``x`` horizontal along the ground
acceleration ``ag`` [m/s2], ``y`` upward; ``ag_v`` [m/s2] is the vertical ground acceleration, positive
upward. The ground accelerations enter only through the first moment of mass (Sx, Sy) [kg m]: the
potential of the inertial and gravity forces is ``ag * Sx + (g + ag_v) * Sy``.

The contact modes of a two-corner base are derived, not written: flight keeps every coordinate; rocking on
corner c solves "corner c at its rest position" for the base's translations (``slide_index``,
``lift_index``); full contact pins the base (translations and ``phi``) at its rest values. Their reduced
dynamics come from the Lagrangian restricted to the remaining coordinates. Where the forces depend on where
the base stands (a tendon anchored in the ground), the rest position is shifted by the base's horizontal
offset, which the engine carries beside the reduced state.

A force law with branches is a sympy ``Piecewise`` (a tendon that slackens); declare where it changes as a
`Switch`, so that the event-driven scheme steps to it.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable, Optional

#: marker values of `Mechanics.outputs`: quantities the generator computes itself
SLIP = "slip"          # horizontal displacement of the lower contact from its rest position [m]
ENERGY = "energy"      # kinetic + elastic + gravity (g, not g + ag_v) energy relative to rest [J]


@dataclass
class Check:
    """A parameter combination the model refuses: ``fails`` (a sympy boolean of the parameters and the
    derived quantities) makes the constructor fail with ``message``, a template whose ``{name}`` or
    ``{name:fmt}`` fields name parameters or entries of `Mechanics.derived` (printf formats: ``g``, ``.6g``)."""

    fails: Any
    message: str


@dataclass
class ClassicalImpact:
    """An impact rule the model adds to the contact laws, replacing the impact LCP at a rocking impact when
    the integer parameter ``param`` equals ``code``: ``velocity(q, v_minus, s_new)`` returns the full
    post-impact velocity (sympy expressions) when the corner of pivot sign ``s_new`` (-1 left, +1 right) lands
    while the body rocks on the other one."""

    param: str
    code: int
    velocity: Callable


@dataclass
class Switch:
    """A point where a smooth force law of the model changes (a kink of the forces, no impulse): ``value`` (a
    sympy expression of q, v and the parameters) crosses zero there, e.g. a tendon's force when it slackens.
    The event-driven scheme ends its step at each crossing (located to ``value``/``scale`` within its event
    tolerance), so that no Runge-Kutta step straddles the kink; ``description`` names it in reports."""

    value: Any
    scale: Any
    description: str


@dataclass
class Mechanics:
    """The mechanics of a model in its generalized coordinates (sympy expressions of ``p``, ``q``, ``v``).

    kinetic: kinetic energy relative to the ground T(q, v) [J].
    first_moment: (Sx, Sy), the first moment of mass sum(m_i x_i), sum(m_i y_i) [kg m]; gravity and the
        ground accelerations act through it.
    contacts: the contact points (X_c(q), Y_c(q)) [m] in the ground frame; Y_c is the contact's gap.
    rest: q at rest (every contact closed, nothing moving).
    potential: the elastic energy V(q) [J] (default none); its Hessian, evaluated at the step's start, is
        the stiff part that the time-stepper treats implicitly.
    dissipation: Rayleigh's dissipation function D(q, v) [W/2] (default none): the damping forces are -dD/dv.
    derived: named derived quantities (R, alpha, p, ...): they appear in the scales, checks and messages.
    length_scale [m], time_scale [s], force_scale [N]: scales of the tolerances and the event functions.
    step_limit [s]: largest time-stepper step (None: no limit).
    outputs: name -> expression of (q, v) for every declared output (`SLIP`, `ENERGY`: computed by the
        generator), in any order; the class's OUTPUTS fix the order.
    initial_bounds: name -> (lo, hi) expressions of the parameters, for initial values whose range
        depends on them.
    checks: parameter combinations refused by the constructor (`Check`).
    work_note: (template, ) what drives the cost of a step, named in work-limit messages (``{name:fmt}``
        fields as in `Check`), or None.
    classical_impact: the model's own impact rule (`ClassicalImpact`) or None.
    switches: the points where a force law changes (`Switch`), located as events by the event-driven scheme.
    """

    kinetic: Any
    first_moment: tuple
    contacts: list
    rest: tuple
    length_scale: Any
    time_scale: Any
    force_scale: Any
    outputs: dict
    potential: Any = 0
    dissipation: Any = 0
    derived: dict = field(default_factory=dict)
    step_limit: Any = None
    initial_bounds: dict = field(default_factory=dict)
    checks: list = field(default_factory=list)
    work_note: Optional[str] = None
    classical_impact: Optional[ClassicalImpact] = None
    switches: list = field(default_factory=list)
