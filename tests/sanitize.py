"""Sanitized builds and fuzzing of the C core: AddressSanitizer + UndefinedBehaviorSanitizer builds
of the self-contained FMUs and of the Python extension, the FMU fault suite and the engine tests run under
them, and the libFuzzer harnesses of fuzz/ (fuzz/README.md) run for a bounded time.

Usage (from the checkout, with the virtual environment's python):

    python tests/sanitize.py build              # sanitized FMUs, the fuzz harnesses, the sanitized extension
    python tests/sanitize.py fuzz --seconds 60  # each harness for 60 s in all (split over the three models)
    python tests/sanitize.py faults [--all]     # the fault suite's standalone cases on the sanitized FMUs
    python tests/sanitize.py engine [--all]     # engine tests on the sanitized extension
    python tests/sanitize.py seeds              # rewrite fuzz/corpus/ (valid states per model and scheme)
    python tests/sanitize.py ci                 # what tests/test_sanitize.py runs: all of the above, bounded

Everything is built under --work (default: build/sanitize, gitignored), once: a step finds its products there.
The FMUs' C sources are those build_fmu.py compiles: each self-contained FMU is built by
`rocking_model.fmi.build.build_standalone`, and its own sources/ folder (the files its modelDescription lists
under <SourceFiles>, with rk_fmu_vars.h) is compiled again with clang and the sanitizers; no list of sources is
kept here. Needs clang (Debian: clang-14, with libclang-rt-14-dev for the sanitizer and libFuzzer runtimes).
"""
from __future__ import annotations

import argparse
import hashlib
import json
import os
import re
import shutil
import subprocess
import sys
import time
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
FUZZ = ROOT / "fuzz"
HARNESSES = ("state", "sequence")
#: the Debian packages this needs (named when they are missing)
PACKAGES = "clang-14 libclang-rt-14-dev"
SAN = ["-fsanitize=address,undefined", "-fno-sanitize-recover=undefined"]
#: the FMUs' own flags (build.PORTABLE_CFLAGS) but -O1 and the sanitizers; `fuzzer-no-link`: the same objects
#: serve the fuzz harnesses (coverage counters) and the sanitized FMU binaries (the ASan runtime the host
#: preloads defines the counters' hooks)
CFLAGS = ["-std=c99", "-O1", "-g", "-fno-omit-frame-pointer", "-ffp-contract=off", "-fno-fast-math", "-fPIC",
          *SAN, "-fsanitize=fuzzer-no-link"]
#: the sanitizers' settings for every process run here (CPython's own allocations are not leaks to report)
SAN_ENV = {"ASAN_OPTIONS": "detect_leaks=0:abort_on_error=1:allocator_may_return_null=1",
           "UBSAN_OPTIONS": "print_stacktrace=1:halt_on_error=1"}
#: the fault suite's cases run by `faults`: all those of the self-contained FMUs (435; about 40 s on 2 cores)
FAULT_SUBSET = "standalone"
#: the engine tests run by `engine` without --all (about a minute on one core under the sanitizers)
ENGINE_SUBSET = ["tests/test_engine_api.py", "tests/test_vertical_engine.py", "tests/test_zeno_painleve.py",
                 "tests/test_bad_input.py", "tests/test_simulator_state.py"]


def log(msg: str) -> None:
    print(f"sanitize: {msg}", flush=True)


# ---------------------------------------------------------------------------------------------- toolchain
def find_clang() -> str | None:
    """clang with the sanitizer and libFuzzer runtimes (None when either is missing)."""
    for name in (os.environ.get("SANITIZE_CC"), "clang", "clang-14", "clang-15", "clang-16"):
        cc = name and shutil.which(name)
        if cc and runtime(cc, "libclang_rt.fuzzer-x86_64.a") and runtime(cc, "libclang_rt.asan-x86_64.so"):
            return cc
    return None


