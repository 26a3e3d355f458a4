"""Models declared after the build: their kernels generated and compiled on first use, then added to the engine.

The models of the package are compiled into the extension module at build time (gen_models.py). A model
declared elsewhere (a subclass of `RockingModel` with its own ``kind`` and ``mechanics``, registered with
`rocking_model.models.register_model`) reaches the same engine through this module: the first time it is
simulated, its kernels are generated from its declaration (sympy), compiled with the engine's own sources and
flags by the system C compiler into a library of its own, and that library's kernel table is added to the
engine (`rocking_model._engine.add_model`). The library is cached by the hash of everything it is built from
(``ROCKING_MODEL_CACHE`` or ``~/.cache/rocking_model``): later runs load it without sympy or a compiler.
"""
from __future__ import annotations

import ctypes
import hashlib
import os
import shlex
import subprocess
import sys
import sysconfig
import tempfile
from pathlib import Path

SRC = Path(__file__).resolve().parent / "src"
#: the engine's flags (setup.py): portable, no contraction of a*b + c into an FMA
CFLAGS = ["-std=c99", "-O3", "-ffp-contract=off", "-fno-fast-math", "-fvisibility=hidden", "-fPIC", "-shared"]

EXPORT = """
#if defined(_WIN32)
#define RK_EXPORT __declspec(dllexport)
#else
#define RK_EXPORT __attribute__((visibility("default")))
#endif
RK_EXPORT const rk_model_ops *rk_plugin_ops(void)
{
    return rk_generated_models[0];
}
"""

#: model class -> its loaded library (kept: the engines of that kind call into it)
_LOADED: dict = {}
#: the kinds compiled into the extension ("'rigid', 'flexible'"), read before any is added
_BUILT_IN = None


def cache_dir() -> Path:
    """Where compiled model libraries are kept."""
    root = os.environ.get("ROCKING_MODEL_CACHE")
    if root:
        return Path(root)
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "rocking_model" / "models"


def _compiler() -> list:
    cc = os.environ.get("CC") or sysconfig.get_config_var("CC") or "cc"
    return shlex.split(cc)[:1]


def _engine_sources() -> list:
    return sorted(p for p in SRC.glob("*.c") if p.name != "rk_models_gen.c")


def source_of(cls, export: bool = True) -> str:
    """The C of the model's kernels (generated from its declaration), with the library's export."""
    from . import gen_models
    return gen_models.generate([cls]) + (EXPORT if export else "")


def built_in(cls) -> bool:
    """Whether ``cls``'s kernels are compiled into the extension (a model of the package)."""
    from .. import _engine
    global _BUILT_IN
    if _BUILT_IN is None:
        _BUILT_IN = _engine.kinds()
    return f"'{cls.kind}'" in _BUILT_IN and cls not in _LOADED


def build(cls, dest: Path | None = None) -> Path:
    """The compiled library of ``cls``'s kernels (built if not cached); RuntimeError naming the compiler's
    message if it fails."""
    text = source_of(cls)
    digest = hashlib.sha256(text.encode())
    for p in _engine_sources() + sorted(SRC.glob("*.h")):
        digest.update(p.read_bytes())
    digest.update(" ".join(_compiler() + CFLAGS).encode())
    suffix = ".dll" if sys.platform == "win32" else ".so"
    dest = Path(dest) if dest is not None else cache_dir()
    lib = dest / f"rk_model_{cls.kind}_{digest.hexdigest()[:16]}{suffix}"
    if lib.is_file():
        return lib
    dest.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(dir=dest) as tmp:
        gen = Path(tmp) / "rk_models_gen.c"
        gen.write_text(text, encoding="utf-8")
        out = Path(tmp) / lib.name
        cmd = _compiler() + CFLAGS + ["-I", str(SRC), "-o", str(out), str(gen)] + [str(p) for p in _engine_sources()] \
            + ["-lm"]
        try:
            run = subprocess.run(cmd, capture_output=True, text=True)
        except OSError as exc:
            raise RuntimeError(f"model {cls.kind!r}: no C compiler to build its kernels ({cmd[0]}: {exc}); "
                               "install one (gcc or clang) or set CC") from None
        if run.returncode != 0:
            raise RuntimeError(f"model {cls.kind!r}: its generated kernels did not compile:\n{run.stderr[-2000:]}")
        os.replace(out, lib)          # atomic: a concurrent build of the same library writes the same bytes
    return lib


def ensure(cls) -> None:
    """Make the engine know ``cls``'s kind: built in, already added, or generated, compiled and added now."""
    from .. import _engine

    if cls in _LOADED or built_in(cls):
        return
    if not hasattr(cls, "mechanics"):
        raise ValueError(f"model {cls.__name__} declares no mechanics(): the engine cannot run it "
                         "(rocking_model.models.declare)")
    handle = ctypes.CDLL(str(build(cls)))
    get = handle.rk_plugin_ops
    get.restype = ctypes.c_void_p
    _engine.add_model(get())
    _LOADED[cls] = handle
