"""Ensembles: case grids, one case against a direct simulation, incremental output, resume, Dask."""
import math
from pathlib import Path

import numpy as np
import pytest

from rocking_model import RigidBlock, SinePulse, simulate
from rocking_model.ensemble import (FIELDS, CsvWriter, RepairWarning, pulse_cases, read_results, record_cases,
                                    run_case, run_ensemble)


def _grid(**kw):
    return pulse_cases("sine", amplitude_ratios=[1.5, 3.0, 6.0], frequency_ratios=[2.0, 8.0], **kw)


def test_pulse_grid_is_dimensionless_and_ids_are_stable():
    cases = _grid(geometries=[(0.2, 1.0), (0.3, 2.0)])
    assert len(cases) == 12 and len({c["case_id"] for c in cases}) == 12
    assert [c["case_id"] for c in cases] == [c["case_id"] for c in _grid(geometries=[(0.2, 1.0), (0.3, 2.0)])]
    c = cases[0]
    alpha, p = math.atan(0.2 / 1.0), math.sqrt(3 * 9.81 / (4 * math.hypot(0.2, 1.0)))
    assert c["A"] == pytest.approx(1.5 * 9.81 * math.tan(alpha)) and c["omega_p"] == pytest.approx(2 * p)
    assert c["t_end"] == pytest.approx(2 * math.pi / c["omega_p"] + 15 / p)
    with pytest.raises(ValueError, match="ratios are defined for the rigid block"):
        pulse_cases("sine", amplitude_ratios=[1], frequency_ratios=[1], model="flexible")
    with pytest.raises(ValueError, match="pulse = 'square' is not supported"):
        pulse_cases("square", amplitude_ratios=[1], frequency_ratios=[1])
    with pytest.raises(ValueError, match="amplitude ratio = -1 is out of range"):
        pulse_cases("sine", amplitude_ratios=[-1], frequency_ratios=[1])


def test_case_motion_uses_the_pulse_factory():
    """Each pulse kind of a case is `pulse_from_parameters(kind, A, omega_p, scale=scale)`: starts at 0
    (Ricker centred at 1.5 T_p), rectangular for 2 pi / omega_p; an unknown kind names the field."""
    from rocking_model.ensemble import PULSES, case_motion
    from rocking_model.ground_motion import RectangularPulse, RickerPulse, pulse_from_parameters

    for kind in PULSES:
        c = dict(pulse_cases(kind, amplitudes=[2.0], frequencies=[0.8])[0], scale=1.5)
        m, ref = case_motion(c), pulse_from_parameters(kind, c["A"], c["omega_p"], scale=1.5)
        assert type(m) is type(ref) and m.support == ref.support and m.A == 3.0
        assert [m(t) for t in np.linspace(0, 5, 501)] == [ref(t) for t in np.linspace(0, 5, 501)]
    assert case_motion(pulse_cases("ricker", amplitudes=[2.0], frequencies=[0.8])[0]).t_c == \
        RickerPulse(2.0, 2 * math.pi * 0.8).t_c
    rect = case_motion(pulse_cases("rectangular", amplitudes=[2.0], frequencies=[0.8])[0])
    assert isinstance(rect, RectangularPulse) and rect.duration == pytest.approx(1.25, rel=1e-15)
    with pytest.raises(ValueError, match="motion = 'square' is not supported; allowed values: record, sine"):
        case_motion(dict(pulse_cases("sine", amplitudes=[2.0], frequencies=[0.8])[0], motion="square"))


def test_run_case_equals_direct_simulation():
    c = pulse_cases("sine", amplitude_ratios=[3.0], frequency_ratios=[4.0])[0]
    row = run_case(c)
    blk = RigidBlock(0.2, 1.0)
    res = simulate(blk, SinePulse(c["A"], c["omega_p"]), c["t_end"], scheme="event_driven", tolerance=1e-8)
    assert row["error"] == ""
    assert row["max_abs_phi"] == np.max(np.abs(res.phi))
    assert row["overturned"] == bool(res.overturned[-1]) is True
    assert row["t_overturn"] == res.t[np.argmax(res.overturned)]
    assert row["impacts"] == int(res.impacts[-1])
    assert row["max_phi_over_alpha"] == pytest.approx(row["max_abs_phi"] / blk.alpha)
    # a bad case is reported in its row, not raised
    bad = dict(c, b=-1.0)
    assert "b = -1" in run_case(bad)["error"]


