"""Fault-injection worker of the conformance and fault suite (tests/test_fault_suite.py).

Every case drives the FMUs through fmpy's low-level ``fmpy.fmi2.FMU2Slave`` (every FMI 2.0 co-simulation
function) in a process of its own, because a case may crash the process or hang. A case is a small function (or a row of a table fed to a shared function) that records,
as it goes:

* every FMI call with its status and duration (``calls``),
* every message the FMU sends to the logger callback, with instance, status and category (``messages``;
  through fmpy's native logger proxy, which formats the message like any C importer does),
* named checks (``checks``): the status of a call against FMI 2.0 (kind "status"), the logged message naming the variable or the call (kind "message"), the state after a
  refused call being bit-identical to before (kind "state": all outputs and parameters as exact floats,
  the bytes of fmi2SerializeFMUstate, and the outputs of further identical steps next to a control
  instance that never saw the refused call),
* figures (``figures``): times, sizes, memory.

The record goes to a JSON file; tests/test_fault_suite.py asserts on it. Run one case by hand::

    python tests/fault_harness.py --list
    python tests/fault_harness.py --case <id> --config <fmus.json> --out rec.json

``--serve`` is the fork server the suite uses: it imports fmpy and numpy once and forks one child process
per case (a crash or a hang of the child is seen by the server through waitpid and a timeout and reported
as the case's outcome; the server itself runs no FMU code).
"""
from __future__ import annotations

import argparse
import ctypes
import hashlib
import json
import math
import os
import pickle
import random
import re
import shutil
import signal
import struct
import sys
import time
import traceback
import zlib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Dict, List, Optional, Sequence

OK, WARNING, DISCARD, ERROR, FATAL = 0, 1, 2, 3, 4
STATUS_NAMES = {OK: "fmi2OK", WARNING: "fmi2Warning", DISCARD: "fmi2Discard", ERROR: "fmi2Error",
                FATAL: "fmi2Fatal", -1: "exception"}

RIGID, FLEX, GMS, STOREY = ("RigidRockingBlock", "FlexibleRockingOscillator", "GroundMotionSource",
                            "LinearBuildingStorey")
PT = "PostTensionedRockingBlock"
FMUS = (RIGID, FLEX, PT, GMS, STOREY)
SHORT = {RIGID: "rigid", FLEX: "flex", PT: "pt", GMS: "ground", STOREY: "storey"}
#: the model FMUs (`rocking_model.models.MODELS`), all of them `ModelSlave`s on the compiled engine
ROCKING = (RIGID, FLEX, PT)
WITH_INPUT = (RIGID, FLEX, PT, STOREY)
#: the FMUs with the vertical ground acceleration input ag_v besides ag
WITH_VERTICAL = (RIGID, FLEX, PT)
#: The post-tensioned block (PT) shares the rigid block's slave class code (`ModelSlave`), its C FMI layer and
#: its state format: it runs the cases over every FMU, every input and every kind of FMU (statuses, messages,
#: state after refusals in a scene where the tendon acts, states, resets), its own parameters (P0, k_t: their
#: bad values and the edges of their ranges) and the resets; the cases that test the shared machinery once
#: more (the other slave classes' second initialization, batched setters, corrupted state bytes, input rates
#: in initialization mode, declared solver options, the 50 instances) stay on the rigid and flexible FMUs.

#: [m/s2] declared range of the input ag on every FMU that has it (modelDescription min/max)
AG_LIMIT = 1000.0
#: [s] communication step of the scenes
DT = 0.01
#: pulse amplitude [m/s2] and start values of the scene each FMU runs before a refused call: the rigid
#: block (b/h = 0.2, uplift at g tan(alpha) = 1.96 m/s2) and the flexible oscillator rock, the storey vibrates
SCENES = {RIGID: (3.0, {}), FLEX: (4.0, {}), STOREY: (2.0, {}), GMS: (None, {}),
          # b/h = 0.2 with a tendon (P0/m = 20 m/s2): uplift at 0.2 (9.81 + 20) = 5.96 m/s2; rocks, the tendon taut
          PT: (8.0, {"m": 1000.0, "P0": 2e4, "k_t": 2e6})}
#: steps of the scene before the refused call, and identical steps after it (subject versus control)
N_BEFORE, N_AFTER = 20, 5
#: a value reference no FMU of the package has
BAD_VR = 9999
#: the file the pickle gadgets try to create in the case's working directory
PWNED = "pwned"


#: the magic that starts the self-contained FMUs' own state payload (a binary record of the slave's fields
#: and the engine snapshot, rocking_model/fmi/binary/standalone/fmi2_engine.c), behind the same binary header; version 2
#: since the input ag_v (one rate per input), as rocking_model.fmi.standalone.STATE_PAYLOAD_MAGIC
STANDALONE_PAYLOAD_MAGIC = b"rocking engine FMU state v2\n"


def slave_bytes(data: bytes) -> bytes:
    """The slave's own state format inside a serialized FMU state (after the binary's header: the
    communication time, the FMI state fields and the CRC-32, written by rocking_model/fmi/binary/fmi2_common.c for both kinds
    of FMU)."""
    from rocking_model.fmi_state import MAGIC

    for magic in (MAGIC, STANDALONE_PAYLOAD_MAGIC):
        i = data.find(magic)
        if i >= 0:
            return data[i:]
    return data


def decode_payload(payload: bytes) -> dict:
    """The fields of a state payload (`slave_bytes`): the pythonfmu FMUs' document (rocking_model.fmi_state)
    or the self-contained FMUs' binary record (rocking_model.fmi.standalone.decode_state_payload; its engine
    snapshot as opaque bytes). Raises what the decoder raises."""
    if payload.startswith(STANDALONE_PAYLOAD_MAGIC):
        from rocking_model.fmi.standalone import decode_state_payload

        return decode_state_payload(payload)
    from rocking_model.fmi_state import decode_state

    return decode_state(payload)


#: [bytes] offset of the CRC-32 in the binary's header of a serialized state (rocking_model/fmi/binary/fmi2_common.c: magic 22,
#: time 8, three int32 fields), and the header's size
SERIAL_CRC_OFFSET = 42
SERIAL_HEADER_SIZE = SERIAL_CRC_OFFSET + 4


def with_binary_header(header: bytes, payload: bytes) -> bytes:
    """``payload`` (the slave's bytes) behind the binary's ``header`` with its CRC-32 recomputed: a state whose
    checksums hold, so that the slave's own checks of the payload are reached."""
    head = header[:SERIAL_CRC_OFFSET]
    return head + struct.pack("<I", zlib.crc32(payload, zlib.crc32(head))) + payload


def ag_of(k: int, amplitude: float) -> float:
    """One-sine pulse of period 1 s sampled at the communication points k*DT (then zero)."""
    return amplitude * math.sin(2 * math.pi * k * DT) if k < 100 else 0.0


def enc(value):
    """JSON-safe, exact encoding of an FMI value (floats as hex: bit-exact comparisons, NaN kept)."""
    if isinstance(value, bool):
        return value
    if isinstance(value, float):
        return value.hex()
    if isinstance(value, bytes):
        return value.decode("utf-8", "replace")
    return value


def dec_float(text) -> float:
    return float.fromhex(text) if isinstance(text, str) else float(text)


def rss_bytes() -> int:
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")


#: model descriptions by FMU path, and configs by file (filled in the fork server, inherited by the children)
_MD_CACHE: Dict[str, Any] = {}
_CONFIGS: Dict[str, dict] = {}


class HarnessError(RuntimeError):
    """A call the case needs in order to go on did not succeed (the case fails with this message)."""


# ---------------------------------------------------------------------------------------------- harness
class Harness:
    """The context of one case: FMU locations, callbacks, the record being written."""

    def __init__(self, config: dict, workdir: Path):
        import fmpy
        from fmpy.fmi2 import (fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE, fmi2CallbackFunctions,
                               fmi2CallbackLoggerTYPE)
        from fmpy.logging import addLoggerProxy

        self.config = config
        self.workdir = Path(workdir)
        self.messages: List[dict] = []
        self.calls: List[dict] = []
        self.checks: List[dict] = []
        self.figures: Dict[str, Any] = {}
        self.max_call: Dict[str, Any] = {}
        self.max_step: Dict[str, Any] = {}
        cb = fmi2CallbackFunctions()
        cb.logger = fmi2CallbackLoggerTYPE(self._log)
        cb.allocateMemory = fmi2CallbackAllocateMemoryTYPE(fmpy.calloc)
        cb.freeMemory = fmi2CallbackFreeMemoryTYPE(fmpy.free)
        # the native proxy formats the message with vsnprintf, as a C importer's logger does: a '%' the
        # FMU did not escape is interpreted here (and may crash the process, which the suite then reports)
        addLoggerProxy(ctypes.byref(cb))
        self.callbacks = cb
        self.instances: List["Inst"] = []

    def _log(self, env, instance, status, category, message):
        self.messages.append({"inst": enc(instance or b""), "status": int(status),
                              "category": enc(category or b""), "message": enc(message or b"")})

    # ---------------------------------------------------------------- FMUs
    def fmu_path(self, name: str) -> str:
        return self.config["fmus"][name]["path"]

    def unzip_dir(self, name: str) -> str:
        return self.config["fmus"][name]["unzip"]

    def md(self, name: str):
        path = self.fmu_path(name)
        if path not in _MD_CACHE:
            from fmpy import read_model_description
            _MD_CACHE[path] = read_model_description(path)
        return _MD_CACHE[path]

    def instance(self, name: str, iname: str = "subject", logging: bool = True, unzip: Optional[str] = None,
                 guid: Optional[str] = None) -> "Inst":
        inst = Inst(self, name, iname, logging, unzip or self.unzip_dir(name), guid)
        self.instances.append(inst)
        return inst

    def scene(self, name: str, logging: bool = True, params: Optional[dict] = None, n: int = N_BEFORE,
              control: bool = True):
        """A subject and (optionally) a control instance, initialized alike and driven n steps."""
        params = {**SCENES[name][1], **(params or {})}
        subject = self.instance(name, "subject", logging)
        subject.init(**params)
        subject.drive(n)
        if not control:
            return subject
        ctrl = self.instance(name, "control", logging)
        ctrl.init(**params)
        ctrl.drive(n)
        return subject, ctrl

    # ---------------------------------------------------------------- record
    def mark(self) -> int:
        return len(self.messages)

    def check(self, kind: str, label: str, ok: bool, detail: Any = None) -> bool:
        self.checks.append({"kind": kind, "label": label, "ok": bool(ok), "detail": detail})
        return bool(ok)

    def expect_status(self, label: str, actual: int, expected) -> bool:
        allowed = set(expected) if isinstance(expected, (set, tuple, list, frozenset)) else {expected}
        return self.check("status", label, actual in allowed,
                          f"{STATUS_NAMES.get(actual, actual)}; expected "
                          f"{' or '.join(STATUS_NAMES.get(s, str(s)) for s in sorted(allowed))}")

    def messages_since(self, mark: int, inst: Optional["Inst"] = None, min_status: int = ERROR) -> List[dict]:
        return [m for m in self.messages[mark:]
                if m["status"] >= min_status and (inst is None or m["inst"] == inst.iname)]

    def expect_log(self, label: str, mark: int, inst: Optional["Inst"], fragments: Sequence,
                   min_status: int = ERROR) -> bool:
        """A message (status >= min_status) of ``inst`` since ``mark`` containing every fragment: a string
        (case-insensitive substring), a tuple of alternatives, or "re:<regex>"."""
        candidates = self.messages_since(mark, inst, min_status)
        ok = any(all(_matches(m["message"], f) for f in fragments) for m in candidates)
        return self.check("message", label, ok,
                          {"wanted": [list(f) if isinstance(f, tuple) else f for f in fragments],
                           "got": [f"[{STATUS_NAMES.get(m['status'])}] {m['message'][:600]}" for m in candidates]
                           or "no message of that status"})

    def expect_no_log(self, label: str, mark: int, inst: Optional["Inst"] = None,
                      min_status: int = WARNING) -> bool:
        got = self.messages_since(mark, inst, min_status)
        return self.check("message", label, not got, [m["message"][:300] for m in got])

    def expect_same(self, label: str, before: dict, after: dict, kind: str = "state") -> bool:
        problems = snapshot_diff(before, after)
        return self.check(kind, label, not problems, problems or None)

    def expect_same_run(self, label: str, subject: "Inst", control: "Inst", n: int = N_AFTER) -> bool:
        """n further identical valid steps of subject and control: every step OK, identical outputs after
        each, and identical serialized states at the end."""
        problems = []
        for i in range(n):
            s1, s2 = subject.drive_step(), control.drive_step()
            # fmi2Warning: the step was done with a warning logged (an inexact contact solve; an overturning is
            # an event, fmi2OK); subject and control must agree on it
            if s1 != s2 or s1 not in (OK, WARNING):
                problems.append(f"step {i + 1} after the refused call: subject {STATUS_NAMES.get(s1)}, control "
                                f"{STATUS_NAMES.get(s2)}")
                break
            a, b = subject.outputs(), control.outputs()
            if a != b:
                problems.append({"step": i + 1, "outputs differ": _dict_diff(a, b)})
                break
        if not problems:
            problems = snapshot_diff(subject.snapshot(), control.snapshot(), "subject", "control")
        return self.check("state", f"{label}: {n} more steps identical to a control instance", not problems,
                          problems or None)

    def figure(self, name: str, value) -> None:
        self.figures[name] = value


def _matches(message: str, fragment) -> bool:
    if isinstance(fragment, tuple):
        return any(_matches(message, f) for f in fragment)
    if fragment.startswith("re:"):
        return re.search(fragment[3:], message) is not None
    return fragment.lower() in message.lower()


def word(name: str) -> str:
    """Fragment: ``name`` as a whole word (a variable name such as b or T)."""
    return rf"re:(?<![A-Za-z0-9_]){re.escape(name)}(?![A-Za-z0-9_])"


def _dict_diff(a: dict, b: dict) -> dict:
    keys = sorted(set(a) | set(b))
    return {k: [a.get(k), b.get(k)] for k in keys if a.get(k) != b.get(k)}


def _flatten(obj, prefix="") -> dict:
    if isinstance(obj, dict):
        out = {}
        for k, v in obj.items():
            out.update(_flatten(v, f"{prefix}{k}."))
        return out
    if isinstance(obj, list) and len(obj) > 8:
        return {prefix[:-1]: f"list[{len(obj)}] sha={hashlib.sha256(repr(obj).encode()).hexdigest()[:12]}"}
    return {prefix[:-1]: repr(obj)}


def snapshot_diff(a: dict, b: dict, na: str = "before", nb: str = "after") -> list:
    problems = []
    for side, snap in ((na, a), (nb, b)):
        if not snap.get("state_ok"):
            problems.append(f"{side}: no valid serialized state ({snap.get('state_problem')})")
    if a["values"] != b["values"]:
        problems.append({"values differ": _dict_diff(a["values"], b["values"])})
    if a.get("state_ok") and b.get("state_ok") and a["state_sha"] != b["state_sha"]:
        diff = _dict_diff(_flatten(a.get("state_doc")), _flatten(b.get("state_doc"))) \
            if a.get("state_doc") is not None and b.get("state_doc") is not None else "undecodable"
        problems.append({"serialized states differ": {"len": [a["state_len"], b["state_len"]], "fields": diff}})
    return problems


