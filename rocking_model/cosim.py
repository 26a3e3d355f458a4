"""Co-simulation of several FMUs: a minimal fixed-step master on top of fmpy, the same system run in
Open Simulation Platform's libcosim (libcosimpy), and the ground-motion source behind the
GroundMotionSource FMU.

System description. A system is read from an OSP system structure file (``OspSystemStructure.xml``, the
format libcosim reads): ``<StartTime>``, ``<BaseStepSize>``, ``<Simulators>`` (name, FMU ``source``
relative to the file, optional ``stepSize``, ``<InitialValues>``) and ``<Connections>`` /
``<VariableConnection>`` (two ``<Variable simulator=... name=...>``; the output end is found from the
causalities). The same file drives both masters, so their results can be compared.

Master algorithm (`FmpyMaster`, mirroring libcosim's ``fixedStep`` algorithm). Time is counted in
integer nanoseconds as in libcosim: communication point n is ``t_n = (t0_ns + n * h_ns) / 1e9`` and every
step is ``h_ns / 1e9`` long, so both masters hand the FMUs the same doubles. In each base step, every
component whose step (a multiple of the base step) is due gets its inputs set (connected values, then
overrides) and steps from t_n; then the outputs of the components that stepped are copied to the connected
inputs (Jacobi: a value produced at t_{n+1} is used in the step that starts at t_{n+1}). Inputs are held
constant over a step. After initialization the outputs are copied once, so the first step uses the
values at t0.

fmpy has no multi-FMU master; libcosimpy is optional (``pip install rocking-model[cosim]``).
"""
from __future__ import annotations

import csv
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Dict, List, Mapping, Optional, Sequence, Tuple
from xml.etree import ElementTree

import numpy as np

from .ground_motion import GroundMotion, pulse_from_parameters
from .records import Record, load_motion, unit_factor
from .validation import check_real

__all__ = ["MotionSource", "load_record", "ground_motion_from_parameters", "Component", "Connection",
           "System", "read_osp_system_structure", "write_osp_system_structure", "FmpyMaster", "run_fmpy", "run_libcosim", "NS"]

NS = 1_000_000_000  #: nanoseconds per second (libcosim's time unit)


# ------------------------------------------------------------------------------------------------------
# the ground-motion source component
#: units of a CSV record for the GroundMotionSource FMU when neither the file nor the ``units`` parameter
#: states them (the FMU's historical reading)
RECORD_DEFAULT_UNITS = "m/s2"


def load_record(path, units: Optional[str] = None) -> Record:
    """Read the ground-motion record of the GroundMotionSource FMU with `rocking_model.records` (the reader
    of the CLI and the ensembles, with the same errors): a PEER ``.AT2`` file (units from its line 3, else
    g), a two-column ``.csv``/``.txt``/``.dat``/``.tsv`` file (time [s], acceleration; units from the header
    ``time [s], ag [cm/s2]`` or a ``# units: g`` comment, else ``units``, else m/s2) or ``synthetic[:seed]``.
    ``units`` that contradict the units the file states are an error. Returns a `Record` (ag in m/s2)."""
    return load_motion(str(path), units or None, default_units=RECORD_DEFAULT_UNITS)


def ground_motion_from_parameters(p: Mapping[str, Any]) -> GroundMotion:
    """The ground motion named by the GroundMotionSource parameters: ``motion`` 0 = one-sine pulse
    (``A`` [m/s2], ``omega_p`` [rad/s], ``t_start`` [s], built by
    `rocking_model.ground_motion.pulse_from_parameters` like the CLI's and the ensembles' pulses), 1 = the
    record ``record`` (a file or ``synthetic[:seed]``, read by `load_record` in ``units``; "" = as the file
    states, else m/s2); both multiplied by ``scale`` [1]. Raises ValueError naming the parameter and its
    allowed values."""
    motion = p.get("motion", 0)
    scale = check_real("scale", p.get("scale", 1.0))
    units = str(p.get("units", "") or "")
    if units:
        unit_factor(units)          # a misspelt unit is an error whatever the motion
    if motion == 0:
        return pulse_from_parameters("sine", p["A"], p["omega_p"], p.get("t_start", 0.0), scale=scale)
    if motion == 1:
        record = str(p.get("record", ""))
        if not record:
            raise ValueError("record = '': motion = 1 needs a record file (.AT2, .csv) or synthetic[:seed]")
        return load_record(record, units).scaled(scale)
    raise ValueError(f"motion = {motion!r} is not supported; allowed values: 0 (sine pulse), 1 (record)")


