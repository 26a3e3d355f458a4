"""docs/performance.md and its plots from the raw results of `benchmarks.run`."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from benchmarks import summary

LEVELS = ("1e-02", "1e-03", "1e-04", "1e-05", "1e-06", "1e-07", "1e-08")
COLORS = {"package Moreau-Jean": "tab:blue", "package event-driven": "tab:red", "solve_ivp DOP853": "tab:green",
          "Siconos Moreau-Jean": "tab:purple", "compiled Moreau-Jean": "tab:cyan", "compiled event-driven": "tab:orange"}


# ------------------------------------------------------------------------------------------------ formatting
def ft(s) -> str:
    if s is None or not isinstance(s, (int, float)) or not math.isfinite(s):
        return "–"
    if s < 1e-3:
        return f"{s * 1e6:.0f} µs"
    if s < 1:
        return f"{s * 1e3:.3g} ms"
    return f"{s:.3g} s"


def fe(e) -> str:
    if e is None or (isinstance(e, float) and math.isnan(e)):
        return "–"
    if isinstance(e, float) and math.isinf(e):
        return "∞"
    return f"{e:.1e}"


def fr(r) -> str:
    if r is None or (isinstance(r, float) and math.isnan(r)):
        return "n/r"
    if math.isinf(r):
        return "∞"
    return f"{r:.2g}×" if r < 10 else f"{r:.0f}×"


def shown_label(label: str) -> str:
    """A contender's label as the pages show it: "package ..." (in results written before the Python engine's
    removal, the name of its runs) as "Python engine ...", next to "compiled ..."."""
    return "Python engine" + label[len("package"):] if label.startswith("package ") else label


def fsetting(s: dict) -> str:
    return ", ".join(f"{k} {v:g}" for k, v in s.items())


# ------------------------------------------------------------------------------------------------ plots
def plot_work_precision(res, path: Path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    scenes = [s for s in res["scenes"].values() if "entries" in s]
    if not scenes:
        return None
    n = len(scenes)
    cols = 2 if n > 1 else 1
    rows = int(math.ceil(n / cols))
    fig, axes = plt.subplots(rows, cols, figsize=(8.6 * cols, 4.3 * rows), squeeze=False)
    for ax, sc in zip(axes.flat, scenes):
        labels = []
        for e in sc["entries"]:
            if e["label"] not in labels:
                labels.append(e["label"])
        floor = max(sc["reference"]["floor"]["phi_max"], 1e-15)
        at_floor = 0
        for lab in labels:
            pts = [(e["time"], e["errors"]["phi_max"]) for e in sc["entries"] if e["label"] == lab]
            pts = [(t, err) for t, err in pts if math.isfinite(err)]
            if not pts:
                continue
            t, err = zip(*sorted(pts))
            err = np.array(err)
            color = next((c for k, c in COLORS.items() if lab.startswith(k)), None)
            style = "--" if "max_step" in lab else "-"
            # an error below the reference's own accuracy is not measured: drawn on the floor, hollow
            shown = np.maximum(err, floor)
            line, = ax.loglog(t, shown, style, lw=1.0, label=shown_label(lab), color=color)
            low = err <= floor
            at_floor += int(low.sum())
            ax.loglog(np.array(t)[~low], shown[~low], "o", ms=4, color=line.get_color())
            if low.any():
                ax.loglog(np.array(t)[low], shown[low], "o", ms=5, mfc="white", color=line.get_color())
        ax.axhspan(floor / 30.0, floor, color="gray", alpha=0.15, lw=0)
        ax.axhline(floor, color="gray", lw=1.0, ls=":",
                   label=f"reference floor {floor:.0e} rad (hollow: at or below it)")
        if at_floor:
            ax.text(0.98, 0.02, f"{at_floor} point(s) on the floor: error below what the\nreference resolves "
                    "(not measured, only bounded)", transform=ax.transAxes, ha="right", va="bottom", fontsize=7,
                    color="0.3", bbox=dict(facecolor="white", edgecolor="0.8", alpha=0.9))
        ax.set_ylim(bottom=floor / 30.0)
        for lvl in (1e-2, 1e-8):
            ax.axhline(lvl, color="k", lw=0.4, alpha=0.4)
        from matplotlib.ticker import NullFormatter
        ax.xaxis.set_minor_formatter(NullFormatter())
        ax.yaxis.set_minor_formatter(NullFormatter())
        ax.set_title(sc["title"], fontsize=10)
        ax.set_xlabel("wall time [s] (min of the repeats)")
        ax.set_ylabel("max |φ − φ_ref| on the 0.01 s grid [rad]")
        ax.grid(True, which="major", alpha=0.3)
        ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0)
    for ax in list(axes.flat)[n:]:
        ax.axis("off")
    fig.suptitle("Work-precision (lower left is better); errors below the reference's floor are drawn on it "
                 "(hollow markers)", fontsize=11)
    fig.tight_layout()
    fig.savefig(path, dpi=110, bbox_inches="tight")
    plt.close(fig)
    return path


def plot_orders(res, path: Path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    orders = res.get("orders", {})
    fig, axes = plt.subplots(1, 3, figsize=(16, 5.6))
    err_label = "error  max(|Δφ(T)| / α, p·|Δt_impact|)  [1]"

    def err_of(f):
        # dimensionless: the end rotation against alpha, the first three impact times against 1/p (older
        # result files without "err" fall back to the larger of the two raw errors)
        return max(f.get("err", max(f["err_end"], f["err_impacts"])), 1e-16)
    ax = axes[0]
    for name, o in orders.items():
        h = [f["dt_max"] for f in o["fixed"]]
        e = [err_of(f) for f in o["fixed"]]
        ax.loglog(h, e, "o-", label=f"{name} (slope {o['order_fixed_vs_h'][0]:.1f})")
    hh = np.array([0.03, 0.5])
    ax.loglog(hh, 1e-4 * (hh / 0.5) ** 4, "k:", lw=0.8, label="order 4")
    ax.loglog(hh, 1e-4 * (hh / 0.5) ** 8, "k--", lw=0.8, label="order 8")
    ax.set_xlabel("dt_max [s] (tolerance 1e-2: fixed step)")
    ax.set_ylabel(err_label)
    ax.set_title("event-driven, fixed step")
    ax = axes[1]
    for name, o in orders.items():
        n = [a["n_steps"] for a in o["adaptive"]]
        e = [err_of(a) for a in o["adaptive"]]
        ax.loglog(n, e, "o-", label=f"{name}: event-driven")
        n = [a["n_steps"] for a in o["baseline"]]
        e = [err_of(a) for a in o["baseline"]]
        ax.loglog(n, e, "s--", label=f"{name}: solve_ivp DOP853")
    ax.set_xlabel("steps (adaptive, tolerance 1e-3 … 1e-11)")
    ax.set_ylabel(err_label)
    ax.set_title("adaptive: error vs steps (one advance over the span)")
    ax = axes[2]
    for sc in res["scenes"].values():
        ent = [e for e in sc.get("entries", []) if e["contender"] == "moreau_jean"]
        if len(ent) < 2:
            continue
        h = [e["setting"]["dt_max"] for e in ent]
        err = [max(e["errors"]["phi_max"], 1e-16) for e in ent]
        ax.loglog(h, err, "o-", label=sc["name"])
    hh = np.array([2e-4, 1e-2])
    ax.loglog(hh, 0.5 * hh / 1e-2, "k:", lw=0.8, label="order 1")
    ax.set_xlabel("dt_max [s]")
    ax.set_ylabel("max |φ − φ_ref| on the 0.01 s grid [rad]")
    ax.set_title("package Moreau-Jean")
    from matplotlib.ticker import NullFormatter
    for ax in axes:
        ax.xaxis.set_minor_formatter(NullFormatter())
        ax.grid(True, alpha=0.3)
        # below the axes: a legend never covers a point
        ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.16), ncol=2, frameon=False)
    fig.tight_layout()
    fig.savefig(path, dpi=110, bbox_inches="tight")
    plt.close(fig)
    return path


def plot_memory(mem, path: Path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    s = mem["samples"]
    fig, ax = plt.subplots(figsize=(6.5, 3.4))
    ax.plot([x["t"] for x in s], [x["rss_mib"] for x in s], "o-")
    ax.set_xlabel("simulated time [s]")
    ax.set_ylabel("RSS [MiB]")
    ax.set_title(f"Simulator ({mem['scheme']}), {mem['simulated_s']:.0f} s record in 0.01 s steps")
    lo = min(x["rss_mib"] for x in s)
    ax.set_ylim(lo * 0.95, max(x["rss_mib"] for x in s) * 1.05)
    ax.grid(True, alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


# ------------------------------------------------------------------------------------------------ report
REPO_ROOT = Path(__file__).resolve().parents[1]


def machine_paths() -> list[tuple[str, str]]:
    """(path, placeholder) pairs of the directories of the machine that runs the suite, longest first: a
    generated page names files relative to the repository and never a directory of that machine."""
    import os
    import sys
    import tempfile
    pairs = [(str(REPO_ROOT), "<repo>"), (sys.prefix, "<python>"), (sys.base_prefix, "<python>"),
             (sys.exec_prefix, "<python>"), (tempfile.gettempdir(), "<tmp>"), (os.path.expanduser("~"), "<home>")]
    pairs = [(path, name) for path, name in pairs if len(path) > 1]   # never "/" itself
    return sorted(set(pairs), key=lambda pair: -len(pair[0]))


def scrub_paths(text: str) -> str:
    """The text with every directory of this machine (repository, Python prefix, temp dir, home) replaced by a
    placeholder (<repo>, <python>, <tmp>, <home>)."""
    for path, name in machine_paths():
        text = text.replace(path, name)
    return text


def failure_line(error: str) -> str:
    """One line for a table cell from a captured traceback: its last line (the exception and its message),
    without machine paths and without characters that break a Markdown table."""
    lines = [ln.strip() for ln in str(error).strip().splitlines() if ln.strip()]
    last = lines[-1] if lines else "unknown error"
    return scrub_paths(last).replace("|", "/")[:200]


#: everything after this line of docs/performance.md comes from other benchmark scripts and is kept
KEEP_MARKER = "<!-- sections below: written by benchmarks/cosim_interpolation.py and binary_overhead.py; kept by the report -->"


def write_report(res, docs: Path) -> Path:
    docs = Path(docs)
    docs.mkdir(parents=True, exist_ok=True)
    img_dir = docs / "performance"
    img_dir.mkdir(parents=True, exist_ok=True)
    imgs = {}
    try:
        imgs["wp"] = plot_work_precision(res, img_dir / "work_precision.png")
        imgs["orders"] = plot_orders(res, img_dir / "orders.png")
        if "memory" in res and "samples" in res["memory"]:
            imgs["memory"] = plot_memory(res["memory"], img_dir / "memory.png")
    except ImportError as exc:  # matplotlib missing
        imgs["error"] = str(exc)
    L: list[str] = []
    w = L.append
    info = res["info"]
    w("# Performance of rocking_model")
    w("")
    w(f"Generated by `python -m benchmarks{' --quick' if res['quick'] else ''}` on {info['date']} "
      f"({res['total_wall']:.0f} s wall). **Do not edit by hand**: re-run the suite; raw numbers in "
      f"`benchmarks/results/latest.json` (written by the run, git-ignored).")
    w("")
    w(f"- Machine: {info['cpu']}, {info['cores']} cores, {info['platform']}; load average at start "
      f"{', '.join(f'{x:.2f}' for x in info['loadavg'] or [])}")
    w("- Versions: " + ", ".join(f"{k} {v}" for k, v in info["versions"].items())
      + (f", Siconos {next((s.get('siconos_version') for s in res['scenes'].values() if s.get('siconos_version')), 'n/a')}"))
    w(f"- Library commit: {info['commit']}")
    w(f"- Timing: as Python's `timeit`, the same way for every contender: the garbage collector off during each "
      f"timed run (no `gc.collect()` before it), runs repeated until they took {res.get('min_total', 0.5):g} s (at least "
      f"{res['repeats']}, no more once a setting's runs took {res['budget']:g} s; the count is in the tables), and the "
      "minimum reported (the median too); single process, one contender at a time (on the rigid scenes the compiled "
      "event-driven settings and the solve_ivp baseline are timed again after all others, in "
      f"{res.get('second_pass_rounds', 1)} interleaved rounds, the minimum taken over all their runs: both sides of a "
      "ratio of the speed target are sampled at the same times, so a slow phase of the shared machine slows both), "
      "`time.perf_counter` around the "
      "whole public call (`simulate(...)` for the package, the model built inside, on the "
      "compiled engine with `engine=\"c\"`; the full restart loop for the baseline; the stepping loop incl. model set-up for Siconos; the "
      "stepping loop for the FMUs).")
    if res.get("skipped"):
        w("- Skipped: " + "; ".join(f"{k}: {v}" for k, v in res["skipped"].items()))
    w("")
    w("How to run: `python -m benchmarks` (full, regenerates this page and `docs/performance/*.png`) "
      "or `python -m benchmarks --quick` (smoke run, written to `benchmarks/results/quick/`). Options: "
      "`--skip-siconos --skip-fmu --skip-memory --skip-ensemble --skip-friction --repeats N --scenes free record ...`.")
    w("")
    verdicts = _targets(res)
    w("## Targets")
    w("")
    w("| target | measured | met |")
    w("| --- | --- | --- |")
    for t, m, ok in verdicts:
        w(f"| {t} | {m} | {ok} |")
    w("")
    _scenes_section(res, w, imgs)
    _orders_section(res, w, imgs)
    _compiled_section(res, w)
    _ensemble_section(res, w)
    _fmu_section(res, w)
    _memory_section(res, w, imgs)
    _checks_section(res, w)
    _method_section(w)
    path = docs / "performance.md"
    kept = ""
    if path.is_file():
        # the sections written by the other benchmark scripts (co-simulation accuracy, binary overhead) follow
        # this marker and are kept as they are
        _, kept = summary.split_page(path.read_text(), KEEP_MARKER)
        kept = KEEP_MARKER + "\n\n" + kept if kept else ""
    # the page: the summary (one table per question) first, this full run and the kept sections collapsed
    path.write_text(scrub_paths(summary.compose("\n".join(L) + "\n", kept, img_dir)))
    return path


def _targets(res):
    out = []
    ratios_b, ratios_s = [], []
    for sc in res["scenes"].values():
        for lvl, row in sc.get("equal_error", {}).items():
            if "ratio_baseline" in row:
                ratios_b.append((sc["name"], lvl, row["ratio_baseline"]))
            if "ratio_siconos" in row:
                ratios_s.append((sc["name"], lvl, row["ratio_siconos"]))

    def summary(ratios, need):
        if not ratios:
            return "not measured", "–"
        met = [r for r in ratios if not math.isnan(r[2]) and r[2] >= need]
        finite = [r for r in ratios if not math.isnan(r[2])]
        worst = min(finite, key=lambda r: r[2]) if finite else None
        nr = [r for r in ratios if math.isnan(r[2])]
        txt = f"met at {len(met)} of {len(ratios)} (scene, level) pairs"
        if worst:
            txt += f"; worst {fr(worst[2])} ({worst[0]}, {worst[1]} rad)"
        if nr:
            txt += f"; package does not reach {len(nr)} pair(s)"
        return txt, ("yes" if len(met) == len(ratios) else "**no**")

    ratios_cb, ratios_cmj = [], []
    for sc in res["scenes"].values():
        if sc.get("kind") != "rigid":
            continue
        for lvl, row in sc.get("equal_error", {}).items():
            if "ratio_c_baseline" in row:
                ratios_cb.append((sc["name"], lvl, row["ratio_c_baseline"]))
            # the levels Siconos reaches (elsewhere it has no time to compare); nan: the compiled MJ does not
            sic = row.get("siconos")
            if "ratio_cmj_siconos" in row and sic and not math.isnan(sic["time"]):
                ratios_cmj.append((sc["name"], lvl, row["ratio_cmj_siconos"]))
    m, ok = summary(ratios_cb, 50.0)
    out.append(("compiled engine's best scheme ≥ 50× faster than the solve_ivp baseline at equal max "
                "error, every level 1e-2 … 1e-8 rad (rigid scenes)", m, ok))
    if ratios_cmj:
        met = [r for r in ratios_cmj if r[2] > 1]
        finite = [r for r in ratios_cmj if not math.isnan(r[2])]
        worst = min(finite, key=lambda r: r[2]) if finite else None
        nr = len(ratios_cmj) - len(finite)
        out.append(("compiled Moreau-Jean faster than Siconos' Moreau-Jean at equal error (the levels "
                    "Siconos reaches, rigid scenes)", f"met at {len(met)} of {len(ratios_cmj)} (scene, level) pairs"
                    + (f"; worst {fr(worst[2])} ({worst[0]}, {worst[1]} rad)" if worst else "")
                    + (f"; the compiled Moreau-Jean does not reach {nr} of them" if nr else ""),
                    "yes" if len(met) == len(ratios_cmj) else "**no**"))
    out += _compiled_targets(res)
    if ratios_b:           # results written before the Python engine's removal
        m, ok = summary(ratios_b, 5.0)
        out.append(("Python engine's best scheme ≥ 5× faster than the solve_ivp baseline at equal max error, every "
                    "level 1e-2 … 1e-8 rad (rigid scenes)", m, ok))
    if ratios_s:
        m, ok = summary(ratios_s, 10.0)
        out.append(("Python engine ≥ 10× faster than Siconos' Moreau-Jean at equal error", m, ok))
    fmu = res.get("fmu", {})
    for key, name in (("rigid", "rigid"), ("flexible", "flexible")):
        c = fmu.get(key, {})
        if "rows" in c:
            b = c.get("best")
            if b:
                m = (f"{fr(b['ratio_null'])} the do-nothing FMU ({ft(b['time'])} vs {ft(fmu['null']['time'])} for "
                     f"{fmu['steps']} steps; cheapest setting with error ≤ 1e-4: {b['label']}, error {fe(b['phi_max_err'])})")
                ok = "yes" if b["ratio_null"] <= c["target"] else f"**no** ({b['ratio_null'] / c['target']:.1f}× over)"
            else:
                m, ok = "no setting reached max |φ| error ≤ 1e-4", "**no**"
        else:
            m, ok = c.get("skipped", fmu.get("error", "not measured")), "–"
        group = fmu.get("engines", {}).get(key)
        if group and "rows" in c:
            # the verdict from the interleaved rounds (the FMU and the do-nothing FMU measured side by side)
            good = [(lab, r) for lab, r in group.items() if isinstance(r, dict) and r["phi_err_c"] <= 1e-4]
            if good:
                lab, r = min(good, key=lambda x: x[1]["ratio_c"])
                m = (f"{fr(r['ratio_c'])} the do-nothing FMU ({r['c_us']:.2f} µs vs {group['null_us']:.2f} µs per "
                     f"step, fastest of {group['rounds']} interleaved rounds; {lab}, error {fe(r['phi_err_c'])}"
                     + (f"; the Python engine's FMU {fr(r['ratio_python'])}" if "ratio_python" in r else "") + ")")
                ok = "yes" if r["ratio_c"] <= c["target"] else f"**no** ({r['ratio_c'] / c['target']:.2f}× over)"
        pga = c.get("pga_g", 0.4)
        out.append((f"FMU ({name}) over the {fmu.get('duration', 30):g} s record"
                    + (f" (scaled to PGA {pga:.2g} g)" if abs(pga - 0.4) > 1e-9 else "")
                    + " at 0.01 s, error ≤ 1e-4 rad: "
                    f"≤ {c.get('target', 2 if key == 'rigid' else 4):g}× the do-nothing FMU", m, ok))
    cold = fmu.get("cold", {})
    for name, c in cold.items():
        if name == "NullSlave":
            continue
        if "instantiate_to_first_step" in c:
            v = c["instantiate_to_first_step"]
            out.append((f"cold start < 0.5 s ({name}: instantiate → first step, fresh interpreter)", ft(v),
                        "yes" if v < 0.5 else f"**no** ({v / 0.5:.1f}×)"))
    mem = res.get("memory", {})
    if "samples" in mem and mem != res.get("memory_c"):      # one run since the Python engine's removal
        s = mem["samples"]
        r0, r1 = s[1]["rss_mib"], s[-1]["rss_mib"]
        growth = (r1 - r0) / max(s[-1]["t"] - s[1]["t"], 1e-9) * 60 * 1024
        flat = abs(r1 - r0) / r0 < 0.05
        out.append(("memory flat over a 10-minute record", f"RSS {s[0]['rss_mib']:.1f} MiB at start, {r0:.1f} after "
                    f"30 s, {r1:.1f} at {s[-1]['t']:.0f} s ({growth:.0f} KiB per simulated minute)",
                    (f"nearly (+{(r1 - r0) / r0 * 100:.1f} %), but it grows linearly with the number of impacts"
                     if flat and r1 > r0 * 1.001 else "yes" if flat else "**no**")))
    orders = res.get("orders", {})
    mj = _mj_orders(res)
    if mj:
        out.append(("Moreau-Jean order ≈ 1", ", ".join(f"{k} {v[0]:.2f}" for k, v in mj.items()),
                    "yes" if all(0.6 <= v[0] <= 1.6 for v in mj.values() if math.isfinite(v[0])) else "**no**"))
    if orders:
        txt = ", ".join(f"{k}: {o['order_fixed_vs_h'][0]:.1f} (fixed step)" for k, o in orders.items())
        ok = all(o["order_fixed_vs_h"][0] >= 4 for o in orders.values())
        out.append(("event-driven order ≥ 4 before reaching its tolerance", txt, "yes" if ok else "**no**"))
    return out


def _compiled_targets(res):
    """The compiled engine's targets measured by benchmarks/compiled_bench.py, memory.py (engine c), ensemble_bench.py."""
    out = []
    comp = res.get("compiled", {})
    rows = {(r["kind"], r["scheme"]): r for r in comp.get("per_step", {}).get("rows", [])}
    proto = comp.get("prototype", {})
    if "sample_us" in proto and ("rigid", "event_driven") in rows:
        # the target compares with the C prototype's loop (0.33 us per sample on a 40 s record of 5 ms samples):
        # the C loop per communication step on a record of that shape, the benchmark record's alongside
        r = rows[("rigid", "event_driven")]
        v = proto["sample_us"]
        out.append(("compiled event-driven, rigid, ≤ 1 µs per communication step on a record like the prototype's "
                    "(40 s of 5 ms samples, about 400 impacts; the C loop, as the prototype's 0.33 µs)",
                    f"{v:.2f} µs through one `Engine.sample` call ({proto['sample_impacts']} impacts), "
                    f"{proto['raw_us']:.2f} µs in the raw loop from Python; on the benchmark's {r['steps'] * r['dt']:g} s "
                    f"record of {r['dt']:g} s steps: {r['sample_us']:.2f} µs (C loop), {r['raw_us']:.2f} µs raw, "
                    f"{r['api_us']:.2f} µs through `Simulator.advance`",
                    "yes" if v <= 1.0 else f"**no** ({v:.1f}×)"))
    for (kind, scheme), lim, what in ((("rigid", "event_driven"), 1.0, "per communication step"),
                                      (("flexible", "event_driven"), 5.0, "per communication step"),
                                      (("rigid", "moreau_jean"), 1.0, "per Moreau-Jean time step")):
        r = rows.get((kind, scheme))
        if not r or (kind, scheme) == ("rigid", "event_driven") and "sample_us" in proto:
            continue
        v = r["raw_us_per_internal_step"] if scheme == "moreau_jean" else r["raw_us"]
        api = r["api_us"] / (r["internal_steps"] / r["steps"]) if scheme == "moreau_jean" else r["api_us"]
        smp = ""
        if "sample_us" in r:
            sv = r["sample_us"] / (r["internal_steps"] / r["steps"]) if scheme == "moreau_jean" else r["sample_us"]
            smp = f"; {sv:.2f} µs through one `Engine.sample` call (the C loop; {r['sample_impacts']} impacts)"
        out.append((f"compiled {scheme.replace('_', '-')}, {kind}, ≤ {lim:g} µs {what} on the "
                    f"{r['steps'] * r['dt']:g} s record (impacts included)",
                    f"{v:.2f} µs raw engine loop, {api:.2f} µs through `Simulator.advance` ({r['impacts']} impacts)"
                    f"{smp}",
                    "yes" if v <= lim else f"**no** ({v / lim:.1f}×)"))
    cold = comp.get("cold", {})
    low = cold.get("low_level", {})
    if "import_to_first_step" in low:
        # the compiled engine reached from Python: its low-level API (the extension module, no numpy)
        v = low["import_to_first_step"]
        sim = (f"; through `Simulator`: {ft(cold['import_to_first_step'])}, numpy's import "
               f"{ft(cold['numpy_import'])} of it, the package's import {ft(cold['package_import'])}, Simulator + "
               f"first step {ft(cold['first_step'])}" if "import_to_first_step" in cold else "")
        out.append(("cold start of the compiled engine from Python (import → first step) < 50 ms",
                    f"{ft(v)} through the low-level API `rocking_model._engine.Engine` (import "
                    f"{ft(low['import'])}, numpy not imported: {not low['numpy_imported']}){sim}",
                    "yes" if v < 0.05 else f"**no** ({v / 0.05:.1f}×)"))
    elif "import_to_first_step" in cold:
        v = cold["import_to_first_step"]
        out.append(("cold start of the compiled engine from Python (import → first step) < 50 ms",
                    f"{ft(v)} (numpy's import {ft(cold['numpy_import'])} of it; the package's import "
                    f"{ft(cold['package_import'])}; Simulator + first step {ft(cold['first_step'])})",
                    "yes" if v < 0.05 else f"**no** ({v / 0.05:.1f}×)"))
    mem = res.get("memory_c", {})
    if "samples" in mem:
        s = mem["samples"]
        r0, r1 = s[1]["rss_mib"], s[-1]["rss_mib"]
        out.append(("memory flat over a 10-minute record (compiled engine)",
                    f"RSS {r0:.2f} MiB after 30 s, {r1:.2f} at {s[-1]['t']:.0f} s ({s[-1]['impacts']} impacts; "
                    f"impact log bounded at {mem['impact_log_len']} rows)",
                    "yes" if r1 <= r0 * 1.005 else "**no**"))
    ens = res.get("ensemble", {})
    if "best_over_python" in ens:          # results written before the Python engine's removal
        v = ens["best_over_python"]
        out.append(("ensembles ≥ 50× the cases per second of the Python engine's serial run "
                    "(docs/performance/ensemble.md)",
                    f"{ens['best']:.0f} cases/s against {ens['python_serial']:.0f} ({v:.0f}×; compiled serial "
                    f"{ens['compiled_serial']:.0f} cases/s)", "yes" if v >= 50 else f"**no** ({v:.0f}×)"))
    return out


