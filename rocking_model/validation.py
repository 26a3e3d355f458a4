"""Input checks: every message names the variable and its allowed range."""
from __future__ import annotations

import math


def check_real(name: str, value, *, lo: float | None = None, hi: float | None = None,
               lo_open: bool = False, hi_open: bool = False) -> float:
    """Return ``value`` as a finite float inside the given range or raise ValueError."""
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a real number, got {value!r}") from None
    if math.isfinite(x) and (lo is None or x > lo or (not lo_open and x == lo)) and \
            (hi is None or x < hi or (not hi_open and x == hi)):
        return x                      # the common case, without building the message
    lo_s = "-inf" if lo is None else f"{lo:g}"
    hi_s = "inf" if hi is None else f"{hi:g}"
    rng = f"{'(' if lo_open or lo is None else '['}{lo_s}, {hi_s}{')' if hi_open or hi is None else ']'}"
    if not math.isfinite(x):
        raise ValueError(f"{name} = {value!r} is not finite; allowed range {rng}")
    if lo is not None and (x < lo or (lo_open and x == lo)):
        raise ValueError(f"{name} = {x:g} is out of range; allowed range {rng}")
    if hi is not None and (x > hi or (hi_open and x == hi)):
        raise ValueError(f"{name} = {x:g} is out of range; allowed range {rng}")
    return x


def check_choice(name: str, value, allowed: dict):
    """Map ``value`` through ``allowed`` (keys: accepted spellings) or raise ValueError."""
    if value in allowed:
        return allowed[value]
    names = ", ".join(repr(k) for k in allowed)
    raise ValueError(f"{name} = {value!r} is not supported; allowed values: {names}")


#: [m/s2] largest supported |ag| (about 100 g). The strongest recorded ground motions peak near 4 g; the
#: bound leaves room for shake-table and impulse studies while keeping every force, velocity and energy of
#: the models many orders of magnitude below overflow (and far from the loss of all digits in the event
#: functions, which compare the weight with the inertial force). `Simulator.advance` refuses a larger
#: constant ag or a motion whose known peak exceeds it; a user callable that returns a larger value stops
#: the step with a ValueError naming ag (the state is kept).
AG_MAX = 1000.0

#: default work budget of one `Simulator.advance` [internal steps]: Moreau-Jean steps, or Runge-Kutta steps
#: plus `EVENT_WORK` (30) per event. The costliest unit is a Moreau-Jean step (150 to 350 us: numpy, an LCP
#: per step); 10000 of them take a few seconds at most (the longest advance measured over the declared ranges:
#: docs/robustness_library.md), while they cover 10 s of motion at the Moreau-Jean default dt_max = 1e-3 s and
#: over 300 impacts in one event-driven step.
MAX_STEPS = 10_000


def check_ag(value, name: str = "ag") -> float:
    """``value`` as a float in [-AG_MAX, AG_MAX] [m/s2] or ValueError naming ``name``."""
    return check_real(name, value, lo=-AG_MAX, hi=AG_MAX)


def check_ag_v(value, name: str = "ag_v") -> float:
    """The vertical ground acceleration ``value`` [m/s2], positive upward, as a float in [-AG_MAX, AG_MAX]
    (the same range as the horizontal one) or ValueError naming ``name``."""
    return check_real(name, value, lo=-AG_MAX, hi=AG_MAX)


class WorkLimitError(RuntimeError):
    """One `Simulator.advance` would take more internal steps than its budget (``max_steps``): the step is
    refused and the simulator is left as it was before the call. The message names the cause and the way
    out (shorter communication steps, a larger dt_max, a looser tolerance, or max_steps=None)."""


# ---------------------------------------------------------------------------------------------- state dicts
#: longest str value in a state dict
STATE_STR_MAX = 64
#: largest int counter in a state dict (int64, what any reader can hold)
STATE_INT_MAX = 2 ** 63 - 1


def _field(state, key):
    try:
        return state[key]
    except KeyError:
        raise ValueError(f"state field {key!r} is missing") from None


def check_state_keys(state, keys) -> None:
    """``state`` is a Mapping with exactly the str keys ``keys`` or ValueError naming the first field that
    is missing or not expected."""
    from collections.abc import Mapping

    if not isinstance(state, Mapping):
        raise ValueError(f"state must be a mapping (dict) of plain values, got {type(state).__name__}")
    for key in keys:
        if key not in state:
            raise ValueError(f"state field {key!r} is missing")
    extra = [k for k in state if k not in keys]
    if extra:
        raise ValueError(f"state field {str(extra[0])[:STATE_STR_MAX]!r} is not expected; allowed fields: "
                         f"{', '.join(sorted(keys))}")


