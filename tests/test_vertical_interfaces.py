"""The vertical ground acceleration ag_v at the interfaces: records (a third CSV column, a second AT2 file),
the GroundMotionSource FMU's output ag_v, the CLI's --vertical / --vertical-scale, the ensembles' case fields
ag_v_scale and vertical (old result files resume), and the three-component example."""
from __future__ import annotations

import math

import numpy as np
import pytest

from rocking_model.records import (G_N, Record, combine, load_motion, read_at2, read_csv, read_record,
                                   synthetic_record, write_at2, write_csv)


def _at2(path, dt, values, units="G"):
    """A minimal PEER AT2 file with ``values`` (in g) every ``dt`` [s]."""
    lines = ["TITLE", "EVENT", f"ACCELERATION TIME SERIES IN UNITS OF {units}",
             f"NPTS= {len(values):6d}, DT= {dt:.4f} SEC"]
    lines += [" ".join(f"{v:.7E}" for v in values[k:k + 5]) for k in range(0, len(values), 5)]
    path.write_text("\n".join(lines) + "\n")
    return path


# ------------------------------------------------------------------------------------------- records: CSV
def test_three_column_csv_is_a_record_with_a_vertical_component(tmp_path):
    """The third column is ag_v in the units of the second; a two-column file has no vertical component."""
    p = tmp_path / "three.csv"
    p.write_text("time [s],ag [cm/s2],ag_v [cm/s2]\n0,10,-5\n0.01,20,7\n0.02,-30,0\n")
    r = read_csv(p)
    assert isinstance(r.vertical, Record) and r.units == "cm/s2" and r.vertical.units == "cm/s2"
    assert np.array_equal(r.ag_v, np.array([-5.0, 7.0, 0.0]) * 0.01)
    assert np.array_equal(r.ag, np.array([10.0, 20.0, -30.0]) * 0.01)
    assert np.array_equal(r.vertical.t, r.t) and r.pga_v == pytest.approx(0.07)
    assert r(0.005) == pytest.approx(0.15) and r.vertical(0.005) == pytest.approx(0.01)
    q = tmp_path / "two.csv"
    q.write_text("time [s],ag [g]\n0,0.1\n0.01,0.2\n")
    two = read_csv(q)
    assert two.vertical is None and two.ag_v is None and two.pga_v == 0.0 and two.horizontal is two
    # units from a comment or given apply to both columns
    c = tmp_path / "c.txt"
    c.write_text("# units: g\n0 0.1 0.05\n0.01 0.2 -0.1\n")
    assert np.allclose(read_record(c).ag_v, [0.05 * G_N, -0.1 * G_N], rtol=1e-15)
    n = tmp_path / "n.csv"
    n.write_text("0,1,2\n0.5,3,4\n")
    assert np.array_equal(read_csv(n, units="m/s2").ag_v, [2.0, 4.0])
    assert np.array_equal(read_csv(n, default_units="mm/s2").ag_v, [0.002, 0.004])


@pytest.mark.parametrize("text, match", [
    ("time [s],ag [g],ag_v [cm/s2]\n0,1,2\n0.1,2,3\n", r"line 1: the third column \(ag_v\) states units 'cm/s2'"),
    ("t [s],a [g],v [g]\n0,1,2\n0.1,2\n", r"line 3: 2 columns, expected 3 \(as the rows before it\)"),
    ("t [s],a [g]\n0,1,2,3\n0.1,2,3,4\n", r"line 2: 4 columns, expected 2 \(time \[s\], acceleration\) or 3"),
    ("t [s],a [g],v [g]\n0,1,2\n0.1,2,inf\n", r"line 3: values must be finite"),
])
def test_malformed_three_column_csv(tmp_path, text, match):
    p = tmp_path / "bad3.csv"
    p.write_text(text)
    with pytest.raises(ValueError, match=match) as exc:
        read_csv(p)
    assert "bad3.csv" in str(exc.value)


