"""Ground motions and records: pulses against closed forms, breakpoints, scaling, resampling, AT2/CSV."""
import math

import numpy as np
import pytest
from scipy.integrate import quad

from rocking_model import RigidBlock, SampledMotion, Simulator, SinePulse
from rocking_model.ground_motion import CosinePulse, RectangularPulse, RickerPulse
from rocking_model.records import (G_N, Record, load_motion, read_at2, read_csv, read_record, synthetic_record,
                                   unit_factor, write_at2, write_csv)


# ------------------------------------------------------------------------------------------- pulses
def test_pulse_values_and_integrals():
    A, w, t0 = 2.5, 2 * math.pi * 1.5, 0.3
    T = 2 * math.pi / w
    c = CosinePulse(A, w, t0)
    assert c(t0 + 0.25 * T) == pytest.approx(0.0, abs=1e-12)
    assert c(t0 + 0.5 * T) == pytest.approx(-A)
    assert c(t0 - 1e-9) == 0.0 and c(t0 + T + 1e-9) == 0.0
    # one full cosine: no residual ground velocity; one sine: residual velocity zero, area of half = 2A/w
    assert quad(c, t0, t0 + T, points=[t0 + T / 2])[0] == pytest.approx(0.0, abs=1e-10)
    s = SinePulse(A, w, t0)
    assert quad(s, t0, t0 + T / 2)[0] == pytest.approx(2 * A / w, rel=1e-10)
    r = RickerPulse(A, w)
    assert r.t_c == pytest.approx(1.5 * T)
    assert r(r.t_c) == A
    assert r(r.t_c + math.sqrt(2) / w) == pytest.approx(0.0, abs=1e-14)   # zeros at tau = sqrt(2)/w
    assert abs(r(0.0)) < 1e-8 * A
    assert quad(r, r.t_c - 3 * T, r.t_c + 3 * T, limit=200)[0] == pytest.approx(0.0, abs=1e-10)
    assert r.next_breakpoint(0.0) == math.inf
    p = RectangularPulse(A, 0.4, t0)
    assert p(t0) == 0.0 and p(t0 + 1e-6) == A and p(t0 + 0.4) == A and p(t0 + 0.4 + 1e-6) == 0.0
    assert quad(p, 0, 2, points=[t0, t0 + 0.4])[0] == pytest.approx(A * 0.4, rel=1e-9)


def test_breakpoints():
    s = SinePulse(1.0, 2 * math.pi, 0.5)
    assert [s.next_breakpoint(t) for t in (0.0, 0.5, 1.2, 1.5)] == [0.5, 1.5, 1.5, math.inf]
    p = RectangularPulse(1.0, 0.4, 0.5)
    bp = [0.0]
    while math.isfinite(bp[-1]):
        bp.append(p.next_breakpoint(bp[-1]))
    # each jump: the jump time and a sliver after it (see ground_motion._jump_breakpoints)
    assert bp[1] == 0.5 and bp[3] == 0.9 and 0 < bp[2] - 0.5 < 1e-9 and 0 < bp[4] - 0.9 < 1e-9
    assert bp[5] == math.inf
    m = SampledMotion([0.0, 0.1, 0.3], [0.0, 1.0, 2.0])
    assert [m.next_breakpoint(t) for t in (-1, 0.0, 0.05, 0.3)] == [0.0, 0.1, 0.1, math.inf]
    assert m(0.2) == pytest.approx(1.5) and m(0.31) == 0.0 and m(-0.01) == 0.0


def test_rectangular_pulse_matches_piecewise_constant_runs():
    """The pulse through the breakpoints gives what three runs with ag held constant give."""
    blk, A, t0, d, T = RigidBlock(0.2, 1.0), 0.3 * 9.81, 0.3, 0.4, 3.0
    ref = Simulator(blk, "event_driven", tolerance=1e-8)
    ref.advance(t0, 0.0)
    ref.advance(t0 + d, A)
    ref.advance(T, 0.0)
    sim = Simulator(blk, "event_driven", tolerance=1e-8)
    sim.advance(T, RectangularPulse(A, d, t0))
    assert ref.outputs()["impacts"] == sim.outputs()["impacts"] == 1
    # a single breakpoint per jump (a Runge-Kutta stage on the wrong side) is off by ~1e-7 here
    assert sim.outputs()["phi"] == pytest.approx(ref.outputs()["phi"], abs=4e-8)


