"""Ground motions and records: pulses against closed forms, breakpoints, scaling, resampling, AT2/CSV."""
import math

import numpy as np
import pytest
from scipy.integrate import quad

from rocking_model import RigidBlock, SampledMotion, Simulator, SinePulse
from rocking_model.ground_motion import PULSES, CosinePulse, RectangularPulse, RickerPulse, pulse_from_parameters
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


# ------------------------------------------------------------------------------------------- one factory
def test_pulse_from_parameters_builds_each_kind():
    A, w, t0 = 2.5, 2 * math.pi * 1.5, 0.3
    T = 2 * math.pi / w
    s = pulse_from_parameters("sine", A, w, t0, scale=2.0)
    assert type(s) is SinePulse and (s.A, s.omega_p, s.t0) == (5.0, w, t0)
    assert type(pulse_from_parameters("sine", A, w)) is SinePulse and pulse_from_parameters("sine", A, w).t0 == 0.0
    c = pulse_from_parameters("cosine", A, w, t0)
    assert type(c) is CosinePulse and c(t0 + 0.5 * T) == pytest.approx(-A)
    r = pulse_from_parameters("ricker", A, w)
    assert type(r) is RickerPulse and r.t_c == pytest.approx(1.5 * T)        # default centre
    assert pulse_from_parameters("ricker", A, w, t0).t_c == t0                  # t_start is the centre
    rect = pulse_from_parameters("rectangular", A, w, t0)
    assert type(rect) is RectangularPulse and rect.duration == T and rect.support == (t0, t0 + T)
    rect = pulse_from_parameters("rectangular", A, t_start=t0, duration=0.4)
    assert rect.support == (t0, t0 + 0.4) and rect(t0 + 0.2) == A
    assert set(PULSES) == {"sine", "cosine", "ricker", "rectangular"}


@pytest.mark.parametrize("kwargs, match", [
    (dict(kind="square", A=1.0, omega_p=1.0), r"pulse = 'square' is not supported; allowed values: 'sine'"),
    (dict(kind="sine", A=1.0, omega_p=0.0), r"omega_p = 0 is out of range; allowed range \(0, inf\)"),
    (dict(kind="cosine", A=1.0), r"a cosine pulse needs omega_p \[rad/s\]; allowed range \(0, inf\)"),
    (dict(kind="ricker", A=float("nan"), omega_p=1.0), r"A = nan is not finite"),
    (dict(kind="sine", A=1.0, omega_p=1.0, t_start=float("inf")), r"t_start = inf is not finite"),
    (dict(kind="sine", A=1.0, omega_p=1.0, scale="x"), r"scale must be a real number"),
    (dict(kind="sine", A=1.0, omega_p=1.0, duration=0.5), r"duration = 0.5 applies to the rectangular pulse only"),
    (dict(kind="rectangular", A=1.0), r"needs either duration \[s\] \(allowed range \(0, inf\)\) or omega_p.*neither"),
    (dict(kind="rectangular", A=1.0, omega_p=1.0, duration=1.0), r"not both"),
    (dict(kind="rectangular", A=1.0, duration=-0.1), r"duration = -0.1 is out of range; allowed range \(0, inf\)"),
])
def test_pulse_from_parameters_errors_name_the_parameter(kwargs, match):
    with pytest.raises(ValueError, match=match):
        pulse_from_parameters(**kwargs)


def _same_motion(a, b, t_end):
    """Same class, same parameters, bit-identical values and breakpoints."""
    assert type(a) is type(b)
    grid = np.linspace(-0.1, t_end, 1237).tolist()
    assert [a(t) for t in grid] == [b(t) for t in grid]
    bp_a, bp_b, t = [], [], -1.0
    while math.isfinite(t) and len(bp_a) < 50:
        bp_a.append(a.next_breakpoint(t))
        bp_b.append(b.next_breakpoint(t))
        t = bp_a[-1]
    assert bp_a == bp_b and a.support == b.support


@pytest.mark.parametrize("kind", PULSES)
def test_cli_ensemble_and_fmu_build_the_same_pulse(kind):
    """The CLI (``rocking simulate --pulse``), the ensembles (`case_motion`) and the GroundMotionSource FMU
    (`ground_motion_from_parameters`, sine only) build identical motions from identical parameters."""
    from rocking_model import cli, cosim, ensemble

    A, f, scale = 2.75, 1.3, 1.7
    w = 2.0 * math.pi * f
    argv = ["simulate", "--pulse", kind, "--amplitude", repr(A), "--scale", repr(scale)]
    argv += ["--duration", repr(2 * math.pi / w)] if kind == "rectangular" else ["--frequency", repr(f)]
    from_cli, _, _ = cli._motion(cli.build_parser().parse_args(argv))
    case = dict(ensemble.pulse_cases(kind, amplitudes=[A], frequencies=[f])[0], scale=scale)
    from_ensemble = ensemble.case_motion(case)
    factory = pulse_from_parameters(kind, A, w, scale=scale)
    t_end = factory.support[1] + 0.5
    _same_motion(from_cli, factory, t_end)
    _same_motion(from_ensemble, factory, t_end)
    if kind == "sine":
        from_fmu = cosim.ground_motion_from_parameters(dict(motion=0, A=A, omega_p=w, t_start=0.0, scale=scale))
        _same_motion(from_fmu, factory, t_end)
        assert max(abs(factory(t)) for t in np.linspace(0, t_end, 101)) == pytest.approx(A * scale, rel=1e-3)