# ---------------------------------------------------------------------------------------------- instance
class Inst:
    """One FMU2Slave instance; every call records its status (fmpy raises FMICallException above
    fmi2Warning: the status is taken from it)."""

    def __init__(self, h: Harness, name: str, iname: str, logging: bool, unzip: str, guid: Optional[str]):
        from fmpy.fmi2 import FMU2Slave

        self.h, self.name, self.iname = h, name, iname
        md = h.md(name)
        self.vars = {v.name: v for v in md.modelVariables}
        self.by_vr = {v.valueReference: v for v in md.modelVariables}
        self.output_names = [v.name for v in md.modelVariables if v.causality == "output"]
        self.value_names = [v.name for v in md.modelVariables]
        self.amplitude = SCENES[name][0]
        self.k = 0
        self.t = 0.0
        self.fmu = FMU2Slave(guid=guid or md.guid, unzipDirectory=unzip,
                             modelIdentifier=md.coSimulation.modelIdentifier, instanceName=iname)
        self.alive = True
        # FMI 2.0 allows no getter before initialization mode: values() reads nothing in this phase (a
        # getter there is an illegal call, fmi2Error, and would put the instance into the error state)
        self.phase = "instantiated"
        st = self.call("fmi2Instantiate", self.fmu.instantiate, loggingOn=logging, callbacks=h.callbacks)
        if st != OK:
            raise HarnessError(f"fmi2Instantiate of {name} failed ({STATUS_NAMES.get(st, st)})")

    # ---------------------------------------------------------------- raw calls
    def call(self, label: str, fn: Callable, *args, **kwargs) -> int:
        status, _ = self.call_value(label, fn, *args, **kwargs)
        return status

    def call_value(self, label: str, fn: Callable, *args, **kwargs):
        from fmpy.fmi1 import FMICallException

        t0 = time.perf_counter()
        value = None
        try:
            value = fn(*args, **kwargs)
            # the calls made through the raw FMI function report their own status (fmi2OK or fmi2Warning)
            status = value if label == "fmi2DoStep" and isinstance(value, int) else OK
        except FMICallException as exc:
            status = int(exc.status)
        except Exception as exc:  # fmpy's own exceptions (e.g. "Failed to instantiate model")
            status = -1
            value = f"{type(exc).__name__}: {exc}"
        elapsed = time.perf_counter() - t0
        rec = {"inst": self.iname, "call": label, "status": status, "elapsed": round(elapsed, 6)}
        if len(self.h.calls) < 400:
            self.h.calls.append(rec)
        if elapsed > self.h.max_call.get("elapsed", -1.0):
            self.h.max_call = rec
        if label == "fmi2DoStep" and elapsed > self.h.max_step.get("elapsed", -1.0):
            self.h.max_step = rec
        return status, value

    # ---------------------------------------------------------------- life cycle
    def setup(self, t0: float = 0.0) -> int:
        return self.call("fmi2SetupExperiment", self.fmu.setupExperiment, startTime=t0)

    def enter(self) -> int:
        st = self.call("fmi2EnterInitializationMode", self.fmu.enterInitializationMode)
        if st == OK:
            self.phase = "initialization"
        return st

    def exit(self) -> int:
        return self.call("fmi2ExitInitializationMode", self.fmu.exitInitializationMode)

    def init(self, t0: float = 0.0, **params) -> None:
        for label, st in (("fmi2SetupExperiment", self.setup(t0)), ("fmi2EnterInitializationMode", self.enter())):
            if st != OK:
                raise HarnessError(f"{self.iname}: {label} returned {STATUS_NAMES.get(st, st)}")
        st = self.set(**params)
        if st != OK:
            raise HarnessError(f"{self.iname}: setting {params} returned {STATUS_NAMES.get(st, st)}")
        st = self.exit()
        if st != OK:
            raise HarnessError(f"{self.iname}: fmi2ExitInitializationMode with {params} returned "
                               f"{STATUS_NAMES.get(st, st)}")
        self.t, self.k = t0, 0

    def terminate(self) -> int:
        return self.call("fmi2Terminate", self.fmu.terminate)

    def reset(self) -> int:
        st = self.call("fmi2Reset", self.fmu.reset)
        self.t, self.k = 0.0, 0
        if st == OK:
            self.phase = "instantiated"
        return st

    def free(self) -> int:
        st = self.call("fmi2FreeInstance", self.fmu.freeInstance)
        self.alive = False
        return st

    # ---------------------------------------------------------------- values
    def typed(self, type_name: str):
        f = self.fmu
        return {"Real": (f.setReal, f.getReal), "Integer": (f.setInteger, f.getInteger),
                "Boolean": (f.setBoolean, f.getBoolean), "String": (f.setString, f.getString)}[type_name]

    def set(self, **values) -> int:
        """Set variables by name (one call per variable); the worst status."""
        worst = OK
        for name, value in values.items():
            var = self.vars[name]
            setter = self.typed(var.type)[0]
            if var.type == "Real":
                value = float(value)
            elif var.type == "Integer":
                value = int(value)
            elif var.type == "Boolean":
                value = bool(value)
            else:
                value = str(value)
            st = self.call(f"fmi2Set{var.type}({name})", setter, [var.valueReference], [value])
            worst = st if st != OK and worst == OK else worst
        return worst

    def set_vr(self, type_name: str, vrs: list, values: list) -> int:
        return self.call(f"fmi2Set{type_name}({vrs})", self.typed(type_name)[0], vrs, values)

    def get_vr(self, type_name: str, vrs: list):
        status, values = self.call_value(f"fmi2Get{type_name}({vrs})", self.typed(type_name)[1], vrs)
        return status, values

    def get(self, name: str):
        var = self.vars[name]
        status, values = self.get_vr(var.type, [var.valueReference])
        if status != OK:
            raise HarnessError(f"{self.iname}: fmi2Get{var.type}({name}) returned {STATUS_NAMES.get(status)}")
        return values[0]

    def values(self, names: Optional[Sequence[str]] = None) -> dict:
        """Every variable (parameters, inputs, outputs), read type by type in one call each."""
        names = list(names or self.value_names)
        if self.phase == "instantiated":
            return {"<phase>": "instantiated"}
        out = {}
        for type_name in ("Real", "Integer", "Boolean", "String"):
            group = [n for n in names if self.vars[n].type == type_name]
            if not group:
                continue
            status, vals = self.get_vr(type_name, [self.vars[n].valueReference for n in group])
            if status != OK:
                out.update({n: f"<fmi2Get{type_name} {STATUS_NAMES.get(status)}>" for n in group})
            else:
                out.update({n: enc(v) for n, v in zip(group, vals)})
        return out

    def outputs(self) -> dict:
        return self.values(self.output_names)

    # ---------------------------------------------------------------- stepping
    def _do_step(self, t: float, dt: float) -> int:
        """fmi2DoStep returning its status (fmpy's doStep drops an fmi2Warning)."""
        return int(self.fmu.fmi2DoStep(self.fmu.component, t, dt, 1))

    def step(self, dt: float = DT, t: Optional[float] = None) -> int:
        t = self.t if t is None else t
        st = self.call("fmi2DoStep", self._do_step, t, dt)
        if st in (OK, WARNING):          # fmi2Warning: the step was done (with something logged)
            self.t = t + dt
        return st

    def drive_step(self) -> int:
        if self.amplitude is not None:
            st = self.set(ag=ag_of(self.k, self.amplitude))
            if st != OK:
                return st
        st = self.step()
        if st == OK:
            self.k += 1
        return st

    def drive(self, n: int) -> None:
        for _ in range(n):
            st = self.drive_step()
            if st != OK:
                raise HarnessError(f"{self.iname}: valid step at t = {self.t:g} returned {STATUS_NAMES.get(st)}")

    # ---------------------------------------------------------------- FMU state
    def get_state(self):
        from fmpy.fmi2 import fmi2FMUstate

        state = fmi2FMUstate()
        st = self.call("fmi2GetFMUstate", self.fmu.fmi2GetFMUstate, self.fmu.component, ctypes.byref(state))
        return st, state

    def serialize(self, state):
        size = ctypes.c_size_t()
        st = self.call("fmi2SerializedFMUstateSize", self.fmu.fmi2SerializedFMUstateSize, self.fmu.component,
                       state, ctypes.byref(size))
        if st != OK:
            return st, b""
        buf = ctypes.create_string_buffer(size.value)
        st = self.call("fmi2SerializeFMUstate", self.fmu.fmi2SerializeFMUstate, self.fmu.component, state, buf,
                       size)
        return st, buf.raw

    def deserialize(self, data: bytes):
        from fmpy.fmi2 import fmi2FMUstate

        state = fmi2FMUstate()
        buf = ctypes.create_string_buffer(data, len(data))
        st = self.call("fmi2DeSerializeFMUstate", self.fmu.fmi2DeSerializeFMUstate, self.fmu.component, buf,
                       len(data), ctypes.byref(state))
        return st, state

    def set_state(self, state) -> int:
        return self.call("fmi2SetFMUstate", self.fmu.setFMUstate, state)

    def free_state(self, state) -> int:
        return self.call("fmi2FreeFMUstate", self.fmu.freeFMUstate, state)

    def state_bytes(self) -> tuple:
        """(bytes of the current state, problem or None): get, serialize, free."""
        st, state = self.get_state()
        if st != OK:
            return b"", f"fmi2GetFMUstate returned {STATUS_NAMES.get(st)}"
        st2, data = self.serialize(state)
        self.free_state(state)
        if st2 != OK:
            return b"", f"fmi2SerializeFMUstate returned {STATUS_NAMES.get(st2)}"
        problem = None
        try:
            decode_payload(slave_bytes(data))
        except ImportError:
            problem = None if data else "empty"
        except Exception as exc:
            problem = f"the FMU's own state does not decode: {exc}"
        return data, problem

    def snapshot(self) -> dict:
        """Everything observable: all variable values (exact) and the serialized state. Neither call changes
        the instance (a getter or fmi2GetFMUstate that fails is recorded, not retried)."""
        mark = self.h.mark()
        values = self.values()
        data, problem = self.state_bytes()
        data = slave_bytes(data)  # the binary's header holds the FMI status of the last step, compared apart
        snap = {"values": values, "state_len": len(data), "state_sha": hashlib.sha256(data).hexdigest(),
                "state_ok": bool(data) and problem is None, "state_problem": problem, "state_doc": None}
        if snap["state_ok"]:
            try:
                snap["state_doc"] = decode_payload(slave_bytes(data))
            except Exception:
                pass
        # a snapshot must not leave messages behind that a later check could mistake for its own
        snap["messages"] = [m["message"][:200] for m in self.h.messages[mark:]]
        return snap


# ---------------------------------------------------------------------------------------------- registry
@dataclass
class Case:
    cid: str
    fn: Callable
    kwargs: dict = field(default_factory=dict)
    kinds: tuple = ("status", "message", "state")
    timeout: float = 60.0
    xfail: Optional[str] = None
    family: str = ""
    what: str = ""


CASES: Dict[str, Case] = {}


def add(cid: str, fn: Callable, *, kinds=("status", "message", "state"), timeout: float = 60.0,
        xfail: Optional[str] = None, desc: str = "", **kwargs) -> None:
    if cid in CASES:
        raise ValueError(f"duplicate case {cid}")
    CASES[cid] = Case(cid, fn, kwargs, tuple(kinds), timeout, xfail, cid.split("/")[0], desc)


def refusal(h: Harness, s: Inst, label: str, action: Callable[[], int], *, status, fragments: Sequence,
            control: Optional[Inst] = None) -> None:
    """The common protocol of a refused call: its status, a message naming what is wrong, every variable
    bit-identical; after fmi2Error the instance is in the error state (a step is an illegal call) and
    fmi2SetFMUstate of a state saved before the call brings it back, bit-identical; then it steps on like a
    control instance that never saw the call."""
    before = s.snapshot()
    st_saved, saved = s.get_state()
    mark = h.mark()
    st = action()
    h.expect_status(f"{label}: status of the refused call", st, status)
    h.expect_log(f"{label}: error message", mark, s, fragments)
    values = s.values()
    h.check("state", f"{label}: every variable bit-identical after the refused call", values == before["values"],
            _dict_diff(before["values"], values) or None)
    if st == ERROR:
        h.expect_status(f"{label}: fmi2DoStep in the error state is an illegal call", s.step(), ERROR)
        h.expect_status(f"{label}: fmi2SetFMUstate of the state saved before leaves the error state",
                        s.set_state(saved), OK)
    h.expect_same(f"{label}: state bit-identical to before", before, s.snapshot())
    if st_saved == OK:
        s.free_state(saved)
    if control is not None:
        h.expect_same_run(label, s, control)
    else:
        h.expect_status(f"{label}: a valid step afterwards", s.drive_step(), OK)


# ============================================================================================== cases
# ---------------------------------------------------------------------------------------------- parameters
def bad_parameter(h: Harness, fmu: str, values: dict, fragments: Sequence, logging: bool = True,
                  files: Optional[dict] = None):
    """Invalid start values: fmi2ExitInitializationMode returns fmi2Error with a message naming the variable and
    its allowed range, which reaches the logger with logging on or off; every later call is safe; fmi2Reset +
    valid values give a working instance."""
    for fname, text in (files or {}).items():
        (h.workdir / fname).write_text(text)
    values = {k: (str(h.workdir / v[5:]) if isinstance(v, str) and v.startswith("@cwd/") else v)
              for k, v in values.items()}
    s = h.instance(fmu, "subject", logging)
    h.expect_status("fmi2SetupExperiment", s.setup(), OK)
    h.expect_status("fmi2EnterInitializationMode", s.enter(), OK)
    h.expect_status(f"setting {values} in initialization mode (checked at exit)", s.set(**values), OK)
    mark = h.mark()
    h.expect_status("fmi2ExitInitializationMode with invalid parameters", s.exit(), ERROR)
    h.expect_log(f"the message names the variable and its allowed range (logging {'on' if logging else 'off'})",
                 mark, s, fragments)
    after_error(h, s, fmu, logging)


def after_error(h: Harness, s: Inst, fmu: str, logging: bool = True) -> None:
    """After fmi2ExitInitializationMode returned fmi2Error: the instance is in the error state, every later
    call is safe, no step is reported done, and fmi2Reset + valid start values give an instance that runs
    like a fresh one."""
    mark = h.mark()
    st = s.step()
    h.expect_status("fmi2DoStep after the failed initialization: an illegal call", st, ERROR)
    h.expect_log("fmi2DoStep after the failed initialization says why", mark, s,
                 ("fmi2DoStep", "illegal call sequence", "error state"))
    st, vals = s.get_vr("Real", [v.valueReference for v in s.vars.values() if v.type == "Real"])
    h.check("status", "getters after the failed initialization", st in (OK, DISCARD, ERROR), STATUS_NAMES.get(st))
    for label, fn in (("fmi2GetFMUstate", lambda: s.get_state()[0]), ("fmi2Terminate", s.terminate),
                      ("fmi2Reset", s.reset)):
        st = fn()
        h.check("status", f"{label} after the failed initialization does not fail", st in (OK, WARNING, ERROR,
                                                                                          DISCARD),
                STATUS_NAMES.get(st))
    # reset + valid start values: a working instance, identical to a fresh one
    ctrl = h.instance(fmu, "control", logging)
    h.expect_same("after fmi2Reset the instance holds the start values of a fresh one",
                  ctrl.snapshot(), s.snapshot())
    s.init(**SCENES[fmu][1])
    ctrl.init(**SCENES[fmu][1])
    h.expect_same_run("after fmi2Reset and valid parameters", s, ctrl, N_AFTER)
    h.expect_status("fmi2Terminate", s.terminate(), OK)
    h.expect_status("fmi2FreeInstance", s.free(), OK)


def _rng(name):
    return (word(name), "allowed")


BAD_PARAMS = [
    # rigid block
    (RIGID, {"b": -0.2}), (RIGID, {"b": 0.0}), (RIGID, {"b": math.nan}), (RIGID, {"b": math.inf}),
    (RIGID, {"h": 0.0}), (RIGID, {"h": -1.0}), (RIGID, {"h": 1e4}), (RIGID, {"m": 0.0}), (RIGID, {"g": 0.0}),
    (RIGID, {"e_N": 2.0}), (RIGID, {"e_N": -0.1}), (RIGID, {"e_N": math.nan}), (RIGID, {"phi_0": 2.0}),
    (RIGID, {"phi_0": -math.inf}), (RIGID, {"phi_dot_0": 1e5}), (RIGID, {"scheme": 7}), (RIGID, {"scheme": -1}),
    (RIGID, {"scheme": 2**31 - 1}), (RIGID, {"tolerance": 1.0}), (RIGID, {"tolerance": 0.0}),
    (RIGID, {"tolerance": math.nan}), (RIGID, {"dt_max": -1e-3}), (RIGID, {"dt_max": math.nan}),
    # flexible oscillator
    (FLEX, {"EI": 0.0}), (FLEX, {"EI": -1.0}), (FLEX, {"EI": math.nan}), (FLEX, {"m": 0.0}), (FLEX, {"m_c": -1.0}),
    (FLEX, {"rho": -1.0}), (FLEX, {"zeta": -0.1}), (FLEX, {"e_N": 2.0}), (FLEX, {"h": 0.0}), (FLEX, {"b": -0.2}),
    (FLEX, {"u_0": 10.0}), (FLEX, {"scheme": 7}), (FLEX, {"impact_rule": 5}), (FLEX, {"tolerance": 1.0}),
    (FLEX, {"g": math.inf}),
    # post-tensioned block: its own parameters (the others are the rigid block's)
    (PT, {"P0": -1.0}), (PT, {"P0": math.nan}), (PT, {"P0": math.inf}), (PT, {"k_t": -1.0}), (PT, {"k_t": math.nan}),
    (PT, {"k_t": 1e16}),
    # linear storey
    (STOREY, {"T": -1.0}), (STOREY, {"T": math.nan}), (STOREY, {"zeta": -0.1}), (STOREY, {"u_0": math.inf}),
    # ground-motion source
    (GMS, {"motion": 5}), (GMS, {"omega_p": 0.0}), (GMS, {"omega_p": -1.0}), (GMS, {"A": math.nan}),
    (GMS, {"scale": math.inf}), (GMS, {"units": "furlongs/s2"}),
]
for _fmu, _vals in BAD_PARAMS:
    (_name, _value), = _vals.items()
    add(f"param/{SHORT[_fmu]}/{_name}={_value!r}", bad_parameter, fmu=_fmu, values=_vals, fragments=_rng(_name),
        desc=f"{_fmu}: invalid start value {_name} = {_value!r}")
add("param/flex/m_c=0,m_b=0", bad_parameter, fmu=FLEX, values={"m_c": 0.0, "m_b": 0.0},
    fragments=(word("m_b"), "allowed"), desc="FlexibleRockingOscillator: singular mass matrix (m_c = m_b = 0)")
add("param/storey/T=0,u_0=0.1", bad_parameter, fmu=STOREY, values={"T": 0.0, "u_0": 0.1},
    fragments=(word("u_0"), "allowed"), desc="LinearBuildingStorey: rigid storey with an initial displacement")
add("param/ground/record-missing", bad_parameter, fmu=GMS, values={"motion": 1, "record": "@cwd/nope.csv"},
    fragments=("nope.csv",), desc="GroundMotionSource: record file that does not exist")
add("param/ground/record-malformed", bad_parameter, fmu=GMS, values={"motion": 1, "record": "@cwd/bad.csv"},
    files={"bad.csv": "time [s],ag [m/s2]\n0.0,1.0\n0.01,abc\n"}, fragments=("bad.csv", "line 3"),
    desc="GroundMotionSource: malformed record file (a non-number on line 3)")
add("param/ground/record-empty", bad_parameter, fmu=GMS, values={"motion": 1, "record": ""},
    fragments=(word("record"),), desc="GroundMotionSource: motion = 1 without a record")
add("param/ground/record-not-increasing", bad_parameter, fmu=GMS, values={"motion": 1, "record": "@cwd/back.csv"},
    files={"back.csv": "time [s],ag [m/s2]\n0.0,1.0\n0.02,1.0\n0.01,2.0\n"}, fragments=("back.csv", "line"),
    desc="GroundMotionSource: record whose time goes back")
for _fmu, _vals, _frag in ((RIGID, {"b": -0.2}, _rng("b")), (FLEX, {"EI": 0.0}, _rng("EI")),
                           (STOREY, {"T": -1.0}, _rng("T")),
                           (GMS, {"motion": 1, "record": "@cwd/nope.csv"}, ("nope.csv",))):
    add(f"param-logging-off/{SHORT[_fmu]}/{','.join(_vals)}", bad_parameter, fmu=_fmu, values=_vals,
        fragments=_frag, logging=False, desc=f"{_fmu}: invalid start value with loggingOn = false")


def setup_experiment_bad_start(h: Harness, t0: float):
    s = h.instance(RIGID)
    mark = h.mark()
    h.expect_status(f"fmi2SetupExperiment(startTime = {t0!r})", s.setup(t0), ERROR)
    h.expect_log("the message names startTime", mark, s, ("startTime",))
    h.check("status", "fmi2DoStep afterwards is not fmi2OK", s.step(t=0.0) not in (OK, -1))
    h.expect_status("fmi2Reset", s.reset(), OK)
    ctrl = h.instance(RIGID, "control")
    s.init()
    ctrl.init()
    h.expect_same_run("after fmi2Reset", s, ctrl)


