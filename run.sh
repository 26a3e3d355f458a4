#!/usr/bin/env bash
# Set-up and entry points. Usage:
#   bash run.sh demo   # create .venv, install, build the FMUs into dist/, run the demo scene through fmpy
#   bash run.sh test   # create .venv, install with test extras, run the whole test suite
#   bash run.sh docs   # create .venv, install with the docs extras, build the documentation site into site/
# Each phase prints one line first (the install is silent; on a first run it downloads and compiles, which takes a while).
set -euo pipefail
cd "$(dirname "$0")"
PY=${PYTHON:-python3}
VENV=${VENV:-.venv}

say() { echo "run.sh: $*"; }

setup() {
    if [ ! -x "$VENV/bin/python" ]; then
        say "creating the virtual environment $VENV"
        "$PY" -m venv "$VENV"
    fi
    say "installing rocking_model[$1] and its dependencies into $VENV (pip; silent, a while on a first run)"
    "$VENV/bin/python" -m pip install -q --disable-pip-version-check --upgrade pip >/dev/null
    "$VENV/bin/python" -m pip install -q --disable-pip-version-check -e ".[$1]"
}

# Ecos' library (the 'ecos' extra, tests/test_ecos.py) needs Debian's libtbb12: installed here when it is
# missing and this is a root shell with apt-get; otherwise (or if apt-get fails) the Ecos tests skip.
libtbb() {
    if ldconfig -p 2>/dev/null | grep -q 'libtbb\.so\.12'; then return 0; fi
    if command -v apt-get >/dev/null 2>&1 && [ "$(id -u)" = 0 ]; then
        say "installing libtbb12 for Ecos (apt-get)"
        { apt-get install -y -q libtbb12 || { apt-get update -q && apt-get install -y -q libtbb12; }; } \
            >/dev/null 2>&1 || say "apt-get could not install libtbb12: the Ecos tests will skip"
    else
        say "libtbb12 is missing (not root or no apt-get): the Ecos tests will skip"
    fi
}

# The sanitized builds and the fuzz harnesses (tests/test_sanitize.py, tests/sanitize.py) need clang with its
# sanitizer and libFuzzer runtimes: Debian's clang-14 and libclang-rt-14-dev, installed the same way; without
# them those tests skip naming the packages.
sanitizers() {
    if command -v clang-14 >/dev/null 2>&1 && [ -e "$(clang-14 -print-file-name=libclang_rt.fuzzer-x86_64.a)" ]; then
        return 0
    fi
    if command -v apt-get >/dev/null 2>&1 && [ "$(id -u)" = 0 ]; then
        say "installing clang-14 and libclang-rt-14-dev for the sanitized builds and fuzzing (apt-get)"
        { apt-get install -y -q clang-14 libclang-rt-14-dev || { apt-get update -q && apt-get install -y -q clang-14 libclang-rt-14-dev; }; } \
            >/dev/null 2>&1 || say "apt-get could not install clang-14 libclang-rt-14-dev: the sanitizer tests will skip"
    else
        say "clang-14 / libclang-rt-14-dev are missing (not root or no apt-get): the sanitizer tests will skip"
    fi
}

# The cross-platform tests (tests/test_cross_platform.py) build the self-contained FMUs' win64 and aarch64-linux
# binaries and run them under wine and qemu-user, and rebuild the FMUs with fmpy's compile (CMake): Debian's
# cross compilers, wine, qemu-user-static and cmake are installed here when missing and this is a root shell
# with apt-get (one line of output); otherwise (or if apt-get fails) those tests skip, naming the package.
cross_tools() {
    local pkgs=()
    command -v x86_64-w64-mingw32-gcc >/dev/null 2>&1 || pkgs+=(gcc-mingw-w64-x86-64)
    { command -v aarch64-linux-gnu-gcc >/dev/null 2>&1 && [ -d /usr/aarch64-linux-gnu/lib ]; } \
        || pkgs+=(gcc-aarch64-linux-gnu libc6-dev-arm64-cross)
    { command -v wine >/dev/null 2>&1 || command -v wine64 >/dev/null 2>&1; } || pkgs+=(wine64 wine)
    { command -v qemu-aarch64-static >/dev/null 2>&1 || command -v qemu-aarch64 >/dev/null 2>&1; } \
        || pkgs+=(qemu-user-static)
    command -v cmake >/dev/null 2>&1 || pkgs+=(cmake)
    [ "${#pkgs[@]}" -eq 0 ] && return 0
    if command -v apt-get >/dev/null 2>&1 && [ "$(id -u)" = 0 ]; then
        say "installing ${pkgs[*]} for the cross-platform tests (apt-get; a few minutes on a first run)"
        local install=(env DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends "${pkgs[@]}")
        { "${install[@]}" || { apt-get update -q && "${install[@]}"; }; } >/dev/null 2>&1 \
            || say "apt-get could not install ${pkgs[*]}: the cross-platform tests will skip"
    else
        say "${pkgs[*]} missing (not root or no apt-get): the cross-platform tests will skip"
    fi
}

# The site's browser test (tests/test_doc_site.py) opens the built documentation in Debian's chromium (driven by
# playwright, no browser download): installed here when missing and this is a root shell with apt-get; otherwise
# (or if apt-get fails) that test skips, naming the package.
browser() {
    command -v chromium >/dev/null 2>&1 && return 0
    if command -v apt-get >/dev/null 2>&1 && [ "$(id -u)" = 0 ]; then
        say "installing chromium for the documentation site's browser test (apt-get)"
        local install=(env DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends chromium)
        { "${install[@]}" || { apt-get update -q && "${install[@]}"; }; } >/dev/null 2>&1 \
            || say "apt-get could not install chromium: the browser test of the site will skip"
    else
        say "chromium missing (not root or no apt-get): the browser test of the site will skip"
    fi
}

case "${1:-}" in
    demo)
        setup plot
        say "building and validating the FMUs into dist/ (build_fmu.py)"
        "$VENV/bin/python" build_fmu.py
        say "running the demo scene through fmpy (examples/demo.py)"
        "$VENV/bin/python" examples/demo.py
        ;;
    test)
        setup test,ecos,docs
        libtbb
        sanitizers
        cross_tools
        browser
        shift
        say "running the tests (pytest $*)"
        "$VENV/bin/python" -m pytest "$@"
        ;;
    docs)
        setup docs,plot
        say "building the documentation site into site/ (mkdocs build --strict; the gallery runs examples/)"
        "$VENV/bin/python" -m mkdocs build --strict --site-dir site "${@:2}"
        say "open site/index.html"
        ;;
    *)
        echo "usage: bash run.sh demo|test|docs [pytest args]" >&2
        exit 2
        ;;
esac
