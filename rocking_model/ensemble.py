"""Ensembles of rocking simulations: case grids, one pure function per case, and runners (serial, or Dask).

A case is a flat dict of plain values (model, geometry, ground motion, scheme, solver settings) with a
content-based ``case_id``; `run_case` turns it into a result row (the case plus max|phi|, overturned, time
of overturning, impacts, wall time). `run_ensemble` runs a list of cases on a Dask cluster (a LocalCluster
on this machine by default, or an existing scheduler by address) or serially (workers=0, no Dask needed),
writes each row as soon as it arrives (CSV appended and flushed, or Parquet parts) and, on restart, skips
the case ids already in the output, so an interrupted run loses nothing and resumes.

Dimensionless pulse grids follow Makris' overturning spectra: amplitude ratio A / (g tan(alpha)) and
frequency ratio omega_p / p of the rigid block (alpha = atan(b/h), p = sqrt(3g/(4R))).
"""
from __future__ import annotations

import csv
import functools
import hashlib
import itertools
import json
import logging
import math
import os
import time
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
CASE_FIELDS = ("case_id", "model", "b", "h", "e_N", "mu", "motion", "A", "omega_p", "a_ratio", "w_ratio",
               "record", "units", "scale", "scheme", "t_end", "output_interval", "tolerance", "dt_max")
#: result fields appended by `run_case`
RESULT_FIELDS = ("alpha", "p", "max_abs_phi", "max_phi_over_alpha", "overturned", "t_overturn", "impacts",
                 "max_abs_slip", "friction_demand", "wall_time", "error")
FIELDS = CASE_FIELDS + RESULT_FIELDS

_FLOATS = {"b", "h", "e_N", "mu", "max_abs_slip", "friction_demand", "A", "omega_p", "a_ratio", "w_ratio", "scale", "t_end", "output_interval",
           "tolerance", "dt_max", "alpha", "p", "max_abs_phi", "max_phi_over_alpha", "t_overturn",
           "wall_time"}
_INTS = {"impacts"}
_BOOLS = {"overturned"}


def case_id(case: dict) -> str:
    """Content hash of the case's parameters: the same case gets the same id in every run."""
    key = {k: case.get(k) for k in CASE_FIELDS if k != "case_id"}
    if key.get("mu") in (None, math.inf):
        del key["mu"]             # the default law: the ids of the cases of earlier versions stay valid
    return hashlib.sha1(json.dumps(key, sort_keys=True, default=repr).encode()).hexdigest()[:16]


def _rigid_scales(b: float, h: float, g: float = 9.81) -> tuple[float, float]:
    """(alpha [rad], p [rad/s]) of the rigid block."""
    R = math.hypot(b, h)
    return math.atan2(b, h), math.sqrt(3.0 * g / (4.0 * R))


def _finish(case: dict) -> dict:
    case = {k: case.get(k, "" if k in ("record", "units") else math.inf if k == "mu" else math.nan)
            for k in CASE_FIELDS}
    case["case_id"] = case_id(case)
    return case


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
                dt_max: float | None = None) -> list[dict]:
    """Grid of pulse cases: pulse ``kind`` x amplitudes x frequencies x geometries (b, h) [m] x schemes.

    Amplitudes either as ratios A / (g tan(alpha)) or in m/s2; frequencies as ratios omega_p / p or in Hz
    (omega_p = 2 pi f). Ratios need the rigid block. t_end [s] defaults to the end of the pulse plus 15/p
    (enough for overturning after an impact). dt_max: Moreau-Jean step [s] (default 1e-3). e_N, mu: the
    model's coefficient of restitution and friction coefficient (inf: the paper's sticking law)."""
    if kind not in PULSES:
        raise ValueError(f"pulse = {kind!r} is not supported; allowed values: {', '.join(PULSES)}")
    model_class(model)                    # ValueError naming the registered models
    if (amplitude_ratios is None) == (amplitudes is None):
        raise ValueError("give either amplitude ratios A/(g tan alpha) or amplitudes [m/s2]")
    if (frequency_ratios is None) == (frequencies is None):
        raise ValueError("give either frequency ratios omega_p/p or frequencies [Hz]")
    if model != "rigid" and (amplitude_ratios is not None or frequency_ratios is not None):
        raise ValueError("amplitude and frequency ratios are defined for the rigid block; give amplitudes "
                         "[m/s2] and frequencies [Hz] for the flexible oscillator")
    amps = _check_list("amplitude ratio" if amplitudes is None else "amplitude",
                       amplitude_ratios if amplitudes is None else amplitudes)
    freqs = _check_list("frequency ratio" if frequencies is None else "frequency",
                        frequency_ratios if frequencies is None else frequencies)
    for s in schemes:
        if s not in SCHEMES:
            raise ValueError(f"scheme = {s!r} is not supported; allowed values: {', '.join(SCHEMES)}")
    cases = []
    for (b, h), scheme, a, f in itertools.product(geometries, schemes, amps, freqs):
        alpha, p = _rigid_scales(b, h) if model == "rigid" else (math.nan, math.nan)
        A = a * 9.81 * math.tan(alpha) if amplitudes is None else a
        omega_p = f * p if frequencies is None else 2.0 * math.pi * f
        T_p = 2.0 * math.pi / omega_p
        t_pulse = 3.0 * T_p if kind == "ricker" else T_p
        p_ref = p if model == "rigid" else 2.5
        te = t_end if t_end is not None else t_pulse + 15.0 / p_ref
        cases.append(_finish(dict(model=model, b=float(b), h=float(h), e_N=float(e_N), mu=float(mu), motion=kind, A=A,
                                  omega_p=omega_p, a_ratio=A / (9.81 * math.tan(alpha)) if model == "rigid"
                                  else math.nan, w_ratio=omega_p / p if model == "rigid" else math.nan,
                                  scale=1.0, scheme=scheme, t_end=float(te), output_interval=output_interval,
                                  tolerance=tolerance, dt_max=math.nan if dt_max is None else dt_max)))
    return cases


