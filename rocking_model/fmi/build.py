"""Build every FMU (`rocking_model.fmi.fmus.FMUS`) into <dest>/<Name>.fmu and validate it with fmpy.

The registered models (`rocking_model.models.MODELS`: the rigid block, the flexible oscillator, the
post-tensioned block) are also built as self-contained FMUs,
<dest>/standalone/<Name>.fmu: the compiled C engine (rocking_model/engine/src) under the C FMI layer
rocking_model/fmi/binary/standalone/fmi2_engine.c, no Python needed (`build_standalone`). They carry the
binaries of binaries/linux64, binaries/win64 and binaries/aarch64-linux (`TARGETS`), each built where its
compiler is installed (natively, or with the cross compilers x86_64-w64-mingw32-gcc and aarch64-linux-gnu-gcc);
the build prints one line naming the platforms built and the Debian packages for the others
(`platforms_summary`). sources/ builds every platform to the same numbers (the sources pin their
floating-point contract, engine/src/rk_fp.h, and carry their version, sources/rk_version.h).

Usage: ``rocking build-fmu [--dest dist] [--no-cross-check] [Name ...]``
        python build_fmu.py ...   (in a checkout: the same, with dist/ of the checkout as default)

Everything needed ships with the package (the FMI layer's C sources in rocking_model/fmi/binary, the engine's
in rocking_model/engine/src, the slave classes in rocking_model.fmi.fmus), so an installed package builds the
same FMUs as a checkout; the build needs a C compiler and the Python headers. Only in a checkout are the
generated engine sources (the model kernels, the Runge-Kutta tableaux) brought up to date before the build: an
installed package carries the ones generated when it was built.

Each FMU is built from a one-line script named like it (`fmu_script`: it imports the slave class; pythonfmu and
the binary import the class from a module of the FMU's name).

Each FMU bundles a clean copy of the `rocking_model` package (no __pycache__, no .pyc) in its resources,
under the import name ``rocking_model_<digest>`` (the SHA-256 of its sources, `package_digest`), so it runs
in any Python that has numpy, and each FMU runs the code it was built with even when FMUs of other versions
(or another rocking_model) are loaded into the same process (see `bundled_script`). The modelDescription (units, variability, ModelStructure)
is produced by `rocking_model.fmi.RockingSlave.to_xml`; nothing is post-processed here. The build fails
(ValueError, exit code 1) if `fmpy.validation.validate_fmu` reports a problem.

Cross-check folders. The command line build also writes, for every FMU, a folder in the layout of the FMI
cross-check repository (modelica/fmi-cross-check) next to the FMUs::

    <dest>/cross-check/fmus/2.0/cs/<platform>/rocking_model/<version>/<Name>/
        <Name>.fmu  <Name>_in.csv (FMUs with inputs)  <Name>_ref.csv  <Name>_ref.opt  ReadMe.md

``_in.csv``: the input signals sampled at every communication point; ``_ref.csv``: the reference result, the
fmpy run of the FMU (default start values, as the rules require) with that input; ``_ref.opt``: StartTime,
StopTime, StepSize, RelTol (the keys of the rules, read by ``fmpy.cross_check``). CSV: the first column
"time", quoted variable names, Booleans as 0/1. The scenarios are ``CROSS_CHECK`` below.

Importable: ``build_all(dest="dist", names=None, cross_check=False) -> list[Path]``,
``write_cross_check(fmu, root) -> Path``.
"""
from __future__ import annotations

import argparse
import hashlib
import json
import math
import os
import platform
import re
import shutil
import site
import subprocess
import sys
import sysconfig
import tempfile
import zipfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .. import __version__

#: the package being built into the FMUs: this one (a checkout's or an installed one)
PACKAGE = Path(__file__).resolve().parents[1]
#: the C sources of the FMI layer (package data)
FMI_BINARY = PACKAGE / "fmi" / "binary"
#: the Python side of the binary and its configuration, in every FMU's resources
PYHOST = "fmi2_pyhost.py"
PYHOST_CONFIG = "fmi2_pyhost.json"

_IGNORE = shutil.ignore_patterns("__pycache__", "*.pyc", "*.pyo", "*.egg-info", ".pytest_cache")


def checkout_root() -> Path | None:
    """The source checkout this package lives in (build_fmu.py and fmu_src/ next to it), or None when the
    package is installed."""
    root = PACKAGE.parent
    return root if (root / "build_fmu.py").is_file() and (root / "fmu_src").is_dir() else None


def registered_fmu_names() -> list[str]:
    """The FMU names of the registered models (`rocking_model.models.MODELS`): each needs a slave class in
    `rocking_model.fmi.fmus` (the other FMUs there, the ground-motion source and the building storey, are
    system parts)."""
    from ..models import MODELS

    return [cls.fmu_name for cls in MODELS.values()]


def fmu_names(names=None) -> list[str]:
    """The FMU names (`rocking_model.fmi.fmus.FMUS`, sorted), optionally only those in ``names``; BuildError when
    a registered model has no slave class."""
    from .fmus import FMUS

    known = sorted(FMUS)
    lacking = [n for n in registered_fmu_names() if n not in known]
    if lacking:
        raise BuildError(f"the registered model(s) {lacking} have no FMU: add a ModelSlave naming the model to "
                         f"rocking_model/fmi/fmus.py (see RigidRockingBlock there) and to its FMUS")
    if names:
        missing = set(names) - set(known)
        if missing:
            raise ValueError(f"no FMU named {sorted(missing)}; the FMUs are {', '.join(known)}")
        known = [n for n in known if n in names]
    return known


