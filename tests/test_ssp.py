"""The system example as an SSP 1.0 archive: the archive's layout, the .ssd against the SSP 1.0
structure, the round trip through read_ssp, and the masters run on the archive with the OSP file's results
(bit-identical: the same master algorithm on the same system)."""
from __future__ import annotations

import importlib.util
import zipfile
from pathlib import Path
from xml.etree import ElementTree

import numpy as np
import pytest

fmpy = pytest.importorskip("fmpy")
pytest.importorskip("pythonfmu")

from rocking_model.cosim import (PARAMETER_SET, SSD_NAMESPACES, read_osp_system_structure,  # noqa: E402
                                 read_ssp, run_fmpy, run_libcosim, write_ssp)

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "examples" / "system"
NS = SSD_NAMESPACES
STOP = 1.0  # [s] 200 base steps: the pulse (t_start 0.1 s, 0.5 s long) has rocked both structures by then


def _load(name, path):
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def example_osp(built_fmus, tmp_path_factory):
    """The example's OspSystemStructure.xml with the FMUs of this test session."""
    text = (EXAMPLE / "OspSystemStructure.xml").read_text()
    for name, path in built_fmus.items():
        text = text.replace(f"../../dist/{name}.fmu", str(path))
    osp = tmp_path_factory.mktemp("osp") / "OspSystemStructure.xml"
    osp.write_text(text)
    return osp


@pytest.fixture(scope="module")
def example_ssp(example_osp, tmp_path_factory):
    example = _load("system_example", EXAMPLE / "run.py")
    return example.write_ssp(tmp_path_factory.mktemp("ssp") / "RockingSystem.ssp", osp=example_osp)


def _q(prefix, tag):
    return f"{{{NS[prefix]}}}{tag}"


def _ssd(path):
    with zipfile.ZipFile(path) as z:
        return z.namelist(), ElementTree.fromstring(z.read("SystemStructure.ssd"))


# ------------------------------------------------------------------------------ the .ssd's structure
#: SSP 1.0 child order (SystemStructureDescription.xsd): the allowed children of each element, in order
ROOT_CHILDREN = ["ssd:System", "ssd:Enumerations", "ssd:Units", "ssd:DefaultExperiment", "ssd:MetaData",
                 "ssd:Signature", "ssc:Annotations"]
ELEMENT_CHILDREN = ["ssd:Connectors", "ssd:ElementGeometry", "ssd:ParameterBindings", "ssd:Elements",
                    "ssd:Connections", "ssd:SignalDictionaries", "ssd:SystemGeometry", "ssd:GraphicalElements",
                    "ssd:Annotations"]
CONNECTOR_KINDS = {"input", "output", "parameter", "calculatedParameter", "inout", "unspecified"}


def _in_order(node, allowed):
    tags = [c.tag for c in node]
    keys = [_q(*a.split(":")) for a in allowed]
    assert all(t in keys for t in tags), f"{node.tag}: unexpected children {set(tags) - set(keys)}"
    idx = [keys.index(t) for t in tags]
    assert idx == sorted(idx), f"{node.tag}: children out of the SSP 1.0 order: {tags}"