def record_cases(records: Sequence[str], scales: Sequence[float] = (1.0,), *, units: str | None = None,
                 geometries: Sequence[tuple[float, float]] = ((0.2, 1.0),), schemes: Sequence[str] = ("event_driven",),
                 model: str = "rigid", e_N: float = 0.0, mu: float = math.inf, t_end: float | None = None,
                 output_interval: float = 0.01, tolerance: float = 1e-8, dt_max: float | None = None) -> list[dict]:
    """Grid of record cases: records (file paths or ``synthetic:<seed>``) x scale factors x geometries x
    schemes. t_end [s] defaults to the record's end plus 5 s. The records are read here once (so a bad
    file fails before anything runs) and again, once per worker, by `run_case`."""
    from .records import load_motion

    scales = _check_list("scale", scales)
    for s in schemes:
        if s not in SCHEMES:
            raise ValueError(f"scheme = {s!r} is not supported; allowed values: {', '.join(SCHEMES)}")
    cases = []
    for spec in records:
        rec = load_motion(spec, units)
        spec = spec if str(spec).startswith("synthetic") else str(Path(spec).resolve())
        te = t_end if t_end is not None else float(rec.t[-1]) + 5.0
        for (b, h), scheme, s in itertools.product(geometries, schemes, scales):
            alpha, p = _rigid_scales(b, h) if model == "rigid" else (math.nan, math.nan)
            cases.append(_finish(dict(model=model, b=float(b), h=float(h), e_N=float(e_N), mu=float(mu), motion="record",
                                      record=spec, units=units or "", scale=float(s), scheme=scheme,
                                      A=rec.pga * s, a_ratio=rec.pga * s / (9.81 * math.tan(alpha)),
                                      t_end=float(te), output_interval=output_interval, tolerance=tolerance,
                                      dt_max=math.nan if dt_max is None else dt_max)))
    return cases


# --------------------------------------------------------------------------------------------- one case
@functools.lru_cache(maxsize=32)
def _record(spec: str, units: str):
    from .records import load_motion
    return load_motion(spec, units or None)


def case_motion(case: dict):
    """The GroundMotion of a case."""
    from . import ground_motion as gm

    kind = case["motion"]
    if kind == "record":
        return _record(case["record"], case.get("units") or "").scaled(case["scale"])
    if kind not in PULSES:
        raise ValueError(f"motion = {kind!r} is not supported; allowed values: record, {', '.join(PULSES)}")
    # the pulse starts at t = 0 (Ricker: centred at 1.5 T_p); a rectangular pulse lasts 2 pi / omega_p
    return gm.pulse_from_parameters(kind, case["A"], case["omega_p"], scale=case.get("scale", 1.0))


def case_model(case: dict):
    """The model of a case: the registered ``case["model"]`` (`rocking_model.models.MODELS`) with the case's
    b, h, e_N and mu (inf where a file of an earlier version has none)."""
    mu = case.get("mu", math.inf)
    return model_class(case["model"])(b=case["b"], h=case["h"], e_N=case["e_N"],
                                      mu=math.inf if mu != mu else mu)


