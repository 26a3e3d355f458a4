"""The contenders of a scene, timed in the same process: the package's schemes, the scipy baseline and
(in a subprocess under the system interpreter) Siconos."""
from __future__ import annotations

import gc
import json
import math
import os
import shutil
import statistics
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np

from rocking_model import Simulator, simulate

from .baseline import rigid_solve_ivp
from .scenes import Scene

HERE = Path(__file__).resolve().parent
SICONOS_PYTHON = os.environ.get("SICONOS_PYTHON", "/usr/bin/python3")


# timeit's practice (Python's own `timeit`): the garbage collector is off during each timed run (on again
# between runs, where it collects what the run left), no gc.collect() right before a run (it leaves the caches
# cold), runs repeated within a time budget and the minimum reported: the noise of a machine only ever adds time
MIN_TOTAL = 0.5  # s of timed runs per setting at least (many repeats of a short run, one of a long one)
MAX_REPEATS = 10000  # bound on the repeats of a very short run


def timed(fn, repeats: int = 3, budget: float = 6.0, min_total: float = MIN_TOTAL, post=None):
    """Run ``fn`` with the garbage collector disabled during each run, at least ``repeats`` times and until the
    runs took ``min_total`` seconds, but no more once they took ``budget`` seconds (at least once); return
    (result of the last run, list of wall times [s]), the result passed through ``post`` (untimed: the
    benchmark's own bookkeeping, e.g. `outputs_of` a package Result) when given. Every contender is timed by
    this one function."""
    times, out = [], None
    enabled = gc.isenabled()
    while True:
        gc.disable()
        try:
            t0 = time.perf_counter()
            out = fn()
            times.append(time.perf_counter() - t0)
        finally:
            if enabled:
                gc.enable()
        total = sum(times)
        if total > budget or len(times) >= MAX_REPEATS or (len(times) >= max(1, repeats) and total >= min_total):
            return (out if post is None else post(out)), times


def grid_of(scene: Scene) -> np.ndarray:
    n = int(math.ceil(scene.t_end / scene.grid - 1e-9))
    return np.minimum(scene.grid * np.arange(n + 1), scene.t_end)


def wrong_side(sol: dict, eps: float = 1e-9) -> bool:
    """True if a package run rotates on the wrong side of its pivot (contact 1 = left pivot needs phi >= 0,
    contact 2 = right pivot needs phi <= 0): the body is then rocking through the ground."""
    if "contact" not in sol:
        return False
    c, phi = np.asarray(sol["contact"]), np.asarray(sol["phi"], float)
    return bool(np.any((c == 1) & (phi < -eps)) or np.any((c == 2) & (phi > eps)))


def _outputs(res) -> dict:
    out = {"phi": np.asarray(res.phi, float), "impact_times": np.asarray(res.impact_times, float),
           "n_steps": int(res.n_steps), "overturned": bool(res.overturned[-1]),
           "contact": np.asarray(res.contact)}
    if "top_displacement" in res.values:
        out["top_displacement"] = np.asarray(res.top_displacement, float)
    return out


def package_result(scene: Scene, scheme: str, engine: str = "c", **settings):
    """One run of ``simulate`` (the public API, the model built as a user builds it) on the scene's grid, on the
    Python engine (the reference implementation) or the compiled one (``engine="c"``): its `Result`. This is
    what the benchmark times (`timed(..., post=outputs_of)`)."""
    return simulate(scene.model(), scene.ground_motion(), scene.t_end, scheme=scheme, output_interval=scene.grid,
                    hold="exact", engine=engine, **scene.initial, **settings)


#: a package Result as the benchmark's dict of arrays (untimed bookkeeping)
outputs_of = _outputs


def run_package(scene: Scene, scheme: str, engine: str = "c", **settings) -> dict:
    """`package_result` as the benchmark's dict of arrays."""
    return _outputs(package_result(scene, scheme, engine, **settings))


