"""Ensembles of rocking simulations: case grids, one pure function per case, and runners (serial, or Dask).

A case is a flat dict of plain values (model, geometry, ground motion, scheme, solver settings) with a
content-based ``case_id``; `run_case` turns it into a result row (the case plus max|phi|, overturned, time
of overturning, impacts, wall time). `run_ensemble` runs a list of cases on a Dask cluster (a LocalCluster
on this machine by default, or an existing scheduler by address) or serially (workers=0, no Dask needed),
writes each row as soon as it arrives (CSV appended and flushed, or Parquet parts) and, on restart, skips
the case ids already in the output, so an interrupted run loses nothing and resumes. A run holds a lock on
its output (`OutputLock`) from start to end, so two runs never write to one output; outputs are only
appended to, and a resume sets aside what an interruption broke (rows, parts) without losing good rows.

A vertical ground acceleration ag_v [m/s2] (positive upward) enters through two case fields: ``ag_v_scale``
[1] (0, the default, means no vertical component) and ``vertical`` (the vertical record's file for a record
given as two files, "" otherwise). ag_v is ``ag_v_scale`` times the record's vertical component (its third CSV
column or its ``vertical`` file) or, for a record without one and for the pulses, times the horizontal motion
itself; the record's ``scale`` applies to both components. A case without a vertical component has the
case id it had before these fields existed, and a result file written before them (without their columns)
resumes: its header is completed on the first resume (`RepairWarning`).

The model's other declared parameters (`rocking_model.models.MODELS`: e.g. m, P0, k_t of the post-tensioned
block, EI of the flexible oscillator) enter through the case field ``params``: a JSON object of the values
given (by name; "" for none: the model's declared defaults). A case without any has the case id it had before
this field existed, and a result file written before it resumes (its header is completed, `RepairWarning`).

Dimensionless pulse grids follow Makris' overturning spectra: amplitude ratio A / (g tan(alpha)) and
frequency ratio omega_p / p of a rigid block (alpha = atan(b/h), p = sqrt(3g/(4R))): the models that are rigid
blocks (`is_rigid_block`: the rigid block and its subclasses, such as the post-tensioned block). For the
post-tensioned block these are its rigid block's ratios: its uplift threshold from rest is
tan(alpha) (g + P0/m), so its uplift starts above a_ratio = 1 + P0/(m g), and its tendon makes it stiffer than
p says.
"""
from __future__ import annotations

import csv
import functools
import hashlib
import io
import itertools
import json
import logging
import math
import os
import secrets
import socket
import time
import warnings
from pathlib import Path
from typing import Callable, Iterable, Sequence

from .ground_motion import PULSES
from .integrators import SCHEMES as _SCHEME_CLASSES
from .models import model_class

# PULSES: the pulse kinds of the grids, built by `ground_motion.pulse_from_parameters` (rectangular:
# duration 2 pi / omega_p)
#: the registered schemes (`rocking_model.integrators.SCHEMES`), event-driven first (the default)
SCHEMES = tuple(sorted(_SCHEME_CLASSES, key=lambda name: -_SCHEME_CLASSES[name].code))

#: case fields, in output column order
CASE_FIELDS = ("case_id", "model", "b", "h", "e_N", "mu", "params", "motion", "A", "omega_p", "a_ratio", "w_ratio",
               "record", "units", "scale", "vertical", "ag_v_scale", "scheme", "t_end", "output_interval",
               "tolerance", "dt_max", "im", "im_level")
#: the case fields of the vertical ground acceleration and their values in a case without one (the rows of
#: result files written before they existed, the cases whose ids stay those of earlier versions)
VERTICAL_DEFAULTS = {"vertical": "", "ag_v_scale": 0.0}
#: the case field of the model's other parameters and its value in a case without any (as VERTICAL_DEFAULTS)
PARAMS_DEFAULTS = {"params": ""}
#: the fields of a record scaled to a target intensity measure (`rocking_model.assessment`: stripes, IDA): the
#: measure's name (`rocking_model.intensity`) and its target value [its units]; and the result field of the
#: models with a tendon; their values in a case (or a row of an older file) without them
IM_DEFAULTS = {"im": "", "im_level": math.nan, "max_tendon_force": math.nan}
#: the case fields added since the first version, in the order they were added, with their values in a case
#: (or a row of an older file) without them
ADDED_FIELDS = (VERTICAL_DEFAULTS, PARAMS_DEFAULTS, IM_DEFAULTS)
#: the case fields set by `pulse_cases` / `record_cases` themselves, not through ``params``
_OWN_FIELDS = ("b", "h", "e_N", "mu")
#: [1] allowed range of ag_v_scale: a vertical component up to 10 times the record's (or the horizontal's);
#: the simulators refuse any |ag_v| above AG_MAX anyway
AG_V_SCALE_MAX = 10.0
#: result fields appended by `run_case`
RESULT_FIELDS = ("alpha", "p", "max_abs_phi", "max_phi_over_alpha", "overturned", "t_overturn", "impacts",
                 "max_abs_slip", "friction_demand", "max_tendon_force", "wall_time", "error")
FIELDS = CASE_FIELDS + RESULT_FIELDS

_FLOATS = {"b", "h", "e_N", "mu", "max_abs_slip", "friction_demand", "A", "omega_p", "a_ratio", "w_ratio", "scale",
           "ag_v_scale", "t_end", "output_interval",
           "tolerance", "dt_max", "alpha", "p", "max_abs_phi", "max_phi_over_alpha", "t_overturn",
           "wall_time", "im_level", "max_tendon_force"}
_INTS = {"impacts"}
_BOOLS = {"overturned"}


def case_id(case: dict) -> str:
    """Content hash of the case's parameters: the same case gets the same id in every run."""
    key = {k: case.get(k) for k in CASE_FIELDS if k != "case_id"}
    if key.get("mu") in (None, math.inf):
        del key["mu"]             # the default law: the ids of the cases of earlier versions stay valid
    if not _ag_v_scale(case):
        del key["vertical"], key["ag_v_scale"]      # no vertical component: the ids of earlier versions
    if key.get("params") in (None, ""):
        del key["params"]         # the model's defaults: the ids of earlier versions
    if key.get("im") in (None, ""):
        del key["im"], key["im_level"]      # not scaled to a measure: the ids of earlier versions
    else:
        # a record scaled to a measure's level is that level: the scale factor (and the PGA and ratio that
        # follow from it) is derived from the record's measure, whose last bits may differ between machines
        del key["scale"], key["A"], key["a_ratio"]
    return hashlib.sha1(json.dumps(key, sort_keys=True, default=repr).encode()).hexdigest()[:16]


def _ag_v_scale(case: dict) -> float:
    """The case's ag_v_scale [1]; 0 when absent, empty or NaN (a case or row without a vertical component)."""
    v = case.get("ag_v_scale")
    if v in (None, ""):
        return 0.0
    try:
        v = float(v)
    except (TypeError, ValueError):
        return v                  # kept as it is, so that the case's own check names it
    return 0.0 if v != v else v


def _rigid_scales(b: float, h: float, g: float = 9.81) -> tuple[float, float]:
    """(alpha [rad], p [rad/s]) of the rigid block."""
    R = math.hypot(b, h)
    return math.atan2(b, h), math.sqrt(3.0 * g / (4.0 * R))


def is_rigid_block(model: str) -> bool:
    """Whether the registered model ``model`` is a rigid block of half-width b and half-height h (the
    `RigidBlock` and its subclasses, e.g. the post-tensioned block): its slenderness alpha, frequency parameter
    p and the dimensionless ratios of the overturning spectra are the block's."""
    from .models import RigidBlock

    return issubclass(model_class(model), RigidBlock)


