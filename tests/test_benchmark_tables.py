"""The benchmark's equal-error table and targets (the compiled-engine rows) on made-up runs: the
arithmetic only, nothing timed."""
import math

from benchmarks import report
from benchmarks.run import equal_error


def _e(contender, label, time, err):
    return {"contender": contender, "label": label, "time": time, "errors": {"phi_max": err}, "setting": {}}


def test_equal_error_compares_each_engine_with_the_baseline_and_siconos():
    entries = [_e("event_driven", "package event-driven", 1e-2, 1e-9),
               _e("c_event_driven", "compiled event-driven", 1e-4, 1e-9),
               _e("c_moreau_jean", "compiled Moreau-Jean", 1e-3, 1e-3),
               _e("c_moreau_jean", "compiled Moreau-Jean", 1e-2, 1e-4),
               _e("baseline", "solve_ivp DOP853", 2e-2, 1e-9),
               _e("siconos", "Siconos Moreau-Jean", 3e-2, 1e-2),
               _e("siconos", "Siconos Moreau-Jean", 5e-1, 1e-3)]
    ee = equal_error(entries)
    row = ee["1e-03"]
    assert row["compiled"]["by"] == "compiled event-driven"
    assert math.isclose(row["ratio_c_baseline"], 200.0) and math.isclose(row["ratio_baseline"], 2.0)
    assert math.isclose(row["ratio_c_package"], 100.0) and math.isclose(row["ratio_c_siconos"], 5000.0)
    assert math.isclose(row["ratio_cmj_siconos"], 500.0)             # Siconos 0.5 s against 1 ms, both MJ
    assert math.isinf(ee["1e-04"]["ratio_cmj_siconos"])              # Siconos does not reach 1e-4 rad
    assert math.isnan(ee["1e-05"]["ratio_cmj_siconos"])              # neither does the compiled MJ 1e-5 rad
    assert math.isnan(ee["1e-06"]["siconos"]["time"])


def test_compiled_targets_read_the_per_step_cold_start_memory_and_ensemble_figures():
    res = {"compiled": {"per_step": {"rows": [
        {"kind": "rigid", "scheme": "event_driven", "raw_us": 0.8, "api_us": 1.5, "steps": 3000, "dt": 0.01,
         "internal_steps": 3100, "impacts": 300, "raw_us_per_internal_step": 0.77},
        {"kind": "rigid", "scheme": "moreau_jean", "raw_us": 4.0, "api_us": 5.0, "steps": 3000, "dt": 0.01,
         "internal_steps": 30000, "impacts": 30, "raw_us_per_internal_step": 0.4},
        {"kind": "flexible", "scheme": "event_driven", "raw_us": 6.0, "api_us": 7.0, "steps": 3000, "dt": 0.01,
         "internal_steps": 5000, "impacts": 20, "raw_us_per_internal_step": 3.6}]},
        "cold": {"import_to_first_step": 0.2, "numpy_import": 0.1, "package_import": 0.09, "first_step": 0.01}},
        "ensemble": {"best": 9000.0, "python_serial": 150.0, "compiled_serial": 4000.0, "best_over_python": 60.0}}
    rows = report._compiled_targets(res)
    # rigid event-driven 0.8 <= 1 us, flexible 6 > 5 us, Moreau-Jean 0.4 us per time step, cold start 0.2 s,
    # ensembles 60x
    assert [ok for _, _, ok in rows] == ["yes", "**no** (1.2×)", "yes", "**no** (4.0×)", "yes"], rows
    assert "0.40 µs raw engine loop" in rows[2][1] and "60×" in rows[4][1]


def test_equal_error_and_targets_without_the_removed_python_engine():
    """Results since the Python engine's removal: no "package" family, its ratios and targets left out."""
    entries = [_e("c_event_driven", "compiled event-driven", 1e-4, 1e-9),
               _e("baseline", "solve_ivp DOP853", 2e-2, 1e-9)]
    row = equal_error(entries)["1e-03"]
    assert "package" not in row and "ratio_baseline" not in row and "ratio_c_package" not in row
    assert math.isclose(row["ratio_c_baseline"], 200.0)
    res = {"scenes": {"s": {"name": "s", "kind": "rigid", "equal_error": {"1e-03": row}}},
           "ensemble": {"best": 9000.0, "compiled_serial": 4000.0, "best_over_serial": 2.25}}
    names = [name for name, _, _ in report._targets(res)]
    assert not any("Python engine" in n for n in names), names


def test_performance_page_summarises_and_keeps_the_full_run_collapsed():
    """docs/performance.md: one short table per question first (the machine and its load named), the full run
    and the other machines' runs in collapsed sections; `python -m benchmarks.summary` rebuilds the page from
    its own recorded tables, unchanged (the summary is read from those tables, nothing re-run)."""
    from pathlib import Path

    from benchmarks import summary
    page_path = Path(__file__).resolve().parents[1] / "docs" / "performance.md"
    page = page_path.read_text()
    head = page.split("## Raw runs", 1)[0]
    for question in ("## How long does a `simulate` take?", "## How much does an FMU step cost?",
                     "## How many cases per second", "## Speed against error"):
        assert question in head, question
    assert "load average at start" in head.split("\n## ", 1)[0]
    assert len(head.splitlines()) < 90, len(head.splitlines())
    assert summary.RAW_OPEN in page and summary.KEPT_OPEN in page and page.rstrip().endswith(summary.KEPT_END)
    raw, kept = summary.split_page(page, report.KEEP_MARKER)
    again = summary.compose(raw, report.KEEP_MARKER + "\n\n" + kept, page_path.parent / "performance")
    assert again == page
    # every figure of the summary's first table is one of the full run's
    _, rows = summary.table_after(raw, "<summary>Rigid block, 30 s synthetic record (")
    ed = summary._row(rows, contender="compiled event-driven", setting=summary.DEFAULT_ED)
    assert f"| 30 s record | rigid block | {ed['time (min)']} |" in head
