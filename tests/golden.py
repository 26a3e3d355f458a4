"""Golden outputs: the benchmark scenes and the FMU cross-check runs, recorded bit for bit.

A restructuring of the package (contact states per corner, declared contracts, one set of tolerances,
event handling as pure functions) must not change a single number. This module runs every benchmark scene
(`benchmarks/scenes.py`, full length) on the compiled engine, with both schemes and both Runge-Kutta methods, plus stepwise and
zero-order-hold runs as the FMUs do them, and the FMUs' own cross-check runs through fmpy, and compares
every output with the recording in ``tests/data/golden.npz``.

Bit identity is a property of one arithmetic environment: another CPU's libm or BLAS kernel rounds
differently, and the record scenes are chaotic. The recording therefore carries the fingerprint of the
kernels it was made with (`roundoff.fingerprint`); on a machine with the same fingerprint every array must be
bit-identical, elsewhere the runs marked ``smooth`` (short, far from any decision boundary) are compared to
a round-off bound and the others are skipped with the reason.

Command line: ``python tests/golden.py --write [--fmus DIR]`` re-records (only when a change of the numbers
is intended and explained in the commit).
"""
from __future__ import annotations

import argparse
import hashlib
import json
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
for p in (str(ROOT), str(ROOT / "benchmarks"), str(HERE)):
    if p not in sys.path:
        sys.path.insert(0, p)

GOLDEN = HERE / "data" / "golden.npz"

#: (label, scheme, keyword arguments, smooth) of the runs of every benchmark scene; ``smooth`` runs are
#: compared to round-off on machines whose kernels differ from the recording's
SETTINGS = (
    ("ed_dop853", "event_driven", dict(tolerance=1e-8)),
    ("ed_dopri5", "event_driven", dict(tolerance=1e-5, method="DOPRI5")),
    ("mj_half", "moreau_jean", dict(dt_max=2e-3)),
    ("mj_one", "moreau_jean", dict(dt_max=5e-3, theta=1.0)),
)
#: [1] relative bound of a smooth run on other kernels (round-off grown over a few impacts)
SMOOTH_RTOL = 1e-6
#: scenes whose runs are smooth (the record scene is long and chaotic)
SMOOTH_SCENES = ("free", "pulse_below", "flex_soft")


def _pack(result) -> dict:
    out = {"t": np.asarray(result.t, dtype=float), "impact_times": np.asarray(result.impact_times, dtype=float),
           "n_steps": np.array([result.n_steps])}
    for name, arr in result.values.items():
        out[name] = np.asarray(arr)
    return out


def library_runs() -> dict:
    """{run name: {output name: array}} of the Python API runs."""
    from scenes import flexible_scenes, rigid_scenes
    from rocking_model import Simulator, simulate
    from rocking_model.ground_motion import ConstantMotion, as_ground_motion

    runs = {}
    for s in rigid_scenes() + flexible_scenes():
        for label, scheme, kw in SETTINGS:
            r = simulate(s.model(), s.ground_motion(), s.t_end, scheme=scheme, output_interval=s.grid,
                         **s.initial, **kw)
            runs[f"{s.name}/{label}"] = _pack(r)
        # zero-order hold over the output grid, as a co-simulation master drives the FMU
        r = simulate(s.model(), s.ground_motion(), min(s.t_end, 4.0), hold="zoh", output_interval=0.01,
                     **s.initial)
        runs[f"{s.name}/zoh"] = _pack(r)
        # stepwise Simulator with a bounded log and save/load of the state half way (the FMU's path)
        sim = Simulator(s.model(), "event_driven", **s.initial)
        gm = as_ground_motion(s.ground_motion())
        rows = []
        for k in range(200):
            if k == 100:
                state = sim.get_state()
                sim = Simulator(s.model(), "event_driven", **s.initial)
                sim.set_state(state)
            sim.advance((k + 1) * 0.01, ConstantMotion(gm(k * 0.01)))
            out = sim.outputs()
            rows.append([float(out[n]) for n in sorted(out)])
        runs[f"{s.name}/stepwise"] = {"rows": np.array(rows), "impact_times": np.array(sim.impact_times)}
    return runs


def fmu_names() -> list[str]:
    """The FMUs with a cross-check scenario (build_fmu.CROSS_CHECK)."""
    import build_fmu
    return sorted(build_fmu.CROSS_CHECK)


