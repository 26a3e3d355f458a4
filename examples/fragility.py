"""Fragility curves of a slender rigid block for three damage states, from a multiple-stripe analysis of a
synthetic suite of records.

    python examples/fragility.py [--out OUT_DIR] [--records 12] [--stripes 16] [--duration 30] [--workers 2]

Block b = 0.15 m, h = 1.0 m (alpha = 0.149 rad, p = 2.70 rad/s); records synthetic:1 ... synthetic:12 (30 s
Clough-Penzien accelerograms; shorter ones with --duration, written as CSV files first); stripes of
PGA/(g tan alpha) = 0.8 ... 4 (the dimensionless measure: 1 is the uplift threshold of a block at rest);
damage states |phi|max/alpha >= 0.2, |phi|max/alpha >= 0.5 and overturning (overturning reaches every one),
fitted by maximum likelihood over the stripes with 200 bootstrap resamples over records for the bands.
Writes OUT_DIR/cases.csv (a rerun resumes), fragility.csv, fragility.json and fragility.png (--out, default
results/fragility_example/, git-ignored; also as the first argument). Equivalent command line (30 s records):

    rocking fragility --records synthetic:1 ... synthetic:12 --im "PGA/(g tan alpha)" --b 0.15 --h 1.0 \
        --stripes 0.8:4:16 --out results/fragility_example
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from rocking_model import assessment as A

ROOT = Path(__file__).resolve().parents[1]
IM = "PGA/(g tan alpha)"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=str(ROOT / "results" / "fragility_example"),
                    help="output folder (default results/fragility_example/, git-ignored)")
    ap.add_argument("out_pos", nargs="?", metavar="OUT", help="the output folder, as --out")
    ap.add_argument("--records", type=int, default=12, help="synthetic records (default 12)")
    ap.add_argument("--stripes", type=int, default=16, help="stripes (default 16)")
    ap.add_argument("--duration", type=float, default=30.0, help="record duration [s] (default 30)")
    ap.add_argument("--workers", type=int, default=2, help="Dask workers (0: serial)")
    ap.add_argument("--bootstrap", type=int, default=200)
    args = ap.parse_args(argv)
    out = Path(args.out_pos or args.out)
    out.mkdir(parents=True, exist_ok=True)
    records = [f"synthetic:{i}" for i in range(1, args.records + 1)]
    if args.duration != 30.0:          # shorter records (a quicker run): written once as CSV files
        from rocking_model.records import synthetic_record, write_csv
        folder = out / "records"
        folder.mkdir(exist_ok=True)
        records = []
        for i in range(1, args.records + 1):
            t, a = synthetic_record(duration=args.duration, seed=i, t_rise=min(2.0, args.duration / 6),
                                    t_strong=args.duration * 0.4)
            records.append(str(write_csv(folder / f"synthetic_{i}.csv", t, a, units="m/s2")))
    r = A.run_msa(records, IM, np.linspace(0.8, 4.0, args.stripes), out / "cases.csv", geometries=[(0.15, 1.0)],
                  damage_states=["phi/alpha>=0.2", "phi/alpha>=0.5", "overturned"], n_boot=args.bootstrap,
                  workers=args.workers, progress=args.workers > 0)
    s = r.summary
    print(f"{len(r.rows)} cases ({s['n_run']} run, {s['n_skipped']} already in {out / 'cases.csv'})")
    for f in r.fragilities:
        lo, hi = f.bands.theta_band if f.bands is not None else (np.nan, np.nan)
        print(f"  {f.ds:16s} theta = {f.fit.theta:.3f} [{lo:.3f}, {hi:.3f}], beta = {f.fit.beta:.3f}")
    written = A.write_fragilities(r.fragilities, out, im_label=IM,
                                  title="Slender block b = 0.15 m, h = 1.0 m")
    print("wrote " + ", ".join(map(str, written)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
