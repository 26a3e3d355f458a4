"""Dynamical systems and contact relations of the rocking models."""
from .base import RockingModel
from .flexible_oscillator import FlexibleOscillator
from .rigid_block import RigidBlock

__all__ = ["RockingModel", "RigidBlock", "FlexibleOscillator"]
