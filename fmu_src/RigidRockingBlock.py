"""FMI 2.0 co-simulation FMU of the rigid rocking block (Housner 1963; Giouvanidis & Dimitrakopoulos 2017).

Thin wrapper: the FMI plumbing lives in `rocking_model.fmi`, the physics in `rocking_model`. Build with
``python build_fmu.py`` (writes dist/RigidRockingBlock.fmu). The module name is unique on purpose: two FMUs
whose scripts share a module name cannot be loaded in the same process.
"""
from rocking_model.fmi import AG_INPUT, DefaultExperiment, MAX_STEPS_PARAMETER, RockingSlave, Var


class RigidRockingBlock(RockingSlave):
    """Rigid rectangular block rocking on a horizontally accelerating rigid ground."""

    description = ("Rigid rocking block (half-width b, half-height h) on a rigid ground with horizontal "
                   "acceleration ag: unilateral corner contacts, Newton impact law (e_N = 0: Housner's "
                   "restitution), sticking, uplift and flight; Moreau-Jean time-stepping (scheme = 0) or "
                   "event-driven integration (scheme = 1). The input ag is held constant over each "
                   "communication step. Outputs freeze once the block overturns.")
    default_experiment = DefaultExperiment(start_time=0.0, stop_time=5.0, step_size=0.01)

    variables = (
        # parameters
        Var("b", "parameter", 0.2, unit="m", description="Half-width of the block"),
        Var("h", "parameter", 1.0, unit="m", description="Half-height of the block"),
        Var("m", "parameter", 1.0, unit="kg", description="Mass of the block"),
        Var("g", "parameter", 9.81, unit="m/s2", description="Gravitational acceleration"),
        Var("e_N", "parameter", 0.0, unit="1", min=0.0, max=1.0,
            description="Newton coefficient of restitution at the corners (0: Housner's angular-momentum "
                        "impact)"),
        Var("phi_0", "parameter", 0.0, unit="rad",
            description="Initial rotation (positive: pivoting on the left corner), |phi_0| < pi/2"),
        Var("phi_dot_0", "parameter", 0.0, unit="rad/s", description="Initial angular velocity"),
        Var("scheme", "parameter", 1, type="Integer", min=0, max=1,
            description="Integration scheme: 0 Moreau-Jean time-stepping, 1 event-driven (default: the "
                        "faster at equal error, see docs/performance.md)"),
        Var("dt_max", "parameter", 0.0, unit="s", min=0.0,
            description="Moreau-Jean time step (largest; each communication step is split evenly) or "
                        "largest event-driven step; 0: the scheme's default (Moreau-Jean 1e-3 s, "
                        "event-driven uncapped)"),
        Var("tolerance", "parameter", 1e-8, unit="1",
            description="Relative tolerance of the event-driven scheme, in [1e-14, 1e-2]"),
        MAX_STEPS_PARAMETER,
        # input
        AG_INPUT,
        # outputs
        Var("phi", "output", unit="rad", description="Rotation of the block"),
        Var("phi_dot", "output", unit="rad/s", description="Angular velocity of the block"),
        Var("x", "output", unit="m", description="Horizontal displacement of the centroid relative to the "
                                                  "ground"),
        Var("y", "output", unit="m", description="Vertical displacement of the centroid from rest"),
        Var("x_dot", "output", unit="m/s", description="Horizontal velocity of the centroid relative to the "
                                                        "ground"),
        Var("y_dot", "output", unit="m/s", description="Vertical velocity of the centroid"),
        Var("contact", "output", 0, type="Integer",
            description="Contact state: 0 full contact, 1 rocking on the left corner, 2 rocking on the "
                        "right corner, 3 flight"),
        Var("impacts", "output", 0, type="Integer", description="Number of impacts so far"),
        Var("overturned", "output", False, type="Boolean",
            description="True once the block has overturned (outputs are frozen from then on)"),
        Var("energy", "output", unit="J",
            description="Mechanical energy relative to rest (kinetic relative to the ground + potential)"),
    )

    def create_simulator(self, p, t0):
        from rocking_model.models.rigid_block import RigidBlock
        from rocking_model.simulation import Simulator

        model = RigidBlock(b=p["b"], h=p["h"], m=p["m"], g=p["g"], e_N=p["e_N"])
        return Simulator(model, scheme=p["scheme"], dt_max=p["dt_max"], tolerance=p["tolerance"], t0=t0,
                         impact_log_size=0, max_steps=p["max_steps"],
                         phi_0=p["phi_0"], phi_dot_0=p["phi_dot_0"])
