"""Performance of Coulomb friction: the cost of the mu = inf path against the pre-friction
baseline, and the work-precision of both schemes on finite-mu scenes.

    .venv/bin/python benchmarks/friction_performance.py [--quick] [--baseline COMMIT] [--current COMMIT]

1. mu = inf overhead. The same mu = inf scenes (the paper's sticking law, which has a solution throughout
   them: nothing overturns, so both versions compute the same physics) are timed with the current package
   (the work tree this script sits in) and with the baseline package (``--baseline``, default eda5b07, the
   last commit before friction), checked out at run time into a temporary ``git worktree`` that is removed
   at the end (``--current COMMIT`` measures a commit the same way instead of the work tree, for a report
   that does not depend on edits in progress). Each version runs in its own fresh interpreter (``--runner``: the package imported from the
   given root by sys.path insertion), the two alternating A/B, B/A, ... over several repeats; per scene and
   scheme the best run of each version gives the ratio current / baseline (the median of the per-process
   best runs and the paired per-repeat ratios are reported to show the noise). The phi outputs of the two
   versions are compared (max |difference|, bit-identical or not). A ratio above ``--profile-threshold``
   (1.05) triggers a cProfile run of that case in both versions, and the report lists the functions whose
   own time grew.
2. Work-precision for finite mu (current package, in this process): a sliding block, a slide-rock block and
   a slide-rock flexible oscillator; reference event_driven at tolerance 1e-12; error = max over the 0.01 s
   output grid of max(|phi - phi_ref|, |slip - slip_ref| / L), L = the block's half-diagonal R or the
   flexible model's length_scale; event_driven tolerances 1e-4 ... 1e-10, moreau_jean dt_max 4e-3 ... 1.25e-4
   (halving), wall time best of 3.
3. Report: docs/performance/friction.md and docs/performance/friction_work_precision.png (with --quick:
   benchmarks/results/quick/, git-ignored, so that a smoke run never overwrites the committed report).

Speed is only ever stated as ratios measured in the same run; nothing here asserts a time.
"""
from __future__ import annotations

import os

# one BLAS thread in this process and in the runners: the same conditions for both versions, less noise
for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import cProfile  # noqa: E402
import datetime  # noqa: E402
import gc  # noqa: E402
import hashlib  # noqa: E402
import json  # noqa: E402
import math  # noqa: E402
import platform  # noqa: E402
import pstats  # noqa: E402
import statistics  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
REPORT = ROOT / "docs" / "performance" / "friction.md"
PLOT = ROOT / "docs" / "performance" / "friction_work_precision.png"
QUICK_DIR = ROOT / "benchmarks" / "results" / "quick"
DEFAULT_BASELINE = "eda5b07"
G = 9.81
GRID = 0.01

# ------------------------------------------------------------------------------------------------- scenes
#: the mu = inf scenes of the overhead comparison: plain data, built by the runner with whichever package
#: version it imported (the baseline has no mu: none is passed, the current default is mu = inf)
INF_SCENES = {
    "free": {
        "title": "rigid block, free rocking",
        "setup": "RigidBlock(b=0.2, h=1), released at rest from phi_0 = 0.1 rad, no ground motion, 5 s",
        "model": ["rigid", {"b": 0.2, "h": 1.0}], "motion": ["none"], "t_end": 5.0, "initial": {"phi_0": 0.1}},
    "two_sine": {
        "title": "rigid block, two-sine record",
        "setup": "RigidBlock(b=0.2, h=1), ag = 2.0 sin(2 pi 1.3 t) + 1.0 sin(2 pi 3.1 t) m/s2 sampled every "
                 "0.01 s ((t, ag) arrays, linear in between), at rest, 10 s",
        "model": ["rigid", {"b": 0.2, "h": 1.0}], "motion": ["two_sine", 2.0, 1.3, 1.0, 3.1], "t_end": 10.0,
        "initial": {}},
    "flex_pulse": {
        "title": "flexible oscillator, one-sine pulse",
        "setup": "FlexibleOscillator() (default parameters), one-sine pulse 0.3 g, period 0.6 s, at rest, 4 s",
        "model": ["flexible", {}], "motion": ["sine", 0.3 * G, 0.6], "t_end": 4.0, "initial": {}},
}
SCHEMES = {"event_driven": {"tolerance": 1e-8}, "moreau_jean": {"dt_max": 1e-3}}

#: the finite-mu work-precision scenes: (key, title, set-up, model kind, model kwargs, pulse (A/g, T), t_end)
WP_SCENES = [
    ("slide", "rigid block, sliding", "RigidBlock(b=0.3, h=0.6, mu=0.3) (tan alpha = 0.5), one-sine pulse "
     "ag = 0.6 g sin(4 pi t) for t <= 0.5 s, 2 s", "rigid", {"b": 0.3, "h": 0.6, "mu": 0.3}, (0.6, 0.5), 2.0),
    ("slide_rock", "rigid block, slide-rock", "RigidBlock(b=0.3, h=0.6, mu=0.52), one-sine pulse "
     "ag = 0.8 g sin(4 pi t) for t <= 0.5 s, 2 s", "rigid", {"b": 0.3, "h": 0.6, "mu": 0.52}, (0.8, 0.5), 2.0),
    ("flex_slide_rock", "flexible oscillator, slide-rock", "FlexibleOscillator(mu=0.2) (default parameters "
     "otherwise), one-sine pulse ag = 0.35 g sin(2 pi t / 0.6) for t <= 0.6 s, 3 s", "flexible", {"mu": 0.2},
     (0.35, 0.6), 3.0),
]
REF_TOL = 1e-12
ED_TOLS = (1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10)
MJ_DTS = (4e-3, 2e-3, 1e-3, 5e-4, 2.5e-4, 1.25e-4)
LEVELS = (1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8)

