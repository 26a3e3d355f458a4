"""Records scaled to intensity measures, MSA and IDA on the ensembles, damage states, fragility outputs, and
`rocking fragility` end to end; on short synthetic records, serially (a few seconds in all)."""
from __future__ import annotations

import csv
import json
import math

import numpy as np
import pytest

from rocking_model import assessment as A
from rocking_model import ensemble as E
from rocking_model.cli import main
from rocking_model.intensity import measure
from rocking_model.models import RigidBlock
from rocking_model.records import Record, synthetic_record, write_csv
from rocking_model.simulation import simulate

ROCK = "PGA/(g tan alpha)"
#: a slender block (alpha = 0.149 rad, p = 2.70 rad/s): rocks and overturns under the 6 s records below
BLOCK = dict(geometries=[(0.15, 1.0)], t_end=8.0)


def _suite(folder, n=4, with_vertical=False):
    """``n`` synthetic records of 6 s (a 3 s strong phase), as CSV files (the third column a vertical one)."""
    folder.mkdir(exist_ok=True)
    for s in range(n):
        t, a = synthetic_record(duration=6.0, seed=s, t_rise=0.5, t_strong=3.0)
        write_csv(folder / f"r{s}.csv", t, a, units="m/s2", ag_v=0.4 * a[::-1] if with_vertical else None)
    return folder


# --------------------------------------------------------------------------------------------- scaling
@pytest.mark.parametrize("im", ["PGA", "PGV", "Sa(0.5)", "Arias", "CAV", ROCK, "PGV p/(g tan alpha)"])
def test_scaled_cases_have_the_target_measure_and_stable_ids(tmp_path, im):
    """Each case's record, scaled by its factor, has the target level of the measure (Arias: factor^2); both
    components take the factor; the id is the level's (not the derived factor's)."""
    s = A.suite([str(_suite(tmp_path / "r", 2, with_vertical=True))], im, **BLOCK)
    block = E.case_model(s.templates[0])
    for level in (0.3, 2.0):
        c = s.at(0, level)
        motion = E.case_motion(c)
        rec = E._record(c["record"], "", "")
        got = measure(Record(motion.t, motion.horizontal.ag), im, block=block)
        assert got == pytest.approx(level, rel=1e-9)
        assert c["ag_v_scale"] == 1.0 and np.allclose(motion.vertical.ag, c["scale"] * rec.vertical.ag, rtol=1e-14)
        assert c["im"] == im and c["im_level"] == level
        assert c["case_id"] == E.case_id(dict(c, scale=c["scale"] * (1 + 1e-15), A=0.0))
    ids = {c["case_id"] for c in s.stripes([0.5, 1.0])}
    assert len(ids) == 4
    assert A.suite([str(tmp_path / "r")], im, **BLOCK).stripes([0.5, 1.0])[0]["case_id"] in ids


def test_scaling_refusals(tmp_path):
    with pytest.raises(ValueError, match="does not change when a record is scaled"):
        A.suite(["synthetic:1"], "D5_95")
    with pytest.raises(ValueError, match="not a known intensity measure"):
        A.suite(["synthetic:1"], "PGX")
    with pytest.raises(ValueError, match="defined for the rigid blocks"):
        A.suite(["synthetic:1"], ROCK, model="flexible")
    with pytest.raises(ValueError, match="has no .AT2 or .csv file"):
        A.record_files([str(tmp_path)])
    assert A.canonical_measure("Sa(1.0)") == "Sa(1)"
    assert A.scale_factor(2.0, 8.0, "Arias") == 2.0


