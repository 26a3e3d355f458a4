"""The rocking command line: simulate (CSV, PNG, summary), ensemble, errors as exit status 2."""
import csv
import math
import subprocess
import sys

import numpy as np
import pytest

from rocking_model import RigidBlock, SinePulse, simulate
from rocking_model.cli import main
from rocking_model.records import write_csv


def test_simulate_pulse_writes_csv_png_and_summary(tmp_path, capsys):
    rc = main(["simulate", "--model", "rigid", "--b", "0.2", "--h", "1.0", "--pulse", "sine", "--amplitude", "3",
               "--frequency", "2", "--t-end", "3", "--out", str(tmp_path), "--name", "run"])
    assert rc == 0
    out = capsys.readouterr().out
    ref = simulate(RigidBlock(0.2, 1.0), SinePulse(3.0, 4 * math.pi), 3.0, scheme="event_driven")
    assert f"impacts    = {int(ref.impacts[-1])}" in out and "overturned = no" in out
    assert f"max |phi|  = {np.max(np.abs(ref.phi)):.5g} rad" in out
    with open(tmp_path / "run.csv") as f:
        header = next(csv.reader(f))
    assert header[:3] == ["time [s]", "ag [m/s2]", "phi [rad]"]
    data = np.loadtxt(tmp_path / "run.csv", delimiter=",", skiprows=1)
    assert data.shape[0] == 301
    assert np.allclose(data[:, 2], ref.phi, rtol=1e-9, atol=1e-12)
    assert np.allclose(data[:, 1], [SinePulse(3.0, 4 * math.pi)(t) for t in ref.t], atol=1e-9)
    png = (tmp_path / "run.png").read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 20000


def test_simulate_record_scaled(tmp_path, capsys):
    t = np.arange(0, 1.0001, 0.01)
    rec = write_csv(tmp_path / "rec.csv", t, 0.3 * 9.80665 * np.sin(2 * np.pi * t), units="g")  # 0.3 g
    rc = main(["simulate", "--record", str(rec), "--scale", "2", "--t-end", "2", "--scheme", "moreau_jean",
               "--out", str(tmp_path), "--no-plot"])
    assert rc == 0
    out = capsys.readouterr().out
    assert "PGA = 5.88 m/s2" in out                    # 0.6 g
    data = np.loadtxt(tmp_path / "rigid_rec_x2_moreau_jean.csv", delimiter=",", skiprows=1)
    assert data[25, 1] == pytest.approx(0.6 * 9.80665, rel=1e-9)
    assert not (tmp_path / "rigid_rec_x2_moreau_jean.png").exists()


@pytest.mark.parametrize("argv, msg", [
    (["simulate", "--pulse", "sine", "--amplitude", "3"], "--pulse sine needs --frequency"),
    (["simulate", "--b", "-0.2"], "b = -0.2 is out of range"),
    (["simulate", "--EI", "1e6"], "--EI is not a parameter of the rigid model"),
    (["simulate", "--record", "missing.AT2"], "no such file"),
    (["simulate", "--pulse", "sine", "--amplitude", "3", "--frequency", "2", "--record", "x.csv"],
     "either --record or --pulse"),
    (["simulate", "--pulse", "sine", "--amplitude", "3", "--frequency", "2", "--amplitude-units", "furlong"],
     "units = 'furlong' is not supported"),
    (["ensemble", "--pulse", "sine", "--amplitude-ratios", "2", "--frequency-ratios", "0:1:2"],
     "frequency ratio = 0 is out of range"),
    (["ensemble", "--workers", "0"], "give either --record"),
    (["simulate", "--pulse", "sine", "--amplitude", "3", "--frequency", "-1"],
     "--frequency = -1 is out of range; allowed range (0, inf)"),
    (["simulate", "--pulse", "rectangular", "--amplitude", "3", "--duration", "0"],
     "duration = 0 is out of range; allowed range (0, inf)"),
    (["simulate", "--pulse", "ricker", "--amplitude", "3", "--frequency", "2", "--t0", "nan"],
     "t_start = nan is not finite"),
])
def test_bad_input_exits_2_without_traceback(argv, msg, capsys, tmp_path):
    assert main(argv + ["--out", str(tmp_path / "o.csv" if argv[0] == "ensemble" else tmp_path)]) == 2
    err = capsys.readouterr().err
    assert msg in err and "Traceback" not in err


