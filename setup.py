"""Build of the compiled engine (issue 21): the extension module rocking_model._engine from the C99 sources
in rocking_model/engine/src (every *.c there: the parts add their files without touching this one) and the
module glue rocking_model/engine/_engine.c. Everything else is declared in pyproject.toml.

Flags: portable (-std=c99 -O2, no -march=native) and -ffp-contract=off, so that the compiler does not fuse
a*b + c into an FMA: the C engine must round like the Python reference (rocking_model/engine/DESIGN.md,
"Numerics"). MSVC: /fp:precise (its default) and no contraction flags."""
import glob
import os
import re
import sys

from setuptools import Extension, setup

HERE = os.path.dirname(os.path.abspath(__file__))


def package_version() -> str:
    """rocking_model.__version__, read without importing the package (numpy is not in the build env)."""
    with open(os.path.join(HERE, "rocking_model", "__init__.py"), encoding="utf-8") as fh:
        match = re.search(r'^__version__\s*=\s*["\']([^"\']+)["\']', fh.read(), re.M)
    return match.group(1) if match else "unknown"


SOURCES = sorted(glob.glob(os.path.join("rocking_model", "engine", "src", "*.c")))
if sys.platform == "win32":
    CFLAGS = ["/O2", "/fp:precise"]
    LIBS = []
else:
    CFLAGS = ["-std=c99", "-O2", "-ffp-contract=off", "-fno-fast-math"]
    LIBS = ["m"]

setup(
    ext_modules=[
        Extension(
            "rocking_model._engine",
            sources=SOURCES + [os.path.join("rocking_model", "engine", "_engine.c")],
            include_dirs=[os.path.join("rocking_model", "engine")],
            define_macros=[("RK_ENGINE_VERSION_STRING", '"%s"' % package_version())],
            extra_compile_args=CFLAGS,
            libraries=LIBS,
        )
    ],
)
