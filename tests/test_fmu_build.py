"""What the FMU build and the demo entry point print: the cross-check reference runs are silent
about their own scenes (an overturning there is expected, noted in the folder's ReadMe.md), and run.sh says
what each phase does before it runs."""
from __future__ import annotations

from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def test_cross_check_build_prints_no_warning_of_its_reference_scenes(built_fmus, build_module, tmp_path, capfd):
    """Writing the cross-check folders (what `python build_fmu.py`, `rocking build-fmu` and `bash run.sh
    demo` do after building) prints nothing of the reference runs: the overturning of a reference scene is
    noted in its ReadMe.md as expected, never printed where a user reads it as their own run overturning."""
    pytest.importorskip("fmpy")
    capfd.readouterr()
    folders = [build_module.write_cross_check(path, tmp_path / "cross-check") for path in built_fmus.values()]
    out, err = capfd.readouterr()
    assert "overturned" not in out + err and "WARNING" not in (out + err).upper(), out + err
    readmes = {folder.name: (folder / "ReadMe.md").read_text() for folder in folders}
    noted = [name for name, text in readmes.items() if "overturned at t =" in text]
    assert noted, "no reference scene overturns: nothing to note (the scenes changed?)"
    for name in noted:
        assert "expected: they belong to this reference scene" in readmes[name], name


def test_run_sh_says_what_each_phase_does(run_sh_stubbed):
    """bash run.sh demo with a stand-in interpreter (each call only logged): a line before the install,
    the build and the demo, so that the 40 s of pip are not silent."""
    proc, calls = run_sh_stubbed("demo")
    assert proc.returncode == 0, proc.stderr
    lines = proc.stdout.splitlines()
    phases = [next((i for i, line in enumerate(lines) if line.startswith("run.sh: ") and word in line), None)
              for word in ("installing", "building", "demo")]
    assert None not in phases and phases == sorted(phases), proc.stdout
    assert [c.split()[0] for c in calls] == ["-m", "-m", "build_fmu.py", "examples/demo.py"], calls


def test_fmu_src_scripts_are_the_packages_wrappers(build_module):
    """fmu_src/ holds one thin script per FMU, exactly the text the build writes from the package's registry
    (`rocking_model.fmi.build.fmu_script`): the slave classes live in the package alone, and a checkout
    builds what an installed package builds."""
    from rocking_model.fmi.fmus import FMUS

    scripts = {p.stem: p.read_text() for p in (ROOT / "fmu_src").glob("*.py")}
    assert sorted(scripts) == sorted(FMUS)
    for name, text in scripts.items():
        assert text == build_module.fmu_script(name), f"fmu_src/{name}.py differs from fmu_script({name!r})"


def test_unknown_fmu_name_is_one_clear_error(build_module, tmp_path, capsys):
    assert build_module.main(["--dest", str(tmp_path), "--no-cross-check", "NoSuchFmu"]) == 1
    err = capsys.readouterr().err
    assert "build_fmu: FAILED: no FMU named ['NoSuchFmu']; the FMUs are FlexibleRockingOscillator" in err
    assert not list(tmp_path.iterdir())
