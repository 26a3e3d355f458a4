"""The serialized FMU state: a versioned, documented byte format that holds only data.

An FMU state (``fmi2SerializeFMUstate``) is a file that travels between tools and people, so reading one must
never run code: the payload is JSON (numbers, booleans, null, strings, lists and objects), parsed by
`json.loads` with a bounded size and nesting, never by pickle or any other loader that can build objects.

In an FMU these bytes follow the binary's own header (rocking_model/fmi/binary/fmi2_common.c, shared by both FMU binaries:
the communication time, the instance state, the fmi2Terminated flag, the last step status and a CRC-32 over its header and these bytes),
so that a corrupted byte anywhere in ``fmi2SerializeFMUstate``'s output is refused.

Layout (version 1), all integers little-endian::

    offset  size  field
    0       24    MAGIC = b"rocking_model FMU state\\n"
    24      4     format version (uint32), FORMAT_VERSION
    28      4     payload length n in bytes (uint32), at most MAX_PAYLOAD
    32      32    SHA-256 of the payload (catches truncation and accidental corruption; it is not a
                  signature: whoever writes the bytes can recompute it, which is why the payload is data only
                  and every field is checked on load)
    64      n     payload: UTF-8 JSON object (see below); non-finite floats are written as NaN / Infinity /
                  -Infinity (Python's json extension), so an unset step size round-trips

Payload of a rocking_model FMU (`rocking_model.fmi.RockingSlave`)::

    {"fmu": <model name>, "signature": <SHA-256 hex of the variable table (name, causality, type)>,
     "slave": {"initialized": bool, "terminated": bool, "frozen": bool, "t": float, "t0": float,
               "error": str | null, "pending": str | null, "values": {<variable name>: value, ...}},
     "simulator": {<flat dict of the simulator's get_state()>} | null}

The simulator part is the plain-data state of `Simulator.get_state` (or `MotionSource` / `StoreySimulator`):
the model itself is not stored; it is rebuilt from the parameter values in ``values`` and the state is then
set, with every field checked for type, shape and range.

Functions: `encode_state(doc) -> bytes`, `decode_state(data) -> dict` (raises `StateFormatError`, a
ValueError, with a message saying what is wrong).
"""
from __future__ import annotations

import hashlib
import json
import struct
from typing import Any, Dict

__all__ = ["MAGIC", "FORMAT_VERSION", "MAX_PAYLOAD", "StateFormatError", "encode_state", "decode_state"]

MAGIC = b"rocking_model FMU state\n"
FORMAT_VERSION = 1
#: [bytes] bound on the payload: a state holds some tens of numbers (the impact log of an FMU is empty), so
#: 1 MiB is generous and keeps a hostile file from costing memory or time
MAX_PAYLOAD = 1 << 20
#: bound on the nesting of JSON containers (the format uses 3 levels)
MAX_DEPTH = 8

_HEADER = struct.Struct("<24sII32s")


class StateFormatError(ValueError):
    """The bytes are not a valid serialized state of this format."""


def encode_state(doc: Dict[str, Any]) -> bytes:
    """Serialize ``doc`` (a JSON-able dict of plain data) with the header of format `FORMAT_VERSION`."""
    if not isinstance(doc, dict):
        raise StateFormatError(f"an FMU state document is a dict, got {type(doc).__name__}")
    payload = json.dumps(doc, separators=(",", ":"), allow_nan=True).encode("utf-8")
    if len(payload) > MAX_PAYLOAD:
        raise StateFormatError(f"the state has {len(payload)} bytes; at most {MAX_PAYLOAD} are allowed")
    return _HEADER.pack(MAGIC, FORMAT_VERSION, len(payload), hashlib.sha256(payload).digest()) + payload


def _depth(obj) -> int:
    """Nesting depth of JSON containers (iterative: a hostile document must not exhaust the stack)."""
    deepest, stack = 0, [(obj, 1)]
    while stack:
        node, level = stack.pop()
        if isinstance(node, (dict, list)):
            deepest = max(deepest, level)
            stack.extend((child, level + 1) for child in (node.values() if isinstance(node, dict) else node))
    return deepest


def decode_state(data) -> Dict[str, Any]:
    """Parse serialized state bytes; raise `StateFormatError` naming what is wrong (header, version, length,
    digest, JSON, nesting)."""
    try:
        data = bytes(data)
    except Exception as exc:
        raise StateFormatError(f"the serialized state is not a byte string ({type(data).__name__})") from exc
    if len(data) < _HEADER.size:
        raise StateFormatError(f"the serialized state has {len(data)} bytes, fewer than its {_HEADER.size}-byte "
                               f"header (truncated, or not a rocking_model FMU state)")
    magic, version, n, digest = _HEADER.unpack_from(data)
    if magic != MAGIC:
        raise StateFormatError("not a serialized rocking_model FMU state (bad header)")
    if version != FORMAT_VERSION:
        raise StateFormatError(f"state format version {version} is not supported; this FMU reads version "
                               f"{FORMAT_VERSION}")
    if n > MAX_PAYLOAD:
        raise StateFormatError(f"the state declares {n} payload bytes; at most {MAX_PAYLOAD} are allowed")
    payload = data[_HEADER.size:]
    if len(payload) != n:
        raise StateFormatError(f"the state has {len(payload)} payload bytes, its header declares {n} "
                               f"(truncated or padded)")
    if hashlib.sha256(payload).digest() != digest:
        raise StateFormatError("the serialized state is corrupted (SHA-256 mismatch)")
    try:
        doc = json.loads(payload.decode("utf-8"))
    except (UnicodeDecodeError, ValueError, RecursionError) as exc:
        raise StateFormatError(f"the state payload is not valid JSON: {exc}") from None
    if not isinstance(doc, dict):
        raise StateFormatError("the state payload is not a JSON object")
    if _depth(doc) > MAX_DEPTH:
        raise StateFormatError(f"the state payload nests deeper than {MAX_DEPTH} levels")
    return doc
