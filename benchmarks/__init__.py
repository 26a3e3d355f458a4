"""Benchmark suite of rocking_model: scenes, references, contenders (the package's schemes, a scipy
solve_ivp baseline, Siconos), FMU overhead, memory. Run with ``python -m benchmarks [--quick]``; it
regenerates docs/performance.md. Not part of the test suite."""