# --------------------------------------------------------------------------------------------- damage states
def test_damage_state_predicates():
    ds = A.damage_states(["minor:phi/alpha>=0.2", "slip>0.01", "tendon>=2e5", "overturned"])
    assert [d.name for d in ds] == ["minor", "slip>0.01", "tendon>=2e5", "overturned"]
    minor, slip, tendon, over = ds
    row = dict(max_phi_over_alpha=0.2, max_abs_slip=0.01, max_tendon_force=2e5, overturned=False, error="")
    assert minor(row) and not slip(row) and tendon(row) and not over(row)
    assert not minor(dict(row, max_phi_over_alpha=0.19)) and slip(dict(row, max_abs_slip=0.011))
    # overturning reaches every damage state; a failed case has no outcome
    gone = dict(row, max_phi_over_alpha=0.0, max_abs_slip=0.0, max_tendon_force=0.0, overturned=True)
    assert all(d(gone) for d in ds)
    assert all(d(dict(row, error="ValueError: x")) is None for d in ds)
    with pytest.raises(ValueError, match="has no max_tendon_force"):
        tendon(dict(row, max_tendon_force=math.nan, model="rigid"))
    assert [d.name for d in A.damage_states()] == list(A.DEFAULT_DAMAGE_STATES)
    for bad, msg in [("phi/alpha", "give a threshold"), ("overturned>1", "takes no threshold"),
                     ("width>=1", "is not a quantity"), ("phi>=-1", "out of range"), ("a:phi>1 b", "give")]:
        with pytest.raises(ValueError, match=msg):
            A.damage_state(bad)
    with pytest.raises(ValueError, match="two are named"):
        A.damage_states(["x:phi>0.1", "x:overturned"])


# --------------------------------------------------------------------------------------------- MSA
def test_msa_pipeline_fits_and_resumes(tmp_path):
    """4 records x 6 stripes: fits per damage state ordered by severity, bands, outputs; a rerun computes
    nothing, and after an interruption (rows lost) only the lost cases run again."""
    recs = [str(_suite(tmp_path / "r"))]
    levels = [0.8, 1.2, 1.6, 2.4, 3.2, 4.8]
    out = tmp_path / "msa.csv"
    r = A.run_msa(recs, ROCK, levels, out, n_boot=30, **BLOCK)
    assert r.summary["n_run"] == 24 and r.summary["n_errors"] == 0 and len(r.rows) == 24
    fits = {f.ds: f.fit for f in r.fragilities}
    assert list(fits) == list(A.DEFAULT_DAMAGE_STATES)
    thetas = [fits[k].theta for k in A.DEFAULT_DAMAGE_STATES]
    assert all(0.8 < t < 4.8 for t in thetas) and thetas == sorted(thetas)
    f0 = r.fragilities[2]
    assert f0.bands.n_boot == 30 and list(f0.observed[0]) == levels and list(f0.observed[1]) == [4] * 6
    assert list(f0.observed[2]) == [sum(row["overturned"] for row in r.rows if row["im_level"] == x) for x in levels]
    again = A.run_msa(recs, ROCK, levels, out, n_boot=30, **BLOCK)
    assert again.summary["n_run"] == 0 and again.summary["n_skipped"] == 24
    assert [f.fit.theta for f in again.fragilities] == [f.fit.theta for f in r.fragilities]
    lines = out.read_text().splitlines(keepends=True)
    out.write_text("".join(lines[:-5]) + lines[-5][:40])             # 5 rows lost, one cut mid-row
    with pytest.warns(E.RepairWarning):
        third = A.run_msa(recs, ROCK, levels, out, n_boot=0, **BLOCK)
    assert third.summary["n_run"] == 5 and len(third.rows) == 24
    written = A.write_fragilities(r.fragilities, tmp_path / "o", im_label=ROCK)
    assert [p.name for p in written] == ["fragility.csv", "fragility.json", "fragility.png"]
    js = json.loads((tmp_path / "o" / "fragility.json").read_text())
    assert [j["name"] for j in js] == list(A.DEFAULT_DAMAGE_STATES) and js[2]["theta_lo"] <= js[2]["theta"]


