"""The summary of docs/performance.md: one short table per question a user asks, from the full run's tables.

`benchmarks.report.write_report` writes the full run (targets, scenes, equal-error tables, every run, orders,
compiled engine, FMUs, memory, method) and hands it to `compose`, which puts the summary first and the full
run in a collapsed section (`<details markdown="1">`, rendered by GitHub and by MkDocs' md_in_html). The
summary is read from the full run's Markdown tables, so that it can be rebuilt from the committed page
without re-running the benchmarks:

    python -m benchmarks.summary            # rewrite docs/performance.md from its own recorded tables

The sections that other benchmark scripts wrote (after `report.KEEP_MARKER`; another machine's runs) go to a
collapsed section of their own, with their machine named.
"""
from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

#: the line that opens the collapsed full run and the one that closes the kept sections
RAW_OPEN = '<details markdown="1"><summary><b>The full run</b>'
KEPT_OPEN = '<details markdown="1"><summary><b>Other runs</b>'
KEPT_END = "<!-- end of the kept sections -->"

#: what a user gets by default (simulate, Simulator and the FMUs)
DEFAULT_ED = "tolerance 1e-08"
DEFAULT_MJ = "dt_max 0.001"


# ------------------------------------------------------------------------------------------------ Markdown tables
def _cells(line: str) -> list[str]:
    # cells are separated by " | ": a header such as "|φ(T) err|" keeps its own bars
    return [c.strip() for c in re.split(r" \| ", line.strip()[1:-1].strip())]


def table_after(md: str, marker: str) -> tuple[list[str], list[dict]]:
    """(header, rows as {column: cell}) of the first Markdown table after the line containing ``marker``;
    ([], []) when there is none."""
    i = md.find(marker)
    if i < 0:
        return [], []
    lines = md[i:].splitlines()[1:]
    k = next((n for n, ln in enumerate(lines) if ln.startswith("| ")), None)
    if k is None or k + 1 >= len(lines) or not lines[k + 1].startswith("| ---"):
        return [], []
    header = _cells(lines[k])
    seen: dict = {}
    for n, name in enumerate(header):        # a repeated column name ("× do-nothing") gets "#2", "#3", ...
        seen[name] = seen.get(name, 0) + 1
        if seen[name] > 1:
            header[n] = f"{name}#{seen[name]}"
    rows = []
    for ln in lines[k + 2:]:
        if not ln.startswith("|"):
            break
        cells = _cells(ln)
        rows.append(dict(zip(header, cells)))
    return header, rows


def _row(rows, **match):
    return next((r for r in rows if all(r.get(k) == v for k, v in match.items())), None)


def _first(pattern: str, text: str, default: str = "n/a") -> str:
    m = re.search(pattern, text, re.S)
    return m.group(1).strip() if m else default


# ------------------------------------------------------------------------------------------------ the questions
#: the scenes of the full run: (title on the page, what a user calls it, model)
SCENES = [("Rigid block, one-sine pulse below overturning", "one-sine pulse, 4 s (rocks)", "rigid block"),
          ("Rigid block, one-sine pulse above overturning", "one-sine pulse, 4 s (overturns)", "rigid block"),
          ("Rigid block, free rocking to rest", "free rocking to rest, 7 s", "rigid block"),
          ("Rigid block, 30 s synthetic record", "30 s record", "rigid block"),
          ("Flexible oscillator, soft column, pulse", "one-sine pulse, 5 s, soft column", "flexible oscillator"),
          ("Flexible oscillator, stiff column, pulse", "one-sine pulse, 5 s, stiff column", "flexible oscillator")]


