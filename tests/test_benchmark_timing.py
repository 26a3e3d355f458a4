"""The benchmarks' timing method (benchmarks/contenders.py `timed`, Python's timeit practice), checked on its
behaviour, not on any time: the garbage collector is off during each timed run and on again after, no
gc.collect() precedes a run, short runs are repeated within the budget, long ones run at least once, and the
tables compare the minimum of the repeats."""
import gc
import time

from benchmarks import contenders as C


def test_gc_off_during_each_run_and_restored_after():
    seen = []
    assert gc.isenabled()
    C.timed(lambda: seen.append(gc.isenabled()), repeats=3, budget=1.0, min_total=0.0)
    assert seen == [False, False, False]
    assert gc.isenabled()


def test_no_collect_before_a_run(monkeypatch):
    calls = []
    monkeypatch.setattr(gc, "collect", lambda *a: calls.append(a) or 0)
    C.timed(lambda: None, repeats=5, budget=1.0, min_total=0.0)
    assert calls == []


def test_gc_restored_when_the_run_raises():
    def boom():
        raise ValueError("x")
    try:
        C.timed(boom)
    except ValueError:
        pass
    assert gc.isenabled()


def test_short_runs_repeated_long_runs_once():
    _, short = C.timed(lambda: None, repeats=1, budget=10.0, min_total=0.02)
    assert len(short) > 100  # an empty call repeated until the runs took 0.02 s
    _, long = C.timed(lambda: time.sleep(0.05), repeats=1, budget=0.01, min_total=1.0)
    assert len(long) == 1  # past the budget after the first run


def test_tables_compare_the_minimum():
    assert C.best([3.0, 1.0, 2.0]) == 1.0


def test_post_is_applied_once_to_the_last_result_outside_the_timed_runs():
    calls, seen = [], []
    out, ts = C.timed(lambda: calls.append(1) or len(calls), repeats=4, budget=1.0, min_total=0.0,
                      post=lambda r: seen.append(gc.isenabled()) or r * 10)
    assert len(ts) == len(calls) == 4
    assert out == 40 and seen == [True]


def test_second_pass_interleaves_the_entries_in_rounds(monkeypatch):
    """Each round times every entry once, in order, so that the two sides of a ratio are sampled at the same
    times of the run; each entry keeps its first pass's runs and adds the second pass's, and reports the minimum
    of all of them."""
    from benchmarks import run as R

    order = []
    monkeypatch.setattr(C, "MIN_TOTAL", 0.0)
    entries = [({"contender": "c_event_driven", "times": [5.0]}, lambda: order.append("c") or {}),
               ({"contender": "baseline", "times": [7.0]}, lambda: order.append("b") or {})]
    monkeypatch.setattr(C, "outputs_of", lambda out: out)
    R._second_pass(entries, reps=1, budget=1.0, rounds=3)
    assert order == ["c", "b"] * 3
    for e, _ in entries:
        assert len(e["times"]) == 4 and e["times"][0] in (5.0, 7.0)
        assert e["time"] == min(e["times"]) < 1.0
