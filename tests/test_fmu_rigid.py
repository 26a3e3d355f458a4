"""RigidRockingBlock FMU: build, validation, equivalence with the Python Simulator, error paths."""
from __future__ import annotations

import importlib.util
import math
import re
import zipfile
from pathlib import Path
from xml.etree import ElementTree

import numpy as np
import pytest

fmpy = pytest.importorskip("fmpy")
pytest.importorskip("pythonfmu")
from fmpy.simulation import Input  # noqa: E402
from fmpy.validation import validate_fmu  # noqa: E402

from rocking_model.fmi import FMUError, run_fmu  # noqa: E402
from rocking_model.models.rigid_block import RigidBlock  # noqa: E402
from rocking_model.simulation import Simulator  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]

PARAMS = dict(b=0.2, h=1.0, m=1.0, g=9.81, e_N=0.0, phi_0=0.0, phi_dot_0=0.0, dt_max=1e-3, tolerance=1e-8)
OUTPUTS = ["phi", "phi_dot", "x", "y", "x_dot", "y_dot", "slip", "energy", "contact", "impacts", "overturned",
           "friction_demand", "painleve"]


@pytest.fixture(scope="session")
def fmu(built_fmus) -> Path:
    return built_fmus["RigidRockingBlock"]


def pulse_table(amplitude, t_end=2.0, period=1.0, n=201):
    """One-sine ground-acceleration pulse as an fmpy input table (no duplicate times: no input events)."""
    t = np.linspace(0.0, t_end, n)
    ag = np.where(t < period, amplitude * np.sin(2 * np.pi * t / period), 0.0)
    return np.array(list(zip(t, ag)), dtype=[("time", np.float64), ("ag", np.float64)])


def reference(table, scheme, start, stop, h, params=PARAMS):
    """Drive the Simulator as fmpy drives the FMU: communication points start + n h, the input set at the
    start of each step from fmpy's interpolant of the table (zero-order hold over the step)."""
    p = params
    sim = Simulator(RigidBlock(b=p["b"], h=p["h"], m=p["m"], g=p["g"], e_N=p["e_N"], mu=p.get("mu", math.inf)),
                    scheme=scheme,
                    dt_max=p["dt_max"], tolerance=p["tolerance"], t0=start, phi_0=p["phi_0"],
                    phi_dot_0=p["phi_dot_0"])
    values = table["ag"].reshape(1, -1)
    times, rows = [start], [sim.outputs()]
    time, n = start, 0
    frozen = False
    while not (time > stop or math.isclose(time, stop)):
        nxt = start + (n + 1) * h
        ag = float(Input.interpolate(time=time, t=table["time"], table=values, after_event=True)[0][0])
        if not frozen:  # the FMU stops integrating once the block has overturned
            sim.advance(time + (nxt - time), ag)
            frozen = sim.outputs()["overturned"]
        time = nxt
        n += 1
        times.append(time)
        rows.append(sim.outputs())
    return np.array(times), {k: np.array([r[k] for r in rows]) for k in rows[0]}


def model_description(fmu_path):
    with zipfile.ZipFile(fmu_path) as zf:
        return ElementTree.fromstring(zf.read("modelDescription.xml"))


# ---------------------------------------------------------------------------------------------- XML
def test_validate_fmu_reports_no_problems(fmu):
    assert validate_fmu(str(fmu)) == []