def test_csv_with_vertical_round_trip_is_exact(tmp_path):
    t, a = synthetic_record(duration=1.0, seed=3)
    _, v = synthetic_record(duration=1.0, seed=4)
    r = read_csv(write_csv(tmp_path / "r.csv", t, a, ag_v=v))
    assert np.array_equal(r.t, t) and np.array_equal(r.ag, a) and np.array_equal(r.ag_v, v)
    assert (tmp_path / "r.csv").read_text().splitlines()[0] == "time [s],ag [m/s2],ag_v [m/s2]"
    back = read_csv(write_csv(tmp_path / "g.csv", r, units="g"))            # a Record: its vertical too
    assert np.allclose(back.ag_v, v, rtol=1e-15, atol=0.0)
    assert (tmp_path / "g.csv").read_text().splitlines()[0] == "time [s],ag [g],ag_v [g]"
    with pytest.raises(ValueError, match="ag_v must have the shape of ag"):
        write_csv(tmp_path / "x.csv", t, a, ag_v=v[:-1])


# ------------------------------------------------------------------------------------------- records: AT2 pairs
def test_at2_pair_reads_the_vertical_from_the_second_file(tmp_path):
    h = _at2(tmp_path / "H.AT2", 0.005, [0.01, -0.02, 0.3, -0.004, 0.0005, 0.0, -0.01])
    v = _at2(tmp_path / "V.AT2", 0.005, [0.02, 0.01, -0.1, 0.0, 0.0, 0.005, 0.001])
    r = read_at2(h, vertical=v)
    assert np.array_equal(r.t, np.arange(7) * 0.005)
    assert np.array_equal(r.ag, read_at2(h).ag) and np.array_equal(r.ag_v, read_at2(v).ag)
    assert r.name == "H" and r.vertical.name == "V" and r.vertical.source == str(v)
    assert np.array_equal(read_record(h, vertical=v).ag_v, r.ag_v)
    assert np.array_equal(load_motion(str(h), vertical=str(v)).ag_v, r.ag_v)
    assert load_motion(str(h), vertical="").vertical is None
    # the units override applies to both files
    assert np.allclose(read_at2(h, units="cm/s2", vertical=v).ag_v, np.array(read_at2(v).ag) / G_N * 0.01,
                       rtol=1e-14)


def test_at2_pair_of_unequal_lengths_is_padded_with_zeros(tmp_path):
    """The shorter component gets zeros up to the longer one's end, whichever it is; the horizontal's own
    samples are unchanged."""
    h = _at2(tmp_path / "H.AT2", 0.01, [0.1, 0.2, 0.3, 0.4, 0.5, 0.6])
    v = _at2(tmp_path / "V.AT2", 0.01, [0.05, -0.05, 0.02])
    r = read_at2(h, vertical=v)
    assert r.t.size == 6 and np.array_equal(r.t, read_at2(h).t)
    assert np.array_equal(r.ag_v[3:], [0.0, 0.0, 0.0]) and np.array_equal(r.ag_v[:3], read_at2(v).ag)
    s = read_at2(v, vertical=h)                          # the vertical longer: the horizontal padded
    assert np.array_equal(s.t, np.arange(6) * 0.01)
    assert np.array_equal(s.ag[3:], [0.0, 0.0, 0.0]) and np.array_equal(s.ag_v, read_at2(h).ag)
    assert s.support == (0.0, 0.05)


