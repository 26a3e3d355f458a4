"""System-level co-simulation: source and storey FMUs, the fmpy master, the OSP example (also in libcosim)."""
from __future__ import annotations

import importlib.util
import math
import zipfile
from pathlib import Path

import numpy as np
import pytest

fmpy = pytest.importorskip("fmpy")
pytest.importorskip("pythonfmu")
from fmpy.validation import validate_fmu  # noqa: E402

from rocking_model.cosim import (Component, Connection, System, read_osp_system_structure,  # noqa: E402
                                 run_fmpy, write_osp_system_structure)
from rocking_model.fmi import FMUError, run_fmu  # noqa: E402
from rocking_model.ground_motion import SinePulse  # noqa: E402
from rocking_model.models.linear_building import LinearStorey, StoreySimulator  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "examples" / "system"
NAMES = ["GroundMotionSource", "LinearBuildingStorey", "RigidRockingBlock", "FlexibleRockingOscillator"]


def _load(name, path):
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def fmus(built_fmus):
    return built_fmus


def _libcosim():
    try:
        import libcosimpy.CosimExecution  # noqa: F401
    except Exception as exc:
        pytest.skip(f"libcosimpy cannot be imported ({exc!r})")


# ------------------------------------------------------------------------------ linear storey physics
def test_storey_step_response_is_exact():
    """Constant ag from rest: u(t) = -(a/w^2) (1 - exp(-z w t) (cos wd t + z/sqrt(1-z^2) sin wd t))."""
    storey = LinearStorey(T=0.4, zeta=0.05)
    sim = StoreySimulator(storey)
    a, w, z = 1.3, 2 * math.pi / 0.4, 0.05
    wd = w * math.sqrt(1 - z * z)
    for k in range(1, 101):
        t = 0.013 * k
        sim.advance(t, a)
        u = -(a / w**2) * (1 - math.exp(-z * w * t) * (math.cos(wd * t) + z / math.sqrt(1 - z * z) * math.sin(wd * t)))
        assert sim.outputs()["u"] == pytest.approx(u, rel=1e-10, abs=1e-14)
        out = sim.outputs()
        # absolute floor acceleration = relative acceleration + ag, from the equation of motion
        assert out["a_floor"] == pytest.approx(-(2 * z * w * out["u_dot"] + w * w * out["u"]), rel=1e-12)
    # free decay (ag = 0): the energy of the storey decreases
    energy = []
    for k in range(20):
        sim.advance(sim.t + 0.05, 0.0)
        energy.append(0.5 * sim.outputs()["u_dot"] ** 2 + 0.5 * w * w * sim.outputs()["u"] ** 2)
    assert np.all(np.diff(energy) < 0) and energy[-1] < 0.5 * energy[0]
    rigid = StoreySimulator(LinearStorey(T=0.0))
    rigid.advance(0.01, 2.5)
    assert rigid.outputs() == {"u": 0.0, "u_dot": 0.0, "a_floor": 2.5}
    with pytest.raises(ValueError, match=r"T = -1 is out of range"):
        LinearStorey(T=-1.0)


def test_storey_declared_ranges_are_the_checks(fmus):
    """The storey FMU declares the ranges its model checks: each declared bound is accepted by the model,
    a value just beyond it refused with a message naming the variable (T's gap (0, T_MIN) is named in
    its description)."""
    from fmpy import read_model_description

    from rocking_model.models.linear_building import T_MIN

    declared = {v.name: v for v in read_model_description(str(fmus["LinearBuildingStorey"])).modelVariables
                if v.causality == "parameter"}
    assert set(declared) == {"T", "zeta", "u_0", "u_dot_0"}

    def build(name, value):
        p = {"T": 0.5, "zeta": 0.05, "u_0": 0.0, "u_dot_0": 0.0, name: value}
        StoreySimulator(LinearStorey(T=p["T"], zeta=p["zeta"]), u_0=p["u_0"], u_dot_0=p["u_dot_0"])

    for name, var in declared.items():
        lo, hi = float(var.min), float(var.max)
        for bound in (lo, hi):
            build(name, bound)
        for beyond in (lo - max(1.0, abs(lo)) * 1e-6, hi + max(1.0, abs(hi)) * 1e-6):
            with pytest.raises(ValueError, match=rf"\b{name} = .* allowed"):
                build(name, beyond)
    assert f"{T_MIN:g}" in declared["T"].description
    with pytest.raises(ValueError, match=r"T = 1e-05 is out of range"):
        build("T", 1e-5)


