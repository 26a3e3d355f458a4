"""FMI 2.0 co-simulation FMU that outputs a horizontal ground acceleration ag(t) (no inputs).

Thin wrapper: the motions are `rocking_model.ground_motion` (`SinePulse`, `SampledMotion`), chosen from the
parameters by `rocking_model.cosim.ground_motion_from_parameters`; the FMI plumbing is `rocking_model.fmi`.
At every communication point t the output is ag(t); an importer that holds it over the next step (any
fixed-step master) drives a connected rocking FMU exactly like a standalone run with the table ag(t_n).
"""
from rocking_model.fmi import DefaultExperiment, RockingSlave, Var


class GroundMotionSource(RockingSlave):
    """Ground-motion source: one-sine pulse or a sampled record file, times a scale factor."""

    description = ("Ground-motion source: outputs the horizontal ground acceleration ag(t) of a one-sine pulse "
                   "(motion = 0: A sin(omega_p (t - t_start)) for one period) or of a sampled record file "
                   "(motion = 1: two columns time [s], ag [m/s2], linear interpolation, 0 outside), times "
                   "scale. ag is the value at the communication point.")
    default_experiment = DefaultExperiment(start_time=0.0, stop_time=5.0, step_size=0.01)
    freeze_output = None

    variables = (
        Var("motion", "parameter", 0, type="Integer", min=0, max=1,
            description="Kind of motion: 0 one-sine pulse, 1 sampled record file (parameter record)"),
        Var("A", "parameter", 0.4 * 9.81, unit="m/s2", description="Pulse amplitude"),
        Var("omega_p", "parameter", 6.283185307179586, unit="rad/s",
            description="Pulse circular frequency (> 0); the pulse lasts 2 pi / omega_p"),
        Var("t_start", "parameter", 0.0, unit="s", description="Start time of the pulse"),
        Var("scale", "parameter", 1.0, unit="1", description="Scale factor applied to the motion"),
        Var("record", "parameter", "", type="String",
            description="Record file for motion = 1: absolute path (or relative to the importer's working "
                        "directory) of a text/CSV file with columns time [s], ag [m/s2]"),
        Var("ag", "output", unit="m/s2", description="Horizontal ground acceleration, positive in +x"),
    )

    def create_simulator(self, p, t0):
        from rocking_model.cosim import MotionSource, ground_motion_from_parameters

        return MotionSource(ground_motion_from_parameters(p), t0=t0)

    def advance(self, sim, t_end, inputs):
        sim.advance(t_end)