def model_params(model: str, params: dict | None) -> str:
    """The case field ``params``: the model's declared parameters in ``params`` (other than b, h, e_N and mu,
    case fields of their own) checked against its declarations, as a JSON object with sorted keys; "" for
    none. ValueError naming a parameter the model does not declare or a value out of its range."""
    if not params:
        return ""
    declared = {p.name: p for p in model_class(model).parameters()}
    out = {}
    for name, value in params.items():
        if name in _OWN_FIELDS:
            raise ValueError(f"params: {name} is a case field of its own (give it as "
                             f"{'geometries' if name in ('b', 'h') else name})")
        if name not in declared:
            raise ValueError(f"params: {name!r} is not a parameter of the {model} model; allowed: "
                             + ", ".join(n for n in declared if n not in _OWN_FIELDS))
        value = declared[name].check(value)
        out[name] = value if isinstance(value, int) and not isinstance(value, bool) else float(value)
    return json.dumps(out, sort_keys=True, separators=(",", ":"))


def _params_of(case: dict) -> dict:
    """The model parameters of a case's ``params`` field ({} when absent or empty)."""
    text = case.get("params")
    if text in (None, "") or (isinstance(text, float) and text != text):
        return {}
    if isinstance(text, dict):
        return dict(text)
    value = json.loads(text)
    if not isinstance(value, dict):
        raise ValueError(f"params = {text!r}: a JSON object of model parameters by name")
    return value


def _block_scales(model: str, b: float, h: float, params: str) -> tuple[float, float, float]:
    """(alpha [rad], p [rad/s], g [m/s2]) of a rigid-block model (`is_rigid_block`), NaN for the others."""
    if not is_rigid_block(model):
        return math.nan, math.nan, math.nan
    g = float(_params_of({"params": params}).get("g", 9.81))
    return (*_rigid_scales(b, h, g), g)


def _finish(case: dict) -> dict:
    defaults = {k: v for added in ADDED_FIELDS for k, v in added.items()}
    case = {k: case.get(k, "" if k in ("record", "units") else math.inf if k == "mu" else
                        defaults.get(k, math.nan)) for k in CASE_FIELDS}
    case["case_id"] = case_id(case)
    return case


def _check_case_fields(model: str, geometries, e_N, mu, t_end, output_interval, tolerance, dt_max) -> None:
    """Refuse a bad case field before anything runs (ValueError naming the field and its allowed range):
    b, h, e_N and mu through the model's declared checks (`rocking_model.params`), tolerance and dt_max
    through the solver's (`simulation.SOLVER_PARAMETERS`)."""
    from .simulation import SOLVER_PARAMETERS
    from .validation import check_real

    declared = {p.name: p for p in model_class(model).parameters()}
    solver = {p.name: p for p in SOLVER_PARAMETERS}
    try:
        geometries = [(b, h) for b, h in geometries]
    except (TypeError, ValueError):
        raise ValueError(f"geometries = {geometries!r}: give a list of (b, h) pairs [m]") from None
    if not geometries:
        raise ValueError("geometries: give at least one (b, h) pair [m]")
    for b, h in geometries:
        declared["b"].check(b)
        declared["h"].check(h)
    declared["e_N"].check(e_N)
    declared["mu"].check(mu)
    if t_end is not None:
        check_real("t_end", t_end, lo=0.0, lo_open=True)
    check_real("output_interval", output_interval, lo=0.0, lo_open=True)
    solver["tolerance"].check(tolerance)
    if dt_max is not None:
        solver["dt_max"].check(dt_max)


def _check_ag_v_scales(values) -> list[float]:
    from .validation import check_real
    out = [check_real("ag_v_scale", v, lo=-AG_V_SCALE_MAX, hi=AG_V_SCALE_MAX) for v in values]
    if not out:
        raise ValueError("ag_v_scale: give at least one value")
    return out


def _check_list(name: str, values, lo=0.0) -> list[float]:
    from .validation import check_real
    out = [check_real(name, v, lo=lo, lo_open=True) for v in values]
    if not out:
        raise ValueError(f"{name}: give at least one value")
    return out


def pulse_cases(kind: str = "sine", *, amplitude_ratios: Sequence[float] | None = None,
                frequency_ratios: Sequence[float] | None = None, amplitudes: Sequence[float] | None = None,
                frequencies: Sequence[float] | None = None, geometries: Sequence[tuple[float, float]] = ((0.2, 1.0),),
                schemes: Sequence[str] = ("event_driven",), model: str = "rigid", e_N: float = 0.0,
                mu: float = math.inf, t_end: float | None = None, output_interval: float = 0.01, tolerance: float = 1e-8,
                dt_max: float | None = None, ag_v_scales: Sequence[float] = (0.0,),
                params: dict | None = None) -> list[dict]:
    """Grid of pulse cases: pulse ``kind`` x amplitudes x frequencies x geometries (b, h) [m] x schemes x
    ag_v_scales.

    Amplitudes either as ratios A / (g tan(alpha)) or in m/s2; frequencies as ratios omega_p / p or in Hz
    (omega_p = 2 pi f). Ratios need a rigid block (`is_rigid_block`: the rigid and the post-tensioned block;
    for the post-tensioned block they are those of its rigid block, whose uplift threshold tan(alpha) g the
    tendon raises to tan(alpha) (g + P0/m)). t_end [s] defaults to the end of the pulse plus 15/p
    (enough for overturning after an impact). dt_max: Moreau-Jean step [s] (default 1e-3). e_N, mu: the
    model's coefficient of restitution and friction coefficient (inf: the paper's sticking law).
    ag_v_scales: vertical components [1], in [-10, 10]: ag_v = ag_v_scale x the pulse (0, the default: none).
    params: the model's other declared parameters by name (e.g. {"m": 1000, "P0": 2e4, "k_t": 2e6}; the case
    field ``params``, `model_params`); g among them sets the ratios' g."""
    if kind not in PULSES:
        raise ValueError(f"pulse = {kind!r} is not supported; allowed values: {', '.join(PULSES)}")
    model_class(model)                    # ValueError naming the registered models
    _check_case_fields(model, geometries, e_N, mu, t_end, output_interval, tolerance, dt_max)
    if (amplitude_ratios is None) == (amplitudes is None):
        raise ValueError("give either amplitude ratios A/(g tan alpha) or amplitudes [m/s2]")
    if (frequency_ratios is None) == (frequencies is None):
        raise ValueError("give either frequency ratios omega_p/p or frequencies [Hz]")
    extra = model_params(model, params)
    block = is_rigid_block(model)
    if not block and (amplitude_ratios is not None or frequency_ratios is not None):
        raise ValueError(f"amplitude and frequency ratios are defined for the rigid blocks; give amplitudes "
                         f"[m/s2] and frequencies [Hz] for the {model_class(model).title}")
    amps = _check_list("amplitude ratio" if amplitudes is None else "amplitude",
                       amplitude_ratios if amplitudes is None else amplitudes)
    freqs = _check_list("frequency ratio" if frequencies is None else "frequency",
                        frequency_ratios if frequencies is None else frequencies)
    vscales = _check_ag_v_scales(ag_v_scales)
    for s in schemes:
        if s not in SCHEMES:
            raise ValueError(f"scheme = {s!r} is not supported; allowed values: {', '.join(SCHEMES)}")
    cases = []
    for (b, h), scheme, a, f, v in itertools.product(geometries, schemes, amps, freqs, vscales):
        alpha, p, g = _block_scales(model, b, h, extra)
        A = a * g * math.tan(alpha) if amplitudes is None else a
        omega_p = f * p if frequencies is None else 2.0 * math.pi * f
        T_p = 2.0 * math.pi / omega_p
        t_pulse = 3.0 * T_p if kind == "ricker" else T_p
        p_ref = p if block else 2.5
        te = t_end if t_end is not None else t_pulse + 15.0 / p_ref
        cases.append(_finish(dict(model=model, b=float(b), h=float(h), e_N=float(e_N), mu=float(mu), params=extra,
                                  motion=kind, A=A,
                                  omega_p=omega_p, a_ratio=A / (g * math.tan(alpha)) if block
                                  else math.nan, w_ratio=omega_p / p if block else math.nan,
                                  scale=1.0, ag_v_scale=float(v), scheme=scheme, t_end=float(te),
                                  output_interval=output_interval,
                                  tolerance=tolerance, dt_max=math.nan if dt_max is None else dt_max)))
    return cases


