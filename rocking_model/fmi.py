"""Shared FMI 2.0 co-simulation plumbing for the rocking FMUs (pythonfmu 0.7, driven by fmpy).

This module knows nothing about the physics. An FMU script (``fmu_src/<Name>.py``, unique module name)
subclasses :class:`RockingSlave`, declares its interface as a table of :class:`Var` and implements
:meth:`RockingSlave.create_simulator`, which builds the model and its `Simulator` from the parameter
values when the importer leaves initialization mode::

    class MyBlock(RockingSlave):
        description = "..."
        variables = (
            Var("b", "parameter", 0.2, unit="m", description="half-width"),
            Var("ag", "input", 0.0, unit="m/s2", description="ground acceleration"),
            Var("phi", "output", unit="rad", description="rotation"),
            ...
        )

        def create_simulator(self, p, t0):
            return Simulator(RigidBlock(b=p["b"]), t0=t0)

What the base class provides:

* registration of every variable with description, unit, start value and an explicit variability
  (parameters ``fixed``, Real inputs/outputs ``continuous``, Integer/Boolean outputs ``discrete``,
  outputs ``initial="calculated"``);
* a modelDescription that passes ``fmpy validate``: ``<UnitDefinitions>`` (with ``<BaseUnit>`` exponents)
  inserted after ``<CoSimulation>``, a ``<DefaultExperiment>``, ``ModelStructure/Outputs`` (no direct
  feed-through: ``dependencies=""``) and ``ModelStructure/InitialUnknowns``;
* ``do_step(t, dt)``: advances the simulator to ``t + dt`` with the inputs held constant over the step
  (zero-order hold, the importer sets the inputs at the start of each step) or, after
  ``fmi2SetRealInputDerivatives`` of order 1 (`set_real_input_derivatives`, ``canInterpolateInputs`` is
  true where ``interpolates_inputs``), varying linearly over it (`rocking_model.ground_motion.LinearMotion`),
  and copies ``Simulator.outputs()`` to the output variables;
* FMU state (``canGetAndSetFMUstate`` and ``canSerializeFMUstate`` are true): ``fmi2GetFMUstate`` captures
  the complete internal state -- the values of every variable, the communication time, the status flags
  (initialized, terminated, frozen, failed, pending error) and the simulator's plain-data state
  (`Simulator.get_state`: time, contact mode, coordinates, counters, step-size memory) -- as the serialized
  byte string of `rocking_model.fmi_state` (versioned, data only, no pickle). ``fmi2SetFMUstate`` checks
  every field (type, shape, range), rebuilds the simulator from the saved parameter values and sets its
  state, in the same or in another instance of the same FMU, so that save -> step -> restore -> step gives
  bit-identical outputs (rollback for iterative masters). A state of another FMU, a corrupted, truncated,
  foreign or junk byte string is rejected when it is set: error log, the instance keeps its state and the
  next ``do_step`` is discarded once;
* ``fmi2Reset``: the pythonfmu 0.7 C wrapper re-creates the Python object (start values, not initialized);
  :meth:`RockingSlave.reset` does the same in place for direct use of the class.

Status of every FMI call. The FMUs run the project's own binary (``fmi_binary/``, see its ``fmi2_cs.c``),
which calls these pythonfmu methods directly: an exception is fmi2Error (its text goes to the importer's
logger, the instance is in the error state until fmi2Reset or fmi2SetFMUstate), ``do_step`` returning False
is fmi2Discard, a warning logged during the call is fmi2Warning. The binary checks the call sequence, NULL
arguments, ``fmi2SetupExperiment``'s times and ``fmi2DoStep``'s step size and communication point itself;
the same checks here serve direct users of the class. Hence:

* invalid parameters (the model / Simulator raise ``ValueError`` naming the variable and its allowed range):
  ``exit_initialization_mode`` raises, fmi2ExitInitializationMode is fmi2Error (fmpy raises
  ``FMICallException``, the message is printed by its logger);
* an invalid value reference (unknown, of another type, an output set), a value that cannot be converted, an
  input outside its declared ``min``/``max`` or not finite, a ``fixed`` parameter changed after
  initialization: the setter or getter raises and nothing of that call is set (fmi2Error);
* a step whose internal work would exceed the simulator's budget (`WorkLimitError`) or that would leave the
  physical ranges (``ValueError`` from the simulator): error log naming the cause and the way out,
  ``do_step`` returns False (fmi2Discard), the state is unchanged and the step can be retried;
* any other exception inside the integrator: ``do_step`` raises (fmi2Error) and keeps refusing until reset;
* a rejected FMU state (foreign, corrupted, of another FMU): ``_set_fmu_state`` raises, the instance keeps its
  state (fmi2Error);
* once the output named by ``freeze_output`` (``"overturned"``) is true the integration stops, the outputs
  stay frozen (a warning says so) and ``do_step`` keeps returning True.

Messages are queued with `RockingSlave.log`; the binary passes each one to the importer's logger as data
(``"%s"``): errors and warnings always, the others only with logging on.

Each FMU bundles the package under the digest of its sources (``build_fmu.py``), so FMUs built from other
versions and a host's own ``rocking_model`` can live in one process.
"""
from __future__ import annotations

import hashlib
import math
import threading
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any, ClassVar, Dict, List, Optional, Sequence
from xml.etree.ElementTree import Element, SubElement

from pythonfmu import Fmi2Causality, Fmi2Slave, Fmi2Variability
from pythonfmu.default_experiment import DefaultExperiment
from pythonfmu.enums import Fmi2Initial, Fmi2Status
from pythonfmu.variables import Boolean, Integer, Real, String

from .fmi_state import decode_state, encode_state
from .ground_motion import LinearMotion
from .simulation import Simulator, report_summary
from .validation import AG_MAX, MAX_STEPS, WorkLimitError, check_real, check_state_keys, state_bool

