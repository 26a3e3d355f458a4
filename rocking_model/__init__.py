"""Nonsmooth rocking dynamics (Giouvanidis & Dimitrakopoulos 2017): rigid rocking block and flexible
rocking oscillator with unilateral corner contacts, Newton's impact law and sticking, impact and uplift as
LCPs, a Moreau-Jean time-stepper and an event-driven scheme."""
from .ground_motion import ConstantMotion, FunctionMotion, GroundMotion, SampledMotion, SinePulse
from .models.flexible_oscillator import FlexibleOscillator
from .models.rigid_block import RigidBlock
from .modes import Mode
from .simulation import Result, Simulator, SolverFailure, SolverWarning, simulate
from .tolerances import ContactTolerances
from .validation import AG_MAX, WorkLimitError

__all__ = ["RigidBlock", "FlexibleOscillator", "Mode", "Simulator", "simulate", "Result", "GroundMotion", "ConstantMotion",
           "FunctionMotion", "SampledMotion", "SinePulse", "AG_MAX", "WorkLimitError",
           "SolverWarning", "SolverFailure", "ContactTolerances"]
__version__ = "0.1.0"