def fmu_script(name: str) -> str:
    """The script of FMU ``name``: a module of the FMU's name that imports its slave class (the checkout's
    fmu_src/<name>.py is this text)."""
    return (f'"""FMI 2.0 co-simulation FMU {name}: its slave class is `rocking_model.fmi.fmus.{name}`.\n\n'
            f"Written by rocking_model.fmi.build.fmu_script; build with ``rocking build-fmu`` or ``python "
            f"build_fmu.py``.\nThe module is named like the FMU on purpose: pythonfmu and the FMU binary import "
            f"the slave class from it, and\ntwo FMUs whose scripts share a module name cannot be loaded in the "
            f'same process.\n"""\nfrom rocking_model.fmi.fmus import {name}\n')


def fmu_scripts(folder: Path, names=None) -> list[Path]:
    """Write the scripts of the FMUs (all, or those in ``names``) into ``folder``; return their paths."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    scripts = []
    for name in fmu_names(names):
        script = folder / f"{name}.py"
        script.write_text(fmu_script(name))
        scripts.append(script)
    return scripts


def validate(fmu: Path) -> None:
    """Raise ValueError listing the problems fmpy finds in ``fmu``."""
    from fmpy.validation import validate_fmu

    problems = validate_fmu(str(fmu))
    if problems:
        raise ValueError(f"{fmu} failed fmpy validation:\n  " + "\n  ".join(problems))


def package_digest(package: Path = PACKAGE) -> str:
    """Short SHA-256 of the package's source files (names and contents): the bundled copy's import name."""
    h = hashlib.sha256()
    for path in sorted(p for p in package.rglob("*.py") if "__pycache__" not in p.parts):
        h.update(path.relative_to(package).as_posix().encode() + b"\0" + path.read_bytes() + b"\0")
    return h.hexdigest()[:16]


_IMPORT = re.compile(r"^(\s*)(from|import)(\s+)rocking_model\b", re.MULTILINE)


def bundled_script(script: Path, alias: str, folder: Path) -> Path:
    """The FMU's copy of ``script``: its imports of rocking_model point at the bundled copy ``alias``.

    Why: every FMU loaded into one process shares sys.modules. Under its own name the bundled package of one
    FMU would serve all of them (the first one imported wins, whatever version the others bundle); under the
    digest of its sources each FMU imports exactly the code it was built with. The binary imports the script
    itself under a name unique to its contents (rocking_model/fmi/binary/fmi2_pyhost.py)."""
    text = script.read_text()
    text, n = _IMPORT.subn(lambda m: f"{m.group(1)}{m.group(2)}{m.group(3)}{alias}", text)
    if n == 0:
        raise ValueError(f"{script.name}: no import of rocking_model found")
    out = folder / script.name
    out.write_text(text)
    return out


class BuildError(RuntimeError):
    """The FMU binary cannot be built on this machine (no C compiler, no Python headers, ...)."""


def _binary_platform() -> tuple:
    """(FMI platform folder, shared-library suffix) of this machine."""
    system = platform.system()
    bits = 64 if sys.maxsize > 2**32 else 32
    if system == "Linux":
        return f"linux{bits}", ".so"
    if system == "Darwin":
        return f"darwin{bits}", ".dylib"
    if system == "Windows":
        return f"win{bits}", ".dll"
    raise BuildError(f"no FMI platform name for {system}")


def find_compiler() -> str:
    """The C compiler: $CC, else cc, gcc or clang on PATH."""
    cc = os.environ.get("CC") or shutil.which("cc") or shutil.which("gcc") or shutil.which("clang")
    if not cc:
        raise BuildError("no C compiler found: the FMUs carry a binary compiled from rocking_model/fmi/binary; "
                         "install one "
                         "(Debian/Ubuntu: apt install gcc; Fedora: dnf install gcc; macOS: xcode-select "
                         "--install) or set CC to its path")
    return cc


def fmi_headers() -> Path:
    """The folder with fmi2Functions.h (fmpy ships the FMI 2.0 headers)."""
    import fmpy

    folder = Path(fmpy.__file__).parent / "c-code"
    if not (folder / "fmi2Functions.h").is_file():
        raise BuildError(f"the FMI 2.0 headers are not in {folder}; reinstall fmpy")
    return folder


def libpython() -> str:
    """The shared libpython of this interpreter (recorded in the binary for hosts without Python), or ''."""
    name = sysconfig.get_config_var("LDLIBRARY") or ""
    candidates = [name, sysconfig.get_config_var("INSTSONAME") or ""]
    for folder in (sysconfig.get_config_var("LIBDIR"), sysconfig.get_config_var("LIBPL"), sys.base_prefix):
        for candidate in candidates:
            if folder and candidate and (".so" in candidate or candidate.endswith((".dylib", ".dll"))):
                path = Path(folder) / candidate
                if path.is_file():
                    return str(path)
    return ""


def site_packages() -> list:
    """The folders of this environment that hold numpy and the other dependencies (a fallback sys.path for
    an interpreter that the binary starts in a host without Python)."""
    folders = []
    candidates = [sysconfig.get_paths().get(k) for k in ("purelib", "platlib")] + list(site.getsitepackages())
    for folder in candidates:
        if folder and os.path.isdir(folder) and folder not in folders:
            folders.append(folder)
    return folders


def _c_string(text: str) -> str:
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"') + '"'


def compile_binary(out_dir: Path) -> Path:
    """Compile rocking_model/fmi/binary/*.c into ``out_dir``/fmi2_python<suffix> with the system C compiler, against the FMI
    2.0 headers and this Python's headers; raise `BuildError` naming what is missing."""
    cc = find_compiler()
    include = Path(sysconfig.get_paths()["include"])
    if not (include / "Python.h").is_file():
        raise BuildError(f"Python.h is not in {include}: install the Python development headers (Debian/Ubuntu: "
                         f"apt install python3-dev, or the -dev package of your Python {sys.version_info.major}."
                         f"{sys.version_info.minor})")
    _, suffix = _binary_platform()
    out = Path(out_dir) / f"fmi2_python{suffix}"
    sources = sorted(str(p) for p in FMI_BINARY.glob("*.c"))
    cmd = [cc, "-shared", "-fPIC", "-O2", "-std=c99", "-Wall", "-Wextra", "-fvisibility=hidden",
           f"-I{fmi_headers()}", f"-I{include}", f"-I{FMI_BINARY}", f"-I{ENGINE_SRC}",
           f"-DFMI_PYTHON_LIBRARY={_c_string(libpython())}", f"-DFMI_PYTHON_EXECUTABLE={_c_string(sys.executable)}",
           *sources, "-o", str(out)]
    if platform.system() == "Linux":
        # every Python symbol goes through the run-time table (binary/pyapi.h): none may be left undefined
        cmd += ["-Wl,--no-undefined", "-ldl", "-lpthread", "-lm"]
    try:
        proc = subprocess.run(cmd, capture_output=True, text=True)
    except OSError as exc:
        raise BuildError(f"cannot run the C compiler {cc}: {exc}") from None
    if proc.returncode != 0:
        raise BuildError(f"compiling the FMU binary failed ({' '.join(cmd)}):\n{proc.stderr.strip()}")
    return out


def install_binary(fmu: Path, binary: Path, script: Path) -> None:
    """Put the project's binary into ``fmu`` instead of pythonfmu's, with its Python side and configuration:
    the binaries of other platforms (pythonfmu's) are dropped, the resources get fmi2_pyhost.py and
    fmi2_pyhost.json (the GUID, the slave module and class, the site-packages fallback)."""
    from fmpy import read_model_description

    md = read_model_description(str(fmu))
    identifier = md.coSimulation.modelIdentifier
    folder, suffix = _binary_platform()
    config = {"guid": md.guid, "slave_module": script.stem, "slave_class": script.stem,
              "site_packages": site_packages()}
    tmp = fmu.with_suffix(".fmu.tmp")
    with zipfile.ZipFile(fmu) as src, zipfile.ZipFile(tmp, "w", zipfile.ZIP_DEFLATED) as dst:
        for item in src.infolist():
            if item.filename.startswith("binaries/"):
                continue
            dst.writestr(item, src.read(item.filename))
        dst.write(binary, f"binaries/{folder}/{identifier}{suffix}")
        dst.write(FMI_BINARY / PYHOST, f"resources/{PYHOST}")
        dst.writestr(f"resources/{PYHOST_CONFIG}", json.dumps(config, indent=1) + "\n")
    os.replace(tmp, fmu)


def build_one(script: Path, dest: Path, package_copy: Path, binary: Path) -> Path:
    from pythonfmu.builder import FmuBuilder

    # the builder imports the script by module name: a module of that name from an earlier build in this
    # process must not answer for this one
    sys.modules.pop(script.stem, None)
    fmu = FmuBuilder.build_FMU(script, dest=dest, project_files=[package_copy])
    fmu = Path(fmu)
    expected = dest / f"{script.stem}.fmu"
    if fmu.resolve() != expected.resolve():
        raise ValueError(f"{script.name}: the FMU class must be named like the script ({script.stem}); "
                         f"pythonfmu produced {fmu.name}")
    install_binary(fmu, binary, script)
    validate(fmu)
    return fmu


def _pulse(A, period=1.0, t_start=0.0):
    def ag(t):
        s = t - t_start
        return A * math.sin(2.0 * math.pi * s / period) if 0.0 <= s <= period else 0.0
    return ag


def _zero(t):
    """The vertical ground acceleration of the cross-check scenes: none (their reference results predate it)."""
    return 0.0


#: cross-check scenario of each FMU: stop time, step size, tolerance, input signals (functions of t)
CROSS_CHECK = {
    "RigidRockingBlock": dict(stop=3.0, step=0.01, rel_tol=1e-8, inputs={"ag": _pulse(2.5), "ag_v": _zero}),
    "FlexibleRockingOscillator": dict(stop=3.0, step=0.01, rel_tol=1e-8, inputs={"ag": _pulse(3.0), "ag_v": _zero}),
    # default start values (the rules): the pier with its tendon; 0.5 g rocks it (its uplift needs 0.302 g)
    "PostTensionedRockingBlock": dict(stop=3.0, step=0.01, rel_tol=1e-8, inputs={"ag": _pulse(5.0), "ag_v": _zero}),
    "GroundMotionSource": dict(stop=2.0, step=0.01, rel_tol=1e-8, inputs={}),
    "LinearBuildingStorey": dict(stop=3.0, step=0.01, rel_tol=1e-8, inputs={"ag": _pulse(2.0, 0.5, 0.1)}),
}

CROSS_CHECK_DIR = "cross-check"


def _platform() -> str:
    system = {"Linux": "linux", "Windows": "win", "Darwin": "darwin"}.get(platform.system(), "linux")
    return f"{system}{64 if sys.maxsize > 2**32 else 32}"


def cross_check_dir(root, name: str) -> Path:
    """The cross-check folder of FMU ``name`` under ``root`` (e.g. dist/cross-check)."""
    return Path(root) / "fmus" / "2.0" / "cs" / _platform() / "rocking_model" / str(__version__) / name


def _csv_literal(value) -> str:
    if isinstance(value, (bool, np.bool_)):
        return "1" if value else "0"
    if isinstance(value, (int, np.integer)):
        return str(int(value))
    return repr(float(value))


def write_cross_check_csv(path: Path, result) -> None:
    """Write a structured array as a cross-check CSV: quoted names, "time" first, Booleans as 0/1."""
    names = result.dtype.names
    if names[0] != "time":
        raise ValueError("the first column must be 'time'")
    with open(path, "w", newline="\n") as f:
        f.write(",".join(f'"{n}"' for n in names) + "\n")
        for row in result:
            f.write(",".join(_csv_literal(row[n].item() if hasattr(row[n], "item") else row[n])
                             for n in names) + "\n")


def cross_check_input(name: str):
    """The input table of FMU ``name`` (structured array with 'time' first) or None if it has no input."""
    spec = CROSS_CHECK[name]
    if not spec["inputs"]:
        return None
    n = int(round(spec["stop"] / spec["step"]))
    t = np.array([k * spec["step"] for k in range(n + 1)])
    cols = [("time", np.float64)] + [(k, np.float64) for k in spec["inputs"]]
    return np.array([(ti, *[f(ti) for f in spec["inputs"].values()]) for ti in t], dtype=cols)


def simulate_cross_check(fmu: Path, input_table, opts: dict, messages: list | None = None):
    """The reference run: fmpy.simulate_fmu with the default start values, the input table and the
    options of the _ref.opt file; every output recorded. The FMU's messages (an overturning of the reference
    scene is one, an event logged with fmi2OK: the run logs with logging on so that it arrives) are collected
    into ``messages`` as (status, category, text), not printed: they describe the reference scene, not the
    user's run."""
    import fmpy
    from fmpy import read_model_description

    from . import collect_fmu_messages

    outputs = [v.name for v in read_model_description(str(fmu)).modelVariables if v.causality == "output"]
    with collect_fmu_messages() as collected:
        try:
            return fmpy.simulate_fmu(str(fmu), start_time=opts["StartTime"], stop_time=opts["StopTime"],
                                     output_interval=opts["StepSize"], relative_tolerance=opts["RelTol"],
                                     input=input_table, output=outputs, debug_logging=True)
        finally:
            if messages is not None:
                messages.extend(collected)


def write_cross_check(fmu: Path, root) -> Path:
    """Write the cross-check folder of ``fmu`` under ``root``; return the folder."""
    fmu = Path(fmu)
    name = fmu.stem
    if name not in CROSS_CHECK:
        raise ValueError(f"no cross-check scenario for {name}; add one to CROSS_CHECK in rocking_model/fmi/build.py")
    spec = CROSS_CHECK[name]
    folder = cross_check_dir(root, name)
    if folder.exists():
        shutil.rmtree(folder)
    folder.mkdir(parents=True)
    shutil.copy2(fmu, folder / fmu.name)
    opts = {"StartTime": 0.0, "StopTime": spec["stop"], "StepSize": spec["step"], "RelTol": spec["rel_tol"]}
    (folder / f"{name}_ref.opt").write_text("".join(f"{k}, {v!r}\n" for k, v in opts.items()))
    table = cross_check_input(name)
    if table is not None:
        write_cross_check_csv(folder / f"{name}_in.csv", table)
    messages: list = []
    result = simulate_cross_check(fmu, table, opts, messages)
    t_last = float(result["time"][-1])
    errors = [text for status, _, text in messages if status >= 3]   # fmi2Error or worse
    if errors or not math.isclose(t_last, spec["stop"], rel_tol=1e-9):
        raise ValueError(f"{name}: the cross-check run ended at t = {t_last:g} s (StopTime {spec['stop']:g} s): "
                         + ("; ".join(errors) or "no error message"))
    # the events (the overturning) and any fmi2Warning: part of the scene
    notes = [text for status, category, text in messages if status == 1 or category == "logEvents"]
    write_cross_check_csv(folder / f"{name}_ref.csv", result)
    inputs = ", ".join(spec["inputs"]) or "none"
    (folder / "ReadMe.md").write_text(
        f"# {name}\n\nExported by rocking_model's FMU build (pythonfmu). Reference: fmpy "
        f"simulate_fmu with the default start values, communication step {spec['step']} s, inputs ({inputs}) "
        f"from {name}_in.csv held over each step (the table is sampled at the communication points). "
        f"The FMU embeds Python: the importer needs libpython loaded and numpy and scipy importable "
        f"(see the FMU page of rocking_model's documentation, 'Loading the FMUs in a non-Python host').\n"
        + ("\nEvents and warnings of the reference run (expected: they belong to this reference scene):\n\n"
           + "".join(f"- {text}\n" for text in notes) if notes else ""))
    return folder


# ---------------------------------------------------------------------------------------------------- standalone
#: the self-contained FMUs: <dest>/standalone/<Name>.fmu, the compiled engine with no Python
STANDALONE_DIR = "standalone"
ENGINE_SRC = PACKAGE / "engine" / "src"
STANDALONE_SRC = FMI_BINARY / "standalone"
#: portable flags: strict C99, IEEE arithmetic as written (no contraction into FMAs, no fast-math), no
#: -march: the binary runs on any x86-64 (or aarch64, whatever the compiler targets) and the results are the
#: engine's (-O3 as setup.py builds the extension: the same bits). The sources pin the contraction themselves
#: too (engine/src/rk_fp.h), for importers that compile sources/ with flags of their own.
PORTABLE_CFLAGS = ["-std=c99", "-O3", "-ffp-contract=off", "-fno-fast-math"]


@dataclass(frozen=True)
class Target:
    """A platform the self-contained FMUs carry a binary for: its folder under binaries/ (the FMI 2.0 names for
    x86-64, the FMI 3.0 platform tuple for 64-bit ARM, as FMI 2.0.4 prescribes), the library suffix, the
    system and machine names (`platform.system()`, `platform.machine()`) of a host that builds it natively,
    and the cross compiler (GCC's target triple) with the Debian package that installs it."""

    folder: str
    suffix: str
    system: str
    machines: tuple
    cross: str
    package: str

    @property
    def env(self) -> str:
        """The environment variable naming this platform's compiler instead (e.g. ROCKING_CC_AARCH64_LINUX)."""
        return "ROCKING_CC_" + self.folder.upper().replace("-", "_")


#: the platforms of the self-contained FMUs, each built where its compiler is installed: natively ($CC, cc) on
#: a host of that platform, else by its cross compiler (or $ROCKING_CC_<FOLDER>). Darwin: no cross compiler
#: (and no way to test a binary here): a Mac builds its own (`DARWIN_TARGETS`), every importer can build sources/.
TARGETS = (
    Target("linux64", ".so", "Linux", ("x86_64", "amd64"), "x86_64-linux-gnu-gcc", "gcc-x86-64-linux-gnu"),
    Target("win64", ".dll", "Windows", ("amd64", "x86_64"), "x86_64-w64-mingw32-gcc", "gcc-mingw-w64-x86-64"),
    Target("aarch64-linux", ".so", "Linux", ("aarch64", "arm64"), "aarch64-linux-gnu-gcc", "gcc-aarch64-linux-gnu"),
)
DARWIN_TARGETS = (
    Target("darwin64", ".dylib", "Darwin", ("x86_64",), "", ""),
    Target("aarch64-darwin", ".dylib", "Darwin", ("arm64", "aarch64"), "", ""),
)


def host_target() -> Target | None:
    """The platform of this machine among `TARGETS` and `DARWIN_TARGETS`, or None (32-bit, another system)."""
    system, machine = platform.system(), platform.machine().lower()
    if sys.maxsize <= 2**32:
        return None
    for target in TARGETS + DARWIN_TARGETS:
        if target.system == system and machine in target.machines:
            return target
    return None


#: the environment variable that restricts the platforms built (comma-separated folders, e.g. "linux64"; unset:
#: every platform whose compiler is installed)
PLATFORMS_ENV = "ROCKING_FMU_PLATFORMS"


def standalone_compilers() -> dict:
    """{folder: compiler command or None} of the self-contained FMUs' platforms on this machine: this
    machine's own platform with the system C compiler (`find_compiler`), the others of `TARGETS` with their
    cross compilers where installed ($ROCKING_CC_<FOLDER> first; None when absent). Only the platforms of
    $ROCKING_FMU_PLATFORMS when it is set."""
    host = host_target()
    found = {}
    if host is not None:
        found[host.folder] = os.environ.get(host.env) or find_compiler()
    for target in TARGETS:
        if target.folder not in found:
            found[target.folder] = os.environ.get(target.env) or shutil.which(target.cross)
    wanted = [f.strip() for f in os.environ.get(PLATFORMS_ENV, "").split(",") if f.strip()]
    if wanted:
        unknown = sorted(set(wanted) - set(found))
        if unknown:
            raise BuildError(f"{PLATFORMS_ENV} names {unknown}; the platforms here are {sorted(found)}")
        found = {f: cc for f, cc in found.items() if f in wanted}
    return found


def platforms_summary(compilers: dict | None = None) -> str:
    """The one line the build prints: the platforms it built binaries for and, for the others, what to
    install (the Debian/Ubuntu package of the cross compiler) or that $ROCKING_FMU_PLATFORMS left them out."""
    compilers = standalone_compilers() if compilers is None else compilers
    built = [f for f, cc in compilers.items() if cc]
    missing = [f"{t.folder} (install {t.package})" for t in TARGETS if t.folder in compilers
               and not compilers[t.folder]]
    missing += [f"{t.folder} ({PLATFORMS_ENV})" for t in TARGETS if t.folder not in compilers
                and (host_target() is None or t.folder != host_target().folder)]
    line = "self-contained FMUs: binaries for " + (", ".join(built) or "no platform")
    if missing:
        line += "; not for " + ", ".join(missing)
    return line + "; sources/ for any platform"


def _target(folder: str) -> Target:
    for target in TARGETS + DARWIN_TARGETS:
        if target.folder == folder:
            return target
    raise ValueError(f"no platform {folder!r}; the platforms are {[t.folder for t in TARGETS + DARWIN_TARGETS]}")


def target_flags(target: Target) -> tuple:
    """(compile flags, link flags) of the self-contained FMU's binary for ``target``."""
    cflags = [*PORTABLE_CFLAGS, "-I."]
    if target.system == "Windows":
        # mingw-w64: printf-family formatting (the messages) by mingw's C99 implementation, as glibc's, not
        # msvcrt's; the DLL imports KERNEL32 and msvcrt only (libgcc linked in); neither the link time nor an
        # image base drawn from the output's path in the PE headers (the same sources give the same bytes)
        return cflags + ["-D__USE_MINGW_ANSI_STDIO=1"], ["-shared", "-static-libgcc", "-s", "-lm",
                                                           "-Wl,--no-insert-timestamp,--disable-auto-image-base"]
    cflags += ["-fPIC", "-fvisibility=hidden"]
    if target.system == "Linux":
        # every symbol resolved at link time (libc, libm: NEEDED), stripped
        return cflags, ["-shared", "-Wl,--no-undefined", "-s", "-lm"]
    return cflags, ["-shared", "-lm"]


_INCLUDE = re.compile(rb'^\s*#\s*include\s*"([^"]+)"', re.MULTILINE)


def _dependencies(src: Path, name: str, texts: dict) -> list:
    """``name`` and the files of ``src`` it includes (#include "...", transitively), sorted."""
    seen, todo = set(), [name]
    while todo:
        n = todo.pop()
        if n in seen or n not in texts:
            continue
        seen.add(n)
        todo.extend(m.decode() for m in _INCLUDE.findall(texts[n]))
    return sorted(seen)


#: object files compiled in this process, by everything that makes them (the compiler, its flags, the bytes of
#: the source and of every header it includes): the engine's objects are shared by the FMUs and by the
#: platforms' builds of later test modules (a compile cache, as ccache; the link runs every time)
_OBJECTS: dict = {}


def _compile_targets(name: str, src: Path, out_dir: Path, compilers: dict) -> dict:
    """Compile sources/ (``src``) for every platform of ``compilers`` ({folder: cc}) -- each source to an object
    (concurrently, `_OBJECTS` reused), then the link -- and return {folder: path of the binary}."""
    from concurrent.futures import ThreadPoolExecutor

    texts = {p.name: p.read_bytes() for p in src.iterdir() if p.is_file()}
    c_sources = sorted(n for n in texts if n.endswith(".c"))
    deps = {c: _dependencies(src, c, texts) for c in c_sources}
    jobs, links = [], []
    for folder, cc in compilers.items():
        target = _target(folder)
        cflags, ldflags = target_flags(target)
        obj_dir = out_dir / folder / "obj"
        obj_dir.mkdir(parents=True, exist_ok=True)
        objects = []
        for c in c_sources:
            obj = obj_dir / (c[:-2] + ".o")
            key = hashlib.sha256(repr([cc, cflags, c]).encode()
                                 + b"".join(d.encode() + b"\0" + texts[d] + b"\0" for d in deps[c])).hexdigest()
            if key in _OBJECTS:
                obj.write_bytes(_OBJECTS[key])
            else:
                jobs.append((folder, [cc, "-c", *cflags, c, "-o", str(obj)], obj, key))
            objects.append(str(obj))
        out = out_dir / folder / f"{name}{target.suffix}"
        links.append((folder, [cc, *objects, "-o", str(out), *ldflags], out))

    def run(cmd):
        try:
            return subprocess.run(cmd, cwd=src, capture_output=True, text=True)
        except OSError as exc:
            return exc

    failures = []
    with ThreadPoolExecutor(max_workers=max(2, os.cpu_count() or 2)) as pool:
        for (folder, cmd, obj, key), proc in zip(jobs, pool.map(run, [j[1] for j in jobs])):
            if isinstance(proc, OSError):
                failures.append(f"{folder}: cannot run the C compiler {cmd[0]}: {proc}")
            elif proc.returncode != 0:
                failures.append(f"{folder} ({' '.join(cmd)}):\n{proc.stderr.strip()}")
            else:
                _OBJECTS[key] = obj.read_bytes()
        if not failures:
            for (folder, cmd, out), proc in zip(links, pool.map(run, [link[1] for link in links])):
                if isinstance(proc, OSError) or proc.returncode != 0:
                    failures.append(f"{folder} ({' '.join(cmd)}):\n"
                                    f"{proc if isinstance(proc, OSError) else proc.stderr.strip()}")
    if failures:
        raise BuildError(f"compiling the standalone FMU {name} failed for " + "\n".join(failures))
    return {folder: out for folder, _, out in links}
#: the FMI 2.0 headers shipped in sources/ (from fmpy's copy of the standard's headers, BSD-2-Clause)
FMI2_HEADERS = ("fmi2Functions.h", "fmi2FunctionTypes.h", "fmi2TypesPlatform.h")
#: fixed zip timestamps: the same sources give the same FMU bytes
_ZIP_DATE = (2020, 1, 1, 0, 0, 0)


#: the engine's sources generated at build time (gitignored in a checkout; an installed package carries them)
GENERATED_ENGINE_SOURCES = ("rk_tableaux.h", "rk_models_gen.c")


def _engine_sources() -> list[Path]:
    if checkout_root() is not None:
        if not (ENGINE_SRC / "rk_tableaux.h").is_file():     # gen_rk.py writes it
            import runpy
            runpy.run_path(str(PACKAGE / "engine" / "gen_rk.py"), run_name="__main__")
        # the model kernels, generated from the declarations (up to date: a no-op); sympy, a build-time
        # dependency, is only needed here
        from ..engine import gen_models
        gen_models.main()
    else:
        missing = [n for n in GENERATED_ENGINE_SOURCES if not (ENGINE_SRC / n).is_file()]
        if missing:
            raise BuildError(f"the installed package lacks the generated engine sources {missing} in {ENGINE_SRC} "
                             f"(they are written when the package is built); reinstall rocking-model, or build "
                             f"from a source checkout (python build_fmu.py), which generates them")
    return sorted(p for p in ENGINE_SRC.glob("*.c") if p.suffix == ".c") + sorted(ENGINE_SRC.glob("*.h"))


#: the engine's version header (engine/src/rk_version.h): the FMUs' sources/ carry it with the version written in
VERSION_HEADER = "rk_version.h"


def version_header(version: str = __version__) -> str:
    """sources/rk_version.h of the self-contained FMUs: the engine's version as a macro, so that a library built
    from sources/ by an importer (who passes no -D) reports it (rk_engine_version)."""
    return (f"/* rk_version.h -- the engine's version, written by rocking_model/fmi/build.py into the FMU's sources\n"
            f" * (rocking_model {version}); rk_engine_version() returns it. */\n"
            f"#ifndef RK_VERSION_H\n#define RK_VERSION_H\n\n#ifndef RK_ENGINE_VERSION_STRING\n"
            f"#define RK_ENGINE_VERSION_STRING {json.dumps(version)}\n#endif\n\n#endif /* RK_VERSION_H */\n")


