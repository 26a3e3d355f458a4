"""The ``rocking`` command line.

    rocking simulate --model rigid --b 0.2 --h 1.0 --pulse sine --amplitude 3 --frequency 2 --out results/
        (writes results/rigid_b0.2_h1_sine-A3ms2-f2Hz.csv and .png; --name to choose, --force to overwrite)
    rocking simulate --record RSN6_IMPVALL.I_I-ELC180.AT2 --scale 1.5 --scheme moreau_jean
    rocking simulate --record H.AT2 --vertical UP.AT2 --vertical-scale 1.2   (vertical ag_v, positive upward)
    rocking ensemble --pulse sine --amplitude-ratios 1:6:11 --frequency-ratios 1:10:10 --workers 2
    rocking build-fmu [--dest dist]          (needs a C compiler and the Python headers)
    rocking benchmark [--quick] [--ensemble] (source checkout only)
    rocking im RECORD --periods 0.5 1 2 [--b 0.2 --h 1.0]   (a record's intensity measures)
    rocking fragility --records records/ --im "Sa(1)" --stripes 0.5:5:10 --out results/fragility
    rocking fragility --records synthetic:1 synthetic:2 --im "PGA/(g tan alpha)" --ida 0.8 --workers 0

Only argument handling and reporting live here; the physics is in `rocking_model.simulation`. Bad input
prints one line ``rocking <command>: error: ...`` and exits with status 2 (never a traceback).
"""
from __future__ import annotations

import argparse
import math
import subprocess
import os
import sys
import time
import warnings
from pathlib import Path

import numpy as np

from . import __version__
from .ensemble import AG_V_SCALE_MAX as VERTICAL_SCALE_MAX   # [1] range of --vertical-scale(s): ag_v_scale's
from .ground_motion import PULSES

ROOT = Path(__file__).resolve().parent.parent
#: CSV header units of the simulator's own outputs (the model's come from its declarations, `OUTPUTS`)
UNITS_OF = {"friction_demand": "1", "contact": "mode code: 0 full/1 left/2 right/3 flight/4-9 sliding/10 overturned"}


class UsageError(ValueError):
    """Bad command-line input (exit status 2)."""


# --------------------------------------------------------------------------------------------- helpers
def _values(text: str) -> list[float]:
    """A number, or start:stop:num (num evenly spaced values, both ends included)."""
    try:
        if ":" in text:
            a, b, n = text.split(":")
            n = int(n)
            if n < 1:
                raise ValueError
            return list(np.linspace(float(a), float(b), n))
        return [float(text)]
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number or start:stop:num") from None


def _count(lo: int):
    """argparse type: an integer >= lo, refused at parse time (before any cluster starts)."""
    def parse(text: str) -> int:
        try:
            n = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not an integer") from None
        if n < lo:
            raise argparse.ArgumentTypeError(f"{n} is out of range; allowed range [{lo}, inf)")
        return n
    return parse


def _positive(text: str) -> float:
    """argparse type: a real number > 0."""
    try:
        x = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not x > 0:
        raise argparse.ArgumentTypeError(f"{text} is out of range; allowed range (0, inf]")
    return x


def _flat(lists) -> list[float] | None:
    return None if lists is None else [float(x) for sub in lists for x in sub]


def _repo_root() -> Path:
    if not ((ROOT / "build_fmu.py").is_file() and (ROOT / "benchmarks").is_dir()):
        raise UsageError(f"this command needs a source checkout of rocking-model (build_fmu.py and "
                         f"benchmarks/ next to the package); {ROOT} has none")
    return ROOT


def _declared() -> dict:
    """{name: {kind: Param}} of the parameters of the registered models."""
    from .models import MODELS

    out: dict = {}
    for k, cls in MODELS.items():
        for p in cls.parameters():
            out.setdefault(p.name, {})[k] = p
    return out


def _declared_initial() -> dict:
    """{name: {kind: Param}} of the initial values of the registered models."""
    from .models import MODELS

    out: dict = {}
    for k, cls in MODELS.items():
        for p in cls.INITIAL:
            out.setdefault(p.name, {})[k] = p
    return out


def _help(per_kind: dict, n_models: int) -> str:
    """Help text of an option declared by the models in ``per_kind`` ({kind: Param})."""
    def one(p):
        if p.items:
            return f"{p.description}: " + ", ".join(f"{code} or {item} ({d})" for item, code, d in p.items)
        unit = f" [{p.unit}]" if p.unit else ""
        return f"{p.description}{unit}, default {p.default:g}"
    texts = {k: one(p) for k, p in per_kind.items()}
    if len(set(texts.values())) == 1:
        (text,) = set(texts.values())
        return text if len(per_kind) == n_models else f"{', '.join(per_kind)}: {text}"
    kinds: dict = {}                      # text -> the models that declare it so, in registry order
    for k, t in texts.items():
        kinds.setdefault(t, []).append(k)
    return "; ".join(f"{', '.join(ks)}: {t}" for t, ks in kinds.items())


def _given_parameters(args, skip=()) -> dict:
    """The model parameters given on the command line ({name: value}), checked to be the model's (UsageError
    naming an option that belongs to another model and the model's own)."""
    from .models import model_class

    cls = model_class(args.model)
    allowed = [p.name for p in cls.parameters() if p.name not in skip]
    given = {k: getattr(args, k) for k in _declared() if k not in skip and getattr(args, k, None) is not None}
    extra = sorted(set(given) - set(allowed))
    if extra:
        raise UsageError(f"--{extra[0].replace('_', '-')} is not a parameter of the {args.model} model; "
                         f"allowed: " + ", ".join("--" + k.replace("_", "-") for k in allowed))
    return given


def _model(args):
    from .models import model_class

    return model_class(args.model)(**_given_parameters(args))