def test_ssd_follows_the_ssp_1_0_structure(example_ssp, built_fmus):
    """Well-formed XML in the SSP 1.0 namespaces, the elements in the schema's order, every component an FMU
    of the archive, every connector typed with the kind and type of the FMU's variable, every connection
    from an output to an input, every parameter an FMU variable with a value of its type, and the base step
    in the OSP annotation. (The SSP schemas are not vendored: this checks the parts of them the file uses.)"""
    names, root = _ssd(example_ssp)
    assert names[0] == "SystemStructure.ssd"
    assert set(names) == {"SystemStructure.ssd"} | {f"resources/{n}.fmu" for n in
                                                    ["GroundMotionSource", "LinearBuildingStorey",
                                                     "RigidRockingBlock", "FlexibleRockingOscillator"]}
    assert root.tag == _q("ssd", "SystemStructureDescription")
    assert root.get("version") == "1.0" and root.get("name") == "RockingSystem"
    _in_order(root, ROOT_CHILDREN)
    system = root.find("ssd:System", NS)
    assert system.get("name")
    _in_order(system, ELEMENT_CHILDREN)
    kinds = {}
    components = system.findall("ssd:Elements/ssd:Component", NS)
    assert [c.get("name") for c in components] == ["ground", "storey", "block", "oscillator"]
    for comp in components:
        _in_order(comp, ELEMENT_CHILDREN)
        assert comp.get("type") == "application/x-fmu-sharedlibrary" and comp.get("source") in names
        with zipfile.ZipFile(example_ssp) as z:
            fmu_bytes = z.read(comp.get("source"))
        stem = Path(comp.get("source")).stem
        assert fmu_bytes == built_fmus[stem].read_bytes()
        md = {v.name: v for v in fmpy.read_model_description(str(built_fmus[stem])).modelVariables}
        declared = []
        for con in comp.findall("ssd:Connectors/ssd:Connector", NS):
            v = md[con.get("name")]
            assert con.get("kind") in CONNECTOR_KINDS and con.get("kind") == v.causality
            (typed,) = list(con)
            assert typed.tag == _q("ssc", v.type)
            kinds[(comp.get("name"), v.name)] = v.causality
            declared.append(v.name)
        assert declared == [v.name for v in md.values() if v.causality in ("input", "output")]
        for pset in comp.findall("ssd:ParameterBindings/ssd:ParameterBinding/ssd:ParameterValues/"
                                 "ssv:ParameterSet", NS):
            assert pset.get("version") == "1.0" and pset.get("name") == PARAMETER_SET
            for p in pset.findall("ssv:Parameters/ssv:Parameter", NS):
                v = md[p.get("name")]
                assert v.causality == "parameter"
                (typed,) = list(p)
                assert typed.tag == _q("ssv", v.type)
                {"Real": float, "Integer": int}[v.type](typed.get("value"))
    connections = system.findall("ssd:Connections/ssd:Connection", NS)
    assert len(connections) == 5        # ag, a_floor x 2, ag_v x 2
    for c in connections:
        assert kinds[(c.get("startElement"), c.get("startConnector"))] == "output"
        assert kinds[(c.get("endElement"), c.get("endConnector"))] == "input"
    exp = root.find("ssd:DefaultExperiment", NS)
    assert float(exp.get("startTime")) == 0.0
    (ann,) = exp.findall("ssd:Annotations/ssc:Annotation", NS)
    assert ann.get("type") == "com.opensimulationplatform"
    assert float(ann.find("osp:Algorithm/osp:FixedStepAlgorithm", NS).get("baseStepSize")) == 0.005


def test_read_ssp_gives_back_the_system(example_osp, example_ssp, tmp_path):
    osp = read_osp_system_structure(example_osp)
    ssp = read_ssp(example_ssp, unzipdir=tmp_path)
    assert (ssp.step_size, ssp.start_time) == (osp.step_size, osp.start_time)
    assert ssp.connections == osp.connections
    for a, b in zip(ssp.components, osp.components):
        assert (a.name, a.step_size, a.start_values) == (b.name, b.step_size, b.start_values)
        assert {k: type(v) for k, v in a.start_values.items()} == {k: type(v) for k, v in b.start_values.items()}
        assert Path(a.fmu).parent == tmp_path / "resources" and Path(a.fmu).read_bytes() == Path(b.fmu).read_bytes()
    # a component step size survives as an OSP step size hint
    osp.components[2].step_size = 0.01
    again = read_ssp(write_ssp(osp, tmp_path / "hint.ssp"), unzipdir=tmp_path / "hint")
    assert [c.step_size for c in again.components] == [None, None, 0.01, None]


def test_read_ssp_names_what_is_wrong(example_ssp, tmp_path):
    _, root = _ssd(example_ssp)

    def rewrite(edit, name):
        r = ElementTree.fromstring(ElementTree.tostring(root))
        edit(r)
        out = tmp_path / name
        with zipfile.ZipFile(example_ssp) as src, zipfile.ZipFile(out, "w") as dst:
            for n in src.namelist():
                data = ElementTree.tostring(r) if n == "SystemStructure.ssd" else src.read(n)
                dst.writestr(n, data)
        return out

    def no_step(r):
        exp = r.find("ssd:DefaultExperiment", NS)
        exp.remove(exp.find("ssd:Annotations", NS))

    def reversed_connection(r):
        c = r.find("ssd:System/ssd:Connections/ssd:Connection", NS)
        c.set("startElement", "storey")
        c.set("endElement", "ground")

    def missing_fmu(r):
        r.find("ssd:System/ssd:Elements/ssd:Component", NS).set("source", "resources/Nope.fmu")

    def bad_value(r):
        r.find(".//ssv:Parameter/ssv:Real", NS).set("value", "two")

    cases = [(no_step, r"no base step"), (reversed_connection, r"storey.ag is not an output connector"),
             (missing_fmu, r"component 'ground': source 'resources/Nope.fmu' is not in the archive"),
             (bad_value, r"ground.A: 'two' is not a valid Real")]
    for i, (edit, message) in enumerate(cases):
        with pytest.raises(ValueError, match=message):
            read_ssp(rewrite(edit, f"bad{i}.ssp"), unzipdir=tmp_path / f"bad{i}")


