"""FMI 2.0 co-simulation FMU of the flexible rocking oscillator (Giouvanidis & Dimitrakopoulos 2017, appendix).

Thin wrapper: the FMI plumbing lives in `rocking_model.fmi`, the physics in `rocking_model`. Build with
``python build_fmu.py`` (writes dist/FlexibleRockingOscillator.fmu). Unique module name on purpose.
Default parameters: the representative laboratory specimen of `FlexibleOscillator` (see its docstring).
"""
from rocking_model.fmi import AG_INPUT, DefaultExperiment, MAX_STEPS_PARAMETER, RockingSlave, Var


class FlexibleRockingOscillator(RockingSlave):
    """Flexible column with a top mass on a rigid base that can uplift, on a horizontally moving ground."""

    description = ("Flexible rocking oscillator: cantilever column (height h, flexural rigidity EI, mass m_c) "
                   "with a top mass m on a rigid base (mass m_b, radius of gyration rho, half-width b) that "
                   "can uplift from a rigid ground with horizontal acceleration ag. Generalized coordinates "
                   "[u, x, y, phi]; unilateral corner contacts with Newton's impact law and sticking solved as "
                   "LCPs (or the classical momentum rule, impact_rule = 1); Moreau-Jean (scheme = 0) or "
                   "event-driven (scheme = 1). ag is held constant over each communication step.")
    default_experiment = DefaultExperiment(start_time=0.0, stop_time=5.0, step_size=0.01)

    variables = (
        Var("m", "parameter", 500.0, unit="kg", description="Lumped top mass (> 0)"),
        Var("m_c", "parameter", 30.0, unit="kg", description="Column mass, uniformly distributed (>= 0)"),
        Var("m_b", "parameter", 100.0, unit="kg", description="Base mass (>= 0)"),
        Var("rho", "parameter", 0.145, unit="m", description="Radius of gyration of the base (>= 0)"),
        Var("h", "parameter", 1.5, unit="m", description="Column height (> 0)"),
        Var("b", "parameter", 0.25, unit="m", description="Half-width of the base (> 0)"),
        Var("EI", "parameter", 9.45e5, unit="N.m2", description="Flexural rigidity of the column (> 0)"),
        Var("zeta", "parameter", 0.02, unit="1", min=0.0, description="Damping ratio of the flexural mode (>= 0)"),
        Var("e_N", "parameter", 0.0, unit="1", min=0.0, max=1.0,
            description="Newton coefficient of restitution at the base corners, in [0, 1]"),
        Var("g", "parameter", 9.81, unit="m/s2", description="Gravitational acceleration"),
        Var("u_0", "parameter", 0.0, unit="m", description="Initial flexural coordinate (tip deflection)"),
        Var("u_dot_0", "parameter", 0.0, unit="m/s", description="Initial flexural velocity"),
        Var("phi_0", "parameter", 0.0, unit="rad",
            description="Initial base rotation (positive: pivoting on the left corner), |phi_0| < pi/2"),
        Var("phi_dot_0", "parameter", 0.0, unit="rad/s", description="Initial angular velocity of the base"),
        Var("scheme", "parameter", 1, type="Integer", min=0, max=1,
            description="Integration scheme: 0 Moreau-Jean time-stepping, 1 event-driven (default: the "
                        "faster at equal error, see docs/performance.md)"),
        Var("impact_rule", "parameter", 0, type="Integer", min=0, max=1,
            description="Impact rule: 0 LCP with Newton's law, 1 classical angular-momentum rule "
                        "(flexural velocity continuous)"),
        Var("dt_max", "parameter", 0.0, unit="s", min=0.0,
            description="Moreau-Jean time step (largest; each communication step is split evenly) or "
                        "largest event-driven step; 0: the scheme's default (Moreau-Jean 1e-3 s, "
                        "event-driven uncapped)"),
        Var("tolerance", "parameter", 1e-8, unit="1",
            description="Relative tolerance of the event-driven scheme, in [1e-14, 1e-2]"),
        MAX_STEPS_PARAMETER,
        AG_INPUT,
        Var("u", "output", unit="m", description="Flexural coordinate (tip deflection relative to the base)"),
        Var("u_dot", "output", unit="m/s", description="Flexural velocity"),
        Var("phi", "output", unit="rad", description="Rotation of the base"),
        Var("phi_dot", "output", unit="rad/s", description="Angular velocity of the base"),
        Var("x", "output", unit="m", description="Horizontal displacement of the base midpoint relative to "
                                                  "the ground"),
        Var("y", "output", unit="m", description="Vertical displacement of the base midpoint"),
        Var("x_dot", "output", unit="m/s", description="Horizontal velocity of the base midpoint"),
        Var("y_dot", "output", unit="m/s", description="Vertical velocity of the base midpoint"),
        Var("top_displacement", "output", unit="m",
            description="Horizontal displacement of the top mass relative to the ground"),
        Var("contact", "output", 0, type="Integer",
            description="Contact state: 0 full contact, 1 rocking on the left corner, 2 rocking on the "
                        "right corner, 3 flight"),
        Var("impacts", "output", 0, type="Integer", description="Number of impacts so far"),
        Var("overturned", "output", False, type="Boolean",
            description="True once the structure has overturned (outputs are frozen from then on)"),
        Var("energy", "output", unit="J",
            description="Mechanical energy relative to rest (kinetic relative to the ground + potential + "
                        "strain)"),
    )

    def create_simulator(self, p, t0):
        from rocking_model.models.flexible_oscillator import FlexibleOscillator
        from rocking_model.simulation import Simulator

        model = FlexibleOscillator(m=p["m"], m_c=p["m_c"], m_b=p["m_b"], rho=p["rho"], h=p["h"], b=p["b"],
                                   EI=p["EI"], zeta=p["zeta"], e_N=p["e_N"], g=p["g"],
                                   impact_rule=p["impact_rule"])
        return Simulator(model, scheme=p["scheme"], dt_max=p["dt_max"], tolerance=p["tolerance"], t0=t0,
                         impact_log_size=0, max_steps=p["max_steps"],
                         phi_0=p["phi_0"], phi_dot_0=p["phi_dot_0"], u_0=p["u_0"], u_dot_0=p["u_dot_0"])
