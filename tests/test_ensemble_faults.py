"""Ensembles under faults, as a user meets them: two runs on one output, workers killed until none is left,
malformed cases, broken rows and parts left by interruptions. The runs that need real processes are
subprocesses of the `rocking` command, each bounded in time."""
import csv
import math
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from rocking_model.ensemble import (FIELDS, CsvWriter, OutputInUse, OutputLock, ParquetWriter, RepairWarning,
                                    pulse_cases, read_results, run_case, run_ensemble)
from rocking_model.records import write_csv

#: [s] bound on one subprocess run of these tests (a hang fails the test instead of blocking the suite)
RUN_TIMEOUT = 180.0


def _grid(n_freq=2):
    return pulse_cases("sine", amplitude_ratios=[1.5, 3.0, 6.0], frequency_ratios=[2.0, 8.0][:n_freq])


def _rows_per_line(path):
    """The CSV's lines, each split into fields (what pandas and spreadsheets see)."""
    with open(path, newline="") as f:
        return list(csv.reader(f))


def _records(tmp_path):
    """A short record (0.5 s) and a long one (200 s), both below uplift or rocking mildly, so no case
    overturns early and stops. On the compiled engine (about 0.5 us per Moreau-Jean step) the tests that need
    a run still going pass their own small dt_max (`SLOW_DT_SHORT`, `SLOW_DT_LONG`)."""
    t = np.arange(0, 0.5001, 0.01)
    short = write_csv(tmp_path / "short.csv", t, 0.3 * 9.80665 * np.sin(4 * np.pi * t), units="g")
    t = np.arange(0, 200.0001, 0.01)
    long = write_csv(tmp_path / "long.csv", t, 0.1 * 9.80665 * np.sin(4 * np.pi * t), units="g")
    return str(short), str(long)


#: [s] Moreau-Jean steps that keep a run going on the compiled engine: a short-record case (5.5 s) then takes
#: 4.4e6 steps (about 2.5 s; 8000 per 0.01 s output interval, within the default max_steps = 10000 of an
#: advance), a long-record case (205 s) 2e7 steps of SLOW_DT_LONG (about 10 s)
SLOW_DT_SHORT = 1.25e-6
SLOW_DT_LONG = 1e-5


def _cli(*args):
    return [sys.executable, "-m", "rocking_model.cli", "ensemble", *map(str, args), "--no-progress", "--no-plot"]


def _kill_tree(proc):
    import psutil
    try:
        for child in psutil.Process(proc.pid).children(recursive=True):
            child.kill()
    except psutil.NoSuchProcess:
        pass
    proc.kill()
    proc.wait(10)


def _wait_for_rows(out, n, proc, deadline):
    while time.monotonic() < deadline:
        if out.exists() and len(out.read_text().splitlines()) >= n + 1:
            return
        assert proc.poll() is None, proc.communicate()
        time.sleep(0.05)
    raise AssertionError(f"no {n} row(s) in {out} in time")


# ------------------------------------------------------------------------------------------ two runs
def test_second_run_on_one_output_is_refused_naming_the_first(tmp_path):
    """A double launch: the second run is refused at once (exit 1) with the first run's pid, host and start
    time; the first run's rows are neither truncated nor duplicated (then it is interrupted with Ctrl-C, to
    keep the test short), and each case appears once."""
    short, _ = _records(tmp_path)
    out = tmp_path / "runs.csv"
    argv = _cli("--record", short, "--scales", "0.2:1.2:12", "--scheme", "moreau_jean", "--dt-max", SLOW_DT_SHORT,
                "--workers", "0", "--out", out)
    first = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        _wait_for_rows(out, 1, first, time.monotonic() + RUN_TIMEOUT)
        before = out.read_bytes()
        second = subprocess.run(argv, capture_output=True, text=True, timeout=RUN_TIMEOUT)
        still_running = first.poll() is None
        first.send_signal(signal.SIGINT)
        stdout, stderr = first.communicate(timeout=RUN_TIMEOUT)
    finally:
        if first.poll() is None:
            _kill_tree(first)
    assert second.returncode == 1 and "Traceback" not in second.stderr, (second.stdout, second.stderr)
    assert still_running, "the first run ended before the second started: lengthen its cases"
    assert f"{out} is in use by another run (pid {first.pid} on host " in second.stderr and "started" in \
        second.stderr
    assert first.returncode == 130 and "run the same command to resume" in stderr, stderr
    after = out.read_bytes()
    assert after.startswith(before)                            # not truncated: only appended to
    lines = _rows_per_line(out)
    assert lines[0] == list(FIELDS) and 2 <= len(lines) <= 13
    assert all(len(r) == len(FIELDS) for r in lines)
    assert len({r[0] for r in lines[1:]}) == len(lines) - 1   # no case twice
    assert not (tmp_path / "runs.csv.lock").exists()          # released at the end


