"""Declared contracts: the registries of schemes and models, the `Integrator` and model
interfaces, one `ContactTolerances`, per-contact states, reports of inexact contact solves and failed
steps, and the contact LCP for any number of contacts."""
from __future__ import annotations

import inspect
import re
from pathlib import Path

import numpy as np
import pytest

from rocking_model import ContactTolerances, FlexibleOscillator, PostTensionedBlock, RigidBlock, Simulator, SinePulse
from rocking_model.integrators import SCHEMES, Integrator, scheme_class
from rocking_model.models import MODELS, RockingModel, make_model, model_class
from rocking_model.modes import ContactState, Mode, slide_sign
from rocking_model.params import Param

PACKAGE = Path(__file__).resolve().parents[1] / "rocking_model"


# ---------------------------------------------------------------------------------------------- registries
def test_scheme_registry():
    assert set(SCHEMES) == {"moreau_jean", "event_driven"}
    codes = sorted(cls.code for cls in SCHEMES.values())
    assert codes == list(range(len(SCHEMES)))                  # the FMU enumeration's values
    assert scheme_class(0) is SCHEMES["moreau_jean"] and scheme_class("event_driven").code == 1
    with pytest.raises(ValueError, match=r"scheme = 'rk4' is not supported; allowed values: "):
        scheme_class("rk4")


@pytest.mark.parametrize("name", sorted(SCHEMES))
def test_integrator_contract(name):
    """Every registered scheme provides what `Integrator` says a subclass must, and keeps the attributes
    current through an advance (both used by the Simulator only through that interface)."""
    cls = SCHEMES[name]
    assert issubclass(cls, Integrator) and cls.name == name and cls.summary and cls.STATE_KEYS
    assert callable(cls.settings) and callable(cls.read_state)
    sim = Simulator(RigidBlock(), name, phi_0=0.1)
    integ = sim.integrator
    assert integ.STATE_TOKEN and integ.STATE_KEYS == cls.STATE_KEYS
    for method in ("from_options", "advance", "state", "outputs", "get_state", "set_state"):
        assert getattr(type(integ), method) is not getattr(Integrator, method), f"{name} lacks {method}"
    sim.advance(1.0, 0.0)
    assert integ.t == 1.0 and integ.impacts >= 1 and integ.overturned is False and integ.n_steps > 0
    assert isinstance(integ.mode, Mode) and len(integ.contacts) == 2
    assert all(isinstance(c, ContactState) for c in integ.contacts)
    assert set(integ.get_state()) == set(integ.STATE_KEYS)
    modes, values, impacts, overturned = integ.sample([1.1, 1.2], SinePulse(1.0, 5.0))
    assert len(modes) == 3 and set(values) >= {"phi", "energy"} and impacts[-1] >= impacts[0]


def test_model_registry():
    assert MODELS == {"rigid": RigidBlock, "flexible": FlexibleOscillator, "post_tensioned": PostTensionedBlock}
    assert model_class("flexible") is FlexibleOscillator
    assert make_model("rigid", b=0.3).b == 0.3
    with pytest.raises(ValueError, match=r"model = 'frame' is not supported; allowed values: rigid, flexible, post_tensioned"):
        model_class("frame")


@pytest.mark.parametrize("kind", sorted(MODELS))
def test_model_contract(kind):
    """A registered model implements every abstract method, declares each parameter with a unit, a
    description and a default that passes its own check, and declares its initial values and outputs."""
    cls = MODELS[kind]
    assert not inspect.isabstract(cls)
    assert cls.kind == kind and cls.fmu_name and cls.title
    for p in cls.parameters() + cls.INITIAL:
        assert isinstance(p, Param) and p.description and (p.unit or p.items), p
        assert p.check(p.default) is not None
    model = cls()
    q, v = model.rest_position(), np.zeros(model.n_dof)
    assert set(model.outputs(q, v)) == {p.name for p in cls.OUTPUTS}
    assert len(model.dof_scales) == model.n_dof
    assert model.n_contacts == len(model.gaps(q)) == model.contact_jacobians(q)[0].shape[1]
    for code in cls.contact_codes():
        closed = model.closed_of(code)
        assert model.mode_of(closed, slide_sign(code)) == code


def test_no_probing_of_optional_hooks():
    """Optional model hooks are base-class methods with defaults: the integrators and the contact
    layer never probe the model with getattr / hasattr."""
    for path in (PACKAGE / "integrators").glob("*.py"):
        text = path.read_text()
        found = re.findall(r"(?:getattr|hasattr)\((?:self\.)?model\b", text)
        assert not found, f"{path.name}: {found}"


# ---------------------------------------------------------------------------------------------- tolerances
def test_contact_tolerances_shared_and_checked():
    tol = ContactTolerances(gap=1e-8, step_gap=1e-11, event=1e-9)
    model = RigidBlock(b=0.2, h=1.0)
    ed = Simulator(model, "event_driven", tolerances=tol).integrator
    mj = Simulator(model, "moreau_jean", tolerances=tol).integrator
    assert ed.tolerances is tol and mj.tolerances is tol
    scaled = tol.for_model(model)
    assert scaled.gap == 1e-8 * model.length_scale and scaled.step_gap == 1e-11 * model.length_scale
    assert Simulator(model, "event_driven").integrator.tolerances == ContactTolerances()
    with pytest.raises(ValueError, match=r"tolerances.gap = -1.0 is out of range; allowed range \(0, 1\)"):
        ContactTolerances(gap=-1.0)
    with pytest.raises(ValueError, match=r"tolerances.sub_samples = 1 is out of range"):
        ContactTolerances(sub_samples=1)
    with pytest.raises(ValueError, match="tolerances must be a ContactTolerances"):
        Simulator(model, tolerances={"gap": 1e-9})


def test_every_tolerance_is_documented():
    """Each field of ContactTolerances carries its unit and reason in a #: comment."""
    import rocking_model.tolerances as mod
    src = inspect.getsource(mod.ContactTolerances)
    for name in mod.ContactTolerances.__dataclass_fields__:
        block = re.search(r"((?:\s*#:.*\n)+)\s*" + name + r":", src)
        assert block and re.search(r"\[[^\]]+\]", block.group(1)), name




# ---------------------------------------------------------------------------------------------- events
def test_contact_states_per_corner():
    model = RigidBlock()
    sim = Simulator(model, "event_driven", phi_0=0.05)
    assert sim.integrator.contacts == (ContactState.CLOSED, ContactState.OPEN)      # pivoting on the left
    assert Simulator(model, "event_driven").integrator.contacts == (ContactState.CLOSED,) * 2


def test_rocking_model_is_the_base():
    assert issubclass(RigidBlock, RockingModel) and issubclass(FlexibleOscillator, RockingModel)