__all__ = ["AG_INPUT", "AG_MAX", "MAX_STEPS_PARAMETER", "UNITS", "Var", "RockingSlave", "DefaultExperiment",
           "Fmi2Status", "FMUError", "run_fmu", "run_fmu_record", "fmpy_callbacks", "collect_fmu_messages"]

# SI base-unit exponents of every unit an FMU of this package may use (FMI 2.0 <BaseUnit> attributes).
UNITS: Dict[str, Dict[str, int]] = {
    "1": {},
    "m": {"m": 1},
    "s": {"s": 1},
    "kg": {"kg": 1},
    "rad": {"rad": 1},
    "rad/s": {"rad": 1, "s": -1},
    "rad/s2": {"rad": 1, "s": -2},
    "m/s": {"m": 1, "s": -1},
    "m/s2": {"m": 1, "s": -2},
    "1/s": {"s": -1},
    "Hz": {"s": -1},
    "J": {"kg": 1, "m": 2, "s": -2},
    "N": {"kg": 1, "m": 1, "s": -2},
    "N.m": {"kg": 1, "m": 2, "s": -2},
    "N.m2": {"kg": 1, "m": 3, "s": -2},
    "N/m": {"kg": 1, "s": -2},
    "N.s/m": {"kg": 1, "s": -1},
    "kg/m": {"kg": 1, "m": -1},
    "kg.m2": {"kg": 1, "m": 2},
    "Pa": {"kg": 1, "m": -1, "s": -2},
}

_CAUSALITIES = {"parameter": Fmi2Causality.parameter, "input": Fmi2Causality.input,
                "output": Fmi2Causality.output}
_VARIABILITIES = {"fixed": Fmi2Variability.fixed, "tunable": Fmi2Variability.tunable,
                  "discrete": Fmi2Variability.discrete, "continuous": Fmi2Variability.continuous}
_PY_TYPES = {"Real": float, "Integer": int, "Boolean": bool, "String": str}


@dataclass(frozen=True)
class Var:
    """One FMU variable.

    name: FMI name (also the key in the parameter dict and in ``Simulator.outputs()``).
    causality: "parameter", "input" or "output".
    start: start value (parameters, inputs); outputs report it until initialization is done.
    type: "Real", "Integer", "Boolean" or "String" (String: parameters only, e.g. a file name).
    unit: unit name, a key of ``UNITS`` (or of the FMU's ``extra_units``); required for Real.
    description: text for the modelDescription.
    variability: default "fixed" for parameters, "continuous" for Real inputs/outputs, "discrete"
        otherwise. A "tunable" parameter may be changed after initialization (the subclass must read it
        from ``self.parameter_values`` itself); "fixed" ones may not.
    min, max: optional declared range (written to the XML; inputs are checked against it in do_step).
    """

    name: str
    causality: str
    start: Any = None
    type: str = "Real"
    unit: Optional[str] = None
    description: str = ""
    variability: Optional[str] = None
    min: Optional[float] = None
    max: Optional[float] = None

    def __post_init__(self):
        if self.causality not in _CAUSALITIES:
            raise ValueError(f"Var {self.name!r}: causality must be one of {sorted(_CAUSALITIES)}")
        if self.type not in _PY_TYPES:
            raise ValueError(f"Var {self.name!r}: type must be one of {sorted(_PY_TYPES)}")
        if self.type == "Real" and self.unit is None:
            raise ValueError(f"Var {self.name!r}: a Real variable needs a unit ('1' if dimensionless)")
        if self.type != "Real" and self.unit is not None:
            raise ValueError(f"Var {self.name!r}: only Real variables carry a unit in FMI 2.0")
        if not self.description:
            raise ValueError(f"Var {self.name!r}: a description is required")
        if self.resolved_variability not in _VARIABILITIES:
            raise ValueError(f"Var {self.name!r}: variability must be one of {sorted(_VARIABILITIES)}")
        if self.causality == "parameter" and self.resolved_variability not in ("fixed", "tunable"):
            raise ValueError(f"Var {self.name!r}: a parameter is 'fixed' or 'tunable'")
        if self.type == "String" and self.causality != "parameter":
            raise ValueError(f"Var {self.name!r}: String variables are parameters here")
        if self.type != "Real" and self.resolved_variability == "continuous":
            raise ValueError(f"Var {self.name!r}: only Real variables can be 'continuous'")

    @property
    def resolved_variability(self) -> str:
        if self.variability is not None:
            return self.variability
        if self.causality == "parameter":
            return "fixed"
        return "continuous" if self.type == "Real" else "discrete"

    @property
    def default(self):
        """Start value cast to the Python type (0 / 0.0 / False when no start is given)."""
        py = _PY_TYPES[self.type]
        return py(0) if self.start is None else py(self.start)

    def range_text(self) -> str:
        lo = "-inf" if self.min is None else f"{self.min:g}"
        hi = "inf" if self.max is None else f"{self.max:g}"
        return f"[{lo}, {hi}]"


#: the ground acceleration input of every FMU that takes one (the bound of `rocking_model.validation.AG_MAX`)
AG_INPUT = Var("ag", "input", 0.0, unit="m/s2", min=-AG_MAX, max=AG_MAX,
               description="Horizontal ground acceleration (held constant over each communication step), "
                           f"|ag| <= {AG_MAX:g} m/s2 (about 100 g)")
#: the work budget of one communication step, a parameter of every FMU that runs a `Simulator`
MAX_STEPS_PARAMETER = Var("max_steps", "parameter", MAX_STEPS, type="Integer", min=1, max=1000000000,
                          description="Work budget of one communication step: internal steps (Moreau-Jean "
                                      "steps, or Runge-Kutta steps with each event counting 30); a step that "
                                      "needs more is refused (fmi2Discard, state unchanged, message naming "
                                      "the cause)")


# ----------------------------------------------------------------------------------------------------
# pythonfmu variables with the attributes pythonfmu 0.7 does not write (unit, min, max)
def _fmt(value, type_: str) -> str:
    if type_ == "Real":
        return f"{float(value):.16g}"
    if type_ == "Boolean":
        return "true" if value else "false"
    return str(int(value))