def test_msa_of_the_post_tensioned_block_on_its_tendon_force(tmp_path):
    """A tendon damage state: the rows carry the largest tendon force (at least P0), fitted like the others;
    several geometries give one fragility per geometry."""
    recs = [str(_suite(tmp_path / "r", 3))]
    r = A.run_msa(recs, "PGA", [2.0, 4.0, 8.0], tmp_path / "pt.csv", model="post_tensioned",
                  geometries=[(0.15, 1.0), (0.2, 1.0)], t_end=8.0, params={"m": 1000.0, "P0": 1e3, "k_t": 1e5},
                  damage_states=["tendon>=1.5e3", "overturned"], n_boot=0)
    assert all(row["max_tendon_force"] >= 1e3 for row in r.rows) and not any(row["error"] for row in r.rows)
    assert {f.group for f in r.fragilities} == {"b=0.15", "b=0.2"}
    assert {f.ds for f in r.fragilities} == {"tendon>=1.5e3", "overturned"}


# --------------------------------------------------------------------------------------------- IDA
def _sine_record(block, w_ratio):
    """One sine pulse, omega_p = w_ratio p, of amplitude g tan(alpha) (PGA/(g tan alpha) = 1), 4 s of rest."""
    wp = w_ratio * block.p
    T = 2 * math.pi / wp
    t = np.arange(int(round((T + 4.0) / (T / 400))) + 1) * (T / 400)        # (uniform: the measures need it)
    a = np.where(np.arange(t.size) < 400, np.sin(wp * t), 0.0) * block.g * math.tan(block.alpha)
    return t, a


def test_ida_finds_the_first_overturning_of_a_sine_pulse_within_its_tolerance(tmp_path):
    """A one-sine pulse (omega_p/p = 3) on the rigid block: the hunt-and-fill's first overturning lies within
    rtol above the threshold a direct bisection on the scale factor finds (1e-6)."""
    block = RigidBlock(b=0.2, h=1.0)
    t, a = _sine_record(block, 3.0)
    path = write_csv(tmp_path / "sine.csv", t, a, units="m/s2")
    t_end = float(t[-1]) + 15.0 / block.p

    def over(x):
        return bool(simulate(block, Record(t, a).scaled(x), t_end).overturned[-1])
    lo, hi = 1.0, 2.0
    assert not over(lo) and over(hi)
    while hi / lo > 1 + 1e-6:
        mid = math.sqrt(lo * hi)
        lo, hi = (lo, mid) if over(mid) else (mid, hi)
    r = A.run_ida([str(path)], ROCK, tmp_path / "ida.csv", start=0.8, rtol=0.005, n_boot=0,
                  geometries=[(0.2, 1.0)], t_end=t_end)
    (c,) = r.curves
    assert hi <= c.first_overturning <= hi * 1.005 + 1e-9
    assert c.bracket[0] < hi and c.first_overturning / c.bracket[0] <= 1.005 + 1e-12
    assert c.capacities["overturned"] == c.first_overturning
    # every run is a case of the output: a rerun replays them and runs nothing
    again = A.run_ida([str(path)], ROCK, tmp_path / "ida.csv", start=0.8, rtol=0.005, n_boot=0,
                      geometries=[(0.2, 1.0)], t_end=t_end)
    assert again.summary["n_run"] == 0 and again.curves[0].levels == c.levels


