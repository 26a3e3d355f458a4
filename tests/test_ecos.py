"""A third importer: Ecos (C++, FMI 1/2, SSP 1.0; ``pip install rocking-model[ecos]``, whose prebuilt binary
needs Debian's libtbb12). The rocking FMUs -- the pythonfmu ones and the self-contained ones --
and the system example's SSP archive run in Ecos with the results of the project's fmpy master.

Ecos counts time in doubles (t += h) where fmpy's master and libcosim count integer nanoseconds, so the
communication points can differ in the last bits: the results are compared to round-off, not bit for bit.
"""
from __future__ import annotations

import importlib.util
import math
import os
import shutil
import stat
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("fmpy")
pytest.importorskip("pythonfmu")
try:
    import ecospy  # noqa: F401  (loads Ecos' shared library: fails without libtbb12)
except ImportError as exc:  # pragma: no cover - depends on the machine
    reason = (f"Ecos' library cannot be loaded ({exc}): install Debian's libtbb12 (apt-get install libtbb12)"
              if "libtbb" in str(exc) else
              f"ecospy is not installed ({exc}): pip install 'rocking-model[ecos]' (and Debian's libtbb12)")
    pytest.skip(reason, allow_module_level=True)
except OSError as exc:  # pragma: no cover - depends on the machine
    pytest.skip(f"Ecos' library cannot be loaded ({exc}): install Debian's libtbb12 (apt-get install libtbb12)",
                allow_module_level=True)

from rocking_model.cosim import Component, System, read_osp_system_structure, run_ecos, run_fmpy  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "examples" / "system"
#: [1] Ecos against the fmpy master, relative to each output's peak: the same algorithm, with Ecos'
#: communication points t += h differing from t0 + n h in the last bits, which the flexible oscillator's
#: contact events amplify (measured: 1.3e-9 of the peak for its u_dot over 2 s, ~1e-14 for the rigid block
#: and the system example)
ECOS_REL = 1e-8


def assert_close(actual, desired, err_msg):
    atol = ECOS_REL * max(float(np.abs(desired).max()), 1e-300)
    np.testing.assert_allclose(actual, desired, rtol=0, atol=atol, err_msg=err_msg)

RIGID_OUT = ["phi", "phi_dot", "x", "y", "energy", "contact", "impacts", "overturned"]
FLEX_OUT = ["u", "u_dot", "phi", "phi_dot", "top_displacement", "energy", "contact", "impacts"]


def _load(name, path):
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def standalone(build_module, tmp_path_factory):
    import fault_harness as fh

    try:
        return fh.standalone_fmus(build_module, tmp_path_factory)
    except Exception as exc:
        pytest.skip(f"the self-contained FMUs could not be built: {exc!r}")


@pytest.fixture(scope="module")
def kinds(built_fmus, standalone):
    return {"pythonfmu": built_fmus, "standalone": {**built_fmus, **standalone}}


@pytest.fixture()
def proxyfmu_on_path(tmp_path, monkeypatch):
    """Ecos starts its per-process proxy ``proxyfmu`` through PATH; the wheel installs the binary without
    its execute bit, so a copy with the bit set goes first on PATH (the installed package is not changed)."""
    src = Path(ecospy.__file__).parent / "binaries" / "proxyfmu"
    if not src.is_file():
        pytest.skip(f"ecospy has no proxyfmu binary at {src}")
    dest = tmp_path / "bin" / "proxyfmu"
    dest.parent.mkdir()
    shutil.copy2(src, dest)
    dest.chmod(dest.stat().st_mode | stat.S_IXUSR)
    monkeypatch.setenv("PATH", f"{dest.parent}{os.pathsep}{os.environ.get('PATH', '')}")


def pulse(A, period=1.0):
    return lambda t: A * math.sin(2 * math.pi * t / period) if t < period else 0.0


CASES = [("RigidRockingBlock", 2.5, RIGID_OUT), ("FlexibleRockingOscillator", 3.0, FLEX_OUT)]


@pytest.mark.parametrize("kind", ["pythonfmu", "standalone"])
@pytest.mark.parametrize("name, A, outputs", CASES, ids=[c[0] for c in CASES])
def test_fmu_in_ecos_matches_fmpy(kinds, kind, name, A, outputs):
    """Each rocking FMU in Ecos, ag set before every step: the fmpy master's outputs to round-off."""
    system = System([Component("m", kinds[kind][name], start_values={"scheme": 1})], [], step_size=0.01)
    keys = [f"m.{k}" for k in outputs]
    ag = pulse(A)
    ecos = run_ecos(system, 2.0, keys, inputs={"m.ag": ag})
    master = run_fmpy(system, 2.0, keys, inputs={"m.ag": ag})
    assert len(ecos) == 200 and len(master) == 201
    np.testing.assert_allclose(ecos["time"], master["time"][1:], rtol=0, atol=1e-12)
    assert np.abs(ecos["m.phi"]).max() > 0.02 and ecos["m.impacts"][-1] >= 1  # it rocks and impacts
    for k in keys:
        assert_close(ecos[k], master[k][1:], err_msg=k)


def test_standalone_fmu_in_ecos_proxyfmu_process(kinds, proxyfmu_on_path):
    """The self-contained block in Ecos' proxyfmu, a C++ process of its own with no Python in it: the
    results of the in-process run (the pythonfmu FMU there would need a CPython with numpy)."""
    system = System([Component("m", kinds["standalone"]["RigidRockingBlock"])], [], step_size=0.01)
    keys = ["m.phi", "m.impacts"]
    ag = pulse(2.5)
    inproc = run_ecos(system, 2.0, keys, inputs={"m.ag": ag})
    proxied = run_ecos(system, 2.0, keys, inputs={"m.ag": ag}, proxy=True)
    assert np.abs(proxied["m.phi"]).max() > 0.02
    for k in keys:
        np.testing.assert_array_equal(proxied[k], inproc[k], err_msg=k)


@pytest.mark.parametrize("kind", ["pythonfmu", "standalone"])
def test_system_ssp_in_ecos_matches_the_fmpy_master(kinds, kind, tmp_path):
    """The system example packaged as an SSP 1.0 archive (with the pythonfmu or the self-contained block and
    oscillator) runs in Ecos from the archive (Ecos' own SSP loader: components, connections, the parameter
    set) with the fmpy master's results on the OSP file to round-off."""
    text = (EXAMPLE / "OspSystemStructure.xml").read_text()
    for name, path in kinds[kind].items():
        text = text.replace(f"../../dist/{name}.fmu", str(path))
    osp = tmp_path / "OspSystemStructure.xml"
    osp.write_text(text)
    example = _load("system_example", EXAMPLE / "run.py")
    ssp = example.write_ssp(tmp_path / "RockingSystem.ssp", osp=osp)
    stop = 1.0
    master = run_fmpy(osp, stop, example.OUTPUTS)
    ecos = run_ecos(ssp, stop, example.OUTPUTS)
    assert len(ecos) == len(master) - 1
    assert np.abs(ecos["block.phi"]).max() > 0.05  # the archive's parameters reached the FMUs in Ecos
    for k in example.OUTPUTS:
        assert_close(ecos[k], master[k][1:], err_msg=k)
    # the same system given to Ecos as a structure (not the archive) gives the same values
    structure = run_ecos(read_osp_system_structure(osp), stop, example.OUTPUTS)
    for k in example.OUTPUTS:
        np.testing.assert_array_equal(structure[k], ecos[k], err_msg=k)
