"""Build of the compiled engine: the extension module rocking_model._engine from the C99 sources
in rocking_model/engine/src (every *.c there) and the module glue rocking_model/engine/_engine.c. Everything else is declared in pyproject.toml.

Flags: portable (-std=c99 -O3, no -march=native) and -ffp-contract=off, so that the compiler does not fuse
a*b + c into an FMA: the results must not depend on the compiler's choice of contraction (the goldens are
recorded bit for bit; rocking_model/engine/DESIGN.md, "Numerics"). -O3 rather than -O2: 6 % fewer instructions per run on the benchmark's pulse scene, the same bits
(without -ffast-math the compiler may not reassociate, so its vector code computes what the scalar code does).
-fvisibility=hidden: the engine's functions are called directly rather than through the PLT (the module exports
PyInit__engine alone, as the self-contained FMU's binary exports the fmi2 functions alone): 1 % fewer
instructions on the record. MSVC: /fp:precise (its default) and no contraction flags."""
import glob
import os
import re
import runpy
import sys

from setuptools import Extension, setup

HERE = os.path.dirname(os.path.abspath(__file__))


def package_version() -> str:
    """rocking_model.__version__, read without importing the package (numpy is not in the build env)."""
    with open(os.path.join(HERE, "rocking_model", "__init__.py"), encoding="utf-8") as fh:
        match = re.search(r'^__version__\s*=\s*["\']([^"\']+)["\']', fh.read(), re.M)
    return match.group(1) if match else "unknown"


# generated sources: rocking_model/engine/gen_rk.py writes src/rk_tableaux.h from the tableaux of
# rocking_model/engine/tableaux.py (read with ast: no numpy in the build environment)
GENERATOR = os.path.join(HERE, "rocking_model", "engine", "gen_rk.py")
if os.path.exists(GENERATOR):
    runpy.run_path(GENERATOR, run_name="__main__")

# the model kernels: rocking_model/engine/gen_models.py writes src/rk_models_gen.c from the models' declarations
# (sympy, at build time; the file is rewritten only when a declaration or the generator changed)
# main() rather than run_name="__main__": the script's command line takes sys.argv[1] as the output path, and
# here that is setuptools' command (egg_info, bdist_wheel, ...)
sys.path.insert(0, HERE)
runpy.run_path(os.path.join(HERE, "rocking_model", "engine", "gen_models.py"))["main"]()

SOURCES = sorted(glob.glob(os.path.join("rocking_model", "engine", "src", "*.c")))
if sys.platform == "win32":
    CFLAGS = ["/O2", "/fp:precise"]
    LIBS = []
else:
    CFLAGS = ["-std=c99", "-O3", "-ffp-contract=off", "-fno-fast-math", "-fvisibility=hidden"]
    LIBS = ["m"]

# the engine's cold calls bound with cffi (rocking_model._rk): no engine code of its own, it calls the engine of the
# extension below (rocking_model/engine/build_ffi.py)
sys.path.insert(0, os.path.join(HERE, "rocking_model", "engine"))
from build_ffi import builder  # noqa: E402

COLD = builder(include_dirs=[os.path.join("rocking_model", "engine")], extra_compile_args=CFLAGS) \
    .distutils_extension(tmpdir=os.path.join("build", "cffi"), verbose=False)
COLD.depends = [os.path.join("rocking_model", "engine", "rk_py_api.h")]

setup(
    ext_modules=[
        COLD,
        Extension(
            "rocking_model._engine",
            sources=SOURCES + [os.path.join("rocking_model", "engine", "_engine.c")],
            include_dirs=[os.path.join("rocking_model", "engine")],
            define_macros=[("RK_ENGINE_VERSION_STRING", '"%s"' % package_version())],
            depends=sorted(glob.glob(os.path.join("rocking_model", "engine", "src", "*.h")))
            + [os.path.join("rocking_model", "engine", "rk_py_api.h")],
            extra_compile_args=CFLAGS,
            libraries=LIBS,
        )
    ],
)