def record_cases(records: Sequence[str], scales: Sequence[float] = (1.0,), *, units: str | None = None,
                 geometries: Sequence[tuple[float, float]] = ((0.2, 1.0),), schemes: Sequence[str] = ("event_driven",),
                 model: str = "rigid", e_N: float = 0.0, mu: float = math.inf, t_end: float | None = None,
                 output_interval: float = 0.01, tolerance: float = 1e-8, dt_max: float | None = None,
                 vertical: Sequence[str] | None = None, ag_v_scales: Sequence[float] | None = None,
                 params: dict | None = None) -> list[dict]:
    """Grid of record cases: records (file paths or ``synthetic:<seed>``) x scale factors x geometries x
    schemes x ag_v_scales. t_end [s] defaults to the record's end plus 5 s. The records are read here once
    (so a bad file fails before anything runs) and again, once per worker, by `run_case`.

    vertical: one vertical record (file or synthetic:<seed>; "" for none) per record, its vertical component
    (see `rocking_model.records.combine`); a three-column CSV record has its own. ag_v_scales [1], in
    [-10, 10]: ag_v = ag_v_scale x the vertical component, or x the horizontal record for a record without
    one; default 1 for records with a vertical component, 0 (none) for the others. ``scale`` applies to
    both components. params: the model's other declared parameters by name, as in `pulse_cases`; a_ratio
    (PGA / (g tan(alpha))) is set for the rigid blocks (`is_rigid_block`), NaN for the others."""
    from .records import load_motion

    model_class(model)
    _check_case_fields(model, geometries, e_N, mu, t_end, output_interval, tolerance, dt_max)
    extra = model_params(model, params)
    scales = _check_list("scale", scales)
    records = list(records)
    verticals = [""] * len(records) if vertical is None else ["" if v is None else str(v) for v in vertical]
    if len(verticals) != len(records):
        raise ValueError(f"vertical: give one vertical record per record ({len(records)}), got {len(verticals)} "
                         "(\"\" for a record without one)")
    if ag_v_scales is not None:
        ag_v_scales = _check_ag_v_scales(ag_v_scales)
    for s in schemes:
        if s not in SCHEMES:
            raise ValueError(f"scheme = {s!r} is not supported; allowed values: {', '.join(SCHEMES)}")
    cases = []
    for spec, vspec in zip(records, verticals):
        rec = load_motion(spec, units, vertical=vspec or None)
        spec = spec if str(spec).startswith("synthetic") else str(Path(spec).resolve())
        vspec = vspec if not vspec or vspec.startswith("synthetic") else str(Path(vspec).resolve())
        te = t_end if t_end is not None else float(rec.t[-1]) + 5.0
        vscales = ag_v_scales if ag_v_scales is not None else [0.0 if rec.vertical is None else 1.0]
        for (b, h), scheme, s, v in itertools.product(geometries, schemes, scales, vscales):
            alpha, p, g = _block_scales(model, b, h, extra)
            cases.append(_finish(dict(model=model, b=float(b), h=float(h), e_N=float(e_N), mu=float(mu), params=extra,
                                      motion="record", record=spec, units=units or "", scale=float(s), vertical=vspec,
                                      ag_v_scale=float(v), scheme=scheme,
                                      A=rec.pga * s, a_ratio=rec.pga * s / (g * math.tan(alpha)),
                                      t_end=float(te), output_interval=output_interval, tolerance=tolerance,
                                      dt_max=math.nan if dt_max is None else dt_max)))
    return cases


# --------------------------------------------------------------------------------------------- one case
@functools.lru_cache(maxsize=32)
def _record(spec: str, units: str, vertical: str = ""):
    from .records import load_motion
    return load_motion(spec, units or None, vertical=vertical or None)


def case_motion(case: dict):
    """The GroundMotion of a case: horizontal only when its ag_v_scale is 0 (or absent), else with the vertical
    component ag_v_scale x (the record's vertical component, or the horizontal motion)."""
    from . import ground_motion as gm
    from .validation import check_real

    kind = case["motion"]
    v = _ag_v_scale(case)
    if v:
        v = check_real("ag_v_scale", v, lo=-AG_V_SCALE_MAX, hi=AG_V_SCALE_MAX)
    if kind == "record":
        rec = _record(case["record"], case.get("units") or "", (case.get("vertical") or "") if v else "")
        if not v:
            return rec.horizontal.scaled(case["scale"])
        rec = rec.scaled(case["scale"])
        return rec.scaled_vertical(v) if rec.vertical is not None else rec.with_vertical(v * rec.ag)
    if kind not in PULSES:
        raise ValueError(f"motion = {kind!r} is not supported; allowed values: record, {', '.join(PULSES)}")
    # the pulse starts at t = 0 (Ricker: centred at 1.5 T_p); a rectangular pulse lasts 2 pi / omega_p
    m = gm.pulse_from_parameters(kind, case["A"], case["omega_p"], scale=case.get("scale", 1.0))
    return gm.TwoComponentMotion(m, m.scaled(v)) if v else m


def case_model(case: dict):
    """The model of a case: the registered ``case["model"]`` (`rocking_model.models.MODELS`) with the case's
    b, h, e_N and mu (inf where a file of an earlier version has none) and the parameters of its ``params``
    (none where absent). The models are immutable, so one made for the same (model, b, h, e_N, mu, params) of
    plain floats and text is reused (an ensemble has few geometries and many motions; building and checking a
    model is a third of a compiled case's Python work)."""
    mu = case.get("mu", math.inf)
    mu = math.inf if mu != mu else mu
    name, b, h, e_N = case["model"], case["b"], case["h"], case["e_N"]
    params = case.get("params")
    params = "" if params is None or (isinstance(params, float) and params != params) else params
    if type(name) is str and type(b) is float and type(h) is float and type(e_N) is float and type(mu) is float \
            and type(params) is str:
        return _cached_model(name, b, h, e_N, mu, params)
    return model_class(name)(b=b, h=h, e_N=e_N, mu=mu, **_model_kwargs(name, params))


def _model_kwargs(name: str, params) -> dict:
    """The keyword arguments of a case's ``params`` (TypeError-free: a name the model does not declare is a
    ValueError naming it)."""
    kw = _params_of({"params": params})
    declared = {p.name for p in model_class(name).parameters()} - set(_OWN_FIELDS)
    unknown = sorted(set(kw) - declared)
    if unknown:
        raise ValueError(f"params: {unknown[0]!r} is not a parameter of the {name} model; allowed: "
                         + ", ".join(sorted(declared)))
    return kw


