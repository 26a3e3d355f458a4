"""Memory over a long run: a 10-minute record (the 30 s synthetic record repeated; the block is at rest at
the end of each repetition) advanced through `Simulator` in 0.01 s communication steps, as the FMU does.
The resident set size is sampled after every 30 s of simulated time.

Run in a fresh interpreter (`python -m benchmarks.memory [minutes] [scheme]`, the compiled engine) so that the RSS is not inflated by the rest of the benchmark; prints one JSON line.
"""
from __future__ import annotations

import gc
import json
import os
import resource
import sys
import time


def rss_mib() -> float:
    """Current resident set size [MiB] (/proc/self/statm; falls back to the peak from getrusage)."""
    try:
        with open("/proc/self/statm") as f:
            pages = int(f.read().split()[1])
        return pages * os.sysconf("SC_PAGE_SIZE") / 2 ** 20
    except OSError:  # pragma: no cover - non-Linux
        return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def main(minutes: float = 10.0, scheme: str = "event_driven") -> dict:
    from rocking_model import RigidBlock, Simulator
    from rocking_model.ground_motion import ConstantMotion

    from benchmarks.scenes import RECORD_BLOCK, synthetic_record

    t_rec, a_rec = synthetic_record()
    period = float(t_rec[-1])
    dt = 0.01
    n_rep = max(1, int(round(minutes * 60 / period)))
    settings = {"tolerance": 1e-6} if scheme == "event_driven" else {"dt_max": 2e-3}
    sim = Simulator(RigidBlock(**RECORD_BLOCK), scheme, engine="c", **settings)
    gc.collect()
    samples = [{"t": 0.0, "rss_mib": rss_mib(), "impacts": 0, "wall": 0.0}]
    t0 = time.perf_counter()
    n_per = int(round(period / dt))
    k = 0
    for rep in range(n_rep):
        for i in range(n_per):
            sim.advance((k + 1) * dt, ConstantMotion(float(a_rec[i])))
            k += 1
        out = sim.outputs()
        samples.append({"t": k * dt, "rss_mib": rss_mib(), "impacts": int(out["impacts"]),
                        "wall": time.perf_counter() - t0, "phi": out["phi"], "contact": out["contact"]})
    ed = sim.integrator
    return {"scheme": scheme, "engine": "c", "settings": settings, "simulated_s": k * dt, "wall_s": time.perf_counter() - t0,
            "samples": samples, "impact_times_len": len(sim.impact_times),
            "impact_log_len": len(getattr(ed, "impact_log", [])), "overturned": bool(sim.outputs()["overturned"])}


if __name__ == "__main__":
    sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    minutes = float(sys.argv[1]) if len(sys.argv) > 1 else 10.0
    scheme = sys.argv[2] if len(sys.argv) > 2 else "event_driven"
    print(json.dumps(main(minutes, scheme)))
