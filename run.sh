#!/usr/bin/env bash
# Set-up and entry points. Usage:
#   bash run.sh demo   # create .venv, install, build the FMUs into dist/, run the demo scene through fmpy
#   bash run.sh test   # create .venv, install with test extras, run the whole test suite
set -euo pipefail
cd "$(dirname "$0")"
PY=${PYTHON:-python3}
VENV=${VENV:-.venv}

setup() {
    if [ ! -x "$VENV/bin/python" ]; then
        "$PY" -m venv "$VENV"
    fi
    "$VENV/bin/python" -m pip install -q --disable-pip-version-check --upgrade pip >/dev/null
    "$VENV/bin/python" -m pip install -q --disable-pip-version-check -e ".[$1]"
}

case "${1:-}" in
    demo)
        setup plot
        "$VENV/bin/python" build_fmu.py
        "$VENV/bin/python" examples/demo.py
        ;;
    test)
        setup test
        shift
        "$VENV/bin/python" -m pytest "$@"
        ;;
    *)
        echo "usage: bash run.sh demo|test [pytest args]" >&2
        exit 2
        ;;
esac