# ------------------------------------------------------------------------------ FMUs
def test_new_fmus_validate_and_bundle_the_package(fmus):
    for name in ("GroundMotionSource", "LinearBuildingStorey"):
        assert validate_fmu(str(fmus[name])) == []
        names = zipfile.ZipFile(fmus[name]).namelist()
        assert f"resources/{name}.py" in names
        assert any(n.startswith("resources/rocking_model_") and n.endswith("/cosim.py") for n in names)


def test_source_fmu_outputs_the_pulse_at_the_communication_points(fmus):
    res = run_fmu(fmus["GroundMotionSource"], stop_time=1.0, output_interval=0.01,
                  start_values={"A": 3.0, "omega_p": 2 * math.pi / 0.5, "t_start": 0.1, "scale": 2.0})
    pulse = SinePulse(A=3.0, omega_p=2 * math.pi / 0.5, t0=0.1)
    expected = [2.0 * pulse(t) for t in res["time"]]
    np.testing.assert_allclose(res["ag"], expected, rtol=0, atol=1e-12)
    assert np.abs(res["ag"]).max() > 5.9


def test_source_fmu_reads_a_record_file(fmus, tmp_path):
    """A CSV file whose header states no units: read as m/s2 (the FMU's default), with a warning."""
    record = tmp_path / "rec.csv"
    record.write_text("time,ag\n0.0,0.0\n0.5,1.0\n1.0,-1.0\n")
    messages = []
    res = fmpy.simulate_fmu(str(fmus["GroundMotionSource"]), stop_time=1.2, output_interval=0.1,
                            start_values={"motion": 1, "record": str(record)}, debug_logging=True,
                            logger=lambda env, inst, status, cat, msg: messages.append((status, msg.decode())))
    np.testing.assert_allclose(res["ag"], np.interp(res["time"], [0, 0.5, 1.0], [0, 1.0, -1.0], right=0.0),
                               atol=1e-12)
    assert any("does not state its acceleration units; read as m/s2" in m for _, m in messages)
    with pytest.raises(FMUError, match=r"no such file"):
        run_fmu(fmus["GroundMotionSource"], stop_time=0.1, output_interval=0.1,
                start_values={"motion": 1, "record": str(tmp_path / "missing.csv")})


def test_source_fmu_reads_units_from_the_csv_header(fmus, tmp_path):
    """``time [s],ag [cm/s2]``: the FMU outputs m/s2, the file's values / 100 (it read them as m/s2 before)."""
    t = np.round(np.arange(0.0, 1.0 + 1e-9, 0.01), 12)
    a_cm = 250.0 * np.sin(2 * np.pi * t) * np.exp(-t)
    record = tmp_path / "cm.csv"
    record.write_text("time [s],ag [cm/s2]\n" + "".join(f"{ti!r},{ai!r}\n" for ti, ai in zip(t.tolist(), a_cm.tolist())))
    res = run_fmu(fmus["GroundMotionSource"], stop_time=1.0, output_interval=0.01,
                  start_values={"motion": 1, "record": str(record)})
    assert np.abs(res["ag"]).max() == pytest.approx(np.abs(a_cm).max() / 100.0, rel=1e-12)
    np.testing.assert_allclose(res["ag"], np.interp(res["time"], t, a_cm) / 100.0, rtol=0, atol=1e-12)
    # units = "cm/s2" agrees with the header; units = "g" contradicts it: the reader's error
    same = run_fmu(fmus["GroundMotionSource"], stop_time=1.0, output_interval=0.01,
                   start_values={"motion": 1, "record": str(record), "units": "cm/s2"})
    np.testing.assert_array_equal(same["ag"], res["ag"])
    with pytest.raises(FMUError) as exc:
        run_fmu(fmus["GroundMotionSource"], stop_time=0.1, output_interval=0.01,
                start_values={"motion": 1, "record": str(record), "units": "g"})
    assert "the file states units 'cm/s2', but units = 'g' was given" in str(exc.value)


