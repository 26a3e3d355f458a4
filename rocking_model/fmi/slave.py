"""The slave and its state machine: `RockingSlave`, the generic pythonfmu slave around a `Simulator` that
the FMU scripts subclass (see the package docstring of `rocking_model.fmi` for the status of every call).

Engine. The model FMUs (`ModelSlave`) run the compiled engine through a `Simulator`.

Per-step path on the compiled engine (`RockingSlave._bind`): fmi2SetReal of the input is one range comparison,
fmi2DoStep is one `Engine.advance` between the engine's checkpoint and commit (a refused step is rolled back
in C: fmi2Discard, the state bit-identical), and fmi2GetReal reads the engine's output row, fetched once per
step when the importer first asks; nothing is copied per step. Every call that does not fit (an input rate,
several inputs, a frozen or failed instance, a value or time that fails a check) takes the checked path,
which words the messages.
"""
from __future__ import annotations

import hashlib
import math
import sys
from typing import Any, ClassVar, Dict, List, Optional, Sequence
from xml.etree.ElementTree import Element, SubElement

from pythonfmu import Fmi2Causality, Fmi2Slave
from pythonfmu.default_experiment import DefaultExperiment
from pythonfmu.enums import Fmi2Initial, Fmi2Status
from pythonfmu.variables import Boolean, Integer, Real, String

from ..fmi_state import decode_state, encode_state
from ..ground_motion import LinearMotion
from ..simulation import Simulator, report_summary
from ..validation import AG_MAX, WorkLimitError, check_real, check_state_keys, state_bool
from .variables import _CAUSALITIES, _PY_TYPES, _VARIABILITIES, UNITS, RangedInteger, UnitReal, Var

# ----------------------------------------------------------------------------------------------------
def _package_version() -> Optional[str]:
    try:
        from .. import __version__
        return str(__version__)
    except Exception:  # pragma: no cover - only outside the package
        return None