@functools.lru_cache(maxsize=256)
def _cached_model(name: str, b: float, h: float, e_N: float, mu: float, params: str = ""):
    """A model of plain float parameters (a failed check raises and is not cached)."""
    return model_class(name)(b=b, h=h, e_N=e_N, mu=mu, **_model_kwargs(name, params))


def run_case(case: dict) -> dict:
    """Simulate one case; return its row (the case plus results). Never raises: any failure of the case (a
    field missing, of the wrong type or out of range, a model or solver error) is recorded in ``error``, so
    one bad case does not stop an ensemble, its batch keeps its good cases, and a resume skips the case (its
    row is in the output). t_overturn [s] is the first output time at which the block has overturned
    (resolution: output_interval); NaN if it did not."""
    t0 = time.perf_counter()
    try:
        row = dict(case)
    except (TypeError, ValueError):
        row = {"error_case": repr(case)[:200]}
    row.update(alpha=math.nan, p=math.nan, max_abs_phi=math.nan, max_phi_over_alpha=math.nan, overturned=False,
               t_overturn=math.nan, impacts=-1, max_abs_slip=math.nan, friction_demand=math.nan,
               max_tendon_force=math.nan, error="")
    try:
        row["case_id"] = _key(case)
        if "error_case" in row:
            raise TypeError(f"a case is a dict of case fields, got {row.pop('error_case')}")
        row.update(_simulate_case(case))
    except KeyError as exc:
        row["error"] = f"case field {exc.args[0]!r} is missing"
    except Exception as exc:          # recorded, not raised: see the docstring
        row["error"] = f"{type(exc).__name__}: {exc}"
    row["wall_time"] = time.perf_counter() - t0
    return row


def _simulate_case(case: dict) -> dict:
    """The result fields of one case (raises on a bad case; `run_case` records it)."""
    import numpy as np

    from .simulation import simulate

    model = case_model(case)             # b, h, e_N, mu, params checked against the model's declarations
    rigid = is_rigid_block(case["model"])
    alpha, p = _rigid_scales(model.b, model.h, model.g) if rigid else (math.nan, math.nan)
    kw = {}
    if case["scheme"] == "event_driven":
        kw["tolerance"] = case["tolerance"]
    if case.get("dt_max") is not None and not math.isnan(float(case["dt_max"])):
        kw["dt_max"] = case["dt_max"]
    res = simulate(model, case_motion(case), case["t_end"], scheme=case["scheme"],
                   output_interval=case["output_interval"], **kw)
    phi = np.abs(res.phi)
    over = np.asarray(res.overturned, dtype=bool)
    tendon = res.values.get("tendon_force")          # the models with a tendon (post-tensioned block) [N]
    return dict(alpha=alpha, p=p, max_abs_phi=float(phi.max()),
                max_tendon_force=math.nan if tendon is None else float(np.max(np.abs(tendon))),
                max_phi_over_alpha=float(phi.max() / alpha) if rigid else math.nan,
                overturned=bool(over[-1]), t_overturn=float(res.t[np.argmax(over)]) if over[-1] else math.nan,
                impacts=int(res.impacts[-1]), max_abs_slip=float(np.max(np.abs(res.slip))),
                friction_demand=float(res.friction_demand[-1]))


def _warm_up() -> None:
    run_case(pulse_cases("sine", amplitude_ratios=[2.0], frequency_ratios=[4.0], t_end=0.5)[0])


def run_batch(cases: list[dict]) -> list[dict]:
    """`run_case` over a few cases (one Dask task)."""
    return [run_case(c) for c in cases]


# --------------------------------------------------------------------------------------------- output
class EnsembleError(RuntimeError):
    """A run that cannot go on (its output is in use by another run, its cluster has lost its workers); the
    rows already written stay in the output and a rerun resumes."""


class OutputInUse(EnsembleError):
    """Another run holds the output's lock."""


class WorkersLost(EnsembleError):
    """The Dask cluster has no worker left (or a batch killed every worker that ran it)."""


class RepairWarning(UserWarning):
    """A resume set aside something an interruption broke (a row, a Parquet part); the message says where."""


def _key(case) -> str:
    """The case id of ``case`` (its own, or computed; a case that is not a dict: a hash of its repr)."""
    if isinstance(case, dict):
        return case.get("case_id") or case_id(case)
    return "bad-" + hashlib.sha1(repr(case).encode()).hexdigest()[:12]


def _parse(row: dict) -> dict:
    """A row read back, typed (ValueError if a numeric field holds something else)."""
    out = {}
    for k, v in row.items():
        if k in _FLOATS:
            out[k] = float(v) if v not in ("", None) else math.nan
        elif k in _INTS:
            out[k] = int(float(v)) if v not in ("", None) else -1
        elif k in _BOOLS:
            out[k] = v if isinstance(v, bool) else str(v).strip().lower() in ("true", "1")
        else:
            out[k] = "" if v is None else str(v)
    for added in ADDED_FIELDS:
        for k, v in added.items():
            out.setdefault(k, v)      # a row of a file written before these fields existed
    return out


def _typed(row: dict) -> dict:
    """The row to write: every field of FIELDS with its type, whatever the case held (a value that is not a
    number becomes NaN, or -1 for a count: the error column says what was wrong), strings on one line (one
    row per line is what the resume's repair reads)."""
    out = {}
    for k in FIELDS:
        v = row.get(k)
        if k in _FLOATS:
            try:
                out[k] = float(v)
            except (TypeError, ValueError, OverflowError):
                out[k] = math.nan
        elif k in _INTS:
            try:
                out[k] = int(v)
            except (TypeError, ValueError, OverflowError):
                out[k] = -1
        elif k in _BOOLS:
            out[k] = v if isinstance(v, bool) else str(v).strip().lower() in ("true", "1")
        else:
            out[k] = "" if v is None else " | ".join(str(v).splitlines())
    return out


def _is_parquet(out: Path) -> bool:
    return out.suffix == ".parquet" or (out.is_dir() and any(out.glob("part-*.parquet")))