def fmu_runs(fmus: dict) -> dict:
    """{run name: {output name: array}} of the FMUs' cross-check runs (fmpy), ``fmus``: name -> path."""
    import build_fmu

    runs = {}
    for name, path in sorted(fmus.items()):
        spec = build_fmu.CROSS_CHECK[name]
        opts = {"StartTime": 0.0, "StopTime": spec["stop"], "StepSize": spec["step"], "RelTol": spec["rel_tol"]}
        res = build_fmu.simulate_cross_check(path, build_fmu.cross_check_input(name), opts)
        runs[f"fmu/{name}"] = {n: np.asarray(res[n], dtype=float) for n in res.dtype.names}
    return runs


def flatten(runs: dict) -> dict:
    return {f"{run}:{name}": arr for run, outs in runs.items() for name, arr in outs.items()}


def is_smooth(key: str) -> bool:
    run = key.split(":", 1)[0]
    scene, label = run.split("/", 1)
    return scene in SMOOTH_SCENES and label != "stepwise"


def digest(arr: np.ndarray) -> str:
    return hashlib.sha256(np.ascontiguousarray(arr).tobytes()).hexdigest()[:16]


def load() -> tuple[dict, dict]:
    """(arrays, meta) of the recording."""
    with np.load(GOLDEN, allow_pickle=False) as z:
        arrays = {k: z[k] for k in z.files if k != "__meta__"}
        meta = json.loads(str(z["__meta__"]))
    return arrays, meta


def compare(new: dict, ref: dict, same_kernels: bool) -> tuple[list, list]:
    """(failures, skipped) of the arrays ``new`` against the recording ``ref``."""
    failures, skipped = [], []
    for key in sorted(set(ref) | set(new)):
        if key not in new or key not in ref:
            failures.append(f"{key}: {'missing' if key not in new else 'not recorded'}")
            continue
        a, b = new[key], ref[key]
        if a.shape == b.shape and a.dtype == b.dtype and np.array_equal(a, b, equal_nan=True) \
                and a.tobytes() == b.tobytes():
            continue
        if same_kernels:
            failures.append(_diff(key, a, b))
        elif is_smooth(key) and a.shape == b.shape:
            scale = max(float(np.max(np.abs(b))), 1e-300) if b.size else 1.0
            err = float(np.max(np.abs(a.astype(float) - b.astype(float)))) if b.size else 0.0
            if err > SMOOTH_RTOL * scale:
                failures.append(_diff(key, a, b))
        else:
            skipped.append(key)
    return failures, skipped


def _diff(key, a, b) -> str:
    if a.shape != b.shape:
        return f"{key}: shape {a.shape} != recorded {b.shape}"
    d = np.abs(a.astype(float) - b.astype(float))
    i = int(np.nanargmax(d)) if d.size else 0
    return f"{key}: max |diff| {float(np.nanmax(d)) if d.size else 0:.3g} at index {i} (digest {digest(a)} != {digest(b)})"


def main(argv=None) -> int:
    import roundoff

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--write", action="store_true", help="re-record tests/data/golden.npz")
    ap.add_argument("--fmus", help="folder of built FMUs (default: build them into a temporary folder)")
    args = ap.parse_args(argv)
    import tempfile

    import build_fmu

    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(args.fmus) if args.fmus else Path(tmp)
        if not args.fmus:
            build_fmu.build_all(folder, names=list(build_fmu.CROSS_CHECK))
        fmus = {n: folder / f"{n}.fmu" for n in build_fmu.CROSS_CHECK}
        new = flatten(library_runs()) | flatten(fmu_runs(fmus))
    if args.write:
        meta = {"fingerprint": roundoff.fingerprint(), "numpy": np.__version__}
        GOLDEN.parent.mkdir(parents=True, exist_ok=True)
        np.savez_compressed(GOLDEN, __meta__=np.array(json.dumps(meta)), **new)
        print(f"wrote {len(new)} arrays to {GOLDEN}")
        return 0
    ref, meta = load()
    same = meta["fingerprint"] == roundoff.fingerprint()
    failures, skipped = compare(new, ref, same)
    print(f"{len(new)} arrays, same kernels: {same}, {len(failures)} differ, {len(skipped)} skipped")
    for f in failures:
        print("  " + f)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
