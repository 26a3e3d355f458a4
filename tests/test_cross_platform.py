"""The self-contained FMUs on three platforms: binaries/linux64, binaries/win64 and
binaries/aarch64-linux, each run by a C host compiled for its platform (tests/c/xhost.c): natively, under wine
(win64) and under qemu-user (aarch64), on the benchmark scenes of both models and the post-tensioned block,
both schemes, in one start of each emulator. Equal to linux64 within 1e-12 rad (rigid blocks) and 1e-9 rad
(flexible oscillator), the same statuses, impact counts and every other Integer and Boolean output.

And the sources: they pin their floating-point contract (an aarch64 build with GCC's default contraction and
no flag has no fused multiply-add, and gives the shipped aarch64 binary's bits) and carry their version;
`fmpy compile` of each FMU gives the shipped linux64 binary's bits.

A tool that is missing skips its tests with the Debian package to install (`bash run.sh test` installs them
when it runs as root with apt-get). Cost: the cross binaries are compiled once per session
(rocking_model.fmi.build caches them in the process); wine starts once per session, in a prefix kept in
~/.cache/rocking_model/wine64 (its first creation takes about 7 s)."""
from __future__ import annotations

import ctypes
import os
import shutil
import struct
import subprocess
import sys
import zipfile
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
import pytest

fmpy = pytest.importorskip("fmpy")
from fmpy import read_model_description  # noqa: E402

from test_standalone_fmu import FLEX, NAMES, PT, RIGID, _scene_input, _scene_runs  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
XHOST = ROOT / "tests" / "c" / "xhost.c"
HEADERS = Path(fmpy.__file__).parent / "c-code"
CC = os.environ.get("CC") or shutil.which("cc") or shutil.which("gcc")
MINGW = shutil.which("x86_64-w64-mingw32-gcc")
AARCH64 = shutil.which("aarch64-linux-gnu-gcc")
WINE = shutil.which("wine") or shutil.which("wine64") or next(
    (p for p in ("/usr/lib/wine/wine64", "/usr/lib/wine/wine") if os.access(p, os.X_OK)), None)
QEMU = shutil.which("qemu-aarch64-static") or shutil.which("qemu-aarch64")
SYSROOT = Path("/usr/aarch64-linux-gnu")
#: [rad] the agreement required of the other platforms with linux64 (their libm: sin, cos, exp, ... may
#: differ in the last bit; everything else is IEEE arithmetic as written, no contraction)
TOL = {RIGID: 1e-12, PT: 1e-12, FLEX: 1e-9}
#: the fused multiply-add instructions of AArch64 (scalar and vector)
FMA = ("fmadd", "fmsub", "fnmadd", "fnmsub", "fmla", "fmls")

pytestmark = pytest.mark.skipif(CC is None or not sys.platform.startswith("linux") or
                                os.uname().machine not in ("x86_64", "amd64"),
                                reason="builds and runs the FMUs' binaries from an x86-64 Linux machine with a C "
                                       "compiler")


def need(tool, what, package):
    if not tool:
        pytest.skip(f"{what} not found: install the Debian package {package}")


# ------------------------------------------------------------------------------------------------- fixtures
@pytest.fixture(scope="session")
def xfmus(build_module, tmp_path_factory) -> dict:
    """The self-contained FMUs with every platform whose compiler is installed: {name: (fmu, unzipped dir)}."""
    dest = tmp_path_factory.mktemp("xplat")
    fmus = {p.stem: p for p in build_module.build_standalone(dest)}
    out = {}
    for name, fmu in fmus.items():
        unzip = dest / "unzipped" / name
        with zipfile.ZipFile(fmu) as zf:
            zf.extractall(unzip)
        out[name] = (fmu, unzip)
    return out


