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

Status of every FMI call. The FMUs run the project's own binary (``rocking_model/fmi/binary/``, see its ``fmi2_cs.c``),
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
  stay frozen and ``do_step`` keeps returning True; the overturning is an event of the motion, not a
  warning: its step returns fmi2OK and the message is logged with fmi2OK under the category ``logEvents``.

Messages are queued with `RockingSlave.log`; the binary passes each one to the importer's logger as data
(``"%s"``): errors and warnings always, the others (the events) only with logging on and their category
enabled by ``fmi2SetDebugLogging`` (no category named, ``logEvents`` or ``logAll``).

Each FMU bundles the package under the digest of its sources (``rocking_model.fmi.build``), so FMUs built
from other versions and a host's own ``rocking_model`` can live in one process.

Modules (one concern each): `variables` (the variable table, units, pythonfmu variable classes, the
variables derived from a model's declarations), `slave` (the slave and its state machine), the state format
(`rocking_model.fmi_state`) and `importer` (running FMUs through fmpy).
"""
from __future__ import annotations

from pythonfmu.default_experiment import DefaultExperiment
from pythonfmu.enums import Fmi2Status

from ..validation import AG_MAX
from .slave import INPUT_RATE_MAX, ModelSlave, RockingSlave
from .variables import AG_INPUT, AG_V_INPUT, MAX_STEPS_PARAMETER, UNITS, Var

#: the importer-side names, loaded on first use (an FMU never needs them: its cold start stays short)
_IMPORTER = ("FMUError", "collect_fmu_messages", "fmpy_callbacks", "run_fmu", "run_fmu_record", "choice_codes")


def __getattr__(name):
    if name in _IMPORTER:
        from . import importer
        return getattr(importer, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")

__all__ = ["AG_INPUT", "AG_V_INPUT", "AG_MAX", "MAX_STEPS_PARAMETER", "UNITS", "Var", "RockingSlave", "ModelSlave",
           "DefaultExperiment",
           "Fmi2Status", "FMUError", "run_fmu", "run_fmu_record", "fmpy_callbacks", "collect_fmu_messages",
           "INPUT_RATE_MAX"]