def test_argparse_errors_exit_2(capsys):
    with pytest.raises(SystemExit) as e:
        main(["simulate", "--scheme", "rk4"])
    assert e.value.code == 2
    with pytest.raises(SystemExit) as e:
        main(["ensemble", "--amplitude-ratios", "1:x:3"])
    assert e.value.code == 2 and "start:stop:num" in capsys.readouterr().err


def test_ensemble_serial_resume_and_spectrum(tmp_path, capsys):
    out = tmp_path / "ens.csv"
    argv = ["ensemble", "--pulse", "sine", "--amplitude-ratios", "1.5:6:2", "--frequency-ratios", "2", "8",
            "--workers", "0", "--no-progress", "--out", str(out)]
    assert main(argv) == 0
    text = capsys.readouterr().out
    assert "4 cases" in text and "ran 4 cases (0 already" in text and "cases/s" in text
    assert (tmp_path / "ens_spectrum.png").read_bytes()[:4] == b"\x89PNG"
    assert main(argv + ["--no-plot"]) == 0
    assert "ran 0 cases (4 already" in capsys.readouterr().out
    assert len(out.read_text().splitlines()) == 5


def test_console_script_entry_point():
    """`rocking` is installed as a console script; -m works too."""
    r = subprocess.run([sys.executable, "-m", "rocking_model.cli", "--help"], capture_output=True, text=True)
    assert r.returncode == 0 and "simulate" in r.stdout and "ensemble" in r.stdout
    r = subprocess.run([sys.executable, "-m", "rocking_model.cli", "simulate", "--h", "x"], capture_output=True,
                       text=True)
    assert r.returncode == 2 and "Traceback" not in r.stderr


def test_model_options_come_from_the_declarations(tmp_path, capsys):
    """The model options, their help and the allowed ones per model are read from the registered
    models' declarations: a choice takes its name, an option of another model is refused by name."""
    from rocking_model.models import MODELS

    with pytest.raises(SystemExit):
        main(["simulate", "--help"])
    text = capsys.readouterr().out
    for cls in MODELS.values():
        for p in cls.parameters() + cls.INITIAL:
            assert f"--{p.name.replace('_', '-')}" in text, p.name
    assert main(["simulate", "--model", "flexible", "--impact-rule", "classical", "--phi-0", "0.02",
                 "--t-end", "0.5", "--out", str(tmp_path), "--name", "f"]) == 0
    capsys.readouterr()
    assert main(["simulate", "--model", "rigid", "--u-0", "0.01", "--out", str(tmp_path)]) == 2
    assert "--u-0 is not an initial value of the rigid model; allowed: --phi-0, --phi-dot-0" in capsys.readouterr().err
    assert main(["simulate", "--model", "rigid", "--EI", "1e5", "--out", str(tmp_path)]) == 2
    assert "--EI is not a parameter of the rigid model" in capsys.readouterr().err


def test_outputs_are_named_after_the_scene_and_never_overwritten(tmp_path, capsys):
    """Without --name the files are named after the scene (two scenes, two names); running the same
    scene again is refused (exit 2, nothing touched) unless --force is given."""
    base = ["simulate", "--pulse", "sine", "--amplitude", "3", "--frequency", "2", "--t-end", "1", "--no-plot",
            "--out", str(tmp_path)]
    assert main(base + ["--b", "0.3"]) == 0
    assert main(base + ["--b", "0.25"]) == 0
    names = sorted(p.name for p in tmp_path.iterdir())
    assert names == ["rigid_b0.25_sine-A3ms2-f2Hz.csv", "rigid_b0.3_sine-A3ms2-f2Hz.csv"]
    first = tmp_path / names[1]
    stamp = first.stat().st_mtime_ns
    capsys.readouterr()
    assert main(base + ["--b", "0.3"]) == 2
    err = capsys.readouterr().err
    assert f"{first} already exist(s): give --force to overwrite" in err and "Traceback" not in err
    assert first.stat().st_mtime_ns == stamp
    first.write_text("a user's edits\n")
    assert main(base + ["--b", "0.3", "--force"]) == 0
    assert first.read_text().startswith("time [s],ag [m/s2],phi [rad]")
    assert main(base + ["--b", "0.3", "--name", "mine"]) == 0 and (tmp_path / "mine.csv").exists()


