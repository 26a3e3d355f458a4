"""Impact laws (issue 15): the paper's law (Newton normal, sticking tangential) can create energy when
e_N > 0 and a corner slips; the energetically consistent law (tangential restitution e_T = e_N on the closing
contacts, Glocker 2013) never does."""
from __future__ import annotations

import math

import numpy as np
import pytest

from rocking_model import FlexibleOscillator, RigidBlock, simulate
from rocking_model.contact import impact

N_STATES = 1500


def _mu(rng, friction):
    """inf (the paper's sticking, the mu -> inf limit where it has no solution), or with ``friction`` a random
    Coulomb coefficient in [0.05, 3] half of the time."""
    return 10 ** rng.uniform(math.log10(0.05), math.log10(3.0)) if friction and rng.uniform() < 0.5 else math.inf


def _rigid(rng, law, friction=False):
    return RigidBlock(b=rng.uniform(0.05, 1.5), h=rng.uniform(0.2, 2.0), m=10 ** rng.uniform(-1, 3),
                      e_N=rng.uniform(0.0, 1.0), impact_law=law, mu=_mu(rng, friction))


def _flexible(rng, law, friction=False):
    return FlexibleOscillator(b=rng.uniform(0.1, 0.6), h=rng.uniform(0.5, 3.0), EI=10 ** rng.uniform(4, 7),
                              e_N=rng.uniform(0.0, 1.0), zeta=rng.uniform(0.0, 0.1), impact_law=law,
                              mu=_mu(rng, friction))


def random_impacts(make, law, seed, n=N_STATES, friction=False):
    """(relative kinetic-energy changes of the exact solves, number of exact solves) over random impacts:
    a random geometry and e_N, a random tilt (30 % flat, both corners at the ground), a random velocity made
    to approach the ground at the lowest corner(s)."""
    rng = np.random.default_rng(seed)
    changes, n_exact = [], 0
    for _ in range(n):
        m = make(rng, law, friction)
        q = m.rest_position().copy()
        q[m.phi_index] = rng.uniform(-0.5, 0.5) if rng.uniform() < 0.7 else 0.0
        y = m.dof_names.index("y")
        q[y] -= min(m.gaps(q))
        cand = [i for i in range(m.n_contacts) if m.gaps(q)[i] < 1e-12]
        v = rng.normal(size=m.n_dof)
        U = m.contact_jacobians(q)[0].T @ v
        if min(U[cand]) >= -1e-3:
            v[y] -= max(U[cand]) + 0.3 + rng.uniform(0.0, 2.0)
        sol = impact(m, q, v, cand)
        if sol.exact:
            n_exact += 1
            T_minus = m.energy(q, v) - m.energy(q, np.zeros_like(v))
            changes.append((m.energy(q, sol.v) - m.energy(q, v)) / T_minus)
    return np.array(changes), n_exact


@pytest.mark.parametrize("make", [_rigid, _flexible], ids=["rigid", "flexible"])
def test_energy_consistent_law_never_creates_energy(make):
    """Property: under the energetically consistent law, no impact (random geometry, e_N, state and friction:
    mu = inf or Coulomb's with a random mu in [0.05, 3]; ag = 0, zeta >= 0) increases the energy beyond
    round-off. Every impact has an exact solution (before issue 15's friction about 10 % of these states had
    none under sticking)."""
    changes, n_exact = random_impacts(make, 1, seed=11, friction=True)
    assert n_exact == N_STATES
    assert changes.max() <= 1e-12, changes.max()
    assert changes.min() < -0.1                  # it does dissipate


@pytest.mark.parametrize("make", [_rigid, _flexible], ids=["rigid", "flexible"])
def test_paper_law_creates_energy_as_documented(make):
    """The paper's law on the same random impacts: some increase the energy (docs/limitations.md: 1.4 % of the
    exact solves by up to 20 % of the kinetic energy for the block, 1.9 % by up to 2.3 % for the oscillator)."""
    changes, n_exact = random_impacts(make, 0, seed=11)
    assert n_exact == N_STATES
    up = changes[changes > 1e-12]
    assert 0.005 * n_exact <= up.size <= 0.05 * n_exact, up.size
    assert 0.005 < up.max() < 0.6, up.max()


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