# ------------------------------------------------------------------------------ running the archive
@pytest.fixture(scope="module")
def osp_fmpy_result(example_osp):
    example = _load("system_example", EXAMPLE / "run.py")
    return run_fmpy(example_osp, STOP, example.OUTPUTS)


def test_fmpy_master_runs_the_ssp_like_the_osp_file(example_ssp, osp_fmpy_result):
    res = run_fmpy(example_ssp, STOP, list(osp_fmpy_result.dtype.names[1:]))
    assert res.dtype == osp_fmpy_result.dtype and res.tobytes() == osp_fmpy_result.tobytes()
    assert np.abs(res["block.phi"]).max() > 0.05  # the archive's parameters act: the pulse rocks the block


def test_libcosim_runs_the_ssp_like_the_fmpy_master(example_ssp, osp_fmpy_result):
    """libcosim reads the archive with its own SSP loader (components, parameter sets, connections, base
    step from the OSP annotation): its results equal the fmpy master's on the OSP file, bit for bit."""
    try:
        import libcosimpy.CosimExecution  # noqa: F401
    except Exception as exc:
        pytest.skip(f"libcosimpy cannot be imported ({exc!r})")
    outputs = list(osp_fmpy_result.dtype.names[1:])
    res = run_libcosim(example_ssp, STOP, outputs)
    assert len(res) == len(osp_fmpy_result) - 1
    for k in ["time"] + outputs:
        np.testing.assert_array_equal(res[k], osp_fmpy_result[k][1:], err_msg=k)


def test_example_script_writes_and_runs_the_ssp(example_osp, tmp_path, monkeypatch):
    example = _load("system_example", EXAMPLE / "run.py")
    monkeypatch.setattr(example, "OSP", example_osp)
    monkeypatch.setattr(example, "build_fmus", lambda force=False: None)
    assert example.main(["--stop", "0.5", "--out", str(tmp_path), "--master", "fmpy", "--ssp",
                         "--no-plot"]) == 0
    assert zipfile.is_zipfile(tmp_path / "RockingSystem.ssp")
    lines = (tmp_path / "system_fmpy.csv").read_text().splitlines()
    assert lines[0].split(",")[:3] == ["time", "ground.ag", "storey.u"] and len(lines) == 102


def test_ssp_with_the_standalone_block(example_osp, build_module, tmp_path_factory, tmp_path):
    """The archive with the self-contained block and oscillator: they are what resources/ holds,
    and fmpy and libcosim run it bit for bit alike."""
    import fault_harness as fh

    try:
        sa = fh.standalone_fmus(build_module, tmp_path_factory)
    except Exception as exc:
        pytest.skip(f"the self-contained FMUs could not be built: {exc!r}")
    system = read_osp_system_structure(example_osp)
    for c in system.components:
        c.fmu = sa.get(Path(c.fmu).stem, c.fmu)
    ssp = write_ssp(system, tmp_path / "standalone.ssp")
    with zipfile.ZipFile(ssp) as z:
        assert z.read("resources/RigidRockingBlock.fmu") == sa["RigidRockingBlock"].read_bytes()
    outputs = ["storey.a_floor", "block.phi", "block.impacts", "oscillator.phi"]
    res = run_fmpy(ssp, STOP, outputs)
    assert np.abs(res["block.phi"]).max() > 0.05
    try:
        import libcosimpy.CosimExecution  # noqa: F401
    except Exception as exc:
        pytest.skip(f"libcosimpy cannot be imported ({exc!r})")
    lc = run_libcosim(ssp, STOP, outputs)
    for k in ["time"] + outputs:
        np.testing.assert_array_equal(lc[k], res[k][1:], err_msg=k)