def test_build_fmu_command_writes_the_cross_check_folders(tmp_path, capsys):
    """`rocking build-fmu` does what `python build_fmu.py` does, cross-check folders included."""
    import build_fmu

    assert main(["build-fmu", "--dest", str(tmp_path), "RigidRockingBlock"]) == 0
    out = capsys.readouterr().out
    assert f"built and validated {tmp_path / 'RigidRockingBlock.fmu'}" in out and "cross-check folders in" in out
    folder = build_fmu.cross_check_dir(tmp_path / build_fmu.CROSS_CHECK_DIR, "RigidRockingBlock")
    assert (folder / "RigidRockingBlock_ref.csv").is_file() and (folder / "RigidRockingBlock.fmu").is_file()
    assert main(["build-fmu", "--dest", str(tmp_path / "plain"), "--no-cross-check", "RigidRockingBlock"]) == 0
    assert not (tmp_path / "plain" / build_fmu.CROSS_CHECK_DIR).exists()


@pytest.mark.parametrize("argv, msg", [
    (["--b", "0"], "b = 0 is out of range; allowed range [1e-06, 1000]"),
    (["--b", "-1"], "b = -1 is out of range; allowed range [1e-06, 1000]"),
    (["--h", "2000"], "h = 2000 is out of range; allowed range [1e-06, 1000]"),
    (["--e-N", "1.5"], "e_N = 1.5 is out of range; allowed range [0, 1]"),
    (["--mu", "0"], "mu = 0 is out of range; allowed range [0.001, inf]"),
    (["--tolerance", "1"], "tolerance = 1 is out of range; allowed range [1e-14, 0.01]"),
])
def test_ensemble_refuses_bad_case_fields_before_the_cluster_starts(argv, msg, tmp_path, capsys):
    """A bad case field is refused with one line naming it and its range (the models' and the
    solver's declared checks), exit status 2, before the cluster starts (no banner, no output file)."""
    out = tmp_path / "o.csv"
    rc = main(["ensemble", "--pulse", "sine", "--amplitude-ratios", "2", "--frequency-ratios", "3",
               "--workers", "2", "--no-progress", "--out", str(out)] + argv)
    cap = capsys.readouterr()
    assert rc == 2 and cap.err == f"rocking ensemble: error: {msg}\n"
    assert "cases ->" not in cap.out and not out.exists()


@pytest.mark.parametrize("argv, msg", [
    (["--workers", "-1"], "argument --workers: -1 is out of range; allowed range [0, inf)"),
    (["--batch-size", "0"], "argument --batch-size: 0 is out of range; allowed range [1, inf)"),
    (["--workers", "1.5"], "argument --workers: '1.5' is not an integer"),
    (["--no-workers-timeout", "0"], "argument --no-workers-timeout: 0 is out of range; allowed range (0, inf]"),
])
def test_ensemble_execution_options_are_refused_at_parse_time(argv, msg, capsys):
    """--workers -1 used to be refused only after the cluster banner."""
    with pytest.raises(SystemExit) as e:
        main(["ensemble", "--pulse", "sine", "--amplitude-ratios", "2", "--frequency-ratios", "3"] + argv)
    cap = capsys.readouterr()
    assert e.value.code == 2 and msg in cap.err and "cases ->" not in cap.out


def test_version_is_the_package_version(capsys):
    """`rocking --version` prints the installed package's version (one source: its metadata)."""
    from importlib.metadata import version

    import rocking_model

    with pytest.raises(SystemExit) as e:
        main(["--version"])
    assert e.value.code == 0
    assert capsys.readouterr().out == f"rocking {version('rocking-model')}\n"
    assert rocking_model.__version__ == version("rocking-model")


def test_ensemble_reports_repairs_and_a_truncated_header_in_one_line(tmp_path, capsys):
    """What a resume set aside is printed as one warning line; a header cut short is named as
    truncated (exit 2), not as a foreign file."""
    from rocking_model.ensemble import FIELDS

    out = tmp_path / "ens.csv"
    argv = ["ensemble", "--pulse", "sine", "--amplitude-ratios", "2", "4", "--frequency-ratios", "3",
            "--workers", "0", "--no-progress", "--no-plot", "--out", str(out)]
    assert main(argv) == 0
    with open(out, "a") as f:
        f.write("a cut row,rigid,0.2")
    capsys.readouterr()
    assert main(argv) == 0
    err = capsys.readouterr().err
    assert err == f"rocking ensemble: warning: {out}: 1 broken row(s) (line 4) set aside in {out}.rejected; " \
                  "their cases run again\n"
    out.write_text(",".join(FIELDS)[:50] + "\n" + "x," * (len(FIELDS) - 1) + "x\n")
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "its header is truncated" in err and "move it aside" in err and "Traceback" not in err


