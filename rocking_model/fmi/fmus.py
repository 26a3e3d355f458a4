"""The slave classes of the FMUs, one per FMU and named like it: what ``rocking build-fmu`` (and the
checkout's ``python build_fmu.py``) builds, from an installed package as from a checkout.

- `RigidRockingBlock`: the rigid rocking block (Housner 1963; Giouvanidis & Dimitrakopoulos 2017); physics,
  every parameter's default, unit, range and description in `rocking_model.models.rigid_block`.
- `FlexibleRockingOscillator`: the flexible rocking oscillator (Giouvanidis & Dimitrakopoulos 2017, appendix);
  `rocking_model.models.flexible_oscillator` (defaults: its representative laboratory specimen).
  Both run the compiled engine (one call into C per doStep).
- `PostTensionedRockingBlock`: the rigid block held by a vertical unbonded post-tensioned tendon (controlled
  rocking); `rocking_model.models.post_tensioned`.
- `GroundMotionSource`: outputs a horizontal ground acceleration ag(t) and a vertical one ag_v(t) (positive
  upward; 0 without a vertical component), no inputs. The motion is chosen from the parameters by
  `rocking_model.cosim.ground_motion_from_parameters` -- the pulse by
  `rocking_model.ground_motion.pulse_from_parameters` and the record file by `rocking_model.records` (PEER AT2
  and CSV, units from the file), both exactly as the ``rocking`` CLI and the ensembles build them. At every
  communication point t the outputs are ag(t) and ag_v(t); an importer that holds them over the next step (any
  fixed-step master) drives a connected rocking FMU exactly like a standalone run with the table ag(t_n).
- `LinearBuildingStorey`: a linear building storey (damped SDOF floor on a moving ground,
  `rocking_model.models.linear_building`). Input: ground acceleration ag; output: the absolute floor
  acceleration a_floor, to drive equipment (a rocking block) standing on the floor.

Each FMU's script (``fmu_src/<Name>.py`` in a checkout; written by `rocking_model.fmi.build.fmu_script`) only
imports its class: pythonfmu and the FMU binary import the slave class from a module of the FMU's name, unique
on purpose (two FMUs whose scripts share a module name cannot be loaded in the same process). Relative imports
only: each FMU bundles this package under another name.
"""
from ..models import FlexibleOscillator, PostTensionedBlock, RigidBlock
from ..models.linear_building import T_MAX, T_MIN, U_DOT_MAX, U_MAX, ZETA_MAX
from . import AG_INPUT, DefaultExperiment, Fmi2Status, ModelSlave, RockingSlave, Var


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


class PostTensionedRockingBlock(ModelSlave):
    """Rigid rocking block held by a vertical unbonded post-tensioned tendon (controlled rocking)."""

    model_class = PostTensionedBlock
    description = ("Post-tensioned rocking block: the rigid rocking block (half-width b, half-height h) held by "
                   "a vertical unbonded tendon on its centreline, anchored at the base centre in the ground and "
                   "at the top centre of the block, with force P0 + k_t (L - 2h) while taut (0 once slack), on a "
                   "rigid ground with horizontal acceleration ag and vertical acceleration ag_v; unilateral "
                   "corner contacts, Newton impact law, sticking or Coulomb friction; Moreau-Jean (scheme = 0) "
                   "or event-driven (scheme = 1). ag and ag_v are held constant over each communication step (or "
                   "interpolated linearly with fmi2SetRealInputDerivatives). Outputs freeze once the block "
                   "overturns.")
    default_experiment = DefaultExperiment(start_time=0.0, stop_time=5.0, step_size=0.01)