def reference(scene: Scene, hold: str = "exact") -> dict:
    """Event-driven at the scene's reference tolerance with its steps capped at grid/8, through `Simulator`
    (as `simulate` does) so that the impact log (pre-/post-impact velocities) is available for the
    closed-form cross-check. The cap makes the reference's step sequence differ from every contender's
    (on a 0.01 s grid the event-driven contenders take about one step per output interval whatever their
    tolerance); its own uncertainty is estimated apart (`reference_floor`)."""
    model = scene.model()
    sim = Simulator(model, "event_driven", tolerance=scene.ref_tol, dt_max=scene.grid / scene.ref_cap,
                    **scene.initial)
    gm = scene.ground_motion()
    from rocking_model.ground_motion import as_ground_motion
    gm = as_ground_motion(gm)
    grid = grid_of(scene)
    recs = [sim.outputs()]
    t0 = time.perf_counter()
    from rocking_model.ground_motion import ConstantMotion
    for tk0, tk in zip(grid[:-1], grid[1:]):
        sim.advance(float(tk), ConstantMotion(gm(float(tk0))) if hold == "zoh" else gm)
        recs.append(sim.outputs())
    elapsed = time.perf_counter() - t0
    out = {"phi": np.array([r["phi"] for r in recs]), "impact_times": np.array(sim.impact_times),
           "n_steps": sim.integrator.n_steps, "overturned": bool(recs[-1]["overturned"]), "time": elapsed,
           "impact_log": [(t, np.asarray(vm), np.asarray(vp)) for t, vm, vp in sim.integrator.impact_log],
           "contact": np.array([r["contact"] for r in recs])}
    if "top_displacement" in recs[0]:
        out["top_displacement"] = np.array([r["top_displacement"] for r in recs])
    return out


def run_baseline(scene: Scene, rtol: float, max_step: float = math.inf, method: str = "DOP853") -> dict:
    """The solve_ivp baseline (rigid block only); atol = rtol (phi in rad, phi_dot in rad/s are O(1))."""
    block = scene.model()
    gm = scene.ground_motion()
    samples = None
    if scene.motion[0] == "sampled":
        ts, a = scene.motion[1], scene.motion[2]
        samples = (ts, a)
        # what a user writes for a record: linear interpolation with np.interp
        ag = lambda t, ts=ts, a=a: float(np.interp(t, ts, a, left=0.0, right=0.0))  # noqa: E731
    elif scene.motion[0] == "none":
        ag = 0.0
    else:
        ag = gm
    return rigid_solve_ivp(block, ag, scene.t_end, grid_of(scene), rtol=rtol, atol=rtol, samples=samples,
                           max_step=max_step, method=method,
                           phi_0=scene.initial.get("phi_0", 0.0), phi_dot_0=scene.initial.get("phi_dot_0", 0.0))


def siconos_available() -> tuple[bool, str]:
    if not Path(SICONOS_PYTHON).exists():
        return False, f"{SICONOS_PYTHON} not found"
    if shutil.which("gcc") is None:
        return False, "gcc not found (Siconos relations need a compiled plugin)"
    r = subprocess.run([SICONOS_PYTHON, "-c", "import siconos.kernel"], capture_output=True, text=True)
    if r.returncode != 0:
        return False, ("python3-siconos is not installed for " + SICONOS_PYTHON +
                       " (Debian: apt-get install python3-siconos)")
    return True, ""


def run_siconos(scene: Scene, dts, repeats: int, budget: float = 3.0, mu: float = 100.0) -> dict:
    """Siconos Moreau-Jean on a rigid-block scene (subprocess); {"runs": [...]} or {"error": ...}."""
    block = scene.model()
    with tempfile.TemporaryDirectory(prefix="rocking_siconos_") as tmp:
        job = {"b": block.b, "h": block.h, "m": block.m, "g": block.g, "phi_0": scene.initial.get("phi_0", 0.0),
               "t_end": scene.t_end, "grid": scene.grid, "dts": list(dts), "repeats": repeats, "budget": budget, "min_total": MIN_TOTAL,
               "motion": scene.motion_json(), "mu": mu, "tmp": tmp}
        job_file, out_file = Path(tmp) / "job.json", Path(tmp) / "result.json"
        job_file.write_text(json.dumps(job))
        r = subprocess.run([SICONOS_PYTHON, str(HERE / "siconos_runner.py"), str(job_file), str(out_file)],
                           capture_output=True, text=True, timeout=1800)
        if r.returncode != 0 or not out_file.exists():
            return {"error": f"siconos runner failed (exit {r.returncode}): {r.stderr.strip()[-500:]}"}
        result = json.loads(out_file.read_text())
        result["stdout_lines"] = len(r.stdout.splitlines())
        return result


def median(xs):
    return statistics.median(xs) if xs else math.nan


def best(xs):
    """The time a table reports and the ratios compare: the minimum of the repeats (as timeit)."""
    return min(xs) if xs else math.nan
