"""Nonsmooth rocking dynamics (Giouvanidis & Dimitrakopoulos 2017): rigid rocking block and flexible
rocking oscillator with unilateral corner contacts, Newton's impact law and sticking, impact and uplift as
LCPs, a Moreau-Jean time-stepper and an event-driven scheme.

The public names below are imported on first use (PEP 562): ``import rocking_model`` itself imports neither
numpy nor the Python engine, so that the compiled engine's low-level API (`rocking_model._engine.Engine`, see
``rocking_model/engine/DESIGN.md``) starts in a few milliseconds; ``from rocking_model import simulate`` imports
what `simulate` needs."""

#: ground motions: every GroundMotion subclass of rocking_model.ground_motion, and the readers' Record
GROUND_MOTIONS = ["GroundMotion", "ConstantMotion", "LinearMotion", "FunctionMotion", "CheckedMotion", "SampledMotion",
                  "ScaledMotion", "SinePulse", "CosinePulse", "RickerPulse", "RectangularPulse", "TwoComponentMotion",
                  "Record"]
__all__ = ["RigidBlock", "FlexibleOscillator", "PostTensionedBlock", "Mode", "Simulator", "simulate", "Result", *GROUND_MOTIONS,
           "AG_MAX", "WorkLimitError", "SolverWarning", "SolverFailure", "ContactTolerances"]
__version__ = "0.1.0"

#: public name -> the submodule that defines it (imported on first access)
_LAZY = {
    **{name: "ground_motion" for name in GROUND_MOTIONS if name != "Record"},
    "Record": "records",
    "FlexibleOscillator": "models.flexible_oscillator",
    "PostTensionedBlock": "models.post_tensioned",
    "RigidBlock": "models.rigid_block",
    "Mode": "modes",
    "Result": "simulation", "Simulator": "simulation", "SolverFailure": "simulation", "SolverWarning": "simulation",
    "simulate": "simulation",
    "ContactTolerances": "tolerances",
    "AG_MAX": "validation", "WorkLimitError": "validation",
}


def __getattr__(name):
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    from importlib import import_module

    value = getattr(import_module(f"{__name__}.{module}"), name)
    globals()[name] = value           # later reads find it without this function
    return value


def __dir__():
    return sorted(set(globals()) | set(__all__))