def _compiled_section(res, w):
    comp = res.get("compiled")
    if not comp:
        return
    w("## Compiled engine: per communication step and cold start")
    w("")
    if "error" in comp:
        w("Compiled-engine benchmark failed:\n\n```\n" + comp["error"][-2000:] + "\n```\n")
        return
    ps = comp.get("per_step", {})
    if ps.get("rows"):
        r0 = ps["rows"][0]
        old = any("python_us" in r for r in ps["rows"])     # results written before the Python engine's removal
        w(f"The first {r0['steps'] * r0['dt']:g} s of the synthetic record (`benchmarks.scenes.synthetic_record`) in "
          f"{r0['dt']:g} s communication steps ({r0['steps']} steps), `ag` held over each step, the outputs read after "
          "each (`benchmarks/compiled_bench.py`; the fastest of 15 interleaved rounds, each round one run of every variant "
          "below, 3 rounds in a quick run). *Raw*: the loop `Engine.advance(t, ag, 0, max_steps)` + "
          "`Engine.output_row()` on `rocking_model._engine.Engine`; *Engine.sample*: one call over the record, the C loop "
          "over the communication steps (the record integrated as given, linear between samples, not held); *API*: `Simulator(engine=\"c\").advance(t, ag)` + "
          "`outputs()`; *simulate*: `simulate(..., hold=\"zoh\", engine=\"c\")` over the whole record"
          + ("; *Python*: the `Simulator.advance` loop on the Python engine (removed since), |Δφ| its max difference "
             "of φ after each step from the compiled engine (same algorithm, same steps)" if old else "") + ".")
        w("")
        w("| model | scheme, settings | record PGA | impacts | raw [µs/step] | Engine.sample [µs/step] | API [µs/step] | "
          "simulate [µs/step] | " + ("Python [µs/step] | Python / raw | " if old else "")
          + "internal steps | raw per internal step [µs] |" + (" max |Δφ| C vs Python [rad] |" if old else ""))
        w("|" + " --- |" * (13 if old else 10))
        for r in ps["rows"]:
            smp = f"{r['sample_us']:.2f}" if "sample_us" in r else "–"
            py = (f"{r['python_us']:.1f} | {fr(r['python_over_raw'])} | " if "python_us" in r else "– | – | ") if old else ""
            dphi = (f" {fe(r['max_dphi_c_python'])} |" if "max_dphi_c_python" in r else " – |") if old else ""
            w(f"| {r['kind']} | {r['scheme']}, {fsetting(r['settings'])} | {r['pga_g']:.2g} g | {r['impacts']} | "
              f"{r['raw_us']:.2f} | {smp} | {r['api_us']:.2f} | {r['simulate_us']:.2f} | {py}"
              f"{r['internal_steps']} | {r['raw_us_per_internal_step']:.2f} |{dphi}")
        w("")
    proto = comp.get("prototype", {})
    if "sample_us" in proto:
        rec = proto["record"]
        w(f"A record shaped like the C prototype's record (a 40 s far-field record of 5 ms samples with about 400 "
          f"impacts; here `synthetic_record` over {rec['duration']:g} s at {rec['dt']:g} s, PGA {rec['pga_g']:g} g, "
          f"strong phase to {rec['t_strong']:g} s, decay {rec['decay']:g}, seed {rec['seed']}: {proto['steps']} "
          f"communication steps), the rigid block event-driven at tolerance 1e-8: **{proto['sample_us']:.2f} µs** per "
          f"step through one `Engine.sample` call (the C loop, {proto['sample_impacts']} impacts), "
          f"{proto['raw_us']:.2f} µs in the raw loop (`ag` held, {proto['raw_impacts']} impacts).")
        w("")
    cold = comp.get("cold", {})
    if "import_to_first_step" in cold:
        w(f"Cold start (fresh interpreter, median of {len(cold['samples'])}): from `import numpy` / `import "
          f"rocking_model` to the end of the first 0.01 s step of `Simulator(RigidBlock(b=0.4, h=2.0), engine=\"c\")`: "
          f"**{ft(cold['import_to_first_step'])}** = numpy's import {ft(cold['numpy_import'])} + the package's "
          f"import {ft(cold['package_import'])} + Simulator and first step {ft(cold['first_step'])}.")
        low = cold.get("low_level", {})
        if "import_to_first_step" in low:
            w(f"Through the low-level API (`from rocking_model._engine import Engine`; `Engine(\"rigid\", params)`, "
              f"`advance`, `outputs`; imports {', '.join(low['package_modules'])} and not numpy: "
              f"{not low['numpy_imported']}): **{ft(low['import_to_first_step'])}** = the import {ft(low['import'])} "
              f"+ engine and first step {ft(low['first_step'])} (the same φ as the Simulator's: "
              f"{low.get('same_phi_as_simulator')}). Both with the package's bytecode cached, as after `pip install`.")
        w("")
    elif "error" in cold:
        w(f"Cold start failed: {failure_line(cold['error'])}")
        w("")
    w("MuJoCo's rollout is not measured: the `mujoco` distribution that the package registry here serves is a "
      "pure-Python wheel without the simulator's binary, so MuJoCo cannot be installed on this machine.")
    w("")


