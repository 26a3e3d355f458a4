"""Golden outputs (issue 14): every output of the benchmark scenes and of the FMU cross-check runs is
bit-identical to the recording in tests/data/golden.npz (see tests/golden.py: on a machine whose arithmetic
kernels differ from the recording's, the smooth runs are held to round-off and the chaotic ones skipped).
The comparison is also re-run in a subprocess under other kernels, where it must hold in the same way."""
from __future__ import annotations

import subprocess
import sys

import pytest

import golden
import roundoff

pytest.importorskip("fmpy")


@pytest.fixture(scope="module")
def new_runs(built_fmus):
    fmus = {n: built_fmus[n] for n in golden.fmu_names()}
    return golden.flatten(golden.library_runs()) | golden.flatten(golden.fmu_runs(fmus))


def test_golden_outputs(new_runs):
    ref, meta = golden.load()
    same = meta["fingerprint"] == roundoff.fingerprint()
    failures, skipped = golden.compare(new_runs, ref, same)
    assert not failures, f"{len(failures)} of {len(ref)} recorded arrays changed:\n" + "\n".join(failures[:20])
    if skipped:
        pytest.skip(f"{len(skipped)} chaotic arrays not compared: the arithmetic kernels differ from the "
                    f"recording's ({meta['fingerprint']})")


def test_golden_under_other_kernels(built_fmus):
    """The same comparison in a process with the generic libm/BLAS/SIMD kernels: no failure (the smooth
    runs within round-off; the chaotic ones are skipped there, unless the kernels happen to agree)."""
    folder = next(iter(built_fmus.values())).parent
    proc = subprocess.run([sys.executable, str(golden.HERE / "golden.py"), "--fmus", str(folder)],
                          env=roundoff.kernel_env(), capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    assert " 0 differ" in proc.stdout