def test_model_description_units_variability_structure(fmu):
    root = model_description(fmu)
    assert [c.tag for c in root] == ["CoSimulation", "UnitDefinitions", "LogCategories", "DefaultExperiment",
                                     "ModelVariables", "ModelStructure"]
    assert root.get("description")
    cs = root.find("CoSimulation")
    assert cs.get("canInterpolateInputs") == "true"  # fmi2SetRealInputDerivatives of order 1
    assert cs.get("maxOutputDerivativeOrder") in (None, "0")
    assert cs.get("canGetAndSetFMUstate") == "true" and cs.get("canSerializeFMUstate") == "true"
    units = {u.get("name"): u.find("BaseUnit").attrib for u in root.find("UnitDefinitions")}
    assert units["m/s2"] == {"m": "1", "s": "-2"}
    assert units["J"] == {"kg": "1", "m": "2", "s": "-2"}
    assert units["rad/s"] == {"rad": "1", "s": "-1"}
    expected_units = dict(b="m", h="m", m="kg", g="m/s2", e_N="1", phi_0="rad", phi_dot_0="rad/s",
                          dt_max="s", tolerance="1", ag="m/s2", ag_v="m/s2", phi="rad", phi_dot="rad/s", x="m", y="m",
                          x_dot="m/s", y_dot="m/s", energy="J", mu="1", slip="m", friction_demand="1")
    variables = {}
    for i, sv in enumerate(root.find("ModelVariables"), start=1):
        (typ,) = list(sv)
        variables[sv.get("name")] = (i, sv, typ)
        assert sv.get("description"), sv.get("name")
        assert sv.get("variability"), sv.get("name")
        if typ.tag == "Real":
            assert typ.get("unit") in units, sv.get("name")
    assert {n: v[2].get("unit") for n, v in variables.items() if v[2].tag == "Real"} == expected_units
    assert set(variables) == set(expected_units) | {"scheme", "impact_law", "max_steps", "contact", "impacts",
                                                    "overturned", "painleve"}
    assert variables["mu"][2].get("start") == "INF" and variables["mu"][2].get("max") is None
    for name in ("b", "h", "m", "g", "e_N", "impact_law", "phi_0", "phi_dot_0", "scheme", "dt_max", "tolerance",
                 "max_steps"):
        sv = variables[name][1]
        assert (sv.get("causality"), sv.get("variability"), sv.get("initial")) == ("parameter", "fixed", "exact")
        assert variables[name][2].get("start") is not None
    assert float(variables["b"][2].get("start")) == 0.2
    assert float(variables["g"][2].get("start")) == 9.81
    # scheme: an Integer (libcosim ignores FMI Enumerations) whose range and description come from the
    # registered schemes
    assert variables["scheme"][2].tag == "Integer" and variables["scheme"][2].get("start") == "1"
    assert (variables["scheme"][2].get("min"), variables["scheme"][2].get("max")) == ("0", "1")
    assert "0 moreau_jean (" in variables["scheme"][1].get("description")
    assert "1 event_driven (" in variables["scheme"][1].get("description")
    # start values, ranges and descriptions come from the model's declarations (one source of truth)
    from rocking_model.models import RigidBlock
    for p in RigidBlock.parameters() + RigidBlock.INITIAL:
        typ = variables[p.name][2]
        assert float(typ.get("start")) == p.check(p.default)
        for bound, value in (("min", p.fmu_min()), ("max", p.fmu_max())):
            assert (None if typ.get(bound) is None else float(typ.get(bound))) == value, (p.name, bound)
        assert variables[p.name][1].get("description").startswith(p.description)
    for name in ("ag", "ag_v"):  # the horizontal and the vertical ground acceleration: the same declaration
        sv, typ = variables[name][1], variables[name][2]
        assert (sv.get("causality"), sv.get("variability")) == ("input", "continuous")
        assert [float(typ.get(k)) for k in ("start", "min", "max")] == [0.0, -1000.0, 1000.0]
    # the sign convention of ag_v is stated where the importer reads it
    assert "positive upward" in variables["ag_v"][1].get("description")
    assert "g + ag_v" in variables["ag_v"][1].get("description")
    for name in OUTPUTS:
        sv, typ = variables[name][1], variables[name][2]
        assert sv.get("causality") == "output" and sv.get("initial") == "calculated"
        assert sv.get("variability") == ("continuous" if typ.tag == "Real" else "discrete")
        assert typ.get("start") is None
    assert variables["contact"][2].tag == "Integer" and variables["impacts"][2].tag == "Integer"
    assert variables["overturned"][2].tag == "Boolean"
    structure = root.find("ModelStructure")
    out_idx = sorted(variables[n][0] for n in OUTPUTS)
    assert sorted(int(u.get("index")) for u in structure.find("Outputs")) == out_idx
    assert sorted(int(u.get("index")) for u in structure.find("InitialUnknowns")) == out_idx