def _ensemble_section(res, w):
    ens = res.get("ensemble")
    if not ens:
        return
    w("## Ensembles")
    w("")
    if "error" in ens:
        w(f"Ensemble benchmark failed: {failure_line(ens['error'])}")
        w("")
        return
    w(f"`benchmarks/ensemble_bench.py` (its page: [ensemble.md](performance/ensemble.md)): {ens['cases']} one-sine "
      f"pulse cases on the compiled engine, best {ens['best']:.0f} cases/s"
      + (f", {ens['best_over_python']:.0f}× the Python engine's serial run ({ens['python_serial']:.0f} cases/s on "
         f"its first {ens['python_cases']} cases)" if "best_over_python" in ens else "")
      + f"; serially {ens['compiled_serial']:.0f} cases/s.")
    w("")


def _mj_orders(res):
    """Slope of max |phi err| against dt_max over the Moreau-Jean runs with error < 0.05 rad (the asymptotic
    range; larger errors mean a different impact sequence or overturning), at least 3 points."""
    from benchmarks.analysis import fit_order

    out = {}
    for sc in res["scenes"].values():
        ent = [e for e in sc.get("entries", []) if e["contender"] == "moreau_jean" and e["errors"]["phi_max"] < 0.05]
        if len(ent) >= 3 and sc["name"] != "record":
            out[sc["name"]] = fit_order([e["setting"]["dt_max"] for e in ent], [e["errors"]["phi_max"] for e in ent])
    return out