def _fsync_dir(path: Path) -> None:
    """Make a rename or a new file in ``path`` durable (POSIX; a no-op where directories cannot be opened)."""
    try:
        fd = os.open(path, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


#: the header line of a CSV output
_HEADER = ",".join(FIELDS)
#: the columns of a CSV output written before each group of `ADDED_FIELDS` existed, by header (completed on
#: resume): the first version's (none of them), then with the vertical fields but without params, ...
_OLDER_FIELDS = {}
for _i in range(len(ADDED_FIELDS)):
    _cols = tuple(k for k in FIELDS if not any(k in added for added in ADDED_FIELDS[_i:]))
    _OLDER_FIELDS[",".join(_cols)] = _cols
#: [lines] longest record joined when a quoted field spans lines (rows of earlier versions could hold a
#: multi-line error message; rows are now written on one line)
_MAX_JOIN = 20


def _csv_record(raw: str, cols: Sequence[str]) -> dict | None:
    """The typed row of one CSV record, or None if it is broken (wrong number of columns, no case id, a
    number that is not one)."""
    try:
        fields = list(csv.reader(io.StringIO(raw)))
    except csv.Error:
        return None
    if len(fields) != 1 or len(fields[0]) != len(cols):
        return None
    row = dict(zip(cols, fields[0]))
    if not row.get("case_id"):
        return None
    try:
        return _parse(row)
    except (ValueError, OverflowError):
        return None


def _scan_csv(body: str, cols: Sequence[str]) -> tuple[list, list]:
    """Split the records after the header into good ones [(raw, row)] and broken ones [(line, raw)] (line:
    1-based line number in the file). The text after the last newline is the unfinished row of a killed run
    (broken); a broken row anywhere else (two writers, a torn write) is found too, and the good rows around
    it are kept."""
    lines = body.split("\n")
    tail = lines.pop()
    good, broken = [], []
    i = 0
    while i < len(lines):
        j, raw = i, lines[i]
        while raw.count('"') % 2 and j + 1 < len(lines) and j - i < _MAX_JOIN:
            j += 1
            raw += "\n" + lines[j]
        row = _csv_record(raw, cols)
        if j > i and (row is None or any(_csv_record(lines[k], cols) for k in range(i + 1, j + 1))):
            row, j, raw = None, i, lines[i]    # not one multi-line record: only this line is broken
        if row is None:
            broken.append((i + 2, raw))
        else:
            good.append((raw, row))
        i = j + 1
    if tail:
        broken.append((len(lines) + 2, tail))
    return good, broken


def _header_problem(path: Path, head: str, has_newline: bool) -> str | None:
    cols = head.rstrip("\r")
    if cols == _HEADER:
        return None
    if cols and _HEADER.startswith(cols):
        n = len(cols.split(","))
        return (f"{path}: its header is truncated (it stops in column {n} of {len(FIELDS)}, at {cols[-20:]!r}): "
                "the file was cut short while it was being created" + (", and rows follow it, which cannot be "
                "matched to columns" if has_newline else "") + "; move it aside (or delete it) and rerun, or "
                "give another --out")
    return f"{path}: its columns are not those of an ensemble output; use another --out"


def _repair_csv(path: Path) -> list[str]:
    """Make ``path`` a clean ensemble CSV before appending to it (the caller holds its lock): an unfinished
    last row is cut off, a broken row anywhere is removed, and both are set aside in ``<path>.rejected``
    (nothing is lost silently; their cases run again); a header cut short with no row after it is completed.
    The good rows are kept byte for byte (a rewrite goes through a temporary file, fsync and rename).
    Returns what was done (one message each)."""
    if not path.exists() or path.stat().st_size == 0:
        return []
    data = path.read_bytes()
    text = data.decode("utf-8", "surrogateescape")
    head, sep, body = text.partition("\n")
    notes = []
    older = _OLDER_FIELDS.get(head.rstrip("\r"))
    if older is not None:
        missing = [k for k in FIELDS if k not in older]
        data = _add_columns(path, body, older)
        text = data.decode("utf-8", "surrogateescape")
        head, sep, body = text.partition("\n")
        notes.append(f"{path}: written before the columns {', '.join(missing)} existed: added to its header and "
                     "rows (" + "; ".join(what for what, group in (("no vertical component", VERTICAL_DEFAULTS),
                                                                   ("the model's default parameters",
                                                                    PARAMS_DEFAULTS),
                                                                   ("no intensity-measure target",
                                                                    IM_DEFAULTS))
                                          if any(k in group for k in missing))
                     + "; its cases keep their ids)")
    problem = _header_problem(path, head, bool(sep))
    if problem:
        if _HEADER.startswith(head.rstrip("\r")) and not body.strip():
            _rewrite(path, (_HEADER + "\r\n").encode())
            return [f"{path}: its header was cut short and no row followed it: header completed"]
        raise ValueError(problem)
    good, broken = _scan_csv(body, FIELDS)
    if not broken:
        return notes
    rejected = path.with_name(path.name + ".rejected")
    with open(rejected, "a", encoding="utf-8", errors="surrogateescape", newline="") as f:
        for _, raw in broken:
            f.write(raw.rstrip("\r") + "\n")
        f.flush()
        os.fsync(f.fileno())
    if len(broken) == 1 and not text.endswith("\n") and broken[0][1] == text[text.rfind("\n") + 1:]:
        with open(path, "rb+") as f:                 # only the unfinished last row: cut it off in place
            f.truncate(data.rfind(b"\n") + 1)
            os.fsync(f.fileno())
    else:
        _rewrite(path, (head + "\n" + "".join(raw + "\n" for raw, _ in good)).encode("utf-8", "surrogateescape"))
    lines = ", ".join(str(n) for n, _ in broken[:10]) + (", ..." if len(broken) > 10 else "")
    return notes + [f"{path}: {len(broken)} broken row(s) (line {lines}) set aside in {rejected}; their cases run "
                    "again"]


def _add_columns(path: Path, body: str, older: Sequence[str]) -> bytes:
    """Rewrite a CSV output of the columns ``older`` (written before some of `ADDED_FIELDS` existed) with
    today's header, each good row with the fields of a case without them (e.g. `VERTICAL_DEFAULTS`: no vertical
    component; its other cells as they were) and each broken row, and an unfinished last row, as they were (the
    repair that follows sets them aside). Returns the new contents."""
    defaults = {k: v for added in ADDED_FIELDS for k, v in added.items()}
    lines = body.split("\n")
    tail = lines.pop()
    out = io.StringIO()
    w = csv.writer(out, lineterminator="\r\n")
    w.writerow(FIELDS)
    for raw in lines:
        row = _csv_record(raw, older)
        if row is None:
            out.write(raw + "\n")
            continue
        cells = dict(zip(older, next(csv.reader([raw.rstrip("\r")]))))
        w.writerow([cells[k] if k in cells else defaults[k] for k in FIELDS])
    out.write(tail)
    data = out.getvalue().encode("utf-8", "surrogateescape")
    _rewrite(path, data)
    return data


def _rewrite(path: Path, data: bytes) -> None:
    """Replace ``path`` by ``data`` atomically and durably (temporary file, fsync, rename, fsync of the
    directory)."""
    tmp = path.with_name(f".{path.name}.repair-{os.getpid()}")
    with open(tmp, "wb") as f:
        f.write(data)
        f.flush()
        os.fsync(f.fileno())
    os.replace(tmp, path)
    _fsync_dir(path.parent)


def _read_parts(out: Path, set_aside: bool = False) -> tuple[dict, list[str]]:
    """{case_id: row} of the Parquet parts of ``out`` and messages about unreadable parts (cut short by a
    power loss before parts were fsynced): skipped, or with ``set_aside`` renamed ``*.corrupt``."""
    import pyarrow.parquet as pq

    rows: dict[str, dict] = {}
    notes = []
    for part in sorted(out.glob("part-*.parquet")):
        try:
            table = pq.read_table(part)
        except Exception as exc:             # pyarrow's errors (ArrowInvalid, OSError) of a cut file
            reason = " ".join(str(exc).splitlines())[:200]
            if set_aside:
                aside = part.with_name(part.name + ".corrupt")
                os.replace(part, aside)
                notes.append(f"{part}: unreadable ({reason}); set aside as {aside.name}, its cases run again")
            else:
                notes.append(f"{part}: unreadable ({reason}); skipped")
            continue
        for r in table.to_pylist():
            rows[r["case_id"]] = _parse(r)
    return rows, notes


def read_results(out) -> list[dict]:
    """All rows written so far to ``out`` (a .csv file or a .parquet directory of parts), typed. A broken row
    (cut short by an interruption, anywhere in the file) or an unreadable part is skipped (with a
    `RepairWarning` for a part); if a case appears twice the last row wins."""
    out = Path(out)
    if _is_parquet(out):
        if not out.is_dir():
            return []
        rows, notes = _read_parts(out)
        for note in notes:
            warnings.warn(note, RepairWarning, stacklevel=2)
        return list(rows.values())
    if not out.exists():
        return []
    text = out.read_bytes().decode("utf-8", "surrogateescape")
    head, _, body = text.partition("\n")
    rows: dict[str, dict] = {}
    for _, r in _scan_csv(body, next(csv.reader([head.rstrip("\r")]), []))[0]:
        rows[r["case_id"]] = r
    return list(rows.values())


# ------------------------------------------------------------------------------------------ output lock
try:
    import fcntl

    def _try_lock(fd: int) -> None:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)       # OSError if another process holds it