def runtime(cc: str, name: str) -> str | None:
    """The path of one of clang's runtime libraries (None when not installed)."""
    try:
        out = subprocess.run([cc, f"-print-file-name={name}"], capture_output=True, text=True).stdout.strip()
    except OSError:
        return None
    if not os.path.isabs(out):   # older clang: look in its resource dir
        res = subprocess.run([cc, "-print-resource-dir"], capture_output=True, text=True).stdout.strip()
        out = os.path.join(res, "lib", "linux", name)
    return out if os.path.isfile(out) else None


def missing_reason() -> str | None:
    """Why this cannot run here (None: it can)."""
    if sys.platform != "linux":
        return "the sanitized builds run on Linux only"
    if find_clang() is None:
        return f"clang with its sanitizer and libFuzzer runtimes is missing (Debian: apt-get install {PACKAGES})"
    return None


def sanitizer_env(cc: str) -> dict:
    """The environment of a Python process that loads sanitized code: the ASan runtime preloaded."""
    return {**os.environ, **SAN_ENV, "LD_PRELOAD": runtime(cc, "libclang_rt.asan-x86_64.so")}


def _run(cmd, **kw) -> subprocess.CompletedProcess:
    proc = subprocess.run([str(c) for c in cmd], capture_output=True, text=True, **kw)
    if proc.returncode != 0:
        raise RuntimeError(f"{' '.join(map(str, cmd[:3]))} ... failed ({proc.returncode}):\n"
                           f"{(proc.stdout + proc.stderr)[-4000:]}")
    return proc


# ---------------------------------------------------------------------------------------------- builds
def _includes(path: Path, folder: Path, seen: set) -> None:
    """The local headers `path` includes, recursively (the key of its object in the cache)."""
    for name in re.findall(r'#include\s+"([^"]+)"', path.read_text(errors="replace")):
        h = folder / name
        if h.is_file() and h not in seen:
            seen.add(h)
            _includes(h, folder, seen)


def compile_objects(cc: str, folder: Path, sources: list, cache: Path, extra=()) -> list:
    """Objects of `sources` (in `folder`), cached by their text, their headers' and the flags: the engine's
    files, the same in every model's sources, compile once."""
    cache.mkdir(parents=True, exist_ok=True)
    flags = [*CFLAGS, *extra, f"-I{folder}"]
    objs, jobs = [], []
    for name in sources:
        src = folder / name
        headers: set = set()
        _includes(src, folder, headers)
        h = hashlib.sha256(" ".join(flags[:-1]).encode() + src.read_bytes())
        for p in sorted(headers):
            h.update(p.name.encode() + p.read_bytes())
        obj = cache / f"{src.stem}-{h.hexdigest()[:16]}.o"
        objs.append(obj)
        if not obj.exists():
            jobs.append(subprocess.Popen([cc, "-c", *flags, str(src), "-o", str(obj) + ".tmp"],
                                         stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True))
            jobs[-1].target = obj
        while len([j for j in jobs if j.poll() is None]) >= (os.cpu_count() or 2):
            time.sleep(0.05)
    for j in jobs:
        out = j.communicate()[0]
        if j.returncode != 0:
            raise RuntimeError(f"compiling {j.args[-3]} failed:\n{out[-4000:]}")
        os.replace(str(j.target) + ".tmp", j.target)
    return objs


def fmu_sources(fmu: Path, dest: Path) -> tuple:
    """(folder, C files, modelDescription root) of a self-contained FMU: its sources/ extracted into `dest`,
    the files its modelDescription.xml lists under <SourceFiles> (what build_fmu.py compiled)."""
    if dest.exists():
        shutil.rmtree(dest)
    with zipfile.ZipFile(fmu) as zf:
        root = ET.fromstring(zf.read("modelDescription.xml"))
        for n in zf.namelist():
            if n.startswith("sources/") and not n.endswith("/"):
                (dest / Path(n).name).parent.mkdir(parents=True, exist_ok=True)
                (dest / Path(n).name).write_bytes(zf.read(n))
    files = [f.get("name") for f in root.iter("File")]
    if not files:
        raise RuntimeError(f"{fmu.name}: its modelDescription lists no <SourceFiles>")
    return dest, files, root