class _ExtraAttrs:
    """Mixin: add attributes to the type element (<Real>, <Integer>) of the ScalarVariable node."""

    _type_tag = ""

    def _set_extra(self, **attrs):
        self._extra = {k: v for k, v in attrs.items() if v is not None}

    def to_xml(self) -> Element:
        node = super().to_xml()
        child = node.find(self._type_tag)
        for key, value in getattr(self, "_extra", {}).items():
            child.set(key, value)
        return node


class UnitReal(_ExtraAttrs, Real):
    """pythonfmu ``Real`` with ``unit``, ``min`` and ``max`` attributes."""

    _type_tag = "Real"

    def __init__(self, name: str, unit: str, min: Optional[float] = None, max: Optional[float] = None,
                 **kwargs):
        super().__init__(name, **kwargs)
        self.unit = unit
        self._set_extra(unit=unit, min=None if min is None else _fmt(min, "Real"),
                        max=None if max is None else _fmt(max, "Real"))


class RangedInteger(_ExtraAttrs, Integer):
    """pythonfmu ``Integer`` with ``min`` and ``max`` attributes."""

    _type_tag = "Integer"

    def __init__(self, name: str, min: Optional[int] = None, max: Optional[int] = None, **kwargs):
        super().__init__(name, **kwargs)
        self._set_extra(min=None if min is None else _fmt(min, "Integer"),
                        max=None if max is None else _fmt(max, "Integer"))


# ----------------------------------------------------------------------------------------------------
def _package_version() -> Optional[str]:
    try:
        from . import __version__
        return str(__version__)
    except Exception:  # pragma: no cover - only outside the package
        return None