def _simulate_table(raw: str, w) -> None:
    w("## How long does a `simulate` take?")
    w("")
    w("The compiled engine at the defaults a user gets (event-driven tolerance 1e-8; Moreau-Jean dt_max 1e-3 s; "
      "a record linear between its samples, `hold=\"exact\"`), outputs every 0.01 s; the whole `simulate(...)` "
      "call, the fastest of its repeats; error: max |φ − φ_ref| over the output grid against a tolerance-1e-12 "
      "reference.")
    w("")
    w("| scene | model | event-driven | its error [rad] | Moreau-Jean | its error [rad] |")
    w("| --- | --- | --- | --- | --- | --- |")
    n = 0
    for title, name, model in SCENES:
        _, rows = table_after(raw, f"<summary>{title} (")
        ed = _row(rows, contender="compiled event-driven", setting=DEFAULT_ED)
        mj = _row(rows, contender="compiled Moreau-Jean", setting=DEFAULT_MJ)
        if not (ed or mj):
            continue
        n += 1
        cell = lambda r, k: r.get(k, "–") if r else "–"  # noqa: E731
        w(f"| {name} | {model} | {cell(ed, 'time (min)')} | {cell(ed, 'max |φ err|')} | "
          f"{cell(mj, 'time (min)')} | {cell(mj, 'max |φ err|')} |")
    if not n:
        w("| (no scene runs in this report) | | | | | |")
    w("")


def _per_step_table(raw: str, w) -> None:
    _, rows = table_after(raw, "## Compiled engine: per communication step")
    if not rows:
        return
    w("## What does a co-simulation step cost in Python?")
    w("")
    w("The first 30 s of the synthetic record in 3000 communication steps of 0.01 s, `ag` held over each step "
      "(zero-order hold, as a co-simulation master drives an FMU), the outputs read after each: a "
      "`Simulator(model).advance(t, ag)` loop, and the engine's raw loop underneath it, at the default settings.")
    w("")
    w("| model | scheme, settings | impacts | `Simulator.advance` [µs/step] | raw loop [µs/step] |")
    w("| --- | --- | --- | --- | --- |")
    for r in rows:
        w(f"| {r.get('model')} | {r.get('scheme, settings')} | {r.get('impacts')} | {r.get('API [µs/step]')} | "
          f"{r.get('raw [µs/step]')} |")
    w("")


def _fmu_table(raw: str, w) -> None:
    # (the title of runs made before the Python engine's removal too)
    _, rows = table_after(raw, "**The FMUs against the do-nothing FMU**")
    if not rows:
        _, rows = table_after(raw, "**The FMUs on each engine**")
    _, cold = table_after(raw, "Cold start, fresh interpreter per sample")
    if not rows and not cold:
        return
    w("## How much does an FMU step cost?")
    w("")
    defaults = _fmu_default_tolerances(raw)
    w("The FMUs driven by fmpy's `FMU2Slave` over the 30 s record, one `doStep` per 0.01 s, `ag` set before and "
      "`phi` read after each step; against a do-nothing FMU driven by the same loop (the floor of the master and "
      "the FMI calls). *(default)*: the FMU's default tolerance at the time of the run.")
    w("")
    if rows:
        w("| FMU setting | µs per step | do-nothing FMU [µs/step] | × do-nothing | max error [rad] |")
        w("| --- | --- | --- | --- | --- |")
        for r in rows:
            setting = r.get("FMU setting", "")
            m = re.match(r"(\w+) event-driven tol ([0-9.e+-]+)", setting)
            if m and m.group(1) in defaults and float(m.group(2)) == defaults[m.group(1)]:
                setting += " *(default)*"
            w(f"| {setting} | {r.get('compiled engine [µs/step]')} | {r.get('do-nothing FMU [µs/step]')} | "
              f"{r.get('× do-nothing')} | {r.get('max |φ err| compiled [rad]')} |")

        w("")
    if cold:
        w("Cold start (fresh interpreter: instantiate to the end of the first step): "
          + ", ".join(f"{r.get('FMU')} {r.get('instantiate → first step')}" for r in cold) + ".")
        w("")