def model_header(root) -> str:
    """fuzz_model.h of a modelDescription: the model's name, GUID and variables (fuzz/fuzz_fmu.h)."""
    types = {"Real": "R", "Integer": "I", "Boolean": "B", "String": "S", "Enumeration": "I"}
    caus = {"parameter": "p", "input": "i", "output": "o", "local": "l", "calculatedParameter": "c",
            "independent": "l"}
    rows = []
    for sv in root.iter("ScalarVariable"):
        kind = next(iter(sv)).tag
        rows.append(f'    {{{sv.get("valueReference")}u, \'{types[kind]}\', '
                    f'\'{caus[sv.get("causality", "local")]}\', "{sv.get("name")}"}},')
    return "\n".join([f'#define FUZZ_MODEL_NAME "{root.get("modelName")}"',
                      f'#define FUZZ_GUID "{root.get("guid")}"',
                      "static const fuzz_var FUZZ_VARS[] = {", *rows, "};", ""])


def build_fmus(work: Path, cc: str) -> dict:
    """{name: (FMU path, sanitized FMU path, fuzz harness paths)}: each self-contained FMU built by build.py,
    its sources compiled with the sanitizers into a copy of the FMU and into the fuzz harnesses."""
    sys.path.insert(0, str(ROOT))
    from rocking_model.fmi import build

    t0 = time.perf_counter()
    plain = build.build_standalone(work / "fmus")
    log(f"built the {len(plain)} self-contained FMUs with build.py ({time.perf_counter() - t0:.0f} s)")
    out = {}
    for fmu in plain:
        name = fmu.stem
        folder, files, root = fmu_sources(fmu, work / "src" / name)
        (folder / "fuzz_model.h").write_text(model_header(root))
        t0 = time.perf_counter()
        objs = compile_objects(cc, folder, [f for f in files if f.endswith(".c")], work / "obj",
                               [f'-DRK_ENGINE_VERSION_STRING="{build.__version__}-asan"'])
        # the sanitized FMU: the same zip with its binary replaced
        folder_name, suffix = build._binary_platform()
        so = work / "bin" / name / f"{name}{suffix}"
        so.parent.mkdir(parents=True, exist_ok=True)
        _run([cc, "-shared", *SAN, "-fsanitize=fuzzer-no-link", *map(str, objs), "-o", so, "-lm"])
        san = work / "sanitized" / f"{name}.fmu"
        san.parent.mkdir(parents=True, exist_ok=True)
        with zipfile.ZipFile(fmu) as src, zipfile.ZipFile(san, "w", zipfile.ZIP_DEFLATED) as dst:
            for info in src.infolist():
                data = so.read_bytes() if info.filename == f"binaries/{folder_name}/{name}{suffix}" else \
                    src.read(info.filename)
                dst.writestr(info, data)
        harnesses = {}
        for h in HARNESSES:
            exe = work / "bin" / name / f"fuzz_{h}"
            hobj = compile_objects(cc, FUZZ, [f"fuzz_{h}.c"], work / "obj" / name, [f"-I{folder}"])
            _run([cc, *SAN, "-fsanitize=fuzzer", *map(str, hobj + objs), "-o", exe, "-lm"])
            harnesses[h] = exe
        log(f"{name}: sanitized FMU and fuzz harnesses ({time.perf_counter() - t0:.0f} s)")
        out[name] = (fmu, san, harnesses)
    (work / "built.json").write_text(json.dumps({k: [str(v[0]), str(v[1]), {h: str(p) for h, p in v[2].items()}]
                                                 for k, v in out.items()}))
    return out


def built(work: Path, cc: str) -> dict:
    meta = work / "built.json"
    if not meta.exists():
        return build_fmus(work, cc)
    return {k: (Path(v[0]), Path(v[1]), {h: Path(p) for h, p in v[2].items()})
            for k, v in json.loads(meta.read_text()).items()}