def _is_block(kind: str) -> bool:
    """A rigid block of half-width b and half-height h (`rocking_model.ensemble.is_rigid_block`)."""
    from .ensemble import is_rigid_block

    return is_rigid_block(kind)


def _describe(model, args) -> str:
    """One line naming the model: its title, b and h, the other parameters given on the command line (with
    their units) and, for a rigid block, its slenderness, frequency parameter and uplift acceleration."""
    units = {p.name: p.unit for p in type(model).parameters()}
    shown = ["b", "h"] + [k for k in _declared() if k not in ("b", "h") and getattr(args, k, None) is not None]
    if not _is_block(args.model) and "EI" in units and "EI" not in shown:
        shown.append("EI")
    parts = []
    for k in shown:
        value = getattr(model, k)
        unit = units.get(k, "")
        parts.append(f"{k} = {value:g}" + (f" {unit}" if unit and unit != "1" else "") if isinstance(value, (int, float))
                     else f"{k} = {value}")
    text = f"{type(model).title} " + ", ".join(parts)
    if _is_block(args.model):
        text += (f" (alpha = {model.alpha:.4f} rad, p = {model.p:.3f} rad/s, g tan(alpha) = "
                 f"{model.g * math.tan(model.alpha):.3f} m/s2")
        P0 = getattr(model, "P0", 0.0)
        if P0:                 # the tendon's pre-stress raises the uplift acceleration (models/post_tensioned.py)
            text += f", uplift at tan(alpha) (g + P0/m) = {math.tan(model.alpha) * (model.g + P0 / model.m):.3f} m/s2"
        text += ")"
    return text


def scene_name(args) -> str:
    """The default file stem of `rocking simulate`: the model, the parameters and initial values given, the
    motion and a scheme other than the default, e.g. ``rigid_b0.3_h1.2_sine-A3ms2-f2Hz`` or
    ``post_tensioned_b0.3_h1.5_m1000_P0-20000_k_t2e+06_sine-A10ms2-f1Hz`` (the same scene
    gives the same name; a second run of it is refused without --force)."""
    parts = [args.model]
    for name in list(_declared()) + list(_declared_initial()):
        value = getattr(args, name, None)
        if value is not None:
            # a name ending in a digit (P0, phi_0) takes a dash before its value: P0-20000, not P020000
            sep = "-" if name[-1].isdigit() else ""
            parts.append(f"{name}{sep}{value:g}" if isinstance(value, (int, float)) else f"{name}-{value}")
    if args.record:
        rec = str(args.record)
        parts.append(rec.replace(":", "-") if rec.startswith("synthetic") else Path(rec).stem)
        if args.vertical:
            ver = str(args.vertical)
            parts.append("V-" + (ver.replace(":", "-") if ver.startswith("synthetic") else Path(ver).stem))
    elif args.pulse:
        unit = (args.amplitude_units or "").replace("/", "").replace("2", "2")
        motion = f"{args.pulse}-A{args.amplitude:g}{unit}" if args.amplitude is not None else args.pulse
        if args.frequency is not None:
            motion += f"-f{args.frequency:g}Hz"
        if args.duration is not None:
            motion += f"-T{args.duration:g}s"
        if args.t0 is not None:
            motion += f"-t{args.t0:g}s"
        parts.append(motion)
    else:
        parts.append("free")
    if args.scale != 1.0:
        parts.append(f"x{args.scale:g}")
    if args.vertical_scale is not None:
        parts.append(f"vx{args.vertical_scale:g}")
    if args.resample:
        parts.append(f"dt{args.resample:g}")
    if args.scheme != "event_driven":
        parts.append(args.scheme)
    text = "_".join(parts)
    return "".join(c if c.isalnum() or c in "._-+" else "_" for c in text)


def _vertical_scale(args) -> float | None:
    """--vertical-scale checked: None when not given."""
    from .validation import check_real

    if args.vertical_scale is None:
        return None
    return check_real("--vertical-scale", args.vertical_scale, lo=-VERTICAL_SCALE_MAX, hi=VERTICAL_SCALE_MAX)


def _motion(args):
    """(GroundMotion, description, default t_end [s]). The vertical component ag_v: the record's (a third CSV
    column, or --vertical FILE) times --vertical-scale (default 1), or, for a record without one and for a
    pulse, --vertical-scale times the horizontal motion (default 0: none)."""
    from . import ground_motion as gm
    from .records import load_motion, unit_factor
    from .validation import check_real

    if args.record and args.pulse:
        raise UsageError("give either --record or --pulse, not both")
    vs = _vertical_scale(args)
    if args.vertical and not args.record:
        raise UsageError("--vertical (the vertical component of a record) needs --record; a pulse takes "
                         "--vertical-scale (ag_v = scale x the pulse)")
    if args.record:
        rec = load_motion(args.record, args.units, vertical=args.vertical)
        if args.resample:
            rec = rec.resampled(args.resample)
        if args.scale != 1.0:
            rec = rec.scaled(args.scale)
        if vs is not None:
            if vs == 0.0:
                rec = rec.horizontal             # no vertical component: the horizontal run, bit for bit
            elif rec.vertical is not None:
                rec = rec.scaled_vertical(vs)
            else:
                rec = rec.with_vertical(vs * rec.ag)
        desc = f"record {rec.name}: {rec.t.size} samples, dt = {rec.dt:g} s, PGA = {rec.pga:.3g} m/s2"
        if rec.vertical is not None:
            desc += f", vertical {rec.vertical.name}: PGA_v = {rec.pga_v:.3g} m/s2"
        return rec, desc, float(rec.t[-1]) + 5.0
    if not args.pulse:
        if args.scale != 1.0 or args.resample or vs is not None:
            raise UsageError("--scale, --resample and --vertical-scale apply to a --record or --pulse")
        return gm.ConstantMotion(0.0), "no ground motion", 5.0
    if args.amplitude is None:
        raise UsageError("--pulse needs --amplitude (in --amplitude-units, default m/s2)")
    A = args.amplitude * unit_factor(args.amplitude_units)
    if args.pulse == "rectangular":
        if args.duration is None:
            raise UsageError("--pulse rectangular needs --duration [s]")
        m = gm.pulse_from_parameters("rectangular", A, t_start=args.t0, duration=args.duration, scale=args.scale)
        desc = f"rectangular pulse A = {m.A:.4g} m/s2, duration {args.duration:g} s"
    else:
        if args.frequency is None:
            raise UsageError(f"--pulse {args.pulse} needs --frequency [Hz]")
        w = 2.0 * math.pi * check_real("--frequency", args.frequency, lo=0.0, lo_open=True)
        m = gm.pulse_from_parameters(args.pulse, A, w, args.t0, scale=args.scale)
        desc = f"{args.pulse} pulse A = {m.A:.4g} m/s2, f_p = {args.frequency:g} Hz"
    if args.resample:
        m = m.resampled(args.resample)
    end = m.support[1] + 5.0
    if vs:
        m = gm.TwoComponentMotion(m, m.scaled(vs))
        desc += f", vertical {vs:g} x the pulse"
    return m, desc, end


