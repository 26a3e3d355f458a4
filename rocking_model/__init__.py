"""Nonsmooth rocking dynamics (Giouvanidis & Dimitrakopoulos 2017): rigid rocking block and flexible
rocking oscillator with unilateral corner contacts, Newton's impact law and sticking, impact and uplift as
LCPs, a Moreau-Jean time-stepper and an event-driven scheme."""
from .ground_motion import (CheckedMotion, ConstantMotion, CosinePulse, FunctionMotion, GroundMotion, LinearMotion,
                            RectangularPulse, RickerPulse, SampledMotion, ScaledMotion, SinePulse, TwoComponentMotion)
from .models.flexible_oscillator import FlexibleOscillator
from .models.rigid_block import RigidBlock
from .modes import Mode
from .records import Record
from .simulation import Result, Simulator, SolverFailure, SolverWarning, simulate
from .tolerances import ContactTolerances
from .validation import AG_MAX, WorkLimitError

#: ground motions: every GroundMotion subclass of rocking_model.ground_motion, and the readers' Record
GROUND_MOTIONS = ["GroundMotion", "ConstantMotion", "LinearMotion", "FunctionMotion", "CheckedMotion", "SampledMotion",
                  "ScaledMotion", "SinePulse", "CosinePulse", "RickerPulse", "RectangularPulse", "TwoComponentMotion",
                  "Record"]
__all__ = ["RigidBlock", "FlexibleOscillator", "Mode", "Simulator", "simulate", "Result", *GROUND_MOTIONS,
           "AG_MAX", "WorkLimitError", "SolverWarning", "SolverFailure", "ContactTolerances"]
__version__ = "0.1.0"