#: the project's name in the modelDescription's generationTool ("rocking_model <version>")
GENERATION_TOOL = "rocking_model"


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

    #: the category of the events of the motion (the overturning that freezes the outputs): logged with
    #: fmi2OK, so the step's status stays fmi2OK; they reach the importer with logging on and the category
    #: enabled by fmi2SetDebugLogging (none named, logEvents or logAll), as the binaries filter (fmi2_common.c)
    EVENTS: ClassVar[str] = "logEvents"

    log_categories = {
        "logStatusWarning": "Log messages with fmi2Warning status.",
        "logStatusError": "Log messages with fmi2Error status.",
        EVENTS: "Events of the motion: the overturning that freezes the outputs",
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
        # the lean per-step path (see _bind): Real inputs by reference -> (name, lo, hi), finite bounds, so
        # that one chained comparison checks the range, finiteness and nan as check_real does
        big = sys.float_info.max
        self._fast_inputs = {self._vr_of[s.name]: (s.name, -big if s.min is None else float(s.min),
                                                   big if s.max is None else float(s.max))
                             for s in self.variables if s.causality == "input" and s.type == "Real"}
        # outputs by reference -> (name, FMI type, Python type)
        self._output_vrs = {self._vr_of[s.name]: (s.name, s.type, _PY_TYPES[s.type])
                            for s in self.variables if s.causality == "output"}

    def _clear_state(self) -> None:
        # the FMU state (fmi2GetFMUstate / fmi2SetFMUstate): these flags, the variable values and the simulator
        self._sim = None
        self._eng = None                         # the compiled engine of _sim (the lean path), or None
        self._row = None                         # the engine's output_row() now, or None: read on demand
        self._lean = None                        # (input name, lo, hi) of the lean do_step path, or None
        self._real_out: Dict[int, int] = {}      # Real output reference -> position in the engine's row
        self._freeze_overturned = self._freeze_other = False
        self._reported = False                   # the Simulator's last_reports are not empty (lean path)
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
        if self._specs[name].causality == "output":
            return lambda: self._output_value(name)
        return lambda: self._values[name]

    def _output_value(self, name: str):
        """An output now: read from the compiled engine on demand (once per state), else the value copied at
        the end of the last step."""
        if self._eng is None:
            return self._values[name]
        row = self._row
        if row is None:
            row = self._row = self._eng.output_row()
        spec = self._specs[name]
        if spec.type == "Integer":            # a count past the largest fmi2Integer saturates there
            return int(min(row[self._out_pos[name]], _INT32[1]))
        return _PY_TYPES[spec.type](row[self._out_pos[name]])

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
        # the tool that generated the FMU is this project (pythonfmu writes its own name): the package's
        # version, the one source of it
        root.set("generationTool", f"{GENERATION_TOOL} {_package_version() or 'unknown'}")
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
        # a rate set before initialization refers to the start of the first communication step (FMI 2.0
        # section 4.2.1): the start time, whatever the time known when it was set
        self._rates = {name: (rate, self._t0) for name, (rate, _) in self._rates.items()}
        self._bind()
        self._update_outputs()

    def terminate(self):
        self._terminated = True

    def do_step(self, current_time: float, step_size: float) -> bool:
        """Advance to ``current_time + step_size``; False (fmi2Discard) when the step is refused with the state
        unchanged; raises ValueError on an invalid call (fmi2Error).

        The lean path (a compiled engine, one input held constant, no earlier failure): the same checks as
        `_do_step` as comparisons that pass, then one call into C between the engine's checkpoint and commit
        (none once the outputs are frozen). Anything else, including every check that fails, goes through
        `_do_step`, which words the message."""
        lean = self._lean
        if lean is not None and type(current_time) is float and type(step_size) is float and not self._rates \
                and self._error is None and not self._terminated:
            t, t_now = current_time, self._t
            t_end = t + step_size
            values = self._values
            ag = values[lean[0]]
            # the vertical input (ModelSlave: ag_v), 0.0 where the FMU has none
            ag_v = 0.0 if lean[3] is None else values[lean[3]]
            # t_now within time_tolerance of t (relative beyond 1 s), as _do_step words it
            lim = t_now if t_now >= 1.0 else (-t_now if t_now <= -1.0 else 1.0)
            if 0.0 < step_size <= _BIG and -_BIG <= t_end <= _BIG and lean[1] <= ag <= lean[2] and \
                    lean[4] <= ag_v <= lean[5] and \
                    (t == t_now or -self.time_tolerance * lim <= t - t_now <= self.time_tolerance * lim):
                if self._frozen:                  # overturned: the outputs stay, the time goes on
                    self._t = t_end
                    return True
                eng = self._eng
                t_sim = eng.t
                eng.checkpoint()
                try:
                    if ag_v == 0.0:               # the horizontal-only call: today's results bit for bit
                        eng.advance(t_end if t_end >= t_sim else t_sim, ag, 0.0, self._max_steps)
                    else:
                        eng.advance(t_end if t_end >= t_sim else t_sim, ag, 0.0, self._max_steps, ag_v=ag_v)
                except BaseException as exc:
                    eng.rollback()
                    return self._step_failed(exc, t, t_end, ag, ag_v)
                if eng.report_count:
                    if not self._step_reports(t, t_end):
                        return False
                elif self._reported:              # the Simulator's last_reports: this step's (none)
                    self._sim.last_reports = self._sim.integrator.reports = []
                    self._reported = False
                eng.commit()
                self._row = None
                if self._freeze_overturned:
                    if eng.overturned:
                        self._freeze()
                elif self._freeze_other:
                    self._update_outputs()
                self._t = t_end
                return True
        return self._do_step(current_time, step_size)

    def _step_failed(self, exc, t: float, t_end: float, ag: float, ag_v: float = 0.0) -> bool:
        """A failed engine advance (state restored) as `_do_step` treats it: refused (fmi2Discard) or a
        permanent failure (raises)."""
        try:
            # the Simulator's exception types and messages
            if ag_v == 0.0:
                self._sim._c_failed(exc, t_end, ag)
            else:
                self._c_failed_vertical(exc, t_end, ag, ag_v)
        except (WorkLimitError, ValueError) as err:
            return self._fail(f"step [{t!r}, {t_end!r}] refused, the FMU state is unchanged: {_describe(err)}")
        except Exception as err:
            self._error = f"simulation failed in the step [{t!r}, {t_end!r}]: {_describe(err)}"
            raise RuntimeError(self._error) from None
        raise AssertionError("unreachable: _c_failed always raises")  # pragma: no cover

    def _c_failed_vertical(self, exc, t_end: float, ag: float, ag_v: float) -> None:
        """`Simulator._c_failed` of a lean step under ag and a nonzero ag_v (held): the same exception types,
        the message of `Simulator._diverged` with both components (it names a large ag_v as the likely
        cause)."""
        import numpy as np

        from .. import _engine
        from ..ground_motion import ConstantMotion, TwoComponentMotion

        if isinstance(exc, (_engine.NonFiniteError, np.linalg.LinAlgError)):
            if isinstance(exc, _engine.NonFiniteError):
                exc = FloatingPointError(str(exc))
            motion = TwoComponentMotion(ConstantMotion(ag), ConstantMotion(ag_v))
            raise ValueError(self._sim._diverged(exc, t_end, motion, self._eng.fail_time)) from exc
        raise exc

    def _step_reports(self, t: float, t_end: float) -> bool:
        """Reports of a lean step: a failed internal step refuses it (rolled back, False); the others are
        logged as warnings (True)."""
        eng = self._eng
        self._reported = True
        try:
            self._sim._c_reports(eng)               # raises SolverFailure (a ValueError) on a failed step
        except ValueError as exc:
            eng.rollback()
            return self._fail(f"step [{t!r}, {t_end!r}] refused, the FMU state is unchanged: {_describe(exc)}")
        self._log_reports()
        return True

    def _do_step(self, current_time: float, step_size: float) -> bool:
        """do_step with every check worded and any input (several, interpolated, frozen outputs)."""
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

    def _bind(self) -> None:
        """Set up the lean per-step path on the compiled engine of the simulator (`Simulator(engine="c")`):
        do_step is one advance of the engine between its checkpoint and commit, and the outputs are read from
        the engine when the importer asks for them (`rocking_model.engine`'s output_row, cached until the next
        step), nothing copied per step. Any other simulator (a MotionSource) keeps the
        checked path: outputs copied from ``outputs()`` after every step."""
        sim, eng = self._sim, None
        self._real_out = {}
        if isinstance(sim, Simulator):
            eng = sim.integrator._engine
            keys = [*eng.output_names, "contact", "impacts", "overturned", "friction_demand", "painleve"]
            pos = {k: i for i, k in enumerate(keys)}
            for name, _ in self._outputs:
                if name not in pos:
                    raise KeyError(f"Simulator.outputs() has no entry {name!r}")
            self._out_pos = {name: pos[name] for name, _ in self._outputs}
            self._real_out = {vr: pos[name] for vr, (name, kind, _) in self._output_vrs.items() if kind == "Real"}
        self._eng, self._row, self._reported = eng, None, False
        self._max_steps = None if eng is None else sim.max_steps
        self._freeze_overturned = eng is not None and self.freeze_output == "overturned"
        self._freeze_other = eng is not None and self.freeze_output not in (None, "overturned")
        # the Real inputs the lean path steps (`_lean_inputs`): (name, lo, hi, vertical name or None, lo, hi)
        lean = None
        names = self._lean_inputs() if eng is not None else None
        if names is not None:
            name, lo, hi = self._fast_inputs[self._vr_of[names[0]]]
            if len(names) == 1:
                lean = (name, lo, hi, None, -_BIG, _BIG)
            else:
                lean = (name, lo, hi, *self._fast_inputs[self._vr_of[names[1]]])
        self._lean = lean

    def _lean_inputs(self) -> Optional[tuple]:
        """The names of the Real inputs that the lean path passes to the compiled engine, (horizontal,) or
        (horizontal, vertical); None: every step takes the checked path. Here: the single input of an FMU that
        keeps the default `advance`."""
        if len(self._inputs) == 1 and type(self).advance is RockingSlave.advance:
            return (self._inputs[0][0],)
        return None

    def _update_outputs(self) -> None:
        if self._eng is not None:             # read on demand (_output_value); only the freeze is decided now
            self._row = None
            if self.freeze_output is not None and not self._frozen and self._output_value(self.freeze_output):
                self._freeze()
            return
        out = self._sim.outputs()
        values = self._values
        for name, py in self._outputs:
            if name not in out:
                raise KeyError(f"Simulator.outputs() has no entry {name!r}")
            values[name] = py(out[name]) if py is not int else int(min(out[name], _INT32[1]))
        if self.freeze_output is not None and out.get(self.freeze_output) and not self._frozen:
            self._freeze()

    def _freeze(self) -> None:
        # an event of the motion, not a warning: the step that overturns returns fmi2OK
        self._frozen = True
        self.log(f"{self.freeze_output} at t = {self._sim.t:.6g} s: the outputs are frozen from now on",
                 Fmi2Status.ok, self.EVENTS)

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
        if self._eng is not None:             # the outputs now (read from the engine, not copied per step)
            for name, _ in self._outputs:
                values[name] = self._output_value(name)
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
        self._bind()

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
        Set before initialization (allowed by FMI 2.0), t_now is the start time (fmi2SetupExperiment's
        startTime, the first fmi2DoStep's currentCommunicationPoint).
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
        # the current communication point; before initialization no time has passed: the start time
        now = self._t if self._initialized else self._t0
        for name, rate in checked:
            old = self._rates.get(name)
            if old is not None and self._initialized:  # continue the line: the value at this point
                self._values[name] = self._values[name] + old[0] * (now - old[1])
            self._rates[name] = (rate, now)

    def get_real(self, vrs):
        # lean path: Real outputs read from the engine's row (one call into C per state); anything else, and
        # every bad reference, through _get
        where = self._real_out
        if where and type(vrs) is list:
            try:
                if len(vrs) == 1:             # the usual request: one output
                    i = where[vrs[0]]
                    row = self._row
                    if row is None:
                        row = self._row = self._eng.output_row()
                    return [row[i]]
                pos = [where[vr] for vr in vrs]
            except (KeyError, TypeError):
                pass
            else:
                row = self._row
                if row is None:
                    row = self._row = self._eng.output_row()
                return [row[i] for i in pos]
        return self._get(vrs, "Real")

    def get_integer(self, vrs):
        return self._get(vrs, "Integer")

    def get_boolean(self, vrs):
        return self._get(vrs, "Boolean")

    def get_string(self, vrs):
        return self._get(vrs, "String")

    def set_real(self, vrs, values):
        # lean path: one Real input set to a float inside its declared range (the check of _check_assignment as
        # one comparison: nan and inf fail it); anything else, and every message, through _set
        if type(vrs) is list and type(values) is list and len(vrs) == 1 == len(values):
            try:
                spec = self._fast_inputs.get(vrs[0])
            except TypeError:
                spec = None
            value = values[0]
            if spec is not None and type(value) is float and spec[1] <= value <= spec[2]:
                self._values[spec[0]] = value
                if self._rates:
                    self._rates.pop(spec[0], None)
                return
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



#: [unit/s] largest input rate accepted by fmi2SetRealInputDerivatives: AG_MAX reached from 0 in 1 ms, far
#: beyond any recorded ground motion (a steeper ramp is a step, which a zero-order hold represents)
INPUT_RATE_MAX = AG_MAX / 1e-3

#: the largest finite double: ``-_BIG <= x <= _BIG`` is math.isfinite(x) as one comparison (nan fails it)
_BIG = sys.float_info.max

#: [characters] longest text kept in a state or accepted for a String variable (a file path, a message)
_MAX_TEXT = 4096
#: FMI 2.0 fmi2Integer is a 32-bit int
_INT32 = (-2**31, 2**31 - 1)
#: the simulator's counts exposed as Integer outputs (any count >= 0 in a state) saturate at 2147483647, the
#: largest fmi2Integer: a run that counts past it saves states the FMU must take back
_SATURATES = " (saturates at 2147483647, the largest fmi2Integer)"


#: magnitude (in the parameter's own unit) below which a nonzero parameter is named as the likely cause of an
#: overflow: the smallest normal double (a smaller one is subnormal, and its reciprocal is inf)
_TINY = sys.float_info.min


def _overflow_message(exc: ArithmeticError, values: Dict[str, Any], params) -> str:
    """The message of a model whose construction overflowed: the exception and the parameters whose values
    are subnormal or huge, with their allowed ranges."""
    suspects = [q for q in params if not q.items and isinstance(values.get(q.name), float)
                and (0.0 < abs(values[q.name]) < _TINY or 1e300 < abs(values[q.name]) < math.inf)]
    named = "; ".join(f"{q.name} = {values[q.name]:g} (allowed range {q.range_text()}, but its reciprocal or "
                      f"square overflows)" for q in suspects)
    return (f"the parameters give a non-finite quantity in the model ({type(exc).__name__}: {exc})"
            + (f": {named}; use a value of normal magnitude (at least {_TINY:.3g})" if named else ""))


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


class ModelSlave(RockingSlave):
    """The FMU of a registered model (`rocking_model.models.MODELS`), its whole interface derived from the
    model's declarations: parameters (start values, units, ranges, descriptions), initial values, the solver
    options (`rocking_model.simulation.SOLVER_PARAMETERS`), the work budget, the inputs ag and ag_v (horizontal
    and vertical ground acceleration), the model's outputs and the simulator's (contact, impacts,
    overturned). An FMU script only names the model; its variable table follows (`variables_of`, set when the
    class is made, unless the class writes its own)::

        class RigidRockingBlock(ModelSlave):
            model_class = RigidBlock
            description = "..."
    """

    model_class: ClassVar[type] = None

    def __init_subclass__(cls, **kwargs):
        super().__init_subclass__(**kwargs)
        if cls.__dict__.get("model_class") is not None and "variables" not in cls.__dict__:
            cls.variables = ModelSlave.variables_of(cls.model_class)

    @staticmethod
    def variables_of(model_class) -> tuple:
        """The variable table of ``model_class``'s FMU (see the class docstring)."""
        from ..simulation import SOLVER_PARAMETERS
        from .variables import AG_INPUT, AG_V_INPUT, MAX_STEPS_PARAMETER, model_variables

        extra_outputs = (
            Var("contact", "output", 0, type="Integer", min=0, max=model_class.max_contact_code(),
                description="Contact state: " + model_class.contact_description()),
            Var("impacts", "output", 0, type="Integer", description="Number of impacts so far" + _SATURATES),
            Var("overturned", "output", False, type="Boolean",
                description="True once the structure has overturned (|phi| reached pi/2): from then on the "
                            "outputs are frozen at the pose reached, at rest (velocities 0, energy of that "
                            "pose, contact 10)"),
            Var("friction_demand", "output", 0.0, unit="1",
                description="The largest friction coefficient the corners needed so far, |sum lambda_T| / "
                            "sum lambda_N of the forces (event-driven: their continuous maximum; Moreau-Jean: "
                            "per-step percussions) and of the impact percussions (the paper's sticking law "
                            "holds where it stays below the surface's "
                            "mu; values near 1e6 mean a lift-off where sticking needs unbounded friction)"),
            Var("painleve", "output", 0, type="Integer",
                description="Painleve situations met so far (sliding with no or several consistent "
                            "accelerations, each resolved by an impact without collision)" + _SATURATES),
        )
        return model_variables(model_class, SOLVER_PARAMETERS, (MAX_STEPS_PARAMETER,), (AG_INPUT, AG_V_INPUT),
                               extra_outputs)

    def advance(self, sim, t_end: float, inputs: Dict[str, Any]) -> None:
        """Advance under ag and ag_v (each a number held over the step or a `LinearMotion`); ag_v = 0 held
        takes the horizontal-only call, so that its results are today's bit for bit."""
        ag_v = inputs["ag_v"]
        if type(ag_v) is float and ag_v == 0.0:
            sim.advance(t_end, inputs["ag"])
        else:
            sim.advance(t_end, inputs["ag"], ag_v=ag_v)

    def _lean_inputs(self) -> Optional[tuple]:
        if type(self).advance is ModelSlave.advance:
            return ("ag", "ag_v")
        return super()._lean_inputs()

    def create_simulator(self, p, t0):
        from ..simulation import SOLVER_PARAMETERS
        from .variables import MAX_STEPS_PARAMETER

        # the work budget checked against its declaration (the modelDescription's min and max), so that the
        # declaration, this check and its message agree (the Python API accepts up to 2^53)
        max_steps, lo, hi = p["max_steps"], MAX_STEPS_PARAMETER.min, MAX_STEPS_PARAMETER.max
        if not lo <= max_steps <= hi:  # integers written in full, as in the modelDescription
            raise ValueError(f"max_steps = {max_steps} is out of range; allowed range [{lo}, {hi}]")
        cls = self.model_class
        options = {q.name: p[q.name] for q in SOLVER_PARAMETERS}
        initial = {q.name: p[q.name] for q in cls.INITIAL if q.fmu}
        try:
            model = cls(**{q.name: p[q.name] for q in cls.parameters() if q.fmu})
            # impact_log_size = 0: the FMU keeps no impact log (memory flat over any run; the count is kept)
            return Simulator(model, t0=t0, impact_log_size=0, max_steps=max_steps,
                             **options, **initial)
        except ArithmeticError as exc:
            # guard: a value inside its declared range whose derived quantities overflow (a subnormal number
            # has an infinite reciprocal): refused here with the values at the edge of the floating-point range
            raise ValueError(_overflow_message(exc, p, [*cls.parameters(), *cls.INITIAL, *SOLVER_PARAMETERS])) \
                from None