def test_lock_is_held_for_the_whole_run_csv_and_parquet(tmp_path):
    """While a run holds the lock, run_ensemble on the same output (CSV or Parquet) is refused before it
    reads or writes anything; once released, the output is usable again."""
    pytest.importorskip("pyarrow")
    cases = _grid(1)
    for out in (tmp_path / "r.csv", tmp_path / "r.parquet"):
        with OutputLock(out):
            with pytest.raises(OutputInUse, match=rf"is in use by another run \(pid {os.getpid()} on host .*, "
                                                  r"started \d{4}-\d\d-\d\d \d\d:\d\d:\d\d UTC"):
                run_ensemble(cases, out, workers=0, progress=False)
            assert not out.exists()
        assert run_ensemble(cases, out, workers=0, progress=False)["n_run"] == 3
        assert len(read_results(out)) == 3


def test_output_is_only_appended_to(tmp_path, monkeypatch):
    """An existing output is never opened for writing from the start ("w" truncates a concurrent run's rows);
    a fresh one is created by appending too."""
    import builtins

    modes = []
    real_open = builtins.open

    def spy(file, mode="r", *a, **k):
        if str(file).endswith("o.csv"):
            modes.append(mode)
        return real_open(file, mode, *a, **k)

    monkeypatch.setattr(builtins, "open", spy)
    out = tmp_path / "o.csv"
    run_ensemble(_grid(1), out, workers=0, progress=False)
    run_ensemble(_grid(2), out, workers=0, progress=False)
    assert modes and not any("w" in m for m in modes), modes


def test_two_parquet_writers_never_share_a_name(tmp_path, monkeypatch):
    """Two writers on one directory (two runs, or a crashed run's leftovers) interleave their writes: each
    part has its own temporary and final name, so no part overwrites another and no rename fails."""
    pytest.importorskip("pyarrow")
    cases = _grid()
    rows = [dict(c, error="", overturned=False) for c in cases]
    w1, w2 = ParquetWriter(tmp_path / "p.parquet"), ParquetWriter(tmp_path / "p.parquet")
    w1.write(rows[:3])
    w2.write(rows[3:])
    real_replace = os.replace
    nested = []

    def replace(src, dst):          # w2 flushes between w1's write of its temporary file and its rename
        if not nested:
            nested.append(1)
            w2.flush()
        real_replace(src, dst)

    monkeypatch.setattr(os, "replace", replace)
    w1.flush()
    monkeypatch.undo()
    assert {r["case_id"] for r in read_results(tmp_path / "p.parquet")} == {c["case_id"] for c in cases}