def _scenes_section(res, w, imgs):
    w("## Scenes and references")
    w("")
    w("Reference per scene: the event-driven scheme at tolerance 1e-12 with its steps capped at grid/8 (rigid) or "
      "grid/32 (flexible; see the lift-off check below) — a step sequence unlike any contender's. *Floor* = max "
      "|φ| difference between that reference and the same tolerance without the cap: errors below it are not "
      "resolved. Errors are measured on the common 0.01 s output grid.")
    w("")
    w("| scene | set-up | reference | floor | cross-checks |")
    w("| --- | --- | --- | --- | --- |")
    for sc in res["scenes"].values():
        if "entries" not in sc:
            w(f"| {sc['name']} | FAILED | | | see results json |")
            continue
        r = sc["reference"]
        ref = (f"{ft(r['time'])}, {r['n_steps']} steps, {r['impacts']} impacts, max |φ| {r['phi_absmax']:.3g} rad"
               + (", **overturns**" if r["overturned"] else ""))
        if "top_absmax" in r:
            ref += f", max |top| {r['top_absmax']:.3g} m"
        checks = []
        cf = r.get("closed_form")
        if cf:
            checks.append(f"closed form (quadrature) over the first {cf['n']} impacts: impact times within "
                          f"{fe(cf['impact_time_err'])} s, pre-impact speeds p·sqrt(2[cos(α−φ0)−cos α])·rⁿ within "
                          f"{fe(cf['speed_rel_err'])} (relative); t₁ = {cf['first_impact_closed_form']:.12f} s")
        base = [e for e in sc["entries"] if e["label"] == "solve_ivp DOP853"]
        if base:
            b = min(base, key=lambda e: e["setting"]["rtol"])
            checks.append(f"solve_ivp at rtol {b['setting']['rtol']:g}: max |Δφ| {fe(b['errors']['phi_max'])}, "
                          f"first impacts {fe(b['errors'].get('impact3'))} s")
        if sc.get("window_end") is not None:
            checks.append(f"errors compared up to t = {sc['window_end']:.2f} s, where the reference block leaves the "
                          "ground (flight; Housner's single-DOF baseline cannot)")
        w(f"| {sc['name']} | {sc['describe']} | {ref} | {fe(r['floor']['phi_max'])} | {'; '.join(checks) or '–'} |")
    w("")
    if imgs.get("wp"):
        w("![work-precision](performance/work_precision.png)")
        w("")
    w("### Equal-error comparison")
    w("")
    w("Time each contender needs for a given max |φ − φ_ref| (linear interpolation in log-log on its "
      "work-precision front; *≤* = its cheapest run is already below the level, so the time is an upper bound; "
      "n/r = not reached by any setting). *C* = the compiled engine (`simulate(..., engine=\"c\")`) at its best scheme at "
      "that level (*Python*, in results written before its removal: the former Python engine); "
      "ratio = the other's time / that engine's time (> 1: the engine is faster); *Siconos / C MJ* compares the two "
      "Moreau-Jean implementations.")
    w("")
    for sc in res["scenes"].values():
        ee = sc.get("equal_error")
        if not ee:
            continue
        names = {"compiled": "compiled best", "compiled Moreau-Jean": "C MJ", "compiled event-driven": "C ED",
                 "package": "Python best", "package Moreau-Jean": "Py MJ", "package event-driven": "Py ED",
                 "baseline": "solve_ivp (best variant)", "siconos": "Siconos"}
        fams = [f for f in names if f in ee[LEVELS[0]]]
        w(f"**{sc['title']}**")
        w("")
        head = ["error [rad]"] + [names[f] for f in fams]
        ratio_cols = [(k, t) for k, t in (("ratio_c_baseline", "solve_ivp / C"), ("ratio_c_siconos", "Siconos / C"),
                                          ("ratio_cmj_siconos", "Siconos / C MJ"), ("ratio_c_package", "Python / C"),
                                          ("ratio_baseline", "solve_ivp / Python"), ("ratio_siconos", "Siconos / Python"))
                      if k in ee[LEVELS[0]]]
        head += [t for _, t in ratio_cols]
        w("| " + " | ".join(head) + " |")
        w("|" + " --- |" * len(head))
        for lvl in LEVELS:
            row = ee[lvl]
            cells = [lvl]
            for f in fams:
                t, how = row[f]["time"], row[f]["how"]
                cells.append(("≤ " if how == "cheapest" else "") + ft(t) if how != "not reached" else "n/r")
            cells += [fr(row[k]) for k, _ in ratio_cols]
            w("| " + " | ".join(cells) + " |")
        w("")
    w("### All runs")
    w("")
    for sc in res["scenes"].values():
        if "entries" not in sc:
            continue
        flex = sc["kind"] == "flexible"
        w(f"<details><summary>{sc['title']} ({len(sc['entries'])} runs)</summary>")
        w("")
        head = ["contender", "setting", "time (min)", "median time", "repeats", "steps", "|φ(T) err|", "max |φ err|",
                "first-3 impact times err [s]"] + (["|top(T) err| [m]", "max |top err| [m]"] if flex else [])
        w("| " + " | ".join(head) + " |")
        w("|" + " --- |" * len(head))
        for e in sc["entries"]:
            er = e["errors"]
            cells = [shown_label(e["label"]), fsetting(e["setting"]), ft(e["time"]), ft(e.get("median", math.nan)),
                     str(len(e["times"])), str(e["n_steps"]),
                     fe(er.get("phi_end")), fe(er.get("phi_max")), fe(er.get("impact3"))]
            if flex:
                cells += [fe(er.get("top_displacement_end")), fe(er.get("top_displacement_max"))]
            w("| " + " | ".join(cells) + " |")
        w("")
        w("</details>")
        w("")


