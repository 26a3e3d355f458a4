"""What an import pulls in (cold start): the package's names are imported on first use (PEP 562), the
compiled engine's low-level API needs neither numpy nor the Python engine, and the optional heavy dependencies
(scipy, matplotlib, dask, fmpy) are imported only where they are used. Each check runs in a fresh interpreter
(sys.modules of this one holds whatever the other tests imported); not timed."""
from __future__ import annotations

import json
import subprocess
import sys

import pytest

#: [s] bound on one fresh interpreter (an import takes well under a second)
SUBPROCESS_TIMEOUT = 60

OPTIONAL_HEAVY = ("scipy", "matplotlib", "dask", "distributed", "fmpy", "pandas", "pyarrow")


def _modules_after(code: str) -> set:
    script = code + "\nimport json, sys\nprint(json.dumps(sorted(sys.modules)))"
    r = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=SUBPROCESS_TIMEOUT)
    assert r.returncode == 0, r.stderr
    return set(json.loads(r.stdout.strip().splitlines()[-1]))


def _top(modules: set) -> set:
    return {m.split(".")[0] for m in modules}


def test_low_level_engine_imports_neither_numpy_nor_the_python_engine():
    mods = _modules_after("from rocking_model._engine import Engine, model_kinds\n"
                          "e = Engine('rigid', [0.4, 2.0, 1.0, 9.81, 0.0, 0.0, float('inf')], scheme=1)\n"
                          "e.advance(0.05, 5.0)\n"
                          "assert e.output_dict()['phi'] != 0.0")
    assert not _top(mods) & {"numpy", *OPTIONAL_HEAVY}
    # (the extension and its cffi-bound cold part)
    assert {m for m in mods if m.startswith("rocking_model")} == {"rocking_model", "rocking_model._engine",
                                                                  "rocking_model._engine_cold", "rocking_model._rk",
                                                                  "rocking_model._rk.lib"}


def test_package_import_is_lazy():
    mods = _modules_after("import rocking_model")
    assert not _top(mods) & {"numpy", *OPTIONAL_HEAVY}
    assert {m for m in mods if m.startswith("rocking_model")} == {"rocking_model"}


@pytest.mark.parametrize("names", ["RigidBlock, Simulator, simulate", "*", "SinePulse, Record, ContactTolerances"])
def test_public_names_do_not_import_optional_dependencies(names):
    mods = _modules_after(f"from rocking_model import {names}")
    assert not _top(mods) & set(OPTIONAL_HEAVY)


def test_public_names_resolve():
    import rocking_model

    for name in rocking_model.__all__:
        assert getattr(rocking_model, name) is not None
    assert set(rocking_model.__all__) <= set(dir(rocking_model))
    with pytest.raises(AttributeError, match="no attribute 'no_such_name'"):
        rocking_model.no_such_name  # noqa: B018