# ------------------------------------------------------------------------------------------ worker loss
def test_run_whose_workers_are_all_killed_ends_with_a_clear_error(tmp_path):
    """The workers are killed again and again (as the out-of-memory killer would) until the cluster has
    none: the run ends (exit 1) with one clear message instead of waiting forever; the rows written before
    stay, the lock is released, and a rerun resumes from them."""
    pytest.importorskip("dask.distributed")
    psutil = pytest.importorskip("psutil")
    short, long = _records(tmp_path)
    out = tmp_path / "runs.csv"
    argv = _cli("--record", short, long, "--scales", "0.5", "1", "--scheme", "moreau_jean", "--dt-max", SLOW_DT_LONG,
                "--workers", "2", "--batch-size", "1", "--no-workers-timeout", "3", "--out", out)
    proc = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + RUN_TIMEOUT
    try:
        _wait_for_rows(out, 1, proc, deadline)
        kept = read_results(out)
        before = out.read_bytes()
        before = before[:before.rfind(b"\n") + 1]
        while proc.poll() is None and time.monotonic() < deadline:
            try:
                workers = [c for c in psutil.Process(proc.pid).children(recursive=True)
                           if "spawn_main" in " ".join(c.cmdline())]
            except psutil.NoSuchProcess:
                break
            for w in workers:
                try:
                    w.send_signal(signal.SIGKILL)
                except psutil.NoSuchProcess:
                    pass
            time.sleep(0.2)
        ended = proc.poll() is not None
        stdout, stderr = proc.communicate(timeout=30) if ended else ("", "")
    finally:
        if proc.poll() is None:
            _kill_tree(proc)
    assert ended, "the run still waits for results with no worker left"
    assert proc.returncode == 1 and "Traceback" not in stderr, stderr
    assert "rocking ensemble: error:" in stderr and f"the finished cases are in {out}" in stderr
    assert ("no worker for 3 s" in stderr) or ("died while running it" in stderr) or \
        ("workers died while no batch of cases finished" in stderr), stderr
    after = {r["case_id"]: r for r in read_results(out)}
    assert kept and {r["case_id"] for r in kept} <= set(after) and out.read_bytes().startswith(before)
    assert all(len(r) == len(FIELDS) for r in _rows_per_line(out))
    assert not (tmp_path / "runs.csv.lock").exists()
    # a rerun skips what finished (the long cases are left out here: a rerun of them takes minutes)
    done = set(after)
    from rocking_model.ensemble import record_cases
    cases = record_cases([short], [0.5, 1.0], schemes=["moreau_jean"], dt_max=SLOW_DT_LONG)
    s = run_ensemble(cases, out, workers=0, progress=False)
    assert s["n_skipped"] == len(done & {c["case_id"] for c in cases}) >= 1


# ------------------------------------------------------------------------------------------ bad cases
def test_malformed_cases_become_error_rows_and_the_batch_keeps_its_good_cases(tmp_path):
    """b = h = 0, b as a string, a missing field, a case that is not a dict: each becomes a row with its
    error (naming the field) instead of raising; the good cases of the same batch are kept; the output
    stays typed (Parquet too); a resume does not run the bad cases again."""
    good = _grid(1)
    c = good[0]
    bad = [dict(c, b=0.0, h=0.0, case_id="bad-zero"), dict(c, b="0.2 m", case_id="bad-str"),
           dict({k: v for k, v in c.items() if k != "model"}, case_id="bad-missing"), "not a case"]
    errors = [run_case(b)["error"] for b in bad]
    assert errors[0] == "ValueError: b = 0 is out of range; allowed range [1e-06, 1000]"
    assert errors[1] == "ValueError: b must be a real number, got '0.2 m'"
    assert errors[2] == "case field 'model' is missing"
    assert errors[3].startswith("TypeError: a case is a dict of case fields")
    for out, kw in ((tmp_path / "r.csv", dict(workers=0)),
                    (tmp_path / "r.parquet", dict(workers=1, processes=False, batch_size=len(good) + len(bad)))):
        if out.suffix == ".parquet":
            pytest.importorskip("pyarrow")
            pytest.importorskip("dask.distributed")
        s = run_ensemble(good[:2] + bad + good[2:], out, progress=False, **kw)
        assert s["n_run"] == 7 and s["n_errors"] == 4
        rows = {r["case_id"]: r for r in read_results(out)}
        assert len(rows) == 7
        assert all(rows[g["case_id"]]["error"] == "" for g in good)
        assert math.isnan(rows["bad-str"]["b"]) and "'0.2 m'" in rows["bad-str"]["error"]
        again = run_ensemble(good[:2] + bad + good[2:], out, progress=False, **kw)
        assert again["n_run"] == 0 and again["n_skipped"] == 7