except ImportError:                                            # Windows
    import msvcrt

    def _try_lock(fd: int) -> None:
        msvcrt.locking(fd, msvcrt.LK_NBLCK, 1)


class OutputLock:
    """Exclusive lock of one output for a whole run: ``<out>.lock`` next to it, locked with flock (released by
    the kernel when the process ends, even by kill -9; works on local and NFS file systems) and holding the
    owner's pid, host and start time, which a refused run names. Two runs on one output (a double launch, an
    array job sharing --out) would truncate, duplicate or interleave each other's rows: the second is refused
    with `OutputInUse`. The lock file is removed when the run ends."""

    def __init__(self, out):
        self.out = Path(out)
        self.path = self.out.with_name(self.out.name + ".lock")
        self.fd: int | None = None

    def acquire(self) -> "OutputLock":
        self.path.parent.mkdir(parents=True, exist_ok=True)
        while True:
            fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o644)
            try:
                _try_lock(fd)
            except OSError:
                try:
                    owner = os.read(fd, 1000).decode(errors="replace").strip()
                except OSError:                  # a platform whose locks also block reads
                    owner = ""
                finally:
                    os.close(fd)
                raise OutputInUse(f"{self.out} is in use by another run ({owner or 'starting'}; lock file "
                                  f"{self.path}): two runs on one output would write the same cases twice; "
                                  "wait for it to end, or give another --out") from None
            try:         # the previous owner may have removed the file between our open and our lock
                same = os.path.samestat(os.fstat(fd), os.stat(self.path))
            except FileNotFoundError:
                same = False
            if same:
                break
            os.close(fd)
        started = time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime())
        os.ftruncate(fd, 0)
        os.write(fd, f"pid {os.getpid()} on host {socket.gethostname()}, started {started}\n".encode())
        self.fd = fd
        return self

    def release(self) -> None:
        if self.fd is None:
            return
        try:
            os.unlink(self.path)             # while locked: a waiting opener sees another file and retries
        except OSError:
            pass
        os.close(self.fd)
        self.fd = None

    def __enter__(self):
        return self.acquire()

    def __exit__(self, *exc):
        self.release()


# ---------------------------------------------------------------------------------------------- writers
class CsvWriter:
    """Appends rows to a CSV file (opened for appending only, never truncated); every row is flushed to the
    OS at once (a killed run keeps it). An existing file is repaired first (`_repair_csv`, reported in
    ``repairs``); the caller should hold the output's `OutputLock`."""

    def __init__(self, path: Path):
        self.path = path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        self.repairs = _repair_csv(path)
        fresh = not path.exists() or path.stat().st_size == 0
        self.f = open(path, "a", newline="")
        self.w = csv.DictWriter(self.f, FIELDS)
        if fresh:
            self.w.writeheader()
            self.f.flush()
            os.fsync(self.f.fileno())
            _fsync_dir(path.parent)

    def write(self, rows: Iterable[dict]) -> None:
        for r in rows:
            self.w.writerow(_typed(r))
        self.f.flush()

    def close(self) -> None:
        self.f.flush()
        os.fsync(self.f.fileno())
        self.f.close()


def _part_index(part: Path) -> int:
    try:
        return int(part.name[len("part-"):].split(".")[0].split("-")[0])
    except ValueError:
        return -1


class ParquetWriter:
    """Writes rows as Parquet parts in a directory: ``part-<n>-<run>.parquet``, ``run`` unique to this writer
    (two writers never share a name, temporary or final). Each part is written to a temporary name, fsynced,
    renamed, and the directory fsynced, so a power loss leaves whole parts only; rows are buffered up to
    ``rows_per_part`` or ``seconds`` and flushed on close, also after Ctrl-C. A hard kill loses at most the
    buffer. Unreadable parts found at start are set aside (``*.corrupt``, reported in ``repairs``)."""

    def __init__(self, path: Path, rows_per_part: int = 200, seconds: float = 10.0):
        import pyarrow  # noqa: F401  (fail early with a clear ImportError)
        self.path, self.rows_per_part, self.seconds = Path(path), rows_per_part, seconds
        self.path.mkdir(parents=True, exist_ok=True)
        self.repairs = _read_parts(self.path, set_aside=True)[1]
        self.n = 1 + max((_part_index(p) for p in self.path.glob("part-*.parquet")), default=-1)
        self.run = f"{os.getpid():x}{secrets.token_hex(4)}"
        self.buf: list[dict] = []
        self.t_last = time.monotonic()

    def write(self, rows: Iterable[dict]) -> None:
        self.buf.extend(rows)
        if len(self.buf) >= self.rows_per_part or time.monotonic() - self.t_last > self.seconds:
            self.flush()

    def flush(self) -> None:
        if not self.buf:
            return
        import pyarrow as pa
        import pyarrow.parquet as pq
        table = pa.Table.from_pylist([_typed(r) for r in self.buf], schema=_schema())
        final = self.path / f"part-{self.n:05d}-{self.run}.parquet"
        tmp = self.path / f".tmp-{self.n:05d}-{self.run}.parquet"
        with open(tmp, "wb") as f:
            pq.write_table(table, f)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, final)
        _fsync_dir(self.path)
        self.n += 1
        self.buf = []
        self.t_last = time.monotonic()

    def close(self) -> None:
        self.flush()


def _schema():
    import pyarrow as pa
    return pa.schema([(k, pa.float64() if k in _FLOATS else pa.int64() if k in _INTS else
                       pa.bool_() if k in _BOOLS else pa.string()) for k in FIELDS])


def _writer(out: Path):
    return ParquetWriter(out) if out.suffix == ".parquet" else CsvWriter(out)


# --------------------------------------------------------------------------------------------- runners
def _progress(total: int, initial: int, enabled: bool):
    if not enabled:
        return None
    try:
        from tqdm import tqdm
    except ImportError:
        return None
    return tqdm(total=total, initial=initial, unit="case", dynamic_ncols=True)


#: [s] how long a run waits while its Dask cluster has no worker at all before it ends with `WorkersLost`.
#: A nanny restarts a killed worker within seconds, but after repeated kills (as the out-of-memory killer
#: does) it can give up, and the wait for results would never end. An adaptive cluster that scales up from
#: zero workers may need longer: run_ensemble(no_workers_timeout=...), CLI --no-workers-timeout.
NO_WORKERS_TIMEOUT = 60.0
#: [s] sleep between two looks at the finished tasks while none is ready: short against a task of compiled
#: cases (a few ms), long enough that the look costs nothing
_POLL = 0.005

#: [s] interval between two questions to the scheduler about its workers (one small RPC each)
_WORKER_CHECK = 0.25
#: [workers] how many workers may die (leave the cluster) while no batch finishes before the run ends with
#: `WorkersLost`: a nanny restarts a killed worker, so a cluster whose workers are killed over and over (the
#: out-of-memory killer on a case too large for the machine) is never without workers for long and its tasks
#: may never reach Dask's own KilledWorker limit; an occasional death (one worker killed once) is retried
MAX_DEATHS_WITHOUT_PROGRESS = 8


