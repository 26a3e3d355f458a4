"""Ground-motion records: readers for PEER NGA ``.AT2`` files and two- or three-column CSV files, writers for
both, unit conversion, and a fixed-seed synthetic accelerogram.

Every reader returns a `Record`: a `SampledMotion` (t [s], ag [m/s2], linear between samples, zero outside
the record, breakpoints at the samples) that also carries its name, source file and the header lines, and
optionally a vertical component ``vertical`` (ag_v [m/s2], positive upward, on the same times; None when
the record has none): the third column of a CSV file, or a second file (``vertical=``: PEER stores one
component per AT2 file). A malformed file raises ValueError naming the file and the line; a missing one
FileNotFoundError.

Two components read from two files are aligned by `combine`: they must start together and share their time
step (AT2: the same DT; CSV: the same sample times), else ValueError naming the vertical file. When one file
is longer, the shorter component is padded with zeros up to the longer one's end (a record is zero after its
end anyway; the padding only moves its end, so a zero is what the integrators read there).

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


#: [1, relative to the time step] two components' time steps (AT2 DT, CSV sample times) agree when they
#: differ by at most this fraction of the step: AT2 headers print DT with few digits (.0050 vs 0.005), CSV
#: times carry the decimal round-off of the program that wrote them
DT_RTOL = 1e-6


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
    (True when the file did not state them and no units were given: a reader's default was used).

    ``vertical``: the vertical component ag_v [m/s2] (positive upward) on the same times t, a `Record` (with
    its own name, source and units) or None when the record has none; give it as a Record or SampledMotion
    on the times t, or as an array of ag_v. A record with a vertical component is a two-component ground
    motion: calling it gives the horizontal ag(t), ``horizontal`` is the horizontal component alone and the
    simulators read ``vertical`` (breakpoints, support and continuity are the shared samples'); ``scaled`` and
    ``resampled`` act on both components (`combine` pairs two records read from separate files)."""

    def __init__(self, t, ag, name: str = "record", source: str | None = None, header=(),
                 units: str | None = None, units_assumed: bool = False, vertical=None):
        super().__init__(t, ag)
        self.name = str(name)
        self.source = source
        self.header = list(header)
        self.units = units
        self.units_assumed = bool(units_assumed)
        if vertical is not None:
            if isinstance(vertical, SampledMotion):
                if not np.array_equal(vertical.t, self.t):
                    raise ValueError("vertical: the vertical component must be sampled at the record's times t "
                                     "(records.combine aligns two records)")
                if not isinstance(vertical, Record):
                    vertical = Record(self.t, vertical.ag, f"{self.name} (vertical)")
                elif vertical.vertical is not None:
                    raise ValueError("vertical: the vertical component must have one component")
            else:
                vertical = Record(self.t, vertical, f"{self.name} (vertical)", source, header, units,
                                  units_assumed)
        #: the vertical component ag_v [m/s2] (a Record on the times t), or None
        self.vertical = vertical

    @property
    def ag_v(self):
        """The vertical samples ag_v [m/s2] (positive upward), or None when the record has none."""
        return None if self.vertical is None else self.vertical.ag

    @property
    def horizontal(self) -> "Record":
        """The horizontal component alone (the record itself when it has no vertical component)."""
        if self.vertical is None:
            return self
        if getattr(self, "_horizontal", None) is None:
            self._horizontal = Record(self.t, self.ag, self.name, self.source, self.header, self.units,
                                      self.units_assumed)
        return self._horizontal

    @property
    def pga_v(self) -> float:
        """Peak |ag_v| over the samples [m/s2] (0 without a vertical component)."""
        return 0.0 if self.vertical is None else self.vertical.pga

    def _like(self, t, ag, name: str, ag_v=None) -> "Record":
        v = None
        if ag_v is not None:
            w = self.vertical
            v = Record(t, ag_v, w.name, w.source, w.header, w.units, w.units_assumed)
        return Record(t, ag, name, self.source, self.header, self.units, self.units_assumed, v)

    def scaled(self, factor: float) -> "Record":
        """Both components times ``factor`` [1]."""
        factor = check_real("factor", factor)
        return self._like(self.t, factor * self.ag, f"{self.name} x {factor:g}",
                          None if self.vertical is None else factor * self.vertical.ag)

    def scaled_vertical(self, factor: float) -> "Record":
        """The vertical component times ``factor`` [1], the horizontal unchanged (ValueError naming
        vertical_scale when the record has no vertical component)."""
        factor = check_real("vertical_scale", factor)
        if self.vertical is None:
            raise ValueError(f"vertical_scale: the record {self.name!r} has no vertical component to scale")
        return self._like(self.t, self.ag, self.name, factor * self.vertical.ag)

    def resampled(self, dt: float, t_start: float | None = None, t_end: float | None = None) -> "Record":
        """Both components sampled every ``dt`` [s] (linear, no anti-alias filter)."""
        r = SampledMotion(self.t, self.ag).resampled(dt, t_start, t_end)
        v = None if self.vertical is None else \
            SampledMotion(self.t, self.vertical.ag).resampled(dt, t_start, t_end).ag
        return self._like(r.t, r.ag, f"{self.name} @ {dt:g} s", v)

    def with_vertical(self, vertical, name: str | None = None):
        """This record with the vertical component ``vertical``: a Record or SampledMotion (aligned by
        `combine`), or an array of ag_v [m/s2] on the times t. Other motions (callables, pulses) give what
        `GroundMotion.with_vertical` gives, where the ground motions have it."""
        if isinstance(vertical, SampledMotion):
            if not isinstance(vertical, Record):
                vertical = Record(vertical.t, vertical.ag, name or f"{self.name} (vertical)")
            return combine(self, vertical)
        if isinstance(vertical, (np.ndarray, list, tuple)):
            return Record(self.t, self.ag, self.name, self.source, self.header, self.units, self.units_assumed,
                          np.asarray(vertical, dtype=float))
        parent = getattr(super(), "with_vertical", None)
        if parent is None:
            raise ValueError("vertical: give a Record, a SampledMotion or an array of ag_v [m/s2]")
        return parent(vertical)

    def __repr__(self) -> str:
        v = "" if self.vertical is None else f", PGA_v = {self.pga_v / G_N:.3g} g"
        return (f"Record({self.name!r}, {self.t.size} samples, dt = {self.dt:g} s, "
                f"PGA = {self.pga / G_N:.3g} g{v})")


