"""Impact laws: the paper's law (Newton normal, sticking tangential) can create energy when
e_N > 0 and a corner slips; the energetically consistent law (tangential restitution e_T = e_N on the closing
contacts, Glocker 2013) never does."""
from __future__ import annotations

import numpy as np
import pytest

from rocking_model import FlexibleOscillator, RigidBlock, simulate


def test_elastic_rocking_keeps_its_energy_under_the_consistent_law():
    """e_N = 1, zeta = 0, no ground motion, event-driven: the consistent law keeps the energy (elastic
    impacts), the paper's law creates some (documented figures, docs/limitations.md)."""
    runs = {}
    for law in (0, 1):
        m = FlexibleOscillator(e_N=1.0, zeta=0.0, impact_law=law)
        runs[law] = simulate(m, 0.0, 1.0, phi_0=0.05, output_interval=0.001, on_report="ignore").energy
    E0 = runs[1][0]
    assert np.max(np.abs(runs[1] - E0)) < 1e-6 * E0 and runs[1][-1] <= E0 * (1 + 1e-9)
    assert runs[0][-1] > 1.1 * E0
    rigid = {law: simulate(RigidBlock(e_N=1.0, impact_law=law), 0.0, 5.0, phi_0=0.1,
                           on_report="ignore").energy for law in (0, 1)}
    assert abs(rigid[1][-1] / rigid[1][0] - 1.0) < 1e-7
    assert rigid[0][-1] / rigid[0][0] - 1.0 > 1e-3


def test_impact_law_by_name_and_default():
    assert RigidBlock().impact_law == 0 and RigidBlock().e_T == 0.0
    m = RigidBlock(e_N=0.4, impact_law="energy_consistent")
    assert m.impact_law == 1 and m.e_T == 0.4
    with pytest.raises(ValueError, match=r"impact_law = 'glocker' is not supported; allowed values: 0, 1, "
                                         r"'newton', 'energy_consistent'"):
        RigidBlock(impact_law="glocker")