def _slave_class(fmu):
    """The slave class of ``fmu``: an FMU name (`rocking_model.fmi.fmus.FMUS`) or the path of an FMU script
    (imported under a name of its own, the class named like the script)."""
    if isinstance(fmu, str) and not fmu.endswith(".py"):
        from .fmus import FMUS

        fmu_names([fmu])                                # the error naming the FMUs when unknown
        return FMUS[fmu]
    import importlib.util

    script = Path(fmu)
    spec = importlib.util.spec_from_file_location(f"_standalone_{script.stem}", script)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return getattr(module, script.stem)


def build_standalone_one(fmu, dest: Path, platforms=None) -> Path:
    """Build the self-contained FMU ``fmu`` (a name, or the path of its script) into ``dest``/<Name>.fmu: the
    modelDescription, the C variable table and the documentation generated from the slave's declarations, the
    engine and the FMI layer compiled in a folder of their own (relative paths: no path of this machine in the
    binary) for every platform whose compiler is here (`standalone_compilers`; or those of ``platforms``, FMI
    folder names), the sources shipped under sources/ with their buildDescription.xml and the version header."""
    from . import standalone

    slave_class = _slave_class(fmu)
    name = slave_class.__name__
    slave = standalone.slave_instance(slave_class)
    dest = Path(dest)
    engine_files = _engine_sources()
    # a model declared outside the package: its own kernels, generated from its declaration (sympy), replace
    # the package's in the FMU's sources
    model_class = getattr(slave_class, "model_class", None)
    own_kernels = None
    if model_class is not None:
        from ..engine import plugin
        if not plugin.built_in(model_class):
            own_kernels = plugin.source_of(model_class, export=False).encode()
    kernels_name = "rk_models_gen.c"
    fmi_files = [FMI_BINARY / f for f in standalone.FMI_SOURCES]
    def text(p):
        if own_kernels is not None and p.name == kernels_name:
            return own_kernels
        return version_header().encode() if p.name == VERSION_HEADER else p.read_bytes()

    digest = b"".join(p.name.encode() + b"\0" + text(p) for p in engine_files + fmi_files)
    c_sources = sorted(p.name for p in engine_files + fmi_files if p.suffix == ".c")
    xml, guid = standalone.model_description(slave, c_sources, digest)
    compilers = standalone_compilers()
    if platforms is not None:
        unknown = set(platforms) - set(compilers)
        if unknown:
            raise BuildError(f"no compiler for the platform(s) {sorted(unknown)} on this machine: "
                             + platforms_summary(compilers))
        compilers = {f: cc for f, cc in compilers.items() if f in platforms}
    compilers = {f: cc for f, cc in compilers.items() if cc}
    with tempfile.TemporaryDirectory(prefix="rocking_sa_") as tmp:
        src = Path(tmp) / "sources"
        src.mkdir()
        for p in engine_files + fmi_files:
            if own_kernels is not None and p.name == kernels_name:
                (src / p.name).write_bytes(own_kernels)
            elif p.name == VERSION_HEADER:
                (src / p.name).write_text(version_header())
            else:
                shutil.copy2(p, src / p.name)
        for h in FMI2_HEADERS:
            shutil.copy2(fmi_headers() / h, src / h)
        (src / "rk_fmu_vars.h").write_text(standalone.vars_header(slave, guid))
        binaries = _compile_targets(name, src, Path(tmp) / "binaries", compilers)
        (src / "buildDescription.xml").write_bytes(standalone.build_description(name, c_sources))
        dest.mkdir(parents=True, exist_ok=True)
        fmu = dest / f"{name}.fmu"
        tmp_fmu = fmu.with_suffix(".fmu.tmp")

        def put(zf, arcname, data):
            info = zipfile.ZipInfo(arcname, _ZIP_DATE)
            info.compress_type = zipfile.ZIP_DEFLATED
            info.external_attr = 0o644 << 16
            zf.writestr(info, data)

        with zipfile.ZipFile(tmp_fmu, "w") as zf:
            put(zf, "modelDescription.xml", xml)
            for folder in sorted(binaries):
                put(zf, f"binaries/{folder}/{binaries[folder].name}", binaries[folder].read_bytes())
            for p in sorted(src.iterdir()):
                put(zf, f"sources/{p.name}", p.read_bytes())
            put(zf, "documentation/index.html", standalone.documentation(slave).encode())
            # the FMU reads no resources; the folder exists so that every importer has one to point to
            put(zf, "resources/README.txt", b"This FMU reads no resources: the model is compiled into its binary.\n")
        os.replace(tmp_fmu, fmu)
    validate(fmu)
    return fmu