def test_source_fmu_reads_a_peer_at2_file(fmus, tmp_path):
    """A PEER AT2 file (units of g): the FMU outputs the samples of `records.read_at2`."""
    from rocking_model.records import read_at2, synthetic_record, write_at2

    t, a = synthetic_record(duration=2.0, dt=0.01, seed=3)
    path = write_at2(tmp_path / "RSN_TEST.AT2", t, a, digits=7)          # PEER's 7 digits
    rec = read_at2(path)
    res = run_fmu(fmus["GroundMotionSource"], stop_time=2.0, output_interval=0.01,
                  start_values={"motion": 1, "record": str(path), "scale": 2.0})
    assert res["time"].size == rec.t.size
    np.testing.assert_allclose(res["ag"], 2.0 * rec.ag, rtol=1e-12, atol=1e-12)
    assert np.abs(res["ag"]).max() == pytest.approx(2.0 * rec.pga, rel=1e-12)


@pytest.mark.parametrize("name, text, units", [
    ("bad.csv", "time [s],ag [g]\n0.0,0.1\n0.01,abc\n", ""),
    ("back.csv", "time [s],ag [g]\n0.0,0.1\n0.02,0.2\n0.01,0.3\n", ""),
    ("bad.AT2", "title\nevent\nACCELERATION TIME SERIES IN UNITS OF G\nNPTS=  9, DT= .01 SEC\n.1 .2 .3\n", ""),
    ("ok.csv", "0.0,0.1\n0.01,0.2\n", "furlong"),
    ("rec.xlsx", "0.0,0.1\n0.01,0.2\n", ""),
])
def test_source_fmu_reports_the_record_readers_errors(fmus, tmp_path, name, text, units):
    """A bad record file: the FMU fails with the message of `rocking_model.records` (as the CLI prints it)."""
    from rocking_model.records import read_record

    path = tmp_path / name
    path.write_text(text)
    with pytest.raises(ValueError) as expected:
        read_record(path, units or None, default_units="m/s2")
    with pytest.raises(FMUError) as exc:
        run_fmu(fmus["GroundMotionSource"], stop_time=0.1, output_interval=0.01,
                start_values={"motion": 1, "record": str(path), "units": units})
    assert str(expected.value) in str(exc.value)


# ------------------------------------------------------------------------------ fmpy master
def test_block_driven_by_the_source_fmu_sees_the_standalone_ag(fmus):
    """source -> block in the fmpy master equals the standalone block driven by the table ag(t_n)."""
    pulse = dict(A=2.5, omega_p=2 * math.pi, t_start=0.0)
    system = System([Component("ground", fmus["GroundMotionSource"], start_values=pulse),
                     Component("block", fmus["RigidRockingBlock"], start_values={"scheme": 1})],
                    [Connection(("ground", "ag"), ("block", "ag"))], step_size=0.01)
    res = run_fmpy(system, 2.0, ["ground.ag", "block.phi", "block.impacts"])
    ag = SinePulse(A=2.5, omega_p=2 * math.pi)
    np.testing.assert_allclose(res["ground.ag"], [ag(t) for t in res["time"]], atol=1e-12)
    table = np.array([(t, ag(t)) for t in np.round(res["time"], 12)], dtype=[("time", float), ("ag", float)])
    ref = fmpy.simulate_fmu(str(fmus["RigidRockingBlock"]), stop_time=2.0, output_interval=0.01, input=table,
                            start_values={"scheme": 1}, output=["phi", "impacts"])
    assert np.abs(ref["phi"]).max() > 0.1 and ref["impacts"][-1] >= 1
    np.testing.assert_allclose(res["block.phi"], ref["phi"], rtol=0, atol=1e-12)
    np.testing.assert_array_equal(res["block.impacts"], ref["impacts"])


