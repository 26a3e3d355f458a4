"""FMI 2.0 co-simulation FMU PostTensionedRockingBlock: its slave class is `rocking_model.fmi.fmus.PostTensionedRockingBlock`.

Written by rocking_model.fmi.build.fmu_script; build with ``rocking build-fmu`` or ``python build_fmu.py``.
The module is named like the FMU on purpose: pythonfmu and the FMU binary import the slave class from it, and
two FMUs whose scripts share a module name cannot be loaded in the same process.
"""
from rocking_model.fmi.fmus import PostTensionedRockingBlock