for _t0 in (math.nan, math.inf):
    add(f"sequence/rigid/setupExperiment-startTime={_t0!r}", setup_experiment_bad_start, t0=_t0,
        desc=f"fmi2SetupExperiment with startTime = {_t0!r}")


def simulate_bad(h: Harness, fmu: str, values: dict, fragments: Sequence):
    """fmpy.simulate_fmu with an invalid start value raises (and run_fmu raises FMUError naming it)."""
    import fmpy

    values = {k: (str(h.workdir / v[5:]) if isinstance(v, str) and v.startswith("@cwd/") else v)
              for k, v in values.items()}
    t0 = time.perf_counter()
    try:
        res = fmpy.simulate_fmu(h.fmu_path(fmu), stop_time=0.1, output_interval=DT, start_values=values)
        h.check("status", "fmpy.simulate_fmu raises", False, f"returned {len(res)} rows, no exception")
    except Exception as exc:
        h.check("status", "fmpy.simulate_fmu raises", True, f"{type(exc).__name__}: {exc}"[:300])
    from rocking_model.fmi import FMUError, run_fmu
    try:
        run_fmu(h.fmu_path(fmu), stop_time=0.1, output_interval=DT, start_values=values)
        h.check("status", "rocking_model.fmi.run_fmu raises FMUError", False, "no exception")
    except FMUError as exc:
        h.check("status", "rocking_model.fmi.run_fmu raises FMUError", True)
        h.check("message", "the FMUError names the variable and its allowed range",
                all(_matches(str(exc), f) for f in fragments), str(exc)[:600])
    except Exception as exc:
        h.check("status", "rocking_model.fmi.run_fmu raises FMUError", False, f"{type(exc).__name__}: {exc}")
    h.figure("elapsed", time.perf_counter() - t0)


for _fmu, _vals, _frag in ((RIGID, {"b": -0.2}, _rng("b")), (FLEX, {"EI": -1.0}, _rng("EI")),
                           (STOREY, {"T": -1.0}, _rng("T")), (GMS, {"motion": 5}, _rng("motion"))):
    add(f"simulate_fmu/{SHORT[_fmu]}/{','.join(_vals)}", simulate_bad, fmu=_fmu, values=_vals, fragments=_frag,
        kinds=("status", "message"), desc=f"fmpy.simulate_fmu({_fmu}, start_values={_vals})")


# ---------------------------------------------------------------------------------------------- call sequence
def step_before_init(h: Harness, fmu: str, where: str):
    """fmi2DoStep before initialization: an illegal call sequence, fmi2Error with a message naming the call and
    the state of the instance; fmi2Reset, then the instance initializes and steps like a control instance."""
    s = h.instance(fmu)
    ctrl = h.instance(fmu, "control")
    if where in ("after-setup", "in-init-mode"):
        s.setup()
    if where == "in-init-mode":
        s.enter()
    mark = h.mark()
    h.expect_status(f"fmi2DoStep {where}: status", s.step(t=0.0), ERROR)
    h.expect_log(f"fmi2DoStep {where}: message names the call", mark, s,
                 ("fmi2DoStep", "illegal call sequence", ("instantiated", "initialization")))
    h.expect_status("fmi2Reset", s.reset(), OK)
    s.setup()
    s.enter()
    s.set(**SCENES[fmu][1])
    h.expect_status("fmi2ExitInitializationMode afterwards", s.exit(), OK)
    ctrl.init(**SCENES[fmu][1])
    h.expect_same_run("then initialized", s, ctrl)


for _fmu in FMUS:
    add(f"sequence/{SHORT[_fmu]}/doStep-before-init", step_before_init, fmu=_fmu, where="after-instantiate",
        desc=f"{_fmu}: fmi2DoStep right after fmi2Instantiate")
for _where in ("after-setup", "in-init-mode"):
    add(f"sequence/rigid/doStep-{_where}", step_before_init, fmu=RIGID, where=_where,
        desc=f"RigidRockingBlock: fmi2DoStep {_where.replace('-', ' ')}")


def again_after_init(h: Harness, fmu: str, calls: Sequence[str]):
    """fmi2SetupExperiment / fmi2EnterInitializationMode / fmi2ExitInitializationMode after initialization:
    fmi2OK (all the wrapper can answer), an error naming the call, the state kept, the next step discarded
    once, then stepping on normally."""
    s, ctrl = h.scene(fmu)
    fns = {"setupExperiment": lambda: s.setup(0.0), "enterInitializationMode": s.enter,
           "exitInitializationMode": s.exit}

    def action():
        worst = OK
        for c in calls:
            st = fns[c]()
            worst = st if worst == OK else worst
        return worst

    refusal(h, s, " + ".join(f"fmi2{c}" for c in calls) + " after initialization", action, status=ERROR,
            fragments=(f"fmi2{calls[0][0].upper()}{calls[0][1:]}",), control=ctrl)


for _fmu in FMUS:
    for _calls in (["enterInitializationMode"], ["exitInitializationMode"], ["setupExperiment"]):
        add(f"sequence/{SHORT[_fmu]}/{_calls[0]}-after-init", again_after_init, fmu=_fmu, calls=_calls,
            desc=f"{_fmu}: fmi2{_calls[0][0].upper()}{_calls[0][1:]} after initialization")
for _fmu in (RIGID, FLEX):
    add(f"sequence/{SHORT[_fmu]}/setup+enter+exit-after-init", again_after_init, fmu=_fmu,
        calls=["setupExperiment", "enterInitializationMode", "exitInitializationMode"],
        desc=f"{_fmu}: a whole second initialization sequence mid-run")


def step_after_terminate(h: Harness, fmu: str):
    s, ctrl = h.scene(fmu)
    h.expect_status("fmi2Terminate", s.terminate(), OK)
    before = s.snapshot()
    mark = h.mark()
    h.expect_status("fmi2DoStep after fmi2Terminate", s.step(), ERROR)
    h.expect_log("the message names the call", mark, s, ("fmi2DoStep", "illegal call sequence", "terminated"))
    h.expect_status("fmi2DoStep after fmi2Terminate, again", s.step(), ERROR)
    h.check("state", "every variable kept", s.values() == before["values"])
    h.check("state", "the terminated instance's values equal the control's", s.values() == ctrl.values())
    h.expect_status("fmi2Terminate twice", s.terminate(), (OK, ERROR))
    h.expect_status("fmi2Reset", s.reset(), OK)
    ctrl2 = h.instance(fmu, "control2")
    s.init(**SCENES[fmu][1])
    ctrl2.init(**SCENES[fmu][1])
    h.expect_same_run("after fmi2Reset", s, ctrl2)


for _fmu in FMUS:
    add(f"sequence/{SHORT[_fmu]}/doStep-after-terminate", step_after_terminate, fmu=_fmu,
        desc=f"{_fmu}: fmi2DoStep after fmi2Terminate")


def free_without_terminate(h: Harness):
    s, ctrl = h.scene(RIGID)
    h.expect_status("fmi2FreeInstance without fmi2Terminate", s.free(), OK)
    again = h.instance(RIGID, "again")
    again.init()
    again.drive(N_BEFORE)
    h.expect_same("a new instance afterwards runs like the control", {**ctrl.snapshot()}, {**again.snapshot()})


add("sequence/rigid/free-without-terminate", free_without_terminate, kinds=("status", "state"),
    desc="fmi2FreeInstance without fmi2Terminate, then a new instance")


# ---------------------------------------------------------------------------------------------- doStep arguments
def bad_step(h: Harness, fmu: str, what: str):
    s, ctrl = h.scene(fmu)
    if s.amplitude is not None:  # the input of the next step, as a master sets it, on both
        s.set(ag=ag_of(s.k, s.amplitude))
        ctrl.set(ag=ag_of(ctrl.k, ctrl.amplitude))
    t = s.t
    args = {"dt=0": (t, 0.0), "dt<0": (t, -DT), "dt=nan": (t, math.nan), "dt=inf": (t, math.inf),
            "dt=1e308": (t, 1e308), "t=nan": (math.nan, DT), "t=inf": (math.inf, DT), "t-ahead": (t + 1.0, DT),
            "t-behind": (t - DT, DT)}[what]
    name = "communicationStepSize" if what.startswith("dt") else "currentCommunicationPoint"
    refusal(h, s, f"fmi2DoStep({args[0]!r}, {args[1]!r})", lambda: s.step(args[1], t=args[0]), status=ERROR,
            fragments=(name,), control=ctrl)


for _fmu in FMUS:
    for _what in ("dt=0", "dt<0", "dt=nan", "dt=inf", "t=nan", "t-ahead", "t-behind") if _fmu in ROCKING \
            else ("dt=0", "dt=nan", "t=nan", "t-ahead"):
        add(f"doStep/{SHORT[_fmu]}/{_what}", bad_step, fmu=_fmu, what=_what,
            desc=f"{_fmu}: fmi2DoStep with {_what}")
add("doStep/rigid/t=inf", bad_step, fmu=RIGID, what="t=inf", desc="RigidRockingBlock: currentCommunicationPoint inf")


# ---------------------------------------------------------------------------------------------- inputs
def bad_input(h: Harness, fmu: str, value: float, name: str = "ag"):
    """An input (ag, or the vertical ag_v) outside its declared range: fmi2SetReal answers fmi2Error with a
    message naming the input and the range, nothing is set; then (out of the error state through a saved
    state) a valid input steps on like the control."""
    s, ctrl = h.scene(fmu)
    refusal(h, s, f"fmi2SetReal({name} = {value!r})", lambda: s.set(**{name: value}), status=ERROR,
            fragments=(word(name), "1000"), control=ctrl)


for _fmu in WITH_INPUT:
    for _v in (math.nan, math.inf, -math.inf, 1e308, 1500.0, -1500.0):
        add(f"input/{SHORT[_fmu]}/ag={_v!r}", bad_input, fmu=_fmu, value=_v, desc=f"{_fmu}: input ag = {_v!r}")
for _fmu in WITH_VERTICAL:
    for _v in (math.nan, math.inf, -math.inf, 1e308, 1500.0, -1500.0):
        add(f"input/{SHORT[_fmu]}/ag_v={_v!r}", bad_input, fmu=_fmu, value=_v, name="ag_v",
            desc=f"{_fmu}: input ag_v = {_v!r}")


def both_inputs_bad(h: Harness, fmu: str):
    """ag and ag_v both refused in one fmi2SetReal: fmi2Error naming both, neither set."""
    s, ctrl = h.scene(fmu)
    vrs = [s.vars["ag"].valueReference, s.vars["ag_v"].valueReference]
    refusal(h, s, "fmi2SetReal(ag = 2000, ag_v = nan)", lambda: s.set_vr("Real", vrs, [2000.0, math.nan]),
            status=ERROR, fragments=(word("ag"), word("ag_v"), "2000", "nan"), control=ctrl)


for _fmu in WITH_VERTICAL:
    add(f"input/{SHORT[_fmu]}/ag=2000+ag_v=nan", both_inputs_bad, fmu=_fmu,
        desc=f"{_fmu}: ag and ag_v both invalid in one fmi2SetReal")


def declared_input_range(h: Harness):
    for fmu in WITH_INPUT:
        var = h.md(fmu).modelVariables
        for name in ("ag", "ag_v") if fmu in WITH_VERTICAL else ("ag",):
            inp = next(v for v in var if v.name == name)
            lo = None if inp.min is None else float(inp.min)
            hi = None if inp.max is None else float(inp.max)
            h.check("status", f"{fmu}: {name} declares min = -{AG_LIMIT:g}, max = {AG_LIMIT:g} m/s2",
                    (lo, hi) == (-AG_LIMIT, AG_LIMIT), f"min = {inp.min}, max = {inp.max}")


add("input/all/declared-range", declared_input_range, kinds=("status",),
    desc="modelDescription: the inputs ag and ag_v declare their range |ag|, |ag_v| <= 1000 m/s2")


def set_input_after_terminate(h: Harness, fmu: str, name: str):
    """fmi2SetReal of an input after fmi2Terminate: an illegal call (fmi2Error) naming the call and the
    state; every variable kept; after fmi2Reset the instance runs like a fresh one."""
    s = h.scene(fmu, control=False)
    h.expect_status("fmi2Terminate", s.terminate(), OK)
    before = s.snapshot()
    mark = h.mark()
    h.expect_status(f"fmi2SetReal({name}) after fmi2Terminate", s.set(**{name: 1.0}), ERROR)
    h.expect_log("the message names the call and the state", mark, s, ("fmi2Set", "illegal call sequence",
                                                                        "terminated"))
    h.check("state", "every variable kept", s.values() == before["values"])
    h.expect_status("fmi2Reset", s.reset(), OK)
    ctrl = h.instance(fmu, "control")
    s.init(**SCENES[fmu][1])
    ctrl.init(**SCENES[fmu][1])
    h.expect_same_run("after fmi2Reset", s, ctrl)


for _fmu in WITH_VERTICAL:
    for _name in ("ag", "ag_v"):
        add(f"sequence/{SHORT[_fmu]}/setReal-{_name}-after-terminate", set_input_after_terminate, fmu=_fmu,
            name=_name, desc=f"{_fmu}: fmi2SetReal({_name}) after fmi2Terminate")


# ---------------------------------------------------------------------------------------------- value references
def vr_of(s: Inst, name: str) -> int:
    return s.vars[name].valueReference


def bad_reference(h: Harness, fmu: str, what: str):
    """Unknown, wrong-type or output references and fixed parameters after initialization: fmi2OK (all the
    wrapper can answer), an error naming the reference, the next step discarded once, the state kept."""
    s, ctrl = h.scene(fmu)
    out = {RIGID: "phi", FLEX: "u", STOREY: "a_floor", GMS: "ag"}[fmu]
    param = {RIGID: "b", FLEX: "EI", STOREY: "T", GMS: "A"}[fmu]
    actions = {
        "setReal-unknown": (lambda: s.set_vr("Real", [BAD_VR], [1.0]), (str(BAD_VR),)),
        "setReal-vr-2^32-1": (lambda: s.set_vr("Real", [2**32 - 1], [1.0]), (("4294967295", "-1"),)),
        "setInteger-unknown": (lambda: s.set_vr("Integer", [BAD_VR], [1]), (str(BAD_VR),)),
        "setBoolean-unknown": (lambda: s.set_vr("Boolean", [BAD_VR], [True]), (str(BAD_VR),)),
        "setReal-on-Integer": (lambda: s.set_vr("Real", [vr_of(s, "scheme")], [0.0]),
                               (str(vr_of(s, "scheme")) if "scheme" in s.vars else "", word("scheme"))),
        "setInteger-on-Real": (lambda: s.set_vr("Integer", [vr_of(s, param)], [1]), (word(param), "Integer")),
        "setBoolean-on-Real": (lambda: s.set_vr("Boolean", [vr_of(s, param)], [True]), (word(param), "Boolean")),
        "setReal-output": (lambda: s.set_vr("Real", [vr_of(s, out)], [0.5]), (word(out), "output")),
        "setInteger-output": (lambda: s.set_vr("Integer", [vr_of(s, "contact")], [3]), (word("contact"), "output")),
        "setBoolean-output": (lambda: s.set_vr("Boolean", [vr_of(s, "overturned")], [True]),
                              (word("overturned"), "output")),
        "setReal-fixed-after-init": (lambda: s.set(**{param: s.get(param) * 1.5 + 0.1}),
                                     (word(param), "fixed")),
        "setInteger-fixed-after-init": (lambda: s.set(scheme=0), (word("scheme"), "fixed")),
        "getReal-unknown": (lambda: s.get_vr("Real", [BAD_VR])[0], (str(BAD_VR),)),
        "getInteger-on-Real": (lambda: s.get_vr("Integer", [vr_of(s, out)])[0], (word(out), "Real")),
        "getBoolean-on-Integer": (lambda: s.get_vr("Boolean", [vr_of(s, "contact")])[0], (word("contact"),)),
    }
    action, fragments = actions[what]
    refusal(h, s, what, action, status=ERROR, fragments=fragments, control=ctrl)


for _fmu, _whats in ((RIGID, ("setReal-unknown", "setReal-vr-2^32-1", "setInteger-unknown", "setBoolean-unknown",
                              "setReal-on-Integer", "setInteger-on-Real", "setBoolean-on-Real", "setReal-output",
                              "setInteger-output", "setBoolean-output", "setReal-fixed-after-init",
                              "setInteger-fixed-after-init", "getReal-unknown", "getInteger-on-Real",
                              "getBoolean-on-Integer")),
                     (FLEX, ("setReal-unknown", "setReal-on-Integer", "setReal-output", "setReal-fixed-after-init")),
                     (STOREY, ("setReal-unknown", "setReal-output", "setReal-fixed-after-init", "getReal-unknown")),
                     (GMS, ("setReal-unknown", "setReal-output", "setReal-fixed-after-init", "getReal-unknown"))):
    for _what in _whats:
        add(f"vr/{SHORT[_fmu]}/{_what}", bad_reference, fmu=_fmu, what=_what, desc=f"{_fmu}: {_what}")


def fixed_same_value(h: Harness):
    """Setting a fixed parameter to its current value after initialization is not a change: no error, no
    discard."""
    s, ctrl = h.scene(RIGID)
    mark = h.mark()
    h.expect_status("fmi2SetReal(b = current value)", s.set(b=s.get("b")), OK)
    h.expect_no_log("no error", mark, s, ERROR)
    h.expect_same_run("steps on", s, ctrl)


add("vr/rigid/setReal-fixed-same-value", fixed_same_value, kinds=("status", "message", "state"),
    desc="RigidRockingBlock: a fixed parameter set to its own value after initialization (allowed)")