def test_resume_skips_done_cases_and_union_equals_straight_run(tmp_path):
    cases = _grid()
    straight = tmp_path / "straight.csv"
    s = run_ensemble(cases, straight, workers=0, progress=False)
    assert s["n_run"] == 6 and s["n_skipped"] == 0
    rows = {r["case_id"]: r for r in read_results(straight)}
    assert set(rows) == {c["case_id"] for c in cases}
    # overturning is monotone in the amplitude at a fixed frequency here (Makris' spectrum, far from its
    # boundary): the largest amplitude at omega_p/p = 2 overturns, the smallest does not rock much
    by = {(round(r["a_ratio"], 6), r["w_ratio"]): r for r in rows.values()}
    assert by[(6.0, 2.0)]["overturned"] and not by[(1.5, 8.0)]["overturned"]

    # an interrupted run: 2 cases done and a half-written third row
    part = tmp_path / "part.csv"
    seen = []
    run_ensemble(cases[:2], part, workers=0, progress=False, on_row=seen.append)
    with open(part, "a") as f:
        f.write(cases[2]["case_id"] + ",rigid,0.2,1.0,0.0,sin")
    with pytest.warns(RepairWarning, match=r"1 broken row\(s\) \(line 4\) set aside"):
        s = run_ensemble(cases, part, workers=0, progress=False, on_row=seen.append)
    assert s["n_skipped"] == 2 and s["n_run"] == 4
    assert [r["case_id"] for r in seen].count(cases[0]["case_id"]) == 1
    again = run_ensemble(cases, part, workers=0, progress=False)
    assert again["n_run"] == 0 and again["n_skipped"] == 6
    lines = part.read_text().splitlines()
    assert lines[0] == ",".join(FIELDS) and len(lines) == 7           # the cut row was dropped
    resumed = {r["case_id"]: r for r in read_results(part)}
    keys = ("overturned", "impacts", "max_abs_phi", "t_overturn", "A", "omega_p")
    for cid, r in rows.items():
        for k in keys:
            assert resumed[cid][k] == r[k] or (math.isnan(r[k]) and math.isnan(resumed[cid][k])), (cid, k)
    with pytest.raises(ValueError, match="exists"):
        run_ensemble(cases, part, workers=0, progress=False, resume=False)


def test_csv_writer_refuses_foreign_file(tmp_path):
    p = tmp_path / "other.csv"
    p.write_text("a,b\n1,2\n")
    with pytest.raises(ValueError, match="not those of an ensemble output"):
        CsvWriter(p)


def test_dask_local_cluster_and_parquet(tmp_path):
    pytest.importorskip("dask.distributed")
    pytest.importorskip("pyarrow")
    cases = _grid()
    ref = {r["case_id"]: r for r in (run_case(c) for c in cases)}
    out = tmp_path / "res.parquet"
    s = run_ensemble(cases[:3], out, workers=2, processes=False, progress=False, batch_size=2)
    assert s["n_run"] == 3
    s = run_ensemble(cases, out, workers=1, processes=False, progress=False)
    assert s["n_run"] == 3 and s["n_skipped"] == 3 and s["throughput"] > 0
    got = {r["case_id"]: r for r in read_results(out)}
    assert set(got) == set(ref)
    for cid, r in ref.items():
        assert got[cid]["max_abs_phi"] == r["max_abs_phi"] and got[cid]["impacts"] == r["impacts"]
        assert got[cid]["overturned"] == r["overturned"]


def test_record_cases(tmp_path):
    from rocking_model.records import synthetic_record, write_at2
    t, a = synthetic_record(duration=4.0, seed=11)
    p = write_at2(tmp_path / "s.AT2", t, a)
    cases = record_cases([str(p), "synthetic:5"], scales=[0.4, 2.0], geometries=[(0.2, 1.0)], t_end=3.0)
    assert len(cases) == 4 and {c["scale"] for c in cases} == {0.4, 2.0}
    rows = [run_case(c) for c in cases[:2]]
    assert all(r["error"] == "" for r in rows)
    assert rows[1]["A"] == pytest.approx(2.0 * np.max(np.abs(a)), rel=1e-14)
    # scale 0.4 of a 0.4 g record (0.16 g) stays below uplift (g tan(alpha) = 0.2 g): no rocking at all
    assert rows[0]["max_abs_phi"] == 0.0 and rows[0]["impacts"] == 0
    with pytest.raises(FileNotFoundError, match="no such file"):
        record_cases([str(tmp_path / "missing.AT2")])