def build_extension(work: Path, cc: str) -> Path:
    """The package with its two extension modules (rocking_model._engine, rocking_model._rk) built by setup.py
    with clang and the sanitizers (CC, CFLAGS, LDSHARED), unpacked from its wheel into work/ext (put it first on
    PYTHONPATH)."""
    lib = work / "ext"
    h = hashlib.sha256()
    for p in sorted((ROOT / "rocking_model" / "engine").rglob("*")) + [ROOT / "setup.py"]:
        if p.is_file() and p.suffix in (".c", ".h", ".py") and "__pycache__" not in p.parts:
            h.update(p.name.encode() + p.read_bytes())
    stamp = lib / "sources.sha256"
    if stamp.is_file() and stamp.read_text() == h.hexdigest():
        return lib                        # built from these sources already
    t0 = time.perf_counter()
    flags = " ".join(["-O1", "-g", "-fno-omit-frame-pointer", *SAN])
    env = {**os.environ, "CC": cc, "CFLAGS": flags, "LDSHARED": f"{cc} -shared {flags}", "LDFLAGS": ""}
    # a wheel built by pip (setup.py with the build requirements of pyproject.toml, in isolation), unpacked
    wheels = work / "wheel"
    shutil.rmtree(wheels, ignore_errors=True)
    _run([sys.executable, "-m", "pip", "wheel", "-q", "--no-deps", "--disable-pip-version-check", "-w", wheels,
          ROOT], cwd=ROOT, env=env)
    shutil.rmtree(lib, ignore_errors=True)
    with zipfile.ZipFile(next(wheels.glob("*.whl"))) as zf:
        zf.extractall(lib)
    stamp.write_text(h.hexdigest())
    log(f"sanitized extension built with setup.py in {lib} ({time.perf_counter() - t0:.0f} s)")
    return lib


# ---------------------------------------------------------------------------------------------- corpus
def _state_seeds(fmu: Path) -> list:
    """Valid serialized states of a (plain) self-contained FMU: per scheme, before initialization, after it,
    and after steps of a pulse (with impacts), each with the mode byte of fuzz_state.c (signed, and the phase
    it is read in)."""
    import fmpy
    from fmpy.fmi2 import FMU2Slave

    md = fmpy.read_model_description(str(fmu))
    unzip = fmpy.extract(str(fmu))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    seeds = []
    for scheme in (0, 1):
        s = FMU2Slave(guid=md.guid, unzipDirectory=unzip, modelIdentifier=md.coSimulation.modelIdentifier,
                      instanceName="seed")
        s.instantiate()

        def save(tag):
            st = s.getFMUstate()
            seeds.append((f"scheme{scheme}_{tag}", bytes(s.serializeFMUstate(st))))
            s.freeFMUstate(st)

        save("instantiated")
        if "scheme" in vr:
            s.setInteger([vr["scheme"]], [scheme])
        s.setupExperiment(startTime=0.0)
        s.enterInitializationMode()
        s.exitInitializationMode()
        save("initialized")
        t, h = 0.0, 0.01
        for k in range(150):
            if "ag" in vr:
                s.setReal([vr["ag"]], [4.0 if 0.1 <= t < 0.6 else 0.0])
            s.doStep(t, h)
            t += h
            if k in (30, 149):
                save(f"t{t:.2f}")
        s.terminate()
        s.freeInstance()
    return seeds


def _sequence_seeds(md_root) -> dict:
    """A few programs for fuzz_sequence.c (its opcodes): initialize and step, a pulse through the input,
    states saved / restored / serialized, reset, terminate."""
    reals = [int(sv.get("valueReference")) for sv in md_root.iter("ScalarVariable") if next(iter(sv)).tag == "Real"]
    names = {sv.get("name"): reals.index(int(sv.get("valueReference"))) for sv in md_root.iter("ScalarVariable")
             if next(iter(sv)).tag == "Real"}
    ag = names.get("ag", 0)

    def set_ag(x16):  # SetReal, one value, ref index, small decimal x16 / 16
        return bytes([0, 0, ag, 4, x16 & 0xFF])

    init, step, get_all, reset, term = bytes([4, 0]), bytes([5, 0]), bytes([8]), bytes([7]), bytes([12])
    return {
        "init_steps": init + step * 6 + get_all,
        "pulse": init + set_ag(64) + step * 10 + set_ag(0) + step * 10 + get_all,
        "states": init + bytes([11, 0]) + set_ag(48) + step * 8 + bytes([11, 6, 11, 2]) + get_all + step * 3,
        "reset": init + set_ag(80) + step * 5 + reset + init + step * 2 + get_all + term,
        "bad_values": init + bytes([0, 0, ag, 0]) + bytes([0, 0, ag, 1]) + step + bytes([5, 1, 1]) + get_all,
    }


