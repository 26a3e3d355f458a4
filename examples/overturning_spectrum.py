"""Overturning spectrum of a rigid block under one-sine pulses (Housner 1963, Makris & Roussos 2000).

    python examples/overturning_spectrum.py [--workers 2] [--address tcp://...] [--out results]

Grid: amplitude ratio A / (g tan(alpha)) = 1.0, 1.25, ..., 8 times frequency ratio omega_p / p = 1, 1.5, ...,
12 (667 cases) for the block b = 0.2 m, h = 1.0 m (alpha = 0.197 rad, p = 2.69 rad/s), event-driven scheme,
each run to the end of the pulse plus 15/p. Runs on a local Dask cluster through `rocking_model.ensemble`
(results in OUT/overturning_spectrum.csv; rerunning resumes) and writes OUT/overturning_spectrum.png; OUT is
--out (default results/, git-ignored); ``run(out=folder)`` does the same from Python and returns the figure's
path. Equivalent command line:

    rocking ensemble --pulse sine --amplitude-ratios 1:8:29 --frequency-ratios 1:12:23 --b 0.2 --h 1.0 \
        --out results/overturning_spectrum.csv --plot results/overturning_spectrum.png
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from rocking_model.ensemble import pulse_cases, read_results, run_ensemble
from rocking_model.plotting import plot_overturning_spectrum

ROOT = Path(__file__).resolve().parents[1]


def run(out: Path = ROOT / "results", workers: int = 2, address: str | None = None) -> Path:
    """Run (or resume) the grid into ``out``/overturning_spectrum.csv, plot ``out``/overturning_spectrum.png;
    return the figure's path."""
    out_dir = Path(out)
    out_dir.mkdir(parents=True, exist_ok=True)
    cases = pulse_cases("sine", amplitude_ratios=np.linspace(1.0, 8.0, 29), frequency_ratios=np.linspace(1.0, 12.0, 23),
                        geometries=[(0.2, 1.0)])
    csv = out_dir / "overturning_spectrum.csv"
    s = run_ensemble(cases, csv, workers=workers, address=address)
    print(f"{len(cases)} cases: ran {s['n_run']}, {s['n_skipped']} already done; "
          f"{s['throughput']:.1f} cases/s" if s["n_run"] else f"{len(cases)} cases already done")
    ids = {c["case_id"] for c in cases}
    rows = [r for r in read_results(csv) if r["case_id"] in ids]
    png = plot_overturning_spectrum(rows, out_dir / "overturning_spectrum.png",
                                    title="Overturning spectrum, one-sine pulse, rigid block b = 0.2 m, h = 1.0 m "
                                          "(event-driven)")
    print(f"wrote {png}")
    return Path(png)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--address")
    ap.add_argument("--out", default=str(ROOT / "results"), help="output folder (default results/)")
    args = ap.parse_args(argv)
    run(Path(args.out), args.workers, args.address)
    return 0


if __name__ == "__main__":
    sys.exit(main())