def _where(rec) -> str:
    return str(rec.source) if getattr(rec, "source", None) else repr(rec.name)


def _uniform_step(t) -> float | None:
    """The step [s] of uniformly sampled times t, or None when they are not uniform."""
    dt = (t[-1] - t[0]) / (t.size - 1)
    return float(dt) if np.allclose(np.diff(t), dt, rtol=DT_RTOL, atol=0.0) else None


def combine(horizontal: Record, vertical: Record) -> Record:
    """One two-component Record of a horizontal and a vertical single-component record (read from two
    files, e.g. PEER's two AT2 files of one station).

    They must start at the same time and share their time step: uniformly sampled records (AT2 files) the
    same DT, others the same sample times, each within `DT_RTOL` of the step; else ValueError naming the
    vertical file and both steps. Of unequal lengths, the shorter is padded with zeros to the longer one's
    end. The result keeps the horizontal record's times, name, source and units; its ``vertical`` keeps the
    vertical file's."""
    h, v = horizontal, vertical
    if h.vertical is not None:
        raise ValueError(f"{_where(h)}: the record already has a vertical component (a third column); give "
                         "either a three-column file or a second file for the vertical component, not both")
    if v.vertical is not None:
        raise ValueError(f"{_where(v)}: the vertical record has two components; give a file with one "
                         "component (time [s], ag_v) for the vertical")
    th, tv = h.t, v.t
    dh, dv = _uniform_step(th), _uniform_step(tv)
    step = min(np.min(np.diff(th)), np.min(np.diff(tv)))
    if dh is not None and dv is not None:
        if abs(dh - dv) > DT_RTOL * dh:
            raise ValueError(f"{_where(v)}: DT = {dv:.9g} s, but the horizontal component ({_where(h)}) has "
                             f"DT = {dh:.9g} s; the two components must share one time step (resample one: "
                             "Record.resampled)")
    if abs(th[0] - tv[0]) > DT_RTOL * step:
        raise ValueError(f"{_where(v)}: starts at t = {tv[0]:.9g} s, but the horizontal component "
                         f"({_where(h)}) at t = {th[0]:.9g} s; the two components must start together")
    n = min(th.size, tv.size)
    if dh is None or dv is None:
        off = np.nonzero(np.abs(th[:n] - tv[:n]) > DT_RTOL * step)[0]
        if off.size:
            k = int(off[0])
            raise ValueError(f"{_where(v)}: sample {k + 1} is at t = {tv[k]:.9g} s, but the horizontal "
                             f"component ({_where(h)}) has t = {th[k]:.9g} s there; the two components must "
                             "share their time step (their sample times)")
    if th.size >= tv.size:
        t = th
    elif dh is not None and dv is not None:
        t = np.concatenate([th, th[0] + np.arange(th.size, tv.size) * dh])
    else:
        t = np.concatenate([th, tv[th.size:]])
    ag = np.concatenate([h.ag, np.zeros(t.size - th.size)])
    ag_v = np.concatenate([v.ag, np.zeros(t.size - tv.size)])
    vrec = Record(t, ag_v, v.name, v.source, v.header, v.units, v.units_assumed)
    return Record(t, ag, h.name, h.source, h.header, h.units, h.units_assumed, vrec)


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


