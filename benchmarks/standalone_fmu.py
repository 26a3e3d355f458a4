"""The self-contained FMUs: size, shared-library dependencies, cold start and the cost of a step
through fmpy, printed (never asserted: timing depends on the machine).

    python -m benchmarks.standalone_fmu [--dest dist] [--repeat 20]

Builds dist/standalone/*.fmu if they are missing (build_fmu.build_standalone). The do-nothing FMU is the
standalone FMU's own sources/ compiled with RK_FMU_NULL_STEP (fmi2DoStep without the engine). Cold start: a fresh copy of
the extracted FMU each time (so the loader really loads the binary), then load + fmi2Instantiate +
setup/initialization + the first fmi2DoStep, in this process, median of ``--repeat``. Step cost: the
benchmark record of the rigid block (30 s synthetic record, 3000 steps of 10 ms) and the flexible
oscillator's soft-column pulse through fmpy's FMU2Slave (setReal, doStep, getReal per step), for the
standalone FMU, its do-nothing build and, when it is built, the pythonfmu FMU (rigid).
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


def null_binary(fmu: Path, unzip: Path) -> None:
    """Recompile the FMU's own sources/ (as buildDescription.xml lists them, the build's portable flags) with
    RK_FMU_NULL_STEP into the extracted ``unzip``: the same FMI layer and calls, fmi2DoStep without the engine
    (the do-nothing C FMU of the targets)."""
    import xml.etree.ElementTree as ET

    sys.path.insert(0, str(ROOT))
    import build_fmu

    src = unzip / "sources"
    bd = ET.parse(src / "buildDescription.xml").getroot()
    files = [e.get("name") for e in bd.iter("SourceFile")]
    defines = [f"-D{e.get('name')}={e.get('value')}" for e in bd.iter("PreprocessorDefinition")]
    so = unzip / "binaries" / "linux64" / f"{fmu.stem}.so"
    subprocess.run([build_fmu.find_compiler(), "-shared", *build_fmu.PORTABLE_CFLAGS, "-I.", *defines,
                    "-DRK_FMU_NULL_STEP", *files, "-o", str(so), "-lm"], check=True, cwd=src)


def step_cost(fmu: Path, null: bool = False, scene_name: str = "record") -> float:
    """Seconds per communication step of the rigid record scene through fmpy (setReal, doStep, getReal);
    ``null``: the do-nothing build of the same FMU (`null_binary`)."""
    import numpy as np
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave

    sys.path.insert(0, str(ROOT))
    from benchmarks.scenes import flexible_scenes, rigid_scenes
    from rocking_model.ground_motion import as_ground_motion

    scene = [s for s in rigid_scenes() + flexible_scenes() if s.name == scene_name][0]
    dt = 0.01
    n = int(round(scene.t_end / dt))
    gm = as_ground_motion(scene.ground_motion())
    ag = np.array([gm(k * dt) for k in range(n)])
    md = read_model_description(str(fmu))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    unzip = extract(str(fmu))
    if null:
        null_binary(fmu, Path(unzip))
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
    # the same loop, best of 3 each, in one run (the target: at most 2x the do-nothing C FMU)
    real = min(step_cost(fmus[NAMES[0]]) for _ in range(3))
    null = min(step_cost(fmus[NAMES[0]], null=True) for _ in range(3))
    print(f"rigid record, 3000 steps of 10 ms through fmpy (event-driven, tolerance 1e-8): standalone "
          f"{real * 1e6:.1f} us/step, do-nothing build of the same FMU {null * 1e6:.1f} us/step, ratio "
          f"{real / null:.2f}")
    real = min(step_cost(fmus[NAMES[1]], scene_name="flex_soft") for _ in range(3))
    null = min(step_cost(fmus[NAMES[1]], null=True, scene_name="flex_soft") for _ in range(3))
    print(f"flexible soft-column pulse, 500 steps of 10 ms through fmpy (event-driven, tolerance 1e-8): "
          f"standalone {real * 1e6:.1f} us/step, do-nothing build {null * 1e6:.1f} us/step, ratio {real / null:.2f}")
    py = Path(args.dest) / f"{NAMES[0]}.fmu"
    if py.is_file():
        print(f"  pythonfmu FMU (Python engine, default): {step_cost(py) * 1e6:.1f} us/step")
    return 0


if __name__ == "__main__":
    sys.exit(main())