def batch_set_mixed(h: Harness, fmu: str):
    """setReal([b, scheme, h]) in initialization mode: scheme is an Integer, so the call is fmi2Error and
    nothing of it is set (b and h keep their start values); fmi2Reset, then the instance runs like one
    initialized with those values."""
    s = h.instance(fmu)
    s.setup()
    s.enter()
    vrs = [vr_of(s, "b"), vr_of(s, "scheme"), vr_of(s, "h")]
    start = (s.get("b"), s.get("h"), s.get("scheme"))
    mark = h.mark()
    h.expect_status("fmi2SetReal([b, scheme, h])", s.set_vr("Real", vrs, [0.25, 0.0, 1.2]), ERROR)
    h.expect_log("the message names the refused reference", mark, s, (str(vrs[1]), word("scheme")))
    got = (s.get("b"), s.get("h"), s.get("scheme"))
    h.check("state", "nothing set", got == start, got)
    h.expect_status("fmi2Reset", s.reset(), OK)
    s.init(b=0.25, h=1.2)
    ctrl = h.instance(fmu, "control")
    ctrl.init(b=0.25, h=1.2)
    h.expect_same_run("then the instance runs with b and h set", s, ctrl, 10)


for _fmu in (RIGID, FLEX):
    add(f"vr/{SHORT[_fmu]}/setReal-batch-good-bad-good", batch_set_mixed, fmu=_fmu,
        desc=f"{_fmu}: fmi2SetReal([b, scheme, h]) in initialization mode")


def batch_get_mixed(h: Harness, fmu: str):
    """getReal([good, bad, good]): fmi2Error naming the bad reference; the instance's values are kept."""
    s, ctrl = h.scene(fmu)
    # two Real variables, outputs first (GroundMotionSource has one Real output: a parameter joins it)
    names = list(dict.fromkeys(n for n in s.output_names + s.value_names if s.vars[n].type == "Real"))[:2]
    vrs = [vr_of(s, names[0]), BAD_VR, vr_of(s, names[1])]
    refusal(h, s, "fmi2GetReal([good, bad, good])", lambda: s.get_vr("Real", vrs)[0], status=ERROR,
            fragments=(str(BAD_VR),), control=ctrl)


for _fmu in FMUS:
    add(f"vr/{SHORT[_fmu]}/getReal-batch-good-bad-good", batch_get_mixed, fmu=_fmu,
        desc=f"{_fmu}: fmi2GetReal with one unknown reference among good ones")


def nvr_zero(h: Harness, fmu: str):
    s, ctrl = h.scene(fmu)
    before = s.snapshot()
    mark = h.mark()
    for type_name in ("Real", "Integer", "Boolean", "String"):
        h.expect_status(f"fmi2Set{type_name} with nvr = 0", s.set_vr(type_name, [], []), OK)
        h.expect_status(f"fmi2Get{type_name} with nvr = 0", s.get_vr(type_name, [])[0], OK)
    h.expect_no_log("no message", mark, s, WARNING)
    h.expect_same("state kept", before, s.snapshot())
    h.expect_same_run("the next step is not discarded", s, ctrl)


for _fmu in (RIGID, GMS):
    add(f"vr/{SHORT[_fmu]}/nvr=0", nvr_zero, fmu=_fmu, desc=f"{_fmu}: every setter and getter with nvr = 0")


# ---------------------------------------------------------------------------------------------- strings
def string_calls(h: Harness, fmu: str, what: str):
    """fmi2SetString / fmi2GetString on FMUs without (or with) String variables: never fmi2Fatal, never a
    crash; a wrong reference is logged with its number, the next step discarded once, the state kept."""
    s, ctrl = h.scene(fmu)
    vr0 = 0
    actions = {
        "setString-vr0": (lambda: s.set_vr("String", [vr0], ["x"]), (f"value reference {vr0}", "String")),
        "getString-vr0": (lambda: s.get_vr("String", [vr0])[0], (f"value reference {vr0}", "String")),
        "setString-unknown": (lambda: s.set_vr("String", [BAD_VR], ["x"]), (str(BAD_VR),)),
        "getString-unknown": (lambda: s.get_vr("String", [BAD_VR])[0], (str(BAD_VR),)),
        "setString-on-Real": (lambda: s.set_vr("String", [vr_of(s, "A")], ["1.0"]), (word("A"), "String")),
        "setString-record-after-init": (lambda: s.set(record="synthetic:3"), (word("record"), "fixed")),
    }
    action, fragments = actions[what]
    refusal(h, s, what, action, status=ERROR, fragments=fragments, control=ctrl)


for _fmu in FMUS:
    for _what in ("setString-vr0", "getString-vr0", "setString-unknown", "getString-unknown") if _fmu != GMS \
            else ("setString-unknown", "getString-unknown", "setString-on-Real", "setString-record-after-init"):
        add(f"string/{SHORT[_fmu]}/{_what}", string_calls, fmu=_fmu, what=_what, desc=f"{_fmu}: {_what}")


def string_too_long_before_init(h: Harness):
    s = h.instance(GMS)
    s.setup()
    s.enter()
    mark = h.mark()
    h.expect_status("fmi2SetString(record = 100000 characters)", s.set(record="x" * 100_000), ERROR)
    h.expect_log("refused with a message naming record", mark, s, (word("record"),))
    h.check("state", "record keeps its value", s.get("record") in ("", b""), repr(s.get("record"))[:80])
    h.expect_status("fmi2Reset out of the error state", s.reset(), OK)


add("string/ground/setString-too-long", string_too_long_before_init, kinds=("status", "message", "state"),
    desc="GroundMotionSource: a 100000-character record")


def string_roundtrip(h: Harness):
    s = h.instance(GMS)
    s.setup()
    s.enter()
    value = str(h.workdir / "dir é #[%]" / "rec %s%n.csv")
    mark = h.mark()
    h.expect_status("fmi2SetString(record)", s.set(record=value), OK)
    got = s.get("record")
    got = got.decode("utf-8") if isinstance(got, bytes) else got
    h.check("state", "fmi2GetString returns the string set (UTF-8, '%' kept)", got == value, [got, value])
    h.expect_no_log("no message", mark, s, WARNING)


add("string/ground/record-roundtrip", string_roundtrip, kinds=("status", "message", "state"),
    desc="GroundMotionSource: fmi2SetString / fmi2GetString of a record path with é, #, [, %")


def percent_in_record(h: Harness, pattern: str, logging: bool):
    """A record name full of printf conversions reaches the importer's logger (formatted by fmpy's native
    proxy) as plain text: no crash, the '%' characters shown literally."""
    s = h.instance(GMS, logging=logging)
    s.setup()
    s.enter()
    record = f"/x/{pattern}"
    s.set(motion=1, record=record)
    mark = h.mark()
    h.expect_status("fmi2ExitInitializationMode with a missing record", s.exit(), ERROR)
    h.expect_log(f"the message shows the record name literally (logging {'on' if logging else 'off'})", mark, s,
                 (record,))
    h.check("status", "fmi2DoStep afterwards not fmi2OK", s.step() not in (OK, -1))
    h.expect_status("fmi2Reset", s.reset(), OK)
    s.init()
    ctrl = h.instance(GMS, "control", logging=logging)
    ctrl.init()
    h.expect_same_run("after fmi2Reset", s, ctrl)


for _pat, _log in (("%s%s%s%s", True), ("%n%n%n%n", True), ("%s%s%s%s", False), ("%08x%08x%08x%p%p", True)):
    add(f"string/ground/record={_pat}-logging-{'on' if _log else 'off'}", percent_in_record, pattern=_pat,
        logging=_log, kinds=("status", "message", "state"),
        desc=f"GroundMotionSource: record = '/x/{_pat}', loggingOn = {_log}")


def non_utf8_string(h: Harness):
    from fmpy.fmi2 import fmi2String, fmi2ValueReference

    s, ctrl = h.scene(GMS)
    vrs = (fmi2ValueReference * 1)(vr_of(s, "record"))
    vals = (fmi2String * 1)(b"\xff\xfe\x80 not UTF-8")
    refusal(h, s, "fmi2SetString(non-UTF-8)",
            lambda: s.call("fmi2SetString(non-UTF-8)", s.fmu.fmi2SetString, s.fmu.component, vrs, 1, vals),
            status=ERROR, fragments=("fmi2SetString", ("utf-8", "decode")), control=ctrl)


add("string/ground/setString-non-utf8", non_utf8_string,
    desc="GroundMotionSource: fmi2SetString with bytes that are not UTF-8")


# ---------------------------------------------------------------------------------------------- bounded work
def bounded(h: Harness, fmu: str, params: dict, ag: Optional[float], dt: float, may_succeed: bool,
            refusable: Optional[str] = None):
    """A step that used to hang: it finishes in bounded time, either refused at initialization (fmi2Fatal
    (fmi2Error and a message naming ``refusable``, a parameter outside the narrowed range) or fmi2Discard with a message
    naming the cause and the way out (internal step limit), the state unchanged -- or, where physics allows
    (``may_succeed``: the structure overturns and freezes, or comes to rest), fmi2OK with finite outputs."""
    s = h.instance(fmu)
    s.setup()
    s.enter()
    s.set(**params)
    mark = h.mark()
    t0 = time.perf_counter()
    st = s.exit()
    h.figure("exitInitializationMode_s", time.perf_counter() - t0)
    if st == ERROR and refusable is not None:
        h.check("status", f"refused at initialization (fmi2Error): {refusable} outside its range", True)
        fragments = (word(refusable), "allowed")
        h.expect_log("the message names the parameter and its range", mark, s, fragments)
        after_error(h, s, fmu)
        return
    h.expect_status("fmi2ExitInitializationMode" + (f" (or fmi2Error naming {refusable})" if refusable else ""),
                    st, OK)
    if st != OK:
        return
    if ag is not None:
        s.set(ag=ag)
    before = s.snapshot()
    mark = h.mark()
    t0 = time.perf_counter()
    st = s.step(dt)
    elapsed = time.perf_counter() - t0
    h.figure("doStep_s", elapsed)
    if st in (OK, WARNING) and may_succeed:          # done: the structure overturned or came to rest
        vals = s.outputs()
        bad = {k: v for k, v in vals.items() if isinstance(v, str) and v.lstrip("-") in ("nan", "inf")}
        # fmi2OK, not fmi2Warning: an overturning is an event of the motion (logged with fmi2OK, logEvents)
        h.check("status", "fmi2OK with finite outputs", st == OK and not bad,
                {"status": STATUS_NAMES.get(st), **bad} if st != OK or bad else None)
        h.check("message", "(no refusal: no message needed)", True)
        h.check("state", "(no refusal: state moved on legitimately)", True)
        return
    h.expect_status("fmi2DoStep: fmi2Discard (bounded work)" + (" or fmi2OK" if may_succeed else ""), st,
                    (DISCARD, OK) if may_succeed else DISCARD)
    h.expect_log("the message names the cause and the way out", mark, s,
                 (("limit", "budget", "range", "allowed"),
                  ("shorter", "smaller", "reduce", "split", "retry", "increase", "larger", "allowed")))
    h.expect_same("state unchanged", before, s.snapshot())


HANGS = [  # id, FMU, start values, ag [m/s2], step [s], fmi2OK allowed, parameter that may be refused at init
    ("MJ-doStep-1e12", RIGID, {"scheme": 0}, 0.0, 1e12, False, None),
    ("MJ-doStep-1e308", RIGID, {"scheme": 0}, 0.0, 1e308, False, None),
    ("flex-MJ-doStep-1e12", FLEX, {"scheme": 0}, 0.0, 1e12, False, None),
    # constant ag = 5 m/s2 overturns the oscillator (outputs freeze): fmi2OK is physics, in bounded time
    ("flex-ED-ag=5-doStep-1e12", FLEX, {"scheme": 1}, 5.0, 1e12, True, None),
    ("flex-ED-ag=1-doStep-1e12", FLEX, {"scheme": 1}, 1.0, 1e12, True, None),
    ("flex-ED-ag=-1-rocking-doStep-1e12", FLEX, {"scheme": 1, "phi_0": 0.02}, -1.0, 1e12, True, None),
    ("rigid-ED-phi0-doStep-1e12", RIGID, {"scheme": 1, "phi_0": 0.05, "e_N": 0.0}, 0.0, 1e12, True, None),
    ("MJ-dt_max=1e-300", RIGID, {"scheme": 0, "dt_max": 1e-300}, 0.0, DT, False, "dt_max"),
    ("flex-MJ-dt_max=1e-300", FLEX, {"scheme": 0, "dt_max": 1e-300}, 0.0, DT, False, "dt_max"),
    ("ED-dt_max=1e-9", RIGID, {"scheme": 1, "dt_max": 1e-9}, 3.0, 1.0, False, "dt_max"),
    ("flex-ED-dt_max=1e-9", FLEX, {"scheme": 1, "dt_max": 1e-9}, 3.0, 1.0, False, "dt_max"),
    ("flex-EI=1e15", FLEX, {"EI": 1e15}, 3.0, DT, False, "EI"),
    ("flex-MJ-EI=1e15", FLEX, {"EI": 1e15, "scheme": 0}, 3.0, DT, False, "EI"),
    ("flex-ED-ag=1000-doStep-1", FLEX, {"scheme": 1}, 1000.0, 1.0, True, None),
    ("flex-MJ-ag=-1000-doStep-1", FLEX, {"scheme": 0}, -1000.0, 1.0, True, None),
    ("rigid-ED-ag=1000-doStep-1", RIGID, {"scheme": 1}, 1000.0, 1.0, True, None),
    ("rigid-MJ-ag=999-doStep-10", RIGID, {"scheme": 0, "b": 1.0, "h": 1.0}, 999.0, 10.0, True, None),
    ("storey-doStep-1e12", STOREY, {}, 1.0, 1e12, True, None),
    ("ground-doStep-1e12", GMS, {}, None, 1e12, True, None),
]
for _cid, _fmu, _params, _ag, _dt, _ok, _ref in HANGS:
    add(f"bounded/{_cid}", bounded, fmu=_fmu, params=_params, ag=_ag, dt=_dt, may_succeed=_ok, refusable=_ref,
        desc=f"{_fmu} {_params}, ag = {_ag}, doStep of {_dt:g} s")


def flex_ag_huge(h: Harness, value: float):
    """ag = 1.8e308 on the flexible oscillator, event-driven (used to hang; the literal 1.8e308 is inf in
    binary64, so the largest finite double 1.797...e308 is tried too): refused by the input range."""
    s, ctrl = h.scene(FLEX)
    t0 = time.perf_counter()
    refusal(h, s, f"fmi2SetReal(ag = {value!r})", lambda: s.set(ag=value), status=ERROR, fragments=(word("ag"),),
            control=ctrl)
    h.figure("elapsed_s", time.perf_counter() - t0)


add("bounded/flex-ED-ag=DBL_MAX", flex_ag_huge, value=sys.float_info.max,
    desc="FlexibleRockingOscillator event-driven, ag = 1.797e308 (the hang once found was at ag = 1.8e308, which is inf in "
         "binary64: input/flex/ag=inf)")


# ---------------------------------------------------------------------------------------------- FMU state API
def state_roundtrip(h: Harness, fmu: str):
    """save, step, restore, step: bit-identical outputs and states."""
    s = h.scene(fmu, control=False)
    st, state = s.get_state()
    h.expect_status("fmi2GetFMUstate", st, OK)
    at_save = s.snapshot()
    k, t = s.k, s.t
    rows = []
    for _ in range(10):
        h.expect_status("valid step", s.drive_step(), OK)
        rows.append(s.outputs())
    h.expect_status("fmi2SetFMUstate", s.set_state(state), OK)
    s.k, s.t = k, t
    h.expect_same("restored state equals the saved one", at_save, s.snapshot())
    again = []
    for _ in range(10):
        s.drive_step()
        again.append(s.outputs())
    first = next((i for i, (a, b) in enumerate(zip(rows, again)) if a != b), None)
    h.check("state", "the redone steps are bit-identical", again == rows,
            None if first is None else {"step": first + 1, "differ": _dict_diff(rows[first], again[first])})
    h.check("message", "no error logged", not h.messages_since(0, s), [m["message"] for m in h.messages_since(0, s)])
    h.expect_status("fmi2FreeFMUstate", s.free_state(state), OK)


def state_across_instances(h: Harness, fmu: str):
    """serialize in one instance, deserialize and set in another (initialized with other parameters)."""
    s = h.scene(fmu, control=False)
    st, state = s.get_state()
    st2, blob = s.serialize(state)
    h.expect_status("fmi2GetFMUstate + fmi2SerializeFMUstate", max(st, st2), OK)
    h.figure("state_bytes", len(blob))
    other = h.instance(fmu, "other")
    other.init()
    other.drive(3)
    st, restored = other.deserialize(blob)
    h.expect_status("fmi2DeSerializeFMUstate", st, OK)
    h.expect_status("fmi2SetFMUstate", other.set_state(restored), OK)
    other.k, other.t = s.k, s.t
    h.expect_same("the other instance holds the state", s.snapshot(), other.snapshot())
    h.expect_same_run("both step on identically", s, other, 10)
    h.check("message", "no error logged", not h.messages_since(0), [m["message"] for m in h.messages_since(0)])


for _fmu in FMUS:
    add(f"state/{SHORT[_fmu]}/get-set-roundtrip", state_roundtrip, fmu=_fmu,
        desc=f"{_fmu}: fmi2GetFMUstate, steps, fmi2SetFMUstate, the same steps")
    add(f"state/{SHORT[_fmu]}/serialize-across-instances", state_across_instances, fmu=_fmu,
        desc=f"{_fmu}: serialize in one instance, deserialize in another")


def get_state_twice(h: Harness, n: int = 3000):
    """fmi2GetFMUstate onto the same (non-NULL) state pointer again and again: no crash, the last state is
    valid. The wrapper overwrites the pointer without releasing the old state (memory growth measured)."""
    from fmpy.fmi2 import fmi2FMUstate

    s = h.scene(RIGID, control=False)
    state = fmi2FMUstate()
    st = s.call("fmi2GetFMUstate", s.fmu.fmi2GetFMUstate, s.fmu.component, ctypes.byref(state))
    for _ in range(50):  # warm-up (allocator pools)
        s.fmu.fmi2GetFMUstate(s.fmu.component, ctypes.byref(state))
    rss0 = rss_bytes()
    worst = OK
    for _ in range(n):
        worst = max(worst, s.fmu.fmi2GetFMUstate(s.fmu.component, ctypes.byref(state)))
    growth = (rss_bytes() - rss0) / n
    h.figure("rss_growth_bytes_per_call", round(growth, 1))
    h.expect_status(f"{n} x fmi2GetFMUstate onto the same pointer", max(st, worst), OK)
    at = s.snapshot()
    s.drive(5)
    h.expect_status("fmi2SetFMUstate of the last one", s.set_state(state), OK)
    h.expect_same("the last state is valid", at, s.snapshot())
    h.check("message", "no error logged", not h.messages_since(0, s), [m["message"] for m in h.messages_since(0, s)])
    h.expect_status("fmi2FreeFMUstate", s.free_state(state), OK)