MODE_NAMES = {0: "full", 1: "left", 2: "right", 3: "flight", 4: "full slide +x", 5: "full slide -x",
              6: "left slide +x", 7: "left slide -x", 8: "right slide +x", 9: "right slide -x"}


def build_motion(rm, spec):
    kind = spec[0]
    if kind == "none":
        return 0.0
    if kind == "sine":
        return rm.SinePulse(spec[1], 2.0 * math.pi / spec[2])
    if kind == "two_sine":
        _, a1, f1, a2, f2 = spec
        t = np.arange(0.0, 10.0 + 1e-9, 0.01)
        return t, a1 * np.sin(2 * math.pi * f1 * t) + a2 * np.sin(2 * math.pi * f2 * t)
    raise ValueError(kind)


def build_model(rm, spec):
    kind, kw = spec
    return rm.RigidBlock(**kw) if kind == "rigid" else rm.FlexibleOscillator(**kw)


# ------------------------------------------------------------------------------------------------- runner
def _stat_key(filename: str, root: str) -> str:
    """A version-independent name of a profiled file: relative to the package root, else its tail."""
    if os.path.abspath(filename) == os.path.abspath(__file__):
        return "(runner)"
    for marker in ("site-packages" + os.sep, os.sep + "lib" + os.sep + "python"):
        if marker in filename:                   # numpy, scipy, the standard library: the same in both
            return filename.split(marker, 1)[1]
    if filename.startswith(root + os.sep):
        return os.path.relpath(filename, root)
    return filename


def runner_main(root: str, job_path: str, out_path: str) -> None:
    """Time the job's cases with the package found at ``root`` (a fresh interpreter per call)."""
    sys.path.insert(0, root)
    import rocking_model as rm
    where = Path(rm.__file__).resolve()
    if Path(root).resolve() not in where.parents:
        raise SystemExit(f"rocking_model imported from {where}, not from {root}")
    job = json.loads(Path(job_path).read_text())

    def run(scene_key, scheme, t_end=None):
        sc = INF_SCENES[scene_key]
        return rm.simulate(build_model(rm, sc["model"]), build_motion(rm, sc["motion"]),
                           sc["t_end"] if t_end is None else t_end, scheme=scheme, output_interval=GRID,
                           **sc["initial"], **SCHEMES[scheme])

    cases = [tuple(c) for c in job["cases"]]
    for scene_key, scheme in cases:              # warm-up: every code path once (lazy imports, caches)
        run(scene_key, scheme, t_end=min(1.0, INF_SCENES[scene_key]["t_end"]))
    out = {"file": str(where), "cases": {}, "profiles": {}}
    for scene_key, scheme in cases:
        times, res = [], None
        limits = job["runs"][scheme]
        while len(times) < limits["min"] or (len(times) < limits["max"] and sum(times) < limits["budget"]):
            gc.collect()
            t0 = time.perf_counter()
            res = run(scene_key, scheme)
            times.append(time.perf_counter() - t0)
        out["cases"][f"{scene_key}/{scheme}"] = {
            "times": times, "phi": np.asarray(res.phi, float).tolist(), "x": np.asarray(res.x, float).tolist(),
            "n_steps": int(res.n_steps), "impacts": int(res.impacts[-1]), "overturned": bool(res.overturned[-1]),
            "max_phi": float(np.max(np.abs(res.phi)))}
    for key in job.get("profile", []):
        # the profiled run with the least total own time of a few (the others carry the machine's noise)
        scene_key, scheme = key.split("/")
        best = None
        for _ in range(job.get("profile_repeats", 3)):
            gc.collect()
            prof = cProfile.Profile()
            prof.enable()
            run(scene_key, scheme)
            prof.disable()
            agg: dict = {}
            for (fn, _line, func), (_cc, nc, tt, ct, _callers) in pstats.Stats(prof).stats.items():
                name = f"{_stat_key(fn, root)}:{func}"
                a = agg.setdefault(name, [0, 0.0, 0.0])
                a[0] += nc
                a[1] += tt
                a[2] += ct
            if best is None or sum(v[1] for v in agg.values()) < sum(v[1] for v in best.values()):
                best = agg
        out["profiles"][key] = best
    Path(out_path).write_text(json.dumps(out))


def run_runner(root: Path, job: dict, tmp: Path, tag: str) -> dict:
    job_path, out_path = tmp / f"job_{tag}.json", tmp / f"out_{tag}.json"
    job_path.write_text(json.dumps(job))
    proc = subprocess.run([sys.executable, str(Path(__file__).resolve()), "--runner", str(root), str(job_path),
                           str(out_path)], capture_output=True, text=True, cwd=str(tmp))
    if proc.returncode != 0 or not out_path.exists():
        raise RuntimeError(f"runner for {root} failed (exit {proc.returncode}):\n{proc.stderr[-3000:]}")
    return json.loads(out_path.read_text())


# ------------------------------------------------------------------------------------------------- part 1
def git(*args, check=True) -> str:
    proc = subprocess.run(["git", "--no-optional-locks", "-C", str(ROOT), *args], capture_output=True, text=True)
    if check and proc.returncode != 0:
        raise RuntimeError(f"git {' '.join(args)}: {proc.stderr.strip()}")
    return proc.stdout.strip()


def source_hash(root: Path) -> str:
    h = hashlib.sha256()
    for p in sorted((root / "rocking_model").rglob("*.py")):
        h.update(str(p.relative_to(root)).encode())
        h.update(p.read_bytes())
    return h.hexdigest()[:12]