def test_friction_cases_and_ids():
    """mu is a case field: a finite mu gives its own case id and rows with the slip and the friction demand;
    the default mu = inf keeps the ids of the cases of earlier versions (resumable result files)."""
    import math

    from rocking_model.ensemble import CASE_FIELDS, case_id, pulse_cases, run_case
    inf = pulse_cases("sine", amplitudes=[0.6 * 9.81], frequencies=[2.0], geometries=[(0.3, 0.6)], t_end=2.0)[0]
    old = {k: inf[k] for k in CASE_FIELDS if k not in ("case_id", "mu")}
    assert inf["mu"] == math.inf and inf["case_id"] == case_id(old)
    slide = pulse_cases("sine", amplitudes=[0.6 * 9.81], frequencies=[2.0], geometries=[(0.3, 0.6)], t_end=2.0,
                        mu=0.3)[0]
    assert slide["case_id"] != inf["case_id"]
    row = run_case(slide)
    assert not row["error"] and row["max_abs_slip"] > 1e-3 and row["friction_demand"] == 0.3
    assert row["max_abs_phi"] == 0.0 and not row["overturned"]
    row = run_case(inf)
    assert not row["error"] and row["max_abs_slip"] == 0.0 and 0.3 < row["friction_demand"] < 0.6


def test_cases_run_as_simulate_gives_them():
    """Each row of a case is what simulate gives for the same scene (max |phi|, impact count)."""
    cases = pulse_cases("sine", amplitude_ratios=[1.5, 6.0], frequency_ratios=[2.0, 10.0])
    rows = [run_case(c) for c in cases]
    for c, row in zip(cases, rows):
        assert row["error"] == ""
        r = simulate(RigidBlock(b=0.2, h=1.0), SinePulse(c["A"], c["omega_p"]), c["t_end"],
                     tolerance=c["tolerance"], output_interval=c["output_interval"])
        assert row["max_abs_phi"] == float(np.max(np.abs(r.phi))) and row["impacts"] == int(r.impacts[-1])


def test_models_are_shared_between_cases_and_bad_ones_still_refused():
    """The immutable model of a (model, b, h, e_N, mu) of floats is built once per process; a bad value is
    still refused with its message (and not cached), a value of another type is not shared."""
    from rocking_model.ensemble import case_model

    c = pulse_cases("sine", amplitude_ratios=[2.0], frequency_ratios=[4.0])[0]
    assert case_model(c) is case_model(dict(c))
    assert case_model(dict(c, b=1)) is not case_model(c) and case_model(dict(c, b=1)).b == 1
    for _ in range(2):
        row = run_case(dict(c, case_id="bad", b=-0.2))
        assert "b = -0.2 is out of range" in row["error"], row["error"]


def test_default_batches_are_a_few_per_worker():
    """Few large tasks by default (a Dask round trip costs more than a compiled case): about 4 per worker,
    at least one case each."""
    from rocking_model.ensemble import MAX_BATCH, TASKS_PER_WORKER, default_batch_size

    assert default_batch_size(2000, 2) == 2000 // (2 * TASKS_PER_WORKER)
    assert default_batch_size(3, 2) == 1 and default_batch_size(1, 8) == 1
    assert default_batch_size(10 ** 7, 1) == MAX_BATCH
    n, w = 1001, 2
    size = default_batch_size(n, w)
    assert math.ceil(n / size) <= TASKS_PER_WORKER * w


# --------------------------------------------------------------------------------------------- vertical
#: a result file written by the code before the vertical fields existed (commit d11cb94, rocking_model.ensemble:
#: run_ensemble(_BEFORE_VERTICAL_CASES(), out, workers=0)); flexible pulse cases given in m/s2 and Hz, so that
#: their ids hold no libm round-off (tan, atan2) and are the same on every machine
BEFORE_VERTICAL = Path(__file__).resolve().parent / "data" / "ensemble_before_vertical.csv"


def _before_vertical_cases():
    kw = dict(model="flexible", geometries=[(0.25, 1.5)], t_end=0.5)
    return pulse_cases("sine", amplitudes=[2.0, 6.0], frequencies=[1.0, 2.5], **kw) + \
        pulse_cases("rectangular", amplitudes=[4.0], frequencies=[2.0], mu=0.5, **kw)