def test_rigid_storey_passes_the_ground_motion_one_step_later(fmus):
    """With an infinitely stiff storey (T = 0) the block sees the ground ag one communication step later
    (Jacobi transfer through one more component): identical to the block driven by ag(t_{n-1})."""
    h = 0.01
    pulse = dict(A=2.5, omega_p=2 * math.pi)
    system = System([Component("ground", fmus["GroundMotionSource"], start_values=pulse),
                     Component("storey", fmus["LinearBuildingStorey"], start_values={"T": 0.0}),
                     Component("block", fmus["RigidRockingBlock"], start_values={"scheme": 1})],
                    [Connection(("ground", "ag"), ("storey", "ag")), Connection(("storey", "a_floor"), ("block", "ag"))],
                    step_size=h)
    res = run_fmpy(system, 2.0, ["ground.ag", "storey.a_floor", "block.phi"])
    np.testing.assert_array_equal(res["storey.a_floor"][1:], res["ground.ag"][:-1])
    ag = SinePulse(A=2.5, omega_p=2 * math.pi)
    alone = run_fmpy(System([Component("block", fmus["RigidRockingBlock"], start_values={"scheme": 1})], [], h),
                     2.0, ["block.phi"], inputs={"block.ag": lambda t: ag(t - h) if t >= h else 0.0})
    assert np.abs(alone["block.phi"]).max() > 0.1
    np.testing.assert_allclose(res["block.phi"], alone["block.phi"], rtol=0, atol=1e-13)
    # a stiff elastic storey (T = 0.02 s, zeta = 0.7) is close to the rigid one
    stiff = run_fmpy(system, 2.0, ["block.phi"], start_values={"storey.T": 0.02, "storey.zeta": 0.7})
    assert np.abs(stiff["block.phi"] - res["block.phi"]).max() < 0.02 * np.abs(res["block.phi"]).max()


def test_osp_file_round_trip(example_osp, tmp_path):
    system = read_osp_system_structure(example_osp)
    assert [c.name for c in system.components] == ["ground", "storey", "block", "oscillator"]
    assert system.step_size == 0.005 and len(system.connections) == 5    # ag, a_floor x 2, ag_v x 2
    assert Connection(("storey", "a_floor"), ("block", "ag")) in system.connections
    assert system.component("ground").start_values == {"motion": 0, "A": 2.0, "omega_p": 4 * math.pi,
                                                        "t_start": 0.1}
    again = read_osp_system_structure(write_osp_system_structure(system, tmp_path / "OspSystemStructure.xml"))
    assert again == system


# ------------------------------------------------------------------------------ the example
@pytest.fixture(scope="module")
def example_osp(fmus, tmp_path_factory):
    """The example's OspSystemStructure.xml with the FMUs of this test session."""
    text = (EXAMPLE / "OspSystemStructure.xml").read_text()
    for name, path in fmus.items():
        text = text.replace(f"../../dist/{name}.fmu", str(path))
    osp = tmp_path_factory.mktemp("osp") / "OspSystemStructure.xml"
    osp.write_text(text)
    return osp


def test_example_system_libcosim_equals_fmpy_master(example_osp):
    _libcosim()
    example = _load("system_example", EXAMPLE / "run.py")
    results = example.run(stop=3.0, osp=example_osp)
    a, b = results["fmpy"], results["libcosim"]
    assert len(a) == 601 and len(b) == 600
    for k in example.OUTPUTS:
        np.testing.assert_array_equal(a[k][1:], b[k], err_msg=k)
    # the floor amplifies the pulse and both structures rock without overturning
    assert np.abs(a["storey.a_floor"]).max() > 2 * np.abs(a["ground.ag"]).max()
    assert np.abs(a["block.phi"]).max() > 0.05 and a["block.impacts"][-1] >= 2
    assert np.abs(a["oscillator.phi"]).max() > 0.05 and not a["block.overturned"].any()


def test_example_script_writes_csv_and_png(example_osp, tmp_path, monkeypatch):
    pytest.importorskip("matplotlib")
    example = _load("system_example", EXAMPLE / "run.py")
    monkeypatch.setattr(example, "OSP", example_osp)
    monkeypatch.setattr(example, "build_fmus", lambda force=False: None)
    assert example.main(["--stop", "0.5", "--out", str(tmp_path), "--master", "fmpy"]) == 0
    lines = (tmp_path / "system_fmpy.csv").read_text().splitlines()
    assert lines[0].split(",")[:3] == ["time", "ground.ag", "storey.u"] and len(lines) == 102
    assert (tmp_path / "system.png").stat().st_size > 10_000


