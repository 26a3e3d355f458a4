"""FMU variables: the table an FMU script declares (`Var`), the units, the shared variables (`AG_INPUT`,
`AG_V_INPUT`, `MAX_STEPS_PARAMETER`), the pythonfmu variable classes that write what pythonfmu 0.7 does not (unit, min,
max, enumeration types), and `model_variables`, which derives the variables of a model's FMU from the model's
own declarations (`rocking_model.params`)."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Dict, Optional
from xml.etree.ElementTree import Element

from pythonfmu import Fmi2Causality, Fmi2Variability
from pythonfmu.variables import Integer, Real

from ..validation import AG_MAX, MAX_STEPS

# SI base-unit exponents of every unit an FMU of this package may use (FMI 2.0 <BaseUnit> attributes).
UNITS: Dict[str, Dict[str, int]] = {
    "1": {},
    "m": {"m": 1},
    "s": {"s": 1},
    "kg": {"kg": 1},
    "rad": {"rad": 1},
    "rad/s": {"rad": 1, "s": -1},
    "rad/s2": {"rad": 1, "s": -2},
    "m/s": {"m": 1, "s": -1},
    "m/s2": {"m": 1, "s": -2},
    "1/s": {"s": -1},
    "Hz": {"s": -1},
    "J": {"kg": 1, "m": 2, "s": -2},
    "N": {"kg": 1, "m": 1, "s": -2},
    "N.m": {"kg": 1, "m": 2, "s": -2},
    "N.m2": {"kg": 1, "m": 3, "s": -2},
    "N/m": {"kg": 1, "s": -2},
    "N.s/m": {"kg": 1, "s": -1},
    "kg/m": {"kg": 1, "m": -1},
    "kg.m2": {"kg": 1, "m": 2},
    "Pa": {"kg": 1, "m": -1, "s": -2},
}

_CAUSALITIES = {"parameter": Fmi2Causality.parameter, "input": Fmi2Causality.input,
                "output": Fmi2Causality.output}
_VARIABILITIES = {"fixed": Fmi2Variability.fixed, "tunable": Fmi2Variability.tunable,
                  "discrete": Fmi2Variability.discrete, "continuous": Fmi2Variability.continuous}
_PY_TYPES = {"Real": float, "Integer": int, "Boolean": bool, "String": str}


@dataclass(frozen=True)
class Var:
    """One FMU variable.

    name: FMI name (also the key in the parameter dict and in ``Simulator.outputs()``).
    causality: "parameter", "input" or "output".
    start: start value (parameters, inputs); outputs report it until initialization is done.
    type: "Real", "Integer", "Boolean" or "String" (String: parameters only, e.g. a file name).
    unit: unit name, a key of ``UNITS`` (or of the FMU's ``extra_units``); required for Real.
    description: text for the modelDescription.
    variability: default "fixed" for parameters, "continuous" for Real inputs/outputs, "discrete"
        otherwise. A "tunable" parameter may be changed after initialization (the subclass must read it
        from ``self.parameter_values`` itself); "fixed" ones may not.
    min, max: optional declared range (written to the XML; inputs are checked against it in do_step).
    items: for an Integer that is a choice, the (name, code, description) of its values (named in the
        description; `rocking_model.fmi.run_fmu` takes the names as start values).
    """

    name: str
    causality: str
    start: Any = None
    type: str = "Real"
    unit: Optional[str] = None
    description: str = ""
    variability: Optional[str] = None
    min: Optional[float] = None
    max: Optional[float] = None
    items: tuple = ()

    def __post_init__(self):
        if self.items and self.type != "Integer":
            raise ValueError(f"Var {self.name!r}: only an Integer can be a choice (items)")
        if self.causality not in _CAUSALITIES:
            raise ValueError(f"Var {self.name!r}: causality must be one of {sorted(_CAUSALITIES)}")
        if self.type not in _PY_TYPES:
            raise ValueError(f"Var {self.name!r}: type must be one of {sorted(_PY_TYPES)}")
        if self.type == "Real" and self.unit is None:
            raise ValueError(f"Var {self.name!r}: a Real variable needs a unit ('1' if dimensionless)")
        if self.type != "Real" and self.unit is not None:
            raise ValueError(f"Var {self.name!r}: only Real variables carry a unit in FMI 2.0")
        if not self.description:
            raise ValueError(f"Var {self.name!r}: a description is required")
        if self.resolved_variability not in _VARIABILITIES:
            raise ValueError(f"Var {self.name!r}: variability must be one of {sorted(_VARIABILITIES)}")
        if self.causality == "parameter" and self.resolved_variability not in ("fixed", "tunable"):
            raise ValueError(f"Var {self.name!r}: a parameter is 'fixed' or 'tunable'")
        if self.type == "String" and self.causality != "parameter":
            raise ValueError(f"Var {self.name!r}: String variables are parameters here")
        if self.type != "Real" and self.resolved_variability == "continuous":
            raise ValueError(f"Var {self.name!r}: only Real variables can be 'continuous'")

    @property
    def resolved_variability(self) -> str:
        if self.variability is not None:
            return self.variability
        if self.causality == "parameter":
            return "fixed"
        return "continuous" if self.type == "Real" else "discrete"

    @property
    def default(self):
        """Start value cast to the Python type (0 / 0.0 / False when no start is given)."""
        py = _PY_TYPES[self.type]
        return py(0) if self.start is None else py(self.start)


    def range_text(self) -> str:
        lo = "-inf" if self.min is None else f"{self.min:g}"
        hi = "inf" if self.max is None else f"{self.max:g}"
        return f"[{lo}, {hi}]"


#: the ground acceleration input of every FMU that takes one (the bound of `rocking_model.validation.AG_MAX`)
AG_INPUT = Var("ag", "input", 0.0, unit="m/s2", min=-AG_MAX, max=AG_MAX,
               description="Horizontal ground acceleration (held constant over each communication step), "
                           f"|ag| <= {AG_MAX:g} m/s2 (about 100 g)")
#: the vertical ground acceleration input of the rocking FMUs, the same range, checks, statuses and input
#: derivatives as `AG_INPUT`; start 0 gives exactly the horizontal-only results
AG_V_INPUT = Var("ag_v", "input", 0.0, unit="m/s2", min=-AG_MAX, max=AG_MAX,
                 description="Vertical ground acceleration, positive upward: the effective gravity is g + ag_v "
                             "(g + ag_v < 0 makes the body leave the ground); held constant over each "
                             "communication step (or interpolated linearly with fmi2SetRealInputDerivatives), "
                             f"|ag_v| <= {AG_MAX:g} m/s2")
#: the work budget of one communication step, a parameter of every FMU that runs a `Simulator`
#: [internal steps] largest work budget of one communication step an FMU accepts: at the costliest internal
#: step (a Moreau-Jean step, about 0.3 ms) 1e9 steps take days, far beyond any use, and the bound fits the
#: 32-bit fmi2Integer. The FMUs check max_steps against this declaration (ModelSlave.create_simulator), so
#: the modelDescription's min/max, the check and its message agree.
MAX_STEPS_LIMIT = 1_000_000_000
MAX_STEPS_PARAMETER = Var("max_steps", "parameter", MAX_STEPS, type="Integer", min=1, max=MAX_STEPS_LIMIT,
                          description="Work budget of one communication step: internal steps (Moreau-Jean "
                                      "steps, or Runge-Kutta steps with each event counting 30); a step that "
                                      "needs more is refused (fmi2Discard, state unchanged, message naming "
                                      "the cause)")


# ----------------------------------------------------------------------------------------------------
# pythonfmu variables with the attributes pythonfmu 0.7 does not write (unit, min, max)
def _fmt(value, type_: str) -> str:
    if type_ == "Real":
        return repr(float(value))         # the shortest text that reads back as the same double
    if type_ == "Boolean":
        return "true" if value else "false"
    return str(int(value))


#: Python's spelling of the non-finite doubles -> xs:double's (a start value of mu = inf)
_XS_DOUBLE = {"inf": "INF", "-inf": "-INF", "nan": "NaN"}


class _ExtraAttrs:
    """Mixin: add attributes to the type element (<Real>, <Integer>) of the ScalarVariable node."""

    _type_tag = ""

    def _set_extra(self, **attrs):
        self._extra = {k: v for k, v in attrs.items() if v is not None}

    def to_xml(self) -> Element:
        node = super().to_xml()
        child = node.find(self._type_tag)
        for key, value in getattr(self, "_extra", {}).items():
            child.set(key, value)
        # pythonfmu writes Python's spelling of the non-finite start values; xs:double spells them INF, NaN
        start = child.get("start")
        if start in _XS_DOUBLE:
            child.set("start", _XS_DOUBLE[start])
        return node


class UnitReal(_ExtraAttrs, Real):
    """pythonfmu ``Real`` with ``unit``, ``min`` and ``max`` attributes."""

    _type_tag = "Real"

    def __init__(self, name: str, unit: str, min: Optional[float] = None, max: Optional[float] = None,
                 **kwargs):
        super().__init__(name, **kwargs)
        self.unit = unit
        self._set_extra(unit=unit, min=None if min is None else _fmt(min, "Real"),
                        max=None if max is None else _fmt(max, "Real"))


class RangedInteger(_ExtraAttrs, Integer):
    """pythonfmu ``Integer`` with ``min`` and ``max`` attributes."""

    _type_tag = "Integer"

    def __init__(self, name: str, min: Optional[int] = None, max: Optional[int] = None, **kwargs):
        super().__init__(name, **kwargs)
        self._set_extra(min=None if min is None else _fmt(min, "Integer"),
                        max=None if max is None else _fmt(max, "Integer"))


def param_variable(p, causality: str = "parameter") -> Var:
    """The FMU variable of a declared `rocking_model.params.Param`: start value, unit, min/max and description
    from the declaration (a choice becomes an Integer whose description names the choices)."""
    if p.items:
        # an Integer with the choices named in its description, not an FMI Enumeration: libcosim 0.10 ignores
        # Enumeration variables (libcosim issues 246, 670), so the scheme could not be set there, and fmpy
        # converts Enumeration start values with int() as well (`run_fmu` takes the names)
        return Var(p.name, causality, p.check(p.default), type="Integer", items=tuple(p.items),
                   min=p.fmu_min(), max=p.fmu_max(),
                   description=f"{p.description}: " + "; ".join(f"{code} {name} ({d})" for name, code, d in p.items))
    if causality == "output":
        return Var(p.name, "output", unit=p.unit, description=p.description)
    text = p.description
    if p.lo is not None or p.hi is not None:
        text = f"{text}; allowed range {p.range_text()}"
    return Var(p.name, causality, p.default, unit=p.unit, min=p.fmu_min(), max=p.fmu_max(), description=text)


def model_variables(model_class, solver_parameters=(), extra_parameters=(), inputs=(), extra_outputs=()) -> tuple:
    """The variable table of the FMU of ``model_class`` from its declarations: its parameters
    (``model_class.parameters()``), its initial values (``INITIAL``), the solver parameters, the
    ``extra_parameters`` (Vars), the inputs (Vars), its outputs (``OUTPUTS``) and the ``extra_outputs``."""
    out = [param_variable(p) for p in model_class.parameters() if p.fmu]
    out += [param_variable(p) for p in model_class.INITIAL if p.fmu]
    out += [param_variable(p) for p in solver_parameters if p.fmu]
    out += list(extra_parameters) + list(inputs)
    out += [param_variable(p, "output") for p in model_class.OUTPUTS]
    out += list(extra_outputs)
    return tuple(out)