def read_at2(path, units: str | None = None, name: str | None = None, vertical=None) -> Record:
    """Read a PEER NGA ``.AT2`` acceleration file into a `Record` (t [s] from 0, ag [m/s2]).

    Layout: 3 header lines (title, event, "ACCELERATION TIME SERIES IN UNITS OF G"), a 4th line with the
    number of points and the time step, either NGA-West2 style ``NPTS=  5590, DT=   .0050 SEC`` or the older
    ``  5590    0.0050    NPTS, DT``, then the samples, several per line. ``units`` overrides the units
    stated on line 3 (g if none is stated). Raises ValueError naming the file and line when the file is
    malformed (missing NPTS/DT, a non-number, fewer samples than NPTS, DT <= 0).

    ``vertical``: a second AT2 file, the vertical component ag_v of the same station (positive upward; read
    in the same way, ``units`` applying to both), joined by `combine` (same DT, the shorter padded with
    zeros; a different DT is refused naming that file)."""
    if vertical is not None:
        return combine(read_at2(path, units, name), read_at2(vertical, units))
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


def _samples(writer: str, t, ag, units, ag_v=None):
    """(t, ag, units, ag_v) from a writer's arguments: ``t`` and ``ag`` (and optionally ``ag_v``) arrays [s],
    [m/s2], or ``t`` a `Record` / `SampledMotion` (what the readers return; its vertical component, if any,
    is ag_v) with ``ag`` omitted, or given as the units (positional)."""
    if hasattr(t, "t") and hasattr(t, "ag"):
        if isinstance(ag, str) and units is None:
            ag, units = None, ag
        if ag is not None or ag_v is not None:
            raise ValueError(f"{writer}: give a record, or the arrays t and ag (and ag_v), not both")
        v = getattr(t, "vertical", None)
        ag_v = None if v is None else np.asarray(v.ag, dtype=float)
        return np.asarray(t.t, dtype=float), np.asarray(t.ag, dtype=float), units, ag_v
    if ag is None:
        raise ValueError(f"{writer}: ag is missing (give a record, or the arrays t and ag)")
    t, ag = np.asarray(t, dtype=float), np.asarray(ag, dtype=float)
    if ag_v is not None:
        ag_v = np.asarray(ag_v, dtype=float)
        if ag_v.shape != ag.shape:
            raise ValueError(f"{writer}: ag_v must have the shape of ag {ag.shape}, got {ag_v.shape}")
    return t, ag, units, ag_v