def test_cli_ensemble_and_fmu_read_the_same_record(tmp_path):
    """A CSV headed ``time [s],ag [cm/s2]`` and an AT2 file: the three callers read identical records
    (units converted once, by `rocking_model.records`), scaled identically."""
    from rocking_model import cli, cosim, ensemble

    t, a = synthetic_record(duration=2.0, seed=5)
    files = [write_csv(tmp_path / "r.csv", t, a, units="cm/s2"), write_at2(tmp_path / "r.AT2", t, a)]
    for path in files:
        from_cli, _, _ = cli._motion(cli.build_parser().parse_args(["simulate", "--record", str(path),
                                                                       "--scale", "1.5"]))
        from_ensemble = ensemble.case_motion(ensemble.record_cases([str(path)], scales=[1.5])[0])
        from_fmu = cosim.ground_motion_from_parameters(dict(motion=1, record=str(path), scale=1.5))
        for m in (from_ensemble, from_fmu):
            assert type(m) is Record and np.array_equal(m.t, from_cli.t) and np.array_equal(m.ag, from_cli.ag)
        np.testing.assert_allclose(from_fmu.ag, 1.5 * a, rtol=1e-14, atol=1e-14)


def test_cli_ensemble_and_fmu_read_the_same_three_component_record(tmp_path):
    """A three-column CSV (ag, ag_v in cm/s2) and an AT2 pair: the CLI (--vertical, --vertical-scale), the
    ensembles (case fields vertical, ag_v_scale) and the GroundMotionSource FMU (vertical, vertical_scale)
    build identical two-component records: both components scaled by the scale, the vertical one by the
    vertical scale too."""
    from rocking_model import cli, cosim, ensemble

    t, a = synthetic_record(duration=2.0, seed=5)
    _, v = synthetic_record(duration=2.0, seed=6)
    three = write_csv(tmp_path / "r3.csv", t, a, units="cm/s2", ag_v=v)
    h, up = write_at2(tmp_path / "h.AT2", t, a), write_at2(tmp_path / "up.AT2", t, v)
    for path, vertical in ((three, None), (h, up)):
        argv = ["simulate", "--record", str(path), "--scale", "1.5", "--vertical-scale", "0.5"]
        from_cli, _, _ = cli._motion(cli.build_parser().parse_args(
            argv + (["--vertical", str(vertical)] if vertical else [])))
        case = ensemble.record_cases([str(path)], scales=[1.5], ag_v_scales=[0.5],
                                     vertical=[str(vertical)] if vertical else None)[0]
        from_ensemble = ensemble.case_motion(case)
        from_fmu = cosim.ground_motion_from_parameters(dict(motion=1, record=str(path), scale=1.5,
                                                            vertical=str(vertical or ""), vertical_scale=0.5))
        for m in (from_cli, from_ensemble, from_fmu):
            assert type(m) is Record and np.array_equal(m.t, t)
            np.testing.assert_allclose(m.ag, 1.5 * a, rtol=1e-14, atol=1e-14)
            np.testing.assert_allclose(m.ag_v, 0.75 * v, rtol=1e-14, atol=1e-14)
        assert np.array_equal(from_ensemble.ag_v, from_cli.ag_v) and np.array_equal(from_fmu.ag_v, from_cli.ag_v)