def write_seeds(work: Path, cc: str, dest: Path) -> None:
    """The seed corpus: dest/state/<model>/..., dest/sequence/..."""
    for name, (fmu, _, _) in built(work, cc).items():
        d = dest / "state" / name
        d.mkdir(parents=True, exist_ok=True)
        for tag, data in _state_seeds(fmu):
            phase = 0 if "instantiated" in tag else 1
            (d / tag).write_bytes(bytes([1 | phase << 1]) + data)
        with zipfile.ZipFile(fmu) as zf:
            root = ET.fromstring(zf.read("modelDescription.xml"))
        d = dest / "sequence"
        d.mkdir(parents=True, exist_ok=True)
        for tag, data in _sequence_seeds(root).items():
            (d / f"{tag}_{name}").write_bytes(data)
    log(f"seed corpus written to {dest}")


# ---------------------------------------------------------------------------------------------- runs
_STAT = re.compile(r"#(\d+)\s+(?:DONE|pulse|INITED|NEW|REDUCE)\s+cov: (\d+) ft: (\d+)")


def fuzz(work: Path, cc: str, seconds: float, only=None) -> dict:
    """Each harness on each model for `seconds` / (number of models), from the committed seeds (plus fresh
    ones: the GUID in a committed state changes with the sources; the harness signs states anyway). Returns
    {harness: {model: {"execs", "cov", "ft", "crash"}}}; a crash is kept under work/crashes."""
    models = built(work, cc)
    per = max(1, int(round(seconds / len(models))))
    fresh = work / "seeds"
    if not fresh.exists():
        write_seeds(work, cc, fresh)
    report: dict = {}
    for h in HARNESSES:
        if only and h not in only:
            continue
        for name, (_, _, exes) in models.items():
            corpus = work / "corpus" / h / name
            corpus.mkdir(parents=True, exist_ok=True)
            seeds = [FUZZ / "corpus" / h / name, fresh / h / name] if h == "state" else \
                [FUZZ / "corpus" / h, fresh / h]
            if h == "state":
                seeds.append(FUZZ / "regressions" / name)
            crashes = work / "crashes" / h / name
            crashes.mkdir(parents=True, exist_ok=True)
            cmd = [exes[h], f"-max_total_time={per}", "-timeout=10", "-rss_limit_mb=2048", "-max_len=8192",
                   "-print_final_stats=1", f"-artifact_prefix={crashes}/", str(corpus),
                   *[str(s) for s in seeds if s.is_dir()]]
            t0 = time.perf_counter()
            proc = subprocess.run([str(c) for c in cmd], capture_output=True, text=True,
                                  env={**os.environ, **SAN_ENV}, cwd=work)
            stats = _STAT.findall(proc.stderr)
            execs, cov, ft = (int(x) for x in stats[-1]) if stats else (0, 0, 0)
            m = re.search(r"stat::number_of_executed_units:\s*(\d+)", proc.stderr)
            execs = int(m.group(1)) if m else execs
            crash = None
            if proc.returncode != 0:
                crash = proc.stderr[-6000:]
                (crashes / "log.txt").write_text(proc.stderr)
            report.setdefault(h, {})[name] = {"execs": execs, "cov": cov, "ft": ft, "seconds":
                                              round(time.perf_counter() - t0, 1), "crash": crash}
            log(f"fuzz_{h} {name}: {execs} executions in {per} s, cov: {cov} ft: {ft}"
                + ("" if crash is None else f"; FAILED (exit {proc.returncode}), see {crashes}/log.txt"))
    return report