# --------------------------------------------------------------------------------------------- commands
def cmd_simulate(args) -> int:
    from .simulation import simulate

    model = _model(args)
    motion, desc, t_default = _motion(args)
    t_end = args.t_end if args.t_end is not None else t_default
    kw = {"tolerance": args.tolerance}         # (the Moreau-Jean scheme has no tolerance: it ignores it)
    if args.dt_max is not None:
        kw["dt_max"] = args.dt_max
    own = {p.name for p in type(model).INITIAL}
    for k in _declared_initial():
        if getattr(args, k) is not None:
            if k not in own:
                raise UsageError(f"--{k.replace('_', '-')} is not an initial value of the {args.model} model; "
                                 "allowed: " + ", ".join("--" + n.replace("_", "-") for n in sorted(own)))
            kw[k] = getattr(args, k)
    t0 = time.perf_counter()
    res = simulate(model, motion, t_end, scheme=args.scheme, output_interval=args.output_interval, **kw)
    wall = time.perf_counter() - t0

    out = Path(args.out)
    name = args.name or scene_name(args)
    targets = [out / f"{name}.csv"] + ([] if args.no_plot else [out / f"{name}.png"])
    existing = [str(t) for t in targets if t.exists()]
    if existing and not args.force:
        raise UsageError(f"{' and '.join(existing)} already exist(s): give --force to overwrite, or --name for "
                         "another name (nothing was written)")
    out.mkdir(parents=True, exist_ok=True)
    csv_path = targets[0]
    names = list(res.values)
    ag = np.array([motion(float(t)) for t in res.t])
    cols = [res.t, ag]
    header = ["time [s]", "ag [m/s2]"]
    if motion.vertical is not None:             # the vertical ground acceleration, positive upward
        cols.append(np.array([motion.vertical(float(t)) for t in res.t]))
        header.append("ag_v [m/s2]")
    cols += [np.asarray(res.values[n], dtype=float) for n in names]
    units = {**{p.name: p.unit for p in model.OUTPUTS}, **UNITS_OF}
    header += [f"{n} [{units[n]}]" if n in units else n for n in names]
    np.savetxt(csv_path, np.column_stack(cols), delimiter=",", header=",".join(header), comments="", fmt="%.10g")

    rigid = _is_block(args.model)
    alpha = model.alpha if rigid else None
    geo = _describe(model, args)
    phi = np.abs(res.phi)
    k = int(np.argmax(phi))
    over = np.asarray(res.overturned, dtype=bool)
    print(f"{geo}\n{desc}; scheme {res.scheme}, t_end = {t_end:g} s")
    ratio = f" ({phi[k] / alpha:.3f} alpha)" if rigid else ""
    print(f"  max |phi|  = {phi[k]:.5g} rad{ratio} at t = {res.t[k]:.3f} s")
    print(f"  impacts    = {int(res.impacts[-1])}")
    print(f"  overturned = " + (f"yes, at t = {res.t[int(np.argmax(over))]:.3f} s" if over[-1] else "no"))
    slip = np.asarray(res.slip)
    print(f"  slip       = {slip[-1]:.4g} m at the end, max |slip| = {np.max(np.abs(slip)):.4g} m "
          f"(mu = {model.mu:g})")
    print(f"  friction demand = {res.friction_demand[-1]:.4g} (the largest |lambda_T|/lambda_N needed"
          + (f"; above mu = {model.mu:g} the corners slid" if math.isfinite(model.mu) else
             "; a surface with a smaller mu would slide") + ")"
          + (f", Painleve situations: {int(res.painleve[-1])}" if res.painleve[-1] else ""))
    # the model's own outputs beyond a rigid body's (top_displacement, tendon_force, ...): their largest value
    from .models import RigidBlock
    body = {p.name for p in RigidBlock.OUTPUTS} | {"u", "u_dot"}
    for p in model.OUTPUTS:
        if p.name not in body and p.name in res.values:
            label = p.name.replace("_", " ")
            print(f"  max |{label}| = {np.max(np.abs(np.asarray(res.values[p.name], dtype=float))):.4g} {p.unit}")
    print(f"  wall time  = {wall:.3f} s ({res.n_steps} steps)")
    written = [csv_path]
    if not args.no_plot:
        from .plotting import plot_response
        title = f"{geo}\n{desc}, {res.scheme}"
        written.append(plot_response(res, motion, targets[1], title=title, alpha=alpha,
                                     g=model.g))
    print("wrote " + ", ".join(map(str, written)))
    return 0


