"""The examples write where they are told: every script of examples/ takes ``--out`` (default under results/,
git-ignored) and has a ``run(out=...)`` or ``main(argv)`` the docs build can call; none writes into docs/ or
another tracked folder. The demo drives the FMU with both of its inputs, so that fmpy prints no warning."""
from __future__ import annotations

import importlib.util
import re
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = sorted(p for p in (ROOT / "examples").rglob("*.py") if p.parent.name != "records")


def load(path: Path):
    spec = importlib.util.spec_from_file_location(f"_example_{path.stem}", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


@pytest.mark.parametrize("path", EXAMPLES, ids=lambda p: p.relative_to(ROOT / "examples").as_posix())
def test_example_takes_an_output_folder_and_writes_no_tracked_file(path):
    src = path.read_text()
    assert '"--out"' in src, "no --out option"
    assert re.search(r"^def (run|main)\(", src, re.M), "no run()/main() to call"
    assert not re.search(r"""["']docs["']|/ ?["']docs/""", src), "writes into docs/"
    default = re.search(r'"--out".*?default=([^,)]*)', src, re.S).group(1)
    assert "results" in default.lower(), default


def test_results_folder_is_ignored():
    ignored = subprocess.run(["git", "check-ignore", "-q", "results/x.png"], cwd=ROOT, timeout=60)
    if ignored.returncode == 128:
        pytest.skip("not a git checkout")
    assert ignored.returncode == 0


def test_no_generated_example_figure_is_tracked():
    """The figures the examples draw are built (results/, the docs site build), not committed under docs/."""
    for name in ("flexible_pulse.png", "three_component.png", "overturning_spectrum.png"):
        assert not (ROOT / "docs" / name).exists(), name


def test_flexible_pulse_writes_into_the_given_folder(tmp_path):
    png = load(ROOT / "examples" / "flexible_pulse.py").run(out=tmp_path)
    assert png == tmp_path / "flexible_pulse.png"
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_demo_gives_every_input_and_fmpy_warns_of_none(built_fmus, tmp_path, capfd):
    """examples/demo.py on the session's FMU: fmpy printed `Warning: missing input for variable "ag_v"`
    when the input table had no ag_v column; now the table carries it (zeros) and the output has no
    warning. The CSV and the plot go to the folder given."""
    demo = load(ROOT / "examples" / "demo.py")
    demo.FMU = built_fmus["RigidRockingBlock"]
    assert demo.main(["--out", str(tmp_path)]) == 0
    out, err = capfd.readouterr()
    assert "arning" not in out + err and "missing input" not in out + err, out + err
    assert "overturned  = False" in out
    assert (tmp_path / "demo_rigid.csv").is_file() and (tmp_path / "demo_rigid.png").stat().st_size > 10_000
