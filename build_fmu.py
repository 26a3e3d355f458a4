"""Build every FMU script in fmu_src/ into <dest>/<Name>.fmu and validate it with fmpy.

Usage:  python build_fmu.py [--dest dist] [Name ...]

Each FMU bundles a clean copy of the `rocking_model` package (no __pycache__, no .pyc) in its resources, so
it runs in any Python that has numpy and scipy. The modelDescription (units, variability, ModelStructure)
is produced by `rocking_model.fmi.RockingSlave.to_xml`; nothing is post-processed here. The build fails
(ValueError, exit code 1) if `fmpy.validation.validate_fmu` reports a problem.

Importable: ``build_all(dest="dist") -> list[Path]``.
"""
from __future__ import annotations

import argparse
import shutil
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent
FMU_SRC = ROOT / "fmu_src"
PACKAGE = ROOT / "rocking_model"

_IGNORE = shutil.ignore_patterns("__pycache__", "*.pyc", "*.pyo", "*.egg-info", ".pytest_cache")


def fmu_scripts(names=None) -> list[Path]:
    """The FMU scripts in fmu_src/ (optionally only those whose stem is in ``names``)."""
    scripts = sorted(p for p in FMU_SRC.glob("*.py") if not p.name.startswith("_"))
    if names:
        missing = set(names) - {p.stem for p in scripts}
        if missing:
            raise ValueError(f"no FMU script for {sorted(missing)} in {FMU_SRC}")
        scripts = [p for p in scripts if p.stem in names]
    return scripts


def validate(fmu: Path) -> None:
    """Raise ValueError listing the problems fmpy finds in ``fmu``."""
    from fmpy.validation import validate_fmu

    problems = validate_fmu(str(fmu))
    if problems:
        raise ValueError(f"{fmu} failed fmpy validation:\n  " + "\n  ".join(problems))


def build_one(script: Path, dest: Path, package_copy: Path) -> Path:
    from pythonfmu.builder import FmuBuilder

    # Options are left at pythonfmu's defaults: canInterpolateInputs=false (fmi2SetRealInputDerivatives is
    # not implemented), canGetAndSetFMUstate/canSerializeFMUstate=false (the integrator state is not in the
    # registered variables).
    fmu = FmuBuilder.build_FMU(script, dest=dest, project_files=[package_copy])
    fmu = Path(fmu)
    expected = dest / f"{script.stem}.fmu"
    if fmu.resolve() != expected.resolve():
        raise ValueError(f"{script.name}: the FMU class must be named like the script ({script.stem}); "
                         f"pythonfmu produced {fmu.name}")
    validate(fmu)
    return fmu


def build_all(dest="dist", names=None) -> list[Path]:
    """Build (and validate) all FMUs of fmu_src/ into ``dest``; return their paths."""
    dest = Path(dest)
    if not dest.is_absolute():
        dest = Path.cwd() / dest
    dest.mkdir(parents=True, exist_ok=True)
    scripts = fmu_scripts(names)
    if not scripts:
        raise ValueError(f"no FMU scripts found in {FMU_SRC}")
    built = []
    with tempfile.TemporaryDirectory(prefix="rocking_fmu_") as tmp:
        package_copy = Path(tmp) / PACKAGE.name
        shutil.copytree(PACKAGE, package_copy, ignore=_IGNORE)
        for script in scripts:
            built.append(build_one(script, dest, package_copy))
    return built


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--dest", default=str(ROOT / "dist"), help="output folder (default: dist/)")
    parser.add_argument("names", nargs="*", help="FMU names to build (default: all scripts in fmu_src/)")
    args = parser.parse_args(argv)
    try:
        fmus = build_all(args.dest, args.names or None)
    except Exception as exc:
        print(f"build_fmu: FAILED: {exc}", file=sys.stderr)
        return 1
    for fmu in fmus:
        print(f"built and validated {fmu}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
