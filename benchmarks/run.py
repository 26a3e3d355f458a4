"""Run the whole benchmark suite and regenerate docs/performance.md and its plots.

    python -m benchmarks            # full run (its measured durations, machine and load: benchmarks/README.md)
    python -m benchmarks --quick    # smoke run, report in benchmarks/results/quick/
    python benchmarks/run.py [--quick] [--skip-siconos] [--skip-fmu] [--skip-memory] [--skip-friction] [--repeats N]

Raw results go to benchmarks/results/latest.json (quick: benchmarks/results/quick/results.json), so that a
later run (e.g. after an optimization) can be compared number by number.
"""
from __future__ import annotations

import argparse
import functools
import json
import math
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

if __package__ in (None, ""):                       # python benchmarks/run.py
    sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
    __package__ = "benchmarks"

import numpy as np

from benchmarks import analysis, contenders as C, scenes as S
from benchmarks.machine import cpu_name

ROOT = Path(__file__).resolve().parent.parent
LEVELS = (1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8)


def log(msg: str) -> None:
    print(f"[{time.strftime('%H:%M:%S')}] {msg}", flush=True)


# ------------------------------------------------------------------------------------------------ machine
def machine_info() -> dict:
    cpu = cpu_name()
    versions = {"python": platform.python_version()}
    for mod in ("numpy", "scipy", "fmpy", "pythonfmu", "matplotlib", "rocking_model"):
        try:
            versions[mod] = __import__(mod).__version__
        except Exception:
            versions[mod] = "n/a"
    try:
        commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True,
                                text=True).stdout.strip()
        dirty = subprocess.run(["git", "status", "--porcelain", "--", "rocking_model", "fmu_src"], cwd=ROOT,
                               capture_output=True, text=True).stdout.strip()
        commit += " (library files modified in the work tree)" if dirty else ""
    except Exception:
        commit = "n/a"
    return {"cpu": cpu, "cores": os.cpu_count(), "platform": platform.platform(), "versions": versions,
            "commit": commit, "loadavg": os.getloadavg() if hasattr(os, "getloadavg") else None,
            "date": time.strftime("%Y-%m-%d %H:%M")}


# ------------------------------------------------------------------------------------------------ scenes
def _entry(contender, label, setting, times, sol, ref, names, window):
    return {"contender": contender, "label": label, "setting": setting, "times": times,
            "time": C.best(times), "median": C.median(times), "n_steps": int(sol.get("n_steps", 0) or 0),
            "errors": analysis.errors(sol, ref, names, window), "overturned": bool(sol.get("overturned", False)),
            "wrong_side": C.wrong_side(sol) if contender in ("event_driven", "c_event_driven") else None}