# ------------------------------------------------------------------------------------------ repairs
def test_resume_sets_aside_a_broken_row_in_the_middle_and_keeps_the_good_rows(tmp_path):
    """Rows torn in the middle of the file (an interleaved write) and at its end (a kill): the resume moves
    them to <out>.rejected, keeps every good row byte for byte, runs the broken cases again, and leaves a
    file whose every line has the output's columns (what pandas reads)."""
    cases = _grid()
    out = tmp_path / "o.csv"
    run_ensemble(cases, out, workers=0, progress=False)
    lines = out.read_bytes().split(b"\n")
    assert len(lines) == 8 and lines[-1] == b""
    torn_mid = lines[2][:40]
    broken = lines[:2] + [torn_mid + lines[3]] + lines[4:6] + [lines[6][:55]]
    out.write_bytes(b"\n".join(broken))
    good = [lines[1], lines[4], lines[5]]
    assert {r["case_id"] for r in read_results(out)} == {ln.split(b",")[0].decode() for ln in good}
    with pytest.warns(RepairWarning, match=r"2 broken row\(s\) \(line 3, 6\) set aside in .*o\.csv\.rejected"):
        s = run_ensemble(cases, out, workers=0, progress=False)
    assert s["n_run"] == 3 and s["n_skipped"] == 3
    new = out.read_bytes().split(b"\n")
    assert new[:4] == [lines[0]] + good
    rows = _rows_per_line(out)
    assert len(rows) == 7 and all(len(r) == len(FIELDS) for r in rows)
    assert len({r[0] for r in rows[1:]}) == 6
    rejected = (tmp_path / "o.csv.rejected").read_bytes()
    assert torn_mid in rejected and lines[6][:55] in rejected


def test_a_torn_quoted_field_does_not_swallow_the_good_rows_after_it(tmp_path):
    """A row torn inside a quoted field (an error message with commas) leaves an open quote: the repair
    joins lines into one record only where that is a true multi-line record (rows of earlier versions), so
    the whole rows after the torn one are kept."""
    cases = _grid()
    out = tmp_path / "o.csv"
    run_ensemble(cases[:4], out, workers=0, progress=False)
    lines = out.read_bytes().split(b"\n")
    bad = dict(cases[4], scheme="rk4")
    row = run_case(bad)
    assert "," in row["error"]                    # written in quotes
    with open(out, "a", newline="") as f:
        csv.DictWriter(f, FIELDS).writerow({k: row.get(k, "") for k in FIELDS})
    text = out.read_bytes().split(b"\n")
    torn = text[5][:text[5].index(b'"') + 10]      # cut inside the quoted error field
    # then whole rows, and a row of an earlier version whose error message spans two lines
    old_row = dict(run_case(dict(cases[5], scheme="rk4")), error="line one, with a comma\nline two")
    with open(tmp_path / "old.csv", "w", newline="") as f:
        csv.DictWriter(f, FIELDS).writerow({k: old_row.get(k, "") for k in FIELDS})
    out.write_bytes(b"\n".join(lines[:3] + [torn] + lines[3:5]) + b"\n" + (tmp_path / "old.csv").read_bytes())
    with pytest.warns(RepairWarning, match=r"1 broken row\(s\) \(line 4\)"):
        s = run_ensemble(cases, out, workers=0, progress=False)
    got = {r["case_id"]: r for r in read_results(out)}
    assert set(got) == {c["case_id"] for c in cases}
    assert got[cases[5]["case_id"]]["error"] == "line one, with a comma\nline two"
    assert s["n_run"] == 1                         # only the torn case runs again


def test_truncated_header_is_named_as_such(tmp_path):
    """A header cut short: with no row after it, the resume completes it (reported); with rows after it,
    the message says the header is truncated and what to do (not "not an ensemble output")."""
    header = ",".join(FIELDS)
    out = tmp_path / "o.csv"
    out.write_text(header[:30])
    with pytest.warns(RepairWarning, match="header was cut short and no row followed it: header completed"):
        s = run_ensemble(_grid(1), out, workers=0, progress=False)
    assert s["n_run"] == 3 and _rows_per_line(out)[0] == list(FIELDS)
    out.write_text(header[:30] + "\n" + "x," * (len(FIELDS) - 1) + "x\n")
    with pytest.raises(ValueError, match=rf"its header is truncated \(it stops in column 7 of {len(FIELDS)}.*"
                                         r"move it "
                                         r"aside \(or delete it\) and rerun, or give another --out"):
        run_ensemble(_grid(1), out, workers=0, progress=False)
    with pytest.raises(ValueError, match="not those of an ensemble output"):
        out.write_text("a,b\n1,2\n")
        CsvWriter(out)