def test_fmu_record_parameters(tmp_path):
    """GroundMotionSource's record/units parameters: units from the file, else the units parameter, else m/s2;
    the reader's errors unchanged."""
    from rocking_model.cosim import ground_motion_from_parameters as gmp

    bare = tmp_path / "bare.csv"
    bare.write_text("0.0,1.0\n0.5,-2.0\n")
    m = gmp(dict(motion=1, record=str(bare)))
    assert np.array_equal(m.ag, [1.0, -2.0]) and m.units == "m/s2" and m.units_assumed
    m = gmp(dict(motion=1, record=str(bare), units="g"))
    assert np.array_equal(m.ag, [G_N, -2.0 * G_N]) and m.units == "g" and not m.units_assumed
    cm = tmp_path / "cm.csv"
    cm.write_text("time [s],ag [cm/s2]\n0.0,100\n0.5,-250\n")
    m = gmp(dict(motion=1, record=str(cm)))
    assert np.array_equal(m.ag, [1.0, -2.5]) and m.units == "cm/s2" and not m.units_assumed
    with pytest.raises(ValueError, match=r"cm.csv: the file states units 'cm/s2', but units = 'g' was given"):
        gmp(dict(motion=1, record=str(cm), units="g"))
    with pytest.raises(ValueError, match=r"units = 'furlong' is not supported; allowed values: g, m/s2"):
        gmp(dict(motion=0, A=1.0, omega_p=1.0, units="furlong"))
    with pytest.raises(ValueError, match=r"record = '': motion = 1 needs a record file"):
        gmp(dict(motion=1, record=""))
    with pytest.raises(ValueError, match=r"motion = 2 is not supported; allowed values: 0 \(sine pulse\), 1"):
        gmp(dict(motion=2))
    with pytest.raises(ValueError, match=r"scale = inf is not finite"):
        gmp(dict(motion=0, A=1.0, omega_p=1.0, scale=math.inf))
    assert gmp(dict(motion=1, record="synthetic:2017")).pga == pytest.approx(0.4 * 9.81)


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
    assert r.units == "g" and not r.units_assumed
    p.write_text(NEW_AT2.replace("IN UNITS OF G", ""))
    assert read_at2(p).units == "g" and read_at2(p).units_assumed          # the PEER convention
    assert np.array_equal(read_at2(p, units="cm/s2").ag, np.array([0.01, -0.02, 0.3, -0.004, 0.0005, 0.0,
                                                                     -0.01234567]) * 0.01)
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
    d = read_record(n, default_units="cm/s2")              # a default applies only when nothing is stated
    assert np.allclose(d.ag, [0.01, 0.02]) and d.units == "cm/s2" and d.units_assumed
    assert read_csv(p, default_units="g").units == "cm/s^2" and not read_csv(p, default_units="g").units_assumed
    s = read_csv(n, units="mm/s2").scaled(2.0).resampled(0.005)
    assert s.units == "mm/s2" and not s.units_assumed       # carried through scaled and resampled
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


# ------------------------------------------------------------------------------------------- exports, writers
def test_package_exports_every_public_ground_motion():
    """Every public GroundMotion subclass of rocking_model.ground_motion (and the readers' Record) can be imported
    from the package itself, as the ground-motion table of docs/guide/ground-motions.md names them (`from rocking_model import
    CosinePulse` used to fail while SinePulse worked)."""
    import inspect

    import rocking_model
    from rocking_model import ground_motion
    public = {name for name, cls in inspect.getmembers(ground_motion, inspect.isclass)
              if issubclass(cls, ground_motion.GroundMotion) and cls.__module__ == ground_motion.__name__
              and not name.startswith("_")}
    assert {"SinePulse", "CosinePulse", "RickerPulse", "RectangularPulse", "SampledMotion"} <= public
    missing = sorted((public | {"Record"}) - set(rocking_model.__all__))
    assert not missing, f"not in rocking_model.__all__: {missing}"
    assert sorted(public - set(ground_motion.__all__)) == []
    for name in public:
        assert getattr(rocking_model, name) is getattr(ground_motion, name)
    assert rocking_model.Record is Record
    namespace = {}
    exec("from rocking_model import *", namespace)
    assert all(name in namespace for name in public)


def test_writers_take_the_record_the_readers_return(tmp_path):
    """write_at2 / write_csv accept a Record (what read_at2, read_csv and synthetic_motion return) as well as the
    arrays t, ag; the round trip gives the same samples (1 ulp for the g <-> m/s2 conversion)."""
    from rocking_model.records import synthetic_motion
    rec = synthetic_motion(7, duration=2.0)
    back = read_at2(write_at2(tmp_path / "r.AT2", rec))
    assert np.array_equal(back.t, rec.t) and np.allclose(back.ag, rec.ag, rtol=1e-15, atol=0.0)
    assert (tmp_path / "r.AT2").read_text().splitlines()[0] == rec.name          # the record's name is the title
    again = read_at2(write_at2(tmp_path / "s.AT2", back, "cm/s2"))               # units positional, as before
    assert "CM/S2" in (tmp_path / "s.AT2").read_text().splitlines()[2]
    assert np.allclose(again.ag, rec.ag, rtol=1e-14, atol=0.0)
    csv = read_csv(write_csv(tmp_path / "r.csv", rec, units="g"))
    assert np.array_equal(csv.t, rec.t) and np.allclose(csv.ag, rec.ag, rtol=1e-15, atol=0.0)
    old = read_at2(write_at2(tmp_path / "o.AT2", rec.t, rec.ag, "g"))             # the old signature still works
    assert np.array_equal(old.ag, back.ag)
    with pytest.raises(ValueError, match="not both"):
        write_at2(tmp_path / "x.AT2", rec, rec.ag)
    with pytest.raises(ValueError, match="ag is missing"):
        write_at2(tmp_path / "x.AT2", rec.t)


def test_at2_units_come_from_the_line_that_states_them(tmp_path):
    """A title or event line that mentions another unit does not override PEER's "IN UNITS OF G" line."""
    t, a = synthetic_record(duration=1.0, seed=3)
    p = write_at2(tmp_path / "r.AT2", t, a, title="shake table run, PGA 0.4 g (g = 9.81 m/s2)",
                  event="peak 392 cm/s2")
    r = read_at2(p)
    assert r.units == "g" and np.allclose(r.ag, a, rtol=1e-15, atol=0.0)