def bench_scene(scene: S.Scene, args) -> dict:
    log(f"scene {scene.name}: {scene.describe()}")
    names = ("phi",) if scene.kind == "rigid" else ("phi", "top_displacement")
    out = {"name": scene.name, "title": scene.title, "kind": scene.kind, "describe": scene.describe(),
           "note": scene.note, "grid": scene.grid, "t_end": scene.t_end, "entries": []}
    t0 = time.perf_counter()
    ref = C.reference(scene)
    out["reference"] = {"tolerance": scene.ref_tol, "dt_max": scene.grid / scene.ref_cap, "time": ref["time"],
                        "n_steps": ref["n_steps"], "impacts": int(len(ref["impact_times"])),
                        "overturned": ref["overturned"], "phi_absmax": float(np.max(np.abs(ref["phi"]))),
                        "first_impacts": [float(x) for x in ref["impact_times"][:5]]}
    out["reference"]["wrong_side"] = C.wrong_side(ref)
    if "top_displacement" in ref:
        out["reference"]["top_absmax"] = float(np.max(np.abs(ref["top_displacement"])))
    # comparison window: the rigid-block baseline is Housner's single-DOF model, which cannot leave the
    # ground; compare up to the first flight phase of the reference (if any)
    window = None
    flight = np.nonzero(ref["contact"] == 3)[0]
    if scene.kind == "rigid" and flight.size:
        window = int(flight[0])
        out["window_end"] = float(C.grid_of(scene)[window])
    # uncertainty of the reference: the same tolerance without the step cap
    alt = C.run_package(scene, "event_driven", tolerance=scene.ref_tol)
    out["reference"]["floor"] = analysis.errors(alt, ref, names, window)
    if scene.name == "free" or scene.initial and scene.motion[0] == "none":
        blk = scene.model()
        n = min(20, len(ref["impact_times"]))
        ct, cs = analysis.free_rocking_closed_form(blk.p, blk.alpha, blk.housner_r, scene.initial["phi_0"], n)
        speeds = np.array([abs(vm[blk.phi_index]) for _, vm, _ in ref["impact_log"][:n]])
        out["reference"]["closed_form"] = {
            "n": n, "impact_time_err": float(np.max(np.abs(ct - ref["impact_times"][:n]))),
            "speed_rel_err": float(np.max(np.abs(speeds - cs) / cs)),
            "first_impact_closed_form": float(ct[0]), "first_speed_closed_form": float(cs[0])}
    log(f"  reference: {ref['time']:.2f} s, {ref['n_steps']} steps, {len(ref['impact_times'])} impacts, "
        f"floor {out['reference']['floor']['phi_max']:.1e}")

    reps, budget = args.repeats, args.budget
    # the compiled engine: each scheme through simulate(engine="c") over the scene's sweep
    # (finer Moreau-Jean steps too: cheap on the compiled engine, they extend its curve to smaller errors. Down to
    # 1e-5 s: on the pulse below overturning the error of the first-order scheme is the shift of the late impacts,
    # 1.0e-3 rad at 2e-5 s and 2e-4 rad at 1e-5 s, where Siconos' Moreau-Jean reaches 1e-3 rad)
    for dt in tuple(scene.mj_dts) + (() if args.quick else (1e-4, 5e-5, 2e-5, 1e-5)):
        sol, times = C.timed(lambda: C.package_result(scene, "moreau_jean", engine="c", dt_max=dt), reps,
                             budget, post=C.outputs_of)
        out["entries"].append(_entry("c_moreau_jean", "compiled Moreau-Jean", {"dt_max": dt}, times, sol, ref,
                                     names, window))
    again = []               # (entry, its run): timed once more by _second_pass
    for tol in scene.ed_tols:
        run = functools.partial(C.package_result, scene, "event_driven", engine="c", tolerance=tol)
        sol, times = C.timed(run, reps, budget, post=C.outputs_of)
        out["entries"].append(_entry("c_event_driven", "compiled event-driven", {"tolerance": tol}, times, sol,
                                     ref, names, window))
        again.append((out["entries"][-1], run))
    log(f"  compiled sweeps done ({time.perf_counter() - t0:.0f} s)")
    if scene.kind == "rigid":
        for tol in scene.base_tols:
            run = functools.partial(C.run_baseline, scene, tol)
            sol, times = C.timed(run, reps, budget)
            out["entries"].append(_entry("baseline", "solve_ivp DOP853", {"rtol": tol}, times, sol, ref, names,
                                         window))
            again.append((out["entries"][-1], run))
        if scene.motion[0] == "sampled":
            ms = float(scene.motion[1][1] - scene.motion[1][0])
            for tol in scene.base_tols:
                run = functools.partial(C.run_baseline, scene, tol, max_step=ms)
                sol, times = C.timed(run, reps, budget)
                out["entries"].append(_entry("baseline", f"solve_ivp DOP853, max_step={ms:g}", {"rtol": tol},
                                             times, sol, ref, names, window))
                again.append((out["entries"][-1], run))
        log(f"  baseline done ({time.perf_counter() - t0:.0f} s)")
        if args.siconos_ok:
            sic = C.run_siconos(scene, scene.sic_dts, reps, budget=min(budget, 3.0))
            if "error" in sic:
                out["siconos_error"] = sic["error"]
            else:
                out["siconos_version"] = sic.get("version")
                for run in sic["runs"]:
                    sol = {"phi": np.array(run["phi"]), "n_steps": run["n_steps"]}
                    e = _entry("siconos", "Siconos Moreau-Jean", {"dt": run["dt"]}, run["times"], sol, ref, names,
                               window)
                    e["errors"].pop("impact3", None)
                    out["entries"].append(e)
            log(f"  siconos done ({time.perf_counter() - t0:.0f} s)")
    if scene.kind == "rigid" and not args.quick:
        _second_pass(again, reps, budget)
        log(f"  second pass done ({time.perf_counter() - t0:.0f} s)")
    out["equal_error"] = equal_error(out["entries"])
    out["wall"] = time.perf_counter() - t0
    return out


#: rounds of the second pass: each (entry, run) it times is timed once per round, the rounds one after the other
SECOND_PASS_ROUNDS = 4