def _fmu_default_tolerances(raw: str) -> dict:
    """{"rigid": tolerance, "flexible": tolerance} of the rows the run marked "(FMU defaults)"."""
    out = {}
    for model in ("rigid", "flexible"):
        _, rows = table_after(raw, f"**{model}** (target")
        for r in rows:
            m = re.match(r"event-driven tol ([0-9.e+-]+).*\(FMU defaults\)", r.get("FMU setting", ""))
            if m:
                out[model] = float(m.group(1))
    return out


def _ensemble_table(raw: str, perf_dir: Path, w) -> None:
    rows = []
    ens = perf_dir / "ensemble.md"
    if ens.is_file():
        t = ens.read_text()
        rows.append(("one-sine pulse ensemble, 2000 cases of the rigid block, event-driven",
                     _first(r"Best throughput: \*\*([0-9.,]+ cases/s)", t),
                     _first(r"Machine: ([^;]*?\(load average [0-9.]+ at start\))", t),
                     "[ensemble.md](performance/ensemble.md)"))
    frag = perf_dir / "fragility.md"
    if frag.is_file():
        t = frag.read_text()
        rows.append((f"multiple-stripe analysis, {_first(r'= ([0-9]+) cases', t)} cases on 30 s records, fits "
                     "included", _first(r"\*\*[0-9.]+ s end to end, ([0-9.,]+ cases/s)\*\*", t) + " end to end",
                     _first(r"Machine: ([^;]*?\(load average [0-9.]+ at start\))", t),
                     "[fragility.md](performance/fragility.md)"))
    if not rows:
        return
    w("## How many cases per second in an ensemble or a fragility analysis?")
    w("")
    w("| workload | throughput | machine (load) | details |")
    w("| --- | --- | --- | --- |")
    for r in rows:
        w("| " + " | ".join(r) + " |")
    w("")


#: the equal-error tables summarised, and the levels shown
SPEED_SCENES = ["Rigid block, one-sine pulse below overturning", "Rigid block, 30 s synthetic record",
                "Flexible oscillator, soft column, pulse"]
SPEED_LEVELS = ["1e-03", "1e-06", "1e-08"]


def _speed_table(raw: str, w) -> None:
    found = [(title, table_after(raw, f"**{title}**")[1]) for title in SPEED_SCENES]
    found = [(t, rows) for t, rows in found if rows]
    if not found:
        return
    w("## Speed against error")
    w("")
    w("The time each contender needs to reach a max error (its cheapest setting that does; *≤*: its cheapest run "
      "is already more accurate; n/r: no setting reaches it): the compiled engine at its better scheme at that "
      "level, the solve_ivp baseline (DOP853 with impact events; rigid block only) and Siconos' Moreau-Jean "
      "(rigid block only). The full tables and the work-precision plot are in the full run below.")
    w("")
    w("| scene | max error [rad] | rocking_model | solve_ivp | Siconos | solve_ivp / rocking_model |")
    w("| --- | --- | --- | --- | --- | --- |")
    for title, rows in found:
        for level in SPEED_LEVELS:
            r = _row(rows, **{"error [rad]": level})
            if r:
                w(f"| {title} | {level} | {r.get('compiled best')} | {r.get('solve_ivp (best variant)', '–')} | "
                  f"{r.get('Siconos', '–')} | {r.get('solve_ivp / C', '–')} |")
    w("")


def summarise(raw: str, perf_dir: Path) -> str:
    """The summary tables of the full run ``raw`` (Markdown written by `benchmarks.report`)."""
    L: list[str] = []
    w = L.append
    _simulate_table(raw, w)
    _per_step_table(raw, w)
    _fmu_table(raw, w)
    _ensemble_table(raw, perf_dir, w)
    _speed_table(raw, w)
    return "\n".join(L)


def _header(raw: str) -> tuple[str, str, str]:
    """(date and command, machine line, load) of the full run."""
    gen = _first(r"Generated by (`[^`]*`) on ([0-9: -]+)", raw)
    date = _first(r"Generated by `[^`]*` on ([0-9: -]+)", raw)
    machine = _first(r"- Machine: ([^;\n]*)", raw)
    load = _first(r"load average at start ([0-9., ]+)", raw)
    return f"{gen} on {date}", machine, load


