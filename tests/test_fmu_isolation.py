"""Each FMU runs the code it was built with: FMUs loaded into one process share sys.modules, so the
bundled package is imported under the digest of its sources (build_fmu.bundled_script). Checked with a
deliberately modified copy of the package built into an FMU of the same name, loaded next to the original
(and next to a host that imported, and changed, its own rocking_model first), in one subprocess."""
from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

#: the modification: every output "energy" of the modified package is 1000 J higher
MODIFICATION = """

# --- deliberately modified copy (tests/test_fmu_isolation.py) ---
_original_get_real = RockingSlave.get_real


def _modified_get_real(self, vrs):
    values = _original_get_real(self, vrs)
    return [v + 1000.0 if self.vars[vr].name == "energy" else v for vr, v in zip(vrs, values)]


RockingSlave.get_real = _modified_get_real
"""

WORKER = textwrap.dedent("""
    import json, sys
    import fmpy
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave

    original, modified = sys.argv[1], sys.argv[2]
    # the host imports its own rocking_model first, and changes it: no FMU may run this one
    import rocking_model.simulation as host
    host_outputs = host.Simulator.outputs
    host.Simulator.outputs = lambda self: {**host_outputs(self), "energy": -5000.0}

    def run(path):
        res = fmpy.simulate_fmu(path, stop_time=0.05, output_interval=0.01, output=["energy", "phi"],
                                start_values={"phi_0": 0.01})
        return [float(e) for e in res["energy"]]

    out = {"sys_path": [len(sys.path)]}
    out["original_1"] = run(original)
    out["modified_1"] = run(modified)
    out["original_2"] = run(original)

    # interleaved live instances of both versions
    def instance(path, name):
        md = read_model_description(path)
        fmu = FMU2Slave(guid=md.guid, unzipDirectory=extract(path),
                        modelIdentifier=md.coSimulation.modelIdentifier, instanceName=name)
        fmu.instantiate()
        fmu.setupExperiment(startTime=0.0)
        fmu.enterInitializationMode()
        fmu.exitInitializationMode()
        vr = {v.name: v.valueReference for v in md.modelVariables}
        return fmu, vr

    a, vr = instance(original, "a")
    b, _ = instance(modified, "b")
    out["interleaved"] = []
    for k in range(3):
        a.doStep(0.01 * k, 0.01)
        b.doStep(0.01 * k, 0.01)
        out["interleaved"].append([a.getReal([vr["energy"]])[0], b.getReal([vr["energy"]])[0]])
    for fmu in (a, b):
        fmu.terminate()
        fmu.freeInstance()
    for k in range(50):
        fmu, _ = instance(original if k % 2 else modified, f"i{k}")
        fmu.terminate()
        fmu.freeInstance()
        out["sys_path"].append(len(sys.path))
    print(json.dumps(out))
""")


@pytest.fixture(scope="module")
def two_versions(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("versions")
    sys.path.insert(0, str(ROOT))
    try:
        import build_fmu
    finally:
        sys.path.remove(str(ROOT))

    original = build_fmu.build_all(tmp / "original", names=["RigidRockingBlock"])[0]
    # a copy of the project whose package differs: built by its own build_fmu.py, in another process
    copy = tmp / "copy"
    copy.mkdir()
    for name in ("build_fmu.py", "fmu_src", "rocking_model"):
        src = ROOT / name
        (shutil.copytree(src, copy / name, ignore=shutil.ignore_patterns("__pycache__"))
         if src.is_dir() else shutil.copy2(src, copy / name))
    with open(copy / "rocking_model" / "fmi" / "slave.py", "a") as f:
        f.write(MODIFICATION)
    subprocess.run([sys.executable, str(copy / "build_fmu.py"), "--dest", str(tmp / "modified"),
                    "--no-cross-check", "RigidRockingBlock"], check=True, capture_output=True, cwd=tmp,
                   env={**os.environ, "ROCKING_FMU_PLATFORMS": "linux64"})   # (the cross binaries: another test)
    return original, tmp / "modified" / "RigidRockingBlock.fmu"


def test_each_fmu_runs_its_own_version(two_versions, tmp_path):
    original, modified = two_versions
    proc = subprocess.run([sys.executable, "-c", WORKER, str(original), str(modified)], capture_output=True,
                          text=True, timeout=300, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr[-3000:]
    out = json.loads(proc.stdout.strip().splitlines()[-1])
    # the block tilted by 0.01 rad has a small positive energy; the modified version adds 1000 J
    assert out["original_1"] == out["original_2"]
    assert all(0.0 < e < 1.0 for e in out["original_1"])
    assert [round(m - o, 9) for o, m in zip(out["original_1"], out["modified_1"])] == [1000.0] * 6
    for a, b in out["interleaved"]:
        assert abs(a) < 1.0 and 999.0 < b < 1001.0
    # sys.path does not grow with instances
    assert len(set(out["sys_path"])) == 1, out["sys_path"]
