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
  (zero-order hold, the importer sets the inputs at the start of each step) and copies
  ``Simulator.outputs()`` to the output variables;
* FMU state (``canGetAndSetFMUstate`` and ``canSerializeFMUstate`` are true): ``fmi2GetFMUstate`` captures
  a deep copy of the complete internal state -- the whole `Simulator` (integrator arrays, contact mode,
  counters, impact log, step-size memory), the values of every parameter, input and output, the
  communication time and the status flags (initialized, frozen, failed, pending error) -- and
  ``fmi2SetFMUstate`` restores it, in the same or in another instance of the same FMU, so that
  save -> step -> restore -> step gives bit-identical outputs (rollback for iterative masters).
  ``fmi2SerializeFMUstate`` writes the state as a pickle (protocol 5) behind a header and a SHA-256 digest;
  ``fmi2DeSerializeFMUstate`` checks both and unpickles with a restricted unpickler that only loads
  ``rocking_model`` classes, numpy arrays and plain builtins. A state of another FMU, a corrupted byte
  string or a failed capture is rejected when it is set: error log, the instance keeps its state and the
  next ``do_step`` is discarded once;
* ``fmi2Reset``: the pythonfmu 0.7 C wrapper re-creates the Python object (start values, not initialized);
  :meth:`RockingSlave.reset` does the same in place for direct use of the class.

Error handling. No Python exception ever reaches the pythonfmu C wrapper: there an exception becomes
``fmi2Fatal`` and the wrapper releases the Python instance, so any later call on the instance (e.g.
``fmi2Terminate``) dereferences freed memory and crashes the importer. Instead, a failing ``do_step``
returns False, which pythonfmu 0.7 maps to ``fmi2Discard`` with ``fmi2LastSuccessfulTime`` = the start of
the step and ``fmi2GetBooleanStatus(fmi2Terminated)`` = true; fmpy then ends the simulation early without
raising (use :func:`run_fmu` to get an exception). ``exit_initialization_mode`` always returns fmi2OK.

* invalid parameters (the model / Simulator raise ``ValueError`` naming the variable and its allowed range)
  are caught in ``exit_initialization_mode`` and logged with ``Fmi2Status.error``; every ``do_step``
  then logs the message again and returns False;
* an invalid input (non-finite, or outside the declared ``min``/``max``), a step size that is not
  positive and finite, or a ``current_time`` that does not match the FMU's time (after a rollback with
  ``fmi2SetFMUstate`` the FMU's time is the restored one): error log, ``do_step`` returns False, the
  state is unchanged (the step can be retried with a valid input);
* an exception inside the integrator: error log, the instance is marked failed, ``do_step`` returns
  False from then on;
* a ``fixed`` parameter set to a new value after initialization: the value is rejected (the old one is
  kept), an error is logged and the next ``do_step`` is discarded once, so the mistake is not silent;
* once the output named by ``freeze_output`` (``"overturned"``) is true the integration stops, the outputs
  stay frozen and ``do_step`` keeps returning True.

pythonfmu 0.7 can only report fmi2OK, fmi2Discard (``do_step`` returns False) or -- for an exception --
fmi2Fatal; it has no way to return fmi2Error from Python. Every error therefore goes out as an error log
(status fmi2Error in the logger callback) plus fmi2Discard of the next ``do_step``.

