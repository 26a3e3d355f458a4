"""The contract of an integration scheme (`Integrator`) and the registry of schemes (`SCHEMES`).

In the style of scipy's ``OdeSolver``: `rocking_model.simulation.Simulator` drives any registered scheme
through this interface only, and handles for all of them the checkpoint / rollback around an advance, the
check of the outputs, the reports (`Report`) and the plain-data state header.

A subclass must provide:

    name : str                  registry name ("moreau_jean", "event_driven")
    code : int                  integer code of the scheme (the FMU parameter ``scheme``)
    summary : str               one line describing it
    STATE_KEYS : tuple          fields of `get_state`
    STATE_TOKEN : str           an attribute that is replaced (never mutated) whenever the state changes:
                                the Simulator keys its cache of the outputs on its identity
    from_options(model, mode, q, v, t0, options) -> Integrator
                                a new integrator from the user's solver options (`SolverOptions`), checking
                                those that concern it (ValueError naming the option and its range)
    advance(t_end, ag, max_steps=None)
                                integrate to exactly t_end under the ground motion ``ag`` (a GroundMotion);
                                raise `WorkLimitError` beyond max_steps internal steps
    state() -> (q, v)           full coordinates and velocities now
    outputs() -> dict           the model's outputs now
    get_state() -> dict, set_state(state)
                                plain-data state (the Simulator adds and checks the header)

and keep these attributes current: ``model``, ``t`` [s], ``mode`` (the model's contact mode), ``impacts``
(count), ``impact_times`` (a `BoundedLog`), ``overturned`` (bool), ``n_steps`` (internal steps),
``friction_demand`` (the largest |sum lambda_T| / sum lambda_N of the closed contacts so far, `note_demand`)
and ``painleve`` (Painleve situations resolved so far), the last two in `get_state`.

Overturning (|phi| = pi/2) ends the motion: a scheme sets ``overturned``, keeps the pose it reached there and
sets every velocity to 0; time still advances, the state no longer changes, and
``contact`` reads `OVERTURNED` (`contact_code`) while ``mode`` keeps the last contact mode.

A subclass may provide:

    sample(times, ag, max_steps) -> (contact codes, values, impacts, overturned)
                                outputs at many times in one pass (default: advance to each time and read
                                `outputs`; the event-driven scheme reads its dense output instead)
    LOGS : tuple                names of its `BoundedLog` attributes (see `Checkpointed`)

Reports: a scheme appends a `Report` to ``reports`` for everything the user must know about an advance that
is not an error: a contact LCP without an exact solution, an adaptive step accepted at the smallest step
size with its error above tolerance. The Simulator turns them into warnings (Python API) or log messages
and refused steps (FMUs).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np

from ..modes import OVERTURNED, contact_states, slide_sign
from ..tolerances import DEFAULT_TOLERANCES, ZENO_TOL, ContactTolerances
from .state import Checkpointed


@dataclass(frozen=True)
class Report:
    """Something an advance did that the user must know about (not an error).

    kind: "inexact_contact" (a contact LCP whose best active set violates its conditions beyond
    ContactTolerances.lcp_exact) or "failed_step" (an adaptive step accepted at the smallest step size with
    its error estimate above the tolerance); t [s]; message (what, where, by how much)."""

    kind: str
    t: float
    message: str

    #: kinds that make a step unreliable: an FMU refuses the step (fmi2Discard)
    FAILURES: ClassVar[tuple] = ("failed_step",)


@dataclass(frozen=True)
class SolverOptions:
    """The user's solver options, checked by the scheme that uses them (`Integrator.from_options`).

    dt_max [s] (0: the scheme's default), tolerance [1], theta [1], zeno_tol [1], method (Runge-Kutta pair),
    impact_log_size (None: all), tolerances (`ContactTolerances`)."""

    dt_max: float = 0.0
    tolerance: float = 1e-8
    theta: float = 0.5
    zeno_tol: float = ZENO_TOL
    method: str = "DOP853"
    impact_log_size: int | None = None
    tolerances: ContactTolerances = field(default=DEFAULT_TOLERANCES)

    @classmethod
    def of(cls, dt_max, tolerance, theta, zeno_tol, method, impact_log_size, tolerances) -> "SolverOptions":
        """``SolverOptions(...)`` with every field given, the fields written into the instance's dict at once
        (the frozen dataclass's __init__ makes one object.__setattr__ call per field: a Simulator per run of an
        ensemble made that a measurable part of its set-up). Equal to the instance __init__ makes."""
        obj = object.__new__(cls)
        obj.__dict__.update(dt_max=dt_max, tolerance=tolerance, theta=theta, zeno_tol=zeno_tol, method=method,
                            impact_log_size=impact_log_size, tolerances=tolerances)
        return obj


class Integrator(Checkpointed):
    """Base class of the integration schemes: see the module docstring for the contract."""

    name: ClassVar[str] = ""
    code: ClassVar[int] = -1
    #: one line for documentation and tools (the FMU's enumeration item)
    summary: ClassVar[str] = ""
    STATE_KEYS: ClassVar[tuple] = ()
    STATE_TOKEN: ClassVar[str] = ""

    #: reports of the current advance (cleared by the Simulator before each one)
    reports: list
    #: [1] the largest friction coefficient the contacts needed so far: |sum lambda_T| / sum lambda_N of the
    #: closed contacts (event-driven: the continuous maximum of the forces' ratio and each impact's
    #: percussions; Moreau-Jean: each time-step's percussions); at most mu, as sliding caps it
    friction_demand: float = 0.0
    #: Painleve situations met so far (each resolved by an impact without collision)
    painleve: int = 0

    @classmethod
    def from_options(cls, model, mode, q: np.ndarray, v: np.ndarray, t0: float,
                     options: SolverOptions) -> "Integrator":
        raise NotImplementedError

    def advance(self, t_end: float, ag, max_steps: int | None = None) -> None:
        raise NotImplementedError

    def state(self) -> tuple[np.ndarray, np.ndarray]:
        raise NotImplementedError

    def outputs(self) -> dict:
        raise NotImplementedError

    def get_state(self) -> dict:
        raise NotImplementedError

    def set_state(self, state) -> None:
        raise NotImplementedError

    @property
    def contact_code(self) -> int:
        """The output ``contact``: the mode's code, `OVERTURNED` once overturned."""
        return OVERTURNED if self.overturned else int(self.mode)

    @property
    def contacts(self) -> tuple:
        """`ContactState` of each contact now."""
        return contact_states(self.model.closed_of(self.mode), self.model.n_contacts, slide_sign(self.mode))

    def note_demand(self, lam_N: float, lam_T: float, floor: float) -> None:
        """Raise ``friction_demand`` to |lam_T| / lam_N if larger (forces with lam_N above ``floor`` [N],
        `ContactTolerances.demand_floor`)."""
        if lam_N > floor:
            self.note_ratio(abs(lam_T) / lam_N)

    def note_ratio(self, d) -> None:
        """Raise ``friction_demand`` to the ratio ``d`` [1] if larger (None: no ratio). At most mu: sliding
        caps it (a stick-slip transition is located where the ratio reaches mu, to round-off)."""
        if d is not None and d > self.friction_demand:
            self.friction_demand = min(d, self.model.mu)

    def report(self, kind: str, t: float, message: str) -> None:
        """Record a `Report` of the current advance."""
        reports = self.__dict__.get("reports")
        if reports is None:
            reports = self.reports = []
        reports.append(Report(kind, float(t), message))

    def sample(self, times, ag, max_steps: int | None = None):
        """Outputs at ``times`` (increasing, after t): (modes, values, impacts, overturned), arrays of
        len(times) + 1 starting with the current state (values: the model's outputs, friction_demand and
        painleve); the work budget applies per interval."""
        rows = [self._row()]
        for t in times:
            self.advance(float(t), ag, max_steps=max_steps)
            rows.append(self._row())
        names = list(rows[0][1])
        values = {n: np.array([r[1][n] for r in rows]) for n in names}
        values["friction_demand"] = np.array([r[4] for r in rows])
        values["painleve"] = np.array([r[5] for r in rows])
        return (np.array([r[0] for r in rows]), values, np.array([r[2] for r in rows]),
                np.array([r[3] for r in rows], dtype=bool))

    def _row(self):
        return self.contact_code, self.outputs(), self.impacts, self.overturned, self.friction_demand, self.painleve


#: registry of the schemes: name -> class (`register_scheme`)
SCHEMES: dict[str, type] = {}


def register_scheme(cls: type) -> type:
    """Class decorator: add an `Integrator` subclass to `SCHEMES` under its ``name``."""
    if not (isinstance(cls, type) and issubclass(cls, Integrator)) or not cls.name:
        raise TypeError(f"{cls!r} is not a named Integrator subclass")
    SCHEMES[cls.name] = cls
    return cls


def scheme_choices() -> dict:
    """The accepted spellings of a scheme: its name and its integer code -> name."""
    out = {}
    for name, cls in SCHEMES.items():
        out[name] = name
        out[cls.code] = name
    return out


def scheme_class(scheme) -> type:
    """The registered class of ``scheme`` (name or code); ValueError listing the allowed values."""
    from ..validation import check_choice
    return SCHEMES[check_choice("scheme", scheme, scheme_choices())]

