"""The integration schemes behind one contract (`Integrator`) and their registry (`SCHEMES`): the Moreau-Jean
time-stepper (`moreau_jean`, code 0) and the event-driven scheme (`event_driven`, code 1), both run by the
compiled engine (`rocking_model.engine.CompiledIntegrator`); `schemes` declares them."""
from .base import SCHEMES, Integrator, Report, SolverOptions, register_scheme, scheme_choices, scheme_class
from .schemes import EventDriven, MoreauJean

__all__ = ["Integrator", "Report", "SolverOptions", "SCHEMES", "register_scheme", "scheme_choices",
           "scheme_class", "EventDriven", "MoreauJean"]