#: the case fields before the vertical ones existed and their id (a copy of that version's `case_id`)
_OLD_CASE_FIELDS = ("case_id", "model", "b", "h", "e_N", "mu", "motion", "A", "omega_p", "a_ratio", "w_ratio",
                    "record", "units", "scale", "scheme", "t_end", "output_interval", "tolerance", "dt_max")


def _old_case_id(case):
    import hashlib
    import json
    key = {k: case.get(k) for k in _OLD_CASE_FIELDS if k != "case_id"}
    if key.get("mu") in (None, math.inf):
        del key["mu"]
    return hashlib.sha1(json.dumps(key, sort_keys=True, default=repr).encode()).hexdigest()[:16]


def test_cases_without_vertical_keep_their_ids(tmp_path):
    """ag_v_scale = 0 (the default) leaves the id of every kind of case as it was before the vertical fields;
    a vertical component, or another vertical record, gives another id."""
    from rocking_model.records import synthetic_record, write_at2
    t, a = synthetic_record(duration=2.0, seed=11)
    p = write_at2(tmp_path / "s.AT2", t, a)
    cases = _grid(mu=0.4) + _grid(geometries=[(0.3, 1.2)], schemes=["moreau_jean"], dt_max=1e-3) + \
        record_cases([str(p), "synthetic:5"], scales=[0.5, 1.0], t_end=2.0) + _before_vertical_cases()
    for c in cases:
        assert c["ag_v_scale"] == 0.0 and c["vertical"] == ""
        assert c["case_id"] == _old_case_id(c)
    v = record_cases([str(p)], t_end=2.0, ag_v_scales=[0.0, 0.5, -0.5])
    assert v[0]["case_id"] == _old_case_id(v[0]) and len({c["case_id"] for c in v}) == 3
    w = record_cases([str(p)], t_end=2.0, vertical=[str(p)])
    assert w[0]["ag_v_scale"] == 1.0 and w[0]["vertical"] == str(p.resolve())     # default 1 with a vertical
    assert w[0]["case_id"] not in {c["case_id"] for c in v}
    assert pulse_cases("sine", amplitude_ratios=[2.0], frequency_ratios=[3.0], ag_v_scales=[0.3])[0]["case_id"] \
        != _grid()[0]["case_id"]


def test_result_file_written_before_vertical_resumes_with_zero_new_cases(tmp_path):
    """A CSV output written by the previous version (no vertical columns) resumes: today's cases have its ids,
    nothing runs again, its header and rows gain the vertical columns (its cells otherwise unchanged, one
    RepairWarning) and a vertical case runs on top of it; the same for Parquet parts of the old schema."""
    import shutil

    cases = _before_vertical_cases()
    old_text = BEFORE_VERTICAL.read_text()
    old_ids = [line.split(",")[0] for line in old_text.splitlines()[1:]]
    assert [c["case_id"] for c in cases] == old_ids
    out = tmp_path / "old.csv"
    shutil.copy(BEFORE_VERTICAL, out)
    with pytest.warns(RepairWarning, match="params, vertical, ag_v_scale, im, im_level, max_tendon_force existed: added"):
        s = run_ensemble(cases, out, workers=0, progress=False)
    assert s["n_run"] == 0 and s["n_skipped"] == len(cases)
    lines = out.read_text().splitlines()
    assert lines[0] == ",".join(FIELDS)
    i, j = FIELDS.index("vertical"), FIELDS.index("params")
    m = [FIELDS.index(k) for k in ("im", "im_level", "max_tendon_force")]
    for old, new in zip(old_text.splitlines()[1:], lines[1:]):
        cells = new.split(",")
        assert cells[i:i + 2] == ["", "0.0"] and cells[j] == "" and [cells[k] for k in m] == ["", "nan", "nan"]
        assert [c for k, c in enumerate(cells) if k not in (i, i + 1, j, *m)] == old.split(",")
    rows = {r["case_id"]: r for r in read_results(out)}
    assert set(rows) == set(old_ids) and all(r["ag_v_scale"] == 0.0 for r in rows.values())
    more = pulse_cases("sine", amplitudes=[2.0], frequencies=[1.0], model="flexible", geometries=[(0.25, 1.5)],
                       t_end=0.5, ag_v_scales=[0.0, 0.5])
    s = run_ensemble(cases + more, out, workers=0, progress=False)
    assert s["n_run"] == 1 and s["n_errors"] == 0
    assert {r["case_id"]: r for r in read_results(out)}[more[1]["case_id"]]["ag_v_scale"] == 0.5
    # Parquet parts of the old schema: read with the no-vertical defaults, resumed with zero new cases
    pa = pytest.importorskip("pyarrow")
    import pyarrow.parquet as pq
    from rocking_model.ensemble import _parse
    pdir = tmp_path / "old.parquet"
    pdir.mkdir()
    old_rows = [_parse(r) for r in read_results(BEFORE_VERTICAL)]
    schema = pa.schema([(k, pa.string() if k in ("case_id", "model", "motion", "record", "units", "scheme", "error")
                         else pa.bool_() if k == "overturned" else pa.int64() if k == "impacts" else pa.float64())
                        for k in old_text.splitlines()[0].split(",")])
    pq.write_table(pa.Table.from_pylist([{k: r[k] for k in schema.names} for r in old_rows], schema=schema),
                   pdir / "part-00000-old.parquet")
    s = run_ensemble(cases, pdir, workers=0, progress=False)
    assert s["n_run"] == 0 and s["n_skipped"] == len(cases)
    assert all(r["vertical"] == "" and r["ag_v_scale"] == 0.0 for r in read_results(pdir))