add("state/rigid/getFMUstate-same-pointer", get_state_twice, timeout=60,
    desc="RigidRockingBlock: fmi2GetFMUstate 3000 times onto one state pointer (memory measured)")


def free_state_reuse(h: Harness):
    s = h.scene(RIGID, control=False)
    st, state = s.get_state()
    h.expect_status("fmi2FreeFMUstate", s.free_state(state), OK)
    # FMI 2.0 asks fmi2FreeFMUstate to set the pointer to NULL; the pythonfmu 0.7 wrapper leaves it dangling
    # (recorded, not asserted: no Python code can reach the importer's pointer)
    h.figure("pointer_nulled_by_free", not state.value)
    st, state = s.get_state()
    at = s.snapshot()
    s.drive(3)
    h.expect_status("fmi2GetFMUstate into the freed pointer, then fmi2SetFMUstate", max(st, s.set_state(state)), OK)
    h.expect_same("restored", at, s.snapshot())
    h.check("message", "no error logged", not h.messages_since(0, s), [m["message"] for m in h.messages_since(0, s)])


add("state/rigid/free-then-reuse", free_state_reuse, desc="fmi2FreeFMUstate, then the pointer reused")


def state_size_per_impact(h: Harness, fmu: str, params: dict, amplitude: float, n: int):
    """The serialized state does not grow with the number of impacts (bounded impact log)."""
    s = h.instance(fmu)
    s.init(**params)
    s.amplitude = amplitude
    sizes = []
    for k in range(n):
        s.drive_step() if k < 100 else s.step()
        if k % 25 == 0 or k == n - 1:
            data, problem = s.state_bytes()
            sizes.append((s.get("impacts"), len(data), problem))
    (i0, b0, _), (i1, b1, p1) = sizes[1], sizes[-1]
    per_impact = (b1 - b0) / max(1, i1 - i0)
    h.figure("state_bytes", b1)
    h.figure("impacts", i1)
    h.figure("bytes_per_impact", round(per_impact, 3))
    h.check("state", f"a scene with many impacts ({i1 - i0} between the samples)", i1 - i0 >= 30, sizes)
    h.check("state", "state valid", b1 > 0 and p1 is None, p1)
    h.check("state", "the state does not grow with impacts (< 1 byte per impact, digits of the counters only)",
            b1 > 0 and per_impact < 1.0, {"bytes_per_impact": per_impact, "samples (impacts, bytes)": sizes})
    h.check("status", "every step OK", all(c["status"] == OK for c in h.calls if c["call"] == "fmi2DoStep"))


add("state/rigid/size-per-impact", state_size_per_impact, fmu=RIGID, params={"e_N": 0.8, "phi_0": 0.15},
    amplitude=0.0, n=400, kinds=("status", "state"),
    desc="RigidRockingBlock: serialized state size over a bouncing scene with many impacts")
add("state/flex/size-per-impact", state_size_per_impact, fmu=FLEX, params={"e_N": 0.8, "phi_0": 0.1},
    amplitude=0.0, n=300, kinds=("status", "state"),
    desc="FlexibleRockingOscillator: serialized state size over a scene with many impacts")


def serialize_small_buffer(h: Harness):
    """fmi2SerializeFMUstate with a size smaller than fmi2SerializedFMUstateSize: fmi2Error naming the sizes,
    nothing written into the buffer; a good state leaves the error state; truncated bytes are refused by
    fmi2SetFMUstate."""
    s, ctrl = h.scene(RIGID)
    st, state = s.get_state()
    size = ctypes.c_size_t()
    s.fmu.fmi2SerializedFMUstateSize(s.fmu.component, state, ctypes.byref(size))
    short = max(0, size.value - 16)
    guard = b"\xa5" * 256
    buf = ctypes.create_string_buffer(b"\x00" * short + guard, short + len(guard))
    mark = h.mark()
    st = s.call("fmi2SerializeFMUstate(short buffer)", s.fmu.fmi2SerializeFMUstate, s.fmu.component, state, buf,
                short)
    h.expect_status("fmi2SerializeFMUstate with a short size", st, ERROR)
    h.expect_log("the message names the size", mark, s, ("size", str(short)))
    h.check("state", "nothing written", buf.raw == b"\x00" * short + guard, buf.raw[:32].hex())
    h.expect_status("fmi2SetFMUstate of a good state leaves the error state", s.set_state(state), OK)
    s.free_state(state)
    truncated = s.state_bytes()[0][:-16]
    refusal(h, s, "fmi2SetFMUstate of the truncated bytes",
            lambda: max(s.deserialize(truncated)[0], s.set_state(s.deserialize(truncated)[1])),
            status=ERROR, fragments=(("rejected", "not a serialized state"), ("truncated", "bytes", "length")),
            control=ctrl)


add("state/rigid/serialize-short-buffer", serialize_small_buffer,
    desc="fmi2SerializeFMUstate into a buffer 16 bytes short")


# ---------------------------------------------------------------------------------------------- bad states
class _Gadget:
    def __reduce__(self):
        return (os.system, (f"touch {PWNED}",))


def _short_unicode(s: str) -> bytes:
    b = s.encode()
    return b"\x8c" + bytes([len(b)]) + b


def old_v1(payload: bytes) -> bytes:
    return b"rocking_model FMU state v1\n" + hashlib.sha256(payload).digest() + payload


def gadget_direct() -> bytes:
    return old_v1(pickle.dumps(_Gadget(), protocol=5))


def gadget_via_fmi() -> bytes:
    """rocking_model.fmi -> pickle.loads(<gadget>): a global under rocking_model.* (what the old restricted
    unpickler allowed) reaching the unrestricted loader."""
    inner = pickle.dumps(_Gadget(), protocol=2)
    body = (b"\x80\x04" + _short_unicode("rocking_model.fmi") + _short_unicode("pickle.loads") + b"\x93"
            + b"B" + struct.pack("<I", len(inner)) + inner + b"\x85" + b"R" + b".")
    return old_v1(body)


def _new_header(payload: bytes, version: int = 1, n: Optional[int] = None, digest: Optional[bytes] = None) -> bytes:
    return (struct.pack("<24sII32s", b"rocking_model FMU state\n", version, len(payload) if n is None else n,
                        hashlib.sha256(payload).digest() if digest is None else digest) + payload)


def _junk(doc: dict, what: str):
    """Mutate a decoded valid state document; return (doc, fragments)."""
    sl = doc["slave"]
    sim = doc.get("simulator")
    if what == "t=nan":
        sl["t"] = math.nan
        return doc, (("slave.t", "time"),)
    if what == "initialized-string":
        sl["initialized"] = "yes"
        return doc, ("initialized",)
    if what == "value-wrong-type":
        key = next(iter(sl["values"]))
        sl["values"][key] = "abc"
        return doc, (word(key),)
    if what == "value-missing":
        key = next(iter(sl["values"]))
        del sl["values"][key]
        return doc, (word(key), "missing")
    if what == "extra-key":
        doc["evil"] = {"__reduce__": "os.system"}
        return doc, ("evil",)
    if what == "signature":
        doc["signature"] = "0" * 64
        return doc, (("belongs", "signature", "version"),)
    if what == "pending-huge":
        sl["pending"] = "x" * 200_000
        return doc, ("pending",)
    if not isinstance(sim, dict):
        raise HarnessError(f"the state has no simulator object to corrupt ({type(sim).__name__})")
    flat = [(k, v) for k, v in sim.items()]
    if what == "array-length":
        key = next((k for k, v in flat if isinstance(v, list) and v and all(isinstance(x, (int, float)) for x in v)),
                   None)
        if key is None:
            raise HarnessError(f"no numeric array field in the simulator state: {sorted(sim)}")
        sim[key] = sim[key] + [0.0]
        return doc, (word(key),)
    if what == "array-wrong-type":
        key = next((k for k, v in flat if isinstance(v, list) and v), None)
        if key is None:
            raise HarnessError(f"no array field in the simulator state: {sorted(sim)}")
        sim[key] = ["x"] * len(sim[key])
        return doc, (word(key),)
    if what == "mode=10":
        key = next((k for k in ("mode", "contact") if k in sim), None)
        if key is None:
            raise HarnessError(f"no contact-mode field in the simulator state: {sorted(sim)}")
        sim[key] = 10
        return doc, (word(key),)
    if what in ("negative-impacts", "negative-n_steps"):
        key = what.split("-", 1)[1]
        if not isinstance(sim.get(key), int):
            raise HarnessError(f"no integer counter {key!r} in the simulator state: {sorted(sim)}")
        sim[key] = -5
        return doc, (word(key),)
    if what == "sim-nan":
        key = next((k for k, v in flat if isinstance(v, float)), None)
        if key is None:
            raise HarnessError(f"no float field in the simulator state: {sorted(sim)}")
        sim[key] = math.nan
        return doc, (word(key),)
    raise ValueError(what)


