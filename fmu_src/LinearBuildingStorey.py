"""FMI 2.0 co-simulation FMU of a linear building storey (damped SDOF floor on a moving ground).

Thin wrapper: the equations are in `rocking_model.models.linear_building`, the FMI plumbing in
`rocking_model.fmi`. Input: ground acceleration ag; output: the absolute floor acceleration a_floor, to drive
equipment (a rocking block) standing on the floor.
"""
from rocking_model.fmi import AG_INPUT, DefaultExperiment, RockingSlave, Var
from rocking_model.models.linear_building import T_MAX, T_MIN, U_DOT_MAX, U_MAX, ZETA_MAX


class LinearBuildingStorey(RockingSlave):
    """Damped single-degree-of-freedom storey; T = 0 is a rigid storey (the floor moves with the ground)."""
    interpolates_inputs = False  # exact integration for ag held constant over a step

    description = ("Linear building storey: floor mass on a linear elastic, viscously damped frame, "
                   "u'' + 2 zeta omega u' + omega^2 u = -ag with omega = 2 pi / T; output the absolute floor "
                   "acceleration a_floor = -(2 zeta omega u' + omega^2 u). Exact integration for ag held "
                   "over each communication step. T = 0: rigid storey, a_floor = ag.")
    default_experiment = DefaultExperiment(start_time=0.0, stop_time=5.0, step_size=0.01)
    freeze_output = None

    variables = (
        Var("T", "parameter", 0.5, unit="s", min=0.0, max=T_MAX,
            description=f"Fixed-base natural period of the storey: 0 = rigid, else [{T_MIN:g}, {T_MAX:g}] s"),
        Var("zeta", "parameter", 0.05, unit="1", min=0.0, max=ZETA_MAX,
            description=f"Damping ratio, [0, {ZETA_MAX:g}]"),
        Var("u_0", "parameter", 0.0, unit="m", min=-U_MAX, max=U_MAX,
            description="Initial floor displacement relative to the ground"),
        Var("u_dot_0", "parameter", 0.0, unit="m/s", min=-U_DOT_MAX, max=U_DOT_MAX,
            description="Initial floor velocity relative to the ground"),
        AG_INPUT,
        Var("u", "output", unit="m", description="Floor displacement relative to the ground"),
        Var("u_dot", "output", unit="m/s", description="Floor velocity relative to the ground"),
        Var("a_floor", "output", unit="m/s2", description="Absolute horizontal acceleration of the floor"),
    )

    def create_simulator(self, p, t0):
        from rocking_model.models.linear_building import LinearStorey, StoreySimulator

        return StoreySimulator(LinearStorey(T=p["T"], zeta=p["zeta"]), t0=t0, u_0=p["u_0"], u_dot_0=p["u_dot_0"])
