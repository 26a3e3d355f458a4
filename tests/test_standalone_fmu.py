"""The self-contained FMUs: dist/standalone/<Name>.fmu, the compiled C engine under the C FMI layer
rocking_model/fmi/binary/standalone/fmi2_engine.c, with no Python at all.

- the modelDescription is the pythonfmu FMU's (same variables, references, units, ranges, starts,
  descriptions) with needsExecutionTool = false; fmpy validates it;
- results equal `simulate(hold="zoh", engine="c")` bit for bit on the benchmark scenes (the same engine, the
  same calls) and the pythonfmu FMUs (the Python engine) to round-off;
- the binary needs libc and libm only, holds no path of the build machine, and runs in the C host under
  `env -i` where no Python can be found (the process never maps libpython);
- statuses and messages of the pythonfmu FMUs (bad parameters, bad input, fixed parameters), the FMU state
  (get / set / serialize, corrupt blobs refused), 2 FMUs x 4 threads bit-identical to sequential runs;
- the overturning is an event in both kinds: its step returns fmi2OK, the message is logged with fmi2OK under
  logEvents, filtered by loggingOn and fmi2SetDebugLogging;
- sources/ (with buildDescription.xml) compile to a working binary on their own."""
from __future__ import annotations

import math
import os
import re
import shutil
import subprocess
import sys
import threading
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

import numpy as np
import pytest

fmpy = pytest.importorskip("fmpy")
from fmpy import extract, read_model_description  # noqa: E402
from fmpy.fmi2 import FMU2Slave  # noqa: E402

from rocking_model.fmi import fmpy_callbacks  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
CC = os.environ.get("CC") or shutil.which("cc") or shutil.which("gcc")
HEADERS = Path(fmpy.__file__).parent / "c-code"
RIGID, FLEX, PT = "RigidRockingBlock", "FlexibleRockingOscillator", "PostTensionedRockingBlock"
#: the FMUs of the registered models (the post-tensioned block's: here its packaging, the equality of its two
#: kinds with the Python API and the C host; the other cases exercise the FMI layer it shares with the rigid
#: block's, and stay on the rigid and flexible FMUs)
NAMES = (RIGID, FLEX, PT)

pytestmark = pytest.mark.skipif(CC is None or not sys.platform.startswith("linux"),
                                reason="needs a C compiler on Linux")

#: [rad] agreement of the C engine (standalone FMU) with the Python engine (pythonfmu FMU) on a scene far from
#: any decision boundary: round-off of two implementations of the same algorithm, grown over a few seconds of
#: rocking with impacts (the engine's own tests hold them within ~1e-13)
ROUNDOFF = 1e-9


@pytest.fixture(scope="module")
def standalone(build_module, tmp_path_factory) -> dict:
    dest = tmp_path_factory.mktemp("standalone")
    return {p.stem: p for p in build_module.build_standalone(dest)}


@pytest.fixture(scope="module")
def unzipped(standalone) -> dict:
    return {k: extract(str(p)) for k, p in standalone.items()}


@pytest.fixture(scope="module")
def py_unzipped(built_fmus) -> dict:
    return {k: extract(str(p)) for k, p in built_fmus.items() if k in NAMES}


def _vr(fmu) -> dict:
    return {v.name: v for v in read_model_description(str(fmu)).modelVariables}


class Run:
    """One instance stepped by hand (what fmpy.simulate_fmu does, with every output recorded)."""

    def __init__(self, fmu, unzip, name="run", start=None, sink=None):
        self.md = read_model_description(str(fmu))
        self.vars = {v.name: v for v in self.md.modelVariables}
        self.sink = [] if sink is None else sink
        self.f = FMU2Slave(guid=self.md.guid, unzipDirectory=unzip,
                           modelIdentifier=self.md.coSimulation.modelIdentifier, instanceName=name)
        self.f.instantiate(callbacks=fmpy_callbacks(self.sink))
        self.f.setupExperiment(startTime=0.0)
        self.f.enterInitializationMode()
        for key, value in (start or {}).items():
            v = self.vars[key]
            if v.type == "Real":
                self.f.setReal([v.valueReference], [float(value)])
            else:
                self.f.setInteger([v.valueReference], [int(value)])
        self.f.exitInitializationMode()
        self.outputs = [v for v in self.md.modelVariables if v.causality == "output"]

    def row(self):
        out = []
        for v in self.outputs:
            if v.type == "Real":
                out.append(self.f.getReal([v.valueReference])[0])
            elif v.type == "Integer":
                out.append(self.f.getInteger([v.valueReference])[0])
            else:
                out.append(bool(self.f.getBoolean([v.valueReference])[0]))
        return out

    def run(self, ag, dt):
        rows = [self.row()]
        vr = self.vars["ag"].valueReference
        for k, a in enumerate(ag):
            self.f.setReal([vr], [float(a)])
            status = self.f.doStep(k * dt, dt)
            rows.append(self.row())
        return rows

    def free(self):
        self.f.terminate()
        self.f.freeInstance()