def overhead(base_root: Path, tmp: Path, repeats: int, runs: dict, threshold: float, force_profile: bool,
             profile_repeats: int = 3, cur_root: Path = ROOT) -> dict:
    cases = [[s, sch] for s in INF_SCENES for sch in SCHEMES]
    roots = {"current": cur_root, "baseline": base_root}
    per = {"current": [], "baseline": []}
    order_log = []
    for r in range(repeats):
        order = ("current", "baseline") if r % 2 == 0 else ("baseline", "current")
        for v in order:
            t0 = time.perf_counter()
            per[v].append(run_runner(roots[v], {"cases": cases, "runs": runs}, tmp, f"{v}_{r}"))
            order_log.append((v, time.perf_counter() - t0))
            print(f"  overhead repeat {r + 1}/{repeats}: {v} ({order_log[-1][1]:.1f} s)", flush=True)
    rows = []
    for s, sch in cases:
        key = f"{s}/{sch}"
        mins = {v: [min(o["cases"][key]["times"]) for o in per[v]] for v in per}
        nruns = {v: sum(len(o["cases"][key]["times"]) for o in per[v]) for v in per}
        paired = [c / b for c, b in zip(mins["current"], mins["baseline"])]
        cur, base = per["current"][-1]["cases"][key], per["baseline"][-1]["cases"][key]
        phi_c, phi_b = np.array(cur["phi"]), np.array(base["phi"])
        x_c, x_b = np.array(cur["x"]), np.array(base["x"])
        rows.append({
            "scene": s, "scheme": sch, "key": key,
            "best": {v: min(mins[v]) for v in per}, "median": {v: statistics.median(mins[v]) for v in per},
            "runs": nruns, "ratio_best": min(mins["current"]) / min(mins["baseline"]),
            "ratio_median": statistics.median(mins["current"]) / statistics.median(mins["baseline"]),
            "paired": paired,
            "dphi": float(np.max(np.abs(phi_c - phi_b))) if phi_c.shape == phi_b.shape else math.inf,
            "dx": float(np.max(np.abs(x_c - x_b))) if x_c.shape == x_b.shape else math.inf,
            "identical": bool(phi_c.shape == phi_b.shape and np.array_equal(phi_c, phi_b)),
            "identical_x": bool(x_c.shape == x_b.shape and np.array_equal(x_c, x_b)),
            "n_steps": (cur["n_steps"], base["n_steps"]), "impacts": (cur["impacts"], base["impacts"]),
            "overturned": (cur["overturned"], base["overturned"]), "max_phi": cur["max_phi"],
            # every process of a version must give the same phi (determinism)
            "stable": all(o["cases"][key]["phi"] == per[v][0]["cases"][key]["phi"] for v in per for o in per[v]),
        })
    # above the threshold by the best runs or by the medians (a case near it is profiled either way)
    slow = [r["key"] for r in rows if max(r["ratio_best"], r["ratio_median"]) > threshold
            or (force_profile and r["ratio_best"] > 1.0)]
    profiles = {}
    if slow:
        print(f"  profiling {', '.join(slow)} in both versions", flush=True)
        for v in ("current", "baseline"):
            out = run_runner(roots[v], {"cases": [k.split("/") for k in slow], "profile": slow,
                                        "profile_repeats": profile_repeats,
                                        "runs": {sch: {"min": 1, "max": 1, "budget": 0.0} for sch in SCHEMES}},
                             tmp, f"{v}_profile")
            profiles[v] = out["profiles"]
    return {"rows": rows, "repeats": repeats, "runs": runs, "order": order_log, "profiles": profiles,
            "slow": slow, "threshold": threshold,
            "files": {v: per[v][0]["file"] for v in per}}


def profile_diff(prof: dict, key: str, top: int = 12) -> tuple[list, float, float]:
    """Functions of the case ``key`` sorted by the growth of their own time (current - baseline)."""
    cur, base = prof["current"][key], prof["baseline"][key]
    rows = []
    for name in set(cur) | set(base):
        c, b = cur.get(name, [0, 0.0, 0.0]), base.get(name, [0, 0.0, 0.0])
        rows.append((name, c[0], b[0], c[1], b[1], c[2], b[2]))
    rows.sort(key=lambda r: r[3] - r[4], reverse=True)
    tot_c, tot_b = sum(v[1] for v in cur.values()), sum(v[1] for v in base.values())
    return rows[:top], tot_c, tot_b


# ------------------------------------------------------------------------------------------------- part 2
def work_precision(quick: bool, root: Path = ROOT) -> dict:
    sys.path.insert(0, str(root))
    import rocking_model as rm
    if Path(root).resolve() not in Path(rm.__file__).resolve().parents:
        raise RuntimeError(f"rocking_model imported from {rm.__file__}, not from {root}")
    tols = (1e-4, 1e-6, 1e-8) if quick else ED_TOLS
    dts = MJ_DTS[:3] if quick else MJ_DTS
    best_of = 1 if quick else 3
    out = {}
    for key, title, setup, kind, kw, (a_g, period), t_end in WP_SCENES:
        def run(scheme, **settings):
            model = build_model(rm, [kind, kw])
            t0 = time.perf_counter()
            res = rm.simulate(model, rm.SinePulse(a_g * G, 2 * math.pi / period), t_end, scheme=scheme,
                              output_interval=GRID, **settings)
            return res, time.perf_counter() - t0

        model = build_model(rm, [kind, kw])
        L = model.R if kind == "rigid" else model.length_scale
        ref, ref_time = run("event_driven", tolerance=REF_TOL)
        alt, _ = run("event_driven", tolerance=REF_TOL, dt_max=GRID / 8)

        def err(res):
            e_phi = np.abs(np.asarray(res.phi) - ref.phi)
            e_slip = np.abs(np.asarray(res.slip) - ref.slip) / L
            e = np.maximum(e_phi, e_slip)
            return float(np.max(e)), float(np.max(e_phi)), float(np.max(e_slip)), float(ref.t[int(np.argmax(e))])

        floor = err(alt)[0]
        modes = []
        for c in np.asarray(ref.contact, int):
            if not modes or modes[-1] != c:
                modes.append(int(c))
        scene = {"title": title, "setup": setup, "L": L, "t_end": t_end, "floor": floor,
                 "ref": {"time": ref_time, "n_steps": int(ref.n_steps), "impacts": int(ref.impacts[-1]),
                         "max_phi": float(np.max(np.abs(ref.phi))), "max_slip": float(np.max(np.abs(ref.slip))),
                         "final_slip": float(ref.slip[-1]), "painleve": bool(np.any(ref.painleve)),
                         "overturned": bool(ref.overturned[-1]), "modes": modes,
                         "friction_demand": float(np.nanmax(np.asarray(ref.friction_demand, float)))},
                 "runs": []}
        sweep = [("event_driven", "tolerance", tol) for tol in tols] + [("moreau_jean", "dt_max", dt) for dt in dts]
        for scheme, name, value in sweep:
            times, res = [], None
            for _ in range(best_of):
                gc.collect()
                res, dt_wall = run(scheme, **{name: value})
                times.append(dt_wall)
            e, e_phi, e_slip, t_err = err(res)
            scene["runs"].append({"scheme": scheme, "setting": name, "value": value, "time": min(times),
                                  "times": times, "n_steps": int(res.n_steps), "error": e, "error_phi": e_phi,
                                  "error_slip": e_slip, "t_error": t_err, "impacts": int(res.impacts[-1]),
                                  "painleve": bool(np.any(res.painleve)), "overturned": bool(res.overturned[-1])})
        out[key] = scene
        print(f"  work-precision {key}: done", flush=True)
    return out


