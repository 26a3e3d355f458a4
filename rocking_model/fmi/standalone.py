"""Self-contained FMUs: what the C FMI layer over the compiled engine needs from the Python
declarations, generated at build time from the same declarations the pythonfmu FMUs use (one source).

From the FMU's slave class (e.g. `rocking_model.fmi.fmus.RigidRockingBlock`, a `ModelSlave`):

- `model_description`: the modelDescription.xml of the standalone FMU, which is the pythonfmu FMU's own XML
  (`RockingSlave.to_xml`: the same variables, value references, units, ranges, start values, descriptions)
  with the attributes of a native FMU: needsExecutionTool = false, the binary's GUID, the source files;
- `vars_header`: the C table of the variables (``rk_fmu_vars.h``: name, type, causality, variability, start,
  min/max and the role of each in the engine: model parameter i, initial value i, solver option, input,
  output i, ...), in value-reference order;
- `build_description`: sources/buildDescription.xml (FMI 3.0 / 2.0.4 style);
- `documentation`: documentation/index.html, the table of the variables.

Only this module and the C sources in ``rocking_model/fmi/binary/standalone`` know of each other; the C code reads nothing
at run time (no resources, no Python)."""
from __future__ import annotations

import hashlib
import html
import math
import uuid
from typing import List, Tuple
from xml.etree.ElementTree import Element, SubElement, tostring

#: C role codes of the variables (binary/standalone/fmi2_engine.c reads them)
ROLES = ("RK_ROLE_PARAM", "RK_ROLE_INITIAL", "RK_ROLE_SCHEME", "RK_ROLE_DT_MAX", "RK_ROLE_TOLERANCE",
         "RK_ROLE_MAX_STEPS", "RK_ROLE_INPUT", "RK_ROLE_OUTPUT", "RK_ROLE_CONTACT", "RK_ROLE_IMPACTS",
         "RK_ROLE_OVERTURNED", "RK_ROLE_FRICTION_DEMAND", "RK_ROLE_PAINLEVE")
_SPECIAL = {"scheme": "RK_ROLE_SCHEME", "dt_max": "RK_ROLE_DT_MAX", "tolerance": "RK_ROLE_TOLERANCE",
            "max_steps": "RK_ROLE_MAX_STEPS", "contact": "RK_ROLE_CONTACT", "impacts": "RK_ROLE_IMPACTS",
            "overturned": "RK_ROLE_OVERTURNED", "friction_demand": "RK_ROLE_FRICTION_DEMAND",
            "painleve": "RK_ROLE_PAINLEVE"}
_TYPES = {"Real": "RK_REAL", "Integer": "RK_INTEGER", "Boolean": "RK_BOOLEAN", "String": "RK_STRING"}
_CAUS = {"parameter": "RK_PARAMETER", "input": "RK_INPUT", "output": "RK_OUTPUT"}

#: the C sources of a standalone FMU besides the engine's (rocking_model/engine/src): the FMI layer, with the
#: FMI plumbing (fmi2_common) and the resource-URI check it shares with the pythonfmu FMUs' binary (paths
#: relative to rocking_model/fmi/binary, package data)
FMI_SOURCES = ("standalone/fmi2_engine.c", "fmi2_common.c", "fmi2_common.h", "uri.c", "uri.h")


def slave_instance(slave_class):
    """An instance of the FMU script's slave class, as pythonfmu's builder makes one to write the XML."""
    return slave_class(instance_name="standalone-build", resources=".")


def _guid(slave, engine_sources: bytes) -> str:
    """A GUID fixed by the variable table, the descriptions and the engine sources (the same build twice gives
    the same GUID; a change of any of them a new one)."""
    h = hashlib.sha256()
    h.update(type(slave).__name__.encode() + b"\0")
    h.update(repr([(vr, v.name, _spec(slave, v.name)) for vr, v in slave.vars.items()]).encode())
    h.update(engine_sources)
    return str(uuid.UUID(bytes=h.digest()[:16]))


def _spec(slave, name):
    return slave._specs[name]


def model_description(slave, sources: List[str], engine_sources: bytes = b"") -> Tuple[bytes, str]:
    """(modelDescription.xml, GUID) of the standalone FMU of ``slave``: the pythonfmu FMU's XML with
    needsExecutionTool = false, canBeInstantiatedOnlyOncePerProcess = false, this binary's GUID and the
    source files (FMI 2.0 <SourceFiles>, for importers that compile)."""
    root = slave.to_xml()
    guid = _guid(slave, engine_sources)
    root.set("guid", guid)
    root.attrib.pop("generationDateAndTime", None)     # a reproducible build: the same bytes each time
    cosim = root.find("CoSimulation")
    cosim.set("needsExecutionTool", "false")
    cosim.set("canBeInstantiatedOnlyOncePerProcess", "false")
    cosim.set("canNotUseMemoryManagementFunctions", "true")
    files = SubElement(cosim, "SourceFiles")
    for name in sources:
        SubElement(files, "File", {"name": name})
    return b'<?xml version="1.0" encoding="UTF-8"?>\n' + tostring(root, encoding="utf-8"), guid