def test_at2_pair_with_different_time_steps_is_refused_naming_the_file(tmp_path):
    h = _at2(tmp_path / "H.AT2", 0.005, [0.1, 0.2, 0.3])
    v = _at2(tmp_path / "V10.AT2", 0.01, [0.1, 0.2, 0.3])
    with pytest.raises(ValueError, match=r"V10\.AT2: DT = 0\.01 s, but the horizontal component .*H\.AT2\) has "
                                         r"DT = 0\.005 s"):
        read_at2(h, vertical=v)
    # CSV files: the sample times must agree, and both must start together
    a = tmp_path / "a.csv"
    a.write_text("time [s],ag [g]\n0,0.1\n0.01,0.2\n0.03,0.1\n")
    b = tmp_path / "b.csv"
    b.write_text("time [s],ag_v [g]\n0,0.1\n0.01,0.2\n0.02,0.1\n")
    with pytest.raises(ValueError, match=r"b\.csv: sample 3 is at t = 0\.02 s, but the horizontal"):
        read_csv(a, vertical=b)
    c = tmp_path / "c.csv"
    c.write_text("time [s],ag_v [g]\n0.5,0.1\n0.51,0.2\n0.53,0.1\n")
    with pytest.raises(ValueError, match=r"c\.csv: starts at t = 0\.5 s, but the horizontal component"):
        read_record(a, vertical=c)
    same = read_record(a, vertical=tmp_path / "a.csv")
    assert np.array_equal(same.ag_v, same.ag)
    # a vertical file that has two components itself, or a three-column record with a second file
    three = tmp_path / "three.csv"
    three.write_text("time [s],ag [g],ag_v [g]\n0,0.1,0\n0.01,0.2,0\n0.03,0.1,0\n")
    with pytest.raises(ValueError, match=r"three\.csv: the vertical record has two components"):
        read_record(a, vertical=three)
    with pytest.raises(ValueError, match=r"three\.csv: the record already has a vertical component"):
        read_record(three, vertical=a)


def test_at2_writer_writes_the_vertical_to_a_second_file(tmp_path):
    t, a = synthetic_record(duration=1.0, seed=3)
    _, v = synthetic_record(duration=1.0, seed=4)
    rec = Record(t, a, "pair", vertical=v)
    with pytest.raises(ValueError, match=r"needs vertical=<second AT2 file>"):
        write_at2(tmp_path / "x.AT2", rec)
    with pytest.raises(ValueError, match="there is no vertical component"):
        write_at2(tmp_path / "x.AT2", rec.horizontal, vertical=tmp_path / "y.AT2")
    p = write_at2(tmp_path / "H.AT2", rec, vertical=tmp_path / "UP.AT2")
    back = read_at2(p, vertical=tmp_path / "UP.AT2")
    assert np.array_equal(back.t, t) and np.allclose(back.ag, a, rtol=1e-15, atol=0.0)
    assert np.allclose(back.ag_v, v, rtol=1e-15, atol=0.0)
    q = write_at2(tmp_path / "H2.AT2", t, a, "cm/s2", vertical=tmp_path / "UP2.AT2", ag_v=v)
    assert "CM/S2" in (tmp_path / "UP2.AT2").read_text().splitlines()[2]
    assert np.allclose(read_at2(q, vertical=tmp_path / "UP2.AT2").ag_v, v, rtol=1e-14, atol=0.0)


def test_record_operations_act_on_both_components():
    t = np.arange(5) * 0.1
    rec = Record(t, [0.0, 1.0, -2.0, 0.5, 0.0], "r", vertical=[0.0, 0.5, 0.5, -1.0, 0.0])
    s = rec.scaled(2.0)
    assert np.array_equal(s.ag, 2.0 * rec.ag) and np.array_equal(s.ag_v, 2.0 * rec.ag_v)
    sv = rec.scaled_vertical(-0.5)
    assert np.array_equal(sv.ag, rec.ag) and np.array_equal(sv.ag_v, -0.5 * rec.ag_v)
    with pytest.raises(ValueError, match="vertical_scale: the record 'h' has no vertical component"):
        Record(t, rec.ag, "h").scaled_vertical(2.0)
    f = rec.resampled(0.05)
    assert f.t.size == 9 and np.allclose(f.ag_v[1::2], 0.5 * (rec.ag_v[:-1] + rec.ag_v[1:]))
    assert np.allclose(f.ag[::2], rec.ag)
    h = rec.horizontal
    assert h.vertical is None and np.array_equal(h.ag, rec.ag) and h.name == "r"
    assert rec.peak_bound == 2.0 and rec.pga_v == 1.0           # the horizontal's peak; the vertical's apart
    assert "PGA_v" in repr(rec) and "PGA_v" not in repr(h)
    w = h.with_vertical(Record(t[:3], [1.0, 2.0, 3.0], "v"))      # aligned by combine: zeros after its end
    assert np.array_equal(w.ag_v, [1.0, 2.0, 3.0, 0.0, 0.0])
    with pytest.raises(ValueError, match="sampled at the record's times"):
        Record(t, rec.ag, vertical=Record(t + 0.01, rec.ag))
    with pytest.raises(ValueError, match="must be finite"):
        Record(t, rec.ag, vertical=[0.0, math.nan, 0.0, 0.0, 0.0])
    assert combine(h, Record(t, rec.ag_v, "v")).vertical.name == "v"