# --------------------------------------------------------------------------------------------- vertical
def _three_column_record(tmp_path):
    from rocking_model.records import synthetic_record
    t, a = synthetic_record(duration=2.0, seed=21)
    _, v = synthetic_record(duration=2.0, seed=22, pga_g=0.3)
    return t, a, v, write_csv(tmp_path / "rec3.csv", t, a, units="g", ag_v=v)


def test_simulate_three_column_record_writes_ag_v(tmp_path, capsys):
    """A three-column record's third column is ag_v: the CSV output gets the column ``ag_v [m/s2]`` after ag,
    the response is the simulation of the two-component record, the summary names its vertical PGA, and
    --vertical-scale scales that column (0: the horizontal run, without the column)."""
    from rocking_model.records import read_record

    t, a, v, rec = _three_column_record(tmp_path)
    assert main(["simulate", "--record", str(rec), "--t-end", "2", "--out", str(tmp_path), "--name", "v"]) == 0
    assert "PGA_v = 2.94 m/s2" in capsys.readouterr().out
    with open(tmp_path / "v.csv") as f:
        header = next(csv.reader(f))
    assert header[:4] == ["time [s]", "ag [m/s2]", "ag_v [m/s2]", "phi [rad]"]
    data = np.loadtxt(tmp_path / "v.csv", delimiter=",", skiprows=1)
    assert np.allclose(data[::10, 2], v[::10], rtol=1e-9, atol=1e-12)
    ref = simulate(RigidBlock(), read_record(rec), 2.0)
    assert np.allclose(data[:, 3], ref.phi, rtol=1e-9, atol=1e-12)
    assert (tmp_path / "v.png").read_bytes()[:4] == b"\x89PNG"
    assert main(["simulate", "--record", str(rec), "--t-end", "2", "--out", str(tmp_path), "--name", "v2",
                 "--vertical-scale", "-2", "--no-plot"]) == 0
    data2 = np.loadtxt(tmp_path / "v2.csv", delimiter=",", skiprows=1)
    assert np.allclose(data2[::10, 2], -2.0 * v[::10], rtol=1e-9, atol=1e-12)
    assert main(["simulate", "--record", str(rec), "--t-end", "2", "--out", str(tmp_path), "--name", "v0",
                 "--vertical-scale", "0", "--no-plot"]) == 0
    with open(tmp_path / "v0.csv") as f:
        assert next(csv.reader(f))[:3] == ["time [s]", "ag [m/s2]", "phi [rad]"]
    h = simulate(RigidBlock(), read_record(rec).horizontal, 2.0)
    assert np.allclose(np.loadtxt(tmp_path / "v0.csv", delimiter=",", skiprows=1)[:, 2], h.phi, rtol=1e-9,
                       atol=1e-12)


def test_simulate_vertical_file_and_vertical_scale_of_a_pulse(tmp_path, capsys):
    """--vertical FILE (AT2 pair) gives the record's ag_v, scaled with --scale and --vertical-scale; a pulse's
    --vertical-scale F gives ag_v = F x ag; the scene name carries both."""
    from rocking_model.records import synthetic_motion, write_at2

    h = synthetic_motion(31, duration=2.0)
    v = synthetic_motion(32, duration=2.0)
    write_at2(tmp_path / "H.AT2", h)
    write_at2(tmp_path / "UP.AT2", v)
    assert main(["simulate", "--record", str(tmp_path / "H.AT2"), "--vertical", str(tmp_path / "UP.AT2"),
                 "--scale", "0.5", "--vertical-scale", "1.5", "--t-end", "2", "--out", str(tmp_path),
                 "--no-plot"]) == 0
    out = tmp_path / "rigid_H_V-UP_x0.5_vx1.5.csv"
    data = np.loadtxt(out, delimiter=",", skiprows=1)
    assert np.allclose(data[::10, 1], 0.5 * h.ag[::10], rtol=1e-9, atol=1e-12)
    assert np.allclose(data[::10, 2], 0.75 * v.ag[::10], rtol=1e-9, atol=1e-12)
    assert main(["simulate", "--pulse", "sine", "--amplitude", "3", "--frequency", "2", "--vertical-scale", "0.5",
                 "--t-end", "1", "--out", str(tmp_path), "--name", "p", "--no-plot"]) == 0
    p = np.loadtxt(tmp_path / "p.csv", delimiter=",", skiprows=1)
    assert np.any(p[:, 1] != 0.0) and np.allclose(p[:, 2], 0.5 * p[:, 1], rtol=1e-9, atol=1e-12)
    from rocking_model import TwoComponentMotion
    pulse = SinePulse(3.0, 4 * math.pi)
    ref = simulate(RigidBlock(), TwoComponentMotion(pulse, pulse.scaled(0.5)), 1.0)
    assert np.allclose(p[:, 3], ref.phi, rtol=1e-9, atol=1e-12)
    assert "vertical 0.5 x the pulse" in capsys.readouterr().out


