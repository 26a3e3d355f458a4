"""Adding a model, as docs/architecture.md describes it: one file declares it, and it runs in both schemes and builds both
FMU kinds, with no C written for it.

The model here is new to the package: a rigid block carrying a lumped mass m_top at the centre of its top face
(a block with a heavy cap). Its uplift threshold under a constant ground acceleration is the closed form
ag* = g b / h_G with h_G = (m h + m_top 2 h)/(m + m_top) the height of the combined centre of mass above the
base; its FMUs must reproduce `simulate` under the same held input.
"""
from __future__ import annotations

import importlib.util
import math
import sys
import textwrap

import numpy as np
import pytest

MODEL_FILE = textwrap.dedent('''
    """A rigid block with a lumped mass on its top face: declared in this one file."""
    from dataclasses import dataclass, field
    from typing import ClassVar

    from rocking_model.fmi import DefaultExperiment, ModelSlave
    from rocking_model.models import register_model
    from rocking_model.models.base import (PHI_0, PHI_DOT_0, RockingModel, body_outputs, friction_param,
                                           impact_law_param)
    from rocking_model.models.declare import ENERGY, SLIP, Mechanics
    from rocking_model.params import Param, param


    @dataclass(frozen=True)
    class CappedBlock(RockingModel):
        """Block of half-width b, half-height h, mass m, with a lumped mass m_top at the top centre."""

        b: float = param(0.2, "m", "Half-width of the block", lo=1e-6, hi=1e3)
        h: float = param(1.0, "m", "Half-height of the block", lo=1e-6, hi=1e3)
        m: float = param(1.0, "kg", "Mass of the block", lo=1e-9, hi=1e12)
        m_top: float = param(0.5, "kg", "Lumped mass at the top centre", lo=0.0, hi=1e12)
        g: float = param(9.81, "m/s2", "Gravitational acceleration", lo=1e-3, hi=1e3)
        e_N: float = param(0.0, "1", "Newton coefficient of restitution", lo=0.0, hi=1.0)
        impact_law: int = impact_law_param()
        mu: float = friction_param()
        dof_names: tuple = field(default=("x", "y", "phi"), init=False, repr=False)
        slide_index: int = field(default=0, init=False, repr=False)
        phi_index: int = field(default=2, init=False, repr=False)

        kind: ClassVar[str] = "capped_block"
        fmu_name: ClassVar[str] = "CappedRockingBlock"
        INITIAL: ClassVar[tuple] = (PHI_0, PHI_DOT_0)
        OUTPUTS: ClassVar[tuple] = body_outputs("block", "the block's centroid") + (
            Param("energy", 0.0, "J", "Mechanical energy relative to rest"),)

        @staticmethod
        def mechanics(sp, p, q, v) -> Mechanics:
            x, y, phi = q
            x_dot, y_dot, phi_dot = v
            b, h, m, m_top, g = p.b, p.h, p.m, p.m_top, p.g
            s, c = sp.sin(phi), sp.cos(phi)
            X_top, Y_top = x - h * s, y + h * c
            rate = lambda e: sum(sp.diff(e, qi) * vi for qi, vi in zip(q, v))
            M = m + m_top
            h_G = (m * h + m_top * 2 * h) / M
            R = sp.sqrt(b ** 2 + h ** 2)
            return Mechanics(
                kinetic=m * (x_dot ** 2 + y_dot ** 2) / 2 + m * R ** 2 / 6 * phi_dot ** 2
                + m_top * (rate(X_top) ** 2 + rate(Y_top) ** 2) / 2,
                first_moment=(m * x + m_top * X_top, m * y + m_top * Y_top),
                contacts=[(x + k * b * c + h * s, y + k * b * s - h * c) for k in (-1, 1)],
                rest=(0, h, 0),
                derived={"h_G": h_G},
                length_scale=R, time_scale=sp.sqrt(R / g), force_scale=M * g,
                outputs={"phi": phi, "phi_dot": phi_dot, "x": x, "y": y - h, "x_dot": x_dot, "y_dot": y_dot,
                         "slip": SLIP, "energy": ENERGY},
            )


    register_model(CappedBlock)


    class CappedRockingBlock(ModelSlave):
        """The capped block's FMU."""

        model_class = CappedBlock
        description = "Rigid block with a lumped top mass on a rigid ground with horizontal acceleration ag."
        default_experiment = DefaultExperiment(start_time=0.0, stop_time=2.0, step_size=0.01)
''')