def test_docs_state_the_example_step_count():
    """The co-simulation page's claim about the system example (docs/guide/cosimulation.md: it once said 800 steps
    where it runs 1000)."""
    import re
    import xml.etree.ElementTree as ET

    text = (ROOT / "docs" / "guide" / "cosimulation.md").read_text()
    m = re.search(r"its (\d+(?:\.\d+)?) s in (\d+) steps of (\d+) ms", text)
    assert m, "docs/guide/cosimulation.md no longer states the example's steps"
    stop, steps, ms = float(m.group(1)), int(m.group(2)), int(m.group(3))
    base = float(ET.parse(ROOT / "examples" / "system" / "OspSystemStructure.xml").getroot()
                 .find("{*}BaseStepSize").text)
    assert ms / 1000.0 == base and round(stop / base) == steps
    assert f'default={stop}' in (ROOT / "examples" / "system" / "run.py").read_text().replace(" ", "")


# ------------------------------------------------------------------------------ the self-contained block
#: [rad, m, m/s2] the system with the self-contained rocking FMUs against the pythonfmu ones: round-off of the
#: compiled engine against the Python one, carried through the storey (measured ~4e-13 over 3 s)
STANDALONE_ROUND_OFF = 1e-9


@pytest.fixture(scope="module")
def standalone_osp(fmus, build_module, tmp_path_factory):
    """The example's OspSystemStructure.xml with the self-contained block and oscillator."""
    import fault_harness as fh

    try:
        sa = fh.standalone_fmus(build_module, tmp_path_factory)
    except Exception as exc:
        pytest.skip(f"the self-contained FMUs could not be built: {exc!r}")
    text = (EXAMPLE / "OspSystemStructure.xml").read_text()
    for name, path in fmus.items():
        text = text.replace(f"../../dist/{name}.fmu", str(sa.get(name, path)))
    osp = tmp_path_factory.mktemp("osp_standalone") / "OspSystemStructure.xml"
    osp.write_text(text)
    return osp


def test_example_system_with_the_standalone_block(example_osp, standalone_osp):
    """The system example with the self-contained block and oscillator: both masters agree bit for bit, and
    the results equal those of the pythonfmu FMUs to round-off."""
    system = read_osp_system_structure(standalone_osp)
    assert {c.name: Path(c.fmu).parent.name for c in system.components}["block"] == "standalone"
    example = _load("system_example", EXAMPLE / "run.py")
    sa = example.run(stop=3.0, osp=standalone_osp, master="fmpy")["fmpy"]
    py = example.run(stop=3.0, osp=example_osp, master="fmpy")["fmpy"]
    for k in example.OUTPUTS:
        np.testing.assert_allclose(sa[k], py[k], rtol=0, atol=STANDALONE_ROUND_OFF, err_msg=k)
    assert np.abs(sa["block.phi"]).max() > 0.05 and sa["block.impacts"][-1] >= 2
    try:
        import libcosimpy.CosimExecution  # noqa: F401
    except Exception as exc:
        pytest.skip(f"libcosimpy cannot be imported ({exc!r}): fmpy master only")
    lc = example.run(stop=3.0, osp=standalone_osp, master="libcosim")["libcosim"]
    for k in example.OUTPUTS:
        np.testing.assert_array_equal(lc[k], sa[k][1:], err_msg=k)


def test_example_script_runs_the_standalone_block(example_osp, tmp_path, monkeypatch):
    """`run.py --standalone` puts the self-contained block and oscillator of dist/standalone/ in the system,
    the source and the storey stay the pythonfmu FMUs."""
    example = _load("system_example", EXAMPLE / "run.py")
    monkeypatch.setattr(example, "ROOT", tmp_path)
    sysm = example.system(example_osp, standalone=True)
    fmus = {c.name: Path(c.fmu) for c in sysm.components}
    assert fmus["block"] == tmp_path / "dist" / "standalone" / "RigidRockingBlock.fmu"
    assert fmus["oscillator"] == tmp_path / "dist" / "standalone" / "FlexibleRockingOscillator.fmu"
    assert fmus["storey"] == {c.name: Path(c.fmu) for c in
                              read_osp_system_structure(example_osp).components}["storey"]