class RockingSlave(Fmi2Slave):
    """Generic co-simulation slave around a `rocking_model.simulation.Simulator`.

    Subclasses set the class attributes ``variables`` (a sequence of :class:`Var`), ``description``,
    optionally ``default_experiment``, ``extra_units`` and ``freeze_output``, and implement
    :meth:`create_simulator`. Override :meth:`advance` if the simulator takes more than one input.
    """

    variables: ClassVar[Sequence[Var]] = ()
    description: ClassVar[Optional[str]] = None
    author: ClassVar[Optional[str]] = "rocking_model developers"
    license: ClassVar[Optional[str]] = "MIT"
    version: ClassVar[Optional[str]] = _package_version()
    default_experiment: ClassVar[Optional[DefaultExperiment]] = DefaultExperiment(
        start_time=0.0, stop_time=10.0, step_size=0.01)
    extra_units: ClassVar[Dict[str, Dict[str, int]]] = {}
    #: name of a Boolean output that ends the motion (outputs freeze once it is true); None: never
    freeze_output: ClassVar[Optional[str]] = "overturned"
    #: relative tolerance on current_time versus the FMU's own communication time
    time_tolerance: ClassVar[float] = 1e-9
    #: whether `advance` takes a time-varying input (then fmi2SetRealInputDerivatives of order 1 makes the
    #: inputs vary linearly over a step: canInterpolateInputs = true)
    interpolates_inputs: ClassVar[bool] = True

    log_categories = {
        "logStatusWarning": "Log messages with fmi2Warning status.",
        "logStatusError": "Log messages with fmi2Error status.",
        "logAll": "Log all messages.",
    }

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self._specs: Dict[str, Var] = {}
        self._values: Dict[str, Any] = {}
        self._clear_state()
        names = set()
        for spec in self.variables:
            if spec.name in names:
                raise ValueError(f"duplicate FMU variable {spec.name!r}")
            names.add(spec.name)
            units = {**UNITS, **self.extra_units}
            if spec.unit is not None and spec.unit not in units:
                raise ValueError(f"Var {spec.name!r}: unit {spec.unit!r} is not defined; add it to extra_units")
            self._specs[spec.name] = spec
            self._values[spec.name] = spec.default
            self.register_variable(self._make_variable(spec), nested=False)
        self._vr_of = {var.name: vr for vr, var in self.vars.items()}
        # what every do_step reads, resolved once
        self._inputs = [(s.name, s.min, s.max) for s in self.variables if s.causality == "input"]
        self._outputs = [(s.name, _PY_TYPES[s.type]) for s in self.variables if s.causality == "output"]

    def _clear_state(self) -> None:
        # the FMU state (fmi2GetFMUstate / fmi2SetFMUstate): these flags, the variable values and the simulator
        self._sim = None
        self._initialized = False
        self._terminated = False
        self._error: Optional[str] = None        # permanent failure (an integrator crash), until reset
        self._frozen = False
        self._t = 0.0                            # current communication point [s]
        self._t0 = 0.0
        # Real input -> (rate [unit/s], t_ref [s]): the input is value + rate (t - t_ref) (first-order hold)
        self._rates: Dict[str, tuple] = {}

    def reset(self) -> None:
        """fmi2Reset in place: start values, not initialized, no error (the log queue is kept).

        The binary implements fmi2Reset by creating a new slave, which has the same effect; this method
        serves direct users of the class."""
        self._clear_state()
        for name, spec in self._specs.items():
            self._values[name] = spec.default

    # ------------------------------------------------------------------ variable registration
    def _make_variable(self, spec: Var):
        kwargs = dict(causality=_CAUSALITIES[spec.causality], description=spec.description,
                      variability=_VARIABILITIES[spec.resolved_variability],
                      getter=self._getter(spec.name), setter=self._setter(spec))
        if spec.causality == "output":
            kwargs["initial"] = Fmi2Initial.calculated
        elif spec.causality == "parameter":
            kwargs["initial"] = Fmi2Initial.exact
        if spec.type == "Real":
            return UnitReal(spec.name, unit=spec.unit, min=spec.min, max=spec.max, **kwargs)
        if spec.type == "String":
            return String(spec.name, **kwargs)
        if spec.type == "Integer":
            return RangedInteger(spec.name, min=spec.min, max=spec.max, **kwargs)
        return Boolean(spec.name, **kwargs)

    def _getter(self, name: str):
        return lambda: self._values[name]

    def _setter(self, spec: Var):
        # pythonfmu's own path to a variable (the importer's calls go through _set)
        def setter(value):
            var = self.vars[self._vr_of[spec.name]]
            problem, value = self._check_assignment(var, value)
            if problem is not None:
                raise ValueError(problem)
            self._values[spec.name] = value

        return setter

    @property
    def parameter_values(self) -> Dict[str, Any]:
        """Current parameter values by name."""
        return {n: self._values[n] for n, s in self._specs.items() if s.causality == "parameter"}

    @property
    def input_values(self) -> Dict[str, Any]:
        """Current input values by name."""
        return {n: self._values[n] for n, s in self._specs.items() if s.causality == "input"}

    # ------------------------------------------------------------------ model description
    def to_xml(self, model_options: Dict[str, str] = dict()) -> Element:
        # the complete internal state can be captured, restored and serialized (see _get_fmu_state)
        model_options = {"canGetAndSetFMUstate": True, "canSerializeFMUstate": True, **dict(model_options)}
        root = super().to_xml(model_options)
        cosim = root.find("CoSimulation")
        if cosim is not None:
            # fmi2SetRealInputDerivatives of order 1 (set_real_input_derivatives); no output derivatives
            cosim.set("canInterpolateInputs", "true" if self.interpolates_inputs else "false")
        # <UnitDefinitions> right after <CoSimulation> (FMI 2.0 element order)
        units = {**UNITS, **self.extra_units}
        used: List[str] = []
        for spec in self.variables:
            if spec.unit is not None and spec.unit not in used:
                used.append(spec.unit)
        if used:
            unit_defs = Element("UnitDefinitions")
            for name in used:
                unit = SubElement(unit_defs, "Unit", {"name": name})
                SubElement(unit, "BaseUnit", {k: str(v) for k, v in units[name].items()})
            children = list(root)
            position = children.index(cosim) + 1 if cosim is not None else 0
            root.insert(position, unit_defs)
        # ModelStructure: outputs have no direct feed-through from inputs (co-simulation); every output is
        # an initial unknown (initial="calculated")
        structure = root.find("ModelStructure")
        outputs = structure.find("Outputs")
        if outputs is not None:
            for unknown in outputs:
                unknown.set("dependencies", "")
        initial = [vr for vr, v in self.vars.items()
                   if v.causality == Fmi2Causality.output and v.initial in (Fmi2Initial.calculated,
                                                                             Fmi2Initial.approx)]
        if initial:
            node = SubElement(structure, "InitialUnknowns")
            for vr in initial:
                SubElement(node, "Unknown", {"index": str(vr + 1)})
        return root

    # ------------------------------------------------------------------ to be provided by subclasses
    def create_simulator(self, parameters: Dict[str, Any], t0: float):
        """Build and return the Simulator from the parameter values; raise ValueError on bad values."""
        raise NotImplementedError

    @staticmethod
    def _prepared(sim):
        """A simulator as the FMU runs it: a failed step is refused (fmi2Discard), not warned about; the
        other reports (inexact contact solves) are logged as warnings by `do_step`."""
        if isinstance(sim, Simulator):
            sim.on_report = "raise"
        return sim

    def _log_reports(self) -> None:
        reports = self._sim.last_reports if isinstance(self._sim, Simulator) else None
        if reports:
            self.log(f"t = {self._sim.t:.17g} s: {report_summary(reports)}", Fmi2Status.warning)

    def advance(self, sim, t_end: float, inputs: Dict[str, Any]) -> None:
        """Advance ``sim`` to ``t_end`` under the inputs (default: the single input), each a number held
        constant or, after fmi2SetRealInputDerivatives, a `LinearMotion` over the step."""
        if len(inputs) != 1:
            raise NotImplementedError("override advance() for FMUs with several inputs")
        (value,) = inputs.values()
        sim.advance(t_end, value)

    # ------------------------------------------------------------------ FMI life cycle
    def setup_experiment(self, start_time: float, stop_time: Optional[float] = None,
                         tolerance: Optional[float] = None):
        if self._initialized:
            raise ValueError("fmi2SetupExperiment called after initialization (call fmi2Reset first to start a "
                             "new experiment)")
        try:
            t0 = float(start_time)
        except (TypeError, ValueError):
            t0 = math.nan
        if not math.isfinite(t0):
            raise ValueError(f"fmi2SetupExperiment: startTime = {start_time!r} is invalid; allowed range: finite "
                             f"values")
        self._t0 = t0

    def enter_initialization_mode(self):
        if self._initialized:
            raise ValueError("fmi2EnterInitializationMode called after initialization (call fmi2Reset first to "
                             "initialize again)")

    def exit_initialization_mode(self):
        if self._initialized:
            raise ValueError("fmi2ExitInitializationMode called after initialization (call fmi2Reset first to "
                             "initialize again)")
        try:
            sim = self._prepared(self.create_simulator(self.parameter_values, self._t0))
        except Exception as exc:
            raise ValueError(f"invalid parameters: {_describe(exc)}") from None
        self._sim = sim
        self._initialized = True
        self._t = self._t0
        self._update_outputs()

    def terminate(self):
        self._terminated = True

    def do_step(self, current_time: float, step_size: float) -> bool:
        """Advance to ``current_time + step_size``; False (fmi2Discard) when the step is refused with the state
        unchanged; raises ValueError on an invalid call (fmi2Error)."""
        t, dt = float(current_time), float(step_size)
        if self._terminated:
            raise ValueError("fmi2DoStep called after fmi2Terminate (call fmi2Reset to start again)")
        if not self._initialized:
            raise ValueError("fmi2DoStep called before initialization (fmi2ExitInitializationMode)")
        if self._error is not None:
            raise RuntimeError(f"step refused after an earlier failure (call fmi2Reset): {self._error}")
        if not math.isfinite(dt) or dt <= 0.0:
            raise ValueError(f"fmi2DoStep: communicationStepSize = {dt!r} is invalid; allowed range (0, inf)")
        if not math.isfinite(t) or abs(t - self._t) > self.time_tolerance * max(1.0, abs(self._t)):
            raise ValueError(f"fmi2DoStep: currentCommunicationPoint = {t!r} does not match the FMU time "
                             f"{self._t!r}; allowed value {self._t!r}: each step starts where the last one "
                             f"ended (to go back, restore a state saved with fmi2GetFMUstate)")
        t_end = t + dt
        if not math.isfinite(t_end):
            raise ValueError(f"fmi2DoStep: currentCommunicationPoint + communicationStepSize = {t_end!r} is "
                             f"not finite; allowed: a finite end time")
        values = self._values
        inputs = {}
        for name, lo, hi in self._inputs:
            value = inputs[name] = values[name]
            rate = self._rates.get(name)
            try:  # the same check and message as the Python API (rocking_model.validation)
                check_real(name, value, lo=lo, hi=hi)
                if rate is not None:
                    motion = inputs[name] = LinearMotion(value, rate[0], rate[1], t, t_end)
                    check_real(f"{name} at the end of the step (rate {rate[0]:g} per s)", motion(t_end),
                               lo=lo, hi=hi)
                    check_real(f"{name} at the start of the step (rate {rate[0]:g} per s)", motion(t),
                               lo=lo, hi=hi)
            except ValueError as exc:
                return self._fail(f"input {name} = {value!r} at t = {t!r} is invalid: {exc}")
        if not self._frozen:
            try:
                self.advance(self._sim, max(t_end, self._sim.t), inputs)
            except (WorkLimitError, ValueError) as exc:
                # the simulator is back where the step started: the master may retry (shorter steps, other input)
                return self._fail(f"step [{t!r}, {t_end!r}] refused, the FMU state is unchanged: {_describe(exc)}")
            except Exception as exc:
                self._error = f"simulation failed in the step [{t!r}, {t_end!r}]: {_describe(exc)}"
                raise RuntimeError(self._error) from None
            self._log_reports()
            self._update_outputs()
        self._t = t_end
        return True

    def _update_outputs(self) -> None:
        out = self._sim.outputs()
        values = self._values
        for name, py in self._outputs:
            if name not in out:
                raise KeyError(f"Simulator.outputs() has no entry {name!r}")
            values[name] = py(out[name])
        if self.freeze_output is not None and out.get(self.freeze_output) and not self._frozen:
            self._frozen = True
            self.log(f"{self.freeze_output} at t = {self._sim.t:.6g} s: the outputs are frozen from now on",
                     Fmi2Status.warning)

    def _fail(self, msg: str) -> bool:
        self.log(msg, Fmi2Status.error)
        return False

    # ------------------------------------------------------------------ FMU state
    # The binary calls _get_fmu_state / _set_fmu_state on the instance and _fmu_state_to_bytes /
    # _fmu_state_from_bytes on it too, keeps the returned object as the fmi2FMUstate and releases it in
    # fmi2FreeFMUstate; an exception is fmi2Error. The state object is the serialized byte string itself
    # (rocking_model.fmi_state): immutable, small, data only, and checked field by field when it is set.
    def _get_fmu_state(self) -> bytes:
        return encode_state(self._state_document())

    def _set_fmu_state(self, state) -> None:
        try:
            self._restore(decode_state(state))
        except Exception as exc:
            raise ValueError(f"fmi2SetFMUstate: state rejected, the instance keeps its current state: "
                             f"{_describe(exc)}") from None

    @staticmethod
    def _fmu_state_to_bytes(state) -> bytes:
        if not isinstance(state, bytes):
            raise ValueError("the FMU state is not a state of this FMU")
        return state

    @staticmethod
    def _fmu_state_from_bytes(data) -> bytes:
        return bytes(data)  # checked field by field when it is set

    def _state_signature(self) -> str:
        table = [(s.name, s.causality, s.type) for s in self.variables]
        return hashlib.sha256(repr(table).encode()).hexdigest()

    def _state_document(self) -> Dict[str, Any]:
        values = dict(self._values)
        return {"fmu": type(self).__name__, "signature": self._state_signature(),
                "slave": {"initialized": self._initialized, "terminated": self._terminated,
                          "frozen": self._frozen, "t": self._t, "t0": self._t0, "error": self._error,
                          "values": values, "rates": {k: list(v) for k, v in self._rates.items()}},
                "simulator": None if self._sim is None else self._sim.get_state()}

    def _restore(self, doc: Dict[str, Any]) -> None:
        """Check every field of a decoded state document, rebuild the simulator from its parameter values
        and set its state; nothing of the instance changes unless all of it is valid."""
        check_state_keys(doc, ("fmu", "signature", "slave", "simulator"))
        if doc["fmu"] != type(self).__name__ or doc["signature"] != self._state_signature():
            raise ValueError(f"the state belongs to FMU {str(doc['fmu'])[:64]!r} (or to another version of its "
                             f"variables), not to {type(self).__name__!r}")
        slave = doc["slave"]
        check_state_keys(slave, ("initialized", "terminated", "frozen", "t", "t0", "error", "values", "rates"))
        rates = slave["rates"]
        if not isinstance(rates, dict) or len(rates) > len(self._inputs):
            raise ValueError("state field slave.rates is not an object of the inputs")
        for name, pair in rates.items():
            if name not in {n for n, _, _ in self._inputs} or not isinstance(pair, list) or len(pair) != 2 or \
                    not all(isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)
                            for x in pair) or abs(pair[0]) > INPUT_RATE_MAX:
                raise ValueError(f"state field slave.rates[{str(name)[:64]!r}] is not [rate, t_ref] of an input")
        for key in ("initialized", "terminated", "frozen"):
            state_bool(slave, key)
        for key in ("t", "t0"):
            if isinstance(slave[key], bool) or not isinstance(slave[key], (int, float)) \
                    or not math.isfinite(slave[key]):
                raise ValueError(f"state field slave.{key} = {slave[key]!r} is invalid; allowed: a finite time")
        if slave["error"] is not None and (not isinstance(slave["error"], str) or len(slave["error"]) > _MAX_TEXT):
            raise ValueError(f"state field slave.error is not null or a text of at most {_MAX_TEXT} characters")
        values = slave["values"]
        check_state_keys(values, tuple(self._specs))
        for name, spec in self._specs.items():
            values[name] = _check_value(name, spec.type, values[name])
        sim = None
        if doc["simulator"] is not None:
            if not isinstance(doc["simulator"], dict):
                raise ValueError("state field simulator is not an object")
            params = {n: values[n] for n, s in self._specs.items() if s.causality == "parameter"}
            sim = self._prepared(self.create_simulator(params, float(slave["t0"])))
            sim.set_state(doc["simulator"])
        elif slave["initialized"] and slave["error"] is None:
            raise ValueError("state field simulator is null in an initialized state without an error")
        # all checked: commit
        for name in self._specs:
            self._values[name] = values[name]
        self._sim = sim
        self._initialized, self._terminated, self._frozen = (slave["initialized"], slave["terminated"],
                                                             slave["frozen"])
        self._t, self._t0 = float(slave["t"]), float(slave["t0"])
        self._error = slave["error"]
        self._rates = {k: (float(v[0]), float(v[1])) for k, v in rates.items()}

    # ------------------------------------------------------------------ value references
    # A call with a bad reference (unknown, of another type, an output set), a value that cannot be converted,
    # an input outside its declared range or a fixed parameter changed after initialization raises with every
    # problem named (fmi2Error); a setter then sets nothing.
    def _lookup(self, vr, type_name: str):
        """(variable, problem): the variable of reference ``vr`` if it has type ``type_name``."""
        try:
            var = self.vars.get(int(vr))
        except (TypeError, ValueError):
            var = None
        if var is None:
            return None, f"value reference {vr!r} is unknown to {type(self).__name__}"
        actual = _var_type(var)
        if actual != type_name:
            return None, f"value reference {vr} is {var.name!r}, a {actual} variable, not {type_name}"
        return var, None

    def _get(self, vrs, type_name: str):
        out, problems = [], []
        for vr in vrs:
            var, problem = self._lookup(vr, type_name)
            if var is None:
                problems.append(problem)
                continue
            out.append(var.getter())
        if problems:
            raise ValueError(f"fmi2Get{type_name}: " + "; ".join(problems))
        return out

    def _set(self, vrs, values, type_name: str) -> None:
        checked, problems = [], []
        vrs, values = list(vrs), list(values)
        if len(vrs) != len(values):
            raise ValueError(f"fmi2Set{type_name}: {len(vrs)} value references but {len(values)} values")
        for vr, value in zip(vrs, values):
            var, problem = self._lookup(vr, type_name)
            if var is None:
                problems.append(problem)
                continue
            problem, value = self._check_assignment(var, value)
            if problem is not None:
                problems.append(problem)
            else:
                checked.append((var.name, value))
        if problems:
            raise ValueError(f"fmi2Set{type_name}: " + "; ".join(problems) + " (nothing was set)")
        for name, value in checked:
            self._values[name] = value
            self._rates.pop(name, None)  # a new value: held until a derivative is given again

    def _check_assignment(self, var, value):
        """(problem, converted value): why ``value`` cannot be assigned to ``var``, or None."""
        name = var.name
        if var.causality == Fmi2Causality.output:
            return f"{name} is an output and cannot be set", None
        spec = self._specs.get(name)
        if spec is None:
            return f"{name} is not a variable of the table of {type(self).__name__}", None
        try:
            value = _PY_TYPES[spec.type](value)
        except Exception:
            return f"{name}: cannot convert {str(value)[:64]!r} to {spec.type}", None
        if spec.type == "String" and len(value) > _MAX_TEXT:
            return f"{name}: a text of {len(value)} characters is too long; at most {_MAX_TEXT}", None
        if spec.causality == "input" and spec.type == "Real":
            try:  # the same check and message as the Python API (rocking_model.validation)
                check_real(name, value, lo=spec.min, hi=spec.max)
            except ValueError as exc:
                return f"input {exc}", None
        if (spec.causality == "parameter" and self._initialized and spec.resolved_variability == "fixed"
                and not _same(value, self._values[name])):
            return (f"parameter {name} is 'fixed' and cannot be changed after initialization (requested "
                    f"{value!r}, keeping {self._values[name]!r}); call fmi2Reset first to change it"), None
        return None, value

    def set_real_input_derivatives(self, vrs, orders, values) -> None:
        """fmi2SetRealInputDerivatives: order 1 gives the rate [unit/s] of a Real input at the current
        communication point; from then on the input is u(t) = u_now + rate (t - t_now), a first-order hold
        over the following steps, until the input or its rate is set again (fmi2SetReal resets the rate to 0).
        A step whose input would leave the declared [min, max] is refused (fmi2Discard). Orders other than 1,
        references that are not Real inputs and rates that are not finite or exceed `INPUT_RATE_MAX` raise
        (fmi2Error); nothing of the call is set then."""
        if not self.interpolates_inputs:
            raise ValueError(f"fmi2SetRealInputDerivatives: {type(self).__name__} holds its inputs constant over "
                             f"a step (canInterpolateInputs = false)")
        vrs, orders, values = list(vrs), list(orders), list(values)
        if not len(vrs) == len(orders) == len(values):
            raise ValueError("fmi2SetRealInputDerivatives: the numbers of references, orders and values differ")
        checked, problems = [], []
        for vr, order, rate in zip(vrs, orders, values):
            var, problem = self._lookup(vr, "Real")
            if var is None or self._specs[var.name].causality != "input":
                problems.append(problem or f"value reference {vr} is {var.name!r}, not a Real input")
                continue
            if order != 1:
                problems.append(f"{var.name}: order = {order!r} is not supported; allowed: 1")
                continue
            try:
                rate = check_real(f"rate of {var.name}", rate, lo=-INPUT_RATE_MAX, hi=INPUT_RATE_MAX)
            except ValueError as exc:
                problems.append(str(exc))
                continue
            checked.append((var.name, rate))
        if problems:
            raise ValueError("fmi2SetRealInputDerivatives: " + "; ".join(problems) + " (nothing was set)")
        for name, rate in checked:
            old = self._rates.get(name)
            if old is not None:  # continue the line: the value at this communication point
                self._values[name] = self._values[name] + old[0] * (self._t - old[1])
            self._rates[name] = (rate, self._t)

    def get_real(self, vrs):
        return self._get(vrs, "Real")

    def get_integer(self, vrs):
        return self._get(vrs, "Integer")

    def get_boolean(self, vrs):
        return self._get(vrs, "Boolean")

    def get_string(self, vrs):
        return self._get(vrs, "String")

    def set_real(self, vrs, values):
        self._set(vrs, values, "Real")

    def set_integer(self, vrs, values):
        self._set(vrs, values, "Integer")

    def set_boolean(self, vrs, values):
        self._set(vrs, values, "Boolean")

    def set_string(self, vrs, values):
        self._set(vrs, values, "String")