def _compile_host(cc, out, *extra):
    proc = subprocess.run([cc, "-std=c99", "-O1", "-Wall", f"-I{HEADERS}", str(XHOST), "-o", str(out), *extra],
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    return out


@pytest.fixture(scope="session")
def hosts(tmp_path_factory) -> dict:
    """xhost compiled for each platform whose compiler is here: {folder: executable}."""
    folder = tmp_path_factory.mktemp("xhost")
    out = {"linux64": _compile_host(CC, folder / "xhost", "-ldl")}
    if MINGW:
        out["win64"] = _compile_host(MINGW, folder / "xhost.exe")
    if AARCH64:
        out["aarch64-linux"] = _compile_host(AARCH64, folder / "xhost_aarch64", "-ldl")
    return out


def _hex(x: float) -> str:
    return struct.pack(">d", float(x)).hex()


def _real(h: str) -> float:
    return struct.unpack(">d", bytes.fromhex(h))[0]


def scenes():
    """(FMU name, label, start values, ag per step, dt) of every scene, both schemes: the benchmark scenes of
    the rigid block and the flexible oscillator (benchmarks/scenes.py, quick), and the post-tensioned block
    rocking with its tendon taut (tests/test_standalone_fmu.py's scene)."""
    out = []
    for scheme in (0, 1):
        for scene in _scene_runs():
            name = RIGID if scene.kind == "rigid" else FLEX
            out.append((name, f"{scene.name}/{scheme}", {**scene.model_kw, **scene.initial, "scheme": scheme},
                        _scene_input(scene), 0.01))
        ag = [10.0 * np.sin(2 * np.pi * 0.01 * k) if k < 100 else 0.0 for k in range(300)]
        out.append((PT, f"tendon/{scheme}", dict(b=0.3, h=1.5, m=1000.0, P0=2e4, k_t=2e6, scheme=scheme,
                                                 tolerance=1e-8, dt_max=1e-3), ag, 0.01))
    return out


def job_file(path: Path, jobs) -> Path:
    """Write the xhost job file of ``jobs``: (library, resource URI, model description, start values, ag, dt)."""
    lines = [str(len(jobs))]
    for library, uri, md, start, ag, dt in jobs:
        vars_ = {v.name: v for v in md.modelVariables}
        outputs = [v for v in md.modelVariables if v.causality == "output"]
        lines.append(f"{library} {uri} {md.guid} {vars_['ag'].valueReference} {len(ag)} {_hex(dt)}")
        lines.append(f"{len(outputs)} " + " ".join(f"{v.type[0]} {v.valueReference}" for v in outputs))
        starts = []
        for key, value in start.items():
            v = vars_[key]
            starts.append(f"R {v.valueReference} {_hex(value)}" if v.type == "Real"
                          else f"I {v.valueReference} {int(value)}")
        lines.append(f"{len(starts)} " + " ".join(starts))
        lines.append(" ".join(_hex(a) for a in ag))
    path.write_text("\n".join(lines) + "\n")
    return path


def parse(stdout: str) -> list:
    """xhost's output: per job a list of rows (status, then the outputs: float or int)."""
    jobs = []
    for line in stdout.splitlines():
        if line.startswith("job "):
            jobs.append([])
        elif line.startswith("end"):
            assert line == "end", line
        elif line.strip():
            fields = line.split()
            jobs[-1].append([int(fields[0])] + [_real(f) if len(f) == 16 else int(f) for f in fields[1:]])
    return jobs


def _library(unzip: Path, folder: str, name: str) -> Path:
    return unzip / "binaries" / folder / (name + (".dll" if folder == "win64" else ".so"))


def run_batch(folder: str, host: Path, xfmus: dict, tmp: Path, libraries=None, env_extra=None) -> str:
    """Every scene through ``host`` with the FMUs' ``folder`` binaries (or ``libraries``: {name: path}), in one
    process: natively, under wine or under qemu-aarch64; xhost's output (every Real as its bits)."""
    wine = folder == "win64"

    def native(p: Path) -> str:
        return "Z:" + str(p).replace("/", "\\") if wine else str(p)

    jobs = []
    for name, _, start, ag, dt in scenes():
        fmu, unzip = xfmus[name]
        library = (libraries or {}).get(name) or _library(unzip, folder, name)
        uri = ("file:///Z:" if wine else "file://") + str(unzip / "resources")
        jobs.append((native(library), uri, read_model_description(str(fmu)), start, ag, dt))
    for text in (str(tmp), *(j[0] for j in jobs)):
        assert " " not in text, text                    # the job file is whitespace-separated
    path = job_file(tmp / f"jobs_{folder}.txt", jobs)
    env = {**os.environ, **(env_extra or {})}
    if wine:
        prefix = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "rocking_model" / "wine64"
        prefix.mkdir(parents=True, exist_ok=True)
        env.update(WINEPREFIX=str(prefix), WINEARCH="win64", WINEDEBUG="-all", DISPLAY="",
                   WINEDLLOVERRIDES="mscoree,mshtml=")
        cmd = [WINE, str(host), native(path)]
    elif folder == "aarch64-linux":
        cmd = [QEMU, "-L", str(SYSROOT), str(host), str(path)]
    else:
        cmd = [str(host), str(path)]
    proc = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=900, cwd=tmp)
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert len(parse(proc.stdout)) == len(jobs), proc.stderr[-3000:]
    return proc.stdout


