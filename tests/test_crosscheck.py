"""Cross-check folders written by build_fmu.py (FMI cross-check layout) and their re-simulation with fmpy."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

fmpy = pytest.importorskip("fmpy")
pytest.importorskip("pythonfmu")
from fmpy.cross_check.validate_vendor_repo import read_csv, validate_test_fmu  # noqa: E402
from fmpy.util import read_ref_opt_file  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
NAMES = ["RigidRockingBlock", "FlexibleRockingOscillator", "PostTensionedRockingBlock", "GroundMotionSource",
         "LinearBuildingStorey"]


@pytest.fixture(scope="module")
def build(build_module):
    return build_module


@pytest.fixture(scope="module")
def dist(build, built_fmus, tmp_path_factory):
    """The cross-check folders of the session's FMUs, as ``build_all(cross_check=True)`` writes them."""
    dest = tmp_path_factory.mktemp("dist_cc")
    for name in NAMES:
        build.write_cross_check(built_fmus[name], dest / build.CROSS_CHECK_DIR)
    return dest


def folders(build, dist):
    return {name: build.cross_check_dir(dist / "cross-check", name) for name in NAMES}


def test_every_fmu_has_a_valid_cross_check_folder(build, dist):
    for name, folder in folders(build, dist).items():
        assert folder.parts[-7:-3] == ("fmus", "2.0", "cs", "linux64")
        files = {p.name for p in folder.iterdir()}
        expected = {f"{name}.fmu", f"{name}_ref.csv", f"{name}_ref.opt", "ReadMe.md"}
        if name != "GroundMotionSource":
            expected.add(f"{name}_in.csv")
        assert files == expected, name
        assert validate_test_fmu(str(folder)) == [], name  # fmpy's checker of the cross-check rules
        opts = read_ref_opt_file(str(folder / f"{name}_ref.opt"))
        assert opts["StartTime"] == 0.0 and opts["StepSize"] == 0.01 and opts["StopTime"] >= 2.0
        header = (folder / f"{name}_ref.csv").read_text().splitlines()[0].split(",")
        assert header[0] == '"time"' and all(h.startswith('"') and h.endswith('"') for h in header)


def _resimulate(folder: Path, name: str, start_values=None):
    opts = read_ref_opt_file(str(folder / f"{name}_ref.opt"))
    ref = read_csv(str(folder / f"{name}_ref.csv"))
    in_csv = folder / f"{name}_in.csv"
    table = read_csv(str(in_csv)) if in_csv.exists() else None
    res = fmpy.simulate_fmu(str(folder / f"{name}.fmu"), start_time=opts["StartTime"], stop_time=opts["StopTime"],
                            output_interval=opts["StepSize"], relative_tolerance=opts["RelTol"], input=table,
                            output=list(ref.dtype.names[1:]), start_values=start_values or {})
    return ref, res


@pytest.mark.parametrize("name", NAMES)
def test_resimulation_from_in_csv_reproduces_ref_csv(build, dist, name):
    folder = folders(build, dist)[name]
    ref, res = _resimulate(folder, name)
    assert len(res) == len(ref) == int(round(ref["time"][-1] / 0.01)) + 1
    np.testing.assert_array_equal(res["time"], ref["time"])
    moving = [n for n in ref.dtype.names[1:] if np.abs(ref[n]).max() > 0]
    assert moving  # the scenario excites the FMU
    for n in ref.dtype.names[1:]:
        np.testing.assert_allclose(res[n].astype(float), ref[n], rtol=1e-13, atol=1e-15, err_msg=n)


def test_comparison_detects_a_different_model(build, dist):
    folder = folders(build, dist)["RigidRockingBlock"]
    ref, res = _resimulate(folder, "RigidRockingBlock", start_values={"b": 0.21})
    assert np.abs(res["phi"] - ref["phi"]).max() > 1e-3
