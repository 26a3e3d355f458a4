"""Second, independent importer: Open Simulation Platform's libcosim through libcosimpy.

Both rocking FMUs -- the pythonfmu ones and the self-contained ones -- run in libcosim with the
ground acceleration set before every step by an override manipulator, and give the same outputs as fmpy: bit-identical to the fmpy master of rocking_model.cosim
(same communication points, computed in integer nanoseconds as libcosim does) and equal to round-off to
fmpy.simulate_fmu (whose time grid start + n h differs from libcosim's in the last bits).
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

fmpy = pytest.importorskip("fmpy")
pytest.importorskip("pythonfmu")
try:
    import libcosimpy.CosimExecution  # noqa: F401
except Exception as exc:  # pragma: no cover - depends on the platform
    pytest.skip(f"libcosimpy cannot be imported ({exc!r}); install the 'cosim' extra (Linux/Windows x86_64)",
                allow_module_level=True)

from rocking_model.cosim import Component, Connection, System, load_record, run_fmpy, run_libcosim  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
RIGID_OUT = ["phi", "phi_dot", "x", "y", "x_dot", "y_dot", "energy", "contact", "impacts", "overturned"]
#: [same units as each output] the self-contained FMUs against the pythonfmu ones: round-off of the
#: compiled engine against the Python one (measured ~1e-14 rad over 2 s of rocking with impacts)
ROUND_OFF = 1e-10
FLEX_OUT = ["u", "u_dot", "phi", "phi_dot", "x", "y", "top_displacement", "energy", "contact", "impacts"]


@pytest.fixture(scope="module")
def fmus(built_fmus):
    return built_fmus


@pytest.fixture(scope="module")
def standalone(build_module, tmp_path_factory):
    import fault_harness as fh

    try:
        return fh.standalone_fmus(build_module, tmp_path_factory)
    except Exception as exc:
        pytest.skip(f"the self-contained FMUs could not be built: {exc!r}")


KINDS = ["pythonfmu", "standalone"]


def pulse(A, period=1.0):
    return lambda t: A * math.sin(2 * math.pi * t / period) if t < period else 0.0


CASES = [
    ("RigidRockingBlock", 0, 2.5, RIGID_OUT),
    ("RigidRockingBlock", 1, 2.5, RIGID_OUT),
    ("FlexibleRockingOscillator", 0, 3.0, FLEX_OUT),
    ("FlexibleRockingOscillator", 1, 3.0, FLEX_OUT),
]


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("name, scheme, A, outputs", CASES, ids=[f"{c[0]}-scheme{c[1]}" for c in CASES])
def test_fmu_in_libcosim_matches_fmpy(request, kind, name, scheme, A, outputs):
    fmus = request.getfixturevalue("fmus" if kind == "pythonfmu" else "standalone")
    h, stop = 0.01, 2.0
    ag = pulse(A)
    system = System([Component("m", fmus[name], start_values={"scheme": scheme})], [], step_size=h)
    keys = [f"m.{k}" for k in outputs]
    cosim = run_libcosim(system, stop, keys, inputs={"m.ag": ag})
    master = run_fmpy(system, stop, keys, inputs={"m.ag": ag})
    assert len(cosim) == 200 and len(master) == 201
    np.testing.assert_array_equal(cosim["time"], master["time"][1:])
    assert np.abs(cosim["m.phi"]).max() > 0.02 and cosim["m.impacts"][-1] >= 1  # it rocks and impacts
    # libcosim and the fmpy master: the same doubles in, the same doubles out
    for k in keys:
        np.testing.assert_array_equal(cosim[k], master[k][1:], err_msg=k)
    # plain fmpy.simulate_fmu with the input table ag(t_n) (held over each step): equal to round-off
    t = np.round(np.arange(0, 201) * h, 12)
    table = np.array([(ti, ag(ti)) for ti in t], dtype=[("time", float), ("ag", float)])
    ref = fmpy.simulate_fmu(str(fmus[name]), stop_time=stop, output_interval=h, input=table,
                            start_values={"scheme": scheme}, output=outputs)
    assert len(ref) == 201
    for k in outputs:
        np.testing.assert_allclose(cosim[f"m.{k}"], ref[k][1:].astype(float), rtol=1e-12, atol=1e-11,
                                   err_msg=k)


def test_standalone_fmu_in_libcosim_equals_the_pythonfmu_fmu(fmus, standalone):
    """The self-contained block in libcosim gives the pythonfmu block's outputs to round-off (both driven by
    the same ag(t_n) in the same libcosim master)."""
    system = System([Component("m", fmus["RigidRockingBlock"], start_values={"scheme": 1})], [], step_size=0.01)
    ag = pulse(2.5)
    keys = [f"m.{k}" for k in RIGID_OUT]
    py = run_libcosim(system, 2.0, keys, inputs={"m.ag": ag})
    system.components[0].fmu = standalone["RigidRockingBlock"]
    sa = run_libcosim(system, 2.0, keys, inputs={"m.ag": ag})
    assert np.abs(sa["m.phi"]).max() > 0.02
    for k in keys:
        np.testing.assert_allclose(sa[k], py[k], rtol=0, atol=ROUND_OFF, err_msg=k)


def test_source_fmu_drives_block_in_libcosim(fmus, tmp_path):
    """Connection transfer in libcosim: a record that starts at a non-zero ag(t0), source -> block, equals the
    fmpy master and the block driven directly by the same ag(t_n) (so ag(t0) reaches the first step)."""
    record = tmp_path / "record.csv"
    t = np.linspace(0.0, 1.5, 16)
    a = 2.4 * np.cos(2 * np.pi * t / 0.75)
    np.savetxt(record, np.c_[t, a], delimiter=",", header="time [s], ag [m/s2]")
    system = System([Component("ground", fmus["GroundMotionSource"], start_values={"motion": 1, "record": str(record)}),
                     Component("block", fmus["RigidRockingBlock"], start_values={"scheme": 1})],
                    [Connection(("ground", "ag"), ("block", "ag"))], step_size=0.01)
    keys = ["ground.ag", "block.phi", "block.impacts"]
    cosim = run_libcosim(system, 2.0, keys)
    master = run_fmpy(system, 2.0, keys)
    assert cosim["ground.ag"][0] != 0.0 and np.abs(cosim["block.phi"]).max() > 0.01
    for k in keys:
        np.testing.assert_array_equal(cosim[k], master[k][1:], err_msg=k)
    motion = load_record(record)
    direct = run_libcosim(System([Component("block", fmus["RigidRockingBlock"], start_values={"scheme": 1})], [],
                                 step_size=0.01), 2.0, ["block.phi"], inputs={"block.ag": motion})
    np.testing.assert_array_equal(cosim["block.phi"], direct["block.phi"])


def test_invalid_parameter_fails_the_run_and_the_process_survives(fmus, tmp_path):
    """With invalid parameters the FMU answers fmi2Error in fmi2ExitInitializationMode. libcosim ends its process
    on an error during initialization (an exception escapes its worker thread), so run_libcosim initializes
    every component through fmpy first and raises ValueError with the FMU's message; the process goes on and
    the next run works (checked in a subprocess, where an abort would show as a signal)."""
    import subprocess
    import sys
    import textwrap

    code = textwrap.dedent(f"""
        from rocking_model.cosim import Component, System, run_libcosim
        fmu = {str(fmus["RigidRockingBlock"])!r}
        try:
            run_libcosim(System([Component("m", fmu, start_values={{"b": -0.2}})], [], step_size=0.01), 0.1,
                         ["m.phi"])
            print("NOT REFUSED")
        except ValueError as exc:
            print("REFUSED", exc)
        try:
            run_libcosim(System([Component("m", fmu)], [], step_size=0.01), 0.1, ["m.phi"],
                         start_values={{"m.e_N": 1.5}})
            print("NOT REFUSED")
        except ValueError as exc:
            print("REFUSED", exc)
        out = run_libcosim(System([Component("m", fmu, start_values={{"phi_0": 0.01}})], [], step_size=0.01),
                           0.1, ["m.phi"])
        print("ROWS", len(out))
    """)
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120,
                          cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert "NOT REFUSED" not in proc.stdout and "ROWS 10" in proc.stdout, proc.stdout
    assert "REFUSED component m: " in proc.stdout, proc.stdout
    assert "b = -0.2 is out of range; allowed range [1e-06, 1000]" in proc.stdout
    assert "e_N = 1.5 is out of range; allowed range [0, 1]" in proc.stdout
