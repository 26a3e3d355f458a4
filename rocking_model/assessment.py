"""From a suite of records to fragility curves: records scaled to target intensity measures, multiple-stripe
analysis (MSA), incremental dynamic analysis (IDA, hunt-and-fill), damage states, and their lognormal fits.

Scaling. A record whose measure ``im`` (`rocking_model.intensity`: PGA, PGV, Sa(T), the rocking measures
PGA/(g tan alpha) and PGV p/(g tan alpha), ...) has the value m is scaled to a target level x by the factor
s = (x/m)^(1/k), k = `scale_exponent` (1 for the peaks, Sa and CAV, 2 for Arias; D5_95 cannot be scaled to).
The factor multiplies both components (the vertical one too). A scaled case is an ensemble case
(`rocking_model.ensemble`) with the fields ``im`` and ``im_level``: its id is built from the record, the measure
and its level, the model, geometry, scheme and parameters, not from the derived factor, so a run resumes from
its output whatever the last bits of the record's measure.

MSA (`msa_cases`, `run_msa`): a grid of stripes (IM levels) x records x configurations (model, geometries,
schemes, vertical scales), every case run once; per damage state, the fraction reaching it per stripe is fitted
by maximum likelihood (`rocking_model.fragility.fit_fragility`), with bootstrap bands over records.

IDA (`run_ida`): per record and configuration, a hunt-and-fill on the IM level (Vamvatsikos and Cornell 2002):
levels ``start`` x ``ratio``^k until the block overturns (and ``n_above`` levels more, to see what lies above),
then bisection (geometric) between the highest level below and the lowest level reaching each damage state,
overturning first, down to a relative gap ``rtol``, then the largest gaps are halved, up to ``max_runs``
runs per record. A rocking block's IDA curve is not monotonic: it can overturn at one level and not at a higher
one. The curve reports its first overturning (the lowest level run that overturned) and the non-overturning
levels above it ("resurrections", in pockets of consecutive levels); a damage state's capacity is the lowest
level at which the record reaches it (inf when it never does up to the highest level run). Every run is a case
of the output, so an interrupted IDA resumes: the hunt replays the rows already there.

Vamvatsikos, D. and Cornell, C. A. (2002). Incremental dynamic analysis. Earthquake Engineering and Structural
Dynamics 31(3), 491-514.
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Iterable, Mapping, Sequence

import numpy as np

from . import ensemble as E

# --------------------------------------------------------------------------------------------- damage states
#: short names of the result fields a damage state can threshold (any numeric result field is accepted too)
QUANTITIES = {"phi/alpha": "max_phi_over_alpha", "phi": "max_abs_phi", "slip": "max_abs_slip",
              "tendon": "max_tendon_force", "impacts": "impacts"}
#: units of the quantities, for the messages
_QUANTITY_UNITS = {"max_phi_over_alpha": "1", "max_abs_phi": "rad", "max_abs_slip": "m", "max_tendon_force": "N",
                   "impacts": "1"}
#: the damage states of `rocking fragility` and of the drivers by default: a rocking amplitude of a fifth and of
#: half the slenderness, and overturning
DEFAULT_DAMAGE_STATES = ("phi/alpha>=0.2", "phi/alpha>=0.5", "overturned")

_DS = re.compile(r"^\s*(?:(?P<name>[^:]+?)\s*:)?\s*(?P<q>[A-Za-z_/]+)\s*(?:(?P<op>>=|>)\s*(?P<v>\S+))?\s*$")


@dataclass(frozen=True)
class DamageState:
    """A damage state: reached by a case whose result ``field`` is >= (or >, ``strict``) ``threshold``, or
    that overturned (collapse reaches every damage state). ``field`` "overturned": overturning alone.
    A DamageState is a predicate on a result row: ``ds(row)`` is True, False, or None for a row without an
    outcome (a failed case: its ``error``)."""

    name: str
    field: str
    threshold: float = math.nan
    strict: bool = False

    def __call__(self, row: Mapping) -> bool | None:
        if row.get("error"):
            return None
        if bool(row.get("overturned")):
            return True
        if self.field == "overturned":
            return False
        v = float(row.get(self.field, math.nan))
        if v != v:
            raise ValueError(f"damage state {self.name!r}: the {row.get('model', '')} model has no "
                             f"{self.field} (the tendon force is the post-tensioned block's; phi/alpha a rigid "
                             "block's)")
        return v > self.threshold if self.strict else v >= self.threshold


def damage_state(spec) -> DamageState:
    """A `DamageState` from its spec ``[name:]quantity>=value``, ``[name:]quantity>value`` or
    ``[name:]overturned``; quantity one of `QUANTITIES` (phi/alpha [1], phi [rad], slip [m], tendon [N],
    impacts) or a numeric result field of `rocking_model.ensemble.RESULT_FIELDS`. The name defaults to the
    spec. A DamageState is returned as it is."""
    if isinstance(spec, DamageState):
        return spec
    m = _DS.match(str(spec))
    numeric = [k for k in E.RESULT_FIELDS if (k in E._FLOATS or k in E._INTS) and k not in ("alpha", "p", "wall_time")]
    allowed = "overturned, " + ", ".join(QUANTITIES) + " or a result field (" + ", ".join(numeric) + ")"
    if not m:
        raise ValueError(f"damage state {spec!r}: give [name:]quantity>=value or [name:]overturned; quantity: "
                         f"{allowed}")
    q, op, v = m.group("q"), m.group("op"), m.group("v")
    name = (m.group("name") or "").strip() or str(spec).strip()
    if q == "overturned":
        if op:
            raise ValueError(f"damage state {spec!r}: overturned takes no threshold")
        return DamageState(name, "overturned")
    fieldname = QUANTITIES.get(q, q)
    if fieldname not in numeric:
        raise ValueError(f"damage state {spec!r}: {q!r} is not a quantity; allowed: {allowed}")
    if not op:
        raise ValueError(f"damage state {spec!r}: give a threshold, e.g. {q}>=0.5")
    from .validation import check_real
    t = check_real(f"damage state {name!r} threshold", v, lo=0.0)
    return DamageState(name, fieldname, t, op == ">")


def damage_states(specs: Iterable | None = None) -> list[DamageState]:
    """`damage_state` of each spec (default `DEFAULT_DAMAGE_STATES`); ValueError for two of one name."""
    out = [damage_state(s) for s in (DEFAULT_DAMAGE_STATES if specs is None else specs)]
    if not out:
        raise ValueError("damage states: give at least one")
    names = [d.name for d in out]
    dup = next((n for n in names if names.count(n) > 1), None)
    if dup is not None:
        raise ValueError(f"damage states: two are named {dup!r}")
    return out


_OVERTURNED = DamageState("overturned", "overturned")
_damage_states = damage_states          # (the drivers' argument of the same name hides it)


# --------------------------------------------------------------------------------------------- scaling
def canonical_measure(name: str) -> str:
    """The measure's name as `rocking_model.intensity` writes it (Sa(1.0) -> Sa(1)); ValueError listing the
    accepted names; refused for a measure that does not scale with the record (D5_95)."""
    from .intensity import _parse, sa_name, scale_exponent

    kind, T = _parse(name)
    if scale_exponent(kind if T is None else sa_name(T)) == 0:
        raise ValueError(f"im = {name!r} does not change when a record is scaled; choose a measure that does "
                         "(PGA, PGV, Sa(T), Arias, CAV, the rocking measures)")
    return kind if T is None else sa_name(T)


def scale_factor(value: float, target: float, name: str) -> float:
    """The factor s [1] that takes a record whose measure ``name`` is ``value`` to ``target`` (its units):
    (target/value)^(1/k), k = `scale_exponent`."""
    from .intensity import scale_exponent

    k = scale_exponent(name)
    if not (value > 0.0 and math.isfinite(value)):
        raise ValueError(f"the record's {name} is {value:g}: a record without motion cannot be scaled to it")
    if k == 0:
        raise ValueError(f"im = {name!r} does not change when a record is scaled")
    return (target / value) ** (1.0 / k)


def _im_field(name: str, zeta: float) -> str:
    """The case field ``im``: the measure's name, with the damping ratio when Sa's is not 5 % (another
    measure, another case id)."""
    return f"{name} zeta={zeta:g}" if name.startswith("Sa(") and zeta != 0.05 else name


@dataclass
class Suite:
    """Records x configurations at scale 1 (``templates``: ensemble cases of `rocking_model.ensemble.
    record_cases`) and each template's measure ``values`` [the measure's units]; `at` scales one to a level.
    Built by `suite`."""

    im: str
    zeta: float
    templates: list
    values: list

    def at(self, i: int, level: float) -> dict:
        """Template ``i`` scaled to the IM level ``level`` [the measure's units]: an ensemble case."""
        from .validation import check_real

        level = check_real("IM level", level, lo=0.0, lo_open=True)
        t = self.templates[i]
        s = scale_factor(self.values[i], level, self.im)
        c = dict(t, scale=s, A=t["A"] * s, a_ratio=t["a_ratio"] * s, im=_im_field(self.im, self.zeta),
                 im_level=float(level))
        c.pop("case_id", None)
        return E._finish(c)

    def stripes(self, levels: Sequence[float]) -> list[dict]:
        """Every template at every level (records x configurations x levels)."""
        return [self.at(i, x) for i in range(len(self.templates)) for x in levels]


def suite(records: Sequence[str], im: str = "PGA", *, zeta: float = 0.05, **case_options) -> Suite:
    """The suite of ``records`` (files, folders of .AT2/.csv files, or synthetic:<seed>; `record_files`) for
    the measure ``im`` (`canonical_measure`): `rocking_model.ensemble.record_cases` at scale 1 with the
    ``case_options`` (geometries, schemes, model, e_N, mu, t_end, output_interval, tolerance, dt_max,
    vertical, ag_v_scales, params, units), each with its record's measure (the horizontal component; the
    rocking measures with the case's block; zeta: damping ratio of Sa [1]). Each record is read once."""
    from .intensity import ROCKING_MEASURES, measure
    from .validation import check_real

    name = canonical_measure(im)
    zeta = check_real("zeta", zeta, lo=0.0, hi=1.0, hi_open=True)
    model = case_options.get("model", "rigid")
    if name in ROCKING_MEASURES and not E.is_rigid_block(model):
        raise ValueError(f"im = {name!r} is defined for the rigid blocks (rigid, post_tensioned), not the {model} "
                         "model; give PGA, PGV, Sa(T), ...")
    case_options.pop("scales", None)
    templates = E.record_cases(record_files(records), [1.0], **case_options)
    values, cache = [], {}
    for t in templates:
        block = E.case_model(t) if name in ROCKING_MEASURES else None
        key = (t["record"], t["units"], None if block is None else (block.alpha, block.p, block.g))
        if key not in cache:
            rec = E._record(t["record"], t.get("units") or "", "")
            cache[key] = measure(rec, name, zeta=zeta, block=block)
        values.append(cache[key])
    return Suite(name, zeta, templates, values)


def record_files(records: Sequence[str]) -> list[str]:
    """The record specs of ``records``: a folder stands for its .AT2 and .csv files (sorted by name), a file or
    ``synthetic:<seed>`` for itself. ValueError when nothing is left."""
    out = []
    for r in ([records] if isinstance(records, (str, Path)) else records):
        p = Path(str(r))
        if not str(r).startswith("synthetic") and p.is_dir():
            files = sorted(f for f in p.iterdir() if f.is_file() and f.suffix.lower() in (".at2", ".csv"))
            if not files:
                raise ValueError(f"records: the folder {p} has no .AT2 or .csv file")
            out += [str(f) for f in files]
        else:
            out.append(str(r))
    if not out:
        raise ValueError("records: give at least one record (file, folder or synthetic:<seed>)")
    return out


# --------------------------------------------------------------------------------------------- groups
#: the case fields of a configuration (one fragility per configuration and damage state)
GROUP_FIELDS = ("model", "b", "h", "e_N", "mu", "params", "scheme", "ag_v_scale", "im")


def _group(row: Mapping) -> tuple:
    return tuple(row.get(k) for k in GROUP_FIELDS)


def _labels(groups: Sequence[tuple]) -> dict:
    """A short label per configuration: the fields that differ between them ("" when there is one)."""
    if len(groups) <= 1:
        return {g: "" for g in groups}
    varying = [i for i in range(len(GROUP_FIELDS)) if len({g[i] for g in groups}) > 1]
    return {g: " ".join(f"{GROUP_FIELDS[i]}={g[i]:g}" if isinstance(g[i], float) else f"{GROUP_FIELDS[i]}={g[i]}"
                        for i in varying) for g in groups}


def _record_key(row: Mapping) -> tuple:
    return (row.get("record"), row.get("vertical", ""))


@dataclass
class FragilityResult:
    """The fragility of one damage state in one configuration: its ``fit`` (`FragilityFit`), bootstrap
    ``bands`` over records (or None), the ``observed`` points of its plot ((levels, n_cases, n_exceeded) of
    the stripes, or (capacities, fractions) of an IDA), the configuration's ``group`` label ("" for one) and the
    damage state's name ``ds``."""

    group: str
    ds: str
    fit: object
    bands: object = None
    observed: tuple | None = None

    @property
    def label(self) -> str:
        return f"{self.ds} | {self.group}" if self.group else self.ds


# --------------------------------------------------------------------------------------------- MSA
def msa_cases(records: Sequence[str], im: str, levels: Sequence[float], *, zeta: float = 0.05,
              **case_options) -> list[dict]:
    """The cases of a multiple-stripe analysis: every record of ``records`` scaled to every IM level of
    ``levels`` [the measure's units] in every configuration (`suite` for the arguments)."""
    levels = _stripe_levels(levels)
    return suite(records, im, zeta=zeta, **case_options).stripes(levels)


def _stripe_levels(levels) -> list[float]:
    from .validation import check_real

    out = sorted({check_real("stripes", x, lo=0.0, lo_open=True) for x in levels})
    if not out:
        raise ValueError("stripes: give at least one IM level")
    return out


def fit_msa(rows: Iterable[Mapping], damage_states=None, *, n_boot: int = 200, seed: int = 0,
            confidence: float = 0.90) -> list[FragilityResult]:
    """Per configuration and damage state, the lognormal fragility of MSA result rows by maximum likelihood over
    the stripes (`fit_fragility`), with bootstrap bands over records (``n_boot`` resamples; 0: none). Failed
    cases (``error``) are left out. A damage state that cannot be fitted (fewer than two stripes) gets a fit
    of NaN with the reason in its note."""
    from .fragility import FragilityFit, bootstrap, fit_fragility, stripe_counts

    dss = _damage_states(damage_states)
    rows = [r for r in rows if r.get("im")]
    groups: dict = {}
    for r in rows:
        groups.setdefault(_group(r), []).append(r)
    labels = _labels(list(groups))
    out = []
    for g, rs in groups.items():
        recs = sorted({_record_key(r) for r in rs}, key=str)
        levels = sorted({float(r["im_level"]) for r in rs})
        ri = {k: i for i, k in enumerate(recs)}
        li = {x: j for j, x in enumerate(levels)}
        for ds in dss:
            e = np.full((len(recs), len(levels)), np.nan)
            for r in rs:
                v = ds(r)
                if v is not None:
                    e[ri[_record_key(r)], li[float(r["im_level"])]] = float(v)
            n, k = stripe_counts(e)
            keep = n > 0
            x = np.asarray(levels)[keep]
            try:
                fit = fit_fragility(x, n[keep], k[keep], name=ds.name)
                bands = bootstrap(e[:, keep], x, n_boot=n_boot, seed=seed, confidence=confidence) \
                    if n_boot else None
            except ValueError as exc:
                fit = FragilityFit(math.nan, math.nan, "mle", int(n.sum()), math.nan, None, ds.name, str(exc))
                bands = None
            out.append(FragilityResult(labels[g], ds.name, fit, bands, (x, n[keep], k[keep])))
    return out


@dataclass
class MSAResult:
    """A multiple-stripe analysis: the result ``rows`` of its cases, the ``fragilities`` (`fit_msa`) and the
    run's ``summary`` (`rocking_model.ensemble.run_ensemble`)."""

    rows: list
    fragilities: list
    summary: dict


def run_msa(records: Sequence[str], im: str, levels: Sequence[float], out, *, damage_states=None,
            zeta: float = 0.05, n_boot: int = 200, seed: int = 0, workers: int = 0, address: str | None = None,
            resume: bool = True, progress: bool = False, batch_size: int | None = None, processes: bool = True,
            **case_options) -> MSAResult:
    """A multiple-stripe analysis into ``out`` (.csv or .parquet, `run_ensemble`: serial with workers=0, or
    on Dask; resumable), fitted per damage state (`fit_msa`). ``levels``: the stripes [the measure's units];
    ``case_options``: the configurations, as `suite`."""
    dss = _damage_states(damage_states)
    cases = msa_cases(records, im, levels, zeta=zeta, **case_options)
    summary = E.run_ensemble(cases, out, workers=workers, address=address, resume=resume, progress=progress,
                             batch_size=batch_size, processes=processes)
    ids = {c["case_id"] for c in cases}
    rows = [r for r in E.read_results(out) if r["case_id"] in ids]
    return MSAResult(rows, fit_msa(rows, dss, n_boot=n_boot, seed=seed), summary)


# --------------------------------------------------------------------------------------------- IDA
@dataclass
class IDACurve:
    """One record's IDA in one configuration: its ``rows`` sorted by IM level (``levels``), the first
    overturning level (inf if none) with the highest level below it that did not overturn (``bracket``:
    (lo, first overturning); lo 0 when none was run below), the non-overturning pockets above the first
    overturning (``resurrections``: (lowest, highest) IM level of each run of consecutive non-overturning
    levels), the ``capacities`` per damage state (the lowest level reaching it, inf if none did) and
    ``censored_at``, the highest level run."""

    record: str
    group: str
    levels: list
    rows: list
    first_overturning: float
    bracket: tuple
    resurrections: list
    capacities: dict
    censored_at: float

    def as_row(self) -> dict:
        """A flat row for a CSV: record, group, runs, first overturning, bracket, resurrections, capacities."""
        row = {"record": self.record, "group": self.group, "n_runs": len(self.levels),
               "first_overturning": self.first_overturning, "bracket_lo": self.bracket[0],
               "bracket_hi": self.bracket[1], "censored_at": self.censored_at,
               "resurrections": ";".join(f"{lo:.6g}-{hi:.6g}" for lo, hi in self.resurrections)}
        row.update({f"capacity[{k}]": v for k, v in self.capacities.items()})
        return row


class _Hunt:
    """The hunt-and-fill of one template: which IM level to run next, from the outcomes so far."""

    def __init__(self, i: int, dss: list, start: float, ratio: float, tolerance: float, max_runs: int,
                 n_above: int, im_max: float):
        self.i, self.dss = i, [_OVERTURNED] + [d for d in dss if d.field != "overturned"]
        self.start, self.ratio, self.tol = start, ratio, tolerance
        self.max_runs, self.n_above, self.im_max = max_runs, n_above, im_max
        self.rows: dict[float, dict] = {}

    def _reached(self, ds, level) -> bool | None:
        return ds(self.rows[level])

    def next_level(self) -> float | None:
        if len(self.rows) >= self.max_runs:
            return None
        if not self.rows:
            return self.start
        tried = sorted(self.rows)
        ok = [x for x in tried if not self.rows[x].get("error")]
        top = tried[-1]
        up = top * self.ratio
        can_go_up = up <= self.im_max and not self.rows[top].get("error")
        over = [x for x in ok if self.rows[x]["overturned"]]
        if can_go_up and (not over or sum(x > over[0] for x in ok) < self.n_above):
            return up                                        # hunt up (and a few levels beyond overturning)
        for ds in self.dss:                                  # bracket each damage state's first reach
            hit = [x for x in ok if self._reached(ds, x)]
            if not hit:
                continue
            u = hit[0]
            below = [x for x in ok if x < u]
            # reached at the lowest level run: hunt down; else bisect between the levels around the first reach
            x = u / self.ratio if not below else math.sqrt(below[-1] * u) if u / below[-1] > 1.0 + self.tol \
                else None
            if x is not None and x not in self.rows:         # (a failed run is not run again)
                return x
        gaps = sorted(((b / a, a, b) for a, b in zip(ok, ok[1:]) if b / a > 1.0 + self.tol), reverse=True)
        for _, a, b in gaps:                                 # fill the largest gap
            if math.sqrt(a * b) not in self.rows:
                return math.sqrt(a * b)
        return None

    def curve(self, record: str, group: str, dss: list) -> IDACurve:
        ok = sorted(x for x in self.rows if not self.rows[x].get("error"))
        over = [x for x in ok if self.rows[x]["overturned"]]
        first = over[0] if over else math.inf
        lo = max((x for x in ok if x < first), default=0.0)
        pockets, cur = [], []
        for x in ok:
            if x <= first:
                continue
            if not self.rows[x]["overturned"]:
                cur.append(x)
            elif cur:
                pockets.append((cur[0], cur[-1]))
                cur = []
        if cur:
            pockets.append((cur[0], cur[-1]))
        caps = {}
        for ds in dss:
            hit = [x for x in ok if ds(self.rows[x])]
            caps[ds.name] = hit[0] if hit else math.inf
        levels = sorted(self.rows)
        return IDACurve(record, group, levels, [self.rows[x] for x in levels], first, (lo, first), pockets, caps,
                        ok[-1] if ok else math.nan)


@dataclass
class IDAResult:
    """An incremental dynamic analysis: its ``curves`` (`IDACurve`, one per record and configuration), the
    ``fragilities`` per configuration and damage state (`fit_ida` of the capacities, bootstrap bands over
    records) and the run's ``summary``."""

    curves: list
    fragilities: list
    summary: dict


def fit_capacities(curves: Sequence[IDACurve], damage_states=None, *, method: str = "auto", n_boot: int = 200,
                   seed: int = 0, confidence: float = 0.90) -> list[FragilityResult]:
    """Per configuration and damage state, the lognormal fragility of the IDA curves' capacities (`fit_ida`):
    method "moments", "censored" (records that never reached it censored at their highest level) or "auto"
    (moments when every record reached it, else censored); bands by bootstrap over records (n_boot; 0: none)."""
    from .fragility import FragilityFit, bootstrap, fit_ida

    dss = _damage_states(damage_states)
    groups: dict = {}
    for c in curves:
        groups.setdefault(c.group, []).append(c)
    out = []
    for g, cs in groups.items():
        cens = np.array([c.censored_at for c in cs])
        for ds in dss:
            caps = np.array([c.capacities[ds.name] for c in cs])
            m = method if method != "auto" else ("moments" if np.all(np.isfinite(caps)) else "censored")
            try:
                fit = fit_ida(caps, method=m, censored_at=cens if m == "censored" else None, name=ds.name)
                bands = bootstrap(capacities=caps, n_boot=n_boot, seed=seed, confidence=confidence, ida_method=m,
                                  censored_at=cens if m == "censored" else None) if n_boot else None
            except ValueError as exc:
                fit = FragilityFit(math.nan, math.nan, f"ida_{m}", len(cs), math.nan, None, ds.name, str(exc))
                bands = None
            fin = np.sort(caps[np.isfinite(caps)])
            observed = (fin, np.arange(1, fin.size + 1) / caps.size) if fin.size else None
            out.append(FragilityResult(g, ds.name, fit, bands, observed))
    return out


def run_ida(records: Sequence[str], im: str, out, *, start: float, ratio: float = 1.5, rtol: float = 0.02,
            max_runs: int = 30, n_above: int = 2, im_max: float = math.inf, damage_states=None,
            zeta: float = 0.05, method: str = "auto", n_boot: int = 200, seed: int = 0, workers: int = 0,
            address: str | None = None, resume: bool = True, progress: bool = False,
            batch_size: int | None = None, processes: bool = True, **case_options) -> IDAResult:
    """An incremental dynamic analysis into ``out`` (.csv or .parquet; every run a case: resumable; serial with
    workers=0, or on Dask, the records' next runs in parallel): per record and configuration (`suite`), the
    hunt-and-fill of the module docstring on the IM level.

    start: first IM level [the measure's units]; ratio: the hunt's step factor (> 1); rtol: relative gap
    of the bisections and the fill (e.g. 0.02: the first overturning within 2 %); max_runs: runs per record;
    n_above: hunt levels run above the first overturning (the pockets above it are searched there); im_max:
    no level above it [the measure's units]. Capacities per damage state (overturning always included) are
    fitted by `fit_capacities` (method, n_boot, seed)."""
    from .validation import check_real

    start = check_real("start", start, lo=0.0, lo_open=True)
    ratio = check_real("ratio", ratio, lo=1.0, lo_open=True, hi=100.0)
    rtol = check_real("rtol", rtol, lo=1e-6, hi=1.0)
    max_runs = int(check_real("max_runs", max_runs, lo=1))
    n_above = int(check_real("n_above", n_above, lo=0))
    if not (im_max > 0):
        raise ValueError(f"im_max = {im_max!r} is out of range; allowed range (0, inf]")
    dss = _damage_states(damage_states)
    if not any(d.field == "overturned" for d in dss):
        dss = dss + [_OVERTURNED]
    s = suite(records, im, zeta=zeta, **case_options)
    hunts = [_Hunt(i, dss, start, ratio, rtol, max_runs, n_above, im_max) for i in range(len(s.templates))]
    run = E.EnsembleRun(out, workers=workers, address=address, resume=resume, progress=progress,
                        batch_size=batch_size, processes=processes)
    n_cases = n_skipped = 0
    with run:
        active = list(hunts)
        while active:
            batch, nxt = [], []
            for h in active:
                x = h.next_level()
                if x is not None:
                    batch.append((h, x, s.at(h.i, x)))
                    nxt.append(h)
            active = nxt
            if not batch:
                break
            cases = [c for _, _, c in batch]
            n_cases += len(cases)
            todo = run.todo(cases)
            n_skipped += len(cases) - len(todo)
            if todo:
                run.progress_total((run.bar.total if run.bar is not None else 0) + len(todo))
            for (h, x, _), row in zip(batch, run.run(cases)):
                h.rows[x] = row
    rows0 = [s.templates[h.i] for h in hunts]
    groups = [_group(dict(t, im=_im_field(s.im, s.zeta))) for t in rows0]
    labels = _labels(sorted(set(groups), key=str))
    curves = [h.curve(t["record"], labels[g], dss) for h, t, g in zip(hunts, rows0, groups)]
    summary = dict(n_cases=n_cases, n_skipped=n_skipped, **run.stats)
    summary["throughput"] = summary["n_run"] / summary["wall_time"] if summary["wall_time"] > 0 else math.nan
    return IDAResult(curves, fit_capacities(curves, dss, method=method, n_boot=n_boot, seed=seed), summary)


# --------------------------------------------------------------------------------------------- output
def write_fragilities(results: Sequence[FragilityResult], out_dir, *, im_label: str = "IM", plot: bool = True,
                      stem: str = "fragility", title: str | None = None) -> list[Path]:
    """Write the fits' parameters as ``<stem>.csv`` and ``<stem>.json`` (`rocking_model.fragility.to_csv`,
    `to_json`: one row per damage state and configuration, named "ds | configuration", with the bootstrap
    bands) and, with ``plot``, one ``<stem>[_<n>].png`` per configuration (`plot_fragility`: the curves, bands
    and observed fractions). Returns the paths written."""
    from .fragility import plot_fragility, to_csv, to_json

    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    fits = {r.label: r.fit for r in results}
    bands = {r.label: r.bands for r in results}
    written = [to_csv(fits, out_dir / f"{stem}.csv", bands), to_json(fits, out_dir / f"{stem}.json", bands)]
    if plot:
        groups: dict = {}
        for r in results:
            groups.setdefault(r.group, []).append(r)
        for n, (g, rs) in enumerate(groups.items()):
            ok = [r for r in rs if not math.isnan(r.fit.theta)]
            if not ok:
                continue
            path = out_dir / (f"{stem}.png" if len(groups) == 1 else f"{stem}_{n + 1}.png")
            ax = plot_fragility({r.ds: r.fit for r in ok}, observed={r.ds: r.observed for r in ok},
                                bands={r.ds: r.bands for r in ok}, im_label=im_label,
                                title=(title or "") + (f" ({g})" if g else ""), path=path)
            import matplotlib.pyplot as plt
            plt.close(ax.figure)
            written.append(path)
    return written


def write_curves(curves: Sequence[IDACurve], path) -> Path:
    """The IDA curves' summary (`IDACurve.as_row`), one row per record and configuration, as CSV."""
    from .fragility import write_rows

    return write_rows([c.as_row() for c in curves], path)