def _c_double(x) -> str:
    x = float(x)
    if math.isnan(x):
        return "NAN"
    if math.isinf(x):
        return "INFINITY" if x > 0 else "(-INFINITY)"
    return repr(x)


def _c_string(text: str) -> str:
    out = text.replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n")
    return '"' + out.encode("ascii", "backslashreplace").decode().replace("\\u", "\\u") + '"'


def _scheme_allowed() -> str:
    """The "allowed values: ..." text of the Simulator's check of the scheme, as its ValueError says it."""
    from ..simulation import SCHEMES
    from ..validation import check_choice

    try:
        check_choice("scheme", 2**31 - 1, SCHEMES)         # no scheme has this code
    except ValueError as exc:
        text = str(exc)
        marker = "allowed values: "
        if marker in text:
            return text[text.index(marker) + len(marker):]
    raise ValueError("cannot read the allowed schemes from the Simulator's check")


def vars_header(slave, guid: str) -> str:
    """The C header rk_fmu_vars.h of ``slave``'s FMU (see the module docstring)."""
    cls = slave.model_class
    params = list(cls.parameters())
    initial = list(cls.INITIAL)
    # the inputs in the engine's order: ag, then ag_v (the vertical ground acceleration) where declared
    inputs = [s.name for s in slave.variables if s.causality == "input"]
    if inputs not in (["ag"], ["ag", "ag_v"]):
        raise ValueError(f"{type(slave).__name__}: the C engine FMU takes the inputs ag and (optionally) ag_v, "
                         f"in this order; declared: {inputs}")
    p_index = {p.name: i for i, p in enumerate(params)}
    i_index = {p.name: i for i, p in enumerate(initial)}
    o_index = {p.name: i for i, p in enumerate(cls.OUTPUTS)}
    rows = []
    for vr, var in slave.vars.items():
        spec = slave._specs[var.name]
        if spec.causality == "parameter" and spec.name in p_index:
            role, index = "RK_ROLE_PARAM", p_index[spec.name]
        elif spec.causality == "parameter" and spec.name in i_index:
            role, index = "RK_ROLE_INITIAL", i_index[spec.name]
        elif spec.name in _SPECIAL:
            role, index = _SPECIAL[spec.name], 0
        elif spec.causality == "input":
            role, index = "RK_ROLE_INPUT", inputs.index(spec.name)
        elif spec.causality == "output" and spec.name in o_index:
            role, index = "RK_ROLE_OUTPUT", o_index[spec.name]
        else:
            raise ValueError(f"{type(slave).__name__}: variable {spec.name!r} has no role in the C engine FMU")
        if vr != var.value_reference:
            raise ValueError("value references are not the registration order")
        rows.append("    {%s, %s, %s, %d, %s, %d, %s, %d, %s, %d, %s}," % (
            _c_string(spec.name), _TYPES[spec.type], _CAUS[spec.causality],
            1 if spec.resolved_variability == "fixed" else 0, role, index, _c_double(spec.default),
            spec.min is not None, _c_double(spec.min if spec.min is not None else 0.0),
            spec.max is not None, _c_double(spec.max if spec.max is not None else 0.0)))
    from ..validation import AG_MAX
    from .slave import INPUT_RATE_MAX
    from .variables import MAX_STEPS_PARAMETER

    lines = [
        f"/* rk_fmu_vars.h -- the variables of the FMU {type(slave).__name__}, GENERATED by",
        " * rocking_model/fmi/standalone.py from the declarations the pythonfmu FMU uses (do not edit). */",
        "#ifndef RK_FMU_VARS_H", "#define RK_FMU_VARS_H", "#include <math.h>", "",
        f"#define RK_FMU_NAME {_c_string(type(slave).__name__)}",
        f"#define RK_FMU_GUID {_c_string(guid)}",
        f"#define RK_FMU_MODEL_KIND {_c_string(cls.__name__)}",
        f"#define RK_FMU_N_VARS {len(rows)}",
        f"#define RK_FMU_N_PARAMS {len(params)}",
        f"#define RK_FMU_N_INITIAL {len(initial)}",
        f"#define RK_FMU_N_OUTPUTS {len(cls.OUTPUTS)}",
        "/* the Real inputs: index 0 ag (horizontal), index 1 ag_v (vertical) where declared */",
        f"#define RK_FMU_N_INPUTS {len(inputs)}",
        f"#define RK_FMU_FREEZE {1 if slave.freeze_output == 'overturned' else 0}",
        f"#define RK_FMU_TIME_TOLERANCE {_c_double(slave.time_tolerance)}",
        f"#define RK_FMU_INPUT_RATE_MAX {_c_double(INPUT_RATE_MAX)}",
        f"#define RK_FMU_AG_MAX {_c_double(AG_MAX)}",
        f"#define RK_FMU_MAX_STEPS_LIMIT {int(MAX_STEPS_PARAMETER.max)}",
        "/* the allowed values of the scheme as the Python's check names them (its message) */",
        f"#define RK_FMU_SCHEME_ALLOWED {_c_string(_scheme_allowed())}",
        "/* the declared defaults of every model parameter and initial value (those without an FMU variable",
        " * keep them), in the model's declared order (rk_engine_create) */",
        "static const double RK_FMU_PARAM_DEFAULTS[] = {"
        + ", ".join(_c_double(p.check(p.default) if p.items else p.default) for p in params) + "};",
        "static const double RK_FMU_INITIAL_DEFAULTS[] = {"
        + (", ".join(_c_double(p.default) for p in initial) or "0.0") + "};",
        "static const char *const RK_FMU_OUTPUT_NAMES[] = {"
        + ", ".join(_c_string(p.name) for p in cls.OUTPUTS) + "};",
        "", "/* name, type, causality, fixed, role, index, start, has_min, min, has_max, max; index = value "
        "reference */",
        "static const rk_fmu_var RK_FMU_VARS[RK_FMU_N_VARS] = {", *rows, "};", "#endif", ""]
    return "\n".join(lines)