Log messages reach the importer only when it instantiates the FMU with ``loggingOn = fmi2True``
(``fmpy.simulate_fmu(..., debug_logging=True)``); that is a property of the pythonfmu 0.7 C wrapper.
"""
from __future__ import annotations

import copy
import hashlib
import io
import math
import pickle
from dataclasses import dataclass
from typing import Any, ClassVar, Dict, Iterable, List, Optional, Sequence
from xml.etree.ElementTree import Element, SubElement

from pythonfmu import Fmi2Causality, Fmi2Slave, Fmi2Variability
from pythonfmu.default_experiment import DefaultExperiment
from pythonfmu.enums import Fmi2Initial, Fmi2Status
from pythonfmu.variables import Boolean, Integer, Real

from .validation import check_real

__all__ = ["UNITS", "Var", "RockingSlave", "DefaultExperiment", "Fmi2Status", "FMUError", "run_fmu"]

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
_PY_TYPES = {"Real": float, "Integer": int, "Boolean": bool}


@dataclass(frozen=True)
class Var:
    """One FMU variable.

    name: FMI name (also the key in the parameter dict and in ``Simulator.outputs()``).
    causality: "parameter", "input" or "output".
    start: start value (parameters, inputs); outputs report it until initialization is done.
    type: "Real", "Integer" or "Boolean".
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
        from rocking_model import __version__
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
    #: names of further instance attributes that belong to the FMU state (e.g. a String parameter kept outside
    #: the Var table); the base class captures the simulator, the variable values, time and status flags
    extra_state_attributes: ClassVar[Sequence[str]] = ()

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
        # what every do_step reads, resolved once
        self._inputs = [(s.name, s.min, s.max) for s in self.variables if s.causality == "input"]
        self._outputs = [(s.name, _PY_TYPES[s.type]) for s in self.variables if s.causality == "output"]

    def _clear_state(self) -> None:
        # everything listed in _STATE_FIELDS is the FMU state (fmi2GetFMUstate / fmi2SetFMUstate)
        self._sim = None
        self._initialized = False
        self._error: Optional[str] = None        # permanent failure (bad parameters, integrator crash)
        self._pending: Optional[str] = None      # one-shot failure of the next do_step
        self._frozen = False
        self._t = 0.0                            # current communication point [s]
        self._t0 = 0.0

    def reset(self) -> None:
        """fmi2Reset in place: start values, not initialized, no error (the log queue is kept).

        The pythonfmu 0.7 C wrapper implements fmi2Reset by creating a new Python object, which has the
        same effect; this method serves direct users of the class (and later pythonfmu versions)."""
        try:
            self._clear_state()
            for name, spec in self._specs.items():
                self._values[name] = spec.default
        except Exception as exc:  # pragma: no cover - never raise into the C wrapper
            self.log(f"reset failed: {_describe(exc)}", Fmi2Status.error)

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
        if spec.type == "Integer":
            return RangedInteger(spec.name, min=spec.min, max=spec.max, **kwargs)
        return Boolean(spec.name, **kwargs)

    def _getter(self, name: str):
        return lambda: self._values[name]

    def _setter(self, spec: Var):
        py = _PY_TYPES[spec.type]

        def setter(value):
            try:
                value = py(value)
            except Exception:
                self.log(f"{spec.name}: cannot convert {value!r} to {spec.type}; value ignored",
                         Fmi2Status.error)
                return
            if spec.causality == "output":
                self.log(f"{spec.name} is an output and cannot be set; value ignored", Fmi2Status.error)
                return
            if (spec.causality == "parameter" and self._initialized
                    and spec.resolved_variability == "fixed" and not _same(value, self._values[spec.name])):
                msg = (f"parameter {spec.name} is 'fixed' and cannot be changed after initialization "
                       f"(requested {value!r}, keeping {self._values[spec.name]!r}); re-instantiate or reset "
                       f"the FMU to change it")
                self.log(msg, Fmi2Status.error)
                self._pending = msg
                return
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
            # pythonfmu does not implement fmi2SetRealInputDerivatives
            cosim.set("canInterpolateInputs", "false")
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

    def advance(self, sim, t_end: float, inputs: Dict[str, Any]) -> None:
        """Advance ``sim`` to ``t_end`` with the inputs held constant (default: the single input)."""
        if len(inputs) != 1:
            raise NotImplementedError("override advance() for FMUs with several inputs")
        (value,) = inputs.values()
        sim.advance(t_end, value)

    # ------------------------------------------------------------------ FMI life cycle
    def setup_experiment(self, start_time: float, stop_time: Optional[float] = None,
                         tolerance: Optional[float] = None):
        try:
            if start_time is not None and math.isfinite(float(start_time)):
                self._t0 = float(start_time)
        except Exception as exc:  # never raise into the C wrapper
            self.log(f"setup_experiment: {exc}", Fmi2Status.error)

    def enter_initialization_mode(self):
        pass

    def exit_initialization_mode(self):
        try:
            self._initialized = True
            self._t = self._t0
            self._sim = self.create_simulator(self.parameter_values, self._t0)
            self._update_outputs()
        except Exception as exc:
            self._sim = None
            self._error = f"invalid parameters: {_describe(exc)}"
            self.log(self._error, Fmi2Status.error)

    def do_step(self, current_time: float, step_size: float) -> bool:
        try:
            return self._do_step(float(current_time), float(step_size))
        except Exception as exc:  # last resort: never raise into the C wrapper
            self._error = f"do_step failed at t = {current_time!r}: {_describe(exc)}"
            self.log(self._error, Fmi2Status.error)
            return False

    def _do_step(self, t: float, dt: float) -> bool:
        if not self._initialized:
            return self._fail("do_step called before initialization (exit_initialization_mode)")
        if self._error is not None:
            return self._fail(self._error)
        if self._pending is not None:
            msg, self._pending = self._pending, None
            return self._fail(msg)
        if not math.isfinite(dt) or dt <= 0.0:
            return self._fail(f"step_size = {dt!r} is invalid; allowed range (0, inf)")
        if not math.isfinite(t) or abs(t - self._t) > self.time_tolerance * max(1.0, abs(self._t)):
            return self._fail(f"current_time = {t!r} does not match the FMU time {self._t!r}; allowed value "
                              f"{self._t!r}: each step starts where the last one ended (to go back, restore "
                              f"a state saved with fmi2GetFMUstate)")
        values = self._values
        inputs = {}
        for name, lo, hi in self._inputs:
            value = inputs[name] = values[name]
            try:  # the same check and message as the Python API (rocking_model.validation)
                check_real(name, value, lo=lo, hi=hi)
            except ValueError as exc:
                return self._fail(f"input {name} = {value!r} at t = {t!r} is invalid: {exc}")
        t_end = t + dt
        if not self._frozen:
            try:
                self.advance(self._sim, max(t_end, self._sim.t), inputs)
                self._update_outputs()
            except Exception as exc:
                self._error = f"simulation failed in the step [{t!r}, {t_end!r}]: {_describe(exc)}"
                return self._fail(self._error)
        self._t = t_end
        return True

    def _update_outputs(self) -> None:
        out = self._sim.outputs()
        values = self._values
        for name, py in self._outputs:
            if name not in out:
                raise KeyError(f"Simulator.outputs() has no entry {name!r}")
            values[name] = py(out[name])
        if self.freeze_output is not None and out.get(self.freeze_output):
            self._frozen = True
            self.log(f"{self.freeze_output} at t = {self._sim.t:.6g} s: the outputs are frozen from now on",
                     Fmi2Status.warning)

    def _fail(self, msg: str) -> bool:
        self.log(msg, Fmi2Status.error)
        return False

    # ------------------------------------------------------------------ FMU state
    # pythonfmu 0.7 calls _get_fmu_state / _set_fmu_state on the instance and _fmu_state_to_bytes /
    # _fmu_state_from_bytes on the class; the C wrapper keeps the returned object as the fmi2FMUstate and
    # releases it in fmi2FreeFMUstate. None of them may raise (an exception there is fmi2Fatal).
    def _get_fmu_state(self) -> Dict[str, Any]:
        try:
            fields = copy.deepcopy({name: getattr(self, name) for name in self._state_fields()})
            return {"format": _STATE_FORMAT, "fmu": type(self).__name__, "variables": self._state_signature(),
                    "fields": fields}
        except Exception as exc:
            msg = f"fmi2GetFMUstate failed: {_describe(exc)}"
            self.log(msg, Fmi2Status.error)
            return {"format": _STATE_FORMAT, "invalid": msg}

    def _set_fmu_state(self, state: Dict[str, Any]) -> None:
        try:
            problem = self._state_problem(state)
            if problem is None:
                fields = copy.deepcopy(state["fields"])  # the saved state may be restored again later
                for name in self._state_fields():
                    setattr(self, name, fields[name])
                return
        except Exception as exc:
            problem = _describe(exc)
        msg = f"fmi2SetFMUstate: state rejected, the instance keeps its current state: {problem}"
        self.log(msg, Fmi2Status.error)
        self._pending = msg

    def _state_fields(self) -> tuple:
        return tuple(_STATE_FIELDS) + tuple(self.extra_state_attributes)

    def _state_signature(self) -> List[tuple]:
        return [(s.name, s.causality, s.type) for s in self.variables]

    def _state_problem(self, state) -> Optional[str]:
        if not isinstance(state, dict) or state.get("format") != _STATE_FORMAT:
            return f"not an FMU state of this package (format {_STATE_FORMAT})"
        if "invalid" in state:
            return str(state["invalid"])
        if state.get("fmu") != type(self).__name__ or state.get("variables") != self._state_signature():
            return f"the state belongs to FMU {state.get('fmu')!r}, not to {type(self).__name__!r}"
        fields = state.get("fields")
        if not isinstance(fields, dict) or set(fields) != set(self._state_fields()):
            return "incomplete state"
        return None

    @staticmethod
    def _fmu_state_to_bytes(state: Dict[str, Any]) -> bytes:
        try:
            payload = pickle.dumps(state, protocol=5)
        except Exception as exc:
            payload = pickle.dumps({"format": _STATE_FORMAT,
                                    "invalid": f"fmi2SerializeFMUstate failed: {_describe(exc)}"}, protocol=5)
        return _STATE_MAGIC + hashlib.sha256(payload).digest() + payload

    @staticmethod
    def _fmu_state_from_bytes(data: bytes) -> Dict[str, Any]:
        try:
            data = bytes(data)
            n = len(_STATE_MAGIC)
            if not data.startswith(_STATE_MAGIC):
                raise ValueError("not a serialized state of a rocking_model FMU (bad header)")
            digest, payload = data[n:n + 32], data[n + 32:]
            if hashlib.sha256(payload).digest() != digest:
                raise ValueError("the serialized state is corrupted (SHA-256 mismatch)")
            state = _StateUnpickler(io.BytesIO(payload)).load()
            if not isinstance(state, dict):
                raise ValueError("the serialized state is not a state dictionary")
            return state
        except Exception as exc:
            return {"format": _STATE_FORMAT, "invalid": f"fmi2DeSerializeFMUstate failed: {_describe(exc)}"}

    # ------------------------------------------------------------------ robust accessors
    # pythonfmu raises TypeError/KeyError for a wrong value reference; turn that into an error log so no
    # exception reaches the C wrapper.
    def _safe_set(self, setter, vrs, values):
        try:
            setter(vrs, values)
        except Exception as exc:
            self.log(f"cannot set value references {list(vrs)}: {_describe(exc)}", Fmi2Status.error)

    def _safe_get(self, getter, vrs, fallback):
        try:
            return getter(vrs)
        except Exception as exc:
            self.log(f"cannot get value references {list(vrs)}: {_describe(exc)}", Fmi2Status.error)
            return [fallback] * len(vrs)

    def set_real(self, vrs, values):
        self._safe_set(super().set_real, vrs, values)

    def set_integer(self, vrs, values):
        self._safe_set(super().set_integer, vrs, values)

    def set_boolean(self, vrs, values):
        self._safe_set(super().set_boolean, vrs, values)

    def get_real(self, vrs):
        return self._safe_get(super().get_real, vrs, math.nan)

    def get_integer(self, vrs):
        return self._safe_get(super().get_integer, vrs, 0)

    def get_boolean(self, vrs):
        return self._safe_get(super().get_boolean, vrs, False)