@pytest.mark.parametrize("argv, msg", [
    (["simulate", "--pulse", "sine", "--amplitude", "3", "--frequency", "2", "--vertical-scale", "11"],
     "rocking simulate: error: --vertical-scale = 11 is out of range; allowed range [-10, 10]\n"),
    (["simulate", "--pulse", "sine", "--amplitude", "3", "--frequency", "2", "--vertical-scale", "nan"],
     "rocking simulate: error: --vertical-scale = nan is not finite; allowed range [-10, 10]\n"),
    (["simulate", "--vertical-scale", "0.5"],
     "rocking simulate: error: --scale, --resample and --vertical-scale apply to a --record or --pulse\n"),
    (["simulate", "--pulse", "sine", "--amplitude", "3", "--frequency", "2", "--vertical", "x.AT2"],
     "rocking simulate: error: --vertical (the vertical component of a record) needs --record; a pulse takes "
     "--vertical-scale (ag_v = scale x the pulse)\n"),
    (["ensemble", "--pulse", "sine", "--amplitude-ratios", "2", "--frequency-ratios", "3", "--vertical-scales",
      "-20"], "rocking ensemble: error: --vertical-scales = -20 is out of range; allowed range [-10, 10]\n"),
    (["ensemble", "--record", "synthetic:1", "synthetic:2", "--vertical", "synthetic:3"],
     "rocking ensemble: error: --vertical: give one vertical record per --record (2), got 1 ('' for a record "
     "without one)\n"),
])
def test_bad_vertical_input_is_one_line_and_exit_2(argv, msg, capsys, tmp_path):
    out = tmp_path / "o.csv" if argv[0] == "ensemble" else tmp_path
    assert main(argv + ["--out", str(out), "--no-plot"]) == 2
    assert capsys.readouterr().err == msg


