"""System-level co-simulation: ground-motion source -> linear building storey -> rigid rocking block and
flexible rocking oscillator on the floor (examples/system/OspSystemStructure.xml).

    python examples/system/run.py [--stop 5] [--out results] [--build] [--master both|libcosim|fmpy] [--ssp]
                                  [--standalone]

Builds the FMUs into dist/ when they are missing (or with --build), runs the system in libcosim (Open
Simulation Platform, `pip install -e .[cosim]`) and with the fmpy master of rocking_model.cosim, writes
<out>/system_<master>.csv and <out>/system.png, and prints the largest difference between the two masters.
With --ssp, it also packages the system as an SSP 1.0 archive <out>/RockingSystem.ssp (the system structure,
the connections, the parameter values and the FMUs; rocking_model.cosim.write_ssp) and runs the masters on
the archive instead of the OSP file (same results: the archive holds the same system). With --standalone,
the block and the oscillator are the self-contained FMUs of dist/standalone/ (no Python inside; built by
build_fmu.py when missing) instead of the pythonfmu ones: the same results to round-off.
"""
from __future__ import annotations

import argparse
import importlib.util
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
OSP = HERE / "OspSystemStructure.xml"
FMUS = ["GroundMotionSource", "LinearBuildingStorey", "RigidRockingBlock", "FlexibleRockingOscillator"]
OUTPUTS = ["ground.ag", "storey.u", "storey.a_floor", "block.phi", "block.contact", "block.impacts",
           "block.overturned", "oscillator.phi", "oscillator.u", "oscillator.top_displacement",
           "oscillator.impacts", "oscillator.overturned"]


def build_fmus(force: bool = False) -> None:
    if not force and all((ROOT / "dist" / f"{n}.fmu").is_file() for n in FMUS):
        return
    spec = importlib.util.spec_from_file_location("build_fmu", ROOT / "build_fmu.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    module.build_all(ROOT / "dist", names=FMUS)


STANDALONE = ["RigidRockingBlock", "FlexibleRockingOscillator"]


def build_standalone(force: bool = False) -> None:
    if not force and all((ROOT / "dist" / "standalone" / f"{n}.fmu").is_file() for n in STANDALONE):
        return
    spec = importlib.util.spec_from_file_location("build_fmu", ROOT / "build_fmu.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    module.build_standalone(ROOT / "dist", names=STANDALONE)


def system(osp=None, standalone: bool = False):
    """The example's system (a rocking_model.cosim.System) from the OSP file; with ``standalone``, the block and
    the oscillator are the self-contained FMUs of dist/standalone/."""
    from rocking_model.cosim import read_osp_system_structure

    sysm = read_osp_system_structure(OSP if osp is None else osp)
    if standalone:
        for c in sysm.components:
            if Path(c.fmu).stem in STANDALONE:
                c.fmu = ROOT / "dist" / "standalone" / Path(c.fmu).name
    return sysm


def write_ssp(path, osp=None, standalone: bool = False) -> Path:
    """Package the system of the OSP file (default: the example's) as an SSP 1.0 archive at ``path``."""
    from rocking_model.cosim import write_ssp as _write_ssp

    return _write_ssp(system(osp, standalone), path, name="RockingSystem")


def run(stop: float = 5.0, master: str = "both", osp=None) -> dict:
    """Run the system (``osp``: an OspSystemStructure.xml, an .ssp archive or a System; default the
    example's OSP file); return {"fmpy": result, "libcosim": result} (structured arrays, column 'time' and
    one column per entry of OUTPUTS)."""
    from rocking_model.cosim import run_fmpy, run_libcosim

    osp = OSP if osp is None else osp
    results = {}
    if master in ("both", "fmpy"):
        results["fmpy"] = run_fmpy(osp, stop, OUTPUTS)
    if master in ("both", "libcosim"):
        try:
            import libcosimpy.CosimExecution  # noqa: F401
        except Exception as exc:
            if master == "libcosim":
                raise
            print(f"libcosimpy not available ({exc}); fmpy master only", file=sys.stderr)
        else:
            results["libcosim"] = run_libcosim(osp, stop, OUTPUTS)
    return results


def plot(result: np.ndarray, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = result["time"]
    fig, ax = plt.subplots(3, 1, figsize=(8, 7.5), sharex=True)
    ax[0].plot(t, result["ground.ag"], label="ground ag (source FMU)")
    ax[0].plot(t, result["storey.a_floor"], label="floor acceleration (storey FMU)")
    ax[0].set_ylabel("acceleration [m/s²]")
    ax[1].plot(t, result["block.phi"], label="rigid block φ")
    ax[1].plot(t, result["oscillator.phi"], label="flexible oscillator base φ")
    ax[1].set_ylabel("rotation [rad]")
    ax[2].plot(t, 1e3 * result["storey.u"], label="storey drift u")
    ax[2].plot(t, 1e3 * result["oscillator.top_displacement"], label="oscillator top displacement")
    ax[2].set_ylabel("displacement [mm]")
    ax[2].set_xlabel("time [s]")
    for a in ax:
        a.legend(loc="upper right", fontsize=8)
        a.grid(alpha=0.3)
    fig.suptitle("Co-simulation: pulse → linear storey (T = 0.5 s) → rocking block and oscillator on the floor")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--stop", type=float, default=5.0, help="stop time [s] (default 5)")
    parser.add_argument("--out", default=str(ROOT / "results"), help="output folder (default results/)")
    parser.add_argument("--build", action="store_true", help="rebuild the FMUs into dist/")
    parser.add_argument("--master", choices=["both", "libcosim", "fmpy"], default="both")
    parser.add_argument("--no-plot", action="store_true")
    parser.add_argument("--standalone", action="store_true",
                        help="the self-contained block and oscillator (dist/standalone/) instead of the pythonfmu ones")
    parser.add_argument("--ssp", action="store_true",
                        help="write <out>/RockingSystem.ssp (SSP 1.0) and run the masters on it")
    args = parser.parse_args(argv)
    sys.path.insert(0, str(ROOT))
    from rocking_model.cosim import write_csv

    build_fmus(args.build)
    if args.standalone:
        build_standalone(args.build)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    source = system(standalone=True) if args.standalone else None
    if args.ssp:
        source = write_ssp(out / "RockingSystem.ssp", standalone=args.standalone)
        print(f"wrote {source}")
    results = run(args.stop, args.master, osp=source)
    for name, res in results.items():
        write_csv(out / f"system_{name}.csv", res)
        print(f"wrote {out / f'system_{name}.csv'}")
    if "fmpy" in results and "libcosim" in results:
        a, b = results["fmpy"][1:], results["libcosim"]  # libcosim rows start at t0 + h
        diff = max(float(np.abs(a[k] - b[k]).max()) for k in OUTPUTS)
        print(f"largest difference fmpy master vs libcosim: {diff:.3g}")
    res = results.get("fmpy", results.get("libcosim"))
    print(f"peak floor acceleration {np.abs(res['storey.a_floor']).max():.3f} m/s2, peak block rotation "
          f"{np.abs(res['block.phi']).max():.4f} rad ({int(res['block.impacts'][-1])} impacts), peak oscillator "
          f"rotation {np.abs(res['oscillator.phi']).max():.4f} rad")
    if not args.no_plot:
        plot(res, out / "system.png")
        print(f"wrote {out / 'system.png'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
