"""A non-Python FMI host: tests/c/host.c dlopens the FMU binary, instantiates it with the resources of the
unzipped FMU (file:// URI), sets ag, steps 1 s and prints phi; the result must equal fmpy's.

The FMU's binary loads libpython itself (the path recorded at build time, or ROCKING_FMU_LIBPYTHON) and
finds numpy through the build environment's site-packages: the host runs with an empty environment (only
PATH and HOME), without LD_PRELOAD or PYTHONPATH. Skipped without a C compiler or a shared libpython.
"""
from __future__ import annotations

import os
import platform
import shutil
import subprocess
import sys
import sysconfig
import zipfile
from pathlib import Path

import numpy as np
import pytest

fmpy = pytest.importorskip("fmpy")
pytest.importorskip("pythonfmu")
from fmpy import read_model_description  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
HOST_C = ROOT / "tests" / "c" / "host.c"
CC = os.environ.get("CC") or shutil.which("cc") or shutil.which("gcc")

pytestmark = [
    pytest.mark.skipif(CC is None, reason="no C compiler (cc/gcc) on PATH"),
    pytest.mark.skipif(not (sys.platform.startswith("linux") and platform.machine() in ("x86_64", "AMD64")),
                       reason="the FMUs carry linux64 binaries only"),
]


def libpython() -> Path | None:
    """The shared libpython of this interpreter (what LD_PRELOAD needs), or None."""
    name = sysconfig.get_config_var("LDLIBRARY") or ""
    for folder in (sysconfig.get_config_var("LIBDIR"), sysconfig.get_config_var("LIBPL")):
        if folder and (name.endswith(".so") or ".so." in name):
            path = Path(folder) / name
            if path.is_file():
                return path
    return None


@pytest.fixture(scope="module")
def host(tmp_path_factory) -> Path:
    headers = Path(fmpy.__file__).parent / "c-code"
    if not (headers / "fmi2Functions.h").is_file():
        pytest.skip("fmpy does not ship the FMI 2.0 headers (fmpy/c-code)")
    exe = tmp_path_factory.mktemp("host") / "host"
    subprocess.run([CC, "-std=c99", "-O1", "-Wall", f"-I{headers}", str(HOST_C), "-o", str(exe),
                    "-ldl"], check=True, capture_output=True, text=True)
    return exe


@pytest.fixture(scope="module")
def fmus(built_fmus):
    return built_fmus


def run_host(host: Path, fmu: Path, tmp: Path, ag: float, t_end: float, dt: float, folder: str = "",
             **env_extra):
    if libpython() is None:
        pytest.skip("this Python has no shared libpython (built without --enable-shared)")
    unzip = tmp / (folder or fmu.stem)
    with zipfile.ZipFile(fmu) as zf:
        zf.extractall(unzip)
    md = read_model_description(str(fmu))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    env = {"PATH": os.environ.get("PATH", "/usr/bin:/bin"), "HOME": os.environ.get("HOME", "/"), **env_extra}
    return subprocess.run([str(host), str(unzip), md.coSimulation.modelIdentifier, md.guid, str(vr["ag"]),
                           str(vr["phi"]), repr(ag), repr(t_end), repr(dt)], env=env, capture_output=True,
                          text=True, timeout=120)


@pytest.mark.parametrize("name, ag", [("RigidRockingBlock", 3.0), ("FlexibleRockingOscillator", 4.0)])
def test_c_host_matches_fmpy(host, fmus, tmp_path, name, ag):
    proc = run_host(host, fmus[name], tmp_path, ag, 1.0, 0.01)
    assert proc.returncode == 0, proc.stderr
    rows = np.array([[float(x) for x in line.split(",")] for line in proc.stdout.split()])
    assert rows.shape == (100, 2)
    table = np.array([(0.0, ag), (1.0, ag)], dtype=[("time", float), ("ag", float)])
    ref = fmpy.simulate_fmu(str(fmus[name]), stop_time=1.0, output_interval=0.01, input=table, output=["phi"])
    np.testing.assert_allclose(rows[:, 0], ref["time"][1:], rtol=0, atol=1e-12)
    assert abs(ref["phi"][-1]) > 0.01  # it rocks
    np.testing.assert_allclose(rows[:, 1], ref["phi"][1:], rtol=0, atol=1e-12)


def test_libpython_override(host, fmus, tmp_path):
    """ROCKING_FMU_LIBPYTHON replaces the recorded libpython: a missing file is a clear fmi2Instantiate
    failure (NULL, the message names the file and the variable); the real library works."""
    missing = tmp_path / "no" / "libpython3.so"
    proc = run_host(host, fmus["RigidRockingBlock"], tmp_path, 3.0, 0.1, 0.01, ROCKING_FMU_LIBPYTHON=str(missing))
    assert proc.returncode == 3, proc.stderr
    assert f"cannot load the Python library {missing}" in proc.stderr and "ROCKING_FMU_LIBPYTHON" in proc.stderr
    assert "fmi2Instantiate failed" in proc.stderr
    proc = run_host(host, fmus["RigidRockingBlock"], tmp_path / "ok", 3.0, 0.1, 0.01,
                    ROCKING_FMU_LIBPYTHON=str(libpython()))
    assert proc.returncode == 0, proc.stderr
    assert len(proc.stdout.split()) == 10


def test_c_host_in_a_folder_with_special_characters(host, fmus, tmp_path):
    """The host builds the resource URI by hand (file://<path>/resources, nothing escaped): an extraction
    folder with é, #, [ and spaces works (fmpy's percent-encoded URIs are covered by the fault suite)."""
    proc = run_host(host, fmus["RigidRockingBlock"], tmp_path, 3.0, 0.1, 0.01, folder="dir é # [ x")
    assert proc.returncode == 0, proc.stderr
    assert len(proc.stdout.split()) == 10