def test_fmu_bundles_package_without_bytecode(fmu):
    import build_fmu

    names = zipfile.ZipFile(fmu).namelist()
    alias = f"rocking_model_{build_fmu.package_digest()}"   # the bundled copy's own import name
    assert f"resources/{alias}/fmi/slave.py" in names
    assert f"resources/{alias}/simulation.py" in names
    assert "resources/RigidRockingBlock.py" in names
    assert not [n for n in names if n.startswith("resources/rocking_model/")]
    assert not [n for n in names if "__pycache__" in n or n.endswith(".pyc")]


# ---------------------------------------------------------------------------------------------- runs
@pytest.mark.parametrize("scheme", [0, 1])
def test_fmu_matches_python_simulator(fmu, scheme):
    table = pulse_table(2.5)
    start, stop, h = 0.0, 2.0, 0.01
    res = fmpy.simulate_fmu(str(fmu), start_time=start, stop_time=stop, output_interval=h, input=table,
                            start_values={**PARAMS, "scheme": scheme})
    t_ref, ref = reference(table, scheme, start, stop, h)
    assert len(res) == len(t_ref) == 201
    np.testing.assert_array_equal(res["time"], t_ref)
    assert np.abs(res["phi"]).max() > 0.1  # it rocks
    assert res["impacts"][-1] >= 1
    # the FMU runs the compiled engine as the Simulator does: the same bits
    for name in OUTPUTS:
        np.testing.assert_array_equal(res[name].astype(float), ref[name].astype(float), err_msg=name)


@pytest.mark.parametrize("scheme", [0, 1])
def test_fmu_with_friction_matches_python_simulator(fmu, scheme):
    """mu = 0.45 on a b = 0.3, h = 0.6 block (tan(alpha) = 0.5) under a 0.8 g one-sine pulse: it slides,
    rocks and slides on its pivot; the FMU gives the Python simulator's outputs, slip and friction demand
    included, and the default mu = inf set explicitly gives the default run."""
    table = pulse_table(0.8 * 9.81, period=0.5)
    start, stop, h = 0.0, 2.0, 0.01
    params = {**PARAMS, "b": 0.3, "h": 0.6, "mu": 0.45}
    res = fmpy.simulate_fmu(str(fmu), start_time=start, stop_time=stop, output_interval=h, input=table,
                            start_values={**params, "scheme": scheme})
    t_ref, ref = reference(table, scheme, start, stop, h, params=params)
    assert np.abs(res["slip"]).max() > 1e-3 and res["friction_demand"][-1] == pytest.approx(0.45)
    assert set(res["contact"]) & {4, 5, 6, 7, 8, 9}
    for name in OUTPUTS:
        np.testing.assert_array_equal(res[name].astype(float), ref[name].astype(float), err_msg=name)
    inf = fmpy.simulate_fmu(str(fmu), start_time=start, stop_time=stop, output_interval=h, input=table,
                            start_values={**params, "mu": math.inf, "scheme": scheme})
    default = fmpy.simulate_fmu(str(fmu), start_time=start, stop_time=stop, output_interval=h, input=table,
                                start_values={**{k: v for k, v in params.items() if k != "mu"}, "scheme": scheme})
    for name in OUTPUTS:
        np.testing.assert_array_equal(inf[name], default[name], err_msg=name)


def test_overturning_freezes_outputs_and_keeps_stepping(fmu):
    table = pulse_table(6.0)
    res = run_fmu(fmu, stop_time=2.0, output_interval=0.01, input=table, start_values={"scheme": 1})
    assert math.isclose(res["time"][-1], 2.0)
    over = np.flatnonzero(res["overturned"])
    assert over.size and over[-1] == len(res) - 1 and np.all(np.diff(over) == 1)
    k = over[0]
    assert abs(res["phi"][k]) >= 0.5 * math.pi - 1e-6
    for name in ("phi", "phi_dot", "x", "y", "energy", "contact", "impacts"):
        assert np.all(res[name][k:] == res[name][k]), name