def test_ida_reports_the_non_overturning_pockets_above_the_first_overturning(tmp_path):
    """A synthetic record whose IDA curve is not monotonic: levels above the first overturning that do not
    overturn are reported in pockets, each checked against a direct simulation; the capacities are ordered
    and fitted."""
    recs = [str(_suite(tmp_path / "r"))]
    r = A.run_ida(recs, ROCK, tmp_path / "ida.csv", start=1.0, n_boot=20, **BLOCK)
    by = {c.record.rsplit("/", 1)[-1]: c for c in r.curves}
    c = by["r2.csv"]
    assert c.resurrections and all(lo > c.first_overturning for lo, _ in c.resurrections)
    block = RigidBlock(b=0.15, h=1.0)
    rows = {row["im_level"]: row for row in c.rows}
    for x in (c.first_overturning, c.resurrections[0][0]):
        motion = E.case_motion(rows[x])
        assert bool(simulate(block, motion, 8.0).overturned[-1]) == (x == c.first_overturning)
    for c in r.curves:
        caps = [c.capacities[k] for k in A.DEFAULT_DAMAGE_STATES]
        assert caps == sorted(caps) and caps[-1] == c.first_overturning and len(c.levels) <= 30
    fits = {f.ds: f.fit for f in r.fragilities}
    assert all(f.method == "ida_moments" and 1.0 < f.theta < 4.0 for f in fits.values())
    path = A.write_curves(r.curves, tmp_path / "curves.csv")
    rows = list(csv.DictReader(path.open()))
    assert len(rows) == 4 and rows[2]["resurrections"]


# --------------------------------------------------------------------------------------------- CLI
def test_cli_fragility_end_to_end(tmp_path, capsys):
    recs = str(_suite(tmp_path / "r", 3))
    argv = ["fragility", "--records", recs, "--im", ROCK, "--b", "0.15", "--h", "1.0", "--t-end", "8",
            "--workers", "0", "--no-progress", "--bootstrap", "20", "--damage-states", "rock:phi/alpha>=0.3",
            "overturned"]
    assert main(argv + ["--stripes", "1:4:4", "--out", str(tmp_path / "msa")]) == 0
    out = capsys.readouterr().out
    assert "ran 12 cases (0 already" in out and "rock: theta = " in out
    assert {p.name for p in (tmp_path / "msa").iterdir()} >= {"cases.csv", "fragility.csv", "fragility.json",
                                                               "fragility.png"}
    assert main(argv + ["--stripes", "1:4:4", "--out", str(tmp_path / "msa")]) == 0
    assert "ran 0 cases (12 already" in capsys.readouterr().out
    assert main(argv + ["--ida", "1", "--ida-max-runs", "12", "--out", str(tmp_path / "ida"), "--no-plot"]) == 0
    out = capsys.readouterr().out
    assert "first overturning at" in out and (tmp_path / "ida" / "ida_curves.csv").exists()
    assert not (tmp_path / "ida" / "fragility.png").exists()


@pytest.mark.parametrize("extra, msg", [
    ([], "give either --stripes LEVEL... (multiple-stripe analysis) or --ida START"),
    (["--stripes", "1", "--ida", "1"], "give either --stripes"),
    (["--stripes", "1", "--im", "D5_95"], "im = 'D5_95' does not change when a record is scaled"),
    (["--stripes", "1", "--damage-states", "phi>"], "damage state 'phi>': give [name:]quantity>=value"),
    (["--stripes", "1", "--k-t", "1"], "--k-t is not a parameter of the rigid model"),
])
def test_cli_fragility_errors_are_one_line(tmp_path, capsys, extra, msg):
    assert main(["fragility", "--records", "synthetic:1", "--workers", "0", "--out", str(tmp_path)] + extra) == 2
    err = capsys.readouterr().err
    assert err.startswith("rocking fragility: error: ") and msg in err and err.count("\n") == 1


def test_example_fragility_runs_shortened(tmp_path):
    """examples/fragility.py on 3 records of 6 s x 5 stripes, serially: three fitted damage states and the
    plot in the directory given."""
    import importlib.util
    from pathlib import Path

    path = Path(__file__).resolve().parents[1] / "examples" / "fragility.py"
    spec = importlib.util.spec_from_file_location("example_fragility", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    assert mod.main([str(tmp_path), "--records", "3", "--stripes", "5", "--duration", "6", "--workers", "0",
                     "--bootstrap", "10"]) == 0
    fits = json.loads((tmp_path / "fragility.json").read_text())
    assert [f["name"] for f in fits] == ["phi/alpha>=0.2", "phi/alpha>=0.5", "overturned"]
    assert (tmp_path / "fragility.png").stat().st_size > 10_000