# ---------------------------------------------------------------------------------------------- packaging
def test_model_description_is_the_pythonfmu_ones_with_a_native_binary(standalone, built_fmus):
    for name in NAMES:
        sa, py = read_model_description(str(standalone[name])), read_model_description(str(built_fmus[name]))
        assert sa.coSimulation.needsExecutionTool is False and py.coSimulation.needsExecutionTool is True
        assert sa.coSimulation.canGetAndSetFMUstate and sa.coSimulation.canSerializeFMUstate
        assert sa.coSimulation.canInterpolateInputs
        fields = ("name", "valueReference", "type", "causality", "variability", "initial", "start", "unit",
                  "min", "max", "description")
        table = [tuple(str(getattr(v, f, None)) for f in fields) for v in sa.modelVariables]
        assert table == [tuple(str(getattr(v, f, None)) for f in fields) for v in py.modelVariables]
        assert sa.guid != py.guid
        assert [u.name for u in sa.unitDefinitions] == [u.name for u in py.unitDefinitions]


def test_fmpy_validate_is_clean(standalone):
    from fmpy.validation import validate_fmu

    for name in NAMES:
        assert validate_fmu(str(standalone[name])) == []


def test_zip_content_size_and_no_build_path(standalone):
    for name, fmu in standalone.items():
        with zipfile.ZipFile(fmu) as zf:
            names = zf.namelist()
            blob = b"".join(zf.read(n) for n in names)
        assert {"modelDescription.xml", f"binaries/linux64/{name}.so", "sources/buildDescription.xml",
                "sources/fmi2_engine.c", "sources/rk_engine.h", "sources/rk_fmu_vars.h", "sources/rk_fp.h",
                "sources/rk_version.h",
                "documentation/index.html"} <= set(names)
        assert [n for n in names if n.startswith("resources/")] == ["resources/README.txt"]
        # no path of this machine: the checkout, the home folder, the temporary build folder
        for path in {str(ROOT), str(Path.home()), "/tmp/", sys.prefix}:
            assert path.encode() not in blob, path
        assert fmu.stat().st_size < 1_000_000        # deterministic: the same sources give the same bytes
        doc = zipfile.ZipFile(fmu).read("documentation/index.html").decode()
        for v in read_model_description(str(fmu)).modelVariables:
            assert f"<code>{v.name}</code>" in doc


def test_build_is_reproducible(standalone, build_module, tmp_path):
    again = build_module.build_standalone_one(ROOT / "fmu_src" / f"{RIGID}.py", tmp_path)
    assert again.read_bytes() == standalone[RIGID].read_bytes()


def _ldd(so: Path) -> list:
    out = subprocess.run(["ldd", str(so)], capture_output=True, text=True, timeout=30).stdout
    return [line.split()[0] for line in out.splitlines() if line.strip()]


def test_ldd_shows_libc_and_libm_only(unzipped):
    if shutil.which("ldd") is None:
        pytest.skip("no ldd")
    for name in NAMES:
        libs = _ldd(Path(unzipped[name]) / "binaries" / "linux64" / f"{name}.so")
        for lib in libs:
            assert re.match(r"(linux-vdso|libc\.so|libm\.so|/lib.*/ld-linux)", lib), libs
        assert any(lib.startswith("libc.so") for lib in libs)


def test_exports_only_fmi_functions(unzipped):
    nm = shutil.which("nm")
    if nm is None:
        pytest.skip("no nm")
    so = Path(unzipped[RIGID]) / "binaries" / "linux64" / f"{RIGID}.so"
    defined = subprocess.run([nm, "-D", "--defined-only", str(so)], capture_output=True, text=True).stdout
    names = [line.split()[-1] for line in defined.splitlines() if line.split()[-2] in ("T", "D", "B")]
    assert len(set(names)) == 34 and all(n.startswith("fmi2") for n in names), names


def test_fmi_layer_compiles_without_warnings(standalone, tmp_path):
    with zipfile.ZipFile(standalone[RIGID]) as zf:
        zf.extractall(tmp_path)
    src = tmp_path / "sources"
    cmd = [CC, "-fsyntax-only", "-std=c99", "-pedantic", "-Wall", "-Wextra", "-Werror", "-I.", "fmi2_engine.c"]
    proc = subprocess.run(cmd, capture_output=True, text=True, cwd=src, timeout=120)
    assert proc.returncode == 0, proc.stderr


def test_sources_build_a_working_binary_from_the_build_description(standalone, tmp_path):
    """An importer on another platform compiles sources/ as buildDescription.xml says: the binary built
    that way gives the same results as the shipped one."""
    import xml.etree.ElementTree as ET

    with zipfile.ZipFile(standalone[RIGID]) as zf:
        zf.extractall(tmp_path / "fmu")
    src = tmp_path / "fmu" / "sources"
    bd = ET.parse(src / "buildDescription.xml").getroot()
    files = [e.get("name") for e in bd.iter("SourceFile")]
    defines = [f"-D{e.get('name')}={e.get('value')}" for e in bd.iter("PreprocessorDefinition")]
    std = {"C99": "-std=c99"}[next(bd.iter("SourceFileSet")).get("language")]
    libs = [f"-l{e.get('name')}" for e in bd.iter("Library")]
    so = tmp_path / "fmu" / "binaries" / "linux64" / f"{RIGID}.so"
    so.unlink()
    # no flag of ours (no -ffp-contract=off): the sources pin their floating-point contract (rk_fp.h)
    proc = subprocess.run([CC, "-shared", "-fPIC", std, "-O2", "-I.", *defines, *files, "-o", str(so), *libs],
                          capture_output=True, text=True, cwd=src, timeout=300)
    assert proc.returncode == 0, proc.stderr
    ag = [2.5 * math.sin(2 * math.pi * 0.01 * k) for k in range(100)]
    mine = Run(standalone[RIGID], str(tmp_path / "fmu"), "rebuilt").run(ag, 0.01)
    ref = Run(standalone[RIGID], extract(str(standalone[RIGID])), "shipped").run(ag, 0.01)
    assert mine == ref and abs(ref[-1][0]) > 1e-4