def test_default_start_values_run(fmu):
    res = run_fmu(fmu, stop_time=0.1, output_interval=0.01)
    assert len(res) == 11
    assert np.abs(res["phi"]).max() < 1e-12 and np.all(res["contact"] == 0) and not res["overturned"].any()


# ---------------------------------------------------------------------------------------------- errors
@pytest.mark.parametrize("start_values, pattern, call", [
    ({"b": -1.0}, r"b = -1 is out of range; allowed range \[1e-06, 1000\]", "fmi2ExitInitializationMode"),
    # an Enumeration value that is none of its items is refused where it is set
    ({"scheme": 5}, r"scheme = 5 is not supported; allowed values: 'moreau_jean', 0, 'event_driven', 1",
     "fmi2ExitInitializationMode"),
    ({"e_N": 1.5}, r"e_N = 1.5 is out of range; allowed range \[0, 1\]", "fmi2ExitInitializationMode"),
    ({"phi_0": 2.0}, r"phi_0 = 2 is out of range", "fmi2ExitInitializationMode"),
])
def test_bad_parameter_is_an_error_not_a_crash(fmu, start_values, pattern, call):
    messages = []

    def logger(env, instance, status, category, message):
        messages.append((status, message.decode()))

    # plain fmpy: fmi2ExitInitializationMode fails (pythonfmu 0.7 can only say fmi2Fatal), fmpy raises, and
    # the message naming the variable reaches the logger
    with pytest.raises(fmpy.fmi1.FMICallException, match=call):
        fmpy.simulate_fmu(str(fmu), stop_time=1.0, output_interval=0.01, start_values=start_values,
                          debug_logging=True, logger=logger)
    assert any(re.search(pattern, m) for s, m in messages if s >= 3), messages
    # run_fmu turns that into an FMUError naming the variable
    with pytest.raises(FMUError, match=pattern):
        run_fmu(fmu, stop_time=1.0, output_interval=0.01, start_values=start_values)
    # the process (and the embedded interpreter) is fine
    res = run_fmu(fmu, stop_time=0.05, output_interval=0.01)
    assert math.isclose(res["time"][-1], 0.05)


def test_enumeration_start_values_by_name(fmu):
    """scheme is a choice: run_fmu takes its names (fmpy itself passes start values through int(),
    so fmpy.simulate_fmu(start_values={"scheme": "moreau_jean"}) cannot), and a misspelt name is an FMUError
    listing the choices."""
    by_name = run_fmu(fmu, stop_time=0.3, output_interval=0.01, start_values={"scheme": "moreau_jean",
                                                                              "phi_0": 0.05})
    by_code = run_fmu(fmu, stop_time=0.3, output_interval=0.01, start_values={"scheme": 0, "phi_0": 0.05})
    assert by_name["phi"].tobytes() == by_code["phi"].tobytes()
    event = run_fmu(fmu, stop_time=0.3, output_interval=0.01, start_values={"scheme": "event_driven",
                                                                            "phi_0": 0.05})
    assert event["phi"].tobytes() != by_code["phi"].tobytes()
    with pytest.raises(FMUError, match=r"scheme = 'moreau-jean' is not one of its choices: moreau_jean, event_driven"):
        run_fmu(fmu, stop_time=0.3, output_interval=0.01, start_values={"scheme": "moreau-jean"})


def test_non_finite_input_is_rejected(fmu):
    """A NaN in the input table is refused where fmpy sets it (fmi2SetReal: fmi2Error, naming ag and its range);
    run_fmu raises FMUError with the message."""
    table = np.array([(0.0, 0.0), (0.05, 0.0), (0.06, np.nan), (1.0, np.nan)],
                     dtype=[("time", np.float64), ("ag", np.float64)])
    with pytest.raises(FMUError, match=r"fmi2SetReal: input ag = nan is not finite; allowed range "
                                       r"\[-1000, 1000\] \(nothing was set\)"):
        run_fmu(fmu, stop_time=1.0, output_interval=0.01, input=table)