def write_at2(path, t, ag=None, units: str | None = None, title: str | None = None,
              event: str = "synthetic", digits: int = 17, vertical=None, ag_v=None) -> Path:
    """Write samples ag [m/s2] at uniform times t [s] (t[0] = 0) as a PEER AT2 file in ``units`` (default g):
    NGA-West2 header, 5 values a line in E format with ``digits`` significant digits (17 round-trips the
    values; PEER files use 7). ``write_at2(path, record)`` writes a `Record` (or any `SampledMotion`) as the
    readers return it; its name is the title line unless ``title`` is given.

    An AT2 file holds one component: a record with a vertical component (or ``ag_v`` given with the arrays)
    needs ``vertical``, the path of the second file, written in the same units and format (its title the
    vertical component's name). Returns the path of the (horizontal) file."""
    name = getattr(t, "name", None)
    vname = getattr(getattr(t, "vertical", None), "name", None)
    t, ag, units, ag_v = _samples("write_at2", t, ag, units, ag_v)
    if (ag_v is None) != (vertical is None):
        raise ValueError("write_at2: a vertical component needs vertical=<second AT2 file> (an AT2 file holds "
                         "one component)" if vertical is None else
                         f"write_at2: vertical = {str(vertical)!r} given, but there is no vertical component")
    if vertical is not None:
        write_at2(vertical, t, ag_v, units, title=vname or f"{title or name or 'rocking_model record'} (vertical)",
                  event=event, digits=digits)
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
             default_units: str | None = None, vertical=None) -> Record:
    """Read a two-column text file (time [s], acceleration) into a `Record` (ag converted to m/s2); a third
    column is the vertical acceleration ag_v (positive upward, in the same units: ``time [s],ag [g],ag_v
    [g]``), the record's ``vertical`` component.

    Separators: comma, semicolon, tab or spaces. Lines starting with '#' are comments. An optional first
    non-comment line is a header; the acceleration units are taken from it (``time [s], ag [g]`` or
    ``t (s), acc (cm/s2)``) or from a comment ``# units: g``, else from ``units``, else from
    ``default_units``. Units neither stated nor given (and no ``default_units``), or stated and given
    differently, are an error (a third column that states other units than the second, too). Times must be
    strictly increasing, every row has the columns of the first. ``vertical``: a second (two-column) file
    holding the vertical component, joined by `combine`. Raises ValueError naming the file and line of the
    first problem."""
    if vertical is not None:
        return combine(read_csv(path, units, name, default_units), read_record(vertical, units,
                                                                              default_units=default_units))
    path = Path(path)
    try:
        lines = path.read_text(errors="replace").splitlines()
    except OSError as exc:       # FileNotFoundError, PermissionError, IsADirectoryError: kept, with the path
        raise type(exc)(f"{path}: cannot read the record ({exc.strerror or exc})") from None
    stated = None
    t, a, av = [], [], []
    header_seen = False
    ncols = None
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
                third = _UNIT_IN_HEADER.findall(cells[2]) if len(cells) > 2 else []
                if third and (not found or unit_factor(third[-1]) != unit_factor(found[-1])):
                    raise ValueError(f"{path}, line {j}: the third column (ag_v) states units {third[-1]!r}, "
                                     f"the second (ag) {found[-1] if found else 'none'!r}; both components "
                                     "must be in the same units")
                continue
            bad = next(c for c in cells if not _is_float(c))
            raise ValueError(f"{path}, line {j}: {bad!r} is not a number") from None
        if ncols is None and len(row) in (2, 3):
            ncols = len(row)
        if len(row) != ncols:
            raise ValueError(f"{path}, line {j}: {len(row)} columns, expected " +
                             (f"{ncols} (as the rows before it)" if ncols else
                              "2 (time [s], acceleration) or 3 (time [s], ag, vertical ag_v)"))
        if not all(map(math.isfinite, row)):
            raise ValueError(f"{path}, line {j}: values must be finite, got {line!r}")
        if t and row[0] <= t[-1]:
            raise ValueError(f"{path}, line {j}: time {row[0]:g} s is not after the previous {t[-1]:g} s; "
                             "times must be strictly increasing")
        t.append(row[0])
        a.append(row[1])
        if ncols == 3:
            av.append(row[2])
    if len(t) < 2:
        raise ValueError(f"{path}: {len(t)} data rows, expected at least 2 (time [s], acceleration)")
    if units is None and stated is None and default_units is not None:
        factor = unit_factor(default_units)
        return Record(np.array(t), np.array(a) * factor, name or path.stem, str(path), [], default_units, True,
                      np.array(av) * factor if av else None)
    if units is None and stated is None:
        raise ValueError(f"{path}: acceleration units are not stated (header 'time [s], ag [g]' or "
                         f"'# units: g'); give them (units=..., CLI --units); allowed values: "
                         + ", ".join(UNITS))
    if units is not None and stated is not None and unit_factor(units) != unit_factor(stated):
        raise ValueError(f"{path}: the file states units {stated!r}, but units = {units!r} was given")
    used = units if units is not None else stated
    factor = unit_factor(used)
    return Record(np.array(t), np.array(a) * factor, name or path.stem, str(path), [], used, False,
                  np.array(av) * factor if av else None)