class MotionSource:
    """A ground motion as a stepwise component (``t``, ``advance(t_end)``, ``outputs()``): the output
    ``ag`` at a communication point t is ag(t), exactly as the standalone FMU would be driven by a table
    sampled at the communication points.

    Every value must be a finite number with |ag| <= AG_MAX (1000 m/s2): a motion whose known peak exceeds
    it is refused here, and a step whose end value is out of range is refused by `advance` (ValueError
    naming ag, the time kept). `get_state` / `set_state` save and load the time as plain data."""

    def __init__(self, motion: GroundMotion, t0: float = 0.0):
        from .ground_motion import checked_motion

        self.motion = checked_motion(motion)
        self.t = check_real("t0", t0)
        self._ag = self._value(self.t)

    def _value(self, t: float) -> float:
        # self.motion is a checked motion (`checked_motion`): its values are finite and within AG_MAX, or it
        # raises ValueError naming ag and t
        return float(self.motion(t))

    def advance(self, t_end: float) -> None:
        """Move to ``t_end`` [s]; the output becomes ag(t_end). Raises ValueError (state kept) for a t_end
        before the current time or not finite, or an ag(t_end) out of range."""
        t_end = check_real("t_end", t_end)
        if t_end < self.t:
            raise ValueError(f"t_end = {t_end!r} is before the current time {self.t!r}")
        value = self._value(t_end)
        self.t, self._ag = t_end, value

    def outputs(self) -> dict:
        return {"ag": self._ag}

    #: the `get_state` fields
    STATE_KEYS = ("version", "model", "t")

    def get_state(self) -> dict:
        """The time [s] (the motion is a parameter: rebuild the source from it, then `set_state`) as a flat
        dict of plain values, with a version and the component's name."""
        return {"version": 1, "model": "MotionSource", "t": float(self.t)}

    def set_state(self, state) -> None:
        """Load a `get_state` dict: every field checked (ValueError naming it, nothing changed on error)."""
        from .validation import check_state_header, state_float

        check_state_header(state, "MotionSource", self.STATE_KEYS)
        t = state_float(state, "t")
        value = self._value(t)
        self.t, self._ag = t, value


