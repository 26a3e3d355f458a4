"""Do-nothing FMI 2.0 co-simulation FMU (pythonfmu): the floor of the FMU benchmark.

One Real input `ag` and one Real output `y`; `do_step` copies the input to the output and returns True.
Driving it with the same master loop as the rocking FMUs measures what fmpy + pythonfmu cost per step
without any physics. Built by `benchmarks.fmu_bench.build_null_fmu` (module name unique on purpose).
"""
from pythonfmu import Fmi2Causality, Fmi2Slave, Fmi2Variability, Real


class NullSlave(Fmi2Slave):
    author = "rocking_model benchmarks"
    description = "Do-nothing FMU: y = ag, do_step returns True"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.ag = 0.0
        self.y = 0.0
        self.register_variable(Real("ag", causality=Fmi2Causality.input, variability=Fmi2Variability.continuous))
        self.register_variable(Real("y", causality=Fmi2Causality.output, variability=Fmi2Variability.continuous))

    def do_step(self, current_time, step_size):
        self.y = self.ag
        return True