# ---------------------------------------------------------------------------------------------- results
def _scene_runs():
    sys.path.insert(0, str(ROOT))
    try:
        from benchmarks.scenes import flexible_scenes, rigid_scenes
    finally:
        sys.path.pop(0)
    return rigid_scenes(quick=True) + flexible_scenes(quick=True)


def _scene_input(scene, dt=0.01):
    n = int(round(scene.t_end / dt))
    gm = scene.ground_motion()
    times = dt * np.arange(n)
    if isinstance(gm, float):
        return np.full(n, gm)
    from rocking_model.ground_motion import as_ground_motion
    g = as_ground_motion(gm)
    return np.array([g(t) for t in times])


@pytest.mark.parametrize("scheme", [0, 1])
def test_equal_to_the_c_engine_bit_for_bit_on_the_benchmark_scenes(standalone, unzipped, scheme):
    """The FMU steps its engine as a `Simulator(engine="c")` does under a number held over the step: the
    same calls (advance to t_k + h, the master's end time), so the same bits; and `simulate(hold="zoh",
    engine="c")`, whose grid is t0 + k h (not the master's running sum), to round-off."""
    from rocking_model.simulation import Simulator, simulate

    for scene in _scene_runs():
        name = RIGID if scene.kind == "rigid" else FLEX
        ag = _scene_input(scene)
        scheme_name = ("moreau_jean", "event_driven")[scheme]
        r = Run(standalone[name], unzipped[name], scene.name, {**scene.model_kw, **scene.initial, "scheme": scheme})
        rows = r.run(ag, 0.01)
        r.free()
        sim = Simulator(scene.model(), scheme_name, engine="c", impact_log_size=0, **scene.initial)
        sim.on_report = "raise"                # as the FMUs run it: a failed step refuses the advance
        expected = [sim.outputs()]
        for k, a in enumerate(ag):
            sim.advance(k * 0.01 + 0.01, float(a))
            expected.append(sim.outputs())
        res = simulate(scene.model(), (0.01 * np.arange(len(ag) + 1), np.append(ag, ag[-1])), scene.t_end,
                       scheme=scheme_name, hold="zoh", engine="c", **scene.initial)
        for j, v in enumerate(r.outputs):
            got = np.array([row[j] for row in rows], dtype=float)
            same = np.array([float(e[v.name]) for e in expected])
            assert np.array_equal(got, same), (scene.name, v.name, np.max(np.abs(got - same)))
            if v.name == "phi" and scene.name != "pulse_above":   # (overturning: the time of it differs)
                assert np.max(np.abs(got - np.asarray(res["phi"], dtype=float))) < ROUNDOFF, scene.name


def test_equal_to_the_pythonfmu_fmus_to_round_off(standalone, unzipped, built_fmus, py_unzipped):
    for name, amplitude in ((RIGID, 3.0), (FLEX, 5.0)):
        ag = [amplitude * math.sin(2 * math.pi * 0.01 * k) if k < 100 else 0.0 for k in range(200)]
        run = Run(standalone[name], unzipped[name], "c")
        a = np.array(run.run(ag, 0.01), dtype=float)
        b = np.array(Run(built_fmus[name], py_unzipped[name], "py").run(ag, 0.01), dtype=float)
        assert np.max(np.abs(a - b)) < ROUNDOFF * max(1.0, np.max(np.abs(b)))
        phi = [v.name for v in run.outputs].index("phi")
        assert np.max(np.abs(a[:, phi])) > 1e-3       # it rocks