def cmd_build_fmu(args) -> int:
    from .fmi.build import main as build_main

    # the same entry point as `python build_fmu.py` (a checkout's): FMUs and their cross-check folders
    argv = ["--dest", args.dest] + (["--no-cross-check"] if args.no_cross_check else []) + list(args.names)
    return build_main(argv, prog="rocking build-fmu")


def cmd_benchmark(args, extra: list[str]) -> int:
    root = _repo_root()
    if args.ensemble:
        cmd = [sys.executable, str(root / "benchmarks" / "ensemble_bench.py")]
    else:
        cmd = [sys.executable, "-m", "benchmarks"]
    cmd += (["--quick"] if args.quick else []) + extra
    return subprocess.run(cmd, cwd=root).returncode


def cmd_ensemble(args) -> int:
    from . import ensemble as E

    from .models import model_class

    declared = {p.name: p for p in model_class(args.model).parameters()}
    b0, h0 = declared["b"].default, declared["h"].default      # the model's defaults
    geometries = [(b, h) for b in (_flat(args.b) or [b0]) for h in (_flat(args.h) or [h0])]
    params = _given_parameters(args, skip=ENSEMBLE_GRID)
    common = dict(geometries=geometries, schemes=args.scheme, model=args.model, e_N=args.e_N, mu=args.mu,
                  t_end=args.t_end, output_interval=args.output_interval, tolerance=args.tolerance,
                  dt_max=args.dt_max, params=params or None)
    if bool(args.record) == bool(args.pulse):
        raise UsageError("give either --record FILE... (with --scales) or --pulse KIND (with amplitudes and "
                         "frequencies)")
    vscales = _flat(args.vertical_scales)
    if vscales is not None:
        from .validation import check_real
        vscales = [check_real("--vertical-scales", v, lo=-VERTICAL_SCALE_MAX, hi=VERTICAL_SCALE_MAX)
                   for v in vscales]
    if args.vertical and not args.record:
        raise UsageError("--vertical (the vertical records) needs --record; a pulse grid takes --vertical-scales")
    if args.vertical and len(args.vertical) != len(args.record):
        raise UsageError(f"--vertical: give one vertical record per --record ({len(args.record)}), got "
                         f"{len(args.vertical)} ('' for a record without one)")
    if args.record:
        cases = E.record_cases(args.record, _flat(args.scales) or [1.0], units=args.units, vertical=args.vertical,
                               ag_v_scales=vscales, **common)
    else:
        cases = E.pulse_cases(args.pulse, amplitude_ratios=_flat(args.amplitude_ratios),
                              frequency_ratios=_flat(args.frequency_ratios), amplitudes=_flat(args.amplitudes),
                              frequencies=_flat(args.frequencies), ag_v_scales=vscales or [0.0], **common)
    where = f"on the Dask cluster at {args.address}" if args.address else \
        ("serially (no Dask)" if args.workers == 0 else f"on a local Dask cluster of {args.workers} worker(s)")
    print(f"{len(cases)} cases -> {args.out}, {where}")
    try:
        with warnings.catch_warnings():
            # what a resume repaired, as one line each (not Python's file:line warning format)
            warnings.simplefilter("always", E.RepairWarning)
            warnings.showwarning = lambda msg, *a, **k: print(f"rocking ensemble: warning: {msg}", file=sys.stderr)
            s = E.run_ensemble(cases, args.out, workers=args.workers, address=args.address,
                               resume=not args.no_resume, progress=not args.no_progress, batch_size=args.batch_size,
                               no_workers_timeout=args.no_workers_timeout)
    except KeyboardInterrupt:
        print(f"interrupted: the finished cases are in {args.out}; run the same command to resume",
              file=sys.stderr)
        return 130
    except E.WorkersLost as exc:
        print(f"rocking ensemble: error: {exc}", file=sys.stderr)
        # the rows are written and the lock released (run_ensemble's finally); a cluster whose workers were
        # being killed can leave Dask threads that would hold the interpreter's shutdown: end the process now
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(1)
    except E.EnsembleError as exc:
        print(f"rocking ensemble: error: {exc}", file=sys.stderr)
        return 1
    print(f"ran {s['n_run']} cases ({s['n_skipped']} already in {args.out}): {s['n_overturned']} overturned, "
          f"{s['n_errors']} errors")
    if s["n_run"]:
        on = f"on {s['workers']} worker(s)" if s["workers"] else "serially"
        print(f"throughput {s['throughput']:.2f} cases/s {on} "
              f"({s['wall_time']:.1f} s, plus {s['setup_time']:.1f} s cluster start)")
    if args.pulse and _is_block(args.model) and args.amplitude_ratios and args.frequency_ratios \
            and not args.no_plot:
        from .plotting import plot_overturning_spectrum
        ids = {c["case_id"] for c in cases}
        rows = [r for r in E.read_results(args.out) if r["case_id"] in ids]
        png = Path(args.plot) if args.plot else Path(args.out).with_name(Path(args.out).stem + "_spectrum.png")
        b, h = geometries[0]
        title = f"Overturning spectrum, {args.pulse} pulse, {model_class(args.model).title}" + \
            (f" b = {b:g} m, h = {h:g} m" if len(geometries) == 1 else f" ({len(geometries)} geometries)") + \
            "".join(f", {k} = {v:g}" for k, v in params.items() if isinstance(v, float))
        print(f"wrote {plot_overturning_spectrum(rows, png, title=title)}")
    return 0 if s["n_errors"] == 0 else 1