def _same(a, b) -> bool:
    return a == b or (isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b))


def _describe(exc: BaseException) -> str:
    text = str(exc)
    return text if isinstance(exc, ValueError) and text else f"{type(exc).__name__}: {text}"


# FMU state: the slave attributes that make up the state, the version of its layout, the serialization header
_STATE_FIELDS = ("_values", "_sim", "_initialized", "_error", "_pending", "_frozen", "_t", "_t0")
_STATE_FORMAT = 1
_STATE_MAGIC = b"rocking_model FMU state v1\n"

_SAFE_BUILTINS = frozenset({"set", "frozenset", "list", "dict", "tuple", "complex", "float", "int", "bool",
                            "str", "bytes", "bytearray", "slice", "range"})
_SAFE_NUMPY = frozenset({("numpy", "ndarray"), ("numpy", "dtype"),
                         ("numpy.core.multiarray", "_reconstruct"), ("numpy._core.multiarray", "_reconstruct"),
                         ("numpy.core.multiarray", "scalar"), ("numpy._core.multiarray", "scalar"),
                         ("numpy.core.numeric", "_frombuffer"), ("numpy._core.numeric", "_frombuffer")})


class _StateUnpickler(pickle.Unpickler):
    """Unpickler for serialized FMU states: rocking_model classes, numpy arrays and plain builtins only."""

    def find_class(self, module, name):
        if (module == "rocking_model" or module.startswith("rocking_model.")
                or (module == "builtins" and name in _SAFE_BUILTINS) or (module, name) in _SAFE_NUMPY):
            return super().find_class(module, name)
        raise pickle.UnpicklingError(f"global {module}.{name} is not allowed in an FMU state")


