"""Ground-motion records: readers for PEER NGA ``.AT2`` files and two-column CSV files, writers for both,
unit conversion, and a fixed-seed synthetic accelerogram.

Every reader returns a `Record`: a `SampledMotion` (t [s], ag [m/s2], linear between samples, zero outside
the record, breakpoints at the samples) that also carries its name, source file and the header lines.
A malformed file raises ValueError naming the file and the line; a missing one FileNotFoundError.

Unit "g" is standard gravity g_n = 9.80665 m/s2 (the unit PEER records use); a model's own ``g`` parameter
(9.81 by default) is physics, not a unit, and is not used for conversion.
"""
from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np

from .ground_motion import SampledMotion
from .validation import check_real

#: standard gravity [m/s2], the unit "g" of records
G_N = 9.80665

#: accepted unit spellings (after `_norm_unit`) -> factor to m/s2
UNITS = {
    "g": G_N,
    "m/s2": 1.0,
    "cm/s2": 0.01, "gal": 0.01,
    "mm/s2": 0.001,
    "in/s2": 0.0254,
    "ft/s2": 0.3048,
}


def _norm_unit(units: str) -> str:
    u = str(units).strip().lower().replace(" ", "").replace("**", "").replace("^", "")
    u = u.replace("sec", "s").replace("/s/s", "/s2").replace("s-2", "/s2").replace("//", "/")
    return {"gals": "gal", "ms-2": "m/s2", "m.s-2": "m/s2"}.get(u, u)


def unit_factor(units: str) -> float:
    """Factor that converts an acceleration in ``units`` to m/s2 (g, m/s2, cm/s2 = gal, mm/s2, in/s2,
    ft/s2; spellings such as m/s^2, m/s**2, m/s/s, cm/sec2 are accepted)."""
    u = _norm_unit(units)
    if u not in UNITS:
        raise ValueError(f"units = {units!r} is not supported; allowed values: " + ", ".join(UNITS))
    return UNITS[u]


class Record(SampledMotion):
    """A sampled record: t [s], ag [m/s2]; ``name``, ``source`` (file or None), ``header`` (list of str),
    ``units`` (the units of the values in the file, None if not read from a file) and ``units_assumed``
    (True when the file did not state them and no units were given: a reader's default was used)."""

    def __init__(self, t, ag, name: str = "record", source: str | None = None, header=(),
                 units: str | None = None, units_assumed: bool = False):
        super().__init__(t, ag)
        self.name = str(name)
        self.source = source
        self.header = list(header)
        self.units = units
        self.units_assumed = bool(units_assumed)

    def _like(self, t, ag, name: str) -> "Record":
        return Record(t, ag, name, self.source, self.header, self.units, self.units_assumed)

    def scaled(self, factor: float) -> "Record":
        factor = check_real("factor", factor)
        return self._like(self.t, factor * self.ag, f"{self.name} x {factor:g}")

    def resampled(self, dt: float, t_start: float | None = None, t_end: float | None = None) -> "Record":
        r = super().resampled(dt, t_start, t_end)
        return self._like(r.t, r.ag, f"{self.name} @ {dt:g} s")

    def __repr__(self) -> str:
        return (f"Record({self.name!r}, {self.t.size} samples, dt = {self.dt:g} s, "
                f"PGA = {self.pga / G_N:.3g} g)")


def scaled(motion, factor: float):
    """``motion`` times ``factor`` [1] (function form of `GroundMotion.scaled`)."""
    return motion.scaled(factor)


def resampled(motion, dt: float, t_start: float | None = None, t_end: float | None = None):
    """``motion`` sampled every ``dt`` [s] (function form of `GroundMotion.resampled`)."""
    return motion.resampled(dt, t_start, t_end)


# --------------------------------------------------------------------------------------------- numbers
_FLOAT = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[EeDd][-+]?\d+)?"
_RUN = re.compile(rf"(?:{_FLOAT})+")


def _floats(line: str, where: str) -> list[float]:
    """The numbers on a data line. Fortran output sometimes runs them together (-.1E-02-.2E-02)."""
    out = []
    for tok in line.replace(",", " ").split():
        try:
            out.append(float(tok))
            continue
        except ValueError:
            pass
        if _RUN.fullmatch(tok):
            out.extend(float(x.replace("D", "E").replace("d", "e")) for x in re.findall(_FLOAT, tok))
        else:
            raise ValueError(f"{where}: {tok!r} is not a number")
    return out


# --------------------------------------------------------------------------------------------- PEER AT2
_NPTS_NEW = re.compile(rf"NPTS\s*=\s*(\d+)\s*,?\s*DT\s*=\s*({_FLOAT})", re.IGNORECASE)
_NPTS_OLD = re.compile(rf"^\s*(\d+)\s+({_FLOAT})\s+NPTS\s*,\s*DT", re.IGNORECASE)


