"""The compiled engine's extension module is built by ``pip install`` and reports clear errors."""
import pytest

import rocking_model
from rocking_model import _engine


def test_version_is_the_package_version():
    assert _engine.version() == rocking_model.__version__
    assert _engine.api_version() >= 1


def test_unknown_model_kind_is_a_value_error_naming_the_allowed_kinds():
    with pytest.raises(ValueError, match="allowed values 'rigid', 'flexible'"):
        _engine.Engine("cylinder", [1.0])


def test_params_must_be_numbers():
    with pytest.raises(TypeError, match="params"):
        _engine.Engine("rigid", ["b"])


def test_create_succeeds_with_the_declared_defaults():
    from rocking_model.models import FlexibleOscillator, RigidBlock

    for kind, cls in (("rigid", RigidBlock), ("flexible", FlexibleOscillator)):
        _engine.Engine(kind, [p.default for p in cls.parameters()])


def test_the_kernels_declare_the_parameters_of_the_python_classes():
    """model_kinds() (the low-level API's declarations) names the parameters, initial values and outputs of the
    model classes, in their order, with their defaults."""
    from rocking_model.models import FlexibleOscillator, RigidBlock

    kinds = {k["class_name"]: k for k in _engine.model_kinds()}
    for cls in (RigidBlock, FlexibleOscillator):
        decl = kinds[cls.__name__]
        assert [p[0] for p in decl["params"]] == [p.name for p in cls.parameters()]
        assert [p[2] for p in decl["params"]] == [float(p.default) for p in cls.parameters()]
        assert [p[0] for p in decl["initial"]] == [p.name for p in cls.INITIAL]
        assert [p[0] for p in decl["outputs"]] == [p.name for p in cls.OUTPUTS]
