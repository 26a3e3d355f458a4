"""Declared parameters: name, default, unit, allowed range and description, written once.

A model declares its parameters as dataclass fields made by `param` and its initial values and outputs as
`Param` tuples; the model's checks, the `Simulator`'s solver options, the command line and the FMUs (start
values, ``min``/``max``, descriptions, enumeration items) all read these declarations (`declared_parameters`),
so that a default or a range lives in one place.
"""
from __future__ import annotations

import dataclasses
import functools
import math
from dataclasses import dataclass
from typing import Any

from .validation import check_choice, check_real


@dataclass(frozen=True)
class Param:
    """One declared quantity.

    name: the keyword (and FMU variable) name; default: its value when not given; unit: SI unit ("1" if
    dimensionless, None for integers and choices); description: one sentence for documentation and tools;
    lo, hi, lo_open, hi_open: the allowed range of a real value (None: unbounded); items: for a choice, the
    allowed values as (name, code, description) -- the value is given by name or code and stored as the code;
    fmu: whether the FMUs expose it (False: Python API only)."""

    name: str
    default: Any
    unit: str | None = "1"
    description: str = ""
    lo: float | None = None
    hi: float | None = None
    lo_open: bool = False
    hi_open: bool = False
    items: tuple = ()
    fmu: bool = True
    #: whether +inf is an allowed value (a limit, e.g. the friction coefficient of the sticking law)
    inf_ok: bool = False

    def check(self, value):
        """``value`` checked against the declaration (ValueError naming it and the allowed range/values);
        a choice is returned as its code."""
        if self.accepts_as_is(value):
            return value
        if self.items:
            return check_choice(self.name, value, self._allowed)
        if self.inf_ok and isinstance(value, (int, float, str)) and not isinstance(value, bool):
            try:
                if float(value) == math.inf:
                    return math.inf
            except ValueError:
                pass
        try:
            return check_real(self.name, value, lo=self.lo, hi=self.hi, lo_open=self.lo_open,
                              hi_open=self.hi_open)
        except ValueError as exc:
            if self.inf_ok and self.hi is None:          # the range includes +inf
                raise ValueError(str(exc).replace(", inf)", ", inf]")) from None
            raise

    @functools.cached_property
    def accepts_as_is(self):
        """A predicate true of the values that `check` returns unchanged (a float inside a real range, an int
        code of a choice, +inf where it is allowed): the common case, tested without the checks' calls. A value
        it rejects is not bad: `check` converts it or names it in its message."""
        if self.items:
            codes = frozenset(code for _, code, _ in self.items)
            return lambda x: type(x) is int and x in codes
        lo, hi = (-math.inf if self.lo is None else self.lo), (math.inf if self.hi is None else self.hi)
        lo_open, hi_open = self.lo_open or self.lo is None, self.hi_open or self.hi is None
        inf_ok = self.inf_ok

        def accepts(x) -> bool:
            if type(x) is not float:
                return False
            if inf_ok and x == math.inf:
                return True
            return (lo < x or (not lo_open and x == lo)) and (x < hi or (not hi_open and x == hi))
        return accepts

    @functools.cached_property
    def _allowed(self) -> dict:
        """A choice's accepted spellings: its codes, then its names (made once: every model built checks them)."""
        allowed = {code: code for _, code, _ in self.items}
        allowed.update({name: code for name, code, _ in self.items})
        return allowed

    def fmu_min(self):
        """Closed lower bound for the FMU's ``min`` attribute (None: none; an open bound is written as is,
        the check names it)."""
        if self.items:
            return min(code for _, code, _ in self.items)
        return None if self.lo is None or not math.isfinite(self.lo) else self.lo

    def fmu_max(self):
        if self.inf_ok:
            return None
        if self.items:
            return max(code for _, code, _ in self.items)
        return None if self.hi is None or not math.isfinite(self.hi) else self.hi

    def range_text(self) -> str:
        if self.items:
            return ", ".join(f"{code} {name}" for name, code, _ in self.items)
        lo = "-inf" if self.lo is None else f"{self.lo:g}"
        hi = "inf" if self.hi is None else f"{self.hi:g}"
        text = (f"{'(' if self.lo_open or self.lo is None else '['}{lo}, {hi}"
                f"{')' if self.hi_open or self.hi is None else ']'}")
        if self.inf_ok and self.hi is None:
            return text[:-1] + "]"
        return text + (" or inf" if self.inf_ok else "")


def param(default, unit: str | None = "1", description: str = "", **kw):
    """A dataclass field declared as a `Param` (its name is the field's name)."""
    return dataclasses.field(default=default, metadata={"param": dict(default=default, unit=unit,
                                                                      description=description, **kw)})


#: class -> its declared parameters (a class's fields do not change once it is made; every model built reads
#: them, and building them from the dataclass fields costs more than the checks themselves)
_DECLARED: dict = {}


def declared_parameters(cls) -> tuple:
    """The `Param` of every dataclass field of ``cls`` declared with `param`, in field order."""
    out = _DECLARED.get(cls)
    if out is None:
        out = []
        for f in dataclasses.fields(cls):
            spec = f.metadata.get("param")
            if spec is not None:
                out.append(Param(name=f.name, **spec))
        out = _DECLARED[cls] = tuple(out)
    return out


#: class -> (name, accepts_as_is, Param) of its declared parameters (every model built reads them)
_CHECKS: dict = {}


def check_parameters(obj) -> None:
    """Check (and convert) every declared parameter of the dataclass instance ``obj`` in place (a value that
    `Param.accepts_as_is` is left as it is, without the call into the checks)."""
    d = obj.__dict__
    checks = _CHECKS.get(type(obj))
    if checks is None:
        checks = _CHECKS[type(obj)] = tuple((p.name, p.accepts_as_is, p) for p in declared_parameters(type(obj)))
    for name, accepts, p in checks:
        value = d[name] if name in d else getattr(obj, name)
        if not accepts(value):
            object.__setattr__(obj, name, p.check(value))
