"""A 10,000-case multiple-stripe analysis of the rigid block, end to end, against the engine's own time per case;
written to docs/performance/fragility.md.

    python benchmarks/fragility_bench.py [--quick] [--workers 2] [--out docs/performance/fragility.md]

Suite: 20 synthetic 30 s records (synthetic:1 ... synthetic:20, 0.01 s samples) x 100 stripes of
PGA/(g tan alpha) = 0.5 ... 4 x 5 geometries (b = 0.1 ... 0.3 m, h = 1 m) = 10,000 cases, event-driven
(tolerance 1e-8), each to the record's end + 5 s with output every 0.01 s (quick: 4 records x 20 stripes x 5
geometries = 400 cases). The clock runs from the records' specs to the written outputs: reading (generating)
the records, their intensity measures, the cases and their ids, the Dask cluster's start, the runs, the rows
written to CSV, the fits of three damage states with 200 bootstrap resamples each and their CSV, JSON and
plots (`rocking_model.assessment.run_msa`, `write_fragilities`). The engine's own time per case is
`simulate` alone on a sample of the same cases, serially, records and models already built.
"""
from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

if __package__ in (None, ""):
    sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

import numpy as np

from benchmarks.ensemble_bench import machine
from rocking_model import assessment as A
from rocking_model import ensemble as E

ROOT = Path(__file__).resolve().parent.parent
IM = "PGA/(g tan alpha)"


def suite_spec(quick: bool) -> tuple[list[str], list[float], list[tuple[float, float]]]:
    n_rec, n_stripes = (4, 20) if quick else (20, 100)
    records = [f"synthetic:{i}" for i in range(1, n_rec + 1)]
    return records, list(np.linspace(0.5, 4.0, n_stripes)), [(b, 1.0) for b in np.linspace(0.1, 0.3, 5)]


def engine_time(cases: list[dict], n: int = 500) -> tuple[float, float]:
    """(engine [s], run_case [s]) per case, means over ``n`` random cases run serially here (the records and
    models built beforehand: the engine's `simulate` alone, and the whole `run_case`); means, as the throughput
    is (the cases at rest, rocking and overturning early cost differently)."""
    from rocking_model.simulation import simulate

    rng = np.random.default_rng(0)
    sample = [cases[i] for i in rng.choice(len(cases), size=min(n, len(cases)), replace=False)]
    eng, whole = [], []
    for c in sample:
        model, motion = E.case_model(c), E.case_motion(c)
        t0 = time.perf_counter()
        simulate(model, motion, c["t_end"], scheme=c["scheme"], output_interval=c["output_interval"],
                 tolerance=c["tolerance"])
        eng.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        E.run_case(c)
        whole.append(time.perf_counter() - t0)
    return float(np.mean(eng)), float(np.mean(whole))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--out", default=str(ROOT / "docs" / "performance" / "fragility.md"))
    args = ap.parse_args(argv)
    records, stripes, geometries = suite_spec(args.quick)
    info = machine()
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()                  # (the cases alone, a stage of run_msa, timed apart)
        cases = A.msa_cases(records, IM, stripes, geometries=geometries)
        t_cases = time.perf_counter() - t0
        E._record.cache_clear()                    # the timed run reads (generates) the records again
        t0 = time.perf_counter()
        r = A.run_msa(records, IM, stripes, Path(tmp) / "cases.csv", geometries=geometries,
                      workers=args.workers, n_boot=200, progress=False)
        t_run = time.perf_counter() - t0
        written = A.write_fragilities(r.fragilities, Path(tmp) / "out", im_label=IM)
        total = time.perf_counter() - t0
        n = len(r.rows)
        assert n == len(cases) and r.summary["n_errors"] == 0, r.summary
        n_over = sum(row["overturned"] for row in r.rows)
        in_workers = float(np.mean([row["wall_time"] for row in r.rows]))
    eng, whole = engine_time(cases)
    load_end = os.getloadavg()[0]
    s = r.summary
    lines = [
        "### Fragility: a 10,000-case multiple-stripe analysis" if not args.quick else
        "### Fragility: a multiple-stripe analysis (quick)",
        "",
        f"`python benchmarks/fragility_bench.py{' --quick' if args.quick else ''}` "
        f"({time.strftime('%Y-%m-%d %H:%M')}): {len(records)} synthetic 30 s records x {len(stripes)} stripes of "
        f"{IM} = {stripes[0]:g}...{stripes[-1]:g} x {len(geometries)} rigid blocks (b = "
        f"{geometries[0][0]:g}...{geometries[-1][0]:g} m, h = 1 m) = {n} cases ({n_over} overturn), event-driven, "
        f"on {args.workers} Dask workers; three damage states fitted with 200 bootstrap resamples each.",
        "",
        f"**{total:.1f} s end to end, {n / total:.0f} cases/s** (records, intensity measures, cases, cluster start, "
        "runs, CSV rows, fits, CSV/JSON/plots).",
        "",
        "| stage | time [s] |",
        "| --- | --- |",
        f"| `run_msa`: records read, measures, cases, cluster, runs, rows read back, fits with bootstrap | "
        f"{t_run:.2f} |",
        f"| of which: records read, measures, {n} cases and their ids (timed apart) | {t_cases:.2f} |",
        f"| of which: cluster start | {s['setup_time']:.2f} |",
        f"| of which: the runs on Dask, rows written to CSV ({s['throughput']:.0f} cases/s) | {s['wall_time']:.2f} |",
        f"| `write_fragilities`: plots and parameter files ({len(written)} files) | {total - t_run:.2f} |",
        f"| **total** | **{total:.2f}** |",
        "",
        f"Per case (means): the engine's `simulate` {eng * 1e3:.3f} ms, `run_case` {whole * 1e3:.3f} ms here "
        f"serially, {in_workers * 1e3:.3f} ms inside the workers; the run's {s['throughput']:.0f} cases/s on "
        f"{args.workers} workers against {args.workers / eng:.0f} cases/s for {args.workers} cores of engine time "
        f"alone ({s['throughput'] * eng / args.workers:.0%} of it); end to end {n / total:.0f} cases/s.",
        "",
        f"Machine: {info}; load average {load_end:.2f} at the end (2 cores shared with other jobs).",
        "",
    ]
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text("\n".join(lines))
    print("\n".join(lines))
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