def _orders_section(res, w, imgs):
    orders = res.get("orders")
    if not orders:
        return
    w("## Convergence orders")
    w("")
    mj = _mj_orders(res)
    if mj:
        w("- **Moreau-Jean** (package), slope of max |φ err| against dt_max over the scene sweeps (runs with error "
          "< 0.05 rad; the record is left out, no run gets there): "
          + ", ".join(f"{k} {v[0]:.2f} ({v[1]} points)" for k, v in mj.items()) + ".")
    for name, o in orders.items():
        fh, fx, an, at, bn = (o["order_fixed_vs_h"], o["order_fixed_vs_steps"], o["order_adaptive_vs_steps"],
                              o["slope_vs_tolerance"], o["baseline_order_vs_steps"])
        w(f"- **Event-driven, {name}** (span {o['T']:g} s in one `advance`, error = max of |φ(T) err| and the "
          f"first-3 impact-time error, points between 1e-12 and 1e-2): fixed step (tolerance 1e-2, dt_max = h) "
          f"order **{fh[0]:.1f}** in h ({fh[1]} points; {-fx[0]:.1f} against the step count). Adaptive: error ∝ "
          f"tolerance^{at[0]:.2f} (the tolerance is honoured proportionally).")
    w("")
    if imgs.get("orders"):
        w("![orders](performance/orders.png)")
        w("")
    for name, o in orders.items():
        w(f"<details><summary>order data: {name}</summary>")
        w("")
        w("| event-driven fixed step h | steps | |φ(T) err| | impact-time err |")
        w("| --- | --- | --- | --- |")
        for f in o["fixed"]:
            w(f"| {f['dt_max']:g} | {f['n_steps']} | {fe(f['err_end'])} | {fe(f['err_impacts'])} |")
        w("")
        w("| tolerance | ED steps | ED |φ(T) err| | ED impact err | solve_ivp steps | solve_ivp |φ(T) err| | solve_ivp impact err |")
        w("| --- | --- | --- | --- | --- | --- | --- |")
        for a, b in zip(o["adaptive"], o["baseline"]):
            w(f"| {a['tolerance']:g} | {a['n_steps']} | {fe(a['err_end'])} | {fe(a['err_impacts'])} | {b['n_steps']} | "
              f"{fe(b['err_end'])} | {fe(b['err_impacts'])} |")
        w("")
        w("</details>")
        w("")