# ------------------------------------------------------------------------------------------------------
# system description
@dataclass
class Component:
    name: str
    fmu: Path
    step_size: Optional[float] = None            # None: the base step
    start_values: Dict[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class Connection:
    source: Tuple[str, str]                       # (component, output)
    target: Tuple[str, str]                       # (component, input)


@dataclass
class System:
    components: List[Component]
    connections: List[Connection]
    step_size: float
    start_time: float = 0.0

    def component(self, name: str) -> Component:
        for c in self.components:
            if c.name == name:
                return c
        raise KeyError(f"no component {name!r}; components: {[c.name for c in self.components]}")


_OSP = "{http://opensimulationplatform.com/MSMI/OSPSystemStructure}"


def _strip(tag: str) -> str:
    return tag.split("}", 1)[-1]


def _children(node, name):
    return [c for c in node if _strip(c.tag) == name]


def _child(node, name):
    found = _children(node, name)
    return found[0] if found else None


def read_osp_system_structure(path) -> System:
    """Parse an OspSystemStructure.xml (FMU paths resolved relative to the file; the direction of each
    connection from the causalities in the modelDescriptions)."""
    from fmpy import read_model_description

    path = Path(path)
    root = ElementTree.parse(path).getroot()
    if _strip(root.tag) != "OspSystemStructure":
        raise ValueError(f"{path}: root element is {_strip(root.tag)!r}, expected 'OspSystemStructure'")
    start = _child(root, "StartTime")
    base = _child(root, "BaseStepSize")
    if base is None:
        raise ValueError(f"{path}: <BaseStepSize> is required")
    algo = _child(root, "Algorithm")
    if algo is not None and algo.text.strip() != "fixedStep":
        raise ValueError(f"{path}: only the fixedStep algorithm is supported, got {algo.text.strip()!r}")
    components = []
    causality: Dict[Tuple[str, str], str] = {}
    for sim in _children(_child(root, "Simulators"), "Simulator"):
        fmu = (path.parent / sim.get("source")).resolve()
        values = {}
        init = _child(sim, "InitialValues")
        for iv in (_children(init, "InitialValue") if init is not None else []):
            (typed,) = list(iv)
            kind, text = _strip(typed.tag), typed.get("value")
            values[iv.get("variable")] = {"Real": float, "Integer": int, "String": str,
                                          "Boolean": lambda s: s.strip().lower() in ("true", "1")}[kind](text)
        step = sim.get("stepSize")
        components.append(Component(sim.get("name"), fmu, None if step is None else float(step), values))
        for v in read_model_description(str(fmu)).modelVariables:
            causality[(sim.get("name"), v.name)] = v.causality
    connections = []
    conns = _child(root, "Connections")
    for vc in (_children(conns, "VariableConnection") if conns is not None else []):
        a, b = [(v.get("simulator"), v.get("name")) for v in _children(vc, "Variable")]
        for end in (a, b):
            if end not in causality:
                raise ValueError(f"{path}: connection end {end[0]}.{end[1]} does not exist")
        if causality[a] == "output" and causality[b] == "input":
            connections.append(Connection(a, b))
        elif causality[b] == "output" and causality[a] == "input":
            connections.append(Connection(b, a))
        else:
            raise ValueError(f"{path}: connection {a} - {b} must join an output and an input")
    return System(components, connections, float(base.text),
                  0.0 if start is None else float(start.text))


def write_osp_system_structure(system: System, path) -> Path:
    """Write ``system`` as an OspSystemStructure.xml (FMU paths absolute); return the path."""
    path = Path(path)
    ns = _OSP[1:-1]
    root = ElementTree.Element("OspSystemStructure", {"xmlns": ns, "version": "0.1"})
    ElementTree.SubElement(root, "StartTime").text = repr(float(system.start_time))
    ElementTree.SubElement(root, "BaseStepSize").text = repr(float(system.step_size))
    ElementTree.SubElement(root, "Algorithm").text = "fixedStep"
    sims = ElementTree.SubElement(root, "Simulators")
    for c in system.components:
        attrs = {"name": c.name, "source": str(Path(c.fmu).resolve())}
        if c.step_size is not None:
            attrs["stepSize"] = repr(float(c.step_size))
        sim = ElementTree.SubElement(sims, "Simulator", attrs)
        if c.start_values:
            init = ElementTree.SubElement(sim, "InitialValues")
            for name, value in c.start_values.items():
                iv = ElementTree.SubElement(init, "InitialValue", {"variable": name})
                if isinstance(value, bool):
                    ElementTree.SubElement(iv, "Boolean", {"value": "true" if value else "false"})
                elif isinstance(value, int):
                    ElementTree.SubElement(iv, "Integer", {"value": str(value)})
                elif isinstance(value, float):
                    ElementTree.SubElement(iv, "Real", {"value": repr(value)})
                else:
                    ElementTree.SubElement(iv, "String", {"value": str(value)})
    conns = ElementTree.SubElement(root, "Connections")
    for con in system.connections:
        vc = ElementTree.SubElement(conns, "VariableConnection")
        for comp, var in (con.source, con.target):
            ElementTree.SubElement(vc, "Variable", {"simulator": comp, "name": var})
    ElementTree.indent(root)
    ElementTree.ElementTree(root).write(path, encoding="utf-8", xml_declaration=True)
    return path


def _ticks(seconds: float) -> int:
    return int(round(float(seconds) * NS))


def _step(t_ticks: int, step_ticks: int) -> float:
    """Step length in seconds as libcosim computes it (``to_double_duration``): the difference of the two
    communication points as doubles, so that t + dt lands on the next point as the FMU computes it."""
    return (t_ticks + step_ticks) / NS - t_ticks / NS


# ------------------------------------------------------------------------------------------------------
# fmpy master
class _Slave:
    def __init__(self, comp: Component, base_ticks: int, tmp: Path):
        from fmpy import extract, read_model_description
        from fmpy.fmi2 import FMU2Slave

        self.name = comp.name
        self.md = read_model_description(str(comp.fmu))
        self.vars = {v.name: v for v in self.md.modelVariables}
        step = base_ticks if comp.step_size is None else _ticks(comp.step_size)
        if step % base_ticks:
            raise ValueError(f"{comp.name}: stepSize must be a multiple of the base step")
        self.decimation = step // base_ticks
        self.step_ticks = step
        unzip = extract(str(comp.fmu), unzipdir=str(tmp / comp.name))
        self.fmu = FMU2Slave(guid=self.md.guid, unzipDirectory=unzip,
                             modelIdentifier=self.md.coSimulation.modelIdentifier, instanceName=comp.name)
        self.start_values = dict(comp.start_values)
        self.pending: Dict[str, Any] = {}

    def var(self, name):
        try:
            return self.vars[name]
        except KeyError:
            raise KeyError(f"{self.name} has no variable {name!r}") from None

    def set(self, name, value):
        v = self.var(name)
        vr = [v.valueReference]
        if v.type == "Real":
            self.fmu.setReal(vr, [float(value)])
        elif v.type in ("Integer", "Enumeration"):
            self.fmu.setInteger(vr, [int(value)])
        elif v.type == "Boolean":
            self.fmu.setBoolean(vr, [bool(value)])
        else:
            self.fmu.setString(vr, [str(value)])

    def get(self, name):
        v = self.var(name)
        vr = [v.valueReference]
        if v.type == "Real":
            return self.fmu.getReal(vr)[0]
        if v.type in ("Integer", "Enumeration"):
            return self.fmu.getInteger(vr)[0]
        if v.type == "Boolean":
            return self.fmu.getBoolean(vr)[0]
        return self.fmu.getString(vr)[0]


class FmpyMaster:
    """Fixed-step Jacobi master for a `System` of FMI 2.0 co-simulation FMUs, driven through fmpy.

    ``inputs`` maps "component.variable" to a callable f(t) evaluated at the start of each step (an
    override, like a libcosim override manipulator). ``run`` returns a structured array with "time" and
    one column "component.variable" per requested output (values at every base communication point).
    """

    def __init__(self, system: System):
        self.system = system

    def run(self, stop_time: float, outputs: Sequence[str], inputs: Optional[Mapping[str, Callable]] = None,
            start_values: Optional[Mapping[str, Any]] = None) -> np.ndarray:
        sysm = self.system
        base, t0 = _ticks(sysm.step_size), _ticks(sysm.start_time)
        n_steps = int(round((_ticks(stop_time) - t0) / base))
        overrides = {tuple(k.split(".", 1)): f for k, f in (inputs or {}).items()}
        extra = {tuple(k.split(".", 1)): v for k, v in (start_values or {}).items()}
        probes = [tuple(k.split(".", 1)) for k in outputs]
        with tempfile.TemporaryDirectory(prefix="rocking_cosim_") as tmp:
            slaves = {c.name: _Slave(c, base, Path(tmp)) for c in sysm.components}
            try:
                for c, _ in list(extra) + list(overrides) + probes:
                    if c not in slaves:
                        raise KeyError(f"no component {c!r}")
                from .fmi import fmpy_callbacks

                for s in slaves.values():
                    s.start_values.update({v: x for (c, v), x in extra.items() if c == s.name})
                    s.fmu.instantiate(callbacks=fmpy_callbacks())
                    s.fmu.setupExperiment(startTime=t0 / NS)
                    s.fmu.enterInitializationMode()
                    for name, value in s.start_values.items():
                        s.set(name, value)
                    s.fmu.exitInitializationMode()
                self._transfer(slaves, set(slaves))
                rows = [self._sample(slaves, probes, t0 / NS)]
                for n in range(n_steps):
                    t_ticks = t0 + n * base
                    stepped = set()
                    for s in slaves.values():
                        if n % s.decimation:
                            continue
                        for name, value in s.pending.items():
                            s.set(name, value)
                        for (c, v), f in overrides.items():
                            if c == s.name:
                                s.set(v, f(t_ticks / NS))
                        try:  # fmpy raises FMICallException for fmi2Discard / fmi2Error
                            s.fmu.doStep(currentCommunicationPoint=t_ticks / NS,
                                         communicationStepSize=_step(t_ticks, s.step_ticks))
                        except Exception as exc:
                            raise RuntimeError(f"{s.name}: doStep at t = {t_ticks / NS:g} s failed: {exc}") from exc
                        stepped.add(s.name)
                    self._transfer(slaves, stepped)
                    rows.append(self._sample(slaves, probes, (t_ticks + base) / NS))
            finally:
                for s in slaves.values():
                    try:
                        s.fmu.terminate()
                        s.fmu.freeInstance()
                    except Exception:
                        pass
        dtype = [("time", np.float64)] + [(f"{c}.{v}", np.float64) for c, v in probes]
        return np.array([tuple(r) for r in rows], dtype=dtype)

    def _transfer(self, slaves, stepped):
        for con in self.system.connections:
            if con.source[0] in stepped:
                slaves[con.target[0]].pending[con.target[1]] = slaves[con.source[0]].get(con.source[1])

    @staticmethod
    def _sample(slaves, probes, t):
        return [t] + [float(slaves[c].get(v)) for c, v in probes]


def run_fmpy(system, stop_time: float, outputs: Sequence[str], **kwargs) -> np.ndarray:
    """Run a `System` or the system of an OspSystemStructure.xml with `FmpyMaster` (keyword arguments as
    `FmpyMaster.run`)."""
    if not isinstance(system, System):
        system = read_osp_system_structure(system)
    return FmpyMaster(system).run(stop_time, outputs, **kwargs)


# ------------------------------------------------------------------------------------------------------
# libcosim (Open Simulation Platform) through libcosimpy
def check_initialization(system: System, start_values: Optional[Mapping[str, Any]] = None) -> None:
    """Instantiate and initialize every component of ``system`` once, through fmpy, with its start values
    (and the "component.variable" overrides of ``start_values``); raise ValueError naming the component and
    the FMU's message if one fails (invalid parameters: fmi2ExitInitializationMode returns fmi2Error).

    Why: libcosim (0.10) ends its process when an FMU answers fmi2Error during initialization (the exception
    escapes its worker thread), so `run_libcosim` checks the initialization here first, where an error is an
    exception."""
    from fmpy.fmi1 import FMICallException

    from .fmi import collect_fmu_messages, fmpy_callbacks

    extra = {tuple(k.split(".", 1)): v for k, v in (start_values or {}).items()}
    base, t0 = _ticks(system.step_size), _ticks(system.start_time)
    with tempfile.TemporaryDirectory(prefix="rocking_check_") as tmp:
        for comp in system.components:
            slave = _Slave(comp, base, Path(tmp))
            slave.start_values.update({v: x for (c, v), x in extra.items() if c == comp.name})
            with collect_fmu_messages() as messages:
                try:
                    slave.fmu.instantiate(callbacks=fmpy_callbacks())
                except Exception as exc:
                    raise ValueError(f"component {comp.name}: fmi2Instantiate failed: "
                                     f"{'; '.join(m for _, _, m in messages) or exc}") from None
                try:
                    slave.fmu.setupExperiment(startTime=t0 / NS)
                    slave.fmu.enterInitializationMode()
                    for name, value in slave.start_values.items():
                        slave.set(name, value)
                    slave.fmu.exitInitializationMode()
                except FMICallException as exc:
                    text = "; ".join(m for _, _, m in messages) or "no message"
                    raise ValueError(f"component {comp.name}: {exc}: {text}") from None
                finally:
                    slave.fmu.freeInstance()


def run_libcosim(system, stop_time: float, outputs: Sequence[str],
                 inputs: Optional[Mapping[str, Callable]] = None,
                 start_values: Optional[Mapping[str, Any]] = None) -> np.ndarray:
    """Run a `System` or the system of an OspSystemStructure.xml in libcosim, one base step at a time, and
    return the same structured array as `FmpyMaster.run` without its first row (libcosim's observers have
    values only from the first step on: the rows are t0 + h, t0 + 2h, ...). ``inputs``
    ("component.variable" -> f(t)) are applied with an override manipulator before each step;
    ``start_values`` ("component.variable" -> value) override the initial values. Every component is
    initialized once through fmpy first (`check_initialization`): invalid parameters raise ValueError here
    instead of ending the process inside libcosim."""
    if isinstance(system, System):
        with tempfile.TemporaryDirectory(prefix="rocking_osp_") as tmp:
            osp = write_osp_system_structure(system, Path(tmp) / "OspSystemStructure.xml")
            return run_libcosim(osp, stop_time, outputs, inputs, start_values)
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimManipulator import CosimManipulator
    from libcosimpy.CosimObserver import CosimObserver

    log_output_level(CosimLogLevel.WARNING)

    osp_file = Path(system).resolve()
    system = read_osp_system_structure(osp_file)
    check_initialization(system, start_values)
    execution = CosimExecution.from_osp_config_file(str(osp_file))
    return _drive_libcosim(execution, system, stop_time, outputs, inputs, start_values,
                           CosimManipulator, CosimObserver)


def _drive_libcosim(execution, system, stop_time, outputs, inputs, start_values, CosimManipulator,
                    CosimObserver):
    index = {info.name.decode(): info.index for info in execution.slave_infos()}
    variables = {}
    for name, i in index.items():
        variables[name] = {v.name.decode(): (v.reference, v.type) for v in execution.slave_variables(i)}

    def lookup(key):
        comp, var = key.split(".", 1)
        if comp not in index or var not in variables[comp]:
            raise KeyError(f"libcosim: no variable {key!r}")
        return index[comp], variables[comp][var]

    for key, value in (start_values or {}).items():
        i, (vr, typ) = lookup(key)
        setter = {0: execution.real_initial_value, 1: execution.integer_initial_value,
                  2: execution.string_initial_value, 3: execution.boolean_initial_value}[typ]
        setter(i, vr, value)
    manipulator = CosimManipulator.create_override()
    execution.add_manipulator(manipulator)
    observer = CosimObserver.create_last_value()
    execution.add_observer(observer)
    probes = [lookup(k) for k in outputs]
    overrides = [(lookup(k), f) for k, f in (inputs or {}).items()]
    getters = {0: observer.last_real_values, 1: observer.last_integer_values,
               2: observer.last_string_values, 3: observer.last_boolean_values}

    def sample():
        return [float(getters[typ](i, [vr])[0]) for i, (vr, typ) in probes]

    base, t0 = _ticks(system.step_size), _ticks(system.start_time)
    n_steps = int(round((_ticks(stop_time) - t0) / base))
    rows = []
    for n in range(n_steps):
        t_ticks = t0 + n * base
        for (i, (vr, typ)), f in overrides:
            manipulator.slave_real_values(i, [vr], [float(f(t_ticks / NS))])
        if not execution.step():
            raise RuntimeError(f"libcosim: step at t = {t_ticks / NS:g} failed: {execution.status()}")
        if n == 0:
            # the observer has values only once the execution is initialized (the first step does it);
            # the values at t0 are the start values, which both masters report from initialization
            rows.append(None)
        rows.append([(t_ticks + base) / NS] + sample())
    status = execution.status()
    if status.current_time != t0 + n_steps * base:
        raise RuntimeError(f"libcosim: stopped at {status.current_time} ns, expected {t0 + n_steps * base}")
    dtype = [("time", np.float64)] + [(k, np.float64) for k in outputs]
    result = np.array([tuple(r) for r in rows[1:]], dtype=dtype)
    return result


def write_csv(path, result: np.ndarray) -> None:
    """Write a structured result array as CSV (header = column names)."""
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(result.dtype.names)
        for row in result:
            w.writerow([repr(float(x)) for x in row])
