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
