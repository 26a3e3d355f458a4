"""Importer side: run an FMU of this package through fmpy and fail loudly (`run_fmu`, `run_fmu_record`,
`FMUError`), with fmpy's logger kept alive and routed per instance (`fmpy_callbacks`,
`collect_fmu_messages`). Needs fmpy only, not pythonfmu."""
from __future__ import annotations

import math
import threading
from contextlib import contextmanager
from typing import Any, Dict, List, Optional, Sequence

from ..validation import check_real

#: FMI 2.0 status codes (fmi2Error and worse are errors)
_STATUS_ERROR = 3
_FMPY_LOCK = threading.Lock()

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


def choice_codes(filename, values: Dict[str, Any]) -> Dict[str, Any]:
    """``values`` with the names of choice parameters (``{"scheme": "moreau_jean"}``, ``impact_rule``) replaced
    by their integer codes, read from the declarations of the FMU's model (`rocking_model.models.MODELS`,
    `rocking_model.simulation.SOLVER_PARAMETERS`); fmpy passes start values through int(). FMUError for a
    name that is none of the choices."""
    if not any(isinstance(v, str) for v in values.values()):
        return dict(values)
    from fmpy import read_model_description

    from ..models import MODELS
    from ..simulation import SOLVER_PARAMETERS

    name = read_model_description(str(filename)).modelName
    model = next((cls for cls in MODELS.values() if cls.fmu_name == name), None)
    declared = list(SOLVER_PARAMETERS) + (list(model.parameters()) if model is not None else [])
    out = dict(values)
    for p in declared:
        value = out.get(p.name)
        if p.items and isinstance(value, str):
            codes = {item: code for item, code, _ in p.items}
            if value not in codes:
                raise FMUError(f"{filename}: {p.name} = {value!r} is not one of its choices: " + ", ".join(codes))
            out[p.name] = codes[value]
    return out


def run_fmu(filename, *, stop_time: float, output_interval: float, start_time: float = 0.0,
            start_values: Optional[Dict[str, Any]] = None, input=None, output=None, **kwargs):
    """``fmpy.simulate_fmu`` that fails loudly: raise :class:`FMUError` with the FMU's messages if a call
    fails (fmi2Error: invalid parameters, inputs, ...), the FMU logged an error, or the run ended before
    ``stop_time`` (a refused step: fmi2Discard with fmi2Terminated, which fmpy treats as an early end).
    ``output_interval`` is the co-simulation step (always pass it: fmpy coarsens the default one).
    Choice parameters (``scheme``, ``impact_rule``) take their names or codes. Returns
    the fmpy result (structured array with a 'time' column).
    """
    import fmpy
    from fmpy.fmi1 import FMICallException

    start_values = choice_codes(filename, start_values or {})
    with collect_fmu_messages() as messages:
        try:
            result = fmpy.simulate_fmu(str(filename), start_time=start_time, stop_time=stop_time,
                                       output_interval=output_interval, start_values=start_values,
                                       input=input, output=output, **kwargs)
        except FMICallException as exc:
            errors = [m for s, _, m in messages if s >= _STATUS_ERROR]
            raise FMUError(f"{filename}: {exc}: " + ("; ".join(errors) or "no error message"), messages) from None
    errors = [m for s, _, m in messages if s >= _STATUS_ERROR]
    t_last = float(result["time"][-1])
    early = t_last < stop_time and not math.isclose(t_last, stop_time, rel_tol=1e-9, abs_tol=1e-12)
    if errors or early:
        what = "; ".join(errors) if errors else "no error message"
        raise FMUError(f"{filename}: simulation failed at t = {t_last:g} s (stop_time = {stop_time:g} s): "
                       f"{what}", messages, result)
    return result


def run_fmu_record(filename, t_record, ag_record, *, step: float, stop_time: float, hold: str = "linear",
                   start_values: Optional[Dict[str, Any]] = None, output: Sequence[str] = ("phi",),
                   ag_v_record=None):
    """Drive an FMU with input ``ag`` through a sampled record (times ``t_record`` [s], values ``ag_record``
    [m/s2], linear between samples) with communication step ``step`` [s]; return a structured array with
    "time" and the ``output`` variables at t = 0 (after initialization) and after every step, the rows of
    `rocking_model.simulate`.

    ``hold="linear"``: at every communication point the master sets ag and its slope over the coming step
    (fmi2SetRealInputDerivatives, order 1), so the FMU integrates the record's straight line over the step;
    with ``step`` equal to the record's sampling that is the record itself. ``hold="zoh"``: ag held constant
    over each step (what a master without input derivatives does). fmpy 0.3.32's
    ``simulate_fmu(set_input_derivatives=True)`` cannot serve here: its derivative buffer has a fixed length
    of 9 (one input raises ValueError) and at a sample point it passes the slope of the previous interval.

    ``ag_v_record``: the vertical ground acceleration [m/s2, positive upward] at the times ``t_record``, driven
    into the input ``ag_v`` with the same hold; None: ag_v is left at its start value (0)."""
    import numpy as np
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave

    hold = {"linear": "linear", "zoh": "zoh"}.get(hold)
    if hold is None:
        raise ValueError("hold must be 'linear' or 'zoh'")
    step = check_real("step", step, lo=0.0, lo_open=True)
    t_record = np.asarray(t_record, dtype=float)
    ag_record = np.asarray(ag_record, dtype=float)
    records = [("ag", ag_record)]
    if ag_v_record is not None:
        records.append(("ag_v", np.asarray(ag_v_record, dtype=float)))
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
            rows.append(tuple([0.0] + [fmu.getReal([vr[o]])[0] for o in output]))  # the initial row
            for k in range(n):
                t = k * step
                for name, values in records:
                    a0 = float(np.interp(t, t_record, values))
                    fmu.setReal([vr[name]], [a0])
                    if hold == "linear":
                        a1 = float(np.interp(t + step, t_record, values))
                        fmu.setRealInputDerivatives([vr[name]], [1], [(a1 - a0) / step])
                fmu.doStep(t, step)
                rows.append(tuple([t + step] + [fmu.getReal([vr[o]])[0] for o in output]))
            fmu.terminate()
        except FMICallException as exc:
            errors = [m for st, _, m in messages if st >= _STATUS_ERROR]
            raise FMUError(f"{filename}: {exc}: " + ("; ".join(errors) or "no error message"), messages) from None
        finally:
            fmu.freeInstance()
    return np.array(rows, dtype=[("time", float)] + [(o, float) for o in output])


def _text(value) -> str:
    if value is None:
        return ""
    return value.decode("utf-8", "replace") if isinstance(value, bytes) else str(value)