def build_standalone(dest="dist", names=None, platforms=None) -> list[Path]:
    """Build (and validate) the self-contained FMUs of the registered models into ``dest``/standalone, with the
    binaries of every platform whose compiler is installed (or of ``platforms``, see `build_standalone_one`)."""
    dest = Path(dest)
    if not dest.is_absolute():
        dest = Path.cwd() / dest
    wanted = registered_fmu_names()
    return [build_standalone_one(name, dest / STANDALONE_DIR, platforms) for name in fmu_names(names)
            if name in wanted]


def build_script(script: Path, dest="dist") -> Path:
    """The pythonfmu FMU of an FMU script of one's own (a `ModelSlave` subclass named like the file, whose
    model may be declared in the same file): built and validated into ``dest``. Its model's kernels, if the
    model is not one of the package's, are compiled on the FMU's first use on the host (sympy and a C compiler
    there)."""
    script, dest = Path(script).resolve(), Path(dest).resolve()
    dest.mkdir(parents=True, exist_ok=True)
    # a bundled copy of its own name: the package's FMUs built later in the same process import theirs afresh
    alias = f"{PACKAGE.name}_{package_digest()}_{script.stem.lower()}"
    with tempfile.TemporaryDirectory(prefix="rocking_fmu_") as tmp:
        package_copy = Path(tmp) / alias
        shutil.copytree(PACKAGE, package_copy, ignore=_IGNORE)
        (Path(tmp) / "scripts").mkdir()
        binary = compile_binary(Path(tmp))
        sys.path.insert(0, tmp)
        try:
            return build_one(bundled_script(script, alias, Path(tmp) / "scripts"), dest, package_copy, binary)
        finally:
            sys.path.remove(tmp)
            for name in [m for m in sys.modules if m == alias or m.startswith(alias + ".")]:
                del sys.modules[name]
            sys.modules.pop(script.stem, None)