def run_case(case: dict) -> dict:
    """Simulate one case; return its row (the case plus results). Never raises: a failure is recorded in
    ``error`` (so one bad case does not stop an ensemble). t_overturn [s] is the first output time at which
    the block has overturned (resolution: output_interval); NaN if it did not."""
    import numpy as np

    from .simulation import simulate

    row = dict(case)
    alpha, p = _rigid_scales(case["b"], case["h"]) if case["model"] == "rigid" else (math.nan, math.nan)
    row.update(alpha=alpha, p=p, max_abs_phi=math.nan, max_phi_over_alpha=math.nan, overturned=False,
               t_overturn=math.nan, impacts=-1, max_abs_slip=math.nan, friction_demand=math.nan, error="")
    t0 = time.perf_counter()
    try:
        kw = {}
        if case["scheme"] == "event_driven":
            kw["tolerance"] = case["tolerance"]
        if case.get("dt_max") is not None and not math.isnan(case["dt_max"]):
            kw["dt_max"] = case["dt_max"]
        res = simulate(case_model(case), case_motion(case), case["t_end"], scheme=case["scheme"],
                       output_interval=case["output_interval"], **kw)
        phi = np.abs(res.phi)
        over = np.asarray(res.overturned, dtype=bool)
        row["max_abs_phi"] = float(phi.max())
        row["max_phi_over_alpha"] = float(phi.max() / alpha) if case["model"] == "rigid" else math.nan
        row["overturned"] = bool(over[-1])
        row["t_overturn"] = float(res.t[np.argmax(over)]) if over[-1] else math.nan
        row["impacts"] = int(res.impacts[-1])
        row["max_abs_slip"] = float(np.max(np.abs(res.slip)))
        row["friction_demand"] = float(res.friction_demand[-1])
    except Exception as exc:          # recorded, not raised: see the docstring
        row["error"] = f"{type(exc).__name__}: {exc}"
    row["wall_time"] = time.perf_counter() - t0
    return row


def _warm_up() -> None:
    run_case(pulse_cases("sine", amplitude_ratios=[2.0], frequency_ratios=[4.0], t_end=0.5)[0])


def run_batch(cases: list[dict]) -> list[dict]:
    """`run_case` over a few cases (one Dask task)."""
    return [run_case(c) for c in cases]


# --------------------------------------------------------------------------------------------- output
def _parse(row: dict) -> dict:
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
    return out


def _is_parquet(out: Path) -> bool:
    return out.suffix == ".parquet" or (out.is_dir() and any(out.glob("part-*.parquet")))


def read_results(out) -> list[dict]:
    """All rows written so far to ``out`` (a .csv file or a .parquet directory of parts), typed. A row
    cut short by an interruption is ignored; if a case appears twice the last row wins."""
    out = Path(out)
    rows: dict[str, dict] = {}
    if _is_parquet(out):
        if not out.is_dir():
            return []
        import pyarrow.parquet as pq
        for part in sorted(out.glob("part-*.parquet")):
            for r in pq.read_table(part).to_pylist():
                rows[r["case_id"]] = _parse(r)
        return list(rows.values())
    if not out.exists():
        return []
    with open(out, newline="") as f:
        text = f.read()
    if text and not text.endswith("\n"):
        text = text[:text.rfind("\n") + 1]           # the unfinished last line of a killed run
    reader = csv.DictReader(text.splitlines())
    for r in reader:
        if r.get("case_id") and None not in r and all(v is not None for v in r.values()):
            rows[r["case_id"]] = _parse(r)
    return list(rows.values())


class CsvWriter:
    """Appends rows to a CSV file; every row is flushed to the OS at once (a killed run keeps it)."""

    def __init__(self, path: Path):
        self.path = path
        path.parent.mkdir(parents=True, exist_ok=True)
        if path.exists() and path.stat().st_size > 0:
            with open(path, "rb+") as f:
                data = f.read()
                header = data.split(b"\n", 1)[0].decode().strip().split(",")
                if header != list(FIELDS):
                    raise ValueError(f"{path}: its columns are not those of an ensemble output; use another "
                                     "--out")
                if not data.endswith(b"\n"):                    # drop the unfinished row
                    f.truncate(data.rfind(b"\n") + 1)
            self.f = open(path, "a", newline="")
            self.w = csv.DictWriter(self.f, FIELDS)
        else:
            self.f = open(path, "w", newline="")
            self.w = csv.DictWriter(self.f, FIELDS)
            self.w.writeheader()
        self.f.flush()

    def write(self, rows: Iterable[dict]) -> None:
        for r in rows:
            self.w.writerow({k: r.get(k, "") for k in FIELDS})
        self.f.flush()

    def close(self) -> None:
        self.f.flush()
        os.fsync(self.f.fileno())
        self.f.close()