def _at2_units(line: str) -> str | None:
    u = line.upper()
    if re.search(r"UNITS?\s+OF\s+G\b", u):
        return "g"
    for pat, unit in ((r"CM/S(EC)?(\*\*2|\^2|2|/S(EC)?)", "cm/s2"), (r"\bGALS?\b", "gal"),
                      (r"\bM/S(EC)?(\*\*2|\^2|2|/S(EC)?)", "m/s2")):
        if re.search(pat, u):
            return unit
    return None


def read_at2(path, units: str | None = None, name: str | None = None) -> Record:
    """Read a PEER NGA ``.AT2`` acceleration file into a `Record` (t [s] from 0, ag [m/s2]).

    Layout: 3 header lines (title, event, "ACCELERATION TIME SERIES IN UNITS OF G"), a 4th line with the
    number of points and the time step, either NGA-West2 style ``NPTS=  5590, DT=   .0050 SEC`` or the older
    ``  5590    0.0050    NPTS, DT``, then the samples, several per line. ``units`` overrides the units
    stated on line 3 (g if none is stated). Raises ValueError naming the file and line when the file is
    malformed (missing NPTS/DT, a non-number, fewer samples than NPTS, DT <= 0)."""
    path = Path(path)
    try:
        lines = path.read_text(errors="replace").splitlines()
    except OSError as exc:       # FileNotFoundError, PermissionError, IsADirectoryError: kept, with the path
        raise type(exc)(f"{path}: cannot read the record ({exc.strerror or exc})") from None
    if len(lines) < 4:
        raise ValueError(f"{path}: not a PEER AT2 file: {len(lines)} lines, expected 4 header lines and data")
    npts = dt = None
    for i in range(min(len(lines), 6)):
        m = _NPTS_NEW.search(lines[i]) or _NPTS_OLD.search(lines[i])
        if m:
            npts, dt, first = int(m.group(1)), float(m.group(2)), i + 1
            break
    if npts is None:
        raise ValueError(f"{path}, line 4: no 'NPTS=..., DT=...' (or '<npts> <dt> NPTS, DT') header: "
                         f"{lines[3].strip()!r}")
    where = f"{path}, line {first}"
    if not (math.isfinite(dt) and dt > 0.0):
        raise ValueError(f"{where}: DT = {dt!r} is out of range; allowed range (0, inf)")
    if npts < 2:
        raise ValueError(f"{where}: NPTS = {npts} is out of range; allowed range [2, inf)")
    header = lines[:first]
    assumed = False
    if units is None:
        # the line that states the units ("... IN UNITS OF G", PEER's line 3) first: a title or event line may
        # mention another unit ("PGA 0.4 g (g = 9.81 m/s2)")
        stating = sorted(header, key=lambda line: "UNIT" not in line.upper())
        units = next((u for u in map(_at2_units, stating) if u), None)
        if units is None:
            units, assumed = "g", True          # the PEER convention
    factor = unit_factor(units)
    values: list[float] = []
    for j in range(first, len(lines)):
        if lines[j].strip():
            values.extend(_floats(lines[j], f"{path}, line {j + 1}"))
    if len(values) < npts:
        raise ValueError(f"{path}, line {len(lines)}: {len(values)} samples, header (line {first}) says "
                         f"NPTS = {npts}")
    if len(values) > npts and any(v != 0.0 for v in values[npts:]):
        raise ValueError(f"{path}: {len(values)} samples, header (line {first}) says NPTS = {npts}")
    ag = np.array(values[:npts]) * factor
    if not np.all(np.isfinite(ag)):
        raise ValueError(f"{path}: the samples must be finite numbers")
    return Record(np.arange(npts) * dt, ag, name or path.stem, str(path), header, units, assumed)


def _samples(writer: str, t, ag, units):
    """(t, ag, units) from a writer's arguments: ``t`` and ``ag`` arrays [s], [m/s2], or ``t`` a `Record` /
    `SampledMotion` (what the readers return) with ``ag`` omitted, or given as the units (positional)."""
    if hasattr(t, "t") and hasattr(t, "ag"):
        if isinstance(ag, str) and units is None:
            ag, units = None, ag
        if ag is not None:
            raise ValueError(f"{writer}: give a record, or the arrays t and ag, not both")
        return np.asarray(t.t, dtype=float), np.asarray(t.ag, dtype=float), units
    if ag is None:
        raise ValueError(f"{writer}: ag is missing (give a record, or the arrays t and ag)")
    return np.asarray(t, dtype=float), np.asarray(ag, dtype=float), units