def bad_state(h: Harness, what: str, fmu: str = RIGID):
    """A state that must be rejected: fmi2SetFMUstate answers fmi2Error, the error names what is wrong,
    nothing is executed, the instance keeps its state (a good state can be set afterwards)."""
    s, ctrl = h.scene(fmu)
    full, problem = s.state_bytes()
    valid = slave_bytes(full)
    header = full[:len(full) - len(valid)]
    fragments: Sequence = ()
    if what == "pickle-gadget":
        data, fragments = gadget_direct(), ("header",)
    elif what == "pickle-gadget-via-rocking_model.fmi":
        data, fragments = gadget_via_fmi(), ("header",)
    elif what == "pickle-in-new-header":
        data, fragments = _new_header(pickle.dumps(_Gadget(), protocol=5)), ("JSON",)
    elif what == "random-bytes":
        data, fragments = random.Random(12).randbytes(4096), (("header", "bytes"),)
    elif what == "random-bytes-short":
        data, fragments = random.Random(13).randbytes(10), (("header", "bytes"),)
    elif what == "empty":
        data, fragments = b"", (("header", "0 bytes", "empty"),)
    elif what == "nul-bytes":
        data, fragments = b"\0" * 200, (("header",),)
    else:
        if problem is not None or not valid:
            raise HarnessError(f"the FMU does not produce a valid state to corrupt: {problem}")
        from rocking_model.fmi_state import decode_state, encode_state

        if what == "truncated":
            data, fragments = valid[:len(valid) // 2], (("truncated", "declares", "bytes"),)
        elif what == "truncated-header":
            data, fragments = valid[:40], (("truncated", "header", "bytes"),)
        elif what == "byte-flipped":
            i = len(valid) - 20
            data, fragments = valid[:i] + bytes([valid[i] ^ 0x01]) + valid[i + 1:], (("corrupted", "SHA"),)
        elif what == "magic-flipped":
            data, fragments = bytes([valid[0] ^ 0x20]) + valid[1:], ("header",)
        elif what == "version=2":
            data, fragments = valid[:24] + struct.pack("<I", 2) + valid[28:], ("version",)
        elif what == "version=0":
            data, fragments = valid[:24] + struct.pack("<I", 0) + valid[28:], ("version",)
        elif what == "length-huge":
            data, fragments = valid[:28] + struct.pack("<I", 2**32 - 1) + valid[32:], (("at most", "declares"),)
        elif what == "padded":
            data, fragments = valid + b"\0" * 64, (("padded", "declares", "bytes"),)
        elif what == "other-fmu":
            other = h.instance(FLEX if fmu != FLEX else RIGID, "other")
            other.init()
            other.drive(3)
            data, fragments = other.state_bytes()[0], (("belongs", FLEX if fmu != FLEX else RIGID),)
        elif what == "json-not-object":
            data, fragments = _new_header(b"[1, 2, 3]"), ("object",)
        elif what == "json-invalid":
            data, fragments = _new_header(b"{\"fmu\": "), ("JSON",)
        elif what == "json-deep":
            data, fragments = _new_header(b"[" * 100_000 + b"]" * 100_000), (("nest", "deep", "JSON"),)
        elif what == "payload-2MiB":
            body = json.dumps({"x": "y" * (2 << 20)}).encode()
            data, fragments = _new_header(body), (("at most", "bytes"),)
        else:
            doc, fragments = _junk(decode_state(valid), what)
            data = encode_state(doc) if what != "pending-huge" else _new_header(json.dumps(doc).encode())
    h.figure("bytes", len(data))

    def action():
        st1, state = s.deserialize(data)
        st2 = s.set_state(state)
        s.free_state(state)
        return max(st1, st2)

    if what != "other-fmu":  # the slave's bytes behind the binary's valid header (FMI state and time)
        data = with_binary_header(header, data)
    refusal(h, s, f"state '{what}'", action, status=ERROR, fragments=("rejected",) + tuple(fragments),
            control=ctrl)
    h.check("state", "nothing was executed (no file 'pwned' in the working directory)",
            not (h.workdir / PWNED).exists(), sorted(os.listdir(h.workdir)))


for _what in ("pickle-gadget", "pickle-gadget-via-rocking_model.fmi", "pickle-in-new-header", "random-bytes",
              "random-bytes-short", "empty", "nul-bytes", "truncated", "truncated-header", "byte-flipped",
              "magic-flipped", "version=2", "version=0", "length-huge", "padded", "other-fmu", "json-not-object",
              "json-invalid", "json-deep", "payload-2MiB", "t=nan", "initialized-string", "value-wrong-type",
              "value-missing", "extra-key", "signature", "pending-huge", "array-length", "array-wrong-type",
              "mode=10", "negative-impacts", "negative-n_steps", "sim-nan"):
    add(f"badstate/rigid/{_what}", bad_state, what=_what, desc=f"RigidRockingBlock: FMU state '{_what}'")
for _fmu in (FLEX, STOREY, GMS):
    for _what in ("pickle-gadget-via-rocking_model.fmi", "other-fmu", "value-wrong-type"):
        add(f"badstate/{SHORT[_fmu]}/{_what}", bad_state, what=_what, fmu=_fmu, desc=f"{_fmu}: FMU state '{_what}'")


# ---------------------------------------------------------------------------------------------- declared values
#: fragments of LAPACK's error printout (xerbla), which a library must never write into its host's output
LAPACK_NOISE = ("illegal value", "DLASCL", "On entry to")


def _message_range(message: str):
    """(lo, hi) of the first "allowed range [lo, hi]" (or open brackets) in ``message``, as floats; None."""
    m = re.search(r"allowed range [\[(]([^,\]]+), ([^\])]+)[\])]", message)
    if not m:
        return None
    try:
        return float(m.group(1)), float(m.group(2))
    except ValueError:
        return None


def _declared(h: Harness, fmu: str, name: str):
    var = next(v for v in h.md(fmu).modelVariables if v.name == name)
    return (None if var.min is None else float(var.min)), (None if var.max is None else float(var.max))


def _no_lapack_noise(h: Harness) -> None:
    """The case's own stdout/stderr (files in its working directory, written by the forked child) carry no
    LAPACK error printout."""
    found = []
    for fname in ("stdout.txt", "stderr.txt"):
        path = h.workdir / fname
        if path.exists():
            sys.stdout.flush()
            sys.stderr.flush()
            text = path.read_text(errors="replace")
            found += [f"{fname}: {line[:160]}" for line in text.splitlines() if any(n in line for n in LAPACK_NOISE)]
    h.check("message", "no LAPACK error printout in the host's output", not found, found[:5] or None)


def declared_refused(h: Harness, fmu: str, name: str, value, params: Optional[dict] = None):
    """A value outside the range its modelDescription declares (or at the edge of the floating-point range,
    where the numerics fail): refused at fmi2ExitInitializationMode with fmi2Error, and the range the message
    states is the declared one (min and max of the modelDescription): the declaration, the check and the
    message agree."""
    lo, hi = _declared(h, fmu, name)
    s = h.instance(fmu)
    s.setup()
    s.enter()
    s.set(**(params or {}), **{name: value})
    mark = h.mark()
    h.expect_status(f"fmi2ExitInitializationMode with {name} = {value!r}", s.exit(), ERROR)
    h.expect_log("the message names the variable and its allowed range", mark, s, (word(name), "allowed range"))
    got = [_message_range(m["message"]) for m in h.messages_since(mark, s)]
    got = [r for r in got if r is not None]
    want = (-math.inf if lo is None else lo, math.inf if hi is None else hi)
    h.check("message", f"the range in the message is the declared one (modelDescription min = {lo}, max = {hi})",
            bool(got) and got[0] == want, {"message": got, "declared": want})
    h.check("status", f"the value is outside the declared range [{lo}, {hi}]",
            (lo is not None and value < lo) or (hi is not None and value > hi), None)
    _no_lapack_noise(h)
    after_error(h, s, fmu)


for _fmu in (RIGID, FLEX):
    for _scheme in (0, 1):
        add(f"declared/{SHORT[_fmu]}/mu=5e-324-scheme={_scheme}", declared_refused, fmu=_fmu, name="mu",
            value=5e-324, params={"scheme": _scheme},
            desc=f"{_fmu}: mu = 5e-324 (1/mu = inf: used to hang the event-driven step in LAPACK), scheme {_scheme}")
    for _v in (2**31 - 1, 10**9 + 1):
        add(f"range/{SHORT[_fmu]}/max_steps={_v}", declared_refused, fmu=_fmu, name="max_steps", value=_v,
            desc=f"{_fmu}: max_steps = {_v}, beyond its declared max")


def _edges():
    """(FMU, parameter, value) for the two edges of every declared Real parameter of the rocking FMUs (a closed
    bound itself, an open one's nearest double inside, a missing one 1e300; a range closed at 0 also the
    smallest positive double, whose reciprocal is inf), from the same declarations the FMUs are built from."""
    from rocking_model.models import FlexibleOscillator, PostTensionedBlock, RigidBlock
    from rocking_model.simulation import SOLVER_PARAMETERS

    out = []
    for fmu, cls in ((RIGID, RigidBlock), (FLEX, FlexibleOscillator), (PT, PostTensionedBlock)):
        for q in (*cls.parameters(), *cls.INITIAL, *SOLVER_PARAMETERS):
            if q.items or not q.fmu or q.unit is None:
                continue
            if fmu == PT and q.name not in ("P0", "k_t"):
                continue         # the rigid block's parameters, initial values and solver options: its cases
            lo = -1e300 if q.lo is None else (math.nextafter(q.lo, math.inf) if q.lo_open else q.lo)
            hi = 1e300 if q.hi is None else (math.nextafter(q.hi, -math.inf) if q.hi_open else q.hi)
            tiny = (5e-324,) if lo == 0.0 else ()
            for v in dict.fromkeys((lo, *tiny, hi)):
                out.append((fmu, q.name, v))
    return out


def declared_edge(h: Harness, fmu: str, name: str, value: float, scheme: int):
    """A parameter at an edge of its declared range: either refused at initialization (fmi2Error, a message
    naming it) or the scene's steps run in bounded time (the case's timeout) with fmi2OK / fmi2Warning, or
    fmi2Discard with a message; outputs finite; no LAPACK printout in the host's output."""
    s = h.instance(fmu)
    s.setup()
    s.enter()
    s.set(scheme=scheme, **{name: value})
    mark = h.mark()
    st = s.exit()
    if st == ERROR:
        h.check("status", f"refused at initialization (fmi2Error)", True)
        h.expect_log("the message names the parameter", mark, s, (word(name),))
        _no_lapack_noise(h)
        return
    h.expect_status("fmi2ExitInitializationMode (or fmi2Error naming the parameter)", st, OK)
    if st != OK:
        return
    statuses = []
    for _ in range(N_BEFORE):
        mark = h.mark()
        st = s.drive_step()
        statuses.append(st)
        if st == DISCARD:
            h.expect_log("a refused step says why", mark, s, ("refused",))
            break
        if st not in (OK, WARNING):
            break
    h.check("status", "every step fmi2OK or fmi2Warning (or fmi2Discard with a message)",
            all(x in (OK, WARNING, DISCARD) for x in statuses), [STATUS_NAMES.get(x) for x in statuses])
    vals = s.outputs()
    bad = {k: v for k, v in vals.items() if isinstance(v, str) and v.lstrip("-") in ("nan", "inf")}
    h.check("state", "finite outputs", not bad, bad or None)
    _no_lapack_noise(h)


for _fmu, _name, _v in _edges():
    for _scheme in (0, 1):
        add(f"declared/{SHORT[_fmu]}/edge-{_name}={_v!r}-scheme={_scheme}", declared_edge, fmu=_fmu, name=_name,
            value=_v, scheme=_scheme, kinds=("status", "message"),
            desc=f"{_fmu}: {_name} = {_v!r} (an edge of its declared range), scheme {_scheme}")


# ---------------------------------------------------------------------------------------------- input derivatives
#: [m/s2], [m/s2 / s] the input and its rate set before the first step, and the start time [s]
INPUT_0, INPUT_RATE, START_TIME = 0.5, 50.0, 1.0


#: [m/s2], [m/s2 / s] the rate case of ag_v: ag held at AG_HELD while ag_v goes from 0.5 down at 50 m/s3 (the
#: block lifts off as g + ag_v falls; measured from t = 0 instead of the start time, ag_v would be -49.5)
AG_HELD, INPUT_RATE_V = 2.0, -50.0


def rate_before_init(h: Harness, fmu: str, where: str, name: str = "ag"):
    """fmi2SetRealInputDerivatives (of ag, or of ag_v with ag held) before initialization (FMI 2.0 section
    4.2.1 allows it in the instantiated state and in initialization mode), with startTime = 1 s: the
    derivative refers to the start of the first communication step (the start time), so the run equals a
    control that set the same value and rate after initialization, at t = 1 s (today's code measured it from
    t = 0: ag = 50.5 instead of 0.5)."""
    s, ctrl = h.instance(fmu), h.instance(fmu, "control")
    vr = s.vars[name].valueReference
    slope = INPUT_RATE if name == "ag" else INPUT_RATE_V
    values = {name: INPUT_0} if name == "ag" else {"ag": AG_HELD, name: INPUT_0}

    def rate(inst):
        return inst.call("fmi2SetRealInputDerivatives", inst.fmu.setRealInputDerivatives, [vr], [1], [slope])

    if where == "instantiated":
        h.expect_status(f"fmi2SetReal({name}) when instantiated", s.set(**values), OK)
        h.expect_status("fmi2SetRealInputDerivatives when instantiated", rate(s), OK)
    h.expect_status("fmi2SetupExperiment(startTime = 1)", s.setup(START_TIME), OK)
    h.expect_status("fmi2EnterInitializationMode", s.enter(), OK)
    if where == "initialization":
        h.expect_status(f"fmi2SetReal({name}) in initialization mode", s.set(**values), OK)
        h.expect_status("fmi2SetRealInputDerivatives in initialization mode", rate(s), OK)
    h.expect_status("fmi2ExitInitializationMode", s.exit(), OK)
    s.t = s.k = 0
    s.t = START_TIME
    ctrl.init(START_TIME)
    ctrl.set(**values)
    rate(ctrl)
    problems = []
    for i in range(10):  # ag from 0.5 to 1.0 m/s2 over the first step (no uplift), 5.5 m/s2 after the tenth
        a, b = s.step(), ctrl.step()
        if a != b or a not in (OK, WARNING):
            problems.append(f"step {i + 1}: subject {STATUS_NAMES.get(a)}, control {STATUS_NAMES.get(b)}")
            break
        oa, ob = s.outputs(), ctrl.outputs()
        if oa != ob:
            problems.append({"step": i + 1, "outputs differ": _dict_diff(oa, ob)})
            break
    h.check("state", "the steps equal those of a control that set the rate at the start time", not problems,
            problems or None)
    h.expect_same("same serialized state (value, rate and its reference time)", ctrl.snapshot(), s.snapshot())


for _fmu in (RIGID, FLEX):
    add(f"inputderiv/{SHORT[_fmu]}/rate-in-initialization-mode-startTime=1", rate_before_init, fmu=_fmu,
        where="initialization", kinds=("status", "state"),
        desc=f"{_fmu}: fmi2SetRealInputDerivatives in initialization mode, startTime = 1 s")
add("inputderiv/rigid/rate-when-instantiated-startTime=1", rate_before_init, fmu=RIGID, where="instantiated",
    kinds=("status", "state"), desc="RigidRockingBlock: fmi2SetRealInputDerivatives before fmi2SetupExperiment, "
                                    "startTime = 1 s")
for _fmu in WITH_VERTICAL:
    add(f"inputderiv/{SHORT[_fmu]}/ag_v-rate-in-initialization-mode-startTime=1", rate_before_init, fmu=_fmu,
        where="initialization", name="ag_v", kinds=("status", "state"),
        desc=f"{_fmu}: fmi2SetRealInputDerivatives of ag_v in initialization mode, startTime = 1 s")
add("inputderiv/rigid/ag_v-rate-when-instantiated-startTime=1", rate_before_init, fmu=RIGID, where="instantiated",
    name="ag_v", kinds=("status", "state"),
    desc="RigidRockingBlock: fmi2SetRealInputDerivatives of ag_v before fmi2SetupExperiment, startTime = 1 s")


def bad_derivative(h: Harness, fmu: str, name: str, what: str):
    """fmi2SetRealInputDerivatives of an input with an unsupported order or a rate that is not finite or too
    large: fmi2Error naming the input, nothing set; out of the error state by a saved state it steps on like
    the control."""
    s, ctrl = h.scene(fmu)
    vr = s.vars[name].valueReference
    order, rate, fragments = {"order=2": (2, 1.0, (word(name), "order = 2")),
                              "rate=nan": (1, math.nan, (f"rate of {name}", "nan")),
                              "rate=1e9": (1, 1e9, (f"rate of {name}", "out of range"))}[what]
    refusal(h, s, f"fmi2SetRealInputDerivatives({name}, {what})",
            lambda: s.call("fmi2SetRealInputDerivatives", s.fmu.setRealInputDerivatives, [vr], [order], [rate]),
            status=ERROR, fragments=fragments, control=ctrl)


for _fmu in WITH_VERTICAL:
    for _name in ("ag", "ag_v"):
        for _what in ("order=2", "rate=nan", "rate=1e9"):
            add(f"inputderiv/{SHORT[_fmu]}/{_name}-{_what}", bad_derivative, fmu=_fmu, name=_name, what=_what,
                desc=f"{_fmu}: fmi2SetRealInputDerivatives of {_name} with {_what}")


def ramp_leaves_range(h: Harness, fmu: str, name: str):
    """An input whose ramp (value + rate) would leave its declared range within the step: fmi2Discard naming
    the input, the state (with the other input, its value and its rate) bit-identical; a shorter step stays
    inside and equals the control's; then both step on alike."""
    s, ctrl = h.scene(fmu)
    vrs = [s.vars["ag"].valueReference, s.vars["ag_v"].valueReference]
    start = {"ag": [995.0, -2.0], "ag_v": [1.0, 995.0]}[name]
    for inst in (s, ctrl):  # ag_v and ag both with a rate: the refused step must keep both
        inst.set_vr("Real", vrs, start)
        inst.call("fmi2SetRealInputDerivatives", inst.fmu.setRealInputDerivatives, vrs, [1, 1],
                  [1000.0 if name == "ag" else 10.0, 1000.0 if name == "ag_v" else 10.0])
    label = f"fmi2DoStep with {name} leaving its range over the step"
    before = s.snapshot()
    mark = h.mark()
    h.expect_status(f"{label}: status of the refused call", s.step(), DISCARD)
    h.expect_log(f"{label}: error message", mark, s, (f"{name} at the end of the step", "1000"))
    h.expect_same(f"{label}: state (both inputs, their values and rates) bit-identical to before", before,
                  s.snapshot())
    h.expect_status("a shorter step inside the range", s.step(0.001), OK)
    h.expect_status("the control's shorter step", ctrl.step(0.001), OK)
    h.check("state", "the shorter step equals the control's", s.outputs() == ctrl.outputs(),
            _dict_diff(s.outputs(), ctrl.outputs()) or None)
    for inst in (s, ctrl):
        inst.set(ag_v=0.0)  # held at 0 from here (fmi2SetReal drops the rate); drive_step sets ag
    h.expect_same_run("after the refused step", s, ctrl)


for _fmu in WITH_VERTICAL:
    for _name in ("ag", "ag_v"):
        add(f"inputderiv/{SHORT[_fmu]}/{_name}-ramp-leaves-range", ramp_leaves_range, fmu=_fmu, name=_name,
            desc=f"{_fmu}: fmi2DoStep whose {_name} ramp leaves [-1000, 1000] m/s2")


# ---------------------------------------------------------------------------------------------- corrupted bytes
def _status_fields(s: Inst):
    """(fmi2LastSuccessfulTime, fmi2Terminated): the binary's own fields, readable in the error state too."""
    t, term = ctypes.c_double(), ctypes.c_int()
    st1 = s.call("fmi2GetRealStatus", s.fmu.fmi2GetRealStatus, s.fmu.component, 2, ctypes.byref(t))
    st2 = s.call("fmi2GetBooleanStatus", s.fmu.fmi2GetBooleanStatus, s.fmu.component, 3, ctypes.byref(term))
    return (st1, t.value.hex(), st2, term.value)


#: every PAYLOAD_STRIDE-th byte of the slave's payload is flipped (every byte of both headers is)
PAYLOAD_STRIDE = 7


def flipped_bytes(h: Harness, fmu: str):
    """A serialized state with one bit flipped -- every byte of the binary's header (time, instance state,
    fmi2Terminated flag, last status, CRC) and of the slave's header, every 7th byte of the payload: each is
    refused with fmi2Error (fmi2DeSerializeFMUstate or fmi2SetFMUstate), and the instance keeps its state (every
    variable, fmi2LastSuccessfulTime and fmi2Terminated read in the error state, and the serialized bytes after
    leaving it by a state saved before); then it steps on like a control instance."""
    s, ctrl = h.scene(fmu)
    full, problem = s.state_bytes()
    if problem is not None or not full:
        raise HarnessError(f"no valid state to corrupt: {problem}")
    n_binary = len(full) - len(slave_bytes(full))
    h.check("state", f"the binary's header has {SERIAL_HEADER_SIZE} bytes", n_binary == SERIAL_HEADER_SIZE, n_binary)
    positions = list(range(min(len(full), n_binary + 64))) + list(range(n_binary + 64, len(full), PAYLOAD_STRIDE))
    values, fields = s.values(), _status_fields(s)
    st, saved = s.get_state()
    accepted, changed = [], []
    mark = h.mark()
    for i in positions:
        data = full[:i] + bytes([full[i] ^ 0x01]) + full[i + 1:]
        st1, state = s.deserialize(data)
        status = st1
        if st1 in (OK, WARNING):
            status = max(status, s.set_state(state))
            s.free_state(state)
        if status != ERROR:
            accepted.append({"byte": i, "status": STATUS_NAMES.get(status)})
        if s.values() != values or _status_fields(s) != fields:
            changed.append({"byte": i, "what": "variables or status fields"})
        s.set_state(saved)  # out of the error state (or back from an accepted corrupted state)
        if s.state_bytes()[0] != full:
            changed.append({"byte": i, "what": "serialized state after fmi2SetFMUstate of the saved one"})
    h.figure("bytes_flipped", len(positions))
    h.check("status", f"each of the {len(positions)} corrupted states is refused with fmi2Error", not accepted,
            accepted[:20] or None)
    h.check("state", "the instance keeps its state after each refusal", not changed, changed[:20] or None)
    h.expect_log("the refusal says the state is corrupted", mark, s, ("rejected", ("corrupt", "SHA", "CRC")))
    s.free_state(saved)
    h.expect_same_run("after the corrupted states", s, ctrl)


for _fmu in (RIGID, FLEX):
    add(f"corrupt/{SHORT[_fmu]}/every-header-byte-flipped", flipped_bytes, fmu=_fmu,
        desc=f"{_fmu}: serialized states with one bit flipped in every header byte and a sample of the payload")


# ---------------------------------------------------------------------------------------------- reset
def reset_from(h: Harness, fmu: str, where: str):
    """fmi2Reset from any state gives a fresh instance: the start values of a new instance, and after
    initialization the same run."""
    s = h.instance(fmu)
    params = {RIGID: {"b": 0.3, "phi_0": 0.02}, FLEX: {"b": 0.3, "phi_0": 0.01}, STOREY: {"T": 0.3},
              GMS: {"A": 2.0}, PT: {"b": 0.3, "phi_0": 0.02, "m": 500.0, "P0": 1e4, "k_t": 1e6}}[fmu]
    if where == "before-init":
        s.setup()
        s.enter()
        s.set(**params)
    elif where == "after-init":
        s.init(**params)
        s.drive(N_BEFORE)
    elif where == "after-error":
        s.setup()
        s.enter()
        s.set(**{next(iter(params)): -5.0})
        s.exit()
    elif where == "after-terminate":
        s.init(**params)
        s.drive(N_BEFORE)
        s.terminate()
    elif where == "after-discard":
        s.init(**params)
        s.drive(5)
        s.set_vr("Real", [BAD_VR], [1.0])  # pending discard
    elif where == "in-init-mode":
        s.setup(3.0)
        s.enter()
    mark = h.mark()
    h.expect_status(f"fmi2Reset {where}", s.reset(), OK)
    h.expect_no_log("no error", mark, s, ERROR)
    fresh = h.instance(fmu, "control")
    h.expect_same("after fmi2Reset: the start values and state of a fresh instance", fresh.snapshot(), s.snapshot())
    s.init(**SCENES[fmu][1])
    fresh.init(**SCENES[fmu][1])
    h.expect_same_run("initialized again: the run of a fresh instance (no pending discard)", s, fresh, N_AFTER)


for _fmu, _wheres in ((RIGID, ("before-init", "after-init", "after-error", "after-terminate", "after-discard",
                               "in-init-mode")),
                      (FLEX, ("after-init", "after-error")), (PT, ("after-init", "after-error")),
                      (STOREY, ("after-init", "after-error")),
                      (GMS, ("after-init", "after-error"))):
    for _where in _wheres:
        add(f"reset/{SHORT[_fmu]}/{_where}", reset_from, fmu=_fmu, where=_where,
            desc=f"{_fmu}: fmi2Reset {_where.replace('-', ' ')}")


def many_instances(h: Harness, fmus: Sequence[str], n: int = 50):
    """n instances created, run and freed in one process: no crash, sys.path does not grow."""
    path0 = len(sys.path)
    rss0 = rss_bytes()
    ok = True
    for i in range(n):
        fmu = fmus[i % len(fmus)]
        s = h.instance(fmu, f"i{i}")
        s.init()
        s.drive(3)
        ok &= s.terminate() == OK and s.free() == OK
        if i == 4:
            path5, rss5 = len(sys.path), rss_bytes()
    h.figure("sys_path", [path0, path5, len(sys.path)])
    h.figure("rss_growth_bytes_per_instance", round((rss_bytes() - rss5) / (n - 5), 1))
    h.check("status", f"{n} instances created, stepped, terminated and freed", ok)
    h.check("state", "sys.path does not grow with instances", len(sys.path) <= path5 and len(sys.path) <= path0 + 1,
            [path0, path5, len(sys.path)])


add("reset/rigid/50-instances", many_instances, fmus=(RIGID,), kinds=("status", "state"),
    desc="RigidRockingBlock: 50 instances in one process")
add("reset/all/50-instances-mixed", many_instances, fmus=FMUS, kinds=("status", "state"),
    desc="the five FMUs, 50 instances in turn in one process")


# ---------------------------------------------------------------------------------------------- resources
def resource_folder(h: Harness, folder: str):
    """fmpy.extract into a folder whose path contains a special character, then FMU2Slave: instantiate,
    initialize, step like a control instance."""
    from fmpy import extract

    target = h.workdir / folder
    unzip = extract(h.fmu_path(RIGID), unzipdir=str(target))
    s = Inst(h, RIGID, "subject", True, unzip, None)
    h.check("status", "fmi2Instantiate", True)
    s.init()
    ctrl = h.instance(RIGID, "control")
    ctrl.init()
    s.amplitude = ctrl.amplitude
    h.expect_same_run("runs like an instance extracted elsewhere", s, ctrl, 10)


for _label, _folder in (("space", "dir with space"), ("e-acute", "dir-é"), ("hash", "dir-#"), ("bracket", "dir-["),
                        ("percent", "dir-%")):
    add(f"resources/rigid/extract-{_label}", resource_folder, folder=_folder, kinds=("status", "state"),
        desc=f"FMU extracted into a folder named {_folder!r}, instantiated with fmpy")


def importer_helpers(h: Harness, helper: str):
    """The project's importer helpers work when the FMU FILE lies in a folder with é, #, [, % and a space
    (they extract into a safe temporary folder)."""
    folder = h.workdir / "FMUs é #[%] x"
    folder.mkdir()
    paths = {}
    for fmu in (RIGID, GMS):
        paths[fmu] = folder / Path(h.fmu_path(fmu)).name
        shutil.copy(h.fmu_path(fmu), paths[fmu])
    if helper == "run_fmu":
        from rocking_model.fmi import run_fmu

        res = run_fmu(paths[RIGID], stop_time=0.5, output_interval=DT, start_values={"phi_0": 0.05})
        ref = run_fmu(h.fmu_path(RIGID), stop_time=0.5, output_interval=DT, start_values={"phi_0": 0.05})
        h.check("status", "run_fmu completes", float(res["time"][-1]) == float(ref["time"][-1]))
        h.check("state", "the same result as from a plain folder", res.tobytes() == ref.tobytes())
    else:
        from rocking_model.cosim import Component, Connection, System, run_fmpy

        def system(p):
            return System([Component("ground", p[GMS]), Component("block", p[RIGID])],
                          [Connection(("ground", "ag"), ("block", "ag")),
                           Connection(("ground", "ag_v"), ("block", "ag_v"))], step_size=DT)

        res = run_fmpy(system(paths), 0.5, ["ground.ag", "block.phi"])
        ref = run_fmpy(system({k: Path(h.fmu_path(k)) for k in paths}), 0.5, ["ground.ag", "block.phi"])
        h.check("status", "the fmpy master completes", len(res) == len(ref) == 51)
        h.check("state", "the same result as from a plain folder", res.tobytes() == ref.tobytes())


for _helper in ("run_fmu", "cosim"):
    add(f"resources/helpers/{_helper}-fmu-in-special-folder", importer_helpers, helper=_helper,
        kinds=("status", "state"), desc=f"rocking_model {_helper} with the FMU file in 'FMUs é #[%] x/'")


# ---------------------------------------------------------------------------------------------- other FMI calls
def unsupported(h: Harness, what: str):
    """Functions the FMUs do not provide (no output derivatives, no asynchronous steps): fmi2Error with a
    message naming the function, every variable kept; the instance leaves the error state with a saved
    state and works on."""
    s, ctrl = h.scene(RIGID)
    calls = {
        "getRealOutputDerivatives": (lambda: s.call("fmi2GetRealOutputDerivatives", s.fmu.getRealOutputDerivatives,
                                                    [vr_of(s, "phi")], [1]), "RealOutputDerivatives"),
        "cancelStep": (lambda: s.call("fmi2CancelStep", s.fmu.fmi2CancelStep, s.fmu.component), "fmi2CancelStep"),
    }
    action, name = calls[what]
    refusal(h, s, name, action, status=ERROR, fragments=(name,), control=ctrl)


for _what in ("getRealOutputDerivatives", "cancelStep"):
    add(f"misc/rigid/{_what}", unsupported, what=_what, desc=f"RigidRockingBlock: fmi2{_what[0].upper()}{_what[1:]} (not provided)")


def status_queries(h: Harness):
    """The status queries after a step refused by the simulator (fmi2Discard: the work limit) and after the
    retry: fmi2DoStepStatus is the status of the last step, fmi2Terminated true until a step succeeds again,
    fmi2LastSuccessfulTime the time of the slave (not the requested end); the kinds that FMI 2.0 does not
    define for a synchronous slave are fmi2Discard."""
    s = h.instance(RIGID)
    s.init(scheme=0, max_steps=5, dt_max=1e-3)

    def query(kind, ctype, which):
        out = ctype()
        st = s.call(f"fmi2Get{kind}Status", getattr(s.fmu, f"fmi2Get{kind}Status"), s.fmu.component, which,
                    ctypes.byref(out))
        return st, out.value

    t_before = s.t
    h.expect_status("a step needing more than max_steps internal steps is discarded", s.step(1.0), DISCARD)
    h.expect_status("fmi2GetStatus(fmi2DoStepStatus)", query("", ctypes.c_int, 0)[0], OK)
    h.check("status", "fmi2DoStepStatus after the discard is fmi2Discard", query("", ctypes.c_int, 0)[1] == DISCARD)
    st, terminated = query("Boolean", ctypes.c_int, 3)
    h.check("status", "fmi2Terminated true after the discard", st == OK and terminated == 1, (st, terminated))
    st, t_last = query("Real", ctypes.c_double, 2)
    h.check("status", "fmi2LastSuccessfulTime is the slave's time, not the requested end",
            st == OK and t_last == t_before, (st, t_last))
    h.expect_status("fmi2GetIntegerStatus: no integer status in FMI 2.0 -> fmi2Discard",
                    query("Integer", ctypes.c_int, 0)[0], DISCARD)
    h.expect_status("fmi2GetStringStatus(fmi2PendingStatus): no pending step -> fmi2Discard",
                    query("String", ctypes.c_char_p, 4)[0], DISCARD)
    h.expect_status("the retry with a shorter step succeeds", s.step(0.002), OK)
    st, terminated = query("Boolean", ctypes.c_int, 3)
    h.check("status", "fmi2Terminated false again after the successful retry", st == OK and terminated == 0,
            (st, terminated))
    st, t_last = query("Real", ctypes.c_double, 2)
    h.check("status", "fmi2LastSuccessfulTime follows the successful step", st == OK and t_last == s.t,
            (st, t_last))
    h.check("status", "fmi2DoStepStatus after the retry is fmi2OK", query("", ctypes.c_int, 0) == (OK, OK))


add("misc/rigid/status-queries", status_queries, kinds=("status",),
    desc="fmi2Get*Status after a discarded step and after its retry")


def info_functions(h: Harness):
    s = h.instance(RIGID)
    h.check("status", "fmi2GetVersion = 2.0", s.fmu.getVersion() == "2.0", s.fmu.getVersion())
    h.check("status", "fmi2GetTypesPlatform = default", s.fmu.getTypesPlatform() == "default")
    mark = h.mark()
    st = s.call("fmi2SetDebugLogging(bogus category)", s.fmu.setDebugLogging, True, ["logAll", "no-such-category"])
    h.check("status", "fmi2SetDebugLogging with an unknown category: not fmi2Fatal", st not in (FATAL, -1),
            STATUS_NAMES.get(st))
    st = s.call("fmi2SetDebugLogging(off)", s.fmu.setDebugLogging, False, [])
    h.check("status", "fmi2SetDebugLogging(off) not fmi2Fatal", st not in (FATAL, -1), STATUS_NAMES.get(st))
    s.init()
    ctrl = h.instance(RIGID, "control")
    ctrl.init()
    h.expect_same_run("steps like a control", s, ctrl)


add("misc/rigid/info-and-debug-logging", info_functions, kinds=("status", "state"),
    desc="fmi2GetVersion, fmi2GetTypesPlatform, fmi2SetDebugLogging with an unknown category")


def instantiate_args(h: Harness, what: str):
    """fmi2Instantiate with arguments it must refuse (NULL and a message naming the cause, never a crash) or
    accept (the other spellings of a local file URI: the instance then runs)."""
    import pathlib

    from fmpy.fmi2 import FMU2Slave, fmi2CoSimulation, fmi2ModelExchange

    md = h.md(RIGID)
    unzip = h.unzip_dir(RIGID)
    resources = pathlib.Path(unzip, "resources")
    uri = resources.as_uri()
    cases = {
        "wrong-guid": (md.guid.replace(md.guid[1:9], "00000000"), uri, fmi2CoSimulation, ("fmuGUID", "does not match")),
        "model-exchange": (md.guid, uri, fmi2ModelExchange, ("fmuType", "co-simulation")),
        "uri-null": (md.guid, None, fmi2CoSimulation, ("NULL",)),
        "uri-http": (md.guid, "http://example.org/resources", fmi2CoSimulation, ("not a file URI",)),
        "uri-remote-host": (md.guid, "file://server/share/resources", fmi2CoSimulation, ("remote host",)),
        "uri-missing": (md.guid, (resources.parent / "nowhere").as_uri(), fmi2CoSimulation, ("does not exist",)),
        "uri-bad-escape": (md.guid, uri + "%zz", fmi2CoSimulation, ("invalid escape",)),
        "uri-file-single-slash": (md.guid, "file:" + str(resources), fmi2CoSimulation, None),
        "uri-file-localhost": (md.guid, "file://localhost" + str(resources), fmi2CoSimulation, None),
    }
    guid, location, kind, fragments = cases[what]
    fmu = FMU2Slave(guid=md.guid, unzipDirectory=unzip, modelIdentifier=RIGID, instanceName="subject")
    mark = h.mark()
    component = fmu.fmi2Instantiate(b"subject", kind, guid.encode(), None if location is None else location.encode(),
                                    ctypes.byref(h.callbacks), 0, 0)
    if fragments is not None:
        h.check("status", f"fmi2Instantiate ({what}) refused: NULL", not component)
        h.expect_log("the message names the cause", mark, None, fragments)
        return
    h.check("status", f"fmi2Instantiate ({what}) accepted", bool(component))
    if component:
        fmu.component = component
        ok = all(f() in (None, OK) for f in (lambda: fmu.setupExperiment(startTime=0.0), fmu.enterInitializationMode,
                                      fmu.exitInitializationMode, lambda: fmu.doStep(0.0, DT)))
        h.check("status", "the instance runs", ok)
        fmu.fmi2FreeInstance(component)


for _what in ("wrong-guid", "model-exchange", "uri-null", "uri-http", "uri-remote-host", "uri-missing",
              "uri-bad-escape", "uri-file-single-slash", "uri-file-localhost"):
    add(f"instantiate/rigid/{_what}", instantiate_args, what=_what, kinds=("status",),
        desc=f"fmi2Instantiate: {_what.replace('-', ' ')}")


def logging_off_subset(h: Harness, fmu: str):
    """With loggingOn = false: the refusals behave the same (statuses, state) and their error messages still
    reach the logger (only debug messages need logging on); nothing crashes."""
    s, ctrl = h.scene(fmu, logging=False)
    actions = [("unknown reference", lambda: s.set_vr("Real", [BAD_VR], [1.0]), (str(BAD_VR),)),
               ("fmi2GetString unknown", lambda: s.get_vr("String", [BAD_VR])[0], (str(BAD_VR),)),
               ("fmi2ExitInitializationMode again", s.exit, ("fmi2ExitInitializationMode",))]
    if s.amplitude is not None:
        actions.append(("ag = NaN", lambda: s.set(ag=math.nan), (word("ag"),)))
    if fmu in WITH_VERTICAL:
        actions.append(("ag_v = NaN", lambda: s.set(ag_v=math.nan), (word("ag_v"),)))

    def gadget():
        st, state = s.deserialize(gadget_via_fmi())
        return max(st, s.set_state(state))

    actions.append(("pickle gadget", gadget, ("not a serialized state",)))
    for label, action, fragments in actions:
        refusal(h, s, f"{label} (logging off)", action, status=ERROR, fragments=fragments)
        ctrl.drive_step()
    h.check("state", "nothing executed", not (h.workdir / PWNED).exists())
    h.expect_same_run("steps on", s, ctrl)


for _fmu in FMUS:
    add(f"logging-off/{SHORT[_fmu]}/refusals", logging_off_subset, fmu=_fmu,
        desc=f"{_fmu}: refusals with loggingOn = false")


# ============================================================================================== the page
#: what each class (case family) tries, the statuses its cases assert, and what holds: the rows of
#: docs/robustness.md, written by `robustness_page` (tests/test_fault_suite.py checks the committed page)
FAMILIES = {
    "param": ("invalid start values: outside the declared range, NaN, inf; a singular mass matrix; a record file "
              "missing, empty, malformed or going back in time",
              "`fmi2ExitInitializationMode`: fmi2Error; `fmi2DoStep` then: fmi2Error (error state); `fmi2Reset`: "
              "fmi2OK",
              "the message names the variable and its allowed range (or the file and the line); the getters, "
              "`fmi2GetFMUstate`, `fmi2Terminate` and `fmi2Reset` are safe; after `fmi2Reset` and valid values "
              "the instance runs like a fresh one"),
    "param-logging-off": ("an invalid start value with `loggingOn = false`", "as `param`",
                          "the error message still reaches the logger (only debug messages need logging on)"),
    "declared": ("declared values that hung or overflowed a step: `mu` = 5e-324 (1/mu = inf hung the event-driven "
                 "step in LAPACK), now below the stated minimum 1e-3; both edges of every declared Real parameter "
                 "of the rocking FMUs under both schemes (of the post-tensioned block: its own, P0 and k_t)",
                 "beyond: fmi2Error at `fmi2ExitInitializationMode`; at an edge: fmi2Error naming the parameter, or "
                 "every step fmi2OK / fmi2Warning (fmi2Discard with a message)",
                 "the range the message states is the modelDescription's min and max (one declaration read by "
                 "both); an edge simulates in bounded time with finite outputs or is refused with a message "
                 "(a subnormal value whose reciprocal overflows is named); LAPACK prints nothing into the "
                 "host's output"),
    "simulate_fmu": ("`fmpy.simulate_fmu` and `rocking_model.fmi.run_fmu` with an invalid start value",
                     "fmpy raises; `run_fmu` raises `FMUError`",
                     "the `FMUError` names the variable and its allowed range"),
    "sequence": ("calls out of sequence: `fmi2DoStep` before initialization or after `fmi2Terminate`; "
                 "`fmi2SetupExperiment`, `fmi2EnterInitializationMode`, `fmi2ExitInitializationMode` after "
                 "initialization; `startTime` NaN or inf; `fmi2FreeInstance` without `fmi2Terminate`; "
                 "`fmi2SetReal` of `ag` or `ag_v` after `fmi2Terminate`",
                 "fmi2Error (the instance in the error state); `fmi2FreeInstance`: fmi2OK",
                 "the message names the call and the state of the instance; every variable bit-identical; after "
                 "`fmi2SetFMUstate` of a saved state or `fmi2Reset` it steps like a control instance"),
    "doStep": ("`fmi2DoStep` with a step size 0, < 0, NaN, inf; a communication point NaN, inf, ahead of or behind "
               "the instance's time",
               "fmi2Error",
               "the message names `communicationStepSize` or `currentCommunicationPoint`; the state bit-identical; "
               "out of the error state by a saved state, it steps on like a control instance"),
    "input": ("the inputs `ag` and `ag_v` (the vertical ground acceleration of the rocking FMUs) NaN, ±inf, 1e308, "
              "±1500 m/s² (declared range [-1000, 1000], written as min and max in the modelDescription); both "
              "invalid in one call",
              "`fmi2SetReal`: fmi2Error",
              "the message names the input (`ag`, `ag_v`, or both) and its range; nothing is set; the run goes "
              "on like a control instance"),
    "inputderiv": ("`fmi2SetRealInputDerivatives` of `ag` or `ag_v` before initialization (instantiated, "
                   "initialization mode) with `startTime` = 1 s; of order 2, a rate NaN or 1e9; a ramp that leaves "
                   "[-1000, 1000] m/s² within the step",
                   "before initialization: fmi2OK; a bad order or rate: fmi2Error; the ramp: `fmi2DoStep` "
                   "fmi2Discard",
                   "the derivative refers to the start of the first communication step (the start time, FMI 2.0 "
                   "§4.2.1): the steps and the serialized state equal those of a control that set value and rate "
                   "at t = 1 s; a refusal names the input, and keeps both inputs, their values and rates, "
                   "bit-identical; a shorter step then equals a control's"),
    "vr": ("value references: unknown, 2^32-1, of another type, an output set, a `fixed` parameter changed after "
           "initialization, a batch with one bad reference, `nvr` = 0, a fixed parameter set to its own value",
           "fmi2Error; `nvr` = 0 and the same value: fmi2OK",
           "the message names the reference (and the variable and its type); nothing of the call is set; the run "
           "goes on like a control instance"),
    "string": ("`fmi2SetString` / `fmi2GetString` on FMUs without String variables, unknown references, on a "
               "Real; `record` changed after initialization, 100 000 characters long, not UTF-8; a record path "
               "with é # [ % read back; printf conversions in a record name",
               "fmi2Error; the round trip: fmi2OK",
               "the message names the reference or `record`; `%` is shown literally (messages are passed as "
               "data); the string set comes back unchanged"),
    "bounded": ("steps that used to hang: `fmi2DoStep` of 1e12 s and 1e308 s, `dt_max` 1e-300 and 1e-9, "
                "`EI` = 1e15, `ag` at ±1000 m/s² for 1 s and 999 m/s² for 10 s, `ag` = 1.797e308",
                "fmi2Discard (work budget `max_steps`), fmi2Error at initialization (a parameter outside its "
                "narrowed range) or at `fmi2SetReal`, or fmi2OK",
                "every case ends in bounded time; a refused step names the cause and the way out, the state "
                "unchanged; a completed one has finite outputs"),
    "state": ("FMU state: get, steps, set, the same steps; serialize in one instance and deserialize in another; "
              "`fmi2GetFMUstate` 3000 times onto one pointer; a freed pointer reused; the size over many impacts; "
              "`fmi2SerializeFMUstate` into a buffer 16 bytes short",
              "fmi2OK; the short buffer: fmi2Error",
              "restored states are bit-identical and the redone steps too; no memory growth per call; the size "
              "does not grow with impacts; nothing is written past a short buffer"),
    "badstate": ("states to reject: pickle gadgets, random, short, NUL and empty bytes, truncated, padded, "
                 "version 0 or 2, declared length 2^32-1, another FMU's state, JSON that is not an object, invalid "
                 "or nested 100 000 deep, 2 MiB, fields of the wrong type, missing or out of range (behind a "
                 "binary header whose CRC-32 holds, so that the slave's checks are reached)",
                 "fmi2Error (`fmi2DeSerializeFMUstate` or `fmi2SetFMUstate`)",
                 "the message says the state is rejected and why (header, version, length, digest, JSON, the "
                 "field); nothing is executed; the state kept; the run goes on like a control instance"),
    "corrupt": ("a serialized state with one bit flipped in every byte of both headers (the binary's: time, "
                "instance state, fmi2Terminated flag, last status, CRC-32; the slave's: magic, version, length, "
                "SHA-256) and in every 7th byte of the payload",
                "fmi2Error for every one (`fmi2DeSerializeFMUstate` or `fmi2SetFMUstate`)",
                "the CRC-32 over the whole state (and the slave's SHA-256) refuse each: every variable, "
                "`fmi2LastSuccessfulTime` and `fmi2Terminated` are kept, the message says the state is rejected "
                "as corrupted; the run goes on like a control instance"),
    "range": ("`max_steps` beyond its declared max (2^31-1, 1e9+1)",
              "`fmi2ExitInitializationMode`: fmi2Error",
              "the range the message states is the modelDescription's min and max (the FMU checks the declaration "
              "itself), the variable named"),
    "reset": ("`fmi2Reset` before and after initialization, after an error, after `fmi2Terminate`, after a "
              "discarded step, in initialization mode; 50 instances created, run and freed in one process",
              "fmi2OK",
              "the start values and state of a fresh instance, which then runs like one; `sys.path` keeps its "
              "length"),
    "resources": ("the FMU extracted into folders named with a space, é, #, [, %; `run_fmu` and the co-simulation "
                  "master with the .fmu in `FMUs é #[%] x/`",
                  "fmi2OK",
                  "the resource URI is decoded: the instance runs like a control; the helpers give the results "
                  "of a plain folder"),
    "misc": ("`fmi2GetRealOutputDerivatives`, `fmi2CancelStep`; the status queries after a discarded step; "
             "`fmi2GetVersion`, `fmi2GetTypesPlatform`, `fmi2SetDebugLogging` with an unknown category",
             "not provided: fmi2Error; the queries: fmi2OK (fmi2Discard for a status FMI 2.0 does not define)",
             "fmi2DoStepStatus is fmi2Discard and fmi2Terminated true after a discard, "
             "fmi2LastSuccessfulTime the slave's time; \"2.0\", \"default\""),
    "instantiate": ("`fmi2Instantiate` with a wrong GUID, `fmi2ModelExchange`, a resource location NULL, not a "
                    "local file URI, on a remote host, missing or badly escaped; `file:/…` and "
                    "`file://localhost/…`",
                    "NULL (refused); the last two: an instance",
                    "the message names the cause; the accepted spellings run"),
    "logging-off": ("refusals with `loggingOn = false`: an unknown reference, `fmi2GetString`, a second "
                    "`fmi2ExitInitializationMode`, `ag` = NaN, a pickle gadget",
                    "fmi2Error",
                    "the same statuses and state as with logging on; the errors reach the logger"),
}

_PAGE_HEAD = """\
# Robustness of the FMUs: classes of misuse and what the FMUs do

<!-- generated by `python tests/fault_harness.py --write-doc docs/robustness.md` from the case list of
tests/fault_harness.py; tests/test_fault_suite.py checks that this page is what the list generates -->

The five FMUs (RigidRockingBlock, FlexibleRockingOscillator, PostTensionedRockingBlock, GroundMotionSource,
LinearBuildingStorey) run inside the importer's process. `tests/test_fault_suite.py` drives every FMI 2.0
co-simulation function through fmpy's low-level `fmpy.fmi2.FMU2Slave` with {n_cases} cases in {n_classes} classes,
each case in a process of its own with a timeout (a crash or a hang is a failed case, never a dead test run). Every case asserts:

1. the process survives (exit code 0, no signal) and finishes within its timeout;
2. the status is exactly the one FMI 2.0 gives the call (the column "statuses" below);
3. the logged message names the variable or the call (messages are read through fmpy's native logger
   proxy, which formats them with `vsnprintf` like any C importer);
4. every variable is bit-identical after a refused call (read back as exact floats); after an fmi2Error,
   `fmi2SetFMUstate` of a state saved before the call leaves the error state and the instance is
   bit-identical to before (the bytes of `fmi2SerializeFMUstate`); further identical steps give the outputs
   of a control instance that never saw the refused call.

Run it: `bash run.sh test tests/test_fault_suite.py`; one case by hand: `python tests/fault_harness.py
--list`, then `--case <id> --config <fmus.json>`. The session prints the classes tried and passing, the
longest case and the longest single `fmi2DoStep`.

## Statuses (FMI 2.0 §2.1.3, the project's binaries: `rocking_model/fmi/binary/fmi2_common.c` shared by `fmi2_cs.c` and `standalone/fmi2_engine.c`)

* **fmi2Error** for an invalid argument, value or call sequence, or a rejected FMU state: nothing of the call
  is applied; the instance is in the error state, where the getters, the status queries, `fmi2SetFMUstate`,
  `fmi2Reset`, `fmi2Terminate` and `fmi2FreeInstance` remain;
* **fmi2Discard** for a step the simulator refuses with its state unchanged (the work budget `max_steps`, an
  input ramp leaving its range, a failed step): `fmi2Terminated` is true and `fmi2LastSuccessfulTime` the
  time the step started, until a retried step succeeds;
* **fmi2Warning** for a step done with something to report (an inexact contact solve); an overturning is an
  event of the motion, not a warning: its step returns **fmi2OK** and its message is logged with fmi2OK under
  the category `logEvents` (declared in the modelDescription; with logging on and the category enabled);
* `fmi2Instantiate` returns NULL with a message when it refuses;
* errors and warnings reach the importer's logger with logging on or off; every message is passed as data
  (`"%s"`), so `%` in a file name prints literally.

## Classes

Case ids are `<class>/<fmu>/<what>` in `tests/fault_harness.py`.

| class | cases | FMUs | what is tried | statuses | what holds |
| --- | --- | --- | --- | --- | --- |
"""

_PAGE_TAIL = """
## History

The suite was first written against pythonfmu 0.7's prebuilt wrapper, which failed several classes (SIGSEGV for
`é # [ %` in the resource path, GUID not checked, no input derivatives, fmi2Fatal for a string that is not
UTF-8, aborts at process exit); the project's own binary (`rocking_model/fmi/binary/`) replaced it and passes every class.
The classes `declared`, `inputderiv`, `corrupt` and `range` were added with the faults they found fixed: a
minimum of `mu` (1e-3), input derivatives set before initialization measured from the start time, a CRC-32
over the whole serialized state, and the declared range of `max_steps` checked.
"""


def _cell(text: str) -> str:
    return text.replace("|", "\\|").replace("\n", " ")


def _fmu_of(case: Case) -> Optional[str]:
    """The FMU a case drives (its ``fmu`` argument, or the FMU named in its id) or the importer's helpers;
    None when the id names neither ("all": the case's FMUs are those of the other cases of its class)."""
    if case.kwargs.get("fmu") in FMUS:
        return case.kwargs["fmu"]
    part = case.cid.split("/")[1]
    named = {v: k for k, v in SHORT.items()}
    return named.get(part) or {"helpers": "importer helpers"}.get(part)


def robustness_page() -> str:
    """docs/robustness.md, from the case list (`CASES`) and the class descriptions (`FAMILIES`): one row per
    class with its number of cases and the FMUs they drive. A class without a description is an error."""
    order = list(dict.fromkeys(case.family for case in CASES.values()))
    missing = [f for f in order if f not in FAMILIES]
    if missing:
        raise ValueError(f"classes without a description in FAMILIES: {missing}")
    rows = []
    for family in order:
        cases = [c for c in CASES.values() if c.family == family]
        fmus = list(dict.fromkeys(f for c in cases for f in [_fmu_of(c)] if f))
        shown = ", ".join(fmus)
        tried, statuses, holds = FAMILIES[family]
        rows.append(f"| `{family}` | {len(cases)} | {_cell(shown)} | {_cell(tried)} | {_cell(statuses)} | "
                    f"{_cell(holds)} |")
    return (_PAGE_HEAD.format(n_cases=len(CASES), n_classes=len(order)) + "\n".join(rows) + "\n" + _PAGE_TAIL)


# ============================================================================================== FMU kinds
#: the kinds of FMU the suite runs on: the pythonfmu FMUs (every FMU of fmu_src/) and the self-contained ones
#: (RigidRockingBlock and FlexibleRockingOscillator built from the C engine, dist/standalone/)
KINDS = ("pythonfmu", "standalone")
#: the FMUs that have a self-contained build; the system FMUs (source, storey) exist as pythonfmu FMUs only
STANDALONE_FMUS = (RIGID, FLEX, PT)
_STANDALONE_BUILDS: Dict[str, Any] = {}


def standalone_fmus(build_module, tmp_path_factory) -> Dict[str, Path]:
    """{name: path} of the self-contained FMUs, built once per test session (shared by the test modules
    that run them: the fault suite, libcosim, Ecos, the system example). Raises what the build raises (no C
    compiler, ...): the callers skip with that reason. ROCKING_STANDALONE_FMUS, a folder of prebuilt
    self-contained FMUs (tests/sanitize.py's sanitized ones), replaces the build."""
    prebuilt = os.environ.get("ROCKING_STANDALONE_FMUS")
    if prebuilt:
        return {p.stem: p for p in sorted(Path(prebuilt).glob("*.fmu"))}
    key = str(tmp_path_factory.getbasetemp())
    if key not in _STANDALONE_BUILDS:
        try:
            dest = tmp_path_factory.mktemp("standalone_fmus")
            _STANDALONE_BUILDS[key] = {p.stem: p for p in build_module.build_standalone(dest)}
        except Exception as exc:
            _STANDALONE_BUILDS[key] = exc
    built = _STANDALONE_BUILDS[key]
    if isinstance(built, Exception):
        raise built
    return built


_PY_PAYLOAD = ("it edits the pythonfmu FMU's own state payload (a field of its JSON document, or JSON behind its "
               "header, or the length word of that header at its offset); the self-contained FMU's payload is a "
               "binary record of the C slave and engine under its own CRC-32, which such bytes do not reach "
               "(refused there as a bad header or a CRC mismatch): the state cases that apply to any format "
               "(pickles, random, short, empty, truncated, padded, versions, 2 MiB, another FMU's state, "
               "flipped bytes) run on it")
#: cases (id or id prefix) that do not apply to the self-contained FMUs, with the reason
STANDALONE_NA: Dict[str, str] = {
    **{f"badstate/{f}/{w}": _PY_PAYLOAD for f in ("rigid", "flex")
       for w in ("pickle-in-new-header", "length-huge", "json-not-object", "json-invalid", "json-deep", "t=nan",
                 "initialized-string", "value-wrong-type", "value-missing", "extra-key", "signature",
                 "pending-huge", "array-length", "array-wrong-type", "mode=10", "negative-impacts",
                 "negative-n_steps", "sim-nan")},
}


#: cases where the self-contained FMUs differ from the pythonfmu ones today (they are to give the same statuses
#: and messages): strict xfails, so that a fix shows as an unexpected pass and the entry is removed
STANDALONE_XFAIL: Dict[str, str] = {}


def standalone_xfail(kind: str, cid: str) -> Optional[str]:
    """The reason case ``cid`` is a known difference of ``kind`` of FMU from the pythonfmu FMUs, or None."""
    return STANDALONE_XFAIL.get(cid) if kind == "standalone" else None


def not_applicable(kind: str, cid: str) -> Optional[str]:
    """Why case ``cid`` does not apply to ``kind`` of FMU, or None when it does. On the standalone FMUs every
    case of the rocking FMUs runs, except those of `STANDALONE_NA`; the cases of the system FMUs alone
    (source, storey) would rerun the pythonfmu FMUs and are left to the pythonfmu kind."""
    if kind == "pythonfmu":
        return None
    if kind != "standalone":
        raise ValueError(f"kind = {kind!r}; allowed: {KINDS}")
    for prefix, reason in STANDALONE_NA.items():
        if cid == prefix or cid.startswith(prefix + "/") or cid.startswith(prefix + "-"):
            return reason
    fmu = _fmu_of(CASES[cid])
    if fmu in (GMS, STOREY):
        return (f"{fmu} has no self-contained build (a pythonfmu FMU only): the case would rerun the pythonfmu "
                f"FMU")
    return None


# ============================================================================================== running
def run_case(cid: str, config: dict, workdir: Path) -> dict:
    case = CASES[cid]
    record = {"case": cid, "what": case.what, "kinds": list(case.kinds), "error": None}
    t0 = time.perf_counter()
    h = None
    sys_path0 = len(sys.path)
    try:
        h = Harness(config, workdir)
        case.fn(h, **case.kwargs)
    except Exception:
        record["error"] = traceback.format_exc(limit=8)
    record["elapsed"] = time.perf_counter() - t0
    if h is not None:
        # a case ends with its instances freed (a crash in fmi2FreeInstance is a failure of the case too)
        for inst in h.instances:
            if inst.alive:
                try:
                    inst.call("fmi2Terminate", inst.fmu.terminate)
                    inst.free()
                except Exception:
                    record["error"] = (record["error"] or "") + traceback.format_exc(limit=4)
        record.update(checks=h.checks, calls=h.calls, messages=h.messages[-200:], figures=h.figures,
                      max_call=h.max_call, max_step=h.max_step)
    record["sys_path"] = [sys_path0, len(sys.path)]
    record["pwned"] = (Path(workdir) / PWNED).exists()
    return record


def _write(path: Path, record: dict) -> None:
    tmp = Path(str(path) + ".tmp")
    tmp.write_text(json.dumps(record, default=repr))
    os.replace(tmp, path)


def _child(req: dict) -> None:
    """In the forked child: run the case in its working directory, stdout/stderr to files there."""
    try:
        import resource
        resource.setrlimit(resource.RLIMIT_CORE, (0, 0))  # a crash leaves no core file behind
    except Exception:
        pass
    workdir = Path(req["cwd"])
    os.chdir(workdir)
    for fd, name in ((1, "stdout.txt"), (2, "stderr.txt")):
        f = os.open(workdir / name, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644)
        os.dup2(f, fd)
        os.close(f)
    config = _CONFIGS.get(req["config"]) or json.loads(Path(req["config"]).read_text())
    record = run_case(req["case"], config, workdir)
    _write(Path(req["out"]), record)


def _wait(pid: int, timeout: float) -> dict:
    t0 = time.perf_counter()
    deadline = t0 + timeout
    delay = 0.002
    while True:
        done, status = os.waitpid(pid, os.WNOHANG)
        if done:
            elapsed = time.perf_counter() - t0
            if os.WIFSIGNALED(status):
                return {"rc": None, "signal": os.WTERMSIG(status), "timed_out": False, "elapsed": elapsed}
            return {"rc": os.WEXITSTATUS(status), "signal": None, "timed_out": False, "elapsed": elapsed}
        if time.perf_counter() > deadline:
            os.kill(pid, signal.SIGKILL)
            os.waitpid(pid, 0)
            return {"rc": None, "signal": None, "timed_out": True, "elapsed": time.perf_counter() - t0}
        time.sleep(delay)
        delay = min(0.02, delay * 1.5)


def serve() -> None:
    """Fork server: one JSON request per line on stdin ({case, config, out, cwd, timeout}); for each, fork a
    child that runs the case; answer one JSON line (exit code, signal, timeout, elapsed) on stdout."""
    import importlib

    # the expensive imports, once: the children inherit them (the FMUs import their own bundled copy of
    # rocking_model; these are the libraries it and the wrapper's slave script use)
    for module in ("fmpy", "fmpy.fmi2", "fmpy.logging", "fmpy.validation", "numpy", "scipy.linalg", "lxml.etree",
                   "xml.dom.minidom", "uuid", "pythonfmu", "pythonfmu.fmi2slave", "pythonfmu.builder",
                   "rocking_model.fmi_state", "rocking_model.fmi", "rocking_model.cosim"):
        importlib.import_module(module)
    # byte-code cache of the FMUs' bundled packages, shared by the children (PYTHONDONTWRITEBYTECODE may be set
    # in the environment: each child would compile the package again): only speed, no change of behaviour
    if os.environ.get("FAULT_SUITE_PYCACHE"):
        sys.pycache_prefix = os.environ["FAULT_SUITE_PYCACHE"]
        sys.dont_write_bytecode = False
    from fmpy import read_model_description

    out = sys.stdout
    for line in sys.stdin:
        if not line.strip():
            continue
        req = json.loads(line)
        if req["config"] not in _CONFIGS:  # model descriptions parsed once, in the server
            config = json.loads(Path(req["config"]).read_text())
            _CONFIGS[req["config"]] = config
            for fmu in config["fmus"].values():
                _MD_CACHE[fmu["path"]] = read_model_description(fmu["path"])
        out.flush()
        sys.stderr.flush()
        pid = os.fork()
        if pid == 0:
            code = 0
            try:
                _child(req)
            except BaseException:
                code = 3
                try:
                    traceback.print_exc()
                except Exception:
                    pass
            os._exit(code)
        result = _wait(pid, float(req.get("timeout", 60.0)))
        out.write(json.dumps({"case": req["case"], **result}) + "\n")
        out.flush()


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--list", action="store_true", help="print the case ids and what they try")
    parser.add_argument("--serve", action="store_true", help="fork server (used by tests/test_fault_suite.py)")
    parser.add_argument("--case", help="run one case in this process")
    parser.add_argument("--config", help="JSON file: {'fmus': {name: {'path': ..., 'unzip': ...}}}")
    parser.add_argument("--out", help="record file (JSON)")
    parser.add_argument("--write-doc", metavar="PATH", help="write the page of the classes (docs/robustness.md)")
    args = parser.parse_args(argv)
    if args.write_doc:
        Path(args.write_doc).write_text(robustness_page(), encoding="utf-8")
        return 0
    if args.list:
        for case in CASES.values():
            print(f"{case.cid:60s} {case.what}")
        return 0
    if args.serve:
        serve()
        return 0
    if args.case:
        record = run_case(args.case, json.loads(Path(args.config).read_text()), Path.cwd())
        text = json.dumps(record, default=repr, indent=1)
        if args.out:
            Path(args.out).write_text(text)
        else:
            print(text)
        return 0
    parser.print_help()
    return 2


if __name__ == "__main__":
    sys.exit(main())