class ParquetWriter:
    """Writes rows as Parquet parts (part-<n>.parquet) in a directory, each part written to a temporary
    name and renamed (atomic); rows are buffered up to ``rows_per_part`` or ``seconds`` and flushed on
    close, also after Ctrl-C. A hard kill loses at most the buffer."""

    def __init__(self, path: Path, rows_per_part: int = 200, seconds: float = 10.0):
        import pyarrow  # noqa: F401  (fail early with a clear ImportError)
        self.path, self.rows_per_part, self.seconds = path, rows_per_part, seconds
        path.mkdir(parents=True, exist_ok=True)
        self.n = len(list(path.glob("part-*.parquet")))
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
        table = pa.Table.from_pylist([{k: r.get(k) for k in FIELDS} for r in self.buf])
        while (self.path / f"part-{self.n:05d}.parquet").exists():
            self.n += 1
        final = self.path / f"part-{self.n:05d}.parquet"
        tmp = self.path / f".tmp-{self.n:05d}.parquet"
        pq.write_table(table, tmp)
        os.replace(tmp, final)
        self.n += 1
        self.buf = []
        self.t_last = time.monotonic()

    def close(self) -> None:
        self.flush()


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


def run_ensemble(cases: Sequence[dict], out, *, workers: int = 2, address: str | None = None,
                 resume: bool = True, progress: bool = True, batch_size: int | None = None, processes: bool = True,
                 on_row: Callable[[dict], None] | None = None) -> dict:
    """Run ``cases`` and write one row per case to ``out`` (.csv, or a .parquet directory).

    workers: number of local Dask workers (one thread each; ``processes=False`` runs them as threads of
        this process, e.g. for tests); 0 runs serially here without Dask.
    address: scheduler address of an existing Dask cluster (tcp://host:8786); then ``workers`` is ignored.
        The workers need rocking_model installed (and the record files at the same paths).
    resume: skip the case ids already in ``out``; otherwise ``out`` must not exist yet.
    batch_size: cases per Dask task; larger batches amortize the few ms of scheduling and round trip per
        task; default: about 20 tasks per worker, at most 20 cases each (rows are still written per task).
    Returns a summary: n_cases, n_skipped, n_run, n_errors, n_overturned, wall_time [s] (from the first
    submission to the last row), throughput [cases/s], setup_time [s] (cluster start), workers.
    """
    out = Path(out)
    if not resume and out.exists():
        raise ValueError(f"{out} exists; remove it or resume (the default)")
    done = {r["case_id"] for r in read_results(out)} if resume else set()
    todo, seen = [], set()
    for c in cases:
        if c["case_id"] not in done and c["case_id"] not in seen:
            seen.add(c["case_id"])
            todo.append(c)
    n_total = len(done | {c["case_id"] for c in cases})
    summary = dict(n_cases=len(cases), n_skipped=len(cases) - len(todo), n_run=0, n_errors=0, n_overturned=0,
                   wall_time=0.0, throughput=math.nan, setup_time=0.0, workers=workers, address=address or "")
    if not todo:
        return summary
    writer = _writer(out)
    bar = _progress(len(cases), len(cases) - len(todo), progress)

    def take(rows):
        writer.write(rows)
        for r in rows:
            summary["n_run"] += 1
            summary["n_errors"] += bool(r["error"])
            summary["n_overturned"] += bool(r["overturned"])
            if on_row is not None:
                on_row(r)
        if bar is not None:
            bar.update(len(rows))

    t_setup = time.perf_counter()
    client = cluster = None
    try:
        if workers == 0 and address is None:
            t0 = time.perf_counter()
            for c in todo:
                take([run_case(c)])
        else:
            try:
                from dask.distributed import Client, LocalCluster, as_completed
            except ImportError:
                raise ImportError("ensembles on Dask need dask.distributed: pip install "
                                  "'rocking-model[ensemble]' (or run serially with workers=0)") from None
            if address:
                client = Client(address, timeout="10s")
                summary["workers"] = len(client.scheduler_info().get("workers", {}))
            else:
                if workers < 1:
                    raise ValueError(f"workers = {workers} is out of range; allowed range [0, inf)")
                # silence_logs: shutdown chatter (a worker's last heartbeat to a closed scheduler) is noise
                cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=processes,
                                       dashboard_address=":0", silence_logs=logging.CRITICAL)
                client = Client(cluster)
                client.wait_for_workers(workers)
            # import the package and run one short case on every worker before the clock starts
            client.run(_warm_up)
            summary["setup_time"] = time.perf_counter() - t_setup
            t0 = time.perf_counter()
            n_w = max(1, len(client.scheduler_info().get("workers", {})))
            if batch_size is None:
                batch_size = max(1, min(20, len(todo) // (20 * n_w)))
            summary["batch_size"] = batch_size
            batches = [todo[i:i + batch_size] for i in range(0, len(todo), max(1, batch_size))]
            futures = client.map(run_batch, batches, pure=False)
            for fut in as_completed(futures):
                take(fut.result())
                fut.release()
    finally:
        writer.close()
        if bar is not None:
            bar.close()
        if client is not None:
            client.close()
        if cluster is not None:
            cluster.close()
    summary["wall_time"] = time.perf_counter() - t0
    summary["throughput"] = summary["n_run"] / summary["wall_time"] if summary["wall_time"] > 0 else math.nan
    summary["n_total_in_output"] = n_total
    return summary