# ------------------------------------------------------------------------------------------- the example
ROOT = __import__("pathlib").Path(__file__).resolve().parents[1]


def test_shipped_vertical_record_is_the_synthetic_record_it_says():
    """examples/records/synthetic_2017-UP.AT2 is what examples/records/make_synthetic_record.py writes: the
    vertical component synthetic_record(seed=2018, pga_g=0.3, f_g=5.0), in g with PEER's 7 digits, on the
    horizontal record's time step, its header saying it is synthetic and vertical."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("_make_synthetic_record",
                                                  ROOT / "examples" / "records" / "make_synthetic_record.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    rec = read_at2(mod.PATH, vertical=mod.VERTICAL_PATH)
    t, v = synthetic_record(**mod.VERTICAL)
    assert mod.VERTICAL_PATH.name == "synthetic_2017-UP.AT2" and mod.VERTICAL == dict(seed=2018, pga_g=0.3, f_g=5.0)
    assert np.array_equal(rec.t, t) and rec.vertical.t.size == 3001
    assert np.allclose(rec.ag_v, v, rtol=0, atol=1e-6 * np.max(np.abs(v)))
    assert rec.pga_v == pytest.approx(0.3 * 9.81, rel=1e-6)
    header = " ".join(rec.vertical.header).lower()
    assert "synthetic" in header and "vertical" in header


def test_three_component_example_runs_and_plots_the_difference(tmp_path):
    """examples/three_component.py (shortened to 8 s) runs both models with and without the vertical component
    and writes its PNG; the run without it is the plain horizontal record's run, bit for bit; the vertical
    component changes the rocking of both (here by far more than round-off: 0.3 g vertical in the strong
    phase)."""
    import importlib.util

    from rocking_model import simulate

    spec = importlib.util.spec_from_file_location("_three_component", ROOT / "examples" / "three_component.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    out = tmp_path / "three.png"
    runs = mod.run(t_end=8.0, out=out)
    png = out.read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 30000
    assert len(runs) == 2
    horizontal = read_at2(mod.RECORD)
    for name, (h_only, both) in runs.items():
        assert np.all(np.isfinite(both.phi)) and not both.overturned[-1]
        diff = np.max(np.abs(both.phi - h_only.phi))
        assert diff > 1e-3 * max(np.max(np.abs(h_only.phi)), 1e-3) and diff > 1e-4, name
        model = mod.RigidBlock(b=0.4, h=2.0) if name.startswith("rigid") else mod.FlexibleOscillator()
        ref = simulate(model, horizontal, 8.0, output_interval=0.01)
        assert np.array_equal(ref.phi, h_only.phi), name
    assert mod.main(["--t-end", "2", "--out", str(tmp_path / "short.png")]) == 0
    assert (tmp_path / "short.png").is_file()
    assert mod.main(["--t-end", "2", "--out", str(tmp_path / "folder")]) == 0   # a folder: the fixed name
    assert (tmp_path / "folder" / "three_component.png").is_file()


# ------------------------------------------------------------------------------------------- GroundMotionSource
def _source(built_fmus, **start_values):
    from rocking_model.fmi import run_fmu
    return run_fmu(built_fmus["GroundMotionSource"], stop_time=1.0, output_interval=0.01, start_values=start_values)


def test_source_fmu_declares_ag_v(built_fmus):
    """The output ag_v [m/s2] and the parameters vertical, vertical_scale are declared (fmpy validates the FMU);
    the variables of before keep their value references."""
    fmpy = pytest.importorskip("fmpy")
    from fmpy.validation import validate_fmu
    path = built_fmus["GroundMotionSource"]
    assert validate_fmu(str(path)) == []
    md = {v.name: v for v in fmpy.read_model_description(str(path)).modelVariables}
    assert md["ag_v"].causality == "output" and md["ag_v"].unit == "m/s2" and md["ag_v"].type == "Real"
    assert md["vertical"].type == "String" and float(md["vertical_scale"].start) == 1.0
    assert md["ag_v"].valueReference > md["ag"].valueReference


def test_source_fmu_outputs_the_vertical_component_of_a_record(built_fmus, tmp_path):
    """ag_v is the record's third CSV column, or its second file, times scale and vertical_scale, at the
    communication points (linear between the samples, as ag); 0 for a motion without one."""
    t = np.round(np.arange(0.0, 1.0 + 1e-9, 0.02), 12)
    a = 2.0 * np.sin(2 * np.pi * t)
    v = 1.5 * np.cos(3 * np.pi * t)
    three = write_csv(tmp_path / "three.csv", t, a, units="cm/s2", ag_v=v)          # written in cm/s2
    res = _source(built_fmus, motion=1, record=str(three), scale=2.0, vertical_scale=-0.5)
    np.testing.assert_allclose(res["ag"], 2.0 * np.interp(res["time"], t, a), rtol=0, atol=1e-12)
    np.testing.assert_allclose(res["ag_v"], -1.0 * np.interp(res["time"], t, v), rtol=0, atol=1e-12)
    assert np.abs(res["ag_v"]).max() > 1.4
    h = write_at2(tmp_path / "H.AT2", t, a)
    up = write_at2(tmp_path / "UP.AT2", t, v)
    pair = _source(built_fmus, motion=1, record=str(h), vertical=str(up))
    np.testing.assert_allclose(pair["ag_v"], np.interp(pair["time"], t, v), rtol=0, atol=1e-12)
    np.testing.assert_allclose(pair["ag"], np.interp(pair["time"], t, a), rtol=0, atol=1e-12)
    for plain in (_source(built_fmus, motion=1, record=str(h)), _source(built_fmus, A=3.0)):
        assert np.all(plain["ag_v"] == 0.0) and np.any(plain["ag"] != 0.0)


@pytest.mark.parametrize("start_values, fragment", [
    (dict(motion=0, vertical="UP.AT2"), "vertical = 'UP.AT2': a vertical record needs motion = 1"),
    (dict(motion=1, vertical_scale=11.0), "vertical_scale = 11 is out of range; allowed range [-10, 10]"),
    (dict(motion=1, vertical="V10.AT2"), "V10.AT2: DT = 0.01 s, but the horizontal component"),
    (dict(motion=1, vertical="missing.AT2"), "no such file"),
    (dict(motion=1, vertical="UP.AT2", scale=400.0),
     "ag_v: the ground motion's peak |ag_v| = 1200 m/s2 is out of range"),
])
def test_source_fmu_refuses_a_bad_vertical_component(built_fmus, tmp_path, start_values, fragment):
    """The vertical component gets the checks of ag: a file of another time step, a missing file, a scale out
    of range and values beyond AG_MAX (1000 m/s2) are errors naming the parameter, the file or ag_v."""
    from rocking_model.fmi import FMUError
    t = np.round(np.arange(0.0, 1.0 + 1e-9, 0.005), 12)
    write_at2(tmp_path / "H.AT2", t, np.sin(t))
    write_at2(tmp_path / "UP.AT2", t, 3.0 * np.ones_like(t))
    write_at2(tmp_path / "V10.AT2", t[::2], np.sin(t[::2]))
    values = dict(start_values, record=str(tmp_path / "H.AT2"))
    if "vertical" in values and values.get("motion") == 1:
        values["vertical"] = str(tmp_path / values["vertical"])
    with pytest.raises(FMUError) as exc:
        _source(built_fmus, **values)
    assert fragment in str(exc.value)
