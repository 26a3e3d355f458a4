"""A three-component record (horizontal plus vertical) on both models: the difference the vertical makes.

Reads the shipped synthetic record examples/records/synthetic_2017.AT2 (horizontal ag, PGA 0.4 g) with its
vertical component examples/records/synthetic_2017-UP.AT2 (ag_v, positive upward, PGA 0.3 g; both written by
examples/records/make_synthetic_record.py) and runs the rigid block (b = 0.4 m, h = 2.0 m) and the flexible
rocking oscillator (its default specimen) twice each: under the horizontal component alone and under both. The
vertical acceleration is an effective gravity g + ag_v: it scales the restoring moment and moves the uplift
threshold (g + ag_v) tan(alpha) of the block.

Writes OUT/three_component.png (OUT: --out, a folder, default results/, git-ignored; a path ending in .png is
the file itself): both components with the block's uplift threshold, then for each model the
rotation phi with and without the vertical component and their difference. Run:

    python examples/three_component.py [--t-end 35] [--out results]

``run(out=folder)`` does the same from Python (the docs build calls it).
"""
from __future__ import annotations

import argparse
import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from rocking_model import FlexibleOscillator, RigidBlock, simulate  # noqa: E402
from rocking_model.records import read_at2  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
RECORD = ROOT / "examples" / "records" / "synthetic_2017.AT2"
VERTICAL = ROOT / "examples" / "records" / "synthetic_2017-UP.AT2"


def run(t_end: float = 35.0, out: Path = ROOT / "results", output_interval: float = 0.01) -> dict:
    """Run both models with and without the vertical component up to ``t_end`` [s], plot to
    ``out``/three_component.png (``out`` ending in .png: that file); return {model title: (result without,
    result with the vertical)}."""
    out = Path(out)
    if out.suffix != ".png":
        out = out / "three_component.png"
    rec = read_at2(RECORD, vertical=VERTICAL)          # one Record: ag and its vertical component ag_v
    models = {"rigid block b = 0.4 m, h = 2.0 m": RigidBlock(b=0.4, h=2.0),
              "flexible oscillator (default specimen)": FlexibleOscillator()}
    runs = {name: (simulate(m, rec.horizontal, t_end, output_interval=output_interval),
                   simulate(m, rec, t_end, output_interval=output_interval))
            for name, m in models.items()}

    fig, ax = plt.subplots(1 + 2 * len(models), 1, figsize=(9, 12), sharex=True,
                           gridspec_kw={"height_ratios": [2.2] + [2, 1.2] * len(models)})
    blk = models["rigid block b = 0.4 m, h = 2.0 m"]
    t = np.linspace(0.0, t_end, int(round(t_end / 0.005)) + 1)
    ag = np.array([rec(x) for x in t])
    ag_v = np.array([rec.vertical(x) for x in t])
    ax[0].plot(t, ag, color="C1", lw=0.8, label="$a_g$ (horizontal)")
    ax[0].plot(t, ag_v, color="C9", lw=0.8, label="$a_{g,v}$ (vertical, up)")
    tan_a = math.tan(blk.alpha)
    ax[0].plot(t, (blk.g + ag_v) * tan_a, color="k", ls=":", lw=0.8,
               label=r"$\pm(g + a_{g,v})\tan\alpha$, block uplift")
    ax[0].plot(t, -(blk.g + ag_v) * tan_a, color="k", ls=":", lw=0.8)
    ax[0].axhline(blk.g * tan_a, color="grey", ls="--", lw=0.6, label=r"$\pm g\tan\alpha$ (no vertical)")
    ax[0].axhline(-blk.g * tan_a, color="grey", ls="--", lw=0.6)
    ax[0].set_ylabel("ground acc. [m/s$^2$]")
    ax[0].set_title("Three-component synthetic record (horizontal 0.4 g, vertical 0.3 g): rocking with and "
                    "without the vertical component", fontsize=10)
    for k, (name, (h_only, both)) in enumerate(runs.items()):
        a, d = ax[1 + 2 * k], ax[2 + 2 * k]
        a.plot(h_only.t, h_only.phi, color="C0", lw=1.0, label=f"horizontal only ({int(h_only.impacts[-1])} impacts)")
        a.plot(both.t, both.phi, color="C3", lw=0.9, ls="--",
               label=f"horizontal + vertical ({int(both.impacts[-1])} impacts)")
        a.set_ylabel(r"$\varphi$ [rad]")
        a.set_title(name, fontsize=9)
        d.plot(both.t, both.phi - h_only.phi, color="C4", lw=0.9, label="difference (with - without)")
        d.set_ylabel(r"$\Delta\varphi$ [rad]")
        for x in (a, d):
            x.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, borderaxespad=0.0)
    ax[0].legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, borderaxespad=0.0)
    ax[-1].set_xlabel("time t [s]")
    for x in ax:
        x.grid(alpha=0.3)
    fig.tight_layout()
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=80, bbox_inches="tight")
    plt.close(fig)
    for name, (h_only, both) in runs.items():
        print(f"{name}: max |phi| {np.max(np.abs(h_only.phi)):.4g} rad without, {np.max(np.abs(both.phi)):.4g} "
              f"rad with the vertical component; impacts {int(h_only.impacts[-1])} / {int(both.impacts[-1])}; "
              f"overturned {bool(h_only.overturned[-1])} / {bool(both.overturned[-1])}")
    print(f"wrote {out}")
    return runs


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--t-end", type=float, default=35.0, help="end time [s] (default 35: the record plus 5 s)")
    ap.add_argument("--out", default=str(ROOT / "results"),
                    help="output folder (default results/), or the PNG to write")
    args = ap.parse_args(argv)
    run(args.t_end, Path(args.out))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