class GroundMotionSource(RockingSlave):
    """Ground-motion source: one-sine pulse or a sampled record file, times a scale factor."""
    interpolates_inputs = False  # no input

    description = ("Ground-motion source: outputs the horizontal ground acceleration ag(t) of a one-sine pulse "
                   "(motion = 0: A sin(omega_p (t - t_start)) for one period) or of a sampled record (motion = "
                   "1: a PEER .AT2 file, a two-column .csv/.txt/.dat/.tsv file time [s], acceleration in the "
                   "units its header states, or synthetic[:seed]; linear interpolation, 0 outside), times "
                   "scale. ag is the value at the communication point. ag_v is the record's vertical "
                   "component (a third CSV column, or the file vertical; positive upward) times scale and "
                   "vertical_scale, 0 when it has none.")
    default_experiment = DefaultExperiment(start_time=0.0, stop_time=5.0, step_size=0.01)
    freeze_output = None

    variables = (
        Var("motion", "parameter", 0, type="Integer", min=0, max=1,
            description="Kind of motion: 0 one-sine pulse, 1 sampled record (parameters record, units)"),
        Var("A", "parameter", 0.4 * 9.81, unit="m/s2", description="Pulse amplitude"),
        Var("omega_p", "parameter", 6.283185307179586, unit="rad/s",
            description="Pulse circular frequency (> 0); the pulse lasts 2 pi / omega_p"),
        Var("t_start", "parameter", 0.0, unit="s", description="Start time of the pulse"),
        Var("scale", "parameter", 1.0, unit="1", description="Scale factor applied to the motion"),
        Var("record", "parameter", "", type="String",
            description="Record for motion = 1: absolute path (or relative to the importer's working "
                        "directory) of a PEER .AT2 file (units from its 3rd line, else g) or of a two-column "
                        ".csv/.txt/.dat/.tsv file, time [s] and acceleration, whose header states the units "
                        "('time [s],ag [cm/s2]' or '# units: g'); or synthetic[:seed] (fixed-seed synthetic "
                        "accelerogram, PGA 0.4 g)"),
        Var("units", "parameter", "", type="String",
            description="Acceleration units of the record file for motion = 1: '' = as the file states them "
                        "(a CSV file that states none: m/s2); else one of g, m/s2, cm/s2 (= gal), mm/s2, in/s2, "
                        "ft/s2: the units of a CSV file that states none (an error if it states others), or "
                        "they replace those on the 3rd line of an AT2 file"),
        Var("ag", "output", unit="m/s2", description="Horizontal ground acceleration, positive in +x"),
        Var("vertical", "parameter", "", type="String",
            description="Vertical component for motion = 1: '' = the record's third CSV column if it has one, "
                        "else none (ag_v = 0); or a second file (.AT2, or a two-column .csv/.txt/.dat/.tsv in the "
                        "same units rules as record) holding ag_v, positive upward, on the record's time step "
                        "(the shorter of the two padded with zeros)"),
        Var("vertical_scale", "parameter", 1.0, unit="1",
            description="Scale factor applied to the vertical component (after scale), in [-10, 10]"),
        Var("ag_v", "output", unit="m/s2",
            description="Vertical ground acceleration, positive upward (0 when the motion has no vertical "
                        "component)"),
    )

    def create_simulator(self, p, t0):
        from ..cosim import MotionSource, ground_motion_from_parameters

        motion = ground_motion_from_parameters(p)
        if getattr(motion, "units_assumed", False):
            self.log(f"record {p['record']!r} does not state its acceleration units; read as {motion.units} "
                     "(set the parameter units to say otherwise)", Fmi2Status.warning)
        return MotionSource(motion, t0=t0)

    def advance(self, sim, t_end, inputs):
        sim.advance(t_end)


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
        from ..models.linear_building import LinearStorey, StoreySimulator

        return StoreySimulator(LinearStorey(T=p["T"], zeta=p["zeta"]), t0=t0, u_0=p["u_0"], u_dot_0=p["u_dot_0"])


#: every FMU, by name (the model FMUs first)
FMUS = {cls.__name__: cls for cls in (RigidRockingBlock, FlexibleRockingOscillator, PostTensionedRockingBlock,
                                      GroundMotionSource, LinearBuildingStorey)}
