"""The cffi declarations of the engine's C API that more than one cffi module reads, written once: the package's
cold-call module (`build_ffi`), the binding A/B of the benchmarks (benchmarks/ffi_binding.py) and the motion
harness of the tests (tests/c_motion.py). Each module adds its own functions to these. API mode checks every
declaration against the headers (src/rk_common.h, src/rk_motion.h) when the module compiles; ``...`` leaves a
struct's layout or an enum's other values to the compiler. The ground motion's functions are read from their
header (cffi cannot read a header itself: its macros and inline functions); the types are restated, checked by
the compiler.

The standard library only: setup.py reads this file before anything is installed."""
import re
from pathlib import Path

SRC = Path(__file__).resolve().parent / "src"


def prototypes(header: str, prefix: str) -> str:
    """The one-line declarations of the functions of ``header`` (a file of src/) whose names start with ``prefix``,
    one per line, as the header writes them."""
    text = (SRC / header).read_text(encoding="utf-8")
    found = re.findall(rf"^(?:void|int|double|rk_status) {prefix}\w+\([^;{{}}]*\);$", text, re.M)
    if not found:
        raise RuntimeError(f"no declaration of a function {prefix}* in {SRC / header}")
    return "\n".join(found) + "\n"


#: rk_common.h: the status of every fallible call and the error it fills
STATUS = r"""
typedef enum rk_status { RK_OK = 0, RK_ERR_VALUE = 1, RK_ERR_WORK_LIMIT = 2, RK_ERR_NONFINITE = 3,
                         RK_ERR_SOLVER = 4, RK_ERR_NOT_IMPLEMENTED = 5, RK_ERR_MEMORY = 6,
                         RK_ERR_INTERNAL = 7 } rk_status;
typedef struct rk_error { rk_status status; char message[512]; } rk_error;
"""

#: rk_common.h: contact sets, the scheme codes and the reports of a call
COMMON = r"""
typedef unsigned int rk_set;
typedef enum rk_scheme { RK_SCHEME_MOREAU_JEAN = 0, RK_SCHEME_EVENT_DRIVEN = 1 } rk_scheme;
typedef enum rk_report_kind { RK_REPORT_INEXACT_CONTACT = 0, RK_REPORT_FAILED_STEP = 1 } rk_report_kind;
typedef struct rk_report { rk_report_kind kind; double t; char message[512]; } rk_report;
typedef struct rk_reports { int count; rk_report items[16]; } rk_reports;
"""

#: rk_motion.h: a ground motion (its callback fields: a Python callable through ``extern "Python"`` functions
#: of the module that declares them) and its constructors and evaluations
MOTION = r"""
typedef enum rk_motion_kind { RK_MOTION_CALLBACK = 4, RK_MOTION_SCALED = 5, ... } rk_motion_kind;
typedef struct rk_motion {
    rk_motion_kind kind; double value; double factor; const struct rk_motion *inner;
    double (*fn)(void *ctx, double t, int *failed, char *msg);
    double (*fn_breakpoint)(void *ctx, double t, int *failed, char *msg);
    int (*fn_continuous)(void *ctx, double tb);
    void *ctx; int constant; unsigned long long identity; ...;
} rk_motion;
""" + prototypes("rk_motion.h", "rk_motion_")
