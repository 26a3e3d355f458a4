"""A rocking bridge pier, free-standing and post-tensioned: what the tendon changes.

A pier of 1 m x 5 m (b = 0.5 m, h = 2.5 m) and 20 t rocks on its foundation (`PostTensionedBlock`): free-standing
(P0 = k_t = 0, the rigid rocking block) and held by a vertical unbonded tendon of axial stiffness k_t = 2e7 N/m
(about 560 mm2 of strand over 5 m) post-tensioned to P0 = 100 kN and P0 = 300 kN (about 0.5 and 1.5 times the
pier's weight, 196 kN). The tendon raises the uplift threshold from g tan(alpha) to tan(alpha) (g + P0/m) and
adds a restoring moment as the pier rocks.

Each pier runs under the shipped synthetic record (examples/records/synthetic_2017.AT2, PGA 0.4 g) scaled by 2
(PGA 0.8 g) and two one-sine pulses; the table gives the peak rotation, the rotation left at the end
(re-centring), the impacts, whether it overturned and the largest tendon force. The plot shows the rotation under
the record and the tendon force history. The tendon is linear elastic: a real one would yield near 1 MN here
(560 mm2 at 1860 MPa), which the model does not represent. Run:

    python examples/post_tensioned_pier.py [--t-end 30] [--scale 2] [--out results]

(--out: a folder, default results/, git-ignored, the plot is OUT/post_tensioned_pier.png; or a path ending in
.png.) ``run(out=folder)`` does the same from Python (the docs build calls it).
"""
from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np

from rocking_model import PostTensionedBlock, SinePulse, simulate
from rocking_model.records import read_at2

ROOT = Path(__file__).resolve().parents[1]
RECORD = ROOT / "examples" / "records" / "synthetic_2017.AT2"
PIER = dict(b=0.5, h=2.5, m=20e3)                  # [m], [m], [kg]
K_T = 2e7                                          # [N/m] tendon axial stiffness E_t A_t / L_t
PIERS = {"free-standing": dict(P0=0.0, k_t=0.0),
         "P0 = 100 kN": dict(P0=100e3, k_t=K_T),
         "P0 = 300 kN": dict(P0=300e3, k_t=K_T)}
#: one-sine pulses (A [m/s2], omega_p [rad/s]): a long 1 Hz pulse and a short 2.5 Hz one
PULSES = {"pulse 0.45 g, 1 Hz": (0.45 * 9.81, 2 * math.pi),
          "pulse 0.9 g, 2.5 Hz": (0.9 * 9.81, 5 * math.pi)}


def summary(res) -> dict:
    """Peak and final rotation [rad], impacts, overturned, largest tendon force [N] of one run."""
    return {"peak_phi": float(np.max(np.abs(res.phi))), "final_phi": float(abs(res.phi[-1])),
            "impacts": int(res.impacts[-1]), "overturned": bool(res.overturned[-1]),
            "max_tendon_force": float(np.max(res.tendon_force))}


def run(t_end: float = 30.0, out: Path | None = ROOT / "results",
        output_interval: float = 0.01, scale: float = 2.0) -> dict:
    """Run every pier under the record times ``scale`` (up to ``t_end`` [s]) and the pulses (8 s); print the
    table, plot to ``out``/post_tensioned_pier.png (``out`` ending in .png: that file; None: no plot); return {"table": {(pier, motion): summary}, "record": {pier:
    Result}}."""
    rec = read_at2(RECORD).scaled(scale)
    motions = {"record": (rec, t_end)}
    motions.update({name: (SinePulse(A, w), 8.0) for name, (A, w) in PULSES.items()})
    table, record_runs = {}, {}
    for pier, tendon in PIERS.items():
        model = PostTensionedBlock(**PIER, **tendon)
        for motion, (gm, t) in motions.items():
            res = simulate(model, gm, t, output_interval=output_interval)
            table[(pier, motion)] = summary(res)
            if motion == "record":
                record_runs[pier] = res
    model = PostTensionedBlock(**PIER)
    print(f"pier b = {PIER['b']} m, h = {PIER['h']} m, m = {PIER['m'] / 1e3:g} t; alpha = {model.alpha:.4f} rad, "
          f"p = {model.p:.3f} rad/s; uplift at |ag| > tan(alpha) (g + P0/m)")
    print(f"{'pier':15s} {'motion':22s} {'uplift [g]':>10s} {'peak phi':>9s} {'final phi':>10s} {'impacts':>8s} "
          f"{'overturned':>10s} {'max T [kN]':>10s}")
    for (pier, motion), s in table.items():
        uplift = math.tan(model.alpha) * (1.0 + PIERS[pier]["P0"] / (PIER["m"] * model.g))
        print(f"{pier:15s} {motion:22s} {uplift:10.3f} {s['peak_phi']:9.4f} {s['final_phi']:10.2e} "
              f"{s['impacts']:8d} {str(s['overturned']):>10s} {s['max_tendon_force'] / 1e3:10.1f}")
    if out is not None:
        out = Path(out)
        plot(record_runs, rec, t_end, out if out.suffix == ".png" else out / "post_tensioned_pier.png", scale)
    return {"table": table, "record": record_runs}


def plot(runs: dict, rec, t_end: float, out: Path, scale: float) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(3, 1, figsize=(9, 8), sharex=True, gridspec_kw={"height_ratios": [1, 2, 1.5]})
    t = np.linspace(0.0, t_end, int(round(t_end / 0.005)) + 1)
    ax[0].plot(t, [rec(x) / 9.81 for x in t], color="C7", lw=0.7)
    ax[0].set_ylabel("$a_g$ [g]")
    for k, (pier, res) in enumerate(runs.items()):
        ax[1].plot(res.t, res.phi, color=f"C{k}", lw=0.9, label=pier)
        if PIERS[pier]["k_t"] > 0:
            ax[2].plot(res.t, res.tendon_force / 1e3, color=f"C{k}", lw=0.9, label=pier)
    for k, (pier, res) in enumerate(runs.items()):
        if res.overturned[-1]:          # the panel keeps the rocking of the others readable
            t_o = float(res.t[np.argmax(res.overturned)])
            ax[1].axvline(t_o, color=f"C{k}", ls=":", lw=0.9)
            ax[1].annotate(f"{pier} overturns at {t_o:.1f} s", (t_o, 0.12), xytext=(4, 0),
                           textcoords="offset points", color=f"C{k}", fontsize=8)
    ax[1].set_ylim(-0.15, 0.15)
    ax[1].set_ylabel(r"rotation $\phi$ [rad]")
    ax[1].legend(loc="upper right", fontsize=8)
    ax[2].set_ylabel("tendon force [kN]")
    ax[2].set_xlabel("time [s]")
    ax[2].legend(loc="upper right", fontsize=8)
    ax[0].set_title("Rocking pier 1 m x 5 m, 20 t: free-standing and post-tensioned (k_t = 2e7 N/m), "
                    f"synthetic record x {scale:g}", fontsize=10)
    fig.tight_layout()
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=110)
    plt.close(fig)
    print(f"wrote {out}")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--t-end", type=float, default=30.0, help="duration of the record runs [s]")
    ap.add_argument("--scale", type=float, default=2.0, help="scale factor of the record (PGA 0.4 g at 1)")
    ap.add_argument("--out", type=Path, default=ROOT / "results",
                    help="output folder (default results/), or the plot file (.png)")
    args = ap.parse_args(argv)
    run(args.t_end, args.out, scale=args.scale)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
