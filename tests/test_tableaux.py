"""The Runge-Kutta tableaux the C engine is generated from (rocking_model/engine/tableaux.py, plain data read by
gen_rk.py at build time) are scipy's DOP853 and RK45 coefficients, and the generated header holds them."""
from __future__ import annotations

import importlib.util
import os

import numpy as np
import pytest

import rocking_model

ENGINE_DIR = os.path.join(os.path.dirname(rocking_model.__file__), "engine")


def _module(name):
    spec = importlib.util.spec_from_file_location(f"{name}_under_test", os.path.join(ENGINE_DIR, f"{name}.py"))
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _padded(rows, width):
    return np.array([list(r) + [0.0] * (width - len(r)) for r in rows])


def test_dop853_is_scipys():
    coef = pytest.importorskip("scipy.integrate._ivp.dop853_coefficients")
    tab = _module("tableaux").DOP853
    assert np.array_equal(_padded(tab.A, 16), coef.A)
    assert np.array_equal(tab.B, coef.B) and np.array_equal(tab.C, coef.C)
    assert np.array_equal(tab.E3, coef.E3) and np.array_equal(tab.E5, coef.E5)
    assert np.array_equal(tab.D, coef.D)
    assert tab.n_stages == coef.N_STAGES + 1


def test_dopri5_is_scipys_rk45():
    from scipy.integrate import RK45

    tab = _module("tableaux").DOPRI5
    assert np.array_equal(_padded(tab.A[:6], 5), RK45.A)
    assert np.array_equal(tab.A[6], RK45.B) and np.array_equal(tab.B, RK45.B)
    assert np.array_equal(tab.C[:6], RK45.C) and tab.C[6] == 1.0
    assert np.array_equal(tab.E, RK45.E)
    assert np.array_equal(np.array(tab.P).T, RK45.P)


def test_the_generator_reads_them_without_importing_them():
    """gen_rk.py reads tableaux.py with ast (the build environment has no numpy) and writes the same numbers."""
    gen = _module("gen_rk")
    tabs = _module("tableaux")
    for name in ("DOP853", "DOPRI5"):
        tab, ref = gen.read_tableau(name), getattr(tabs, name)
        for key in ("A", "B", "C"):
            assert tab[key] == list(getattr(ref, key)), (name, key)
        assert tab["errors"] == [getattr(ref, e) for e in ref.error_rows]
        assert tab["dense"] == getattr(ref, ref.dense_rows)
        gen.check(tab)


def test_the_generated_header_is_current(tmp_path):
    """The header the build wrote is what gen_rk.py writes from tableaux.py now (hexadecimal literals: exact)."""
    gen = _module("gen_rk")
    out = tmp_path / "rk_tableaux.h"
    gen.generate(str(out))
    header = os.path.join(ENGINE_DIR, "src", "rk_tableaux.h")
    if not os.path.exists(header):
        pytest.skip("no generated header next to the sources (an installed wheel)")
    with open(header, encoding="utf-8") as fh:
        assert out.read_text(encoding="utf-8") == fh.read()
    assert float.hex(_module("tableaux").DOP853.E5[5]) in out.read_text(encoding="utf-8")
