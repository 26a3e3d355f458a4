"""`rocking build-fmu` from an installed (non-editable) wheel, run outside the checkout: the package carries
everything the build needs (the FMI layer's C sources, the engine's sources with its generated kernels, the
slave classes), so both kinds of FMU come out and run.

The wheel is built from a copy of the package's sources (pip wheel: the checkout's build/ folder, stale
or not, plays no part), installed into a fresh venv whose only other packages are this interpreter's (a .pth
file: numpy, fmpy, pythonfmu, ...; the checkout is not on its path), and the command runs there with the
working directory in a temporary folder."""
from __future__ import annotations

import os
import shutil
import site
import subprocess
import sys
import sysconfig
import zipfile
from pathlib import Path

import numpy as np
import pytest

fmpy = pytest.importorskip("fmpy")
pytest.importorskip("pythonfmu")

ROOT = Path(__file__).resolve().parents[1]
CC = os.environ.get("CC") or shutil.which("cc") or shutil.which("gcc") or shutil.which("clang")
RIGID = "RigidRockingBlock"

pytestmark = [
    pytest.mark.slow,
    pytest.mark.skipif(CC is None, reason="needs a C compiler (the wheel's extension and the FMU binaries)"),
    pytest.mark.skipif(not (Path(sysconfig.get_paths()["include"]) / "Python.h").is_file(),
                       reason="needs the Python headers (Python.h) to build the wheel's extension"),
    pytest.mark.skipif(not sys.platform.startswith("linux"), reason="the venv layout and binaries of Linux"),
]

#: what the wheel is built from: the package and its build configuration (no tests, no benchmarks)
SOURCES = ("pyproject.toml", "setup.py", "MANIFEST.in", "README.md", "rocking_model")
_IGNORE = shutil.ignore_patterns("__pycache__", "*.pyc", "*.so", "*.egg-info", "build")


def _run(cmd, **kw):
    proc = subprocess.run(cmd, capture_output=True, text=True, **kw)
    assert proc.returncode == 0, f"{' '.join(map(str, cmd))} failed:\n{proc.stdout[-3000:]}\n{proc.stderr[-3000:]}"
    return proc


@pytest.fixture(scope="module")
def wheel(tmp_path_factory) -> Path:
    src = tmp_path_factory.mktemp("wheel_src")
    for name in SOURCES:
        path = ROOT / name
        (shutil.copytree(path, src / name, ignore=_IGNORE) if path.is_dir() else shutil.copy2(path, src / name))
    out = tmp_path_factory.mktemp("wheel")
    # build isolation: the build requirements come from the configured index (a local one here), as for a user
    _run([sys.executable, "-m", "pip", "wheel", "--no-deps", "-q", "-w", str(out), str(src)], timeout=600)
    (whl,) = out.glob("rocking_model-*.whl")
    return whl


@pytest.fixture(scope="module")
def venv(wheel, tmp_path_factory) -> Path:
    """A fresh venv with the wheel installed; numpy & co. from this interpreter's site-packages."""
    env_dir = tmp_path_factory.mktemp("venv") / "env"
    _run([sys.executable, "-m", "venv", "--without-pip", str(env_dir)], timeout=120)
    python = env_dir / "bin" / "python"
    purelib = Path(_run([str(python), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"])
                   .stdout.strip())
    ours = {sysconfig.get_paths()["purelib"], sysconfig.get_paths()["platlib"], *site.getsitepackages()}
    # appended after the venv's own site-packages: the installed wheel wins over anything found there
    (purelib / "_test_deps.pth").write_text("".join(f"{p}\n" for p in sorted(ours) if os.path.isdir(p)))
    _run([sys.executable, "-m", "pip", "--python", str(python), "install", "-q", "--no-deps", "--no-index",
          str(wheel)], timeout=300)
    return env_dir


def _clean_env() -> dict:
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONHOME", "PYTHONSAFEPATH")}
    env["PYTHONNOUSERSITE"] = "1"
    env["ROCKING_FMU_PLATFORMS"] = "linux64"   # the cross binaries: tests/test_cross_platform.py
    return env


def test_wheel_carries_the_build_sources_and_no_test_entry_points(wheel):
    names = set(zipfile.ZipFile(wheel).namelist())
    for required in ("rocking_model/fmi/build.py", "rocking_model/fmi/fmus.py",
                     "rocking_model/fmi/binary/fmi2_cs.c", "rocking_model/fmi/binary/pyapi.h",
                     "rocking_model/fmi/binary/fmi2_pyhost.py", "rocking_model/fmi/binary/standalone/fmi2_engine.c",
                     "rocking_model/engine/src/rk_engine.c", "rocking_model/engine/src/rk_models_gen.c",
                     "rocking_model/engine/src/rk_tableaux.h"):
        assert required in names, required
    assert not [n for n in names if n.startswith("rocking_model/engine/py/") and n.endswith(".c")]
    assert not [n for n in names if "__pycache__" in n or n.endswith(".pyc")]


def test_rocking_build_fmu_from_the_installed_wheel(venv, tmp_path):
    """Outside the checkout, the installed `rocking build-fmu --dest` builds every FMU of both kinds; the
    pythonfmu FMU and the standalone one of the rigid block simulate through fmpy (in this process)."""
    work = tmp_path / "elsewhere"
    work.mkdir()
    env = _clean_env()
    where = _run([str(venv / "bin" / "python"), "-c", "import rocking_model; print(rocking_model.__file__)"],
                 cwd=work, env=env).stdout.strip()
    assert Path(where).is_relative_to(venv), where      # the installed copy, not the checkout's
    dest = work / "fmus"
    proc = _run([str(venv / "bin" / "rocking"), "build-fmu", "--dest", str(dest), "--no-cross-check"],
                cwd=work, env=env, timeout=600)
    from rocking_model.fmi.fmus import FMUS
    from rocking_model.models import MODELS

    for name in FMUS:
        assert (dest / f"{name}.fmu").is_file(), proc.stdout
    for cls in MODELS.values():
        assert (dest / "standalone" / f"{cls.fmu_name}.fmu").is_file(), proc.stdout
    assert "built and validated" in proc.stdout

    # the build used the installed package: its bundled copy has the installed sources' digest
    with zipfile.ZipFile(dest / f"{RIGID}.fmu") as zf:
        script = zf.read(f"resources/{RIGID}.py").decode()
    assert "from rocking_model_" in script and f"import {RIGID}" in script

    table = np.array([(0.0, 2.5), (0.5, 2.5), (0.51, 0.0), (1.0, 0.0)], dtype=[("time", float), ("ag", float)])
    for fmu in (dest / f"{RIGID}.fmu", dest / "standalone" / f"{RIGID}.fmu"):
        res = fmpy.simulate_fmu(str(fmu), stop_time=1.0, output_interval=0.01, input=table, output=["phi"])
        assert res["time"][-1] == pytest.approx(1.0)
        assert np.all(np.isfinite(res["phi"])) and np.max(np.abs(res["phi"])) > 0.0, fmu
