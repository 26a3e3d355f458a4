"""Session fixtures shared by the test modules: the FMUs are built once per session.

``built_fmus`` -> {FMU name: path of the .fmu} of every FMU of fmu_src/, built by build_fmu.py into a
session folder; ``build_module`` -> the imported build_fmu module; ``extracted_fmus`` -> {name: (path,
model description, unzipped folder)}. The FMUs are read-only for the tests: a test that needs to alter one
copies it first.
"""
from __future__ import annotations

import sys
from pathlib import Path

import pytest

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
for _p in (str(HERE), str(ROOT)):
    if _p not in sys.path:
        sys.path.insert(0, _p)


@pytest.fixture(scope="session")
def build_module():
    """build_fmu.py, imported once."""
    import build_fmu
    return build_fmu


@pytest.fixture(scope="session")
def built_fmus(build_module, tmp_path_factory) -> dict:
    """Every FMU of fmu_src/, built once per session: {name: Path}."""
    pytest.importorskip("pythonfmu")
    dest = tmp_path_factory.mktemp("fmus")
    return {p.stem: p for p in build_module.build_all(dest)}


@pytest.fixture(scope="session")
def extracted_fmus(built_fmus, tmp_path_factory) -> dict:
    """{name: (path, model description, unzipped folder)} of the session's FMUs, extracted once."""
    fmpy = pytest.importorskip("fmpy")
    root = tmp_path_factory.mktemp("fmus_unzipped")
    return {name: (path, fmpy.read_model_description(str(path)),
                   fmpy.extract(str(path), unzipdir=str(root / name)))
            for name, path in built_fmus.items()}


@pytest.fixture
def run_sh_stubbed(tmp_path):
    """``run(command)``: ``bash run.sh <command>`` with a stand-in interpreter whose every call is only logged;
    returns (the finished process, the logged calls' argument lines)."""
    import os
    import subprocess

    def run(command: str):
        venv = tmp_path / "venv"
        (venv / "bin").mkdir(parents=True, exist_ok=True)
        log = tmp_path / "calls.txt"
        stub = venv / "bin" / "python"
        stub.write_text(f"#!/bin/sh\necho \"$*\" >> '{log}'\n")
        stub.chmod(0o755)
        proc = subprocess.run(["bash", str(ROOT / "run.sh"), command], env={**os.environ, "VENV": str(venv)},
                              capture_output=True, text=True, timeout=60)
        return proc, (log.read_text().splitlines() if log.exists() else [])
    return run


def pytest_terminal_summary(terminalreporter):
    """A visible line when the bit-for-bit golden comparison was skipped on this CPU (tests/test_golden.py):
    a skip is otherwise one letter among the dots."""
    mod = sys.modules.get("test_golden")
    for reason in getattr(mod, "GOLDEN_NOTICES", []):
        terminalreporter.write_sep("-", "golden outputs", yellow=True)
        terminalreporter.write_line(reason, yellow=True)