def test_simulate_refuses_a_vertical_record_of_another_time_step(tmp_path, capsys):
    from rocking_model.records import synthetic_motion, write_at2
    write_at2(tmp_path / "H.AT2", synthetic_motion(31, duration=1.0))
    write_at2(tmp_path / "V.AT2", synthetic_motion(32, duration=1.0, dt=0.02))
    assert main(["simulate", "--record", str(tmp_path / "H.AT2"), "--vertical", str(tmp_path / "V.AT2"),
                 "--out", str(tmp_path), "--no-plot"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "V.AT2: DT = 0.02 s, but the horizontal component" in err


def test_ensemble_vertical_scales_and_records(tmp_path, capsys):
    """--vertical-scales is a grid dimension (case field ag_v_scale); 0 keeps the ids of the runs without it,
    so a result file of a run without vertical resumes; --vertical pairs one file with each record."""
    from rocking_model.ensemble import read_results
    from rocking_model.records import synthetic_motion, write_at2

    out = tmp_path / "ens.csv"
    base = ["ensemble", "--pulse", "sine", "--amplitude-ratios", "2", "--frequency-ratios", "3", "--t-end", "1",
            "--workers", "0", "--no-progress", "--no-plot", "--out", str(out)]
    assert main(base) == 0
    assert main(base + ["--vertical-scales", "0", "0.5"]) == 0
    assert "ran 1 cases (1 already" in capsys.readouterr().out
    assert sorted(r["ag_v_scale"] for r in read_results(out)) == [0.0, 0.5]
    write_at2(tmp_path / "H.AT2", synthetic_motion(31, duration=1.0))
    write_at2(tmp_path / "UP.AT2", synthetic_motion(32, duration=1.0))
    rec = tmp_path / "rec.csv"
    assert main(["ensemble", "--record", str(tmp_path / "H.AT2"), "synthetic:4", "--vertical",
                 str(tmp_path / "UP.AT2"), "", "--t-end", "1", "--workers", "0", "--no-progress", "--no-plot",
                 "--out", str(rec)]) == 0
    rows = sorted(read_results(rec), key=lambda r: r["record"])
    assert [r["ag_v_scale"] for r in rows] == [1.0, 0.0] and rows[0]["vertical"].endswith("UP.AT2")
    assert all(r["error"] == "" for r in rows)


def test_every_model_simulates_and_runs_an_ensemble_from_its_declared_options(tmp_path, capsys):
    """The post-tensioned block (and any registered model) through the CLI by its declared parameters alone:
    `simulate` with --P0 / --k_t (the declared spelling) or --k-t, its summary naming them and its own output
    (the tendon force); `ensemble` with the same options (the case field params) and, a rigid block, the
    dimensionless ratios and the spectrum; an option of another model refused by name."""
    import csv
    import json

    from rocking_model import simulate
    from rocking_model.models import PostTensionedBlock
    from rocking_model.ground_motion import SinePulse

    pt = ["--model", "post_tensioned", "--b", "0.3", "--h", "1.5", "--m", "1000", "--P0", "2e4"]
    assert main(["simulate", *pt, "--k_t", "2e6", "--pulse", "sine", "--amplitude", "10", "--frequency", "1",
                 "--t-end", "3", "--no-plot", "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "post-tensioned rocking block b = 0.3 m, h = 1.5 m, m = 1000 kg, P0 = 20000 N, k_t = 2e+06 N/m" in out
    assert "uplift at tan(alpha) (g + P0/m) = 5.962 m/s2" in out and "max |tendon force| = " in out
    (path,) = tmp_path.glob("post_tensioned_*.csv")
    assert path.name == "post_tensioned_b0.3_h1.5_m1000_P0-20000_k_t2e+06_sine-A10ms2-f1Hz.csv"
    ref = simulate(PostTensionedBlock(b=0.3, h=1.5, m=1000.0, P0=2e4, k_t=2e6), SinePulse(10.0, 2 * math.pi),
                   3.0, output_interval=0.01)
    data = np.genfromtxt(path, delimiter=",", names=True)
    assert np.max(np.abs(data["phi_rad"] - ref.phi)) < 1e-9 and np.max(ref.phi) > 0.1
    assert np.max(np.abs(data["tendon_force_N"] - ref.values["tendon_force"])) < 1e-3
    assert main(["simulate", *pt, "--k-t", "2e6", "--t-end", "0.1", "--no-plot", "--out", str(tmp_path)]) == 0
    capsys.readouterr()
    ens = tmp_path / "pt.csv"
    assert main(["ensemble", *pt, "--k_t", "2e6", "--pulse", "sine", "--amplitude-ratios", "2", "6",
                 "--frequency-ratios", "3", "--workers", "0", "--no-progress", "--out", str(ens)]) == 0
    assert (tmp_path / "pt_spectrum.png").read_bytes()[:4] == b"\x89PNG"
    rows = list(csv.DictReader(ens.open()))
    assert [r["model"] for r in rows] == ["post_tensioned"] * 2 and not any(r["error"] for r in rows)
    assert json.loads(rows[0]["params"]) == {"P0": 20000.0, "k_t": 2e6, "m": 1000.0}
    # a_ratio 2 is below the tendon's uplift threshold (1 + P0/(m g) = 3.04): the block stays at rest
    assert float(rows[0]["max_abs_phi"]) == 0.0 and float(rows[1]["max_abs_phi"]) > 0.05
    capsys.readouterr()
    assert main(["ensemble", "--P0", "1", "--pulse", "sine", "--amplitude-ratios", "2", "--frequency-ratios", "3",
                 "--workers", "0", "--out", str(tmp_path / "r.csv")]) == 2
    assert "--P0 is not a parameter of the rigid model; allowed: --m, --g, --impact-law" in capsys.readouterr().err