def write_at2(path, t, ag=None, units: str | None = None, title: str | None = None,
              event: str = "synthetic", digits: int = 17) -> Path:
    """Write samples ag [m/s2] at uniform times t [s] (t[0] = 0) as a PEER AT2 file in ``units`` (default g):
    NGA-West2 header, 5 values a line in E format with ``digits`` significant digits (17 round-trips the
    values; PEER files use 7). ``write_at2(path, record)`` writes a `Record` (or any `SampledMotion`) as the
    readers return it; its name is the title line unless ``title`` is given."""
    name = getattr(t, "name", None)
    t, ag, units = _samples("write_at2", t, ag, units)
    units = "g" if units is None else units
    title = title if title is not None else (name if name is not None else "rocking_model record")
    if t.ndim != 1 or t.shape != ag.shape or t.size < 2:
        raise ValueError("write_at2: t and ag must be 1-D arrays of equal length >= 2")
    dt = float(t[1] - t[0])
    if abs(t[0]) > 1e-12 or not np.allclose(np.diff(t), dt, rtol=1e-9, atol=0.0) or dt <= 0.0:
        raise ValueError("write_at2: t must be uniform from 0 (AT2 stores only NPTS and DT)")
    u = _norm_unit(units)
    values = ag / unit_factor(units)
    label = "G" if u == "g" else units.upper()
    lines = [title, event, f"ACCELERATION TIME SERIES IN UNITS OF {label}",
             f"NPTS={t.size:7d}, DT={dt:12.6g} SEC"]
    fmt = f"{{:{digits + 8}.{digits - 1}E}}"
    for k in range(0, values.size, 5):
        lines.append("".join(fmt.format(v) for v in values[k:k + 5]))
    path = Path(path)
    path.write_text("\n".join(lines) + "\n")
    return path


# --------------------------------------------------------------------------------------------- CSV
_UNIT_IN_HEADER = re.compile(r"[\[(]([^\])]+)[\])]")


def read_csv(path, units: str | None = None, name: str | None = None,
             default_units: str | None = None) -> Record:
    """Read a two-column text file (time [s], acceleration) into a `Record` (ag converted to m/s2).

    Separators: comma, semicolon, tab or spaces. Lines starting with '#' are comments. An optional first
    non-comment line is a header; the acceleration units are taken from it (``time [s], ag [g]`` or
    ``t (s), acc (cm/s2)``) or from a comment ``# units: g``, else from ``units``, else from
    ``default_units``. Units neither stated nor given (and no ``default_units``), or stated and given
    differently, are an error. Times must be strictly increasing. Raises ValueError naming the file and line
    of the first problem."""
    path = Path(path)
    try:
        lines = path.read_text(errors="replace").splitlines()
    except OSError as exc:       # FileNotFoundError, PermissionError, IsADirectoryError: kept, with the path
        raise type(exc)(f"{path}: cannot read the record ({exc.strerror or exc})") from None
    stated = None
    t, a = [], []
    header_seen = False
    for j, raw in enumerate(lines, start=1):
        line = raw.strip()
        if not line:
            continue
        if line.startswith("#"):
            m = re.match(r"#\s*units?\s*[:=]\s*(\S+)", line, re.IGNORECASE)
            if m:
                stated = m.group(1)
            continue
        sep = "," if "," in line else ";" if ";" in line else None
        cells = [c.strip() for c in line.split(sep)]
        if cells and cells[-1] == "" and sep:
            cells = cells[:-1]                      # trailing separator
        try:
            row = [float(c) for c in cells]
        except ValueError:
            if not t and not header_seen:           # the header line
                header_seen = True
                found = _UNIT_IN_HEADER.findall(cells[1]) if len(cells) > 1 else []
                if found:
                    stated = found[-1]
                continue
            bad = next(c for c in cells if not _is_float(c))
            raise ValueError(f"{path}, line {j}: {bad!r} is not a number") from None
        if len(row) != 2:
            raise ValueError(f"{path}, line {j}: {len(row)} columns, expected 2 (time [s], acceleration)")
        if not all(map(math.isfinite, row)):
            raise ValueError(f"{path}, line {j}: values must be finite, got {line!r}")
        if t and row[0] <= t[-1]:
            raise ValueError(f"{path}, line {j}: time {row[0]:g} s is not after the previous {t[-1]:g} s; "
                             "times must be strictly increasing")
        t.append(row[0])
        a.append(row[1])
    if len(t) < 2:
        raise ValueError(f"{path}: {len(t)} data rows, expected at least 2 (time [s], acceleration)")
    if units is None and stated is None and default_units is not None:
        factor = unit_factor(default_units)
        return Record(np.array(t), np.array(a) * factor, name or path.stem, str(path), [], default_units, True)
    if units is None and stated is None:
        raise ValueError(f"{path}: acceleration units are not stated (header 'time [s], ag [g]' or "
                         f"'# units: g'); give them (units=..., CLI --units); allowed values: "
                         + ", ".join(UNITS))
    if units is not None and stated is not None and unit_factor(units) != unit_factor(stated):
        raise ValueError(f"{path}: the file states units {stated!r}, but units = {units!r} was given")
    used = units if units is not None else stated
    return Record(np.array(t), np.array(a) * unit_factor(used), name or path.stem, str(path), [], used)