def build_description(name: str, sources: List[str]) -> bytes:
    """sources/buildDescription.xml (FMI 3.0, which FMI 2.0.4 importers read in preference to <SourceFiles>):
    one build configuration compiling every source with the include folder sources/, linked with the C math
    library (``<Library name="m" external="true">``: not in the FMU, the system's; on Windows it is part of the
    C run-time). No preprocessor definition and no compiler option is needed: the sources carry their version
    (rk_version.h) and pin their floating-point contract (rk_fp.h) themselves."""
    root = Element("fmiBuildDescription", {"fmiVersion": "3.0"})
    config = SubElement(root, "BuildConfiguration", {"modelIdentifier": name,
                                                    "description": "C99 + libm; no other dependency"})
    files = SubElement(config, "SourceFileSet", {"language": "C99"})
    for src in sources:
        SubElement(files, "SourceFile", {"name": src})
    SubElement(files, "IncludeDirectory", {"name": "."})
    SubElement(config, "Library", {"name": "m", "external": "true",
                                   "description": "the C math library (libm: -lm; part of the C run-time on "
                                                  "Windows)"})
    return b'<?xml version="1.0" encoding="UTF-8"?>\n' + tostring(root, encoding="utf-8")


def documentation(slave) -> str:
    """documentation/index.html: the model's description and its variables (from the declarations)."""
    name = type(slave).__name__
    esc = html.escape
    rows = []
    for vr, var in slave.vars.items():
        s = slave._specs[var.name]
        rng = "" if s.min is None and s.max is None else s.range_text()
        start = "" if s.causality == "output" else esc(str(s.default))
        rows.append(f"<tr><td>{vr}</td><td><code>{esc(s.name)}</code></td><td>{s.causality}</td>"
                    f"<td>{s.resolved_variability}</td><td>{s.type}</td><td>{esc(s.unit or '')}</td>"
                    f"<td>{start}</td><td>{esc(rng)}</td><td>{esc(s.description)}</td></tr>")
    return (f"<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>{esc(name)}</title>"
            f"</head>\n<body>\n<h1>{esc(name)}</h1>\n<p>{esc(slave.description or '')}</p>\n"
            "<p>Self-contained FMI 2.0 co-simulation FMU of rocking_model: the compiled C engine, no Python "
            "needed (C99 + libm). The C sources are in <code>sources/</code> "
            "(<code>sources/buildDescription.xml</code>).</p>\n"
            "<table border=\"1\">\n<tr><th>value reference</th><th>name</th><th>causality</th>"
            "<th>variability</th><th>type</th><th>unit</th><th>start</th><th>range</th><th>description</th>"
            "</tr>\n" + "\n".join(rows) + "\n</table>\n</body></html>\n")