def test_slave_api_directly():
    """Life cycle of the slave class without the binary: every invalid call raises ValueError naming the
    problem (the binary turns it into fmi2Error) and changes nothing."""
    spec = importlib.util.spec_from_file_location("RigidRockingBlock", ROOT / "fmu_src" / "RigidRockingBlock.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    slave = module.RigidRockingBlock(instance_name="test")
    vr = {v.name: v.value_reference for v in slave.vars.values()}
    slave.setup_experiment(1.0)
    slave.enter_initialization_mode()
    slave.set_real([vr["phi_0"]], [0.05])
    slave.exit_initialization_mode()
    assert slave.get_real([vr["phi"]]) == [0.05]
    with pytest.raises(ValueError, match=r"communicationStepSize = 0.0 is invalid; allowed range \(0, inf\)"):
        slave.do_step(1.0, 0.0)
    assert slave.get_real([vr["phi"]]) == [0.05]
    assert slave.do_step(1.0, 0.01) is True
    phi = slave.get_real([vr["phi"]])[0]
    assert 0.0 < phi < 0.05
    # a fixed parameter cannot change after initialization; setting the same value again is harmless
    with pytest.raises(ValueError, match=r"parameter b is 'fixed' and cannot be changed after initialization"):
        slave.set_real([vr["b"]], [0.3])
    assert slave.get_real([vr["b"]]) == [0.2]
    slave.set_real([vr["b"]], [0.2])
    assert slave.do_step(1.01, 0.01) is True
    # steps must be contiguous, positive
    with pytest.raises(ValueError, match=r"currentCommunicationPoint = 0.5 does not match the FMU time"):
        slave.do_step(0.5, 0.01)
    with pytest.raises(ValueError, match=r"communicationStepSize = -0.01"):
        slave.do_step(1.02, -0.01)
    # outputs cannot be set, unknown references and wrong types are refused; nothing of the call is set
    with pytest.raises(ValueError, match=r"phi is an output and cannot be set.*value reference 9999 is unknown.*"
                                         r"\(nothing was set\)"):
        slave.set_real([vr["phi"], 9999, vr["ag"]], [1.0, 1.0, 2.0])
    assert slave.get_real([vr["ag"]]) == [0.0]
    with pytest.raises(ValueError, match=f"value reference {vr['phi']} is 'phi', a Real variable, not Integer"):
        slave.get_integer([vr["phi"]])
    with pytest.raises(ValueError, match=r"input ag = 2000 is out of range; allowed range \[-1000, 1000\]"):
        slave.set_real([vr["ag"]], [2000.0])
    assert slave.do_step(1.02, 0.01) is True
    assert slave.get_real([vr["phi"]])[0] < phi
    slave.terminate()
    with pytest.raises(ValueError, match="after fmi2Terminate"):
        slave.do_step(1.03, 0.01)


def test_max_steps_parameter_bounds_the_work_of_a_step(fmu):
    # Moreau-Jean at dt_max = 1e-3 s: a 0.5 s communication step needs 500 internal steps
    with pytest.raises(FMUError, match=r"more than max_steps = 100 per advance.*Way out"):
        run_fmu(fmu, stop_time=1.0, output_interval=0.5, start_values={"scheme": 0, "max_steps": 100})
    res = run_fmu(fmu, stop_time=1.0, output_interval=0.5, start_values={"scheme": 0, "max_steps": 500,
                                                                        "phi_0": 0.01})
    assert math.isclose(res["time"][-1], 1.0) and res["impacts"][-1] >= 1
    with pytest.raises(FMUError, match=r"max_steps = 0 is out of range"):
        run_fmu(fmu, stop_time=1.0, output_interval=0.5, start_values={"max_steps": 0})


def test_readme_quickstart_shows_what_it_says(fmu):
    """The README's fmpy quickstart (the same on docs/guide/fmus.md), run as written with the session's FMU,
    prints what the README quotes, and the prose says what the run shows: at 3 m/s2 uplift, a peak of 0.34 alpha
    near 0.75 s, 9 impacts, contact alternating between the corners, no overturning; at 4.5 m/s2 one impact at
    0.46 s and the overturning at about 3.0 s (not at the first excursion)."""
    import contextlib
    import io
    import re

    root = Path(__file__).resolve().parents[1]
    for page in (root / "README.md", root / "docs" / "guide" / "fmus.md"):
        text = page.read_text()
        section = text.split("## Quickstart: FMU with fmpy", 1)[1]
        block = section.split("```python\n", 1)[1].split("```", 1)[0]
        quoted = section.split("```text\n", 1)[1].split("```", 1)[0]
        scope: dict = {}
        printed = io.StringIO()
        with contextlib.redirect_stdout(printed):
            exec(compile(block.replace('"dist/RigidRockingBlock.fmu"', repr(str(fmu))), str(page), "exec"), scope)
        lines = [ln for ln in quoted.splitlines() if ln.startswith("A = ")]
        assert [ln for ln in printed.getvalue().splitlines() if ln.startswith("A = ")] == lines, page
        prose = " ".join(section.split("```text\n", 1)[1].split("```", 1)[1].split())
        assert "impacts once, at 0.46 s" in prose and "overturns at about 3.0 s" in prose, page
        assert "first excursion" not in section
    m = re.search(r"A = 4.5 m/s2: first impact at 0.46-0.47 s, 1 impacts, .* overturned at (\d\.\d\d) s", quoted)
    assert m and abs(float(m.group(1)) - 3.0) < 0.05
    # the 3 m/s2 scene's modes, which the prose states
    import numpy as np
    from fmpy import simulate_fmu
    t = np.linspace(0, 5, 501)
    signal = np.array(list(zip(t, 3.0 * np.sin(2 * np.pi * 2 * t) * (t < 0.5), 0 * t)),
                      dtype=[("time", float), ("ag", float), ("ag_v", float)])
    res = simulate_fmu(str(fmu), start_time=0, stop_time=5, output_interval=0.01, input=signal,
                       start_values={"b": 0.2, "h": 1.0}, output=["phi", "contact", "overturned"])
    k = int(np.argmax(np.abs(res["phi"])))
    assert abs(abs(res["phi"][k]) / math.atan(0.2) - 0.34) < 0.005 and abs(res["time"][k] - 0.75) < 0.015
    assert not res["overturned"].any() and set(np.unique(res["contact"])) >= {1, 2}


def test_generation_tool_names_the_project_and_its_version(built_fmus):
    """generationTool of every built FMU: this project and the package's version (rocking_model.__version__,
    its one source), not the pythonfmu library the slave classes derive from."""
    import rocking_model

    for name, path in built_fmus.items():
        tool = model_description(path).get("generationTool")
        assert tool == f"rocking_model {rocking_model.__version__}", (name, tool)


def test_run_fmu_record_returns_the_initial_row(fmu):
    """run_fmu_record starts with the row at t = 0 (the state after initialization), as simulate() does: same
    time grid and, on a block released from phi_0 = 0.05 under a short record, the same first row."""
    from rocking_model import simulate
    from rocking_model.fmi import run_fmu_record
    from rocking_model.ground_motion import SampledMotion

    t = np.linspace(0.0, 0.5, 51)
    a = 0.5 * np.sin(2 * np.pi * t)            # far below the uplift level g tan(alpha) = 1.96 m/s2
    out = run_fmu_record(fmu, t, a, step=0.01, stop_time=0.3, start_values={"phi_0": 0.05},
                         output=("phi", "phi_dot"))
    ref = simulate(RigidBlock(), SampledMotion(t, a), t_end=0.3, output_interval=0.01, phi_0=0.05)
    assert out["time"][0] == 0.0 and ref.t[0] == 0.0
    assert (out["phi"][0], out["phi_dot"][0]) == (0.05, 0.0) == (ref.phi[0], ref.phi_dot[0])
    np.testing.assert_allclose(out["time"], ref.t, rtol=0, atol=1e-12)