def _wait_for_ready(ac) -> None:
    """Wait `_POLL` for a batch to finish (a plain sleep: short, as a task of compiled cases costs a few ms;
    as_completed's own condition variable is not used, as a run whose workers were killed over and over was
    seen to stay in it)."""
    time.sleep(_POLL)


#: [s] how long the run waits for the rows of a batch reported finished before it looks at the cluster again
#: (the rows come in milliseconds from a live worker; from a dead one, only once Dask has run the batch again)
RESULT_WAIT = 0.5

#: [s] how long one question to the scheduler about its workers may take; an answer that does not come (a
#: scheduler busy with dying workers) counts as a look at a cluster without workers
WORKER_QUERY_TIMEOUT = 2.0


def _workers_now(client) -> set:
    """The addresses of the cluster's workers now, or an empty set when the scheduler does not answer within
    `WORKER_QUERY_TIMEOUT` (asked from a daemon thread, so that a hung call never holds the run)."""
    import threading

    box: list = []

    def ask():
        try:
            box.append(set(client.nthreads()))
        except Exception:                 # noqa: BLE001 - a scheduler that cannot answer has no usable worker
            box.append(set())
    th = threading.Thread(target=ask, daemon=True)
    th.start()
    th.join(WORKER_QUERY_TIMEOUT)
    return box[0] if box else set()


class _OrphanedGather(logging.Filter):
    """Drops asyncio's "Task exception was never retrieved" for a Dask gather that a `result(timeout=...)` left
    behind and that ended when the cluster went away (distributed's AllExit): the run reports a cluster without
    workers itself (`WorkersLost`), in one line, and the traceback would only hide it."""

    def filter(self, record: logging.LogRecord) -> bool:
        exc = record.exc_info[1] if record.exc_info else None
        return not (str(record.msg).startswith("Task exception was never retrieved")
                    and type(exc).__name__ == "AllExit")


def _quiet_orphaned_gathers() -> None:
    log = logging.getLogger("asyncio")
    if not any(isinstance(f, _OrphanedGather) for f in log.filters):
        log.addFilter(_OrphanedGather())


def _collect(client, futures, take, no_workers_timeout: float, out: Path) -> None:
    """Hand each batch's rows to ``take`` as it finishes; raise `WorkersLost` when the cluster has had no
    worker for ``no_workers_timeout`` seconds, when `MAX_DEATHS_WITHOUT_PROGRESS` workers died while no batch
    finished, or when a batch killed every worker that ran it."""
    from dask.distributed import KilledWorker, as_completed

    from dask.distributed import TimeoutError as DaskTimeoutError

    ac = as_completed(futures)
    no_worker_since = None
    t_check = time.monotonic()
    alive: set = set()           # worker addresses seen at the last look
    deaths = 0                   # workers that left the cluster since the last finished batch
    # batches reported finished whose rows have not arrived: the worker that held them died after finishing,
    # and Dask computes them again (a result() without a timeout would wait for that, with every worker being
    # killed, for ever)
    waiting: list = []
    while waiting or not ac.is_empty():
        ready = waiting + ac.next_batch(block=False)
        waiting = []
        got = False
        for fut in ready:
            try:
                rows = fut.result(timeout=RESULT_WAIT)
            except (DaskTimeoutError, TimeoutError):
                waiting.append(fut)
                continue
            except KilledWorker as exc:
                raise WorkersLost(f"every worker that ran a batch of cases died while running it (killed, e.g. "
                                  f"by the out-of-memory killer; Dask: {' '.join(str(exc).split())[:160]}); the "
                                  f"finished cases are in {out}; run the same command to resume (fewer --workers, "
                                  "or --batch-size 1, need less memory)") from None
            take(rows)
            fut.release()
            got = True
        if got:
            no_worker_since = None
            deaths = 0
            continue
        _wait_for_ready(ac)
        if time.monotonic() - t_check < _WORKER_CHECK:
            continue
        t_check = time.monotonic()
        workers = _workers_now(client)
        deaths += len(alive - workers)
        alive = workers
        if deaths >= MAX_DEATHS_WITHOUT_PROGRESS:
            raise WorkersLost(f"{deaths} Dask workers died while no batch of cases finished (killed over and over, "
                              f"e.g. by the out-of-memory killer); {ac.count() + len(waiting)} task(s) of cases were left; the "
                              f"finished cases are in {out}; run the same command to resume (fewer --workers, or "
                              "--batch-size 1, need less memory)")
        if workers:
            no_worker_since = None
        elif no_worker_since is None:
            no_worker_since = t_check
        elif t_check - no_worker_since > no_workers_timeout:
            raise WorkersLost(f"the Dask cluster has had no worker for {no_workers_timeout:g} s (all died or "
                              f"were killed, e.g. by the out-of-memory killer); {ac.count() + len(waiting)} task(s) of cases "
                              f"were left; the finished cases are in {out}; run the same command to resume "
                              "(fewer --workers, or --batch-size 1, need less memory)")


#: [s] how long a run waits for its Dask client and local cluster to close at its end (or after an error)
CLOSE_TIMEOUT = 10.0

#: [tasks] Dask tasks per worker by default: enough to balance cases of unequal cost, few enough that a task's
#: scheduling and round trip (a few ms) stay small against its cases (0.1-1 ms each on the compiled engine)
TASKS_PER_WORKER = 4
#: [cases] the largest default batch (a batch's rows are written when it finishes)
MAX_BATCH = 2000


