"""Python side of the FMU binary (fmi_binary/fmi2_cs.c): finds the slave class in the FMU's resources and
creates the slave. Copied into every FMU's resources as ``fmi2_pyhost.py``; the binary loads it under a name
unique to its contents (``_fmi2_pyhost_<sha256>``), so FMUs built by other versions can share a process.

Once the slave exists, the binary calls the slave's pythonfmu methods directly (``get_real``, ``set_real``,
``do_step``, ...); this module only serves fmi2Instantiate, fmi2Reset and fmi2FreeInstance.

The FMU's resources hold, besides the slave script and what it bundles, ``fmi2_pyhost.json`` (written by
``build_fmu.py``)::

    {"guid": "{...}", "slave_module": "RigidRockingBlock", "slave_class": "RigidRockingBlock",
     "site_packages": ["/path/of/the/build/environment/site-packages", ...]}

``site_packages`` is the fallback for an interpreter that the binary started itself (a host without Python):
those folders are appended to ``sys.path`` (after the environment variable ROCKING_FMU_SITE_PACKAGES, a
``os.pathsep``-separated list, which replaces them when set). In a Python host, ``sys.path`` is left alone:
after fmi2FreeInstance it is what it was before fmi2Instantiate.
"""
from __future__ import annotations

import hashlib
import importlib.util
import json
import os
import sys

CONFIG = "fmi2_pyhost.json"
SITE_PACKAGES_ENV = "ROCKING_FMU_SITE_PACKAGES"


def _read_config(resources: str) -> dict:
    path = os.path.join(resources, CONFIG)
    try:
        with open(path, encoding="utf-8") as f:
            config = json.load(f)
    except OSError as exc:
        raise ValueError(f"cannot read {path}: {exc}") from None
    except ValueError as exc:
        raise ValueError(f"{path} is not valid JSON: {exc}") from None
    for key in ("guid", "slave_module", "slave_class"):
        if not isinstance(config.get(key), str) or not config[key]:
            raise ValueError(f"{path}: {key!r} is missing or not a text")
    return config


def _add_site_packages(config: dict) -> None:
    """Make numpy & co. importable in an interpreter the binary started (a host without Python)."""
    env = os.environ.get(SITE_PACKAGES_ENV)
    folders = env.split(os.pathsep) if env else list(config.get("site_packages") or ())
    import site

    for folder in folders:
        if folder and folder not in sys.path and os.path.isdir(folder):
            site.addsitedir(folder)


def _rebase_packages(resources: str) -> None:
    """Repoint the packages this FMU bundles when the folder they were first imported from is gone.

    FMUs that bundle a package under the same (content-hashed) name share the imported modules; an importer
    may delete the extraction folder of one of them (fmpy.simulate_fmu does) while another instance lives on
    and imports submodules lazily through the package's __path__."""
    for entry in os.listdir(resources):
        root = os.path.join(resources, entry)
        module = sys.modules.get(entry)
        if module is None or not os.path.isfile(os.path.join(root, "__init__.py")):
            continue
        path = getattr(module, "__path__", None)
        if path is None or all(os.path.isdir(p) for p in path):
            continue
        for name, mod in list(sys.modules.items()):
            if (name == entry or name.startswith(entry + ".")) and getattr(mod, "__path__", None) is not None:
                mod.__path__[:] = [os.path.join(root, *name.split(".")[1:])]


def _load_slave_class(resources: str, config: dict):
    """The slave class, from the script in the resources, imported under a name unique to its contents."""
    script = os.path.join(resources, config["slave_module"] + ".py")
    with open(script, "rb") as f:
        digest = hashlib.sha256(f.read()).hexdigest()[:16]
    name = f"{config['slave_module']}_{digest}"
    module = sys.modules.get(name)
    if module is None:
        # the script imports what the FMU bundles next to it: resources on sys.path for the import only
        sys.path.insert(0, resources)
        try:
            spec = importlib.util.spec_from_file_location(name, script)
            module = importlib.util.module_from_spec(spec)
            sys.modules[name] = module
            try:
                spec.loader.exec_module(module)
            except BaseException:
                del sys.modules[name]
                raise
        finally:
            try:
                sys.path.remove(resources)
            except ValueError:
                pass
    cls = getattr(module, config["slave_class"], None)
    if not isinstance(cls, type):
        raise ValueError(f"{script} defines no class {config['slave_class']!r}")
    return cls


class Host:
    """One FMU instance: the slave class and the current slave (``slave``, re-created by `new_slave`)."""

    def __init__(self, resources: str, instance_name: str, guid: str, visible: bool, started_interpreter: bool):
        config = _read_config(resources)
        if guid != config["guid"]:
            raise ValueError(f"fmuGUID {guid!r} does not match the GUID of this FMU, {config['guid']!r} (the "
                             f"modelDescription.xml of another FMU or of another build?)")
        if started_interpreter:
            _add_site_packages(config)
        _rebase_packages(resources)
        self.resources = resources
        self.instance_name = instance_name
        self.visible = bool(visible)
        self.slave_class = _load_slave_class(resources, config)
        self.slave = None
        self.new_slave()

    def new_slave(self):
        """A fresh slave (start values, not initialized): fmi2Instantiate and fmi2Reset."""
        self.slave = self.slave_class(instance_name=self.instance_name, resources=self.resources,
                                      visible=self.visible)
        return self.slave

    def free(self) -> None:
        self.slave = None
