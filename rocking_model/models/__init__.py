"""Dynamical systems and contact relations of the rocking models, and their registry (`MODELS`).

The command line, the ensembles, the benchmarks and build_fmu.py choose a model by its registry name
(``kind``) through `model_class` / `make_model`; a new model registers itself with `register_model`.
"""
from .base import RockingModel
from .flexible_oscillator import FlexibleOscillator
from .post_tensioned import PostTensionedBlock
from .rigid_block import RigidBlock

#: registry of the models: kind -> class
MODELS: dict = {}


def register_model(cls: type) -> type:
    """Add a `RockingModel` subclass to `MODELS` under its ``kind`` (class decorator)."""
    if not (isinstance(cls, type) and issubclass(cls, RockingModel)) or not cls.kind:
        raise TypeError(f"{cls!r} is not a RockingModel subclass with a kind")
    MODELS[cls.kind] = cls
    return cls


def model_class(kind: str) -> type:
    """The registered class of ``kind``; ValueError listing the registered kinds."""
    try:
        return MODELS[kind]
    except (KeyError, TypeError):
        raise ValueError(f"model = {kind!r} is not supported; allowed values: {', '.join(MODELS)}") from None


def make_model(kind: str, **parameters) -> RockingModel:
    """A model of the registered ``kind`` with the given parameters (checked by the model)."""
    return model_class(kind)(**parameters)


register_model(RigidBlock)
register_model(FlexibleOscillator)
register_model(PostTensionedBlock)

__all__ = ["RockingModel", "RigidBlock", "FlexibleOscillator", "PostTensionedBlock", "MODELS", "register_model", "model_class",
           "make_model"]
