"""The self-contained FMUs (issue 22): size, shared-library dependencies, cold start and the cost of a step
through fmpy, printed (never asserted: timing depends on the machine).

    python -m benchmarks.standalone_fmu [--dest dist] [--repeat 20]

Builds dist/standalone/*.fmu if they are missing (build_fmu.build_standalone). Cold start: a fresh copy of
the extracted FMU each time (so the loader really loads the binary), then load + fmi2Instantiate +
setup/initialization + the first fmi2DoStep, in this process, median of ``--repeat``. Step cost: the
benchmark record of the rigid block (30 s synthetic record, 3000 steps of 10 ms) through fmpy's FMU2Slave
(setReal, doStep, getReal per step), for the standalone FMU and, when it is built, the pythonfmu FMU.
"""
from __future__ import annotations

import argparse
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
NAMES = ("RigidRockingBlock", "FlexibleRockingOscillator")


def _ensure(dest: Path) -> dict:
    folder = dest / "standalone"
    if not all((folder / f"{n}.fmu").is_file() for n in NAMES):
        sys.path.insert(0, str(ROOT))
        import build_fmu
        build_fmu.build_standalone(dest)
    return {n: folder / f"{n}.fmu" for n in NAMES}


def cold_start(fmu: Path, repeat: int) -> float:
    """Median seconds of load + instantiate + initialize + first step, each from a fresh copy."""
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave

    md = read_model_description(str(fmu))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    base = extract(str(fmu))
    times = []
    with tempfile.TemporaryDirectory() as tmp:
        for k in range(repeat):
            copy = Path(tmp) / f"c{k}"
            shutil.copytree(base, copy)
            t0 = time.perf_counter()
            f = FMU2Slave(guid=md.guid, unzipDirectory=str(copy), modelIdentifier=md.coSimulation.modelIdentifier,
                          instanceName="cold")
            f.instantiate()
            f.setupExperiment(startTime=0.0)
            f.enterInitializationMode()
            f.exitInitializationMode()
            f.setReal([vr["ag"]], [3.0])
            f.doStep(0.0, 0.01)
            f.getReal([vr["phi"]])
            times.append(time.perf_counter() - t0)
            f.terminate()
            f.freeInstance()
    shutil.rmtree(base, ignore_errors=True)
    return statistics.median(times)


def step_cost(fmu: Path) -> float:
    """Seconds per communication step of the rigid record scene through fmpy (setReal, doStep, getReal)."""
    import numpy as np
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave

    sys.path.insert(0, str(ROOT))
    from benchmarks.scenes import rigid_scenes

    scene = [s for s in rigid_scenes() if s.name == "record"][0]
    dt = 0.01
    n = int(round(scene.t_end / dt))
    t_rec, a_rec = scene.motion[1], scene.motion[2]
    ag = np.interp(dt * np.arange(n), t_rec, a_rec)
    md = read_model_description(str(fmu))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    unzip = extract(str(fmu))
    f = FMU2Slave(guid=md.guid, unzipDirectory=unzip, modelIdentifier=md.coSimulation.modelIdentifier,
                  instanceName="steps")
    f.instantiate()
    f.setupExperiment(startTime=0.0)
    f.enterInitializationMode()
    for key, value in {**scene.model_kw, **scene.initial}.items():
        f.setReal([vr[key]], [float(value)])
    f.exitInitializationMode()
    vin, vout = [vr["ag"]], [vr["phi"]]
    t0 = time.perf_counter()
    for k in range(n):
        f.setReal(vin, [float(ag[k])])
        f.doStep(k * dt, dt)
        f.getReal(vout)
    elapsed = time.perf_counter() - t0
    f.terminate()
    f.freeInstance()
    shutil.rmtree(unzip, ignore_errors=True)
    return elapsed / n


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--dest", default=str(ROOT / "dist"))
    parser.add_argument("--repeat", type=int, default=20)
    args = parser.parse_args(argv)
    fmus = _ensure(Path(args.dest))
    for name, fmu in fmus.items():
        print(f"{name}: {fmu.stat().st_size / 1024:.0f} KiB")
        with tempfile.TemporaryDirectory() as tmp:
            import zipfile
            so = zipfile.ZipFile(fmu).extract(f"binaries/linux64/{name}.so", tmp)
            if shutil.which("ldd"):
                out = subprocess.run(["ldd", so], capture_output=True, text=True).stdout
                print("  ldd:", "; ".join(line.strip() for line in out.splitlines()))
        print(f"  cold start (load, instantiate, initialize, first step): {cold_start(fmu, args.repeat) * 1e3:.2f} ms")
    print(f"rigid record, 3000 steps of 10 ms through fmpy: standalone {step_cost(fmus[NAMES[0]]) * 1e6:.1f} us/step")
    py = Path(args.dest) / f"{NAMES[0]}.fmu"
    if py.is_file():
        print(f"  pythonfmu FMU (Python engine, default): {step_cost(py) * 1e6:.1f} us/step")
    return 0


if __name__ == "__main__":
    sys.exit(main())