def compose(raw: str, kept: str, perf_dir: Path) -> str:
    """The page: the title, the machine and load, the summary tables, the full run collapsed, the kept sections
    (another script's runs, possibly on another machine) collapsed."""
    body = raw.split("\n", 1)[1] if raw.startswith("# ") else raw
    run, machine, load = _header(raw)
    L = ["# Performance of rocking_model", "",
         f"What a run costs, measured by {run} on one machine: **{machine}**, load average at start "
         f"{load} (1, 5, 15 min). Every table in the summary comes from that run unless its row names another "
         "machine; other machines and a busier load give other figures. **Do not edit by hand**: "
         "`python -m benchmarks` re-runs the suite and rewrites this page; `python -m benchmarks.summary` "
         "rebuilds the summary from the recorded tables below.", "",
         summarise(raw, perf_dir), "",
         "## Raw runs", "",
         f'{RAW_OPEN} of {run} ({machine}): targets, scenes and references, equal-error tables, every run, '
         "convergence orders, compiled engine, ensembles, FMUs, memory, method</summary>", "",
         _mark_details(_demote(body.strip())), "", "</details>", ""]
    if kept.strip():
        machines = sorted(set(re.findall(r"run on [0-9-]+, ([^,)]+), [0-9]+ cores", kept)))
        L += [f"{KEPT_OPEN}: co-simulation accuracy and FMU binary overhead"
              f"{' (' + '; '.join(machines) + ')' if machines else ''}</summary>", "",
              _demote(kept.strip()), "", "</details>", KEPT_END, ""]
    return "\n".join(L)


def _demote(md: str) -> str:
    # the full run's sections are subsections of "Raw runs"
    return re.sub(r"^(#{2,5}) ", r"#\1 ", md, flags=re.M)


def _promote(md: str) -> str:
    return re.sub(r"^#(#{2,6}) ", r"\1 ", md, flags=re.M)


def _mark_details(md: str) -> str:
    # nested collapsed sections: MkDocs' md_in_html renders their Markdown only with the attribute
    return md.replace("<details><summary>", '<details markdown="1"><summary>')


def split_page(page: str, keep_marker: str) -> tuple[str, str]:
    """(full run Markdown, kept sections after ``keep_marker``) of a page written by `compose` or of a page
    of the old layout (the full run at the top level)."""
    kept = ""
    if keep_marker in page:
        page, kept = page.split(keep_marker, 1)
        kept = kept.split(KEPT_END, 1)[0].strip()
        kept = _promote(re.sub(r"\n</details>\s*$", "", kept).strip())
        page = re.sub(re.escape(KEPT_OPEN) + r".*$", "", page, flags=re.S)
    if RAW_OPEN in page:
        head = "# Performance of rocking_model\n\n"
        body = page.split(RAW_OPEN, 1)[1].split("</summary>", 1)[1]
        body = body.rsplit("</details>", 1)[0]
        # the full run's own header lines were kept at the top of the collapsed section
        raw = head + _promote(body.strip())
    else:
        raw = page.strip()
    return raw.replace('<details markdown="1"><summary>', "<details><summary>"), kept


def main(argv=None) -> int:
    import argparse

    from benchmarks.report import KEEP_MARKER
    ap = argparse.ArgumentParser(description="Rebuild the summary of docs/performance.md from its recorded tables.")
    ap.add_argument("--page", default=str(ROOT / "docs" / "performance.md"))
    args = ap.parse_args(argv)
    page = Path(args.page)
    raw, kept = split_page(page.read_text(), KEEP_MARKER)
    page.write_text(compose(raw, KEEP_MARKER + "\n\n" + kept if kept else "", page.parent / "performance"))
    print(f"wrote {page}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
