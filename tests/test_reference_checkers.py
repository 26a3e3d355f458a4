"""The reference checkers on every FMU the project builds: the FMU Compliance Checker
(fmuCheck.linux64) and Reference-FMUs' fmusim (v0.0.39) must run both kinds of FMU on their cross-check scenes
with no error or warning and give fmpy's results (tests/reference_checkers.py). Runs where the checkers are on
PATH or named by $FMUCHECK / $FMUSIM; skips otherwise (how to build them offline: docs/reference-checkers.md)."""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
import reference_checkers as rc  # noqa: E402

sys.path.remove(str(HERE))


def test_reference_checkers_accept_every_fmu(built_fmus, build_module, tmp_path_factory):
    tools = [n for n in rc.TOOLS if rc.find_tool(n)]
    if not tools:
        pytest.skip(f"neither fmuCheck.linux64 nor fmusim is installed: {rc.HOWTO}")
    folder = Path(next(iter(built_fmus.values()))).parent
    if not list((folder / "standalone").glob("*.fmu")):
        build_module.build_standalone(folder)
    proc = subprocess.run([sys.executable, str(HERE / "reference_checkers.py"), "--fmus", str(folder),
                           "--out", str(tmp_path_factory.mktemp("checkers"))], capture_output=True, text=True)
    print(proc.stdout)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert proc.stdout.count(" OK: ") == len(tools) * len(list(folder.glob("*.fmu")) +
                                                           list((folder / "standalone").glob("*.fmu")))