def test_parquet_parts_are_fsynced_before_and_after_the_rename(tmp_path, monkeypatch):
    """A part is written to a temporary file, fsynced, renamed, then the directory is fsynced: a power loss
    leaves whole parts only."""
    pytest.importorskip("pyarrow")
    if not os.path.isdir("/proc/self/fd"):
        pytest.skip("needs /proc to name the fsynced files")
    events = []
    real_fsync, real_replace = os.fsync, os.replace
    monkeypatch.setattr(os, "fsync", lambda fd: (events.append(("fsync", os.readlink(f"/proc/self/fd/{fd}"))),
                                                 real_fsync(fd))[1])
    monkeypatch.setattr(os, "replace", lambda a, b: (events.append(("replace", str(a), str(b))),
                                                     real_replace(a, b))[1])
    w = ParquetWriter(tmp_path / "p.parquet")
    w.write([dict(c, error="", overturned=False) for c in _grid(1)])
    w.flush()
    monkeypatch.undo()
    (i, (_, tmp, final)), = [(i, e) for i, e in enumerate(events) if e[0] == "replace"]
    assert ("fsync", tmp) in events[:i] and ("fsync", str(tmp_path / "p.parquet")) in events[i + 1:]
    assert os.path.basename(final).startswith("part-") and os.path.exists(final)


def test_cut_parquet_part_is_reported_and_set_aside_on_resume(tmp_path):
    """A part cut short (a power loss before this fix) is skipped with a warning by read_results, and set
    aside as *.corrupt by a resume, which runs its cases again: no crash, no silent loss."""
    pytest.importorskip("pyarrow")
    cases = _grid()
    out = tmp_path / "o.parquet"
    run_ensemble(cases[:3], out, workers=0, progress=False)
    run_ensemble(cases, out, workers=0, progress=False)
    parts = sorted(out.glob("part-*.parquet"))
    assert len(parts) == 2
    data = parts[0].read_bytes()
    parts[0].write_bytes(data[:len(data) // 2])
    with pytest.warns(RepairWarning, match="unreadable"):
        assert len(read_results(out)) == 3
    with pytest.warns(RepairWarning, match=rf"{parts[0].name}: unreadable .*set aside as {parts[0].name}.corrupt"):
        s = run_ensemble(cases, out, workers=0, progress=False)
    assert s["n_run"] == 3 and s["n_skipped"] == 3
    assert (out / (parts[0].name + ".corrupt")).read_bytes() == data[:len(data) // 2]
    assert {r["case_id"] for r in read_results(out)} == {c["case_id"] for c in cases}


def test_workers_dying_over_and_over_end_the_wait(monkeypatch, tmp_path):
    """The stalled-wait rule itself, without timing: a cluster that always has a worker (a nanny restarts
    each one) but loses them one after another while no batch finishes ends with `WorkersLost` after
    MAX_DEATHS_WITHOUT_PROGRESS deaths; a finished batch resets the count."""
    pytest.importorskip("dask.distributed")
    import dask.distributed

    from rocking_model import ensemble
    from rocking_model.ensemble import MAX_DEATHS_WITHOUT_PROGRESS, WorkersLost

    class Pending:                     # as_completed over tasks that never finish
        def __init__(self, futures):
            self.n = len(futures)

        def is_empty(self):
            return False

        def next_batch(self, block=False):
            return []

        def count(self):
            return self.n

    class Churning:                    # each look at the scheduler shows a new worker: the last one died
        looks = 0

        def nthreads(self):
            Churning.looks += 1
            return {f"tcp://127.0.0.1:{40000 + Churning.looks}": 1}

    monkeypatch.setattr(dask.distributed, "as_completed", Pending)
    monkeypatch.setattr(ensemble, "_WORKER_CHECK", 0.0)
    monkeypatch.setattr(ensemble, "_POLL", 0.0)
    with pytest.raises(WorkersLost, match=rf"{MAX_DEATHS_WITHOUT_PROGRESS} Dask workers died while no batch"):
        ensemble._collect(Churning(), [object()] * 3, lambda rows: None, 1e9, tmp_path / "r.csv")
    # every death is counted once: the first look sees the first worker, then one death per look
    assert Churning.looks == MAX_DEATHS_WITHOUT_PROGRESS + 1
