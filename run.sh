#!/usr/bin/env bash
# Set-up and entry points. Usage:
#   bash run.sh demo   # create .venv, install, build the FMUs into dist/, run the demo scene through fmpy
#   bash run.sh test   # create .venv, install with test extras, run the whole test suite
# Each phase prints one line first (the install is silent and takes about 40 s on a first run).
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
    say "installing rocking_model[$1] and its dependencies into $VENV (pip; about 40 s on a first run)"
    "$VENV/bin/python" -m pip install -q --disable-pip-version-check --upgrade pip >/dev/null
    "$VENV/bin/python" -m pip install -q --disable-pip-version-check -e ".[$1]"
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
        setup test
        shift
        say "running the tests (pytest $*)"
        "$VENV/bin/python" -m pytest "$@"
        ;;
    *)
        echo "usage: bash run.sh demo|test [pytest args]" >&2
        exit 2
        ;;
esac