def test_vertical_case_motion_and_rows(tmp_path):
    """ag_v of a case is ag_v_scale x the record's vertical component (scaled with the record), x the horizontal
    record without one, x the pulse; ag_v_scale = 0 gives the horizontal motion of before (a record's third
    column ignored); a row equals the direct simulation of its motion; a bad ag_v_scale names the field."""
    from rocking_model.ensemble import case_model, case_motion
    from rocking_model.records import synthetic_record, write_csv
    t, a = synthetic_record(duration=3.0, seed=11)
    _, v = synthetic_record(duration=3.0, seed=12)
    p = write_csv(tmp_path / "three.csv", t, a, ag_v=v)
    h = write_csv(tmp_path / "h.csv", t, a)
    c3 = record_cases([str(p)], scales=[2.0], ag_v_scales=[0.0, 0.5], t_end=3.0)
    m0, m1 = case_motion(c3[0]), case_motion(c3[1])
    assert m0.vertical is None and np.array_equal(m0.ag, 2.0 * a)
    assert np.array_equal(m1.ag, 2.0 * a) and np.allclose(m1.vertical.ag, 0.5 * 2.0 * v, rtol=1e-15, atol=0)
    assert record_cases([str(p)], t_end=3.0)[0]["ag_v_scale"] == 1.0
    c2 = record_cases([str(h)], scales=[2.0], ag_v_scales=[-0.25], t_end=3.0)[0]
    m2 = case_motion(c2)
    assert np.array_equal(m2.ag, 2.0 * a) and np.allclose(m2.vertical.ag, -0.5 * a, rtol=1e-15, atol=0)
    cv = record_cases([str(h)], vertical=[str(p.with_name("h.csv"))], ag_v_scales=[1.0], t_end=3.0)[0]
    assert np.array_equal(case_motion(cv).vertical.ag, case_motion(cv).ag)
    pc = pulse_cases("sine", amplitude_ratios=[2.0], frequency_ratios=[3.0], ag_v_scales=[0.4])[0]
    mp = case_motion(pc)
    assert mp.vertical is not None and mp.vertical(0.1) == pytest.approx(0.4 * mp(0.1), rel=1e-15)
    row = run_case(c3[1])
    assert row["error"] == "" and row["ag_v_scale"] == 0.5
    res = simulate(case_model(c3[1]), case_motion(c3[1]), 3.0)
    assert row["max_abs_phi"] == float(np.max(np.abs(res.phi))) and row["impacts"] == int(res.impacts[-1])
    with pytest.raises(ValueError, match=r"ag_v_scale = 11 is out of range; allowed range \[-10, 10\]"):
        record_cases([str(p)], ag_v_scales=[11.0])
    with pytest.raises(ValueError, match=r"ag_v_scale = nan is not finite"):
        pulse_cases("sine", amplitude_ratios=[2.0], frequency_ratios=[3.0], ag_v_scales=[math.nan])
    with pytest.raises(ValueError, match="give one vertical record per record"):
        record_cases([str(p), str(h)], vertical=[str(h)])
    assert "ag_v_scale = -20 is out of range" in run_case(dict(c3[1], ag_v_scale=-20.0, case_id=""))["error"]


