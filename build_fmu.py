"""Build every FMU into <dest>/<Name>.fmu (and the models' self-contained FMUs into <dest>/standalone) and
validate them with fmpy; write their cross-check folders into <dest>/cross-check.

Usage:  python build_fmu.py [--dest dist] [--no-cross-check] [Name ...]

The checkout's entry point of `rocking_model.fmi.build`, which does the work (the installed package's
``rocking build-fmu`` runs the same code); here the default destination is the checkout's dist/. Its names
(``build_all``, ``build_standalone``, ``CROSS_CHECK``, ...) are importable from this module too.
"""
import sys
from pathlib import Path

from rocking_model.fmi.build import *  # noqa: F401,F403  (the importable names of the build)
from rocking_model.fmi.build import main as _main

ROOT = Path(__file__).resolve().parent

if __name__ == "__main__":
    sys.exit(_main(default_dest=ROOT / "dist"))