# ---------------------------------------------------------------------------------------------- FMU states
#: the slave part of a standalone FMU's serialized state (binary/standalone/fmi2_engine.c, encode_slave);
#: version 2: one (has_rate, rate, rate_t) per Real input (version 1, a single input, is refused: its GUID is
#: that of another build anyway)
STATE_PAYLOAD_MAGIC = b"rocking engine FMU state v2\n"
#: rk_common.h: RK_MAX_DOF, RK_MAX_Y = 2 RK_MAX_DOF (the fixed array sizes of the engine's plain state)
RK_MAX_DOF = 8
RK_MAX_Y = 2 * RK_MAX_DOF


def decode_state_payload(data: bytes) -> dict:
    """The fields of a standalone FMU's state payload (the bytes after the binary's 46-byte header, what
    fmi2_cs.c's header precedes too): guid, values (value-reference order), the slave's flags and times, the
    input rates (``rates``: one {"has_rate", "rate", "rate_t"} per Real input, ag first; ``has_rate``, ``rate``
    and ``rate_t`` repeat the first), the error text, and the engine's plain-data state (None before
    initialization). ValueError naming what is wrong."""
    import struct

    import zlib

    data = bytes(data)
    m, g = len(STATE_PAYLOAD_MAGIC), 36
    if len(data) < 4 or zlib.crc32(data[:-4]) != struct.unpack("<I", data[-4:])[0]:
        raise ValueError("the standalone FMU state is corrupted (CRC-32 mismatch of its payload)")
    data = data[:-4]
    if not data.startswith(STATE_PAYLOAD_MAGIC) or len(data) < m + g + 4:
        raise ValueError("not a standalone rocking_model FMU state (bad header)")
    guid = data[m:m + g].decode("ascii", "replace")
    off = m + g
    (n_vars,) = struct.unpack_from("<i", data, off)
    off += 4
    if not 0 <= n_vars <= 10_000 or len(data) < off + 8 * n_vars + 16 + 16 + 4:
        raise ValueError("the standalone FMU state is truncated")
    values = list(struct.unpack_from(f"<{n_vars}d", data, off))
    off += 8 * n_vars
    flags = struct.unpack_from("<4i", data, off)       # initialized, terminated, frozen, has_error
    off += 16
    t, t0 = struct.unpack_from("<2d", data, off)
    off += 16
    (n_inputs,) = struct.unpack_from("<i", data, off)
    off += 4
    if not 0 <= n_inputs <= 16 or len(data) < off + 20 * n_inputs + 4:
        raise ValueError("the standalone FMU state is truncated")
    rates = []
    for _ in range(n_inputs):
        (has_rate,) = struct.unpack_from("<i", data, off)
        rate, rate_t = struct.unpack_from("<2d", data, off + 4)
        rates.append({"has_rate": has_rate, "rate": rate, "rate_t": rate_t})
        off += 20
    (n_err,) = struct.unpack_from("<i", data, off)
    off += 4
    if not 0 <= n_err <= len(data) - off - 4:          # the error text, then has_engine
        raise ValueError("the standalone FMU state is truncated")
    error = data[off:off + n_err].decode("utf-8", "replace")
    off += n_err
    (has_engine,) = struct.unpack_from("<i", data, off)
    off += 4
    engine = None
    if has_engine:
        fmt = f"<dii{RK_MAX_Y}d{RK_MAX_DOF}d{RK_MAX_DOF}dIqiqdddq"
        if len(data) - off != struct.calcsize(fmt):
            raise ValueError("the standalone FMU state's engine state has the wrong length")
        f = struct.unpack_from(fmt, data, off)
        y = f[3:3 + RK_MAX_Y]
        q = f[3 + RK_MAX_Y:3 + RK_MAX_Y + RK_MAX_DOF]
        v = f[3 + RK_MAX_Y + RK_MAX_DOF:3 + RK_MAX_Y + 2 * RK_MAX_DOF]
        rest = f[3 + RK_MAX_Y + 2 * RK_MAX_DOF:]
        engine = {"t": f[0], "mode": f[1], "y": list(y[:f[2]]), "q": list(q), "v": list(v),
                  **dict(zip(("closed", "impacts", "overturned", "n_steps", "h", "shift", "friction_demand",
                              "painleve"), rest))}
    elif len(data) != off:
        raise ValueError("the standalone FMU state has bytes after its end")
    keys = ("initialized", "terminated", "frozen", "has_error")
    first = rates[0] if rates else {"has_rate": 0, "rate": 0.0, "rate_t": 0.0}
    return {"guid": guid, "values": values, **dict(zip(keys, flags)), "t": t, "t0": t0, "rates": rates,
            **first, "error": error if flags[3] else None, "engine": engine}