def cmd_fragility(args) -> int:
    """Fragility curves of a suite of records: MSA on --stripes or IDA from --ida, per damage state."""
    from . import assessment as A
    from . import ensemble as E
    from .models import model_class

    if (args.stripes is None) == (args.ida is None):
        raise UsageError("give either --stripes LEVEL... (multiple-stripe analysis) or --ida START (incremental "
                         "dynamic analysis)")
    declared = {p.name: p for p in model_class(args.model).parameters()}
    geometries = [(b, h) for b in (_flat(args.b) or [declared["b"].default])
                  for h in (_flat(args.h) or [declared["h"].default])]
    params = _given_parameters(args, skip=ENSEMBLE_GRID)
    vscales = _flat(args.vertical_scales)
    if args.vertical and len(args.vertical) != len(args.record):
        raise UsageError(f"--vertical: give one vertical record per --records entry ({len(args.record)}), got "
                         f"{len(args.vertical)} ('' for a record without one)")
    common = dict(geometries=geometries, schemes=args.scheme, model=args.model, e_N=args.e_N, mu=args.mu,
                  t_end=args.t_end, output_interval=args.output_interval, tolerance=args.tolerance,
                  dt_max=args.dt_max, params=params or None, units=args.units, vertical=args.vertical,
                  ag_v_scales=vscales, zeta=args.im_zeta, damage_states=args.damage_states, n_boot=args.bootstrap,
                  workers=args.workers, address=args.address, resume=not args.no_resume,
                  progress=not args.no_progress, batch_size=args.batch_size)
    A.damage_states(args.damage_states)                 # a bad spec is refused before anything runs
    out = Path(args.out)
    results = out / ("cases.parquet" if args.parquet else "cases.csv")
    im = A.canonical_measure(args.im)
    kind = "IDA" if args.ida is not None else "MSA"
    print(f"{kind} of {len(A.record_files(args.record))} record(s) x {len(geometries)} geometr"
          f"{'y' if len(geometries) == 1 else 'ies'} on {im} -> {out}")
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("always", E.RepairWarning)
            warnings.showwarning = lambda msg, *a, **k: print(f"rocking fragility: warning: {msg}", file=sys.stderr)
            if args.ida is not None:
                r = A.run_ida(args.record, im, results, start=args.ida, ratio=args.ida_ratio,
                              rtol=args.ida_tolerance, max_runs=args.ida_max_runs, n_above=args.ida_above,
                              im_max=args.ida_max if args.ida_max is not None else math.inf, **common)
            else:
                r = A.run_msa(args.record, im, _flat(args.stripes), results, **common)
    except KeyboardInterrupt:
        print(f"interrupted: the finished cases are in {results}; run the same command to resume", file=sys.stderr)
        return 130
    except E.EnsembleError as exc:
        print(f"rocking fragility: error: {exc}", file=sys.stderr)
        return 1
    s = r.summary
    print(f"ran {s['n_run']} cases ({s['n_skipped']} already in {results}): {s['n_overturned']} overturned, "
          f"{s['n_errors']} errors")
    written = [results]
    if args.ida is not None:
        written.append(A.write_curves(r.curves, out / "ida_curves.csv"))
        for c in r.curves:
            name = Path(c.record).name if not c.record.startswith("synthetic") else c.record
            pockets = ", ".join(f"{lo:.4g}-{hi:.4g}" for lo, hi in c.resurrections) or "none"
            print(f"  {name}{' ' + c.group if c.group else ''}: first overturning at {c.first_overturning:.4g} "
                  f"({len(c.levels)} runs); non-overturning above it: {pockets}")
    for f in r.fragilities:
        band = ""
        if f.bands is not None and math.isfinite(f.bands.theta_band[0]):
            band = f" [{f.bands.theta_band[0]:.4g}, {f.bands.theta_band[1]:.4g}]"
        print(f"  {f.label}: theta = {f.fit.theta:.4g}{band}, beta = {f.fit.beta:.3g}"
              + (f" ({f.fit.note})" if f.fit.note else ""))
    written += A.write_fragilities(r.fragilities, out, im_label=im, plot=not args.no_plot,
                                   title=f"{kind}, {model_class(args.model).title}")
    print("wrote " + ", ".join(map(str, written)))
    return 0 if s["n_errors"] == 0 else 1


def cmd_im(args) -> int:
    """Print a record's intensity measures (rocking_model.intensity), one per line, or as JSON."""
    from .intensity import UNITS, intensity_measures
    from .records import G_N, load_motion
    from .validation import check_real

    if (args.b is None) != (args.h is None):
        raise UsageError("--b and --h go together (the rigid block of the rocking measures)")
    g = check_real("--g", args.g, lo=0.0, lo_open=True)
    block = None
    if args.b is not None:
        from .models.rigid_block import RigidBlock

        block = RigidBlock(b=args.b, h=args.h, g=g)
    rec = load_motion(args.record, args.units)
    if args.resample:
        rec = rec.resampled(args.resample)
    if args.scale != 1.0:
        rec = rec.scaled(args.scale)
    m = intensity_measures(rec, _flat(args.periods) or (), zeta=args.zeta, g=g, block=block,
                           baseline=args.baseline)
    if args.json:
        import json

        print(json.dumps({k: (v if math.isfinite(v) else None) for k, v in m.items()}, indent=2))
        return 0
    print(f"record {rec.name}: {rec.t.size} samples, dt = {rec.dt:g} s, {rec.t[-1] - rec.t[0]:g} s"
          + (f"; rigid block b = {args.b:g} m, h = {args.h:g} m (alpha = {block.alpha:.4f} rad, "
             f"p = {block.p:.3f} rad/s)" if block is not None else ""))
    width = max(len(k) for k in m)
    for k, v in m.items():
        unit = UNITS["Sa" if k.startswith("Sa(") else k]
        extra = f"  ({v / G_N:.4g} g)" if unit == "m/s2" else ""
        print(f"{k:<{width}}  {v:12.6g} {'' if unit == '1' else unit}{extra}".rstrip())
    return 0


