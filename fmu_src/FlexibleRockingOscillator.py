"""FMI 2.0 co-simulation FMU of the flexible rocking oscillator (Giouvanidis & Dimitrakopoulos 2017, appendix).

Thin wrapper: the FMI plumbing lives in `rocking_model.fmi`, the physics and every parameter's default,
unit, range and description in `rocking_model.models.flexible_oscillator` (defaults: its representative
laboratory specimen). Build with ``python build_fmu.py`` (writes dist/FlexibleRockingOscillator.fmu). Unique
module name on purpose.
It runs the compiled engine (one call into C per doStep).
"""
from rocking_model.fmi import DefaultExperiment, ModelSlave
from rocking_model.models import FlexibleOscillator


class FlexibleRockingOscillator(ModelSlave):
    """Flexible column with a top mass on a rigid base that can uplift, on a ground moving horizontally and
    vertically."""

    model_class = FlexibleOscillator
    description = ("Flexible rocking oscillator: cantilever column (height h, flexural rigidity EI, mass m_c) "
                   "with a top mass m on a rigid base (mass m_b, radius of gyration rho, half-width b) that "
                   "can uplift from a rigid ground with horizontal acceleration ag and vertical acceleration "
                   "ag_v. Generalized coordinates [u, x, y, phi]; unilateral corner contacts with Newton's "
                   "impact law and sticking solved as LCPs (or the classical momentum rule, impact_rule = 1); "
                   "Moreau-Jean (scheme = 0) or event-driven (scheme = 1). ag and ag_v (positive upward: an "
                   "effective gravity g + ag_v) are held constant over each communication step (or "
                   "interpolated linearly with fmi2SetRealInputDerivatives).")
    default_experiment = DefaultExperiment(start_time=0.0, stop_time=5.0, step_size=0.01)
    variables = ModelSlave.variables_of(FlexibleOscillator)