def _fmu_section(res, w):
    fmu = res.get("fmu")
    if not fmu:
        return
    w("## FMU overhead and cold start")
    w("")
    if "error" in fmu:
        w("FMU benchmark failed:\n\n```\n" + fmu["error"][-2000:] + "\n```\n")
        return
    w(f"The first {fmu['duration']:g} s of the record scene's accelerogram, driven through fmpy's `FMU2Slave` with "
      f"one `doStep` per 0.01 s ({fmu['steps']} steps), `ag` set at the start of each step (zero-order hold, as "
      "`fmpy.simulate_fmu` does), `phi` read after each step. The same loop drives a do-nothing pythonfmu FMU "
      f"(`benchmarks/fmu_null/NullSlave.py`): {ft(fmu['null']['time'])} "
      f"({fmu['null']['per_step_us']:.1f} µs per step) — the floor. Error: max |φ − φ_ref| against the event-driven "
      f"reference (tolerance 1e-12, zero-order hold). FMUs: {fmu.get('fmu_source')}.")
    w("")
    for key in ("rigid", "flexible"):
        c = fmu.get(key, {})
        if "rows" not in c:
            if c:
                w(f"- {key}: skipped ({c.get('skipped')})")
            continue
        w(f"**{key}** (target ≤ {c['target']:g}× the floor; record PGA {c.get('pga_g', 0.4):.2g} g; reference max |φ| "
          f"{c['ref_phi_absmax']:.3g} rad)")
        w("")
        w("| FMU setting | time (min) | median time | repeats | × do-nothing FMU | max |φ err| |")
        w("| --- | --- | --- | --- | --- | --- |")
        for r in c["rows"]:
            w(f"| {r['label']} | {ft(r['time'])} | {ft(r.get('median', math.nan))} | {len(r['times'])} | {fr(r['ratio_null'])} | {fe(r['phi_max_err'])} |")
        w("")
        b = c.get("best")
        if b:
            py = (f"{ft(c['python_same_settings'])} on the Python engine (removed since), "
                  if "python_same_settings" in c else "")
            w(f"Cheapest setting at error ≤ 1e-4: {b['label']}. The same run through the Python API "
              f"(`simulate(..., hold='zoh', engine='c')`): {py}{ft(c.get('c_same_settings'))} on the compiled "
              "engine; end-to-end `fmpy.simulate_fmu` "
              f"(FMU already extracted): {ft(c['simulate_fmu'])} vs {ft(c['simulate_fmu_null'])} for the do-nothing "
              "FMU.")
            w("")
    eng = fmu.get("engines")
    if eng and "error" in eng:
        w(f"FMUs on each engine failed: {failure_line(eng['error'])}")
        w("")
    elif eng:
        # results written before the Python engine's removal also hold its FMU rows (python_us, ratio_python)
        old = any("python_us" in r for group in eng.values() for r in group.values() if isinstance(r, dict))
        w("**The FMUs against the do-nothing FMU** (`benchmarks/fmu_bench.py` `engine_rows`: the same fmpy loop, "
          "each FMU and the do-nothing FMU in interleaved rounds, the fastest round of each; error: max |φ| "
          "difference from `simulate(..., hold='zoh', tolerance=1e-12)`)")
        w("")
        w("| FMU setting | steps | do-nothing FMU [µs/step] | compiled engine [µs/step] | × do-nothing | "
          + ("Python engine [µs/step] | × do-nothing | " if old else "") + "max |φ err| compiled [rad] |")
        w("| --- | --- | --- | --- | --- | " + ("--- | --- | " if old else "") + "--- |")
        for group in eng.values():
            for label, r in group.items():
                if not isinstance(r, dict):
                    continue
                py = (f"{r['python_us']:.2f} | {fr(r['ratio_python'])} | " if old and "python_us" in r
                      else "– | – | " if old else "")
                w(f"| {label} | {group['steps']} | {group['null_us']:.2f} | {r['c_us']:.2f} | {fr(r['ratio_c'])} | "
                  f"{py}{fe(r['phi_err_c'])} |")
        w("")
    cold = fmu.get("cold", {})
    if cold:
        w("Cold start, fresh interpreter per sample (median of 3): `FMU2Slave()` + instantiate + setup + "
          "initialization + the first `doStep` (the pythonfmu binary starts the slave module, which imports "
          "the package, numpy and scipy); importing fmpy and unzipping the FMU are listed apart.")
        w("")
        w("| FMU | instantiate → first step | import fmpy | read + extract |")
        w("| --- | --- | --- | --- |")
        for name, c in cold.items():
            if "error" in c:
                w(f"| {name} | failed: {failure_line(c['error'])} | | |")
            else:
                w(f"| {name} | {ft(c['instantiate_to_first_step'])} | {ft(c['import_fmpy'])} | "
                  f"{ft(c['read_and_extract'])} |")
        w("")