@pytest.mark.parametrize("scheme", [0, 1])
def test_post_tensioned_fmus_equal_the_python_api(standalone, unzipped, built_fmus, py_unzipped, scheme):
    """PostTensionedRockingBlock, both kinds through fmpy's FMU2Slave, on a one-sine pulse that rocks the block
    with the tendon taut (b = 0.3, h = 1.5, m = 1000, P0 = 2e4, k_t = 2e6: uplift at 5.96 m/s2, A = 10 m/s2):
    every output equals `simulate(hold="zoh")` of the Python API to round-off (`ROUNDOFF` of its scale; the
    counts and the contact state exactly), its own output tendon_force included. (Not bit for bit: the FMU
    steps to the master's t_k + h, simulate to t0 + (k + 1) h; measured: 1e-14 rad.)"""
    from rocking_model import simulate
    from rocking_model.models import PostTensionedBlock

    params = dict(b=0.3, h=1.5, m=1000.0, P0=2e4, k_t=2e6)
    ag = [10.0 * math.sin(2 * math.pi * 0.01 * k) if k < 100 else 0.0 for k in range(300)]
    t = 0.01 * np.arange(len(ag) + 1)
    ref = simulate(PostTensionedBlock(**params), (t, np.append(ag, 0.0)), float(t[-1]), scheme=scheme,
                   output_interval=0.01, hold="zoh", tolerance=1e-8, dt_max=1e-3)
    for fmu, unzip in ((standalone[PT], unzipped[PT]), (built_fmus[PT], py_unzipped[PT])):
        run = Run(fmu, unzip, "pt", {**params, "scheme": scheme, "tolerance": 1e-8, "dt_max": 1e-3})
        rows = np.array(run.run(ag, 0.01), dtype=float)
        run.free()
        names = [v.name for v in run.outputs]
        assert "tendon_force" in names and rows[0, names.index("tendon_force")] == 2e4     # P0 at rest
        for j, name in enumerate(names):
            want = np.asarray(ref[name], dtype=float)
            if run.vars[name].type == "Real":
                assert np.max(np.abs(rows[:, j] - want)) < ROUNDOFF * max(1.0, np.max(np.abs(want))), (fmu, name)
            else:
                np.testing.assert_array_equal(rows[:, j], want, err_msg=f"{fmu}: {name}")
    phi, force = np.asarray(ref["phi"]), np.asarray(ref["tendon_force"])
    assert np.max(np.abs(phi)) > 0.1 and ref["impacts"][-1] >= 1 and not ref["overturned"][-1]
    assert np.max(force) > 4 * 2e4               # the tendon stretched as the block rocked


def test_input_derivatives_as_the_pythonfmu_fmu(standalone, unzipped, built_fmus, py_unzipped):
    """fmi2SetRealInputDerivatives (first-order hold) gives the pythonfmu FMU's motion to round-off."""
    def run(fmu, unzip):
        r = Run(fmu, unzip, "ramp")
        vr = r.vars["ag"].valueReference
        rows = []
        for k in range(80):
            r.f.setReal([vr], [3.0 * math.sin(0.2 * k)])
            r.f.setRealInputDerivatives([vr], [1], [30.0 * math.cos(0.2 * k)])
            r.f.doStep(k * 0.01, 0.01)
            rows.append(r.row())
        return np.array(rows, dtype=float)

    a, b = run(standalone[RIGID], unzipped[RIGID]), run(built_fmus[RIGID], py_unzipped[RIGID])  # phi first
    assert np.max(np.abs(a - b)) < ROUNDOFF and np.max(np.abs(a[:, 0])) > 1e-4


# ---------------------------------------------------------------------------------------------- messages
def _messages(fmu, unzip, action, logging_on=False):
    sink: list = []
    md = read_model_description(str(fmu))
    f = FMU2Slave(guid=md.guid, unzipDirectory=unzip, modelIdentifier=md.coSimulation.modelIdentifier,
                  instanceName="msg")
    f.instantiate(callbacks=fmpy_callbacks(sink), loggingOn=logging_on)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    try:
        action(f, vr)
    except Exception:
        pass
    return [(s, text) for s, _, text in sink]


#: parameter values refused at fmi2ExitInitializationMode (by the model, the Simulator or the FMU's check)
BAD_PARAMETERS = {"b_negative": ("Real", "b", -1.0), "b_nan": ("Real", "b", math.nan),
                  "b_subnormal": ("Real", "b", 1e-310), "scheme": ("Integer", "scheme", 7),
                  "impact_law": ("Integer", "impact_law", 5), "max_steps": ("Integer", "max_steps", 0),
                  "dt_max": ("Real", "dt_max", 1e-12), "tolerance": ("Real", "tolerance", 1.0),
                  "mu": ("Real", "mu", -1.0), "phi_0": ("Real", "phi_0", 2.0)}


@pytest.mark.parametrize("case", ["bad_input", "fixed", "unknown_vr", "bad_rate", "work_limit", "time_mismatch",
                                  "overturn", *BAD_PARAMETERS])
def test_messages_equal_the_pythonfmu_fmu(standalone, unzipped, built_fmus, py_unzipped, case):
    def action(f, vr):
        f.setupExperiment(startTime=0.0)
        f.enterInitializationMode()
        if case in BAD_PARAMETERS:
            kind, name, value = BAD_PARAMETERS[case]
            (f.setInteger if kind == "Integer" else f.setReal)([vr[name]], [value])
        if case == "work_limit":
            f.setInteger([vr["max_steps"], vr["scheme"]], [3, 0])
        f.exitInitializationMode() if case != "bad_rate" else None
        if case == "work_limit":
            f.setReal([vr["ag"]], [3.0])
            f.doStep(0.0, 0.1)
            f.doStep(0.0, 0.30000000000000004)
        if case == "time_mismatch":
            f.doStep(0.5, 0.1)
        if case == "overturn":
            f.setReal([vr["ag"]], [9.0])
            for k in range(100):
                f.doStep(k * 0.01, 0.01)
        if case == "bad_input":
            f.setReal([vr["ag"]], [1e4])
        if case == "fixed":
            f.setReal([vr["b"]], [0.3])
        if case == "unknown_vr":
            f.getReal([9999])
        if case == "bad_rate":
            f.setRealInputDerivatives([vr["ag"]], [2], [1.0])

    # the overturning is an event (fmi2OK, logEvents): it reaches the logger with logging on only
    logging_on = case == "overturn"
    a = _messages(standalone[RIGID], unzipped[RIGID], action, logging_on)
    b = _messages(built_fmus[RIGID], py_unzipped[RIGID], action, logging_on)
    assert a and a == b