@pytest.fixture(scope="session")
def linux64_results(xfmus, hosts, tmp_path_factory) -> str:
    return run_batch("linux64", hosts["linux64"], xfmus, tmp_path_factory.mktemp("run_linux64"))


def compare(results: str, reference: str) -> dict:
    """Check ``results`` against ``reference`` (xhost outputs; per scene: the same rows, statuses, Integer and
    Boolean outputs; phi within `TOL`); return {(model, scheme): max |dphi|}."""
    diffs = {}
    for (name, label, *_), mine, ref in zip(scenes(), parse(results), parse(reference)):
        md_outputs = OUTPUTS[name]
        assert len(mine) == len(ref), (label, len(mine), len(ref))
        a, b = np.array(mine, dtype=float), np.array(ref, dtype=float)
        for j, (out_name, out_type) in enumerate(md_outputs, start=1):
            if out_type != "Real":
                assert np.array_equal(a[:, j], b[:, j]), (name, label, out_name)
        np.testing.assert_array_equal(a[:, 0], b[:, 0], err_msg=f"{name} {label}: the statuses of fmi2DoStep")
        j = 1 + [n for n, _ in md_outputs].index("phi")
        dphi = float(np.max(np.abs(a[:, j] - b[:, j])))
        assert dphi <= TOL[name], (name, label, dphi)
        key = (name, label.split("/")[1])
        diffs[key] = max(diffs.get(key, 0.0), dphi)
    return diffs


OUTPUTS: dict = {}


@pytest.fixture(scope="session")
def outputs(xfmus):
    for name, (fmu, _) in xfmus.items():
        OUTPUTS[name] = [(v.name, v.type) for v in read_model_description(str(fmu)).modelVariables
                         if v.causality == "output"]
    return OUTPUTS


# --------------------------------------------------------------------------------------------- packaging
def test_binaries_of_every_platform_under_1_mb(xfmus):
    """Each FMU carries the binaries of linux64 and of every platform whose cross compiler is installed (the
    build's one-line summary names the Debian package of the others), and stays under 1 MB."""
    from rocking_model.fmi.build import platforms_summary, standalone_compilers

    compilers = standalone_compilers()
    expected = {f for f, cc in compilers.items() if cc}
    assert "linux64" in expected
    for name, (fmu, _) in xfmus.items():
        with zipfile.ZipFile(fmu) as zf:
            folders = {n.split("/")[1] for n in zf.namelist() if n.startswith("binaries/")}
            names = set(zf.namelist())
        assert folders == expected, (name, folders)
        for folder in folders:
            suffix = ".dll" if folder == "win64" else ".so"
            assert f"binaries/{folder}/{name}{suffix}" in names
        assert fmu.stat().st_size < 1_000_000, (name, fmu.stat().st_size)
    line = platforms_summary(compilers)
    assert "\n" not in line and all(f in line for f in expected)
    missing = platforms_summary({"linux64": "cc", "win64": None, "aarch64-linux": None})
    assert missing == ("self-contained FMUs: binaries for linux64; not for win64 (install gcc-mingw-w64-x86-64), "
                       "aarch64-linux (install gcc-aarch64-linux-gnu); sources/ for any platform")


def test_platforms_env_restricts_the_build(monkeypatch):
    from rocking_model.fmi.build import BuildError, platforms_summary, standalone_compilers

    monkeypatch.setenv("ROCKING_FMU_PLATFORMS", "linux64")
    assert list(standalone_compilers()) == ["linux64"]
    assert platforms_summary().endswith("not for win64 (ROCKING_FMU_PLATFORMS), aarch64-linux "
                                        "(ROCKING_FMU_PLATFORMS); sources/ for any platform")
    monkeypatch.setenv("ROCKING_FMU_PLATFORMS", "linux64,darwin64")
    with pytest.raises(BuildError, match="darwin64"):
        standalone_compilers()


def test_win64_dll_imports_kernel32_and_msvcrt_only(xfmus):
    need(MINGW, "x86_64-w64-mingw32-gcc", "gcc-mingw-w64-x86-64")
    objdump = shutil.which("x86_64-w64-mingw32-objdump")
    need(objdump, "x86_64-w64-mingw32-objdump", "binutils-mingw-w64-x86-64")
    for name, (_, unzip) in xfmus.items():
        text = subprocess.run([objdump, "-p", str(_library(unzip, "win64", name))], capture_output=True,
                              text=True, timeout=60).stdout
        dlls = sorted(line.split()[-1] for line in text.splitlines() if "DLL Name:" in line)
        assert dlls == ["KERNEL32.dll", "msvcrt.dll"], (name, dlls)
        exports = [line.split()[-1] for line in text[text.find("[Ordinal/Name Pointer] Table"):].splitlines()[1:]
                   if line.strip().startswith("[")]
        assert len(exports) == 34 and all(e.startswith("fmi2") for e in exports), (name, exports)