def front(points):
    """(time, error) pairs -> the Pareto front sorted by time (each point more accurate than the cheaper)."""
    pts, out, best = sorted(points), [], math.inf
    for t, e in pts:
        if e < best:
            out.append((t, e))
            best = e
    return out


def time_at(points, level):
    """Time the front needs for error <= level: (time, exact?) ; None if never reached. Log-log
    interpolation between the last front point above the level and the first below it; when the cheapest
    run is already below, (its time, False): an upper bound."""
    f = front(points)
    for i, (t, e) in enumerate(f):
        if e <= level:
            if i == 0:
                return t, False
            t0, e0 = f[i - 1]
            if e <= 0:
                return t, False
            w = (math.log(level) - math.log(e0)) / (math.log(e) - math.log(e0))
            return math.exp(math.log(t0) + w * (math.log(t) - math.log(t0))), True
    return None


# ------------------------------------------------------------------------------------------------- report
def fmt_ms(s: float) -> str:
    ms = s * 1e3
    return f"{ms:.3g} ms" if ms < 1000 else f"{s:.3g} s"


def plot(wp: dict, path: Path) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, len(wp), figsize=(5.0 * len(wp), 4.6), squeeze=False)
    for ax, (key, sc) in zip(axes[0], wp.items()):
        for scheme, style, label in (("event_driven", "o-", "event-driven (tolerance 1e-4 ... 1e-10)"),
                                     ("moreau_jean", "s--", "Moreau-Jean (dt_max 4e-3 ... 1.25e-4 s)")):
            runs = [r for r in sc["runs"] if r["scheme"] == scheme]
            t = [r["time"] for r in runs]
            e = [max(r["error"], 1e-16) for r in runs]
            ax.loglog(t, e, style, label=label, ms=5)
            for r, ti, ei in zip(runs, t, e):
                ax.annotate(f"{r['value']:.0e}" if scheme == "event_driven" else f"{r['value']:g}", (ti, ei),
                            textcoords="offset points", xytext=(4, 3), fontsize=6.5, color="0.35")
        ax.axhline(max(sc["floor"], 1e-16), color="0.5", lw=0.8, ls=":",
                   label=f"reference floor ({sc['floor']:.1e})")
        ax.set_title(f"{key}: {sc['title']}", fontsize=10)
        ax.set_xlabel("wall time per run [s] (best of 3)")
        ax.set_ylabel("max error: max(|Δφ| [rad], |Δslip| / L) [1]")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7.5, loc="upper center", bbox_to_anchor=(0.5, -0.16), ncol=1, frameon=False)
    fig.suptitle("Coulomb friction (finite mu): error against the event-driven reference (tolerance 1e-12) "
                 "vs wall time", fontsize=11)
    fig.tight_layout()
    fig.savefig(path, dpi=110, bbox_inches="tight")
    plt.close(fig)


def machine_info() -> dict:
    if str(ROOT) not in sys.path:
        sys.path.insert(0, str(ROOT))
    from benchmarks.machine import cpu_name
    cpu = cpu_name()
    import scipy
    try:
        load = ", ".join(f"{x:.2f}" for x in os.getloadavg())
    except OSError:
        load = "n/a"
    return {"cpu": cpu, "cores": os.cpu_count(), "platform": platform.platform(),
            "python": platform.python_version(), "numpy": np.__version__, "scipy": scipy.__version__, "load": load}