#: [m/s2] a constant ground acceleration that overturns each FMU's default structure within 1 s
OVERTURNING_AG = {RIGID: 9.0, FLEX: 9.0, PT: 50.0}
#: fmi2SetDebugLogging after fmi2Instantiate(loggingOn) -> whether the overturning event reaches the logger
#: (None: not called; "off": loggingOn = false): the filter of every fmi2OK message (fmi2_common.c)
EVENT_LOGGING = [(None, True), ([], True), (["logEvents"], True), (["logAll"], True),
                 (["logStatusWarning", "logStatusError"], False), ("off", False)]


@pytest.mark.parametrize("kind", ["standalone", "pythonfmu"])
@pytest.mark.parametrize("name", NAMES)
def test_the_overturning_is_an_event_not_a_warning(standalone, unzipped, built_fmus, py_unzipped, name, kind):
    """Both kinds of FMU: the step in which the structure overturns returns fmi2OK (fmusim and other masters
    stop at any status above fmi2OK), every step too; its message is logged with fmi2OK under logEvents,
    declared in the modelDescription, and reaches the logger with logging on and the category enabled
    (fmi2SetDebugLogging naming none, logEvents or logAll), never otherwise."""
    fmu, unzip = (standalone[name], unzipped[name]) if kind == "standalone" else \
        (built_fmus[name], py_unzipped[name])
    md = read_model_description(str(fmu))
    with zipfile.ZipFile(fmu) as z:
        root = ET.fromstring(z.read("modelDescription.xml"))
    categories = {c.get("name"): c.get("description") for c in root.iterfind("LogCategories/Category")}
    assert categories.get("logEvents") == "Events of the motion: the overturning that freezes the outputs", \
        categories
    vr = {v.name: v.valueReference for v in md.modelVariables}
    for categories, delivered in EVENT_LOGGING:
        sink: list = []
        f = FMU2Slave(guid=md.guid, unzipDirectory=unzip, modelIdentifier=md.coSimulation.modelIdentifier,
                      instanceName="event")
        f.instantiate(callbacks=fmpy_callbacks(sink), loggingOn=categories != "off")
        if categories not in (None, "off"):
            f.setDebugLogging(True, categories)
        f.setupExperiment(startTime=0.0)
        f.enterInitializationMode()
        f.exitInitializationMode()
        f.setReal([vr["ag"]], [OVERTURNING_AG[name]])
        statuses, overturned_at = [], None
        for k in range(150):
            statuses.append(int(f.fmi2DoStep(f.component, k * 0.01, 0.01, 1)))   # the status, as returned
            if overturned_at is None and f.getBoolean([vr["overturned"]])[0]:
                overturned_at = k
            if overturned_at is not None and k >= overturned_at + 3:              # frozen: steps go on
                break
        f.terminate()
        f.freeInstance()
        assert overturned_at is not None, (name, kind)
        assert set(statuses) == {0}, (categories, statuses)                       # fmi2OK, the overturning too
        events = [(s, c, t) for s, c, t in sink if "overturned at t =" in t]
        assert all(s == 0 and c == "logEvents" for s, c, _ in sink), sink           # no warning, no other message
        assert len(events) == (1 if delivered else 0), (categories, sink)
        if delivered:
            assert events[0][2].endswith("s: the outputs are frozen from now on"), events


def test_step_refused_with_the_state_kept(standalone, unzipped):
    """A work budget too small for the step: fmi2Discard, the message, the state unchanged; the master
    retries after restoring nothing (the instance is where it was)."""
    r = Run(standalone[RIGID], unzipped[RIGID], "budget", {"max_steps": 1, "scheme": 0})
    vr = r.vars["ag"].valueReference
    r.f.setReal([vr], [3.0])
    before = r.row()
    with pytest.raises(Exception):
        r.f.doStep(0.0, 0.1)
    assert r.row() == before
    assert any("refused, the FMU state is unchanged" in text for _, _, text in r.sink)