@pytest.mark.parametrize("bad, match", [
    (lambda: CosinePulse(1.0, 0.0), r"omega_p = 0 is out of range; allowed range \(0, inf\)"),
    (lambda: RickerPulse(float("nan"), 1.0), r"A = nan is not finite"),
    (lambda: RectangularPulse(1.0, -0.1), r"duration = -0.1 is out of range"),
    (lambda: SinePulse(1.0, 1.0).scaled("x"), r"factor must be a real number"),
    (lambda: SinePulse(1.0, 1.0).resampled(0.0), r"dt = 0 is out of range"),
])
def test_pulse_validation(bad, match):
    with pytest.raises(ValueError, match=match):
        bad()


def test_scaled_and_resampled():
    s = SinePulse(2.0, 2 * math.pi, 0.5).scaled(1.5)
    assert isinstance(s, SinePulse) and s.A == 3.0 and s(0.75) == pytest.approx(3.0)
    m = SampledMotion([0.0, 0.1, 0.2], [1.0, -2.0, 4.0])
    assert np.array_equal(m.scaled(-0.5).ag, [-0.5, 1.0, -2.0])
    assert m.scaled(2).next_breakpoint(0.05) == 0.1
    r = RickerPulse(1.0, 5.0).scaled(2.0)
    assert r(r.t_c) == 2.0
    # resampling a linear interpolant on a finer grid keeps the samples and interpolates between them
    f = m.resampled(0.05)
    assert np.allclose(f.t, [0, 0.05, 0.1, 0.15, 0.2]) and np.allclose(f.ag, [1.0, -0.5, -2.0, 1.0, 4.0])
    rs = SinePulse(1.0, 2 * math.pi).resampled(0.125)
    assert rs.t[-1] == 1.0 and np.allclose(rs.ag[:3], [0, math.sqrt(0.5), 1.0])
    with pytest.raises(ValueError, match="no finite support"):
        from rocking_model.ground_motion import ConstantMotion
        ConstantMotion(1.0).resampled(0.1)


# ------------------------------------------------------------------------------------------- AT2
NEW_AT2 = """PEER NGA STRONG MOTION DATABASE RECORD
IMPERIAL VALLEY 10/15/79 2316, EL CENTRO ARRAY #6, 230
ACCELERATION TIME SERIES IN UNITS OF G
NPTS=    7, DT=   .0050 SEC
  .1000000E-01  -.2000000E-01   .3000000E+00  -.4000000E-02   .5000000E-03
  .0000000E+00 -.1234567E-01
"""
OLD_AT2 = """PEER STRONG MOTION DATABASE RECORD. PROCESSING BY PACIFIC ENGINEERING.
KOBE 01/16/95 2046, KJMA, 000
ACCELERATION TIME HISTORY IN UNITS OF G
    6    0.0100    NPTS, DT
 -.1000000E-01-.2000000E-01  .3000000E+00
  .4000000E-02  .0000000E+00  .1000000E-02
"""


def test_read_at2_new_and_old_headers(tmp_path):
    p = tmp_path / "new.AT2"
    p.write_text(NEW_AT2)
    r = read_at2(p)
    assert isinstance(r, Record) and r.name == "new" and r.t.size == 7
    assert np.array_equal(r.t, np.arange(7) * 0.005)
    assert np.array_equal(r.ag, np.array([0.01, -0.02, 0.3, -0.004, 0.0005, 0.0, -0.01234567]) * G_N)
    q = tmp_path / "old.at2"
    q.write_text(OLD_AT2)
    r = read_record(q)
    assert np.array_equal(r.t, np.arange(6) * 0.01)        # run-together numbers are split
    assert np.array_equal(r.ag, np.array([-0.01, -0.02, 0.3, 0.004, 0.0, 0.001]) * G_N)


def test_at2_round_trip_is_exact(tmp_path):
    t, a = synthetic_record(duration=3.0, seed=7)
    p = write_at2(tmp_path / "syn.AT2", t, a)
    r = read_at2(p)
    assert np.array_equal(r.t, t)
    assert np.allclose(r.ag, a, rtol=1e-15, atol=0.0)       # g <-> m/s2 conversion costs at most 1 ulp
    assert np.array_equal(r.ag, (a / G_N) * G_N)