def test_aarch64_library_needs_libc_and_libm_only_and_has_no_fma(xfmus):
    need(AARCH64, "aarch64-linux-gnu-gcc", "gcc-aarch64-linux-gnu")
    for name, (_, unzip) in xfmus.items():
        so = _library(unzip, "aarch64-linux", name)
        dyn = subprocess.run(["aarch64-linux-gnu-readelf", "-d", "-h", str(so)], capture_output=True, text=True,
                             timeout=60).stdout
        assert "AArch64" in dyn
        needed = sorted(line.split("[")[1].rstrip("]") for line in dyn.splitlines() if "(NEEDED)" in line)
        assert needed == ["libc.so.6", "libm.so.6"], needed
        assert _fma_count(so) == 0


def _fma_count(binary: Path) -> int:
    text = subprocess.run(["aarch64-linux-gnu-objdump", "-d", str(binary)], capture_output=True, text=True,
                          timeout=120).stdout
    return sum(1 for line in text.splitlines() if len(line.split("\t")) > 2
               and line.split("\t")[2].split()[0] in FMA)


def test_build_description_names_libm_and_is_valid(xfmus):
    """sources/buildDescription.xml validates against the FMI 3.0 schema (fmpy's copy), names the math library
    as an external one, and needs no definition (the version is in sources/rk_version.h)."""
    from fmpy.model_description import read_build_description
    import xml.etree.ElementTree as ET

    from rocking_model import __version__

    for name, (fmu, unzip) in xfmus.items():
        configs = read_build_description(str(fmu), validate=True)
        assert [c.modelIdentifier for c in configs] == [name]
        root = ET.parse(unzip / "sources" / "buildDescription.xml").getroot()
        libs = [(e.get("name"), e.get("external")) for e in root.iter("Library")]
        assert libs == [("m", "true")]
        assert not list(root.iter("PreprocessorDefinition"))
        assert f'#define RK_ENGINE_VERSION_STRING "{__version__}"' in (unzip / "sources" / "rk_version.h").read_text()


# ----------------------------------------------------------------------------------------------- results
def test_win64_under_wine_equals_linux64(xfmus, hosts, outputs, linux64_results, tmp_path):
    need(MINGW, "x86_64-w64-mingw32-gcc", "gcc-mingw-w64-x86-64")
    need(WINE, "wine", "wine64 (and wine)")
    diffs = compare(run_batch("win64", hosts["win64"], xfmus, tmp_path), linux64_results)
    print("win64 max |dphi| vs linux64:", {f"{k[0]}/{k[1]}": v for k, v in diffs.items()})


@pytest.fixture(scope="session")
def importer_aarch64(xfmus, tmp_path_factory) -> dict:
    """The aarch64 libraries an importer builds from sources/ with nothing but GCC's defaults (GNU C, so
    -ffp-contract=fast: multiply-adds fused wherever the sources do not forbid it) at -O3 and the source files:
    {name: path}."""
    need(AARCH64, "aarch64-linux-gnu-gcc", "gcc-aarch64-linux-gnu")
    from rocking_model.fmi.build import _dependencies

    folder = tmp_path_factory.mktemp("importer_aarch64")
    objects, out = {}, {}          # an object of one FMU's sources serves the others when its inputs are the same

    def compile_(job):
        src, c, obj = job
        return subprocess.run([AARCH64, "-c", "-fPIC", "-O3", "-I.", c, "-o", str(obj)], capture_output=True,
                              text=True, cwd=src, timeout=600)

    jobs, links = [], []
    for name, (_, unzip) in xfmus.items():
        src = unzip / "sources"
        texts = {p.name: p.read_bytes() for p in src.iterdir()}
        objs = []
        for c in sorted(n for n in texts if n.endswith(".c")):
            key = b"".join(d.encode() + b"\0" + texts[d] for d in _dependencies(src, c, texts))
            if key not in objects:
                objects[key] = folder / f"{name}_{c[:-2]}.o"
                jobs.append((src, c, objects[key]))
            objs.append(str(objects[key]))
        out[name] = folder / f"{name}.so"
        links.append([AARCH64, "-shared", *objs, "-o", str(out[name]), "-lm"])
    with ThreadPoolExecutor(max_workers=os.cpu_count() or 2) as pool:
        for proc in [*pool.map(compile_, jobs)]:
            assert proc.returncode == 0, proc.stderr
    for cmd in links:
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
        assert proc.returncode == 0, proc.stderr
    return out