def check_state_header(state, model: str, keys, version: int = 1) -> None:
    """The common head of a component's state dict: a Mapping with exactly ``keys``, the format
    ``version`` and the component's ``model`` name; ValueError naming the first field that is wrong."""
    from collections.abc import Mapping

    if not isinstance(state, Mapping):
        raise ValueError(f"state must be a mapping (dict) of plain values, got {type(state).__name__}")
    state_int(state, "version", version, version)
    state_str(state, "model", model)
    check_state_keys(state, keys)


# bool is an int, and numpy's float64 a float: the checks below take the plain types and their numeric
# subclasses (converted to plain values), never a bool where a number is expected or a number for a bool


def state_bool(state, key: str) -> bool:
    value = _field(state, key)
    if type(value) is not bool:
        raise ValueError(f"state field {key!r} must be a bool, got {type(value).__name__}")
    return value


def _as_int(key, value) -> int:
    if isinstance(value, int) and not isinstance(value, bool):
        return int(value)
    raise ValueError(f"state field {key!r} must be an int, got {type(value).__name__}")


def state_int(state, key: str, lo: int = 0, hi: int = STATE_INT_MAX) -> int:
    value = _as_int(key, _field(state, key))
    if not lo <= value <= hi:
        raise ValueError(f"state field {key!r} = {value} is out of range; allowed range [{lo}, {hi}]")
    return value


def _as_float(key, value) -> float:
    if isinstance(value, float):
        return float(value)
    if isinstance(value, int) and not isinstance(value, bool):
        return float(value)
    raise ValueError(f"state field {key!r} must be a float, got {type(value).__name__}")


def state_float(state, key: str, *, lo: float = -math.inf, hi: float = math.inf, nan_ok: bool = False,
                lo_open: bool = False) -> float:
    """A finite float in [lo, hi] (or (lo, hi] with lo_open); nan too when ``nan_ok``."""
    x = _as_float(key, _field(state, key))
    if nan_ok and x != x:
        return x
    if math.isfinite(x) and (lo < x or (not lo_open and x == lo)) and x <= hi:
        return x
    what = "finite" if not math.isfinite(x) else "in range"
    rng = f"{'(' if lo_open or lo == -math.inf else '['}{lo:g}, {hi:g}{')' if hi == math.inf else ']'}"
    raise ValueError(f"state field {key!r} = {x!r} is not {what}; allowed range {rng}"
                     + (" or nan (unset)" if nan_ok else ""))


def state_floats(state, key: str, *, length: int | None = None, multiple: int | None = None,
                 max_len: int | None = None) -> list[float]:
    """A list of finite floats with the given length (or a multiple of ``multiple``, at most max_len)."""
    value = _field(state, key)
    if not isinstance(value, (list, tuple)):
        raise ValueError(f"state field {key!r} must be a list of floats, got {type(value).__name__}")
    n = len(value)
    if length is not None and n != length:
        raise ValueError(f"state field {key!r} has {n} values; expected {length}")
    if multiple is not None and n % multiple:
        raise ValueError(f"state field {key!r} has {n} values; expected a multiple of {multiple}")
    if max_len is not None and n > max_len:
        raise ValueError(f"state field {key!r} has {n} values; allowed at most {max_len}")
    out = [_as_float(key, v) for v in value]
    for i, x in enumerate(out):
        if not math.isfinite(x):
            raise ValueError(f"state field {key!r}[{i}] = {x!r} is not finite")
    return out


def state_ints(state, key: str, *, lo: int, hi: int, max_len: int) -> list[int]:
    value = _field(state, key)
    if not isinstance(value, (list, tuple)) or len(value) > max_len:
        raise ValueError(f"state field {key!r} must be a list of at most {max_len} ints")
    for i, v in enumerate(value):
        if not isinstance(v, int) or isinstance(v, bool) or not lo <= v <= hi:
            raise ValueError(f"state field {key!r}[{i}] = {v!r} must be an int in [{lo}, {hi}]")
    return [int(v) for v in value]


def state_str(state, key: str, expected: str | None = None) -> str:
    value = _field(state, key)
    if type(value) is not str or len(value) > STATE_STR_MAX:
        raise ValueError(f"state field {key!r} must be a str of at most {STATE_STR_MAX} characters")
    if expected is not None and value != expected:
        raise ValueError(f"state field {key!r} = {value!r} does not match this simulator; expected {expected!r}")
    return value