def write_report(path: Path, plot_name: str, info: dict, ov: dict, wp: dict, quick: bool) -> None:
    L = ["# Performance of Coulomb friction", "",
         f"Generated by `benchmarks/friction_performance.py{info['args']}` on {info['date']} "
         f"({info['wall']:.0f} s wall). **Do not edit by hand**: re-run the script "
         "(`.venv/bin/python benchmarks/friction_performance.py`; `--quick` for a smoke run "
         "written to `benchmarks/results/quick/`).", "",
         f"- Machine: {info['machine']['cpu']}, {info['machine']['cores']} cores, {info['machine']['platform']}; "
         f"load average at start {info['machine']['load']}, at the end {info['load_end']}",
         f"- Versions: python {info['machine']['python']}, numpy {info['machine']['numpy']}, scipy "
         f"{info['machine']['scipy']}",
         (f"- Current package: commit {info['head']}, checked out into a temporary `git worktree` (`--current`)"
          if info.get("current_commit") else
          f"- Current package: the work tree at commit {info['head']}"
          + (f" with uncommitted changes in {info['dirty']} file(s) under rocking_model/" if info["dirty"] else ""))
         + f" (sources hash {info['hash_start']})",
         f"- Baseline package: commit {info['baseline']} (before friction), checked out into a temporary "
         "`git worktree` for the run and removed afterwards",
         ""]
    if info["hash_start"] != info["hash_end"]:
        L += ["**Warning**: rocking_model/ changed during the run (sources hash "
              f"{info['hash_start']} at the start, {info['hash_end']} at the end); re-run on a quiet tree.", ""]
    # ---------------------------------------------------------------- part 1
    runs = ov["runs"]
    L += ["## 1. The mu = inf path against the baseline", "",
          "The target: the mu = inf path (the paper's sticking law, still the default) be no slower than "
          "before friction. The same scenes are timed with both versions, each in its own fresh interpreter "
          "(the package imported from its root by sys.path insertion), the versions alternating "
          f"A/B, B/A, ... over {ov['repeats']} repeats (A = current, B = baseline; {2 * ov['repeats']} processes). "
          "In every process each case runs once shortened to 1 s as a warm-up, then "
          f"{runs['event_driven']['min']}-{runs['event_driven']['max']} times (event-driven, until "
          f"{runs['event_driven']['budget']:g} s are used) or {runs['moreau_jean']['min']} times (Moreau-Jean); "
          "`time.perf_counter` around the whole `simulate(...)` call (model set-up included), `gc.collect()` "
          "before each run, one BLAS thread. **best** = fastest run over all processes of a version; "
          "**median** = median over the processes of each process's fastest run; **paired** = the per-repeat "
          "ratios of the processes' fastest runs (min ... max), which shows the noise of the machine.", "",
          "| scene | set-up | max \\|phi\\| [rad] | impacts | steps (ED / MJ) |", "|---|---|---|---|---|"]
    rows = {r["key"]: r for r in ov["rows"]}
    for s, sc in INF_SCENES.items():
        ed, mj = rows[f"{s}/event_driven"], rows[f"{s}/moreau_jean"]
        L.append(f"| {s} | {sc['setup']} | {ed['max_phi']:.4f} | {ed['impacts'][0]} (ED), {mj['impacts'][0]} "
                 f"(MJ) | {ed['n_steps'][0]} / {mj['n_steps'][0]} |")
    L += ["", "Schemes: `event_driven` with `tolerance=1e-8`, `moreau_jean` with `dt_max=1e-3`; output every "
          "0.01 s. Nothing overturns (the sticking law has a solution throughout).", "",
          "| scene | scheme | current best | baseline best | **ratio best** | current median | baseline median | "
          "ratio median | paired ratios | runs (cur / base) |",
          "|---|---|---|---|---|---|---|---|---|---|"]
    for r in ov["rows"]:
        L.append(f"| {r['scene']} | {r['scheme']} | {fmt_ms(r['best']['current'])} | {fmt_ms(r['best']['baseline'])} "
                 f"| **{r['ratio_best']:.3f}** | {fmt_ms(r['median']['current'])} | "
                 f"{fmt_ms(r['median']['baseline'])} | {r['ratio_median']:.3f} | {min(r['paired']):.3f} ... "
                 f"{max(r['paired']):.3f} | {r['runs']['current']} / {r['runs']['baseline']} |")
    worst = max(ov["rows"], key=lambda r: r["ratio_best"])
    geo = math.exp(statistics.fmean(math.log(r["ratio_best"]) for r in ov["rows"]))
    best_ratio = min(ov["rows"], key=lambda r: r["ratio_best"])
    thr = 100 * (ov["threshold"] - 1)
    L += ["", f"Geometric mean of the best-run ratios: {geo:.3f}; range {best_ratio['ratio_best']:.3f} "
          f"({best_ratio['key']}) ... {worst['ratio_best']:.3f} ({worst['key']}).", "",
          (f"**Verdict: 'the mu = inf path is no slower than today' is met** (no case more than {thr:.0f} % "
           "slower than the baseline, the noise of the paired ratios included)." if not ov["slow"] else
           f"**Verdict: 'the mu = inf path is no slower than today' is not met**: {len(ov['slow'])} of "
           f"{len(ov['rows'])} cases are more than {thr:.0f} % slower than the baseline by the best runs or "
           "the medians "
           f"({', '.join(ov['slow'])}; profiled below)."), ""]
    L += ["### Agreement of the outputs", "",
          "phi (and x) of the last process of each version on the 0.01 s grid; every process of a version gave "
          "the same phi (deterministic) unless said otherwise.", "",
          "| scene | scheme | max \\|phi_current - phi_baseline\\| [rad] | phi bit-identical | max \\|dx\\| [m] | "
          "steps current / baseline | impacts current / baseline |", "|---|---|---|---|---|---|---|"]
    for r in ov["rows"]:
        L.append(f"| {r['scene']} | {r['scheme']} | {r['dphi']:.2e} | {'yes' if r['identical'] else 'no'}"
                 f"{'' if r['stable'] else ' (runs of a version differ!)'} | {r['dx']:.2e} | "
                 f"{r['n_steps'][0]} / {r['n_steps'][1]} | {r['impacts'][0]} / {r['impacts'][1]} |")
    n_ident = sum(r["identical"] for r in ov["rows"])
    L += ["", f"{n_ident} of {len(ov['rows'])} cases are bit-identical in phi; the largest difference is "
          f"{max(r['dphi'] for r in ov['rows']):.2e} rad. Steps and impacts are the same in "
          f"{sum(r['n_steps'][0] == r['n_steps'][1] and r['impacts'][0] == r['impacts'][1] for r in ov['rows'])}"
          f" of {len(ov['rows'])} cases."]
    if any(r["dx"] > 1e-12 and r["dphi"] < 1e-10 for r in ov["rows"]):
        L += ["", "Where x differs while phi agrees: x, the base's horizontal position, does not enter the "
              "rocking dynamics (horizontal translation is a symmetry), so this is a change of the x output, "
              "not of the motion. Found for flex_pulse when this script was written: event-driven, the baseline "
              "put the base back at its rest abscissa when it landed after a short flight (x jumps by 4.8e-5 m "
              "at t = 1.61 s), the current version keeps it where it lands (x continuous); Moreau-Jean, at the "
              "pivot switch at t = 0.45 s the baseline put x back to ~1e-11 m, the current version keeps the "
              "step's O(dt) offset of 8e-6 m. The offset then stays constant."]
    L.append("")
    if ov["profiles"]:
        L += ["### Profile of the cases above the threshold", "",
              "cProfile in each version, the profiled run with the least total own time of "
              f"{1 if quick else 3} (profiling inflates the times; the differences are what matters). Functions sorted by the growth of their own time (tottime); file paths relative to the "
              "package root.", ""]
        for key in ov["slow"]:
            top, tc, tb = profile_diff(ov["profiles"], key)
            cur, base = ov["profiles"]["current"][key], ov["profiles"]["baseline"][key]
            new = {n: v for n, v in cur.items() if n not in base}
            grown = sum(max(0.0, v[1] - base[n][1]) for n, v in cur.items() if n in base)
            new_top = sorted(new.items(), key=lambda kv: kv[1][1], reverse=True)[:6]
            L += [f"**{key}**: total own time {tc:.3f} s current, {tb:.3f} s baseline ({tc - tb:+.3f} s); "
                  f"functions absent from the baseline: {1e3 * sum(v[1] for v in new.values()):.1f} ms of own "
                  f"time ({', '.join(f'`{n.split(chr(58))[-1]}` {1e3 * v[1]:.1f}' for n, v in new_top)}); "
                  f"growth of the own time of functions present in both: {1e3 * grown:.1f} ms.", "",
                  "| function | calls cur / base | tottime cur / base [ms] | cumtime cur / base [ms] |",
                  "|---|---|---|---|"]
            for name, nc, nb, tt_c, tt_b, ct_c, ct_b in top:
                L.append(f"| `{name}` | {nc} / {nb} | {1e3 * tt_c:.1f} / {1e3 * tt_b:.1f} | "
                         f"{1e3 * ct_c:.1f} / {1e3 * ct_b:.1f} |")
            L.append("")
    # ---------------------------------------------------------------- part 2
    L += ["## 2. Work-precision with finite mu", "",
          "Current package, in the driver process. Reference: `event_driven` at tolerance "
          f"{REF_TOL:g}. Error = max over the 0.01 s output grid of max(\\|phi - phi_ref\\| [rad], "
          "\\|slip - slip_ref\\| / L), with L the block's half-diagonal R or the flexible model's `length_scale`; "
          "slip is the `slip` output (the base corner's horizontal displacement). *Floor* = the same error of "
          f"the reference against event-driven at tolerance {REF_TOL:g} with its steps capped at 0.01/8 s (another "
          "step sequence): errors below it are not resolved. Wall time: best of "
          f"{1 if quick else 3} runs of the whole `simulate(...)` call.", "",
          "| scene | set-up | L [m] | reference | floor |", "|---|---|---|---|---|"]
    for key, sc in wp.items():
        ref = sc["ref"]
        modes = ", ".join(MODE_NAMES.get(m, str(m)) for m in ref["modes"])
        L.append(f"| {key} | {sc['setup']} | {sc['L']:.4f} | {fmt_ms(ref['time'])}, {ref['n_steps']} steps, "
                 f"{ref['impacts']} impacts, max \\|phi\\| {ref['max_phi']:.4f} rad, max \\|slip\\| "
                 f"{ref['max_slip']:.4f} m (final {ref['final_slip']:+.4f} m), modes: {modes}"
                 f"{', Painleve' if ref['painleve'] else ''}{', overturns' if ref['overturned'] else ''} | "
                 f"{sc['floor']:.1e} |")
    L += ["", f"![work-precision]({plot_name})", ""]
    for key, sc in wp.items():
        L += [f"**{key}** ({sc['title']})", "",
              "| scheme | setting | wall time | steps | error (at t [s]) | \\|dphi\\| [rad] | \\|dslip\\| / L | "
              "impacts |", "|---|---|---|---|---|---|---|---|"]
        for r in sc["runs"]:
            flag = " (below floor)" if r["error"] < sc["floor"] else ""
            L.append(f"| {r['scheme']} | {r['setting']} = {r['value']:g} | {fmt_ms(r['time'])} | {r['n_steps']} | "
                     f"{r['error']:.2e}{flag} ({r['t_error']:.2f}) | {r['error_phi']:.2e} | {r['error_slip']:.2e} | {r['impacts']}"
                     f"{' Painleve' if r['painleve'] else ''}{' overturned' if r['overturned'] else ''} |")
        L.append("")
    L += ["### Equal error", "",
          "Time each scheme needs for a given error (log-log interpolation on its work-precision front; *≤*: its "
          "cheapest run is already below the level, an upper bound; n/r: not reached). Ratio = Moreau-Jean / "
          "event-driven (> 1: event-driven faster); levels below a scene's floor are left out.", "",
          "| scene | error | event-driven | Moreau-Jean | MJ / ED |", "|---|---|---|---|---|"]
    summary = []
    for key, sc in wp.items():
        pts = {s: [(r["time"], r["error"]) for r in sc["runs"] if r["scheme"] == s]
               for s in ("event_driven", "moreau_jean")}
        for level in LEVELS:
            if level < sc["floor"]:
                continue
            ed, mj = time_at(pts["event_driven"], level), time_at(pts["moreau_jean"], level)
            if ed is None and mj is None:
                continue

            def cell(v):
                return "n/r" if v is None else (fmt_ms(v[0]) if v[1] else f"≤ {fmt_ms(v[0])}")
            if ed and mj:
                bound = {(True, True): "", (False, True): "≥ ", (True, False): "≤ "}
                ratio = (f"{bound[(ed[1], mj[1])]}{mj[0] / ed[0]:.3g}×" if ed[1] or mj[1] else
                         "– (both bounds)")
            else:
                ratio = "–"
            L.append(f"| {key} | {level:.0e} | {cell(ed)} | {cell(mj)} | {ratio} |")
        # headline: the finest Moreau-Jean run against the cheapest event-driven run at least as accurate
        mj_runs = [r for r in sc["runs"] if r["scheme"] == "moreau_jean"]
        ed_runs = [r for r in sc["runs"] if r["scheme"] == "event_driven"]
        fine = min(mj_runs, key=lambda r: r["error"])
        good = [r for r in ed_runs if r["error"] <= fine["error"]]
        cheap = min(good, key=lambda r: r["time"]) if good else None
        summary.append((key, fine, cheap, min(ed_runs, key=lambda r: r["error"]),
                        min(r["time"] for r in ed_runs), max(r["time"] for r in ed_runs)))
    L += ["", "### Interpretation", ""]
    for key, fine, cheap, ed_best, ed_tmin, ed_tmax in summary:
        if cheap:
            L.append(f"- **{key}**: Moreau-Jean's most accurate run (dt_max = {fine['value']:g} s) reaches "
                     f"{fine['error']:.1e} in {fmt_ms(fine['time'])}; event-driven is at least as accurate "
                     f"({cheap['error']:.1e}) already at tolerance {cheap['value']:.0e} in {fmt_ms(cheap['time'])}: "
                     f"**{fine['time'] / cheap['time']:.0f}× faster at equal (or better) error**. Event-driven "
                     f"spans {fmt_ms(ed_tmin)} ... {fmt_ms(ed_tmax)} for errors down to {ed_best['error']:.1e}.")
        else:
            L.append(f"- **{key}**: no event-driven run is as accurate as Moreau-Jean at dt_max = "
                     f"{fine['value']:g} s ({fine['error']:.1e}).")
    mj_orders = []
    for key, sc in wp.items():
        mj_runs = [r for r in sc["runs"] if r["scheme"] == "moreau_jean" and r["error"] > 0]
        if len(mj_runs) >= 2:
            a, b = mj_runs[0], mj_runs[-1]
            mj_orders.append(f"{key} {math.log(a['error'] / b['error']) / math.log(a['value'] / b['value']):.2f}")
    per_step = ""
    ed_fin = [(key, r) for key, sc in wp.items() for r in sc["runs"]
              if r["scheme"] == "event_driven" and r["value"] == 1e-8]
    ed_inf = [r for r in ov["rows"] if r["scheme"] == "event_driven"]
    if ed_fin and ed_inf:
        per_step = (" (wall time per event-driven step at tolerance 1e-8, which also carries the per-event and "
                    "per-output-sample costs: " + ", ".join(f"{k} {1e6 * r['time'] / r['n_steps']:.0f} µs"
                                                           for k, r in ed_fin)
                    + " with finite mu, against " + ", ".join(
                        f"{r['scene']} {1e6 * r['best']['current'] / r['n_steps'][0]:.0f} µs" for r in ed_inf)
                    + " on the mu = inf scenes of part 1)")
    mj_fin = [(key, r) for key, sc in wp.items() for r in sc["runs"]
              if r["scheme"] == "moreau_jean" and r["value"] == 1e-3]
    mj_inf = [r for r in ov["rows"] if r["scheme"] == "moreau_jean"]
    mj_step = ""
    if mj_fin and mj_inf:
        mj_step = (" (wall time per Moreau-Jean step at dt_max = 1e-3: " + ", ".join(
            f"{k} {1e6 * r['time'] / r['n_steps']:.0f} µs" for k, r in mj_fin) + " with finite mu, against "
            + ", ".join(f"{r['scene']} {1e6 * r['best']['current'] / r['n_steps'][0]:.0f} µs" for r in mj_inf)
            + " with mu = inf)")
    bumps = []
    for key, sc in wp.items():
        for scheme in ("event_driven", "moreau_jean"):
            rs = [r for r in sc["runs"] if r["scheme"] == scheme]
            up = [r for a, r in zip(rs, rs[1:]) if r["error"] > 1.5 * a["error"] and r["error"] > 10 * sc["floor"]]
            flat = [r for a, r in zip(rs, rs[1:]) if a["error"] / 1.5 <= r["error"] <= 1.5 * a["error"]]
            if up or flat:
                bumps.append(f"{key} {scheme}: " + ", ".join(
                    [f"larger error at {r['setting']} = {r['value']:g} ({r['error']:.1e} at t = "
                     f"{r['t_error']:.2f} s)" for r in up] +
                    [f"no gain at {r['setting']} = {r['value']:g} ({r['error']:.1e})" for r in flat if r not in up]))
    L += [f"- Moreau-Jean converges at order about one or below (fitted between its coarsest and finest dt_max: "
          f"{', '.join(mj_orders)}), as expected of an impulsive time-stepper with impacts and stick-slip "
          "transitions inside steps; its cost grows like 1/dt_max, so each extra digit costs it about ten "
          "times the time. Event-driven locates the impacts, lift-offs, stick-slip transitions and slip stops "
          "as events; its cost grows slowly with the tolerance (on the rigid scenes hardly at all: most of it "
          "is per phase and per output sample, not per step).",
          "- The errors are not monotone in the setting everywhere (a step that moves an impact or a "
          "stick-slip transition across an output time, or an impact that amplifies an earlier error): "
          + ("; ".join(bumps) if bumps else "none here") + ".",
          "- Event-driven with a finite mu integrates the sliding phases with generic numpy code (the sliding "
          "equations of motion assembled and solved as small linear systems at every right-hand-side "
          "evaluation, in the Python reference engine these figures were measured on), which is slower per step than the closed-form "
          "right-hand sides of the sticking phases (rocking, full contact) that mu = inf uses; the sliding "
          f"scenes' event-driven times above include that cost{per_step}. Moreau-Jean with a finite mu solves the "
          "frictional contact LCP (open / stick / slide forward / slide back per contact) at each step, more "
          f"expensive than the frictionless one when both corners are closed (full-contact sliding){mj_step}.",
          "- The mu = inf path (part 1) keeps the baseline's cost within the noise shown by the paired ratios, "
          "with the outputs above."
          if not ov["slow"] else
          f"- The mu = inf path (part 1) is slower than the baseline in {', '.join(ov['slow'])}; see the "
          "profile.", ""]
    path.write_text("\n".join(L))