def test_sources_pin_the_fp_contract_on_aarch64(xfmus, importer_aarch64, tmp_path):
    """An aarch64 build of sources/ with GCC's defaults has no fused multiply-add; the same build with the
    pragmas of rk_fp.h defeated (its include guard predefined) has hundreds: the sources, not the flags, keep
    the arithmetic as written."""
    for name, so in importer_aarch64.items():
        assert _fma_count(so) == 0, name
    src = xfmus[FLEX][1] / "sources"
    obj = tmp_path / "gen.o"
    proc = subprocess.run([AARCH64, "-c", "-fPIC", "-O3", "-DRK_FP_H", "-I.", "rk_models_gen.c", "-o", str(obj)],
                          capture_output=True, text=True, cwd=src, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert _fma_count(obj) > 100


def test_aarch64_under_qemu_equals_linux64_and_an_importers_build(xfmus, hosts, outputs, linux64_results,
                                                                   importer_aarch64, tmp_path):
    """The shipped aarch64 binaries under qemu-user equal linux64 (within `TOL`, the same counts); the
    importer's build of sources/ (GCC's defaults) gives the shipped aarch64 binaries' results bit for bit."""
    need(QEMU, "qemu-aarch64-static", "qemu-user-static")
    if not (SYSROOT / "lib").is_dir():
        pytest.skip(f"no aarch64 sysroot in {SYSROOT}: install the Debian package libc6-dev-arm64-cross")
    shipped = run_batch("aarch64-linux", hosts["aarch64-linux"], xfmus, tmp_path)
    diffs = compare(shipped, linux64_results)
    print("aarch64 max |dphi| vs linux64:", {f"{k[0]}/{k[1]}": v for k, v in diffs.items()})
    rebuilt = run_batch("aarch64-linux", hosts["aarch64-linux"], xfmus, tmp_path, libraries=importer_aarch64)
    assert rebuilt == shipped                          # every output of every step, bit for bit


# ------------------------------------------------------------------------------------------ fmpy compile
def test_fmpy_compile_gives_the_shipped_binarys_bits(xfmus, hosts, outputs, linux64_results, tmp_path):
    """fmpy's `compile` (fmpy.build.build_platform_binary: CMake, Release, the modelDescription's
    <SourceFiles>, no definition, no flag of ours) of each FMU: the rebuilt library reports the package's
    version and gives the shipped linux64 binary's results bit for bit on every scene. fmpy builds FMI 2.0
    FMUs from <SourceFiles> and ignores buildDescription.xml (its library list): the rebuilt library may lack
    NEEDED libm; a host must then have libm loaded (docs/guide/fmus.md says so): here LD_PRELOAD, as documented."""
    cmake = shutil.which("cmake")
    need(cmake, "cmake", "cmake")
    from fmpy.build import build_platform_binary

    from rocking_model import __version__

    def rebuild(name):
        fmu, _ = xfmus[name]
        unzip = tmp_path / name
        with zipfile.ZipFile(fmu) as zf:
            zf.extractall(unzip)
        (tmp_path / f"build_{name}").mkdir()
        build_platform_binary(unzip, build_dir=tmp_path / f"build_{name}")
        return name, _library(unzip, "linux64", name)

    with ThreadPoolExecutor(max_workers=2) as pool:
        rebuilt = dict(pool.map(rebuild, NAMES))
    needs_libm = False
    for name, so in rebuilt.items():
        assert so.read_bytes() != _library(xfmus[name][1], "linux64", name).read_bytes()   # really rebuilt
        lib = ctypes.CDLL(str(so))                            # (this process has libm)
        lib.rk_engine_version.restype = ctypes.c_char_p
        assert lib.rk_engine_version().decode() == __version__
        needed = subprocess.run(["objdump", "-p", str(so)], capture_output=True, text=True).stdout
        needs_libm |= "libm.so" not in needed
    env = {"LD_PRELOAD": "libm.so.6"} if needs_libm else {}
    results = run_batch("linux64", hosts["linux64"], xfmus, tmp_path, libraries=rebuilt, env_extra=env)
    assert results == linux64_results                  # every output of every step, bit for bit