def _is_float(s: str) -> bool:
    try:
        float(s)
        return True
    except ValueError:
        return False


def write_csv(path, t, ag=None, units: str | None = None) -> Path:
    """Write t [s] and ag [m/s2] as ``time [s],ag [<units>]`` CSV, ag converted to ``units`` (default m/s2;
    repr precision: reading it back gives the same numbers). ``write_csv(path, record)`` writes a `Record`."""
    t, ag, units = _samples("write_csv", t, ag, units)
    units = "m/s2" if units is None else units
    values = ag / unit_factor(units)
    path = Path(path)
    with open(path, "w") as f:
        f.write(f"time [s],ag [{units}]\n")
        for ti, ai in zip(t.tolist(), values.tolist()):
            f.write(f"{ti!r},{ai!r}\n")
    return path


def read_record(path, units: str | None = None, name: str | None = None,
                default_units: str | None = None) -> Record:
    """Read ``path`` by its extension: .AT2 (PEER; units from its line 3, else g) or .csv/.txt/.dat/.tsv
    (two columns, `read_csv`; ``default_units`` applies to these only)."""
    suffix = Path(path).suffix.lower()
    if suffix == ".at2":
        return read_at2(path, units, name)
    if suffix in (".csv", ".txt", ".dat", ".tsv"):
        return read_csv(path, units, name, default_units)
    raise ValueError(f"{path}: unknown record format {suffix!r}; allowed: .AT2 (PEER), .csv/.txt/.dat/.tsv")


# --------------------------------------------------------------------------------------------- synthetic
def synthetic_record(duration: float = 30.0, dt: float = 0.01, pga_g: float = 0.4, seed: int = 2017,
                     f_g: float = 2.5, zeta_g: float = 0.6, f_f: float = 0.25, zeta_f: float = 0.6,
                     t_rise: float = 2.0, t_strong: float = 12.0, decay: float = 0.35):
    """Synthetic accelerogram (t [s], ag [m/s2]): Gaussian white noise (fixed seed) through a
    Clough-Penzien filter (Kanai-Tajimi ground filter f_g, zeta_g followed by a second-order high-pass
    f_f, zeta_f that removes the low-frequency drift), times a Saragoni-Hart-like envelope (quadratic rise
    to t_rise, strong phase to t_strong, exponential decay), scaled to the peak ground acceleration
    pga_g [g] (here g = 9.81 m/s2, as in the benchmark scenes)."""
    from scipy import signal

    G = 9.81        # kept (not G_N) so that the benchmark scenes' numbers do not change
    rng = np.random.default_rng(seed)
    n = int(round(duration / dt)) + 1
    t = np.arange(n) * dt
    w = rng.standard_normal(n)
    wg, wf = 2 * math.pi * f_g, 2 * math.pi * f_f
    num = np.polymul([2 * zeta_g * wg, wg ** 2], [1.0, 0.0, 0.0])
    den = np.polymul([1.0, 2 * zeta_g * wg, wg ** 2], [1.0, 2 * zeta_f * wf, wf ** 2])
    _, a, _ = signal.lsim((num, den), w, t)
    env = np.where(t < t_rise, (t / t_rise) ** 2,
                   np.where(t < t_strong, 1.0, np.exp(-decay * (t - t_strong))))
    a = a * env
    a *= pga_g * G / np.max(np.abs(a))
    a[0] = 0.0
    return t, a


def synthetic_motion(seed: int = 2017, **kwargs) -> Record:
    """`synthetic_record` as a `Record` named ``synthetic:<seed>``."""
    t, a = synthetic_record(seed=seed, **kwargs)
    return Record(t, a, f"synthetic:{seed}")


def load_motion(spec: str, units: str | None = None, default_units: str | None = None) -> Record:
    """A record from a CLI/ensemble/FMU spec: a file path (.AT2, .csv, read by `read_record`) or
    ``synthetic[:seed]``."""
    s = str(spec)
    if s == "synthetic" or s.startswith("synthetic:"):
        seed = s.partition(":")[2] or "2017"
        try:
            return synthetic_motion(int(seed))
        except ValueError:
            raise ValueError(f"record {s!r}: the seed must be an integer (synthetic:2017)") from None
    if not Path(s).exists():
        raise FileNotFoundError(f"record {s!r}: no such file")
    return read_record(s, units, default_units=default_units)
