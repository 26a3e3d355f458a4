"""The compiled engine per communication step, its cold start from Python.

Per step: the first 30 s of the synthetic record (the record scene's accelerogram, the FMU benchmark's) in
0.01 s communication steps, ag held over each step (zero-order hold, as an FMU importer drives it), the
outputs read after each step, through

- the raw engine loop: `rocking_model._engine.Engine.advance(t, ag, 0, max_steps)` and `output_row()`
  (what an FMU's doStep costs in C plus one Python call each);
- one `Engine.sample(times, spec, ...)` call over the record (the C loop over the communication steps, the
  outputs written into arrays): the record integrated as given (linear between its samples), not held, so its
  steps and impacts differ slightly from the held runs';
- `Simulator(engine="c").advance(t, ag)` and `outputs()` (the Python API);
- `simulate(..., hold="zoh", engine="c")` (whole run).

The variants of a case run in interleaved rounds (`_interleaved`: 15 rounds in a full run, each one run of
every variant), the fastest run of each reported.

Models: the record scene's rigid block (b = 0.4 m, h = 2 m) and the default flexible oscillator under the
record scaled to 0.3 g (the flexible FMU's benchmark), each event-driven (tolerance 1e-8, the FMU default)
and Moreau-Jean (dt_max 1e-3: ten time steps per communication step; its cost is also given per time step).

A record shaped like the C prototype's record (`PROTOTYPE_RECORD`: 40 s of 5 ms samples, about 400 impacts):
the rigid block's C loop (`Engine.sample`) and raw loop per communication step, the figures the speed target
(at most 1 us per communication step on such a record, 3x the prototype's C loop) compares with.

Cold start: in a fresh interpreter (median of several), to the end of the first 0.01 s step of the record
scene's rigid block, through

- the low-level API: `from rocking_model._engine import Engine` (the extension module alone: numpy is not
  imported), `Engine("rigid", params)`, `advance`, `outputs`;
- `Simulator(engine="c")`: from `import numpy` (listed apart: the Python API needs it) and
  `from rocking_model import RigidBlock, Simulator`.

The interpreters run with the package's bytecode cached, as after `pip install` (one unmeasured run first;
PYTHONDONTWRITEBYTECODE, if set, is dropped for them: without the cache every import compiles the package's
sources, about 40 ms of the Python API's import).
"""
from __future__ import annotations

import gc
import json
import math
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

from benchmarks import scenes as S

COLD = r"""
import json, time
t0 = time.perf_counter()
import numpy
t1 = time.perf_counter()
from rocking_model import RigidBlock, Simulator
t2 = time.perf_counter()
sim = Simulator(RigidBlock(b=0.4, h=2.0), "event_driven", engine="c")
sim.advance(0.01, 0.5)
phi = sim.outputs()["phi"]
t3 = time.perf_counter()
print(json.dumps({"numpy_import": t1 - t0, "package_import": t2 - t1, "first_step": t3 - t2,
                  "import_to_first_step": t3 - t0, "import_to_first_step_after_numpy": t3 - t1, "phi": phi}))
"""


COLD_LOW = r"""
import json, sys, time
t0 = time.perf_counter()
from rocking_model._engine import Engine, model_kinds
t1 = time.perf_counter()
decl = next(k for k in model_kinds() if k["kind"] == "rigid")
params = [{"b": 0.4, "h": 2.0}.get(p[0], p[2]) for p in decl["params"]]   # the declared defaults, b and h set
eng = Engine("rigid", params, scheme=1)
eng.advance(0.01, 0.5)
phi = eng.outputs()[0]
t2 = time.perf_counter()
print(json.dumps({"import": t1 - t0, "first_step": t2 - t1, "import_to_first_step": t2 - t0, "phi": phi,
                  "numpy_imported": "numpy" in sys.modules,
                  "package_modules": sorted(m for m in sys.modules if m.startswith("rocking_model"))}))
"""