def build_all(dest="dist", names=None, cross_check=False) -> list[Path]:
    """Build (and validate) all FMUs (or those in ``names``) into ``dest``; return their paths. With
    ``cross_check``, also write their cross-check folders under ``dest``/cross-check."""
    dest = Path(dest)
    if not dest.is_absolute():
        dest = Path.cwd() / dest
    dest.mkdir(parents=True, exist_ok=True)
    built = []
    alias = f"{PACKAGE.name}_{package_digest()}"
    with tempfile.TemporaryDirectory(prefix="rocking_fmu_") as tmp:
        scripts = fmu_scripts(Path(tmp) / "src", names)
        package_copy = Path(tmp) / alias
        shutil.copytree(PACKAGE, package_copy, ignore=_IGNORE)
        (Path(tmp) / "scripts").mkdir()
        binary = compile_binary(Path(tmp))
        sys.path.insert(0, tmp)   # the builder imports the script, which imports the bundled copy
        try:
            for script in scripts:
                built.append(build_one(bundled_script(script, alias, Path(tmp) / "scripts"), dest, package_copy,
                                        binary))
        finally:
            sys.path.remove(tmp)
            for name in [m for m in sys.modules if m == alias or m.startswith(alias + ".")]:
                del sys.modules[name]
            for script in scripts:
                sys.modules.pop(script.stem, None)
    if cross_check:
        for fmu in built:
            write_cross_check(fmu, dest / CROSS_CHECK_DIR)
    return built


def main(argv=None, default_dest="dist", prog="build_fmu") -> int:
    """The command line of ``python build_fmu.py`` and ``rocking build-fmu``: exit code 0, or 1 with one line
    ``<prog>: FAILED: ...`` on stderr."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--dest", default=str(default_dest), help="output folder (default: dist/)")
    parser.add_argument("--no-cross-check", action="store_true",
                        help="do not write the cross-check folders (dest/cross-check)")
    parser.add_argument("names", nargs="*", help="FMU names to build (default: all)")
    args = parser.parse_args(argv)
    try:
        fmus = build_all(args.dest, args.names or None, cross_check=not args.no_cross_check)
        # the self-contained FMUs of the registered models among the names
        wanted = set(registered_fmu_names()) & set(args.names or registered_fmu_names())
        if wanted:
            fmus += build_standalone(args.dest, sorted(wanted))
    except Exception as exc:
        print(f"{prog}: FAILED: {exc}", file=sys.stderr)
        return 1
    for fmu in fmus:
        print(f"built and validated {fmu}")
    if wanted:
        print(platforms_summary())
    if not args.no_cross_check:
        print(f"cross-check folders in {Path(args.dest) / CROSS_CHECK_DIR}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