def _memory_section(res, w, imgs):
    mem = res.get("memory")
    if not mem:
        return
    w("## Memory")
    w("")
    if "error" in mem:
        w("Memory benchmark failed:\n\n```\n" + mem["error"] + "\n```\n")
        return
    s = mem["samples"]
    w(f"A {mem['simulated_s']:.0f} s record (the 30 s record repeated; the block is at rest at the end of each "
      f"repetition) through `Simulator` ({mem['scheme']}, {fsetting(mem['settings'])}) in 0.01 s steps with the "
      f"input held per step, as the FMU runs it; fresh interpreter, RSS from /proc/self/statm every 30 s. Wall "
      f"{ft(mem['wall_s'])}.")
    w("")
    w("| simulated time [s] | RSS [MiB] | impacts so far |")
    w("| --- | --- | --- |")
    for x in s[:: max(1, len(s) // 10)] + ([s[-1]] if (len(s) - 1) % max(1, len(s) // 10) else []):
        w(f"| {x['t']:.0f} | {x['rss_mib']:.2f} | {x['impacts']} |")
    w("")
    r0, r1 = s[1]["rss_mib"], s[-1]["rss_mib"]
    per_impact = (r1 - r0) * 2 ** 20 / max(s[-1]["impacts"] - s[1]["impacts"], 1)
    w(f"Growth after the first 30 s: {r1 - r0:+.2f} MiB over {s[-1]['impacts'] - s[1]['impacts']} impacts "
      f"(≈ {per_impact:.0f} B per impact). The integrator keeps every impact in `impact_times` "
      f"({mem['impact_times_len']} entries) and `impact_log` ({mem['impact_log_len']} tuples of two velocity "
      "arrays): memory grows linearly with the number of impacts, not with time.")
    w("")
    if imgs.get("memory"):
        w("![memory](performance/memory.png)")
        w("")
    mc = res.get("memory_c")
    if mc and "samples" in mc:
        s = mc["samples"]
        w(f"The same record through `Simulator(engine=\"c\")` (fresh interpreter, wall {ft(mc['wall_s'])}): RSS "
          f"{s[0]['rss_mib']:.2f} MiB at start, {s[1]['rss_mib']:.2f} after 30 s, {s[-1]['rss_mib']:.2f} at "
          f"{s[-1]['t']:.0f} s after {s[-1]['impacts']} impacts: the engine's impact log is a bounded ring "
          f"({mc['impact_log_len']} rows held; `impact_times` {mc['impact_times_len']} entries, bounded by "
          "`impact_log_size`).")
        w("")
    elif mc and "error" in mc:
        w(f"Memory (compiled engine) failed: {failure_line(mc['error'])}")
        w("")


def _checks_section(res, w):
    notes = _observations(res)
    if not notes:
        return
    w("## Observations from this run")
    w("")
    for n in notes:
        w(f"- {n}")
    w("")


def _observations(res):
    notes = []
    for sc in res["scenes"].values():
        ed = [e for e in sc.get("entries", []) if e["contender"] == "event_driven"]
        if len(ed) >= 2:
            steps = sorted({e["n_steps"] for e in ed})
            tmin, tmax = min(e["time"] for e in ed), max(e["time"] for e in ed)
            if len(steps) <= 2 and steps[-1] <= 1.05 * steps[0]:
                notes.append(f"{sc['name']}: the event-driven step count is {steps[0]}–{steps[-1]} at every tolerance "
                             f"({ed[0]['setting']['tolerance']:g} … {ed[-1]['setting']['tolerance']:g}; "
                             f"{ft(tmin)}–{ft(tmax)}): each `advance` to the next 0.01 s output point ends the DOP853 "
                             "step there (ground-motion breakpoints too), so the tolerance hardly limits the step "
                             "and cannot trade accuracy for speed on this grid.")
    for sc in res["scenes"].values():
        bad = [e for e in sc.get("entries", []) if e.get("wrong_side")]
        if bad:
            notes.append(f"{sc['name']}: {len(bad)} event-driven run(s) rotate on the wrong side of their pivot "
                         "(rocking through the ground): " + ", ".join(fsetting(e["setting"]) for e in bad) + ".")
        if sc.get("reference", {}).get("wrong_side"):
            notes.append(f"{sc['name']}: the reference itself rotates on the wrong side of its pivot.")
    fmu = res.get("fmu", {})
    rig = fmu.get("rigid", {})
    rows = {r["label"]: r for r in rig.get("rows", [])}
    for key in ("rigid", "flexible"):
        rows = fmu.get(key, {}).get("rows", [])
        good = [r for r in rows if r["phi_max_err"] <= 1e-4]
        bad = [r for r in rows if r["phi_max_err"] >= 0.5]
        if good and bad:
            notes.append(f"FMU ({key}): " + ", ".join(f"{r['label']} ends {fe(r['phi_max_err'])} rad away from the "
                                                      "reference" for r in bad)
                         + " (it overturns, or not, unlike the reference) while "
                         + ", ".join(r["label"] for r in good) + f" agree(s) within 1e-4: the outcome is not "
                         "monotone in the tolerance (see the event-driven bugs below).")
    for c in res.get("checks", []):
        notes.append(c)
    return notes


def _method_section(w):
    w("## Method")
    w("")
    w("- Scenes (`benchmarks/scenes.py`): rigid block free rocking to rest through the impact accumulation; "
      "one-sine pulses below and above the overturning boundary; a 30 s synthetic record (white noise, fixed "
      "seed, through a Clough-Penzien filter — Kanai-Tajimi f_g = 2.5 Hz, ζ_g = 0.6, high-pass 0.25 Hz — "
      "times a Saragoni-Hart-like envelope, PGA 0.4 g, dt = 0.01 s); flexible oscillator under a pulse with "
      "a soft and a stiff column.")
    w("- Errors: |φ(T) − φ_ref(T)|; max over the 0.01 s grid of |φ − φ_ref| (the headline measure); max error of "
      "the first three impact times; for the flexible oscillator also the top displacement.")
    w("- Contenders: `simulate(..., engine=\"c\")` with each scheme over a sweep (dt_max for Moreau-Jean, tolerance for the "
      "event-driven scheme); a solve_ivp baseline (`benchmarks/baseline.py`: Housner's single-DOF equation, DOP853, "
      "terminal events for impact and overturning, Housner's r at each impact, restart loop, the same Zeno "
      "threshold; for the record also with max_step = the sampling step); Siconos' MoreauJeanOSI + "
      "FrictionContact(2) (Lemke, large μ: sticking) with C plugins for the corner relations "
      "(`benchmarks/siconos_runner.py`, run under /usr/bin/python3). The flexible oscillator has no baseline: "
      "its impact outcome needs the impact LCP with the u-dependent coupling (the paper's appendix, Eqs. 48–55), i.e. the "
      "package's own machinery.")
    w("- Equal-error comparison: each contender's (time, error) points (the minimum of the repeats) are reduced to their Pareto "
      "front and interpolated linearly in log-log; an engine's best time at a level is the faster of its two "
      "schemes.")
    w("")