def _same(a, b) -> bool:
    return a == b or (isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b))


def _describe(exc: BaseException) -> str:
    text = str(exc)
    return text if isinstance(exc, ValueError) and text else f"{type(exc).__name__}: {text}"


def _var_type(var) -> str:
    """FMI type name of a pythonfmu variable."""
    for cls, name in ((Real, "Real"), (Integer, "Integer"), (Boolean, "Boolean"), (String, "String")):
        if isinstance(var, cls):
            return name
    return type(var).__name__


_FMPY_LOCK = threading.Lock()

#: [unit/s] largest input rate accepted by fmi2SetRealInputDerivatives: AG_MAX reached from 0 in 1 ms, far
#: beyond any recorded ground motion (a steeper ramp is a step, which a zero-order hold represents)
INPUT_RATE_MAX = AG_MAX / 1e-3

#: [characters] longest text kept in a state or accepted for a String variable (a file path, a message)
_MAX_TEXT = 4096
#: FMI 2.0 fmi2Integer is a 32-bit int
_INT32 = (-2**31, 2**31 - 1)


def _check_value(name: str, type_: str, value):
    """A variable value read from a state document, checked for its FMI type."""
    if type_ == "Real":
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ValueError(f"state value of {name} = {str(value)[:64]!r} is not a Real")
        return float(value)
    if type_ == "Integer":
        if isinstance(value, bool) or not isinstance(value, int) or not _INT32[0] <= value <= _INT32[1]:
            raise ValueError(f"state value of {name} = {str(value)[:64]!r} is not a 32-bit Integer")
        return value
    if type_ == "Boolean":
        if not isinstance(value, bool):
            raise ValueError(f"state value of {name} = {str(value)[:64]!r} is not a Boolean")
        return value
    if not isinstance(value, str) or len(value) > _MAX_TEXT:
        raise ValueError(f"state value of {name} is not a String of at most {_MAX_TEXT} characters")
    return value