# ----------------------------------------------------------------------------------------------------
# importer side
class FMUError(RuntimeError):
    """An FMU run failed: error messages logged by the FMU, or the simulation ended before stop_time."""

    def __init__(self, message: str, messages: Sequence[tuple] = (), result=None):
        super().__init__(message)
        self.messages = list(messages)
        self.result = result


def run_fmu(filename, *, stop_time: float, output_interval: float, start_time: float = 0.0,
            start_values: Optional[Dict[str, Any]] = None, input=None, output=None, **kwargs):
    """``fmpy.simulate_fmu`` that fails loudly: raise :class:`FMUError` if the FMU logged an error or the
    run ended before ``stop_time``.

    pythonfmu 0.7 turns a ``do_step`` that returns False into ``fmi2Discard`` with ``fmi2Terminated``
    true, which fmpy treats as a regular early end of the simulation (no exception). This wrapper turns on
    the FMU's debug logging, collects its messages and raises with them. ``output_interval`` is the
    co-simulation step (always pass it: fmpy coarsens the default one). Returns the fmpy result
    (structured array with a 'time' column).
    """
    import fmpy

    messages: List[tuple] = []

    def logger(env, instance, status, category, message):
        messages.append((int(status), _text(category), _text(message)))

    result = fmpy.simulate_fmu(str(filename), start_time=start_time, stop_time=stop_time,
                               output_interval=output_interval, start_values=dict(start_values or {}),
                               input=input, output=output, debug_logging=True, logger=logger, **kwargs)
    errors = [m for s, _, m in messages if s >= int(Fmi2Status.error)]
    t_last = float(result["time"][-1])
    early = t_last < stop_time and not math.isclose(t_last, stop_time, rel_tol=1e-9, abs_tol=1e-12)
    if errors or early:
        what = "; ".join(errors) if errors else "no error message"
        raise FMUError(f"{filename}: simulation failed at t = {t_last:g} s (stop_time = {stop_time:g} s): "
                       f"{what}", messages, result)
    return result


def _text(value) -> str:
    if value is None:
        return ""
    return value.decode("utf-8", "replace") if isinstance(value, bytes) else str(value)
