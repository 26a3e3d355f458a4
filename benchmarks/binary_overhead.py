"""Per-call overhead of the FMU binary: the do-nothing slave (benchmarks/fmu_null/NullSlave.py, a
plain pythonfmu Fmi2Slave) built twice, once with pythonfmu 0.7's prebuilt wrapper and once with the project's
binary (build_fmu.compile_binary + install_binary), both driven by fmpy's FMU2Slave in the same process:
setReal(ag) + doStep + getReal(y) per step, and each call alone. Rounds alternate between the binaries and
the median of the rounds is reported, so both see the same machine state.

With --models, the same calls on the rigid and flexible FMUs (project binary, compiled engine) at rest (ag =
1 m/s2, below uplift): what the slave and one call into the engine add to each FMI call over the null slave.

Usage: python -m benchmarks.binary_overhead [--steps 20000] [--rounds 7] [--models]
"""
from __future__ import annotations

import argparse
import shutil
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
HERE = Path(__file__).resolve().parent


def build(dest: Path) -> dict:
    """{'pythonfmu': fmu, 'project': fmu}: the null FMU with each binary."""
    sys.path.insert(0, str(ROOT))
    import build_fmu
    from pythonfmu.builder import FmuBuilder

    script = HERE / "fmu_null" / "NullSlave.py"
    (dest / "pythonfmu").mkdir(parents=True)
    (dest / "project").mkdir(parents=True)
    original = Path(FmuBuilder.build_FMU(script, dest=dest / "pythonfmu"))
    ours = dest / "project" / original.name
    shutil.copy2(original, ours)
    build_fmu.install_binary(ours, build_fmu.compile_binary(dest), script)
    return {"pythonfmu": original, "project": ours}


class Driver:
    def __init__(self, fmu: Path, name: str, output: str = "y"):
        from fmpy import extract, read_model_description
        from fmpy.fmi2 import FMU2Slave

        md = read_model_description(str(fmu))
        self.vr = {v.name: v.valueReference for v in md.modelVariables}
        self.vr["y"] = self.vr[output]
        self.fmu = FMU2Slave(guid=md.guid, unzipDirectory=extract(str(fmu)),
                             modelIdentifier=md.coSimulation.modelIdentifier, instanceName=name)
        self.fmu.instantiate()
        self.fmu.setupExperiment(startTime=0.0)
        self.fmu.enterInitializationMode()
        self.fmu.exitInitializationMode()
        self.t = 0.0

    def run(self, n: int, what: str) -> float:
        """[µs] per iteration of ``what``."""
        f, ag, y, h = self.fmu, [self.vr["ag"]], [self.vr["y"]], 1e-3
        t = self.t
        t0 = time.perf_counter()
        if what == "set+step+get":
            for k in range(n):
                f.setReal(ag, [1.0])
                f.doStep(t, h)
                t += h
                f.getReal(y)
        elif what == "doStep":
            for k in range(n):
                f.doStep(t, h)
                t += h
        elif what == "setReal":
            for k in range(n):
                f.setReal(ag, [1.0])
        else:
            for k in range(n):
                f.getReal(y)
        self.t = t
        return (time.perf_counter() - t0) / n * 1e6


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=20000)
    parser.add_argument("--rounds", type=int, default=7)
    parser.add_argument("--models", action="store_true",
                        help="also the rigid and flexible FMUs (project binary) at rest")
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        fmus = build(Path(tmp))
        drivers = {k: Driver(p, k) for k, p in fmus.items()}
        models = {}
        if args.models:
            import build_fmu
            built = build_fmu.build_all(Path(tmp) / "models", ["RigidRockingBlock", "FlexibleRockingOscillator"])
            models = {p.stem: Driver(p, p.stem, output="phi") for p in built}
        check = {k: (d.fmu.setReal([d.vr["ag"]], [2.5]), d.fmu.doStep(d.t, 1e-3), d.fmu.getReal([d.vr["y"]])[0])[2]
                 for k, d in drivers.items()}
        for d in drivers.values():
            d.t += 1e-3
        assert check["pythonfmu"] == check["project"] == 2.5, check
        print(f"null slave, {args.steps} iterations x {args.rounds} rounds (median), fmpy FMU2Slave; µs per call")
        for what in ("set+step+get", "setReal", "doStep", "getReal"):
            times = {k: [] for k in drivers}
            for _ in range(args.rounds):
                for k, d in drivers.items():
                    times[k].append(d.run(args.steps, what))
                for k, d in models.items():
                    times.setdefault(k, []).append(d.run(args.steps, what))
            med = {k: statistics.median(v) for k, v in times.items()}
            print(f"  {what:<13} pythonfmu 0.7 {med['pythonfmu']:7.2f}   project {med['project']:7.2f}   "
                  f"ratio project/pythonfmu {med['project'] / med['pythonfmu']:.2f}"
                  + "".join(f"   {k} {med[k]:7.2f} ({med[k] / med['pythonfmu']:.2f}x)" for k in models))
        for d in [*drivers.values(), *models.values()]:
            d.fmu.terminate()
            d.fmu.freeInstance()
    return 0


if __name__ == "__main__":
    sys.exit(main())
