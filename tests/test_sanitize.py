"""The C core under ASan + UBSan, bounded for CI: tests/sanitize.py builds the sanitized
self-contained FMUs, the fuzz harnesses (fuzz/) and the sanitized extension once, runs the committed fuzz
reproducers, each libFuzzer harness for SANITIZE_FUZZ_SECONDS (default 30 s per harness, split over the three
models: the whole suite's 15-minute budget on two busy cores), the fault suite's 435 cases of the
self-contained FMUs on the sanitized binaries and a subset of the engine tests on the sanitized extension.
Longer runs: fuzz/README.md. Skips, naming the Debian packages, where clang or its runtimes are missing."""
from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
import sanitize  # noqa: E402

sys.path.remove(str(HERE))


def test_sanitized_fuzz_faults_and_engine(tmp_path):
    why = sanitize.missing_reason()
    if why:
        pytest.skip(why)
    seconds = os.environ.get("SANITIZE_FUZZ_SECONDS", "30")
    report = tmp_path / "fuzz.json"
    proc = subprocess.run([sys.executable, str(HERE / "sanitize.py"), "ci", "--seconds", seconds,
                           "--report", str(report)], cwd=sanitize.ROOT, capture_output=True, text=True)
    out = proc.stdout + proc.stderr
    print("\n".join(line for line in out.splitlines() if line.startswith(("sanitize:", "fault suite", "standalone"))
                    or " passed" in line or " failed" in line))
    assert proc.returncode == 0, out[-8000:]
    fuzz = json.loads(report.read_text())
    for harness, models in fuzz.items():
        for model, r in models.items():
            assert r["crash"] is None, f"fuzz_{harness} on {model}: {r['crash']}"
            assert r["execs"] > 0 and r["cov"] > 0, (harness, model, r)