# ----------------------------------------------------------------------------------------------------
# importer side
class FMUError(RuntimeError):
    """An FMU run failed: error messages logged by the FMU, or the simulation ended before stop_time."""

    def __init__(self, message: str, messages: Sequence[tuple] = (), result=None):
        super().__init__(message)
        self.messages = list(messages)
        self.result = result


class _FmpyLog:
    """The logger of every FMU this package instantiates through fmpy, alive as long as the process.

    fmpy formats the variadic FMI message in a C proxy (``fmpy.logging.addLoggerProxy``) that forwards to ONE
    process-wide Python logger, the last one registered: after ``fmpy.simulate_fmu(logger=f)`` returns, the
    proxy points at a ctypes closure that is freed with the run, and the next message of any FMU crashes the
    process. `fmpy_callbacks` registers this logger again (re-pointing the proxy at a live closure) and
    routes the messages: to the sink given to `fmpy_callbacks` (through the componentEnvironment of its
    callbacks), else to the sink of `collect_fmu_messages` in this thread, else to fmpy's printer."""

    callbacks = None
    raw_logger = None
    local = threading.local()
    sinks: Dict[int, list] = {}   # componentEnvironment -> list of (status, category, text)

    @staticmethod
    def dispatch(env, instance, status, category, message):
        sink = _FmpyLog.sinks.get(env) if env else None
        if sink is None:
            sink = getattr(_FmpyLog.local, "sink", None)
        if sink is not None:
            sink.append((int(status), _text(category), _text(message)))
            return
        from fmpy.fmi2 import printLogMessage

        printLogMessage(env, instance, status, category, message)


