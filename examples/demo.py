"""Demo scene: the RigidRockingBlock FMU under a one-sine ground-acceleration pulse, driven by fmpy.

    python build_fmu.py && python examples/demo.py [--out results]

Block b = 0.2 m, h = 1.0 m (slenderness alpha = atan(b/h) = 0.197 rad; uplift needs |ag| > g tan(alpha) =
1.96 m/s2), pulse ag = A sin(omega_p t) for one period with A = 3 m/s2, omega_p = 2 pi 2 rad/s. The block
uplifts and keeps rocking with slowly decaying amplitude (Housner restitution ~0.94 per impact); it does
not overturn.

Writes OUT/demo_rigid.csv and OUT/demo_rigid.png (rotation, ground acceleration, contact state); OUT is
--out (default results/, git-ignored). ``run(out=folder)`` does the same from Python (the docs build calls it).
The FMU's second input, the vertical ground acceleration ag_v, is given as zeros in the input table (fmpy
warns about every input the table leaves out).
"""
from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
FMU = ROOT / "dist" / "RigidRockingBlock.fmu"
RESULTS = ROOT / "results"

PARAMS = dict(b=0.2, h=1.0, m=1.0, g=9.81, e_N=0.0, scheme=1, dt_max=1e-3, tolerance=1e-8)
A = 3.0                        # pulse amplitude [m/s2]
OMEGA_P = 2.0 * math.pi * 2.0  # pulse circular frequency [rad/s]
T_END = 4.0                    # [s]
DT = 0.005                     # communication step = output interval [s]
CONTACT_LABELS = ["full", "left corner", "right corner", "flight"]


def pulse_table(t_end=T_END, dt_table=1e-3):
    """Input table for fmpy (structured array 'time', 'ag', 'ag_v'; ag_v, the vertical component, zero);
    fmpy holds its interpolant at step starts."""
    t = np.arange(0.0, t_end + 0.5 * dt_table, dt_table)
    t_p = 2.0 * math.pi / OMEGA_P
    ag = np.where(t <= t_p, A * np.sin(OMEGA_P * np.minimum(t, t_p)), 0.0)
    return np.array(list(zip(t, ag, np.zeros_like(t))),
                    dtype=[("time", np.float64), ("ag", np.float64), ("ag_v", np.float64)])


def run(out: Path = RESULTS) -> int:
    """Run the demo, write ``out``/demo_rigid.csv and ``out``/demo_rigid.png; 0 on success."""
    out = Path(out)
    from rocking_model.fmi import FMUError, run_fmu

    if not FMU.exists():
        print(f"{FMU} not found: run `python build_fmu.py` first", file=sys.stderr)
        return 1
    table = pulse_table()
    try:
        res = run_fmu(FMU, stop_time=T_END, output_interval=DT, input=table, start_values=PARAMS)
    except FMUError as exc:
        print(f"demo: {exc}", file=sys.stderr)
        return 1

    t = res["time"]
    # the ground acceleration the FMU saw over [t_k, t_k+1): the table's interpolant at t_k (zero-order hold)
    ag = np.interp(t, table["time"], table["ag"])
    phi = res["phi"]
    alpha = math.atan2(PARAMS["b"], PARAMS["h"])
    k_max = int(np.argmax(np.abs(phi)))
    print(f"RigidRockingBlock: b = {PARAMS['b']} m, h = {PARAMS['h']} m, alpha = {alpha:.4f} rad; "
          f"one-sine pulse A = {A} m/s2 (g tan(alpha) = {PARAMS['g'] * math.tan(alpha):.3f} m/s2), "
          f"omega_p = {OMEGA_P:.3f} rad/s; scheme = {'event-driven' if PARAMS['scheme'] else 'Moreau-Jean'}")
    print(f"  max |phi|   = {abs(phi[k_max]):.4f} rad ({abs(phi[k_max]) / alpha:.2f} alpha) at t = {t[k_max]:.3f} s")
    print(f"  impacts     = {int(res['impacts'][-1])}")
    print(f"  overturned  = {bool(res['overturned'][-1])}")
    print(f"  final state = {CONTACT_LABELS[int(res['contact'][-1])]} contact, phi = {phi[-1]:.2e} rad")
    if abs(phi[k_max]) < 1e-3 or res["overturned"][-1]:
        print("demo: the pulse should make the block rock without overturning", file=sys.stderr)
        return 1

    out.mkdir(parents=True, exist_ok=True)
    names = ["phi", "phi_dot", "x", "y", "x_dot", "y_dot", "energy", "contact", "impacts", "overturned"]
    data = np.column_stack([t, ag] + [res[n].astype(float) for n in names])
    header = "time [s],ag [m/s2],phi [rad],phi_dot [rad/s],x [m],y [m],x_dot [m/s],y_dot [m/s],energy [J]," \
             "contact [0 full/1 left/2 right/3 flight],impacts,overturned"
    np.savetxt(out / "demo_rigid.csv", data, delimiter=",", header=header, comments="",
               fmt=["%.6f", "%.9g"] + ["%.9g"] * 7 + ["%d", "%d", "%d"])

    fig, axes = plt.subplots(3, 1, figsize=(8, 7), sharex=True,
                             gridspec_kw={"height_ratios": [3, 2, 1.3]})
    ax = axes[0]
    ax.plot(t, phi, color="C0", label=r"$\varphi$ (FMU)")
    for s in (1, -1):
        ax.axhline(s * alpha, color="grey", ls="--", lw=0.8)
    ax.text(0.0, 0.93 * alpha, r"$\pm\alpha$ (overturning scale)", va="top", ha="left", color="grey")
    impacts = np.flatnonzero(np.diff(res["impacts"]) > 0) + 1
    ax.plot(t[impacts], phi[impacts], "x", color="C3", ms=5, label="impact (step end)")
    ax.set_ylabel(r"rotation $\varphi$ [rad]")
    ax.legend(loc="upper right")
    ax.set_title(f"Rigid rocking block (FMU via fmpy), b = {PARAMS['b']} m, h = {PARAMS['h']} m\n"
                 f"one-sine pulse A = {A} m/s², f = {OMEGA_P / (2 * math.pi):g} Hz", fontsize=10)
    ax = axes[1]
    ax.step(t, ag, where="post", color="C1", label="ag held over each step")
    ax.axhline(PARAMS["g"] * math.tan(alpha), color="grey", ls=":", lw=0.8)
    ax.axhline(-PARAMS["g"] * math.tan(alpha), color="grey", ls=":", lw=0.8)
    ax.set_ylabel(r"$a_g$ [m/s$^2$]")
    ax.legend(loc="upper right")
    ax = axes[2]
    ax.step(t, res["contact"], where="post", color="C2")
    ax.set_yticks(range(4), CONTACT_LABELS)
    ax.set_ylim(-0.5, 3.5)
    ax.set_ylabel("contact")
    ax.set_xlabel("time t [s]")
    for a in axes:
        a.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(out / "demo_rigid.png", dpi=120)
    plt.close(fig)
    print(f"wrote {out / 'demo_rigid.csv'} and {out / 'demo_rigid.png'}")
    return 0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=str(RESULTS), help="output folder (default results/)")
    return run(Path(ap.parse_args(argv).out))


if __name__ == "__main__":
    sys.exit(main())