@pytest.fixture(scope="module")
def declared(tmp_path_factory, monkeypatch_module):
    """The model file written to a temporary folder and imported from there (kernels compiled into a cache
    of the test's own)."""
    folder = tmp_path_factory.mktemp("model")
    monkeypatch_module.setenv("ROCKING_MODEL_CACHE", str(folder / "cache"))
    path = folder / "CappedRockingBlock.py"
    path.write_text(MODEL_FILE)
    spec = importlib.util.spec_from_file_location("CappedRockingBlock", path)
    module = importlib.util.module_from_spec(spec)
    sys.modules["CappedRockingBlock"] = module
    spec.loader.exec_module(module)
    yield path, module
    sys.modules.pop("CappedRockingBlock", None)
    from rocking_model.models import MODELS
    MODELS.pop("capped_block", None)


@pytest.fixture(scope="module")
def monkeypatch_module():
    mp = pytest.MonkeyPatch()
    yield mp
    mp.undo()


def _threshold(model) -> float:
    h_G = (model.m * model.h + model.m_top * 2 * model.h) / (model.m + model.m_top)
    return model.g * model.b / h_G


@pytest.mark.parametrize("scheme", ["event_driven", "moreau_jean"])
def test_the_declared_model_runs_in_both_schemes(declared, scheme):
    pytest.importorskip("sympy")
    from rocking_model import simulate

    CappedBlock = declared[1].CappedBlock
    model = CappedBlock(b=0.3, h=1.2, m=2.0, m_top=1.5)
    assert model.h_G == pytest.approx((2.0 * 1.2 + 1.5 * 2.4) / 3.5, rel=1e-15)
    ag_star = _threshold(model)
    below = simulate(model, 0.98 * ag_star, 0.5, scheme=scheme)
    above = simulate(model, 1.02 * ag_star, 0.5, scheme=scheme)
    assert np.all(below.phi == 0.0) and np.all(below.contact == 0)
    assert above.phi[-1] > 1e-4                  # ag > 0 (the inertial force towards -x) lifts the right corner
    # free rocking conserves energy between impacts (event-driven: to the tolerance)
    free = simulate(model, 0.0, 0.3, scheme=scheme, phi_0=0.05)
    assert free.impacts[-1] == 0
    if scheme == "event_driven":
        assert np.ptp(free.energy) <= 1e-7 * abs(free.energy[0])


def test_the_declared_model_builds_both_fmu_kinds(declared, tmp_path):
    pytest.importorskip("pythonfmu")
    fmpy = pytest.importorskip("fmpy")
    from rocking_model import simulate
    from rocking_model.fmi import build
    try:
        build.find_compiler()
    except build.BuildError as exc:
        pytest.skip(str(exc))
    path, module = declared
    model = module.CappedBlock()
    ag = 1.5 * _threshold(model)
    ref = simulate(model, ag, 1.0, output_interval=0.01, hold="zoh", scheme="event_driven")
    fmus = [build.build_script(path, tmp_path / "pythonfmu"),
            build.build_standalone_one(str(path), tmp_path / "standalone")]
    signals = np.array([(0.0, ag), (2.0, ag)], dtype=[("time", float), ("ag", float)])
    for fmu in fmus:
        res = fmpy.simulate_fmu(str(fmu), stop_time=1.0, output_interval=0.01, input=signals,
                                start_values={"scheme": 1}, output=["phi"])
        assert np.max(np.abs(res["phi"] - ref.phi)) <= 1e-9, fmu.name
        assert abs(res["phi"][-1]) > 1e-3
