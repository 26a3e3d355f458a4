"""Co-simulation of several FMUs: a minimal fixed-step master on top of fmpy, the same system run in
Open Simulation Platform's libcosim (libcosimpy), and the ground-motion source behind the
GroundMotionSource FMU.

System description. A system is read from an OSP system structure file (``OspSystemStructure.xml``, the
format libcosim reads): ``<StartTime>``, ``<BaseStepSize>``, ``<Simulators>`` (name, FMU ``source``
relative to the file, optional ``stepSize``, ``<InitialValues>``) and ``<Connections>`` /
``<VariableConnection>`` (two ``<Variable simulator=... name=...>``; the output end is found from the
causalities). The same file drives both masters, so their results can be compared.

The same system can also be packaged as an SSP 1.0 archive (`write_ssp`: ``SystemStructure.ssd`` with the
components, their connectors, the connections and the parameter values, and the FMUs in ``resources/``;
the base step in the OSP annotation of ``<ssd:DefaultExperiment>`` that libcosim reads). `read_ssp` reads
it back into a `System`, so the fmpy master runs an .ssp exactly as it runs the OSP file.

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
           "System", "read_osp_system_structure", "write_osp_system_structure", "write_ssp", "read_ssp",
           "read_system", "SSD_NAMESPACES", "PARAMETER_SET", "FmpyMaster", "run_fmpy", "run_libcosim", "run_ecos", "NS"]

NS = 1_000_000_000  #: nanoseconds per second (libcosim's time unit)


# ------------------------------------------------------------------------------------------------------
# the ground-motion source component
#: units of a CSV record for the GroundMotionSource FMU when neither the file nor the ``units`` parameter
#: states them (the FMU's historical reading)
RECORD_DEFAULT_UNITS = "m/s2"
#: [1] allowed range of the GroundMotionSource parameter vertical_scale (the ensembles' ag_v_scale range)
VERTICAL_SCALE_MAX = 10.0


def load_record(path, units: Optional[str] = None, vertical: Optional[str] = None) -> Record:
    """Read the ground-motion record of the GroundMotionSource FMU with `rocking_model.records` (the reader
    of the CLI and the ensembles, with the same errors): a PEER ``.AT2`` file (units from its line 3, else
    g), a two-column ``.csv``/``.txt``/``.dat``/``.tsv`` file (time [s], acceleration; units from the header
    ``time [s], ag [cm/s2]`` or a ``# units: g`` comment, else ``units``, else m/s2; a third column is the
    vertical ag_v) or ``synthetic[:seed]``; ``vertical`` a second such file holding the vertical component.
    ``units`` that contradict the units the file states are an error. Returns a `Record` (ag in m/s2)."""
    return load_motion(str(path), units or None, default_units=RECORD_DEFAULT_UNITS, vertical=vertical or None)


def ground_motion_from_parameters(p: Mapping[str, Any]) -> GroundMotion:
    """The ground motion named by the GroundMotionSource parameters: ``motion`` 0 = one-sine pulse
    (``A`` [m/s2], ``omega_p`` [rad/s], ``t_start`` [s], built by
    `rocking_model.ground_motion.pulse_from_parameters` like the CLI's and the ensembles' pulses), 1 = the
    record ``record`` (a file or ``synthetic[:seed]``, read by `load_record` in ``units``; "" = as the file
    states, else m/s2); both multiplied by ``scale`` [1]. A record's vertical component ag_v (its third CSV
    column, or the file ``vertical``) is multiplied by ``vertical_scale`` [1] too (default 1); a motion
    without one has ag_v = 0. Raises ValueError naming the parameter and its allowed values."""
    motion = p.get("motion", 0)
    scale = check_real("scale", p.get("scale", 1.0))
    vertical_scale = check_real("vertical_scale", p.get("vertical_scale", 1.0), lo=-VERTICAL_SCALE_MAX,
                                hi=VERTICAL_SCALE_MAX)
    vertical = str(p.get("vertical", "") or "")
    units = str(p.get("units", "") or "")
    if units:
        unit_factor(units)          # a misspelt unit is an error whatever the motion
    if motion == 0:
        if vertical:
            raise ValueError(f"vertical = {vertical!r}: a vertical record needs motion = 1 (a record)")
        return pulse_from_parameters("sine", p["A"], p["omega_p"], p.get("t_start", 0.0), scale=scale)
    if motion == 1:
        record = str(p.get("record", ""))
        if not record:
            raise ValueError("record = '': motion = 1 needs a record file (.AT2, .csv) or synthetic[:seed]")
        rec = load_record(record, units, vertical).scaled(scale)
        if rec.vertical is not None and vertical_scale != 1.0:
            rec = rec.scaled_vertical(vertical_scale)
        return rec
    raise ValueError(f"motion = {motion!r} is not supported; allowed values: 0 (sine pulse), 1 (record)")


class MotionSource:
    """A ground motion as a stepwise component (``t``, ``advance(t_end)``, ``outputs()``): the outputs
    ``ag`` and ``ag_v`` at a communication point t are ag(t) and the vertical ag_v(t) (positive upward; 0
    for a motion without a vertical component), exactly as the standalone FMU would be driven by a table
    sampled at the communication points.

    Every value must be a finite number with |ag|, |ag_v| <= AG_MAX (1000 m/s2): a motion whose known peak
    exceeds it is refused here, and a step whose end value is out of range is refused by `advance`
    (ValueError naming ag or ag_v, the time kept). `get_state` / `set_state` save and load the time as plain
    data."""

    def __init__(self, motion: GroundMotion, t0: float = 0.0):
        from .ground_motion import checked_motion

        self.motion = checked_motion(motion)
        self.t = check_real("t0", t0)
        self._ag, self._ag_v = self._value(self.t)

    def _value(self, t: float) -> tuple:
        # self.motion is a checked motion (`checked_motion`, both components): its values are finite and within
        # AG_MAX, or it raises ValueError naming ag (or ag_v) and t
        vertical = self.motion.vertical
        return float(self.motion(t)), (0.0 if vertical is None else float(vertical(t)))

    def advance(self, t_end: float) -> None:
        """Move to ``t_end`` [s]; the outputs become ag(t_end) and ag_v(t_end). Raises ValueError (state kept)
        for a t_end before the current time or not finite, or a value out of range."""
        t_end = check_real("t_end", t_end)
        if t_end < self.t:
            raise ValueError(f"t_end = {t_end!r} is before the current time {self.t!r}")
        value = self._value(t_end)
        self.t, (self._ag, self._ag_v) = t_end, value

    def outputs(self) -> dict:
        return {"ag": self._ag, "ag_v": self._ag_v}

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
        self.t, (self._ag, self._ag_v) = t, value


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


# ------------------------------------------------------------------------------------------------------
# SSP 1.0 (System Structure and Parameterization): SystemStructure.ssd + resources/*.fmu in a zip archive
#: the SSP 1.0 namespaces (prefix -> URI) of the .ssd, and the OSP annotation namespace of the step size
SSD_NAMESPACES = {
    "ssd": "http://ssp-standard.org/SSP1/SystemStructureDescription",
    "ssc": "http://ssp-standard.org/SSP1/SystemStructureCommon",
    "ssv": "http://ssp-standard.org/SSP1/SystemStructureParameterValues",
    "osp": "http://opensimulationplatform.com/SSP/OSPAnnotations",
}
#: the annotation type that carries the fixed-step algorithm (base step) and the step size hints; SSP 1.0
#: itself has no step size (libcosim and Ecos read this annotation)
OSP_ANNOTATION = "com.opensimulationplatform"
#: the name of every component's parameter set: one name for the whole system, so that an importer that
#: applies parameter sets by name (Ecos: ``init(parameter_set="initialValues")``) applies them all at once
PARAMETER_SET = "initialValues"
#: the MIME type SSP 1.0 gives an FMU component
FMU_MIME = "application/x-fmu-sharedlibrary"
_FMI_TYPES = ("Real", "Integer", "Boolean", "String", "Enumeration")


def _q(prefix: str, tag: str) -> str:
    return f"{{{SSD_NAMESPACES[prefix]}}}{tag}"


def _typed_value(parent, prefix: str, value) -> None:
    """Append <prefix:Real|Integer|Boolean|String value=...> for a Python value (the OSP file's typing)."""
    if isinstance(value, bool):
        ElementTree.SubElement(parent, _q(prefix, "Boolean"), {"value": "true" if value else "false"})
    elif isinstance(value, (int, np.integer)):
        ElementTree.SubElement(parent, _q(prefix, "Integer"), {"value": str(int(value))})
    elif isinstance(value, (float, np.floating)):
        ElementTree.SubElement(parent, _q(prefix, "Real"), {"value": repr(float(value))})
    else:
        ElementTree.SubElement(parent, _q(prefix, "String"), {"value": str(value)})


def _parse_typed(node, where: str):
    kind, text = _strip(node.tag), node.get("value")
    if text is None:
        raise ValueError(f"{where}: <{kind}> has no value attribute")
    try:
        return {"Real": float, "Integer": int, "String": str,
                "Boolean": lambda s: {"true": True, "1": True, "false": False, "0": False}[s.strip().lower()]
                }[kind](text)
    except KeyError:
        raise ValueError(f"{where}: unsupported value type <{kind}> (Real, Integer, Boolean, String)") from None
    except ValueError:
        raise ValueError(f"{where}: {text!r} is not a valid {kind}") from None


def write_ssp(system: System, path, name: str = "System", stop_time: Optional[float] = None) -> Path:
    """Write ``system`` as an SSP 1.0 archive at ``path`` (.ssp) and return the path.

    The archive holds ``SystemStructure.ssd`` and each distinct FMU once as ``resources/<file name>``. Each
    component lists its inputs and outputs as connectors (kind and type from its modelDescription) and its
    start values as an inline parameter set (``<ssd:ParameterBinding>``, the values typed as in the OSP
    file, named `PARAMETER_SET`). Connections go from an output (start) to an input (end).
    ``<ssd:DefaultExperiment>`` has the start time (and ``stop_time`` if given) and, in an OSP annotation,
    the base step; a component step size is an OSP ``StepSizeHint`` annotation of the component."""
    import zipfile

    from fmpy import read_model_description

    path = Path(path)
    for prefix, uri in SSD_NAMESPACES.items():
        ElementTree.register_namespace(prefix, uri)
    root = ElementTree.Element(_q("ssd", "SystemStructureDescription"), {"version": "1.0", "name": name})
    sys_el = ElementTree.SubElement(root, _q("ssd", "System"), {"name": name})
    elements = ElementTree.SubElement(sys_el, _q("ssd", "Elements"))
    resources: Dict[str, Path] = {}
    for comp in system.components:
        fmu = Path(comp.fmu).resolve()
        entry = f"resources/{fmu.name}"
        if resources.setdefault(entry, fmu) != fmu:
            raise ValueError(f"component {comp.name}: two different FMUs named {fmu.name}")
        md = read_model_description(str(fmu))
        el = ElementTree.SubElement(elements, _q("ssd", "Component"),
                                    {"name": comp.name, "type": FMU_MIME, "source": entry})
        connectors = ElementTree.SubElement(el, _q("ssd", "Connectors"))
        for v in md.modelVariables:
            if v.causality in ("input", "output") and v.type in _FMI_TYPES:
                con = ElementTree.SubElement(connectors, _q("ssd", "Connector"),
                                             {"name": v.name, "kind": v.causality})
                # no unit attribute: SSP 1.0 units must then be declared in <ssd:Units> (the FMU has them)
                ElementTree.SubElement(con, _q("ssc", v.type))
        if comp.start_values:
            bindings = ElementTree.SubElement(el, _q("ssd", "ParameterBindings"))
            values = ElementTree.SubElement(ElementTree.SubElement(bindings, _q("ssd", "ParameterBinding")),
                                            _q("ssd", "ParameterValues"))
            pset = ElementTree.SubElement(values, _q("ssv", "ParameterSet"),
                                          {"version": "1.0", "name": PARAMETER_SET})
            params = ElementTree.SubElement(pset, _q("ssv", "Parameters"))
            for var, value in comp.start_values.items():
                _typed_value(ElementTree.SubElement(params, _q("ssv", "Parameter"), {"name": var}), "ssv", value)
        if comp.step_size is not None:
            ann = ElementTree.SubElement(ElementTree.SubElement(el, _q("ssd", "Annotations")),
                                         _q("ssc", "Annotation"), {"type": OSP_ANNOTATION})
            ElementTree.SubElement(ann, _q("osp", "StepSizeHint"), {"value": repr(float(comp.step_size))})
    if system.connections:
        conns = ElementTree.SubElement(sys_el, _q("ssd", "Connections"))
        for con in system.connections:
            ElementTree.SubElement(conns, _q("ssd", "Connection"),
                                   {"startElement": con.source[0], "startConnector": con.source[1],
                                    "endElement": con.target[0], "endConnector": con.target[1]})
    exp = {"startTime": repr(float(system.start_time))}
    if stop_time is not None:
        exp["stopTime"] = repr(float(stop_time))
    exp_el = ElementTree.SubElement(root, _q("ssd", "DefaultExperiment"), exp)
    ann = ElementTree.SubElement(ElementTree.SubElement(exp_el, _q("ssd", "Annotations")),
                                 _q("ssc", "Annotation"), {"type": OSP_ANNOTATION})
    ElementTree.SubElement(ElementTree.SubElement(ann, _q("osp", "Algorithm")), _q("osp", "FixedStepAlgorithm"),
                           {"baseStepSize": repr(float(system.step_size))})
    ElementTree.indent(root)
    ssd = ElementTree.tostring(root, encoding="utf-8", xml_declaration=True)
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as z:
        z.writestr("SystemStructure.ssd", ssd)
        for entry, fmu in resources.items():
            z.write(fmu, entry, compress_type=zipfile.ZIP_STORED)  # FMUs are zips already
    return path


def read_ssp(path, unzipdir=None) -> System:
    """Read an SSP 1.0 archive written by `write_ssp` (or any .ssp of FMU components with inline parameter
    values and connections between components) into a `System`.

    The FMUs are extracted to ``unzipdir`` (default: a temporary folder removed when the System is garbage
    collected). The base step comes from the OSP ``FixedStepAlgorithm`` annotation of
    ``<ssd:DefaultExperiment>``. Raises ValueError naming what is missing or not supported."""
    import shutil
    import weakref
    import zipfile

    path = Path(path)
    with zipfile.ZipFile(path) as z:
        names = set(z.namelist())
        if "SystemStructure.ssd" not in names:
            raise ValueError(f"{path}: no SystemStructure.ssd in the archive")
        root = ElementTree.fromstring(z.read("SystemStructure.ssd"))
        if root.tag != _q("ssd", "SystemStructureDescription"):
            raise ValueError(f"{path}: root element is {root.tag!r}, expected ssd:SystemStructureDescription")
        sys_el = root.find("ssd:System", SSD_NAMESPACES)
        if sys_el is None:
            raise ValueError(f"{path}: <ssd:System> is required")
        step = root.find("ssd:DefaultExperiment/ssd:Annotations/ssc:Annotation/osp:Algorithm/"
                         "osp:FixedStepAlgorithm", SSD_NAMESPACES)
        if step is None or step.get("baseStepSize") is None:
            raise ValueError(f"{path}: no base step (<osp:FixedStepAlgorithm baseStepSize=...> in the "
                             f"{OSP_ANNOTATION} annotation of <ssd:DefaultExperiment>)")
        exp = root.find("ssd:DefaultExperiment", SSD_NAMESPACES)
        own_dir = unzipdir is None
        out = Path(tempfile.mkdtemp(prefix="rocking_ssp_") if own_dir else unzipdir)
        components, kinds = [], {}
        for el in sys_el.findall("ssd:Elements/*", SSD_NAMESPACES):
            cname = el.get("name")
            if el.tag != _q("ssd", "Component") or el.get("type", FMU_MIME) != FMU_MIME:
                raise ValueError(f"{path}: element {cname!r}: only FMU components are supported")
            source = el.get("source", "")
            if source not in names:
                raise ValueError(f"{path}: component {cname!r}: source {source!r} is not in the archive")
            fmu = out / source
            if not fmu.is_file():
                fmu.parent.mkdir(parents=True, exist_ok=True)
                fmu.write_bytes(z.read(source))
            values: Dict[str, Any] = {}
            for binding in el.findall("ssd:ParameterBindings/ssd:ParameterBinding", SSD_NAMESPACES):
                if binding.get("source"):
                    raise ValueError(f"{path}: component {cname!r}: external parameter files are not supported")
                for p in binding.findall("ssd:ParameterValues/ssv:ParameterSet/ssv:Parameters/ssv:Parameter",
                                         SSD_NAMESPACES):
                    (typed,) = list(p)
                    values[p.get("name")] = _parse_typed(typed, f"{path}: {cname}.{p.get('name')}")
            hint = el.find("ssd:Annotations/ssc:Annotation/osp:StepSizeHint", SSD_NAMESPACES)
            components.append(Component(cname, fmu, None if hint is None else float(hint.get("value")), values))
            for con in el.findall("ssd:Connectors/ssd:Connector", SSD_NAMESPACES):
                kinds[(cname, con.get("name"))] = con.get("kind")
    connections = []
    for con in sys_el.findall("ssd:Connections/ssd:Connection", SSD_NAMESPACES):
        if con.get("startElement") is None or con.get("endElement") is None:
            raise ValueError(f"{path}: connections to the system's own connectors are not supported")
        a = (con.get("startElement"), con.get("startConnector"))
        b = (con.get("endElement"), con.get("endConnector"))
        for end, kind in ((a, "output"), (b, "input")):
            if kinds.get(end) != kind:
                raise ValueError(f"{path}: connection {a[0]}.{a[1]} -> {b[0]}.{b[1]}: {end[0]}.{end[1]} "
                                 f"is not an {kind} connector")
        connections.append(Connection(a, b))
    system = System(components, connections, float(step.get("baseStepSize")),
                    float(exp.get("startTime", 0.0)) if exp is not None else 0.0)
    if own_dir:
        weakref.finalize(system, shutil.rmtree, str(out), True)
    return system


def read_system(path) -> System:
    """A `System` from an OspSystemStructure.xml or an SSP archive (.ssp)."""
    return read_ssp(path) if str(path).lower().endswith(".ssp") else read_osp_system_structure(path)


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
    """Run a `System`, the system of an OspSystemStructure.xml or an SSP archive (.ssp) with `FmpyMaster`
    (keyword arguments as `FmpyMaster.run`)."""
    if not isinstance(system, System):
        system = read_system(system)
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
    """Run a `System`, the system of an OspSystemStructure.xml or an SSP archive (.ssp, read by libcosim's
    own SSP loader) in libcosim, one base step at a time, and return the same structured array as
    `FmpyMaster.run` without its first row (libcosim's observers have values only from the first step on:
    the rows are t0 + h, t0 + 2h, ...). ``inputs``
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
    if osp_file.suffix.lower() == ".ssp":
        # libcosim reads the archive itself (its SSP loader: components, parameter sets, connections and
        # the OSP base-step annotation); the System is read here for the initialization check and the steps
        system = read_ssp(osp_file)
        check_initialization(system, start_values)
        execution = CosimExecution.from_ssp_file(str(osp_file))
    else:
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


# ------------------------------------------------------------------------------------------------------
# Ecos (a third importer: C++, FMI 1/2, SSP 1.0) through ecospy
def run_ecos(system, stop_time: float, outputs: Sequence[str], inputs: Optional[Mapping[str, Callable]] = None,
             proxy: bool = False) -> np.ndarray:
    """Run a `System`, the system of an OspSystemStructure.xml or an SSP archive (.ssp, read by Ecos' own SSP
    loader) in Ecos (``pip install rocking-model[ecos]``; its binary needs libtbb12), one base step at a
    time, and return the same structured array as `run_libcosim` (rows t0 + h, t0 + 2h, ...).

    A `System` is given to Ecos as a structure: its components (``proxy``: each in a process of its own
    through Ecos' proxyfmu), its connections and the start values as the parameter set `PARAMETER_SET`;
    an .ssp archive carries them itself (`write_ssp`). ``inputs`` ("component.variable" -> f(t)) are set
    before each step. Ecos counts time in doubles (t += h), so its communication points can differ from
    the integer-nanosecond points of the other masters in the last bits; every component is initialized
    once through fmpy first (`check_initialization`): invalid parameters raise ValueError. The
    connections are Real ones (those of the rocking systems)."""
    from ecospy import EcosSimulation, EcosSimulationStructure

    ssp = Path(system).resolve() if not isinstance(system, System) and str(system).lower().endswith(".ssp") \
        else None
    if not isinstance(system, System):
        system = read_system(system)
    check_initialization(system)
    t0 = float(system.start_time)
    n_steps = int(round((_ticks(stop_time) - _ticks(system.start_time)) / _ticks(system.step_size)))

    from fmpy import read_model_description

    types = {}
    for c in system.components:
        for v in read_model_description(str(c.fmu)).modelVariables:
            types[f"{c.name}.{v.name}"] = v.type

    def ident(key):
        comp, var = key.split(".", 1)
        return f"{comp}::{var}"

    def getter(sim, key):
        if key not in types:
            raise KeyError(f"Ecos: no variable {key!r}")
        return {"Real": sim.get_real, "Integer": sim.get_integer, "Enumeration": sim.get_integer,
                "Boolean": sim.get_bool}[types[key]]

    def build(sim):
        rows = []
        sim.init(t0, PARAMETER_SET)
        for n in range(n_steps):
            t = (_ticks(system.start_time) + n * _ticks(system.step_size)) / NS  # the other masters' t_n
            for key, f in (inputs or {}).items():
                sim.set_real(ident(key), float(f(t)))
            sim.step()
            rows.append([sim.get_time()] + [float(getter(sim, k)(ident(k))) for k in outputs])
        sim.terminate()
        return rows

    if ssp is not None:
        with EcosSimulation(ssp_path=str(ssp), step_size=system.step_size) as sim:
            rows = build(sim)
    else:
        structure = EcosSimulationStructure()
        for c in system.components:
            uri = str(Path(c.fmu).resolve())
            structure.add_model(c.name, f"proxyfmu://localhost?file={uri}" if proxy else uri,
                                c.step_size)
        values = {f"{c.name}::{k}": v for c in system.components for k, v in c.start_values.items()}
        if values:
            structure.add_parameter_set(PARAMETER_SET, values)
        for con in system.connections:
            structure.make_real_connection(f"{con.source[0]}::{con.source[1]}",
                                           f"{con.target[0]}::{con.target[1]}")
        with EcosSimulation(structure=structure, step_size=system.step_size) as sim:
            rows = build(sim)
    dtype = [("time", np.float64)] + [(k, np.float64) for k in outputs]
    return np.array([tuple(r) for r in rows], dtype=dtype)


def write_csv(path, result: np.ndarray) -> None:
    """Write a structured result array as CSV (header = column names)."""
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(result.dtype.names)
        for row in result:
            w.writerow([repr(float(x)) for x in row])