# ------------------------------------------------------------------------------------------------- main
def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="smoke run, written to benchmarks/results/quick/")
    ap.add_argument("--baseline", default=DEFAULT_BASELINE, help="commit of the baseline package (default: "
                    f"{DEFAULT_BASELINE}, before friction)")
    ap.add_argument("--current", default=None, metavar="COMMIT",
                    help="measure this commit (checked out into a temporary worktree) instead of the work tree, "
                    "e.g. HEAD while the work tree is being edited")
    ap.add_argument("--repeats", type=int, default=None, help="A/B repeats of the overhead part (default 6, "
                    "quick 2)")
    ap.add_argument("--profile-threshold", type=float, default=1.05,
                    help="profile the mu = inf cases whose ratio current/baseline exceeds this (default 1.05)")
    ap.add_argument("--profile", action="store_true", help="profile every mu = inf case slower than the baseline")
    ap.add_argument("--skip-work-precision", action="store_true")
    ap.add_argument("--runner", nargs=3, metavar=("ROOT", "JOB", "OUT"), help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.runner:
        runner_main(*args.runner)
        return 0

    t_start = time.perf_counter()
    quick = args.quick
    repeats = args.repeats or (2 if quick else 6)
    runs = ({"event_driven": {"min": 2, "max": 5, "budget": 0.1}, "moreau_jean": {"min": 1, "max": 1, "budget": 0.0}}
            if quick else
            {"event_driven": {"min": 5, "max": 30, "budget": 0.4}, "moreau_jean": {"min": 2, "max": 2, "budget": 0.0}})
    out_dir = QUICK_DIR if quick else REPORT.parent
    out_dir.mkdir(parents=True, exist_ok=True)
    report = out_dir / REPORT.name
    plot_path = out_dir / PLOT.name
    baseline = git("rev-parse", "--short", f"{args.baseline}^{{commit}}")
    current = git("rev-parse", "--short", f"{args.current}^{{commit}}") if args.current else None
    info = {"date": datetime.datetime.now().strftime("%Y-%m-%d %H:%M"), "machine": machine_info(),
            "args": "".join(" " + a for a in (sys.argv[1:] if argv is None else argv)),
            "head": current or git("rev-parse", "--short", "HEAD"), "baseline": baseline, "current_commit": current,
            "dirty": 0 if current else len([ln for ln in git("status", "--porcelain", "--", "rocking_model")
                                            .splitlines() if ln])}
    print(f"friction performance: current = "
          + (f"commit {current}" if current else
             f"work tree at {info['head']} ({info['dirty']} modified files under rocking_model/)")
          + f", baseline = {baseline}", flush=True)
    wp = {}
    with tempfile.TemporaryDirectory(prefix="rocking_friction_perf_") as tmp_name:
        tmp = Path(tmp_name)
        base_root = tmp / "baseline"
        cur_root = tmp / "current" if current else ROOT
        added = []
        try:
            for root, rev in ((base_root, baseline), (cur_root if current else None, current)):
                if root is not None:
                    git("worktree", "add", "--detach", str(root), rev)
                    added.append(root)
            info["hash_start"] = source_hash(cur_root)
            print("part 1: mu = inf, current against baseline", flush=True)
            ov = overhead(base_root, tmp, repeats, runs, args.profile_threshold, args.profile,
                          profile_repeats=1 if quick else 3, cur_root=cur_root)
            for r in ov["rows"]:
                print(f"  {r['key']:<26} ratio best {r['ratio_best']:.3f}  median {r['ratio_median']:.3f}  paired "
                      f"{min(r['paired']):.3f}..{max(r['paired']):.3f}  max|dphi| {r['dphi']:.1e}"
                      f"{' identical' if r['identical'] else ''}")
            if not args.skip_work_precision:
                print("part 2: work-precision with finite mu", flush=True)
                wp = work_precision(quick, cur_root)
                plot(wp, plot_path)
                for key, sc in wp.items():
                    for r in sc["runs"]:
                        print(f"  {key:<16} {r['scheme']:<13} {r['setting']}={r['value']:<8g} "
                              f"{fmt_ms(r['time']):>10} error {r['error']:.2e}")
            info["hash_end"] = source_hash(cur_root)
        finally:
            for root in added:
                git("worktree", "remove", "--force", str(root), check=False)
            git("worktree", "prune", check=False)
    info["load_end"] = ", ".join(f"{x:.2f}" for x in os.getloadavg())
    info["wall"] = time.perf_counter() - t_start
    write_report(report, plot_path.name, info, ov, wp, quick)
    raw_dir = QUICK_DIR if quick else ROOT / "benchmarks" / "results"   # git-ignored
    raw_dir.mkdir(parents=True, exist_ok=True)
    (raw_dir / "friction_performance.json").write_text(json.dumps(
        {"info": info, "overhead": {k: v for k, v in ov.items() if k != "profiles"}, "work_precision": wp},
        indent=1, default=str))
    print(f"report: {report.relative_to(ROOT)}, plot: {plot_path.relative_to(ROOT)} ({info['wall']:.0f} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