def run_regressions(work: Path, cc: str) -> None:
    """The committed reproducers (fuzz/regressions/<model>/*) through the state harness once each."""
    for name, (_, _, exes) in built(work, cc).items():
        folder = FUZZ / "regressions" / name
        files = sorted(folder.glob("*")) if folder.is_dir() else []
        if files:
            _run([exes["state"], "-runs=1", *map(str, files)], env={**os.environ, **SAN_ENV})
            log(f"{name}: {len(files)} regression input(s) pass under ASan/UBSan")


def faults(work: Path, cc: str, everything: bool = False, extra=()) -> int:
    """The fault suite's standalone cases on the sanitized FMUs (tests/test_fault_suite.py): the harness'
    processes get the ASan runtime preloaded and the FMUs from ROCKING_STANDALONE_FMUS."""
    built(work, cc)
    env = sanitizer_env(cc)
    env["ROCKING_STANDALONE_FMUS"] = str(work / "sanitized")
    env["FAULT_SUITE_JOBS"] = env.get("FAULT_SUITE_JOBS", "2")
    cmd = [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "tests/test_fault_suite.py",
           "-k", "standalone" if everything else FAULT_SUBSET, *extra]
    log("running " + " ".join(cmd[2:]) + " on the sanitized FMUs")
    return subprocess.run(cmd, cwd=ROOT, env=env).returncode


def engine(work: Path, cc: str, everything: bool = False, extra=()) -> int:
    """Engine tests with the sanitized extension first on sys.path (its package copy in work/ext)."""
    lib = build_extension(work, cc)
    env = sanitizer_env(cc)
    env["PYTHONPATH"] = os.pathsep.join([str(lib), env.get("PYTHONPATH", "")]).rstrip(os.pathsep)
    probe = subprocess.run([sys.executable, "-c", "import rocking_model._engine as e; print(e.__file__)"],
                           cwd=work, env=env, capture_output=True, text=True)
    if str(lib) not in probe.stdout:
        raise RuntimeError(f"the sanitized extension is not the one imported: {probe.stdout}{probe.stderr}")
    tests = ["tests"] if everything else ENGINE_SUBSET
    cmd = [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", *tests, *extra]
    log("running " + " ".join(cmd[2:]) + " on the sanitized extension")
    return subprocess.run(cmd, cwd=ROOT, env=env).returncode


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("what", choices=["build", "fuzz", "faults", "engine", "seeds", "ci"])
    p.add_argument("--work", default=str(ROOT / "build" / "sanitize"), help="build folder (default build/sanitize)")
    p.add_argument("--seconds", type=float, default=60.0, help="fuzz: seconds per harness (over all models)")
    p.add_argument("--harness", action="append", choices=HARNESSES, help="fuzz: only this harness")
    p.add_argument("--all", action="store_true", help="faults / engine: every case / the whole test suite")
    p.add_argument("--report", help="write the fuzz report (JSON) here")
    args, extra = p.parse_known_args(argv)
    why = missing_reason()
    if why:
        print(f"sanitize: cannot run: {why}", file=sys.stderr)
        return 2
    cc, work = find_clang(), Path(args.work).resolve()
    work.mkdir(parents=True, exist_ok=True)
    if args.what == "build":
        build_fmus(work, cc)
        build_extension(work, cc)
        return 0
    if args.what == "seeds":
        write_seeds(work, cc, FUZZ / "corpus")
        return 0
    if args.what == "faults":
        return faults(work, cc, args.all, extra)
    if args.what == "engine":
        return engine(work, cc, args.all, extra)
    if args.what in ("fuzz", "ci"):
        if args.what == "ci":
            build_fmus(work, cc)          # from the sources as they are now (unchanged objects are cached)
            run_regressions(work, cc)
        report = fuzz(work, cc, args.seconds, args.harness)
        if args.report:
            Path(args.report).write_text(json.dumps(report, indent=1))
        if any(r["crash"] for per in report.values() for r in per.values()):
            return 1
        if args.what == "fuzz":
            return 0
    rc_faults = faults(work, cc)
    rc_engine = engine(work, cc)
    return 1 if rc_faults or rc_engine else 0


if __name__ == "__main__":
    sys.exit(main())