def _second_pass(again: list, reps: int, budget: float, rounds: int = SECOND_PASS_ROUNDS) -> None:
    """Time each (entry, run) of ``again`` (the compiled event-driven settings and the solve_ivp baseline's, the two
    that the speed target compares) once more, after every other contender of the scene, in ``rounds`` interleaved
    rounds (each round times every entry for its share of the repeats and of the time), and keep the repeats of
    both passes (the minimum over all of them). The two sides of a ratio are then sampled at the same times of the
    run, many seconds apart: a slow phase of a shared machine (seen: another job halving the speed for some
    seconds, or for minutes) slows both, and the minimum of each comes from the fastest phase both saw."""
    for e, _ in again:
        e["times"] = list(e["times"])
    for _ in range(rounds):
        for e, run in again:
            post = C.outputs_of if e["contender"] == "c_event_driven" else None
            _, times = C.timed(run, max(1, -(-reps // rounds)), budget / rounds, min_total=C.MIN_TOTAL / rounds,
                               post=post)
            e["times"] += times
    for e, _ in again:
        e["time"], e["median"] = C.best(e["times"]), C.median(e["times"])


def equal_error(entries, measure: str = "phi_max") -> dict:
    """Time of each contender at each error level: linear interpolation in log-log on the work-precision front
    of each curve (one curve per label: a scheme, or a baseline variant). The compiled engine's best time (family
    "compiled") is the faster of its schemes at that level, the baseline's the faster of its variants;
    ratio_c_* = other / compiled (ratio_cmj_siconos: Siconos' Moreau-Jean against the compiled Moreau-Jean).
    Entries of the removed Python engine (family "package", in old results) still get their ratios
    (ratio_baseline, ratio_siconos = other / package; ratio_c_package)."""
    curves: dict[str, list] = {}
    family = {}
    for e in entries:
        curves.setdefault(e["label"], []).append((e["time"], e["errors"].get(measure, math.nan)))
        family[e["label"]] = {"moreau_jean": "package", "event_driven": "package", "c_moreau_jean": "compiled",
                              "c_event_driven": "compiled"}.get(e["contender"], e["contender"])
        family[e["contender"]] = family[e["label"]]
    res = {}
    for lvl in LEVELS:
        row = {}
        for lab, pts in curves.items():
            t, how = analysis.time_at_error(pts, lvl)
            row[lab] = {"time": t, "how": how}
        for fam in sorted(set(family.values())):
            cands = [(row[l]["time"], row[l]["how"], l) for l in curves if family[l] == fam
                     and not math.isnan(row[l]["time"])]
            if cands:
                t, how, lab = min(cands)
                row[fam] = {"time": t, "how": how, "by": lab}
            else:
                row[fam] = {"time": math.nan, "how": "not reached", "by": None}
        tp = row["package"]["time"] if "package" in row else math.nan
        for other in ("baseline", "siconos"):
            if other in row and "package" in row:
                to = row[other]["time"]
                if math.isnan(tp):
                    ratio = math.nan                   # the package does not reach the level
                elif math.isnan(to):
                    ratio = math.inf                   # the other does not reach it
                else:
                    ratio = to / tp
                row[f"ratio_{other}"] = ratio

        def ratio(num, den):
            if num not in row or den not in row:
                return None
            a, b = row[num]["time"], row[den]["time"]
            return math.nan if math.isnan(b) else math.inf if math.isnan(a) else a / b
        for key, num, den in (("ratio_c_baseline", "baseline", "compiled"), ("ratio_c_siconos", "siconos", "compiled"),
                              ("ratio_c_package", "package", "compiled"),
                              ("ratio_cmj_siconos", "siconos", "compiled Moreau-Jean")):
            r = ratio(num, den)
            if r is not None:
                row[key] = r
        res[f"{lvl:.0e}"] = row
    return res


# ------------------------------------------------------------------------------------------------ orders
def bench_orders(args) -> dict:
    """Convergence orders: Moreau-Jean (from the scene sweeps, in the report); event-driven with a fixed
    step (tolerance 1e-2, the step set by dt_max) and adaptive (error against tolerance and step count),
    each in one `advance` over the span so that the output grid does not cut the steps; the scipy baseline
    against its step count for comparison."""
    from rocking_model import Simulator, SinePulse, RigidBlock
    from rocking_model.ground_motion import as_ground_motion

    log("orders")
    cases = {
        "free": (RigidBlock(**S.FREE_BLOCK), 0.0, 2.0, {"phi_0": 0.15}),
        "pulse_below": (RigidBlock(**S.PULSE_BLOCK), SinePulse(S.PULSE_BELOW_G * S.G, 2 * math.pi * S.PULSE_F), 3.0,
                        {}),
    }
    out = {}
    for name, (model, gm, T, ini) in cases.items():
        gm = as_ground_motion(gm)

        def run(**kw):
            sim = Simulator(model, "event_driven", **ini, **kw)
            t0 = time.perf_counter()
            sim.advance(T, gm)
            return {"phi": sim.outputs()["phi"], "impacts": np.array(sim.impact_times),
                    "n_steps": sim.integrator.n_steps, "time": time.perf_counter() - t0}

        ref = run(tolerance=1e-13, dt_max=T / 4000)
        alpha, p = model.alpha, model.p

        def dimensionless(e):
            """The order metric: max(|dphi(T)| / alpha, p |dt_impact|) [1] (one unit for both errors)."""
            e["err"] = max(e["err_end"] / alpha, p * e["err_impacts"])
            return e
        fixed, adaptive = [], []
        for h in (0.5, 0.35, 0.25, 0.18, 0.125, 0.09, 0.0625, 0.044, 0.03):
            r = run(tolerance=1e-2, dt_max=h)
            fixed.append(dimensionless({"dt_max": h, "n_steps": r["n_steps"], "err_end": abs(r["phi"] - ref["phi"]),
                                        "err_impacts": analysis.first_impact_error(r["impacts"], ref["impacts"])}))
        for tol in (1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11):
            r = run(tolerance=tol)
            adaptive.append(dimensionless({"tolerance": tol, "n_steps": r["n_steps"], "time": r["time"],
                                           "err_end": abs(r["phi"] - ref["phi"]),
                                           "err_impacts": analysis.first_impact_error(r["impacts"], ref["impacts"])}))
        base = []
        grid = np.array([0.0, T])
        for tol in (1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11):
            from benchmarks.baseline import rigid_solve_ivp
            r = rigid_solve_ivp(model, gm, T, grid, rtol=tol, atol=tol, **ini)
            base.append(dimensionless({"tolerance": tol, "n_steps": r["n_steps"],
                                       "err_end": abs(r["phi"][-1] - ref["phi"]),
                                       "err_impacts": analysis.first_impact_error(r["impact_times"], ref["impacts"])}))
        fe = [f["err"] for f in fixed]
        fe = [e if e < 5e-2 else math.nan for e in fe]          # pre-asymptotic: another impact sequence
        fx = analysis.fit_order([f["n_steps"] for f in fixed], fe, floor=1e-12)
        fh = analysis.fit_order([f["dt_max"] for f in fixed], fe, floor=1e-12)
        an = analysis.fit_order([a["n_steps"] for a in adaptive], [a["err"] for a in adaptive], floor=5e-12)
        at = analysis.fit_order([a["tolerance"] for a in adaptive], [a["err"] for a in adaptive], floor=5e-12)
        bn = analysis.fit_order([b["n_steps"] for b in base], [b["err"] for b in base], floor=5e-12)
        out[name] = {"T": T, "fixed": fixed, "adaptive": adaptive, "baseline": base,
                     "order_fixed_vs_h": fh, "order_fixed_vs_steps": fx, "order_adaptive_vs_steps": an,
                     "slope_vs_tolerance": at, "baseline_order_vs_steps": bn,
                     "ref_impacts": [float(x) for x in ref["impacts"][:3]]}
        log(f"  {name}: fixed-step order {fh[0]:.2f} ({fh[1]} pts), adaptive err ~ N^{an[0]:.2f}, "
            f"err ~ tol^{at[0]:.2f}")
    return out


# ------------------------------------------------------------------------------------------------ FMU
def bench_fmu(args) -> dict:
    from rocking_model import RigidBlock, simulate

    from benchmarks import fmu_bench as F

    log("FMU overhead")
    tmp = Path(tempfile.mkdtemp(prefix="rocking_bench_fmu_"))
    res: dict = {}
    # FMUs of the current work tree (built into a temp dir; dist/ is left alone), dist/ as a fallback
    fmus = {}
    try:
        sys.path.insert(0, str(ROOT))
        import build_fmu
        for p in build_fmu.build_all(tmp / "built"):
            fmus[p.stem] = p
        res["fmu_source"] = "built from the work tree by build_fmu.build_all into a temp dir"
    except Exception as exc:
        res["fmu_source"] = f"dist/ (building from the work tree failed: {exc})"
        for p in (ROOT / "dist").glob("*.fmu"):
            fmus[p.stem] = p
    null = F.build_null_fmu(tmp / "null")
    dur = 8.0 if args.quick else 30.0
    t, a = S.synthetic_record()
    n = int(round(dur / 0.01)) + 1
    t, a = t[:n], a[:n]
    a_full = a
    dt = 0.01
    reps = args.repeats
    m0 = F.Master(null)
    # the FMU runs as the contenders (C.timed's practice): gc off during each stepping loop (Master.run), repeats
    # within the budget, the minimum compared
    times = []
    while len(times) < max(3, reps) or (sum(times) < C.MIN_TOTAL and len(times) < C.MAX_REPEATS):
        times.append(m0.run(a, dt, output="y")[0])
    res["null"] = {"times": times, "time": C.best(times), "median": C.median(times),
                   "per_step_us": C.best(times) / (n - 1) * 1e6}
    log(f"  null FMU: {res['null']['time'] * 1e3:.1f} ms for {n - 1} steps")
    res["duration"] = dur
    res["steps"] = n - 1

    def case(fmu_name, model, base_sv, settings, ref_kw, target, scale=1.0):
        m = F.Master(fmus[fmu_name])
        a = a_full * scale
        ref = C.reference(S.Scene("fmu", "", "rigid" if fmu_name.startswith("Rigid") else "flexible", ref_kw,
                                  ("sampled", t, a), dur, ref_cap=8 if fmu_name.startswith("Rigid") else 32),
                          hold="zoh")
        rows = []
        for label, sv in settings:
            svs = dict(base_sv, **sv)
            ts, phi = [], None
            while True:
                el, phi = m.run(a, dt, svs)
                ts.append(el)
                if sum(ts) > args.budget or (len(ts) >= max(1, reps) and sum(ts) >= C.MIN_TOTAL):
                    break
            err = float(np.max(np.abs(phi - ref["phi"])))
            rows.append({"label": label, "start_values": sv, "times": ts, "time": C.best(ts), "median": C.median(ts),
                         "phi_max_err": err, "ratio_null": C.best(ts) / res["null"]["time"]})
            log(f"  {fmu_name} {label}: {C.best(ts):.2f} s, max|phi err| {err:.1e}, "
                f"{C.best(ts) / res['null']['time']:.0f}x null")
        ok = [r for r in rows if r["phi_max_err"] <= 1e-4]
        best = min(ok, key=lambda r: r["time"]) if ok else None
        # the same run through the Python API (simulate, zero-order hold): what the FMU adds on top of the package
        sv_best = dict(base_sv, **(best or rows[0])["start_values"])
        kw = {"tolerance": sv_best.get("tolerance", 1e-8), "dt_max": sv_best.get("dt_max", 1e-3)}
        scheme = "event_driven" if sv_best.get("scheme", 0) == 1 else "moreau_jean"
        t0 = time.perf_counter()
        simulate(model, (t, a), dur, scheme=scheme, output_interval=dt, hold="zoh", engine="c", **kw)
        py_c = time.perf_counter() - t0
        e2e = F.simulate_fmu_time(fmus[fmu_name], m.unzipdir, t, a, dt, sv_best)
        e2e_null = F.simulate_fmu_time(null, m0.unzipdir, t, a, dt, {}, output=("y",))
        return {"rows": rows, "best": best, "target": target,
                "c_same_settings": py_c, "pga_g": 0.4 * scale,
                "simulate_fmu": e2e, "simulate_fmu_null": e2e_null, "ref_phi_absmax": float(np.max(np.abs(ref["phi"])))}

    rigid_kw = dict(S.RECORD_BLOCK)
    big = 1e3        # dt_max large: no cap on the event-driven steps
    res["rigid"] = case("RigidRockingBlock", RigidBlock(**rigid_kw), dict(rigid_kw), [
        ("event-driven tol 1e-4, dt_max uncapped", {"scheme": 1, "tolerance": 1e-4, "dt_max": big}),
        ("event-driven tol 1e-6, dt_max uncapped", {"scheme": 1, "tolerance": 1e-6, "dt_max": big}),
        ("event-driven tol 1e-8, dt_max uncapped", {"scheme": 1, "tolerance": 1e-8, "dt_max": big}),
        ("event-driven tol 1e-8, dt_max uncapped (FMU defaults)", {}),
        ("Moreau-Jean dt_max 1e-3 (scheme 0, other FMU defaults)", {"scheme": 0}),
    ], rigid_kw, 1.2)
    if "FlexibleRockingOscillator" in fmus:
        from fmpy import read_model_description

        from rocking_model.models.flexible_oscillator import FlexibleOscillator
        md = read_model_description(str(fmus["FlexibleRockingOscillator"]))
        import dataclasses
        fields = {f.name for f in dataclasses.fields(FlexibleOscillator) if f.init}
        flex_kw = {v.name: float(v.start) if v.type == "Real" else int(v.start) for v in md.modelVariables
                   if v.causality == "parameter" and v.name in fields and v.start is not None}
        # the FMU's default oscillator overturns under the 0.4 g record (and the event-driven runs disagree on
        # when, see the wrong-side check); at 0.3 g it rocks and stays up, consistently across settings
        res["flexible"] = case("FlexibleRockingOscillator", FlexibleOscillator(**flex_kw), {}, [
            ("event-driven tol 1e-6, dt_max uncapped", {"scheme": 1, "tolerance": 1e-6, "dt_max": big}),
            ("event-driven tol 1e-8, dt_max uncapped", {"scheme": 1, "tolerance": 1e-8, "dt_max": big}),
            ("event-driven tol 1e-10, dt_max uncapped", {"scheme": 1, "tolerance": 1e-10, "dt_max": big}),
            ("event-driven tol 1e-8, dt_max uncapped (FMU defaults)", {}),
            ("Moreau-Jean dt_max 1e-3 (scheme 0, other FMU defaults)", {"scheme": 0}),
        ], flex_kw, 1.4, scale=0.75)
        res["flexible"]["model"] = flex_kw
    else:
        res["flexible"] = {"skipped": "no FlexibleRockingOscillator FMU"}
    if hasattr(F, "engine_rows"):
        # the FMUs against the do-nothing FMU in interleaved rounds, the minimum of the rounds (least disturbed by other load)
        log("  FMUs against the do-nothing FMU")
        rounds = 2 if args.quick else 5
        try:
            res["engines"] = {"rigid": F.engine_rows(fmus, null, t, a_full, dt, {
                f"rigid event-driven tol {tol:g}": ("RigidRockingBlock", dict(rigid_kw, scheme=1, tolerance=tol,
                                                                              dt_max=big)) for tol in (1e-6, 1e-8)},
                rounds=rounds)}
            if "FlexibleRockingOscillator" in fmus:
                res["engines"]["flexible"] = F.engine_rows(fmus, null, t, a_full * 0.75, dt, {
                    f"flexible event-driven tol {tol:g} (record at 0.3 g)": (
                        "FlexibleRockingOscillator", dict(flex_kw, scheme=1, tolerance=tol, dt_max=big))
                    for tol in (1e-8, 1e-10)}, rounds=rounds)
        except Exception:
            import traceback
            res["engines"] = {"error": traceback.format_exc()}
    log("  cold starts")
    res["cold"] = {"NullSlave": F.cold_start(null, 3 if not args.quick else 1)}
    for name, p in fmus.items():
        res["cold"][name] = F.cold_start(p, 3 if not args.quick else 1)
    return res


# ------------------------------------------------------------------------------------------------ memory
def bench_memory(args) -> dict:
    minutes = 1.0 if args.quick else 10.0
    log(f"memory: {minutes:g} simulated minutes through Simulator (fresh interpreter)")
    r = subprocess.run([sys.executable, "-m", "benchmarks.memory", str(minutes), "event_driven"], cwd=ROOT,
                       capture_output=True, text=True, timeout=1800)
    if r.returncode != 0:
        return {"error": r.stderr.strip()[-800:]}
    return json.loads(r.stdout.strip().splitlines()[-1])


# ------------------------------------------------------------------------------------------------ compiled
def bench_compiled(args) -> dict:
    """The compiled engine per communication step and its cold start (benchmarks/compiled_bench.py), in a fresh
    interpreter as a user runs it: inside this long run's process the same loops measured up to 2x slower (a heap
    of some hundred MB of earlier results)."""
    log("compiled engine: per communication step, cold start")
    with tempfile.TemporaryDirectory(prefix="rocking_compiled_") as tmp:
        out = Path(tmp) / "compiled.json"
        r = subprocess.run([sys.executable, "-m", "benchmarks.compiled_bench", "--json", str(out)]
                           + (["--quick"] if args.quick else []), cwd=ROOT, capture_output=True, text=True,
                           timeout=1800)
        print(r.stdout, end="", flush=True)          # its progress lines ([compiled] ...)
        if r.returncode != 0 or not out.exists():
            return {"error": (r.stderr or r.stdout).strip()[-2000:]}
        return json.loads(out.read_text())


def bench_ensemble(args) -> dict:
    """Ensemble throughput on Dask (benchmarks/ensemble_bench.py, its own page docs/performance/ensemble.md
    and a JSON summary); run in a fresh interpreter, as a user runs it."""
    log("ensembles: throughput on Dask")
    out = ROOT / "benchmarks" / "results" / ("quick/ensemble.json" if args.quick else "ensemble.json")
    page = (ROOT / "benchmarks" / "results" / "quick" / "ensemble.md" if args.quick
            else ROOT / "docs" / "performance" / "ensemble.md")
    cmd = [sys.executable, str(ROOT / "benchmarks" / "ensemble_bench.py"), "--out", str(page), "--json", str(out)]
    r = subprocess.run(cmd + (["--quick"] if args.quick else []), cwd=ROOT, capture_output=True, text=True,
                       timeout=1800)
    if r.returncode != 0 or not out.exists():
        return {"error": (r.stderr or r.stdout).strip()[-800:]}
    return json.loads(out.read_text())


# ------------------------------------------------------------------------------------------------ checks
def sanity_checks() -> list[str]:
    """Cheap physics checks on cases met while building the suite; each returns a sentence for the report."""
    from rocking_model import RigidBlock, SinePulse, simulate

    out = []
    blk = RigidBlock(**S.PULSE_BLOCK)
    ag_c = blk.g * math.tan(blk.alpha)
    bad = []
    for factor in (1.0, 1.000005, 1.00005):
        for oi in (0.01, 0.02):
            r = simulate(blk, SinePulse(factor * ag_c, 2 * math.pi * 1.0), 4.0, scheme="event_driven",
                         tolerance=1e-8, output_interval=oi)
            if bool(r.overturned[-1]) or C.wrong_side({"phi": r.phi, "contact": r.contact}):
                bad.append(f"A = {factor:.7g}·g·tanα, output interval {oi:g} s: overturned = {bool(r.overturned[-1])}, "
                           f"{len(r.impact_times)} impacts, min φ {r.phi.min():.3g} rad with contact = 1 (left pivot, "
                           "φ ≥ 0)")
    if bad:
        out.append("**Bug (event-driven, grazing uplift)**: one-sine pulse at 1 Hz whose amplitude barely exceeds the "
                   "uplift threshold g·tanα, block b = 0.2, h = 1.0 — " + "; ".join(bad) + ". The block lifts for "
                   "a fraction of a step, φ returns through 0 inside the same DOP853 step, and the impact event "
                   "(armed only once it was seen positive at a step end) never fires: the block rocks on the left "
                   "corner with φ < 0, i.e. through the ground, and 'overturns'. Moreau-Jean keeps it at rest. "
                   "Reproduce: `simulate(RigidBlock(b=0.2, h=1.0), SinePulse(9.81*0.2, 2*math.pi), 4.0, "
                   "scheme='event_driven')` (amplitude exactly g·tanα: the block must not move at all).")
    else:
        out.append("Grazing-uplift check (pulse amplitude just above g·tanα): no overturning, no rotation on the wrong "
                   "side of the pivot.")
    try:
        from rocking_model import FlexibleOscillator
    except ImportError:
        return out
    t_rec, a_rec = S.synthetic_record()
    r = simulate(FlexibleOscillator(), (t_rec, a_rec * 0.15 / 0.4), 30.0, scheme="event_driven", tolerance=1e-10,
                 output_interval=0.01, hold="zoh")
    sol = {"phi": r.phi, "contact": r.contact}
    if C.wrong_side(sol) or bool(r.overturned[-1]):
        ws = ((r.contact == 1) & (r.phi < -1e-9)) | ((r.contact == 2) & (r.phi > 1e-9))
        i = int(np.argmax(ws)) if ws.any() else None
        out.append("**Bug (event-driven, rocking through the ground, flexible oscillator)**: default "
                   "`FlexibleOscillator()` under the synthetic record scaled to 0.15 g (zero-order hold, tolerance "
                   f"1e-10): overturned = {bool(r.overturned[-1])}"
                   + (f"; from t = {r.t[i]:.2f} s it rocks with contact = {r.contact[i]} (right pivot needs φ ≤ 0) at "
                      f"φ = {r.phi[i]:+.3g} rad and grows to ±π/2" if i is not None else "")
                   + ". Moreau-Jean at dt_max 2e-4 keeps max |φ| ≈ 0.02 rad and does not overturn; the event-driven "
                   "run with dt_max = 0.01/32 overturns at another time. Reproduce: `t, a = "
                   "benchmarks.scenes.synthetic_record(pga_g=0.15)`, `simulate(FlexibleOscillator(), (t, a), 30.0, "
                   "scheme='event_driven', tolerance=1e-10, hold='zoh')`.")
    fo = FlexibleOscillator(EI=S.FLEX_SOFT_EI)
    gm = SinePulse(S.FLEX_PULSE_G * S.G, 2 * math.pi * S.FLEX_PULSE_F)
    runs = {}
    for label, kw in (("tolerance 1e-12, dt_max 3.125e-4", dict(tolerance=1e-12, dt_max=3.125e-4)),
                      ("tolerance 1e-10", dict(tolerance=1e-10)),
                      ("tolerance 1e-10, dt_max 1.25e-3", dict(tolerance=1e-10, dt_max=1.25e-3))):
        runs[label] = simulate(fo, gm, 3.0, scheme="event_driven", output_interval=0.01, **kw)
    base = runs["tolerance 1e-12, dt_max 3.125e-4"]
    diffs = {k: float(np.max(np.abs(r.phi - base.phi))) for k, r in runs.items() if r is not base}
    if max(diffs.values()) > 1e-6:
        out.append("**Bug (event-driven, missed lift-off)**: flexible oscillator EI = 9.45e4 under the 0.25 g, 1.5 Hz "
                   "pulse, 3 s; max |φ| difference to tolerance 1e-12 / dt_max 3.125e-4: "
                   + ", ".join(f"{k}: {fe_(v)}" for k, v in diffs.items())
                   + ". After the impact at 1.7812 s (full contact) the release event is located at 1.811726 s, "
                   "but with the state taken a round-off beyond the root (relative corner force ≈ −3e-16) the "
                   "uplift LCP re-selects full contact; in the new segment the release event starts ≤ 0 and is "
                   "therefore disarmed, so the base stays glued until the next `advance` re-solves the LCP "
                   "(`_settle`, 1.82 s): lift-off up to one output interval late. Whether it happens depends on "
                   "dt_max and the tolerance (it also hits the reference if capped at grid/8, hence grid/32 here). "
                   "Reproduce: `simulate(FlexibleOscillator(EI=9.45e4), SinePulse(0.25*9.81, 3*math.pi), 3.0, "
                   "scheme='event_driven', tolerance=1e-10, dt_max=1.25e-3)` against the same without dt_max.")
    else:
        out.append("Lift-off check (flexible oscillator, event-driven with and without a step cap): consistent "
                   f"(max difference {max(diffs.values()):.1e} rad).")
    return out


def fe_(x: float) -> str:
    return f"{x:.1e}"


# ------------------------------------------------------------------------------------------------ main
def flexible_available() -> tuple[bool, str]:
    try:
        from rocking_model.models.flexible_oscillator import FlexibleOscillator  # noqa: F401
        return True, ""
    except Exception as exc:
        return False, f"rocking_model.models.flexible_oscillator not importable ({exc})"


def bench_friction(args) -> dict:
    """The friction reports, each its own script writing its own page: the mu = inf path against
    the pre-friction baseline and the finite-mu work-precision (docs/performance/friction.md), and the
    cross-check against Siconos' NewtonImpactFrictionNSL where Siconos is installed
    (docs/performance/siconos_friction.md). Returns {script: exit code}."""
    out = {}
    scripts = ["friction_performance.py"] + (["siconos_friction.py"] if args.siconos_ok else [])
    for name in scripts:
        log(f"friction: {name}")
        cmd = [sys.executable, str(ROOT / "benchmarks" / name)] + (["--quick"] if args.quick else [])
        out[name] = subprocess.run(cmd, cwd=ROOT).returncode
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description="rocking_model benchmark suite")
    ap.add_argument("--quick", action="store_true", help="smoke run: short scenes, two settings each (durations measured, with machine and load: "
                         "benchmarks/README.md)")
    ap.add_argument("--repeats", type=int, default=None, help="timed repeats per setting (default 3; quick 1)")
    ap.add_argument("--budget", type=float, default=6.0,
                    help="stop repeating a setting once its runs took this many seconds (default 6)")
    ap.add_argument("--skip-siconos", action="store_true")
    ap.add_argument("--skip-fmu", action="store_true")
    ap.add_argument("--skip-memory", action="store_true")
    ap.add_argument("--skip-ensemble", action="store_true",
                    help="skip the ensemble throughput (ensemble_bench.py, which writes docs/performance/ensemble.md)")
    ap.add_argument("--skip-friction", action="store_true",
                    help="skip the friction reports (friction_performance.py; siconos_friction.py where Siconos is "
                         "installed), which write docs/performance/friction*.md themselves")
    ap.add_argument("--scenes", nargs="*", help="only these scenes (free pulse_below pulse_above record "
                                                "flex_soft flex_stiff)")
    ap.add_argument("--docs", default=None, help="where to write performance.md and the plots "
                                                 "(default docs/; quick: benchmarks/results/quick/)")
    ap.add_argument("--report-only", action="store_true",
                    help="only rewrite the report and plots from the saved results json")
    args = ap.parse_args(argv)
    args.repeats = args.repeats if args.repeats is not None else (1 if args.quick else 3)
    docs = Path(args.docs) if args.docs else (ROOT / "benchmarks" / "results" / "quick" if args.quick
                                              else ROOT / "docs")
    results_file = (ROOT / "benchmarks" / "results" / ("quick/results.json" if args.quick else "latest.json"))
    if args.report_only:
        from benchmarks import report
        md = report.write_report(json.loads(results_file.read_text()), docs)
        log(f"wrote {md} from {results_file.relative_to(ROOT)}")
        return 0
    t_start = time.perf_counter()
    info = machine_info()
    log(f"machine: {info['cpu']}, {info['cores']} cores; {info['versions']}")
    res = {"info": info, "quick": args.quick, "repeats": args.repeats, "budget": args.budget, "min_total": C.MIN_TOTAL,
           "second_pass_rounds": SECOND_PASS_ROUNDS, "scenes": {},
           "skipped": {}}
    args.siconos_ok, why = (False, "--skip-siconos") if args.skip_siconos else C.siconos_available()
    if not args.siconos_ok:
        log(f"Siconos skipped: {why}")
        res["skipped"]["siconos"] = why
    scenes = S.rigid_scenes(args.quick)
    ok, why = flexible_available()
    if ok:
        scenes += S.flexible_scenes(args.quick)
    else:
        log(f"flexible scenes skipped: {why}")
        res["skipped"]["flexible"] = why
    if args.scenes:
        scenes = [s for s in scenes if s.name in args.scenes]
    for scene in scenes:
        try:
            res["scenes"][scene.name] = bench_scene(scene, args)
        except Exception as exc:  # keep going: report what failed
            import traceback
            log(f"scene {scene.name} FAILED: {exc!r}")
            res["scenes"][scene.name] = {"name": scene.name, "title": scene.title, "error": traceback.format_exc()}
    res["orders"] = bench_orders(args)
    res["checks"] = sanity_checks()
    if args.skip_fmu:
        res["skipped"]["fmu"] = "--skip-fmu"
    else:
        try:
            res["fmu"] = bench_fmu(args)
        except Exception:
            import traceback
            res["fmu"] = {"error": traceback.format_exc()}
            log("FMU benchmark FAILED:\n" + res["fmu"]["error"])
    try:
        res["compiled"] = bench_compiled(args)
    except Exception:
        import traceback
        res["compiled"] = {"error": traceback.format_exc()}
        log("compiled-engine benchmark FAILED:\n" + res["compiled"]["error"])
    if args.skip_memory:
        res["skipped"]["memory"] = "--skip-memory"
    else:
        # one run (the compiled engine, the only one): "memory_c" is the key the report's target reads
        res["memory"] = res["memory_c"] = bench_memory(args)
    if args.skip_ensemble:
        res["skipped"]["ensemble"] = "--skip-ensemble"
    else:
        res["ensemble"] = bench_ensemble(args)
    if args.skip_friction:
        res["skipped"]["friction"] = "--skip-friction"
    else:
        res["friction"] = bench_friction(args)
    res["total_wall"] = time.perf_counter() - t_start
    results_file.parent.mkdir(parents=True, exist_ok=True)
    results_file.write_text(json.dumps(res, indent=1, default=_json_default))
    from benchmarks import report
    md = report.write_report(res, docs)
    log(f"wrote {results_file.relative_to(ROOT)} and {md} in {res['total_wall']:.0f} s")
    return 0


def _json_default(o):
    if isinstance(o, (np.floating, np.integer)):
        return o.item()
    if isinstance(o, np.ndarray):
        return o.tolist()
    if isinstance(o, np.bool_):
        return bool(o)
    return str(o)


if __name__ == "__main__":
    sys.exit(main())