# --------------------------------------------------------------------------------------------- parser
#: the model parameters of `rocking ensemble` that are case fields of their own (b, h: grids of geometries);
#: the models' other declared parameters are options of one value each (the case field ``params``)
ENSEMBLE_GRID = ("b", "h", "e_N", "mu")


def _option_names(name: str) -> list[str]:
    """The option strings of a declared name: --k-t, and --k_t as it is declared (one option)."""
    dashed = f"--{name.replace('_', '-')}"
    return [dashed] + ([f"--{name}"] if "_" in name else [])


def _model_options(p: argparse.ArgumentParser, lists: bool = False) -> None:
    g = p.add_argument_group("model")
    from .models import MODELS

    g.add_argument("--model", choices=tuple(MODELS), default="rigid",
                   help="; ".join(f"{k}: the {cls.title}" for k, cls in MODELS.items()) + " (default: rigid)")
    declared = _declared()
    if lists:
        def defaults(name):
            return ", ".join(f"{per_kind.default:g} {k}" for k, per_kind in declared[name].items())
        g.add_argument("--b", type=_values, nargs="+", metavar="B",
                       help=f"half-widths [m] (grid; default: the model's, {defaults('b')})")
        g.add_argument("--h", type=_values, nargs="+", metavar="H",
                       help=f"half-heights / column heights [m] (grid; default: the model's, {defaults('h')})")
        g.add_argument(*_option_names("e_N"), dest="e_N", type=float, default=0.0,
                       help="coefficient of restitution [1]")
        g.add_argument("--mu", type=float, default=math.inf,
                       help="Coulomb friction coefficient [1] (default inf: the paper's sticking law)")
    # the options and their help come from the models' declarations (rocking_model.params); an ensemble takes
    # the parameters other than its grid's, one value each, and no initial values
    options = list(declared.items()) + ([] if lists else list(_declared_initial().items()))
    for name, per_kind in options:
        if lists and name in ENSEMBLE_GRID:
            continue
        choice = any(p.items for p in per_kind.values())
        g.add_argument(*_option_names(name), dest=name, type=_choice if choice else float,
                       help=_help(per_kind, len(MODELS)).replace("%", "%%"))


def _choice(text: str):
    """A choice given by code (an integer) or by name."""
    return int(text) if text.lstrip("-").isdigit() else text