def _interpreters(script: str, repeats: int) -> dict:
    """Median of ``repeats`` fresh interpreters running ``script`` (after one unmeasured run that caches the
    bytecode); its last output line is a JSON dict."""
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    samples = []
    for i in range(repeats + 1):
        r = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120,
                           cwd=tempfile.gettempdir(), env=env)
        if r.returncode != 0:
            return {"error": r.stderr.strip()[-1500:]}
        if i:
            samples.append(json.loads(r.stdout.strip().splitlines()[-1]))
    return {k: (sorted(s[k] for s in samples)[len(samples) // 2] if isinstance(samples[0][k], float)
                else samples[0][k]) for k in samples[0]} | {"samples": samples}


def cold_start(repeats: int = 5) -> dict:
    """The Simulator path (fields at the top level) and the low-level path (``low_level``)."""
    out = _interpreters(COLD, repeats)
    low = _interpreters(COLD_LOW, repeats)
    if "error" not in out and "error" not in low:
        low["same_phi_as_simulator"] = low["phi"] == out["phi"]     # the same engine, the same first step
    out["low_level"] = low
    return out


def _best(fn, repeats: int):
    """(result of the last run, the fastest of ``repeats`` wall times [s]); as contenders.timed (timeit's
    practice): the garbage collector off during each run, no collection before it."""
    best, out = float("inf"), None
    enabled = gc.isenabled()
    for _ in range(max(1, repeats)):
        gc.disable()
        try:
            t0 = time.perf_counter()
            out = fn()
            best = min(best, time.perf_counter() - t0)
        finally:
            if enabled:
                gc.enable()
    return out, best


def _interleaved(fns: dict, rounds: int) -> dict:
    """{name: (result of its last run, its fastest wall time [s])}: every function run once per round, the rounds
    one after the other, each run timed as `_best` times it. The variants of a case then share the slow and fast
    phases of a shared machine (one variant's repeats in a row could all fall in another job's burst: seen, a
    2.3 us step against 1.0 us measured alone)."""
    out: dict = {}
    for _ in range(max(1, rounds)):
        for name, fn in fns.items():
            res, wall = _best(fn, 1)
            out[name] = (res, min(wall, out[name][1]) if name in out else wall)
    return out


def _sample_run(sim, grid, spec):
    """One `Engine.sample` call of ``sim``'s engine over ``grid`` (the C loop over the communication steps) into
    fresh row arrays; returns them."""
    eng = sim.integrator._engine
    m = len(grid) + 1
    rows = (np.empty(m, np.intc), np.empty((m, eng.n_outputs + 2)), np.empty(m, np.int64), np.empty(m, np.intc))
    eng.sample(grid, spec, 100000, *rows, 0)
    return rows


def _raw_run(sim, times, ag) -> list:
    """The raw loop on ``sim``'s engine: `Engine.advance(t, ag, 0, max_steps)` and `output_row()` per
    communication step (what an FMU's doStep costs in C plus one Python call each); returns phi after each."""
    eng = sim.integrator._engine
    adv, row = eng.advance, eng.output_row
    j = eng.output_names.index("phi")
    phis = []
    for tk, ak in zip(times, ag):
        adv(tk, ak, 0.0, 100000)
        phis.append(row()[j])
    return phis


def per_step(repeats: int = 3, duration: float = 30.0) -> dict:
    from rocking_model import FlexibleOscillator, RigidBlock, SampledMotion, Simulator, simulate
    from rocking_model.engine import motion_spec

    t, a = S.synthetic_record()
    dt = 0.01
    n = int(round(duration / dt))
    cases = [
        ("rigid", "event_driven", lambda: RigidBlock(**S.RECORD_BLOCK), 1.0, {"tolerance": 1e-8}),
        ("rigid", "moreau_jean", lambda: RigidBlock(**S.RECORD_BLOCK), 1.0, {"dt_max": 1e-3}),
        ("flexible", "event_driven", FlexibleOscillator, 0.75, {"tolerance": 1e-8}),
        ("flexible", "moreau_jean", FlexibleOscillator, 0.75, {"dt_max": 1e-3}),
    ]
    out = []
    for kind, scheme, make, scale, kw in cases:
        ag = (a[:n] * scale).tolist()
        times = [(k + 1) * dt for k in range(n)]

        def raw():
            sim = Simulator(make(), scheme, engine="c", **kw)
            return sim, _raw_run(sim, times, ag)

        def api():
            sim = Simulator(make(), scheme, engine="c", **kw)
            phis = []
            for tk, ak in zip(times, ag):
                sim.advance(tk, ak)
                phis.append(sim.outputs()["phi"])
            return sim, phis

        def sampled():
            # one call into C for the whole record (Engine.sample: the C loop over the communication steps);
            # the record is then integrated as given (linear between samples, simulate's hold="exact"), not held
            sim = Simulator(make(), scheme, engine="c", **kw)
            spec = motion_spec(SampledMotion(t[:n + 1], a[:n + 1] * scale))
            return sim, _sample_run(sim, np.asarray(times), spec)

        best = _interleaved({
            "raw": raw, "sampled": sampled, "api": api,
            "simulate": lambda: simulate(make(), (t[:n + 1], a[:n + 1] * scale), n * dt, scheme=scheme, hold="zoh",
                                         engine="c", **kw)}, repeats)
        (sim_raw, phi_raw), t_raw = best["raw"]
        (sim_smp, _), t_smp = best["sampled"]
        (sim_c, phi_c), t_api = best["api"]
        res_sim, t_sim = best["simulate"]
        n_internal = int(sim_c.integrator.n_steps)
        row = {"kind": kind, "scheme": scheme, "settings": kw, "steps": n, "dt": dt, "pga_g": 0.4 * scale,
               "impacts": int(sim_c.outputs()["impacts"]), "internal_steps": n_internal,
               "raw": t_raw, "api": t_api, "simulate": t_sim, "sample": t_smp,
               "raw_us": t_raw / n * 1e6, "api_us": t_api / n * 1e6, "simulate_us": t_sim / n * 1e6,
               "sample_us": t_smp / n * 1e6, "sample_impacts": int(sim_smp.outputs()["impacts"]),
               "raw_us_per_internal_step": t_raw / max(1, n_internal) * 1e6,
               "max_dphi_raw_api": float(np.max(np.abs(np.array(phi_raw) - np.array(phi_c)))),
               "max_abs_phi": float(np.max(np.abs(phi_c)))}
        out.append(row)
        print(f"[compiled] {kind} {scheme}: raw {row['raw_us']:.2f} us/step, Engine.sample {row['sample_us']:.2f}, "
              f"API {row['api_us']:.2f}, simulate "
              f"{row['simulate_us']:.2f}; {row['impacts']} impacts; |dphi| raw-API {row['max_dphi_raw_api']:.1e}",
              flush=True)
    return {"record": "synthetic record (benchmarks.scenes.synthetic_record), first 30 s", "rows": out}


#: a record shaped like the C prototype's record (a 40 s far-field record, 7991 samples of 5 ms, about 400
#: impacts of the rigid block): the synthetic record's generator at 5 ms over 40 s, a longer strong phase and
#: slower decay, a seed and PGA that give about 400 impacts of the record block without overturning
PROTOTYPE_RECORD = dict(duration=40.0, dt=0.005, pga_g=0.35, t_strong=30.0, decay=0.5, seed=11)


def prototype_shaped(repeats: int = 3, duration: float = 40.0) -> dict:
    """The rigid block (event-driven, tolerance 1e-8) on `PROTOTYPE_RECORD`: the C loop (`Engine.sample`, the
    record linear between samples) and the raw loop (`Engine.advance` + `output_row`, ag held) per
    communication step, interleaved rounds as `per_step`."""
    from rocking_model import RigidBlock, SampledMotion, Simulator
    from rocking_model.engine import motion_spec
    from rocking_model.records import synthetic_record

    kw = dict(PROTOTYPE_RECORD, duration=duration)
    t, a = synthetic_record(**kw)
    n = len(t) - 1
    grid = t[1:]
    spec = motion_spec(SampledMotion(t, a))
    times, ag = grid.tolist(), a[:n].tolist()

    def new():
        return Simulator(RigidBlock(**S.RECORD_BLOCK), "event_driven", engine="c", tolerance=1e-8)

    def sampled():
        sim = new()
        _sample_run(sim, grid, spec)
        return sim

    def raw():
        sim = new()
        _raw_run(sim, times, ag)
        return sim

    best = _interleaved({"sampled": sampled, "raw": raw}, repeats)
    (sim_s, t_s), (sim_r, t_r) = best["sampled"], best["raw"]
    out = {"record": kw, "steps": n, "dt": kw["dt"], "sample_us": t_s / n * 1e6, "raw_us": t_r / n * 1e6,
           "sample_impacts": int(sim_s.outputs()["impacts"]), "raw_impacts": int(sim_r.outputs()["impacts"]),
           "overturned": bool(sim_s.outputs()["overturned"])}
    print(f"[compiled] prototype-shaped record: Engine.sample {out['sample_us']:.2f} us/step "
          f"({out['sample_impacts']} impacts), raw {out['raw_us']:.2f} ({out['raw_impacts']} impacts)", flush=True)
    return out


#: the lean C program of the event-driven scheme (the engine's speed reference: /work/shared/bench/README.md)
LEAN_C = os.environ.get("ROCKING_LEAN_C", "/work/shared/bench/rigid_ed.c")


def _lean_c(tmp: str) -> str | None:
    """`LEAN_C` compiled with gcc -O2 (its README's flags) into ``tmp``; None when missing or gcc fails."""
    exe = os.path.join(tmp, "rigid_ed")
    if not os.path.exists(LEAN_C):
        return None
    r = subprocess.run(["gcc", "-O2", "-o", exe, LEAN_C, "-lm"], capture_output=True, text=True)
    return exe if r.returncode == 0 else None


def _lean_run(exe: str, record: str, b: float, h: float, tol: float, reps: int) -> dict:
    """One run of the lean program: its ``key value`` pairs (min_s: the fastest of ``reps`` runs in its process)."""
    out = subprocess.run([exe, record, repr(b), repr(h), "1", "0", "0", repr(tol), str(reps)], capture_output=True,
                         text=True, timeout=300).stdout.split()
    return {k: float(v) for k, v in zip(out[::2], out[1::2])}


def holds_vs_lean(rounds: int = 15, duration: float = 40.0) -> dict:
    """`simulate(hold="zoh")` and `simulate(hold="exact")` (the rigid block, event-driven, tolerance 1e-8) on
    `PROTOTYPE_RECORD` against the lean C program on the same record (b, h, tol, ag held over each sample as
    hold="zoh" does), in interleaved rounds (one run of each simulate, one of the lean program taking the fastest of
    3 in its process); the fastest of the rounds of each and their ratios."""
    from rocking_model import RigidBlock, SampledMotion, simulate
    from rocking_model.records import synthetic_record

    kw = dict(PROTOTYPE_RECORD, duration=duration)
    t, a = synthetic_record(**kw)
    gm = SampledMotion(t, a)
    b, h, tol, t_end = S.RECORD_BLOCK["b"], S.RECORD_BLOCK["h"], 1e-8, float(t[-1])

    def run(hold):
        return lambda: simulate(RigidBlock(b=b, h=h), gm, t_end, output_interval=kw["dt"], hold=hold, tolerance=tol)

    with tempfile.TemporaryDirectory(prefix="rocking_lean_") as tmp:
        exe = _lean_c(tmp)
        if exe is None:
            return {"error": f"the lean C program {LEAN_C} is missing or does not compile"}
        record = os.path.join(tmp, "record.csv")
        np.savetxt(record, np.column_stack([t, a]), delimiter=",", header="time,ag", comments="")
        best: dict = {}
        cpu: dict = {}
        lean: dict = {}
        lean_cpu = math.inf
        enabled = gc.isenabled()
        for _ in range(max(1, rounds)):
            for name, fn in (("zoh", run("zoh")), ("exact", run("exact"))):
                # wall and CPU time of one run (the CPU time is blind to the other jobs' time slices on a shared
                # machine: a 5 ms run is cut by them more often than the lean program's 2 ms runs)
                gc.disable()
                try:
                    c0, t0 = time.process_time(), time.perf_counter()
                    res = fn()
                    wall, c1 = time.perf_counter() - t0, time.process_time() - c0
                finally:
                    if enabled:
                        gc.enable()
                best[name] = (res, min(wall, best[name][1]) if name in best else wall)
                cpu[name] = min(c1, cpu.get(name, math.inf))
            one = _lean_run(exe, record, b, h, tol, 3)
            if not lean or one["min_s"] < lean["min_s"]:
                lean = one
            lean_cpu = min(lean_cpu, one["cpu_median_s"])
    out = {"record": kw, "steps": len(t) - 1, "b": b, "h": h, "tolerance": tol, "lean_s": lean["min_s"],
           "lean_cpu_s": lean_cpu, "lean_impacts": int(lean["impacts"]), "loadavg": os.getloadavg()}
    for name in ("zoh", "exact"):
        res, wall = best[name]
        out[name + "_s"] = wall
        out[name + "_cpu_s"] = cpu[name]
        out[name + "_impacts"] = int(res["impacts"][-1])
        out[name + "_over_lean"] = wall / lean["min_s"]
        out[name + "_over_lean_cpu"] = cpu[name] / lean_cpu
    print(f"[compiled] prototype-shaped record, simulate against the lean C program (wall; CPU time): hold=\"zoh\" "
          f"{out['zoh_s'] * 1e3:.2f} ms ({out['zoh_over_lean']:.2f}x; {out['zoh_over_lean_cpu']:.2f}x), "
          f"hold=\"exact\" {out['exact_s'] * 1e3:.2f} ms ({out['exact_over_lean']:.2f}x; "
          f"{out['exact_over_lean_cpu']:.2f}x), lean C {out['lean_s'] * 1e3:.2f} ms; impacts {out['zoh_impacts']} / "
          f"{out['exact_impacts']} / {out['lean_impacts']} (the lean program counts every impact of a rest "
          f"sequence); load {out['loadavg'][0]:.2f}", flush=True)
    return out


def pulse_python_fraction(rounds: int = 300) -> dict:
    """The Python layer of a short `simulate`: the pulse scene (`simulate(RigidBlock(...), SinePulse(...), t_end)`,
    the rigid block below overturning, 4 s in 0.01 s outputs) against `Engine.sample` alone on the same grid and
    motion (a fresh engine, built outside the timing), in interleaved rounds. fraction = 1 - sample / simulate, of
    the fastest runs and the median of the rounds' own fractions."""
    from rocking_model import RigidBlock, SinePulse, Simulator, simulate
    from rocking_model.engine import motion_spec

    scene = next(s for s in S.rigid_scenes() if s.name == "pulse_below")
    A, w = scene.motion[1], scene.motion[2]
    res = simulate(RigidBlock(**scene.model_kw), SinePulse(A, w), t_end=scene.t_end)
    grid = np.ascontiguousarray(res.t[1:])
    spec = motion_spec(SinePulse(A, w))
    integ = Simulator(RigidBlock(**scene.model_kw)).integrator
    from rocking_model import _engine

    def sample():
        eng = integ._new_engine(_engine)
        m = len(grid) + 1
        rows = (np.empty(m, np.int64), np.empty((eng.n_outputs + 2, m)), np.empty(m, np.int64), np.empty(m, bool))
        t0 = time.perf_counter()
        eng.sample(grid, spec, 10000, *rows, 0, None, True)
        return time.perf_counter() - t0

    def whole():
        t0 = time.perf_counter()
        simulate(RigidBlock(**scene.model_kw), SinePulse(A, w), t_end=scene.t_end)
        return time.perf_counter() - t0

    enabled = gc.isenabled()
    gc.disable()
    try:
        pairs = [(whole(), sample()) for _ in range(max(1, rounds))]
    finally:
        if enabled:
            gc.enable()
    sim_s = min(p[0] for p in pairs)
    eng_s = min(p[1] for p in pairs)
    fractions = sorted(1.0 - e / w_ for w_, e in pairs)
    out = {"simulate_us": sim_s * 1e6, "sample_us": eng_s * 1e6, "python_us": (sim_s - eng_s) * 1e6,
           "python_fraction": 1.0 - eng_s / sim_s, "python_fraction_median": fractions[len(fractions) // 2],
           "rounds": len(pairs), "outputs": len(grid) + 1, "loadavg": os.getloadavg()}
    print(f"[compiled] pulse scene, the Python layer of simulate: simulate {out['simulate_us']:.1f} us, "
          f"Engine.sample {out['sample_us']:.1f} us: Python {out['python_us']:.1f} us = "
          f"{100 * out['python_fraction']:.0f} % of the whole (median of the rounds "
          f"{100 * out['python_fraction_median']:.0f} %); load {out['loadavg'][0]:.2f}", flush=True)
    return out


def binding_ab(rounds: int = 300, hand=None, tool=None) -> dict:
    """The binding's cost, A/B in one process: the pulse scene `simulate(RigidBlock(b=0.2, h=1.0), SinePulse(0.4 g,
    4 pi), 4.0)` with its engine bound by the hand-written extension (``hand``) against the cffi binding
    (``tool``): the same engine sources and flags, motion and grid. Interleaved rounds (garbage collector off):
    the whole simulate through each, and the binding's part alone (engine creation at the start state,
    `Engine.sample` in columns over the grid, impact times, n_steps, free) through each. cost = (tool - hand) /
    hand simulate, of the fastest runs and the median of the rounds' own differences.

    ``hand`` and ``tool``: modules with the `Engine` API; by default the package's extension
    ``rocking_model._engine`` (the hand-written glue) and `benchmarks.ffi_engine` (cffi, API mode: the module is
    compiled on first use, about a minute, `benchmarks.ffi_binding`)."""
    import importlib

    import rocking_model.engine as engine_pkg
    from rocking_model import RigidBlock, SinePulse, Simulator, simulate
    from rocking_model.engine import motion_spec

    if hand is None:
        hand = importlib.import_module("rocking_model._engine")
    if tool is None:
        try:
            tool = importlib.import_module("benchmarks.ffi_engine")
        except Exception as exc:        # no cffi or no compiler: the A/B cannot run here
            print(f"[compiled] binding A/B skipped: the cffi binding could not be built ({exc})", flush=True)
            return {}
    model_kw, A, w, t_end = {"b": 0.2, "h": 1.0}, 0.4 * 9.81, 4 * math.pi, 4.0
    ref = simulate(RigidBlock(**model_kw), SinePulse(A, w), t_end)
    grid = np.ascontiguousarray(ref.t[1:])
    spec = motion_spec(SinePulse(A, w))
    integ = Simulator(RigidBlock(**model_kw)).integrator

    def whole(mod):
        def run():
            engine_pkg._EXTENSION = mod
            t0 = time.perf_counter()
            res = simulate(RigidBlock(**model_kw), SinePulse(A, w), t_end)
            return time.perf_counter() - t0, res
        return run

    def binding(mod):
        def run():
            m = len(grid) + 1
            t0 = time.perf_counter()
            eng = integ._new_engine(mod)
            ints = np.empty((2, m), np.int64)
            values = np.empty((eng.n_outputs + 2, m))
            over = np.empty(m, bool)
            eng.sample(grid, spec, 10000, ints[0], values, ints[1], over, 0, None, True)
            out = (eng.impact_times, eng.n_steps)
            del eng
            return time.perf_counter() - t0, out
        return run

    fns = {"simulate_hand": whole(hand), "simulate_tool": whole(tool), "binding_hand": binding(hand),
           "binding_tool": binding(tool)}
    saved = engine_pkg._EXTENSION
    times: dict = {name: [] for name in fns}
    results: dict = {}
    enabled = gc.isenabled()
    gc.disable()
    try:
        for _ in range(max(1, rounds)):
            for name, fn in fns.items():
                wall, results[name] = fn()
                times[name].append(wall)
    finally:
        engine_pkg._EXTENSION = saved
        if enabled:
            gc.enable()
    same = all(np.array_equal(results["simulate_hand"].values[k], results["simulate_tool"].values[k])
               for k in results["simulate_hand"].values) and results["binding_hand"] == results["binding_tool"]
    best = {name: min(ts) * 1e6 for name, ts in times.items()}

    def median(xs):
        xs = sorted(xs)
        return xs[len(xs) // 2]

    sim_diff = median([b - a for a, b in zip(times["simulate_hand"], times["simulate_tool"])]) * 1e6
    bind_diff = median([b - a for a, b in zip(times["binding_hand"], times["binding_tool"])]) * 1e6
    out = {"simulate_hand_us": best["simulate_hand"], "simulate_tool_us": best["simulate_tool"],
           "binding_hand_us": best["binding_hand"], "binding_tool_us": best["binding_tool"],
           "cost_simulate_fraction": (best["simulate_tool"] - best["simulate_hand"]) / best["simulate_hand"],
           "cost_binding_fraction": (best["binding_tool"] - best["binding_hand"]) / best["simulate_hand"],
           "cost_simulate_fraction_median": sim_diff / (median(times["simulate_hand"]) * 1e6),
           "cost_binding_fraction_median": bind_diff / (median(times["simulate_hand"]) * 1e6),
           "same_results": bool(same), "rounds": max(1, rounds), "outputs": len(grid) + 1,
           "loadavg": os.getloadavg()}
    print(f"[compiled] binding A/B on the pulse scene ({out['rounds']} interleaved rounds, fastest): simulate "
          f"{out['simulate_hand_us']:.1f} us hand-written / {out['simulate_tool_us']:.1f} us cffi "
          f"({100 * out['cost_simulate_fraction']:+.1f} %, median of the rounds' differences "
          f"{100 * out['cost_simulate_fraction_median']:+.1f} %); the binding's calls "
          f"{out['binding_hand_us']:.1f} / {out['binding_tool_us']:.1f} us "
          f"({100 * out['cost_binding_fraction']:+.1f} % of simulate, median "
          f"{100 * out['cost_binding_fraction_median']:+.1f} %); same results {out['same_results']}; load "
          f"{out['loadavg'][0]:.2f}", flush=True)
    return out


def main(quick: bool = False) -> dict:
    return {"per_step": per_step(3 if quick else 15, 8.0 if quick else 30.0),
            "prototype": prototype_shaped(3 if quick else 15, 10.0 if quick else 40.0),
            "holds": holds_vs_lean(3 if quick else 15, 10.0 if quick else 40.0),
            "pulse_python": pulse_python_fraction(50 if quick else 300),
            "binding_ab": binding_ab(50 if quick else 300),
            "cold": cold_start(2 if quick else 7)}


if __name__ == "__main__":
    # python -m benchmarks.compiled_bench [--quick] [--json PATH]: the results as JSON on stdout, or into PATH
    result = json.dumps(main("--quick" in sys.argv), indent=1)
    if "--json" in sys.argv:
        with open(sys.argv[sys.argv.index("--json") + 1], "w", encoding="utf-8") as fh:
            fh.write(result)
    else:
        print(result)