def fmpy_callbacks(sink: Optional[list] = None):
    """``fmi2CallbackFunctions`` for fmpy (pass as ``FMU2Slave.instantiate(callbacks=...)``), with fmpy's
    logger proxy pointed at the process-wide logger again (see `_FmpyLog`). With ``sink``, new callbacks
    whose messages are appended to it as (status, category, text); keep them alive with the instance."""
    from ctypes import byref

    from fmpy.fmi2 import (calloc, fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE,
                           fmi2CallbackFunctions, fmi2CallbackLoggerTYPE, free)

    with _FMPY_LOCK:
        if _FmpyLog.callbacks is None:
            _FmpyLog.raw_logger = fmi2CallbackLoggerTYPE(_FmpyLog.dispatch)
            callbacks = fmi2CallbackFunctions()
            callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
            callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
            _FmpyLog.callbacks = callbacks
        callbacks = _FmpyLog.callbacks
        # the proxy replaces callbacks.logger by itself: start from the raw logger every time
        callbacks.logger = _FmpyLog.raw_logger
        try:
            from fmpy.logging import addLoggerProxy
            addLoggerProxy(byref(callbacks))
        except Exception:  # pragma: no cover - fmpy without its logging library: the raw format arrives
            pass
        if sink is None:
            return callbacks
        own = fmi2CallbackFunctions()
        own.logger = callbacks.logger   # the proxy, which formats and calls `dispatch`
        own.allocateMemory = callbacks.allocateMemory
        own.freeMemory = callbacks.freeMemory
        token = len(_FmpyLog.sinks) + 1
        own.componentEnvironment = token
        _FmpyLog.sinks[token] = sink
        return own