@pytest.mark.parametrize("text, match", [
    (NEW_AT2.replace("NPTS=    7, DT=   .0050 SEC", "7 points at 0.005 s"), r"line 4: no 'NPTS="),
    (NEW_AT2.replace("-.2000000E-01", "-.2000x00E-01"), r"line 5: '-.2000x00E-01' is not a number"),
    (NEW_AT2.replace("NPTS=    7", "NPTS=    9"), r"8 samples|7 samples, header \(line 4\) says NPTS = 9"),
    (NEW_AT2.replace("DT=   .0050", "DT=   0.0"), r"line 4: DT = 0.0 is out of range"),
    ("only\ntwo lines\n", r"not a PEER AT2 file"),
])
def test_malformed_at2(tmp_path, text, match):
    p = tmp_path / "bad.AT2"
    p.write_text(text)
    with pytest.raises(ValueError, match=match) as exc:
        read_at2(p)
    assert "bad.AT2" in str(exc.value)


# ------------------------------------------------------------------------------------------- CSV
def test_read_csv_units(tmp_path):
    p = tmp_path / "a.csv"
    p.write_text("time [s], ag [cm/s^2]\n0.0, 10\n0.02, -20\n0.04, 5\n")
    r = read_csv(p)
    assert np.array_equal(r.t, [0.0, 0.02, 0.04]) and np.allclose(r.ag, [0.1, -0.2, 0.05], rtol=1e-15)
    q = tmp_path / "b.txt"
    q.write_text("# units: g\n0 0.1\n0.01 0.2\n")
    assert np.allclose(read_record(q).ag, [0.1 * G_N, 0.2 * G_N])
    n = tmp_path / "c.csv"
    n.write_text("0;1\n0.01;2\n")
    assert np.allclose(read_csv(n, units="mm/s2").ag, [0.001, 0.002])
    with pytest.raises(ValueError, match="units are not stated"):
        read_csv(n)
    with pytest.raises(ValueError, match="states units 'cm/s\\^2', but units = 'g'"):
        read_csv(p, units="g")
    assert unit_factor("m/s/s") == 1.0 and unit_factor("Gal") == 0.01 and unit_factor("cm/sec2") == 0.01
    with pytest.raises(ValueError, match="units = 'furlong' is not supported"):
        unit_factor("furlong")


def test_csv_round_trip_is_exact(tmp_path):
    t, a = synthetic_record(duration=1.0, seed=3)
    r = read_csv(write_csv(tmp_path / "r.csv", t, a))
    assert np.array_equal(r.t, t) and np.array_equal(r.ag, a)


@pytest.mark.parametrize("text, match", [
    ("t [s],a [g]\n0,1\n0.1,x\n", r"line 3: 'x' is not a number"),
    ("t [s],a [g]\n0,1\n0.1,2,3\n", r"line 3: 3 columns, expected 2"),
    ("t [s],a [g]\n0,1\n0,2\n", r"line 3: time 0 s is not after"),
    ("t [s],a [g]\n0,1\n", r"1 data rows, expected at least 2"),
])
def test_malformed_csv(tmp_path, text, match):
    p = tmp_path / "bad.csv"
    p.write_text(text)
    with pytest.raises(ValueError, match=match) as exc:
        read_csv(p)
    assert "bad.csv" in str(exc.value)


def test_synthetic_record_fixed_numbers():
    """The benchmarks' record: fixed seed, PGA 0.4 g (9.81), starts at rest (moved here unchanged)."""
    from benchmarks.scenes import synthetic_record as from_scenes
    t, a = synthetic_record()
    assert from_scenes is synthetic_record
    assert t.size == 3001 and t[-1] == pytest.approx(30.0) and a[0] == 0.0
    assert np.max(np.abs(a)) == pytest.approx(0.4 * 9.81, rel=1e-14)
    t2, a2 = synthetic_record()
    assert np.array_equal(a, a2)
    assert load_motion("synthetic:2017").pga == pytest.approx(0.4 * 9.81)
    with pytest.raises(ValueError, match="seed must be an integer"):
        load_motion("synthetic:abc")
