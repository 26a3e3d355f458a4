"""FMI 2.0 co-simulation FMU that outputs a horizontal ground acceleration ag(t) and a vertical one ag_v(t)
(positive upward; 0 without a vertical component) (no inputs).

Thin wrapper: the motion is chosen from the parameters by `rocking_model.cosim.ground_motion_from_parameters`
-- the pulse by `rocking_model.ground_motion.pulse_from_parameters` and the record file by
`rocking_model.records` (PEER AT2 and CSV, units from the file), both exactly as the ``rocking`` CLI and the
ensembles build them; the FMI plumbing is `rocking_model.fmi`.
At every communication point t the outputs are ag(t) and ag_v(t); an importer that holds it over the next step (any
fixed-step master) drives a connected rocking FMU exactly like a standalone run with the table ag(t_n).
"""
from rocking_model.fmi import DefaultExperiment, Fmi2Status, RockingSlave, Var


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
        from rocking_model.cosim import MotionSource, ground_motion_from_parameters

        motion = ground_motion_from_parameters(p)
        if getattr(motion, "units_assumed", False):
            self.log(f"record {p['record']!r} does not state its acceleration units; read as {motion.units} "
                     "(set the parameter units to say otherwise)", Fmi2Status.warning)
        return MotionSource(motion, t0=t0)

    def advance(self, sim, t_end, inputs):
        sim.advance(t_end)