def _is_float(s: str) -> bool:
    try:
        float(s)
        return True
    except ValueError:
        return False


def write_csv(path, t, ag=None, units: str | None = None, ag_v=None) -> Path:
    """Write t [s] and ag [m/s2] as ``time [s],ag [<units>]`` CSV, ag converted to ``units`` (default m/s2;
    repr precision: reading it back gives the same numbers). ``write_csv(path, record)`` writes a `Record`.
    A vertical component (the record's, or ``ag_v`` [m/s2] with the arrays) is a third column
    ``ag_v [<units>]``."""
    t, ag, units, ag_v = _samples("write_csv", t, ag, units, ag_v)
    units = "m/s2" if units is None else units
    values = ag / unit_factor(units)
    path = Path(path)
    with open(path, "w") as f:
        if ag_v is None:
            f.write(f"time [s],ag [{units}]\n")
            for ti, ai in zip(t.tolist(), values.tolist()):
                f.write(f"{ti!r},{ai!r}\n")
        else:
            f.write(f"time [s],ag [{units}],ag_v [{units}]\n")
            for ti, ai, vi in zip(t.tolist(), values.tolist(), (ag_v / unit_factor(units)).tolist()):
                f.write(f"{ti!r},{ai!r},{vi!r}\n")
    return path


def read_record(path, units: str | None = None, name: str | None = None,
                default_units: str | None = None, vertical=None) -> Record:
    """Read ``path`` by its extension: .AT2 (PEER; units from its line 3, else g) or .csv/.txt/.dat/.tsv
    (two columns, or three with the vertical ag_v, `read_csv`; ``default_units`` applies to these only).
    ``vertical``: a second file (either format, one component) holding the vertical component, joined by
    `combine`."""
    if vertical is not None:
        return combine(read_record(path, units, name, default_units),
                       read_record(vertical, units, default_units=default_units))
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


def load_motion(spec: str, units: str | None = None, default_units: str | None = None,
                vertical: str | None = None) -> Record:
    """A record from a CLI/ensemble/FMU spec: a file path (.AT2, .csv, read by `read_record`) or
    ``synthetic[:seed]``. ``vertical``: a second spec (file or synthetic[:seed]) for the vertical component,
    joined by `combine` (None or "": none beyond a third CSV column)."""
    if vertical:
        h = load_motion(spec, units, default_units)
        v = load_motion(vertical, units, default_units)
        if v.vertical is not None:
            raise ValueError(f"vertical = {str(vertical)!r}: the vertical record has two components; give a "
                             "file with one component (time [s], ag_v)")
        return combine(h, v)
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