def test_model_parameters_of_any_model_as_the_case_field_params(tmp_path):
    """The models' other declared parameters (here the post-tensioned block's m, P0, k_t) are the case field
    ``params`` (a JSON object; "" without any, the case ids of earlier versions): the post-tensioned block, a
    rigid block, takes the dimensionless ratios of its rigid block, and its row equals a direct simulation;
    an undeclared parameter, one of another model or a value out of range is refused by name."""
    import json

    from rocking_model.ensemble import case_model, is_rigid_block
    from rocking_model.models import PostTensionedBlock

    assert is_rigid_block("rigid") and is_rigid_block("post_tensioned") and not is_rigid_block("flexible")
    kw = dict(geometries=[(0.3, 1.5)], model="post_tensioned", t_end=3.0)
    cases = pulse_cases("sine", amplitude_ratios=[6.0], frequency_ratios=[3.0],
                        params={"m": 1000, "P0": 2e4, "k_t": 2e6}, **kw)
    (c,) = cases
    assert json.loads(c["params"]) == {"P0": 2e4, "k_t": 2e6, "m": 1000.0}
    alpha, p = math.atan(0.3 / 1.5), math.sqrt(3 * 9.81 / (4 * math.hypot(0.3, 1.5)))
    assert c["A"] == pytest.approx(6.0 * 9.81 * math.tan(alpha)) and c["omega_p"] == pytest.approx(3 * p)
    model = case_model(c)
    assert model == PostTensionedBlock(b=0.3, h=1.5, m=1000.0, P0=2e4, k_t=2e6)
    row = run_case(c)
    ref = simulate(model, SinePulse(c["A"], c["omega_p"]), 3.0, output_interval=0.01)
    assert not row["error"] and row["max_abs_phi"] == float(np.max(np.abs(ref.phi))) > 0.05
    assert row["alpha"] == pytest.approx(alpha) and row["max_phi_over_alpha"] == pytest.approx(row["max_abs_phi"] / alpha)
    # no params: the model's defaults, and the case id of a case without the field
    plain = pulse_cases("sine", amplitude_ratios=[6.0], frequency_ratios=[3.0], **kw)[0]
    assert plain["params"] == "" and plain["case_id"] == _old_case_id(plain) != c["case_id"]
    for params, msg in (({"P0": 1.0}, "'P0' is not a parameter of the rigid model"),
                        ({"b": 0.3}, "b is a case field of its own"),
                        ({"EI": 1e5}, "'EI' is not a parameter of the rigid model")):
        with pytest.raises(ValueError, match=msg):
            pulse_cases("sine", amplitude_ratios=[1.0], frequency_ratios=[1.0], params=params)
    with pytest.raises(ValueError, match="P0 = -1 is out of range"):
        pulse_cases("sine", amplitude_ratios=[1.0], frequency_ratios=[1.0], params={"P0": -1}, **kw)
    bad = dict(c, params='{"EI": 1.0}', case_id="")
    assert "'EI' is not a parameter of the post_tensioned model" in run_case(bad)["error"]


def test_result_file_written_before_params_resumes_with_zero_new_cases(tmp_path):
    """A CSV output of the version before the params field (its header without it) resumes: nothing runs
    again, the column is added empty (one RepairWarning), and a case with params runs on top of it."""
    import csv

    cases = _grid(geometries=[(0.3, 1.2)], t_end=1.0)[:2]
    out = tmp_path / "old.csv"
    run_ensemble(cases, out, workers=0, progress=False)
    old = [r for r in csv.reader(out.open(newline=""))]
    # (and without the columns added after it)
    drop = [old[0].index(k) for k in ("params", "im", "im_level", "max_tendon_force")]
    with out.open("w", newline="") as f:
        csv.writer(f, lineterminator="\r\n").writerows([[c for k, c in enumerate(r) if k not in drop] for r in old])
    with pytest.warns(RepairWarning, match="before the columns params, im, im_level, max_tendon_force existed: added"):
        s = run_ensemble(cases, out, workers=0, progress=False)
    assert s["n_run"] == 0 and s["n_skipped"] == 2
    assert [r for r in csv.reader(out.open(newline=""))] == old
    more = pulse_cases("sine", amplitude_ratios=[3.0], frequency_ratios=[2.0], geometries=[(0.3, 1.2)], t_end=1.0,
                       params={"m": 5.0})
    assert run_ensemble(cases + more, out, workers=0, progress=False)["n_run"] == 1
    assert {r["case_id"]: r["params"] for r in read_results(out)}[more[0]["case_id"]] == '{"m":5.0}'