# ---------------------------------------------------------------------------------------------- FMU state
def test_state_round_trip_and_corrupt_blobs_refused(standalone, unzipped):
    r = Run(standalone[FLEX], unzipped[FLEX], "state")
    vr = r.vars["ag"].valueReference
    ag = [3.0 * math.sin(0.3 * k) for k in range(60)]
    for k in range(30):
        r.f.setReal([vr], [ag[k]])
        r.f.doStep(k * 0.01, 0.01)
    blob = r.f.serializeFMUstate(r.f.getFMUstate())
    rest = []
    for k in range(30, 60):
        r.f.setReal([vr], [ag[k]])
        r.f.doStep(k * 0.01, 0.01)
        rest.append(r.row())
    other = Run(standalone[FLEX], unzipped[FLEX], "other")
    other.f.setFMUstate(other.f.deSerializeFMUstate(blob))
    again = []
    for k in range(30, 60):
        other.f.setReal([vr], [ag[k]])
        other.f.doStep(k * 0.01, 0.01)
        again.append(other.row())
    assert again == rest
    # every flipped byte is refused (CRC), the instance keeps its state
    third = Run(standalone[FLEX], unzipped[FLEX], "third")
    for i in range(0, len(blob), max(1, len(blob) // 40)):
        bad = bytearray(blob)
        bad[i] ^= 0x5A
        with pytest.raises(Exception):
            third.f.setFMUstate(third.f.deSerializeFMUstate(bytes(bad)))
        third.f.reset()
    # a rigid block's state is refused by the flexible oscillator
    rig = Run(standalone[RIGID], unzipped[RIGID], "rig")
    with pytest.raises(Exception):
        third.f.setFMUstate(third.f.deSerializeFMUstate(rig.f.serializeFMUstate(rig.f.getFMUstate())))


# ---------------------------------------------------------------------------------------------- threads
def test_two_fmus_four_threads_match_a_sequential_run(standalone, unzipped):
    jobs = [(RIGID, 3.0), (RIGID, 3.5), (FLEX, 4.0), (FLEX, 4.5)]

    def one(i, kind, amplitude):
        r = Run(standalone[kind], unzipped[kind], f"job{i}")
        rows = r.run([amplitude] * 200, 0.01)
        r.free()
        return rows

    sequential = [one(i, k, a) for i, (k, a) in enumerate(jobs)]
    results: dict = {}
    errors: list = []

    def worker(i, kind, amplitude):
        try:
            results[i] = one(i, kind, amplitude)
        except BaseException as exc:  # reported below
            errors.append(repr(exc))

    threads = [threading.Thread(target=worker, args=(i, k, a)) for i, (k, a) in enumerate(jobs)]
    for th in threads:
        th.start()
    for th in threads:
        th.join(timeout=120)
    assert not errors, errors
    assert [results[i] for i in range(4)] == sequential
    assert sequential[0] != sequential[1] and abs(sequential[2][-1][0]) > 0


# ---------------------------------------------------------------------------------------------- no Python
@pytest.fixture(scope="module")
def host(tmp_path_factory) -> Path:
    exe = tmp_path_factory.mktemp("host") / "host"
    proc = subprocess.run([CC, "-std=c99", f"-I{HEADERS}", str(ROOT / "tests" / "c" / "host.c"), "-o", str(exe),
                           "-ldl"], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    return exe


@pytest.mark.parametrize("name", NAMES)
def test_c_host_under_env_i_without_python(host, standalone, unzipped, name, tmp_path):
    """The host under `env -i` with PATH holding no python and an empty library path, in a folder where
    nothing of Python can be found: the FMU runs, never maps libpython, and gives fmpy's results."""
    md = read_model_description(str(standalone[name]))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    env_i = shutil.which("env") or "/usr/bin/env"
    bindir = tmp_path / "bin"                  # a PATH with no python in it
    bindir.mkdir()
    cmd = [env_i, "-i", f"PATH={bindir}", "LD_LIBRARY_PATH=", "PYTHONHOME=/nonexistent", str(host),
           unzipped[name], md.coSimulation.modelIdentifier, md.guid, str(vr["ag"]), str(vr["phi"]), "3.0", "1.0",
           "0.01", "--maps"]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=120, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert "host: libpython mapped: no" in proc.stderr, proc.stderr
    phi = [float(line.split(",")[1]) for line in proc.stdout.splitlines()]
    run = Run(standalone[name], unzipped[name], "ref")
    ref = run.run([3.0] * 100, 0.01)
    j = [v.name for v in run.outputs].index("phi")
    assert phi == [row[j] for row in ref[1:]] and max(map(abs, phi)) > 0
    # Python really cannot be started from there
    probe = subprocess.run([env_i, "-i", f"PATH={bindir}", "/bin/sh", "-c", "command -v python3 python"],
                           capture_output=True, text=True, timeout=30)
    assert probe.stdout.strip() == ""


def test_crafted_state_blobs_with_a_valid_crc_never_crash_the_host(standalone, unzipped, tmp_path):
    """Blobs altered byte by byte with both CRCs rewritten (what a CRC cannot catch): each is refused with a
    message or, if every field is still valid, steps on; never a crash. Run in a subprocess, so that a crash
    fails this test instead of the session."""
    script = tmp_path / "fuzz.py"
    script.write_text(f"""
import sys, zlib, random
sys.path.insert(0, {str(ROOT / 'tests')!r})
from test_standalone_fmu import Run
fmu, unzip = {str(standalone[FLEX])!r}, {str(unzipped[FLEX])!r}
r = Run(fmu, unzip, "src")
vr = r.vars["ag"].valueReference
for k in range(40):
    r.f.setReal([vr], [4.0])
    r.f.doStep(k * 0.01, 0.01)
blob = bytes(r.f.serializeFMUstate(r.f.getFMUstate()))
rng = random.Random(7)
refused = accepted = 0
for trial in range(400):
    bad = bytearray(blob)
    i = rng.randrange(46, len(bad) - 4)
    bad[i] = rng.randrange(256)
    bad[-4:] = zlib.crc32(bytes(bad[46:-4])).to_bytes(4, "little")      # the payload's own CRC
    crc = zlib.crc32(bytes(bad[:42]) + bytes(bad[46:]))
    bad[42:46] = crc.to_bytes(4, "little")
    t = Run(fmu, unzip, "t%d" % trial)
    try:
        t.f.setFMUstate(t.f.deSerializeFMUstate(bytes(bad)))
    except Exception:
        refused += 1
        continue
    accepted += 1
    try:
        for k in range(3):
            t.f.doStep(0.4 + k * 0.01, 0.01)
    except Exception:
        pass
print("refused", refused, "accepted", accepted)
""")
    proc = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr[-3000:]
    refused, accepted = map(int, re.search(r"refused (\d+) accepted (\d+)", proc.stdout).groups())
    assert refused > 0 and accepted > 0


def test_hypothesis_scenes_bit_identical_to_the_c_engine(standalone, unzipped):
    """Hypothesis-generated scenes (geometry, restitution, pulse, scheme, step size, both models): every output
    of every step equals the `Simulator(engine="c")` run with the FMU's calls, bit for bit; a step refused
    by one is refused by the other."""
    from hypothesis import HealthCheck, given, settings
    from hypothesis import strategies as st

    from rocking_model.models import make_model
    from rocking_model.simulation import Simulator

    @settings(max_examples=8, deadline=None, derandomize=True,
              suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
    @given(kind=st.sampled_from(["rigid", "flexible"]), scheme=st.sampled_from([0, 1]),
           b=st.floats(0.15, 0.4), e_N=st.floats(0.0, 0.9), amplitude=st.floats(0.0, 8.0),
           freq=st.floats(0.5, 4.0), dt=st.sampled_from([0.005, 0.01, 0.02]))
    def check(kind, scheme, b, e_N, amplitude, freq, dt):
        name = RIGID if kind == "rigid" else FLEX
        params = {"b": b, "e_N": e_N}
        n = int(round(1.0 / dt))
        ag = [amplitude * math.sin(2 * math.pi * freq * k * dt) if k * dt * freq < 1 else 0.0 for k in range(n)]
        r = Run(standalone[name], unzipped[name], "hyp", {**params, "scheme": scheme})
        sim = Simulator(make_model(kind, **params), ("moreau_jean", "event_driven")[scheme], engine="c",
                        impact_log_size=0, max_steps=r.vars["max_steps"].start and int(r.vars["max_steps"].start))
        sim.on_report = "raise"
        vr = r.vars["ag"].valueReference
        for k, a in enumerate(ag):
            r.f.setReal([vr], [a])
            try:
                r.f.doStep(k * dt, dt)
                refused = False
            except Exception:
                refused = True
            try:
                sim.advance(k * dt + dt, a)
                sim_refused = False
            except Exception:
                sim_refused = True
            assert refused == sim_refused, k
            if refused:
                break
            out = sim.outputs()
            assert r.row() == [type(x)(out[v.name]) for v, x in zip(r.outputs, r.row())], k
        r.free()

    check()


def test_state_payload_decodes_in_python(standalone, unzipped):
    """rocking_model.fmi.standalone.decode_state_payload reads the FMU's state before and after
    initialization (the fault suite and other tools compare states field by field with it)."""
    from rocking_model.fmi.standalone import decode_state_payload

    md = read_model_description(str(standalone[RIGID]))
    f = FMU2Slave(guid=md.guid, unzipDirectory=unzipped[RIGID], modelIdentifier=md.coSimulation.modelIdentifier,
                  instanceName="decode")
    f.instantiate()
    before = decode_state_payload(bytes(f.serializeFMUstate(f.getFMUstate()))[46:])
    assert before["initialized"] == 0 and before["engine"] is None and before["guid"] == md.guid
    f.setupExperiment(startTime=0.0)
    f.enterInitializationMode()
    f.exitInitializationMode()
    vr = {v.name: v.valueReference for v in md.modelVariables}
    f.setReal([vr["ag"]], [3.0])
    f.doStep(0.0, 0.2)
    after = decode_state_payload(bytes(f.serializeFMUstate(f.getFMUstate()))[46:])
    assert after["initialized"] == 1 and after["t"] == 0.2 and after["engine"]["t"] == 0.2
    assert after["values"][vr["phi"]] == f.getReal([vr["phi"]])[0] != 0.0
    blob = bytearray(f.serializeFMUstate(f.getFMUstate()))[46:]
    blob[60] ^= 1
    with pytest.raises(ValueError, match="CRC-32"):
        decode_state_payload(bytes(blob))


def test_system_example_with_the_standalone_fmus(standalone, built_fmus, tmp_path):
    """examples/system (the building storey with a block and an oscillator on it) with the standalone block
    and oscillator in place of the pythonfmu ones: fmpy and libcosim give the pythonfmu system's results to
    round-off, and the same contacts and impact counts."""
    from rocking_model.cosim import run_fmpy

    sys.path.insert(0, str(ROOT / "examples" / "system"))
    try:
        import run as system
    finally:
        sys.path.pop(0)
    text = system.OSP.read_text()

    def osp(kind: dict) -> Path:
        out = text
        for name in ("GroundMotionSource", "LinearBuildingStorey", RIGID, FLEX):
            out = out.replace(f'source="../../dist/{name}.fmu"', f'source="{kind.get(name, built_fmus[name])}"')
        path = tmp_path / f"{len(kind)}" / "OspSystemStructure.xml"
        path.parent.mkdir(exist_ok=True)
        path.write_text(out)
        return path

    mine, ref = osp({RIGID: standalone[RIGID], FLEX: standalone[FLEX]}), osp({})
    a, b = run_fmpy(mine, 3.0, system.OUTPUTS), run_fmpy(ref, 3.0, system.OUTPUTS)
    masters = [(a, b)]
    try:
        import libcosimpy.CosimExecution  # noqa: F401
        from rocking_model.cosim import run_libcosim
        masters.append((run_libcosim(mine, 3.0, system.OUTPUTS), run_libcosim(ref, 3.0, system.OUTPUTS)))
    except ImportError:
        pass
    for got, want in masters:
        for name in system.OUTPUTS:
            g, w = np.asarray(got[name], dtype=float), np.asarray(want[name], dtype=float)
            if name.endswith(("contact", "impacts", "overturned")):
                assert np.array_equal(g, w), name
            else:
                assert np.max(np.abs(g - w)) < ROUNDOFF * max(1.0, np.max(np.abs(w))), name
        assert np.max(np.abs(np.asarray(got["block.phi"]))) > 1e-4


def test_rocking_build_fmu_builds_both_kinds(tmp_path):
    """`rocking build-fmu` (build_fmu.main) writes the pythonfmu FMU and the standalone one of a model."""
    from rocking_model.cli import main

    assert main(["build-fmu", "--dest", str(tmp_path), "--no-cross-check", RIGID]) == 0
    assert (tmp_path / f"{RIGID}.fmu").is_file()
    sa = tmp_path / "standalone" / f"{RIGID}.fmu"
    assert read_model_description(str(sa)).coSimulation.needsExecutionTool is False
    assert not (tmp_path / "standalone" / f"{FLEX}.fmu").exists()


def test_overflowing_motion_refused_with_the_simulators_message(standalone, unzipped):
    """A valid but huge state (the column deflected by 1e148 m while rocking: its motion overflows within a
    step, as in test_simulator_state) set through a crafted FMU state: the step is refused (fmi2Discard) with
    Simulator._diverged's message, word for word, and the state kept."""
    import struct
    import zlib

    from rocking_model.models import FlexibleOscillator
    from rocking_model.simulation import Simulator

    r = Run(standalone[FLEX], unzipped[FLEX], "huge")
    blob = bytearray(r.f.serializeFMUstate(r.f.getFMUstate()))
    n_vars = len(r.md.modelVariables)
    n_inputs = 2                                                    # ag, ag_v: (has_rate, rate, rate_t) each
    # the engine's plain state (no error text): header, magic, GUID, n_vars, values, 4 flags, t, t0, n_inputs,
    # the rates, the error's length, has_engine
    off = 46 + 28 + 36 + 4 + 8 * n_vars + 16 + 16 + 4 + 20 * n_inputs + 4 + 4
    struct.pack_into("<ii4d", blob, off + 8, 1, 4, 1e148, 0.01, 0.0, 0.1)   # mode LEFT, y = [u, phi, u', phi']
    blob[-4:] = zlib.crc32(bytes(blob[46:-4])).to_bytes(4, "little")
    blob[42:46] = zlib.crc32(bytes(blob[:42]) + bytes(blob[46:])).to_bytes(4, "little")
    r.f.setFMUstate(r.f.deSerializeFMUstate(bytes(blob)))
    before = r.row()
    with pytest.raises(Exception):
        r.f.doStep(0.0, 0.01)
    assert r.row() == before
    sim = Simulator(FlexibleOscillator(), "event_driven", engine="c", impact_log_size=0)
    state = sim.get_state()
    state.update(mode=1, y=[1e148, 0.01, 0.0, 0.1])
    sim.set_state(state)
    sim.on_report = "raise"
    with pytest.raises(ValueError, match="Likely cause") as info:
        sim.advance(0.01, 0.0)
    assert [t for _, _, t in r.sink if "refused" in t] == [
        f"step [0.0, 0.01] refused, the FMU state is unchanged: {info.value}"]


@pytest.mark.parametrize("name", NAMES)
def test_c_host_under_valgrind_has_no_invalid_access_nor_leak(host, standalone, unzipped, name):
    """The C host runs 0.5 s of a rocking motion under valgrind: no invalid read or write, no use of an
    uninitialized value, no definite leak in the FMU (instantiate ... free, dlclose)."""
    valgrind = shutil.which("valgrind")
    if valgrind is None:
        pytest.skip("no valgrind")
    md = read_model_description(str(standalone[name]))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    proc = subprocess.run([valgrind, "--error-exitcode=9", "--leak-check=full", "--errors-for-leak-kinds=definite",
                           "-q", str(host), unzipped[name], md.coSimulation.modelIdentifier, md.guid, str(vr["ag"]),
                           str(vr["phi"]), "5.0", "0.5", "0.01"], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert len(proc.stdout.splitlines()) == 50
