"""FMI 2.0 co-simulation FMU of the rigid rocking block (Housner 1963; Giouvanidis & Dimitrakopoulos 2017).

Thin wrapper: the FMI plumbing lives in `rocking_model.fmi`, the physics and every parameter's default,
unit, range and description in `rocking_model.models.rigid_block`. Build with ``python build_fmu.py`` (writes
dist/RigidRockingBlock.fmu). The module name is unique on purpose: two FMUs whose scripts share a module name
cannot be loaded in the same process.
It runs the compiled engine (one call into C per doStep).
"""
from rocking_model.fmi import DefaultExperiment, ModelSlave
from rocking_model.models import RigidBlock


class RigidRockingBlock(ModelSlave):
    """Rigid rectangular block rocking on a rigid ground accelerating horizontally (ag) and vertically (ag_v)."""

    model_class = RigidBlock
    description = ("Rigid rocking block (half-width b, half-height h) on a rigid ground with horizontal "
                   "acceleration ag and vertical acceleration ag_v: unilateral corner contacts, Newton impact "
                   "law (e_N = 0: Housner's restitution), sticking, uplift and flight; Moreau-Jean time-stepping "
                   "(scheme = 0) or event-driven integration (scheme = 1). The input ag is held constant over "
                   "each communication step (or interpolated linearly with fmi2SetRealInputDerivatives); so is "
                   "the vertical ground acceleration ag_v (positive upward: an effective gravity g + ag_v). "
                   "Outputs freeze once the block overturns.")
    default_experiment = DefaultExperiment(start_time=0.0, stop_time=5.0, step_size=0.01)
    variables = ModelSlave.variables_of(RigidBlock)