def default_batch_size(n_cases: int, n_workers: int) -> int:
    """Cases per Dask task when ``batch_size`` is not given: about `TASKS_PER_WORKER` tasks per worker, at
    most `MAX_BATCH` cases each."""
    return max(1, min(MAX_BATCH, -(-n_cases // (TASKS_PER_WORKER * max(1, n_workers)))))


class EnsembleRun:
    """An open run on one output, for drivers that choose their next cases from the results of earlier ones
    (`rocking_model.assessment`: the IDA's hunt-and-fill) and for `run_ensemble`: ``with EnsembleRun(out, ...)
    as run: rows = run.run(cases)``. It holds ``out``'s `OutputLock` from ``__enter__`` to ``__exit__``,
    repairs the output first (`RepairWarning`), keeps the rows already in it (``rows``: {case_id: row}) and
    starts its Dask cluster (or none: workers=0) on the first case that has to run, once for all the calls of
    `run`. The arguments are `run_ensemble`'s; ``stats`` accumulates its summary fields."""

    def __init__(self, out, *, workers: int = 2, address: str | None = None, resume: bool = True,
                 progress: bool = True, batch_size: int | None = None, processes: bool = True,
                 on_row: Callable[[dict], None] | None = None, no_workers_timeout: float = NO_WORKERS_TIMEOUT):
        from .validation import check_real

        self.out = Path(out)
        if address is None and (isinstance(workers, bool) or not isinstance(workers, int) or workers < 0):
            raise ValueError(f"workers = {workers!r} is out of range; allowed: an integer in [0, inf)")
        if batch_size is not None and (isinstance(batch_size, bool) or not isinstance(batch_size, int)
                                       or batch_size < 1):
            raise ValueError(f"batch_size = {batch_size!r} is out of range; allowed: an integer in [1, inf)")
        check_real("no_workers_timeout", no_workers_timeout, lo=0.0, lo_open=True)
        self.workers, self.address, self.resume, self.progress = workers, address, resume, progress
        self.batch_size, self.processes, self.on_row = batch_size, processes, on_row
        self.no_workers_timeout = no_workers_timeout
        self.lock = self.writer = self.bar = self.client = self.cluster = None
        self.rows: dict[str, dict] = {}
        self.stats = dict(n_run=0, n_errors=0, n_overturned=0, wall_time=0.0, setup_time=0.0, workers=workers,
                          address=address or "", repairs=[])

    def __enter__(self) -> "EnsembleRun":
        self.lock = OutputLock(self.out).acquire()
        try:
            if not self.resume and self.out.exists():
                raise ValueError(f"{self.out} exists; remove it or resume (the default)")
            self.writer = _writer(self.out)
            for note in self.writer.repairs:
                warnings.warn(note, RepairWarning, stacklevel=2)
            self.stats["repairs"] = list(self.writer.repairs)
            self.rows = {r["case_id"]: r for r in read_results(self.out)} if self.resume else {}
        except BaseException:
            self.__exit__(None, None, None)
            raise
        return self

    def __exit__(self, *exc) -> None:
        try:
            if self.writer is not None:
                self.writer.close()
            if self.bar is not None:
                self.bar.close()
            # bounded: a cluster whose workers are being killed may never shut down cleanly, and the run must
            # end (its rows are written) rather than wait for it
            for closing in (self.client, self.cluster):
                if closing is not None:
                    try:
                        closing.close(timeout=CLOSE_TIMEOUT)
                    except Exception:             # noqa: BLE001 - a cluster that cannot close is abandoned
                        pass
        finally:
            self.writer = self.bar = self.client = self.cluster = None
            if self.lock is not None:
                self.lock.release()
                self.lock = None

    def todo(self, cases: Iterable[dict]) -> list[dict]:
        """The cases whose ids are not in the output yet, each id once."""
        todo, seen = [], set()
        for c in cases:
            k = _key(c)
            if k not in self.rows and k not in seen:
                seen.add(k)
                todo.append(c)
        return todo

    def _take(self, rows: list[dict]) -> None:
        self.writer.write(rows)
        for r in rows:
            self.rows[r["case_id"]] = r
            self.stats["n_run"] += 1
            self.stats["n_errors"] += bool(r["error"])
            self.stats["n_overturned"] += bool(r["overturned"])
            if self.on_row is not None:
                self.on_row(r)
        if self.bar is not None:
            self.bar.update(len(rows))

    def progress_total(self, total: int, done: int = 0) -> None:
        """Show (or grow) the progress bar: ``total`` cases, ``done`` of them finished before this run."""
        if self.bar is None:
            self.bar = _progress(total, done, self.progress)
        elif total > self.bar.total:
            self.bar.total = total
            self.bar.refresh()

    def _start(self) -> None:
        """Start (or join) the Dask cluster once, and warm its workers up before the clock starts."""
        t_setup = time.perf_counter()
        _quiet_orphaned_gathers()
        try:
            from dask.distributed import Client, LocalCluster
        except ImportError:
            raise ImportError("ensembles on Dask need dask.distributed: pip install "
                              "'rocking-model[ensemble]' (or run serially with workers=0)") from None
        if self.address:
            self.client = Client(self.address, timeout="10s")
            self.stats["workers"] = len(self.client.scheduler_info().get("workers", {}))
        else:
            # silence_logs: shutdown chatter (a worker's last heartbeat to a closed scheduler) is noise; a
            # cluster that loses all its workers is reported by `_collect` instead
            self.cluster = LocalCluster(n_workers=self.workers, threads_per_worker=1, processes=self.processes,
                                        dashboard_address=":0", silence_logs=logging.CRITICAL)
            self.client = Client(self.cluster)
            self.client.wait_for_workers(self.workers)
        # import the package and run one short case on every worker
        self.client.run(_warm_up)
        self.stats["setup_time"] += time.perf_counter() - t_setup

    def run(self, cases: Sequence[dict]) -> list[dict]:
        """The rows of ``cases``, in their order: those already in the output as they are, the others run
        (serially, or on Dask in batches) and written as they arrive."""
        cases = list(cases)
        todo = self.todo(cases)
        if todo:
            serial = self.workers == 0 and self.address is None
            if not serial and self.client is None:
                self._start()
            t0 = time.perf_counter()
            try:
                if serial:
                    for c in todo:
                        self._take([run_case(c)])
                else:
                    n_w = max(1, len(self.client.scheduler_info().get("workers", {})))
                    size = self.batch_size or default_batch_size(len(todo), n_w)
                    self.stats["batch_size"] = size
                    batches = [todo[i:i + size] for i in range(0, len(todo), size)]
                    _collect(self.client, self.client.map(run_batch, batches, pure=False), self._take,
                             self.no_workers_timeout, self.out)
            finally:
                self.stats["wall_time"] += time.perf_counter() - t0
        return [self.rows[_key(c)] for c in cases]


def run_ensemble(cases: Sequence[dict], out, *, workers: int = 2, address: str | None = None,
                 resume: bool = True, progress: bool = True, batch_size: int | None = None, processes: bool = True,
                 on_row: Callable[[dict], None] | None = None,
                 no_workers_timeout: float = NO_WORKERS_TIMEOUT) -> dict:
    """Run ``cases`` and write one row per case to ``out`` (.csv, or a .parquet directory).

    workers: number of local Dask workers (one thread each; ``processes=False`` runs them as threads of
        this process, e.g. for tests); 0 runs serially here without Dask.
    address: scheduler address of an existing Dask cluster (tcp://host:8786); then ``workers`` is ignored.
        The workers need rocking_model installed (and the record files at the same paths).
    resume: skip the case ids already in ``out``; otherwise ``out`` must not exist yet.
    batch_size: cases per Dask task; larger batches amortize the few ms of scheduling and round trip per
        task; default: `default_batch_size` (about 4 tasks per worker; rows are written per task).
    no_workers_timeout: [s] a cluster without any worker for this long ends the run (`WorkersLost`;
        default `NO_WORKERS_TIMEOUT`).

    The run holds ``out``'s `OutputLock` from start to end (a second run on it raises `OutputInUse` naming
    this one), only appends to ``out``, and first repairs what an interruption broke (`RepairWarning`, also
    listed in the summary's ``repairs``). A case that fails becomes a row with its ``error`` (see `run_case`).
    Rows are written as they arrive, so when the run ends early (`WorkersLost`, Ctrl-C) the finished cases
    stay in ``out`` and a rerun resumes. (`EnsembleRun` is the same run for a driver that chooses its cases
    as it goes.)
    Returns a summary: n_cases, n_skipped, n_run, n_errors, n_overturned, wall_time [s] (from the first
    submission to the last row), throughput [cases/s], setup_time [s] (cluster start), workers, repairs.
    """
    cases = list(cases)
    run = EnsembleRun(out, workers=workers, address=address, resume=resume, progress=progress,
                      batch_size=batch_size, processes=processes, on_row=on_row,
                      no_workers_timeout=no_workers_timeout)
    with run:
        n_done = len(run.rows)
        todo = run.todo(cases)
        n_total = len(set(run.rows) | {_key(c) for c in cases})
        if todo:
            run.progress_total(len(cases), len(cases) - len(todo))
            run.run(todo)
    summary = dict(n_cases=len(cases), n_skipped=len(cases) - len(todo), **run.stats)
    summary["throughput"] = summary["n_run"] / summary["wall_time"] if summary["wall_time"] > 0 else math.nan
    summary["n_total_in_output"] = n_total if todo else n_done
    return summary