def _solver_options(p: argparse.ArgumentParser, many: bool = False) -> None:
    from .integrators import SCHEMES

    g = p.add_argument_group("solver")
    names = tuple(sorted(SCHEMES, key=lambda n: -SCHEMES[n].code))       # event_driven first: the default
    if many:
        g.add_argument("--scheme", nargs="+", choices=names, default=["event_driven"])
    else:
        g.add_argument("--scheme", choices=names, default="event_driven",
                       help="; ".join(f"{n}: {SCHEMES[n].summary}" for n in names))
    g.add_argument("--tolerance", type=float, default=1e-8, help="event-driven tolerance [1] (default 1e-8)")
    g.add_argument("--dt-max", dest="dt_max", type=float, help="Moreau-Jean step [s] (default 1e-3)")
    g.add_argument("--t-end", dest="t_end", type=float, help="end time [s] (default: end of the motion + 5 s)")
    g.add_argument("--output-interval", dest="output_interval", type=float, default=0.01,
                   help="output interval [s] (default 0.01)")


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="rocking", description="Nonsmooth rocking dynamics: simulations, FMUs, "
                                "benchmarks and ensembles (Giouvanidis & Dimitrakopoulos 2017).")
    p.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    sub = p.add_subparsers(dest="command", required=True, metavar="COMMAND")

    s = sub.add_parser("simulate", help="one simulation: CSV, PNG and a summary",
                       description="Simulate one model under a record or a pulse; write <out>/<name>.csv and "
                                   "<out>/<name>.png (phi, ag and contact state over time); print a summary.")
    _model_options(s)
    g = s.add_argument_group("ground motion (a record or a pulse; none: free rocking)")
    g.add_argument("--record", help="PEER .AT2 or .csv file (time, ag and optionally a third column, the "
                                    "vertical ag_v), or synthetic[:seed]")
    g.add_argument("--vertical", metavar="FILE", help="the record's vertical component ag_v (positive upward): a "
                   "second .AT2 or two-column .csv file of the same time step (the shorter one padded with zeros)")
    g.add_argument("--vertical-scale", dest="vertical_scale", type=float, metavar="F",
                   help=f"factor on the vertical component [1], in [-{VERTICAL_SCALE_MAX:g}, {VERTICAL_SCALE_MAX:g}] "
                        "(default 1); for a record without one or a pulse: ag_v = F x the horizontal motion "
                        "(default 0: none)")
    g.add_argument("--units", help="units of a CSV record when its header does not state them (g, m/s2, cm/s2...)")
    g.add_argument("--pulse", choices=PULSES)
    g.add_argument("--amplitude", type=float, help="pulse amplitude (peak) in --amplitude-units")
    g.add_argument("--amplitude-units", default="m/s2", help="g, m/s2 (default), cm/s2, ...")
    g.add_argument("--frequency", type=float, help="pulse frequency f_p [Hz] (omega_p = 2 pi f_p)")
    g.add_argument("--duration", type=float, help="rectangular pulse duration [s]")
    g.add_argument("--t0", type=float, help="pulse start [s], default 0 (Ricker: centre, default 1.5/f_p)")
    g.add_argument("--scale", type=float, default=1.0, help="scale factor on the motion [1]")
    g.add_argument("--resample", type=float, help="resample the motion every DT [s] (linear)")
    _solver_options(s)
    g = s.add_argument_group("output")
    g.add_argument("--out", default="results", help="output directory (default results/)")
    g.add_argument("--name", help="file name stem (default: named after the scene, e.g. "
                                  "rigid_b0.3_sine-A3ms2-f2Hz; see also --force)")
    g.add_argument("--force", action="store_true", help="overwrite existing output files (refused otherwise)")
    g.add_argument("--no-plot", action="store_true", help="skip the PNG (no matplotlib needed)")

    b = sub.add_parser("build-fmu", help="build and validate the FMUs (needs a C compiler)")
    b.add_argument("--dest", default="dist", help="output directory (default dist/)")
    b.add_argument("--no-cross-check", action="store_true",
                   help="do not write the cross-check folders (dest/cross-check), as python build_fmu.py")
    b.add_argument("names", nargs="*", help="FMU names (default: all)")

    k = sub.add_parser("benchmark", help="run the benchmark suite (python -m benchmarks; source checkout)",
                       description="Run python -m benchmarks (or, with --ensemble, benchmarks/ensemble_bench.py); "
                                   "other arguments are passed through.")
    k.add_argument("--quick", action="store_true", help="smoke run")
    k.add_argument("--ensemble", action="store_true", help="ensemble throughput on 1 and 2 Dask workers")

    from .ensemble import NO_WORKERS_TIMEOUT

    e = sub.add_parser("ensemble", help="a grid of cases on Dask, written incrementally, resumable",
                       description="Run records x scales (or pulse amplitudes x frequencies) x geometries x "
                                   "schemes; one row per case in --out (.csv, or a .parquet directory); a rerun "
                                   "skips the cases already there. Lists accept numbers and start:stop:num.")
    _model_options(e, lists=True)
    g = e.add_argument_group("ground motions")
    g.add_argument("--record", nargs="+", help="record files (.AT2, .csv) or synthetic:<seed>")
    g.add_argument("--units", help="units of CSV records without stated units")
    g.add_argument("--scales", type=_values, nargs="+", help="scale factors on the records (default 1)")
    g.add_argument("--vertical", nargs="+", metavar="FILE", help="one vertical record (ag_v, positive upward) per "
                   "--record, '' for none (.AT2 or two-column .csv, the same time step as its record)")
    g.add_argument("--vertical-scales", dest="vertical_scales", type=_values, nargs="+", metavar="F",
                   help=f"factors on the vertical components [1], in [-{VERTICAL_SCALE_MAX:g}, "
                        f"{VERTICAL_SCALE_MAX:g}] (case field ag_v_scale; default 1 for records with a vertical "
                        "component, else 0: none); without one, ag_v = F x the horizontal record or pulse")
    g.add_argument("--pulse", choices=PULSES)
    g.add_argument("--amplitude-ratios", type=_values, nargs="+", metavar="A", help="A / (g tan alpha) [1]")
    g.add_argument("--frequency-ratios", type=_values, nargs="+", metavar="W", help="omega_p / p [1]")
    g.add_argument("--amplitudes", type=_values, nargs="+", metavar="A", help="pulse amplitudes [m/s2]")
    g.add_argument("--frequencies", type=_values, nargs="+", metavar="F", help="pulse frequencies [Hz]")
    _solver_options(e, many=True)
    g = e.add_argument_group("execution and output")
    g.add_argument("--out", default="results/ensemble.csv", help="results file .csv or directory .parquet")
    g.add_argument("--workers", type=_count(0), default=2, help="local Dask workers (default 2; 0: serial, no Dask)")
    g.add_argument("--address", help="scheduler address of an existing Dask cluster, e.g. tcp://10.0.0.5:8786")
    g.add_argument("--batch-size", type=_count(1), help="cases per Dask task (default: about ensemble.TASKS_PER_WORKER = 4 tasks per worker)")
    g.add_argument("--no-workers-timeout", dest="no_workers_timeout", type=_positive, metavar="SECONDS",
                   default=NO_WORKERS_TIMEOUT, help="end the run when the Dask cluster has had no worker for this "
                   "long [s] (default %(default)g); the finished cases stay in --out and a rerun resumes")
    g.add_argument("--no-resume", action="store_true", help="fail if --out exists instead of resuming")
    g.add_argument("--no-progress", action="store_true", help="no progress bar")
    g.add_argument("--plot", help="overturning spectrum PNG (default: <out stem>_spectrum.png)")
    g.add_argument("--no-plot", action="store_true", help="skip the spectrum PNG")

    from .assessment import DEFAULT_DAMAGE_STATES

    f = sub.add_parser("fragility", help="fragility curves of a suite of records (MSA or IDA), resumable",
                       description="Scale a suite of records to target values of an intensity measure and run "
                                   "a multiple-stripe analysis (--stripes) or an incremental dynamic analysis "
                                   "(--ida, hunt-and-fill per record); fit a lognormal fragility per damage state "
                                   "(bootstrap bands over records). Writes <out>/cases.csv (one row per run; a rerun "
                                   "resumes), fragility.csv/.json, fragility.png and, for IDA, ida_curves.csv. "
                                   "Lists accept numbers and start:stop:num.")
    _model_options(f, lists=True)
    g = f.add_argument_group("records and intensity measure")
    g.add_argument("--records", dest="record", nargs="+", required=True, metavar="RECORD",
                   help="record files (.AT2, .csv), folders of them, or synthetic:<seed>")
    g.add_argument("--units", help="units of CSV records without stated units")
    g.add_argument("--vertical", nargs="+", metavar="FILE", help="one vertical record per --records entry ('' for "
                   "none); scaled with its record")
    g.add_argument("--vertical-scales", dest="vertical_scales", type=_values, nargs="+", metavar="F",
                   help=f"factors on the vertical components [1], in [-{VERTICAL_SCALE_MAX:g}, "
                        f"{VERTICAL_SCALE_MAX:g}] (as rocking ensemble)")
    g.add_argument("--im", default="PGA", help="intensity measure: PGA, PGV, PGD, Arias, CAV, Sa(T) (e.g. "
                   "\"Sa(1)\"), \"PGA/(g tan alpha)\", \"PGV p/(g tan alpha)\" (default PGA; SI units)")
    g.add_argument("--im-zeta", dest="im_zeta", type=float, default=0.05,
                   help="damping ratio of the oscillator of Sa(T) [1] (default 0.05)")
    g = f.add_argument_group("analysis")
    g.add_argument("--stripes", type=_values, nargs="+", metavar="IM",
                   help="MSA: the IM levels of the stripes [the measure's units]")
    g.add_argument("--ida", type=_positive, metavar="START", help="IDA: the first IM level of the hunt")
    g.add_argument("--ida-ratio", type=float, default=1.5, help="IDA: hunt step factor (default 1.5)")
    g.add_argument("--ida-tolerance", type=float, default=0.02,
                   help="IDA: relative gap of the bisections and the fill (default 0.02)")
    g.add_argument("--ida-max-runs", type=_count(1), default=30, help="IDA: runs per record (default 30)")
    g.add_argument("--ida-above", type=_count(0), default=2,
                   help="IDA: hunt levels above the first overturning (default 2)")
    g.add_argument("--ida-max", type=_positive, help="IDA: highest IM level (default: none)")
    g.add_argument("--damage-states", nargs="+", metavar="DS",
                   help="[name:]quantity>=value or overturned; quantity phi/alpha, phi [rad], slip [m], tendon [N], "
                        "impacts or a result field (default: " + " ".join(DEFAULT_DAMAGE_STATES)
                        + "); overturning reaches every one")
    g.add_argument("--bootstrap", type=_count(0), default=200,
                   help="bootstrap resamples over records of the bands (default 200; 0: none)")
    _solver_options(f, many=True)
    g = f.add_argument_group("execution and output")
    g.add_argument("--out", default="results/fragility", help="output directory (default results/fragility)")
    g.add_argument("--parquet", action="store_true", help="cases as a .parquet directory instead of CSV")
    g.add_argument("--workers", type=_count(0), default=2, help="local Dask workers (default 2; 0: serial, no Dask)")
    g.add_argument("--address", help="scheduler address of an existing Dask cluster")
    g.add_argument("--batch-size", type=_count(1), help="cases per Dask task")
    g.add_argument("--no-resume", action="store_true", help="fail if the cases file exists instead of resuming")
    g.add_argument("--no-progress", action="store_true", help="no progress bar")
    g.add_argument("--no-plot", action="store_true", help="skip the PNG")

    i = sub.add_parser("im", help="a record's intensity measures (PGA, PGV, PGD, Arias, CAV, D5-95, Sa(T))",
                       description="Print the intensity measures of a record (rocking_model.intensity: the record "
                                   "integrated as sampled, exactly for a piecewise-linear acceleration, no baseline "
                                   "correction unless --baseline; peaks over the samples); the horizontal "
                                   "component. Lists accept numbers and start:stop:num.")
    i.add_argument("record", help="PEER .AT2 or .csv file (time, ag), or synthetic[:seed]")
    i.add_argument("--units", help="units of a CSV record when its header does not state them (g, m/s2, cm/s2...)")
    i.add_argument("--periods", type=_values, nargs="+", metavar="T",
                   help="oscillator periods T [s] of the pseudo-spectral accelerations Sa(T) (T = 0: PGA)")
    i.add_argument("--zeta", type=float, default=0.05, help="oscillator damping ratio [1] (default 0.05)")
    i.add_argument("--g", type=float, default=9.81,
                   help="gravity [m/s2] of the Arias intensity and the rocking measures (default 9.81)")
    i.add_argument("--b", type=float, help="half-width [m] of a rigid block: adds PGA/(g tan alpha) and "
                                           "PGV p/(g tan alpha) (with --h)")
    i.add_argument("--h", type=float, help="half-height [m] of the rigid block (with --b)")
    i.add_argument("--scale", type=float, default=1.0, help="scale factor on the record [1]")
    i.add_argument("--resample", type=float, help="resample the record every DT [s] first (linear; a record "
                                                  "must be uniformly sampled)")
    i.add_argument("--baseline", choices=("linear",), help="remove the least-squares line through the "
                                                          "acceleration samples first")
    i.add_argument("--json", action="store_true", help="print a JSON object {name: value} (SI units)")
    return p


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    argv = sys.argv[1:] if argv is None else list(argv)
    args, extra = parser.parse_known_args(argv)
    if extra and args.command != "benchmark":
        parser.parse_args(argv)                 # reports the unknown arguments, exit status 2
    prog = f"rocking {args.command}"
    try:
        if args.command == "simulate":
            return cmd_simulate(args)
        if args.command == "build-fmu":
            return cmd_build_fmu(args)
        if args.command == "benchmark":
            return cmd_benchmark(args, extra)
        if args.command == "im":
            return cmd_im(args)
        if args.command == "fragility":
            return cmd_fragility(args)
        return cmd_ensemble(args)
    except (UsageError, ValueError, FileNotFoundError) as exc:
        print(f"{prog}: error: {exc}", file=sys.stderr)
        return 2
    except (ImportError, OSError) as exc:
        print(f"{prog}: error: {exc}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print(f"{prog}: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
