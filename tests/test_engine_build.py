"""The compiled engine's extension module is built by ``pip install`` and reports clear errors (issue 21)."""
import pytest

import rocking_model
from rocking_model import _engine


def test_version_is_the_package_version():
    assert _engine.version() == rocking_model.__version__
    assert _engine.api_version() >= 1


def test_unknown_model_kind_is_a_value_error_naming_the_allowed_kinds():
    with pytest.raises(ValueError, match="allowed values 'rigid', 'flexible'"):
        _engine.create_and_free("cylinder", [1.0])


def test_params_must_be_numbers():
    with pytest.raises(TypeError, match="params"):
        _engine.create_and_free("rigid", ["b"])


def test_create_reports_a_clear_error_or_succeeds():
    """Until parts A, D and E land, creating a rigid block engine says which part is missing; afterwards it
    succeeds. Either way it never crashes the interpreter."""
    from rocking_model.models import RigidBlock

    params = [p.default for p in RigidBlock.parameters()]
    try:
        _engine.create_and_free("rigid", params)
    except NotImplementedError as exc:
        assert "not implemented yet" in str(exc) and "engine=\"python\"" in str(exc)