@contextmanager
def collect_fmu_messages():
    """Collect the messages of the FMUs run through fmpy in this thread into a list of
    (status, category, text), yielded; fmpy's default callbacks and `fmpy_callbacks` both end here."""
    fmpy_callbacks()
    previous = getattr(_FmpyLog.local, "sink", None)
    messages: List[tuple] = []
    _FmpyLog.local.sink = messages
    try:
        yield messages
    finally:
        _FmpyLog.local.sink = previous
        fmpy_callbacks()


def run_fmu(filename, *, stop_time: float, output_interval: float, start_time: float = 0.0,
            start_values: Optional[Dict[str, Any]] = None, input=None, output=None, **kwargs):
    """``fmpy.simulate_fmu`` that fails loudly: raise :class:`FMUError` with the FMU's messages if a call
    fails (fmi2Error: invalid parameters, inputs, ...), the FMU logged an error, or the run ended before
    ``stop_time`` (a refused step: fmi2Discard with fmi2Terminated, which fmpy treats as an early end).
    ``output_interval`` is the co-simulation step (always pass it: fmpy coarsens the default one). Returns
    the fmpy result (structured array with a 'time' column).
    """
    import fmpy
    from fmpy.fmi1 import FMICallException

    with collect_fmu_messages() as messages:
        try:
            result = fmpy.simulate_fmu(str(filename), start_time=start_time, stop_time=stop_time,
                                       output_interval=output_interval, start_values=dict(start_values or {}),
                                       input=input, output=output, **kwargs)
        except FMICallException as exc:
            errors = [m for s, _, m in messages if s >= int(Fmi2Status.error)]
            raise FMUError(f"{filename}: {exc}: " + ("; ".join(errors) or "no error message"), messages) from None
    errors = [m for s, _, m in messages if s >= int(Fmi2Status.error)]
    t_last = float(result["time"][-1])
    early = t_last < stop_time and not math.isclose(t_last, stop_time, rel_tol=1e-9, abs_tol=1e-12)
    if errors or early:
        what = "; ".join(errors) if errors else "no error message"
        raise FMUError(f"{filename}: simulation failed at t = {t_last:g} s (stop_time = {stop_time:g} s): "
                       f"{what}", messages, result)
    return result


def run_fmu_record(filename, t_record, ag_record, *, step: float, stop_time: float, hold: str = "linear",
                   start_values: Optional[Dict[str, Any]] = None, output: Sequence[str] = ("phi",)):
    """Drive an FMU with input ``ag`` through a sampled record (times ``t_record`` [s], values ``ag_record``
    [m/s2], linear between samples) with communication step ``step`` [s]; return a structured array with
    "time" and the ``output`` variables after every step.

    ``hold="linear"``: at every communication point the master sets ag and its slope over the coming step
    (fmi2SetRealInputDerivatives, order 1), so the FMU integrates the record's straight line over the step;
    with ``step`` equal to the record's sampling that is the record itself. ``hold="zoh"``: ag held constant
    over each step (what a master without input derivatives does). fmpy 0.3.32's
    ``simulate_fmu(set_input_derivatives=True)`` cannot serve here: its derivative buffer has a fixed length
    of 9 (one input raises ValueError) and at a sample point it passes the slope of the previous interval."""
    import numpy as np
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave

    hold = {"linear": "linear", "zoh": "zoh"}.get(hold)
    if hold is None:
        raise ValueError("hold must be 'linear' or 'zoh'")
    step = check_real("step", step, lo=0.0, lo_open=True)
    t_record = np.asarray(t_record, dtype=float)
    ag_record = np.asarray(ag_record, dtype=float)
    md = read_model_description(str(filename))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    types = {v.name: v.type for v in md.modelVariables}
    unzip = extract(str(filename))
    fmu = FMU2Slave(guid=md.guid, unzipDirectory=unzip, modelIdentifier=md.coSimulation.modelIdentifier,
                    instanceName="record")
    n = int(round(stop_time / step))
    rows = []
    with collect_fmu_messages() as messages:
        from fmpy.fmi1 import FMICallException

        try:
            fmu.instantiate(callbacks=fmpy_callbacks())
            fmu.setupExperiment(startTime=0.0)
            fmu.enterInitializationMode()
            for name, value in (start_values or {}).items():
                setter = {"Real": fmu.setReal, "Integer": fmu.setInteger, "Boolean": fmu.setBoolean,
                          "String": fmu.setString}[types[name]]
                setter([vr[name]], [value])
            fmu.exitInitializationMode()
            for k in range(n):
                t = k * step
                a0 = float(np.interp(t, t_record, ag_record))
                fmu.setReal([vr["ag"]], [a0])
                if hold == "linear":
                    a1 = float(np.interp(t + step, t_record, ag_record))
                    fmu.setRealInputDerivatives([vr["ag"]], [1], [(a1 - a0) / step])
                fmu.doStep(t, step)
                rows.append(tuple([t + step] + [fmu.getReal([vr[o]])[0] for o in output]))
            fmu.terminate()
        except FMICallException as exc:
            errors = [m for st, _, m in messages if st >= int(Fmi2Status.error)]
            raise FMUError(f"{filename}: {exc}: " + ("; ".join(errors) or "no error message"), messages) from None
        finally:
            fmu.freeInstance()
    return np.array(rows, dtype=[("time", float)] + [(o, float) for o in output])


def _text(value) -> str:
    if value is None:
        return ""
    return value.decode("utf-8", "replace") if isinstance(value, bytes) else str(value)
