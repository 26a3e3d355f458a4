"""Python side of the FMU binary (fmi2_cs.c, next to it): finds the slave class in the FMU's resources and
creates the slave. Copied into every FMU's resources as ``fmi2_pyhost.py``; the binary loads it under a name
unique to its contents (``_fmi2_pyhost_<sha256>``), so FMUs built by other versions can share a process.

Once the slave exists, the binary calls the slave's pythonfmu methods directly (``get_real``, ``set_real``,
``do_step``, ...); this module only serves fmi2Instantiate, fmi2Reset and fmi2FreeInstance.

The FMU's resources hold, besides the slave script and what it bundles, ``fmi2_pyhost.json`` (written by
``rocking_model/fmi/build.py``)::

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


def _bundled_packages(resources: str) -> list:
    """The packages the FMU bundles next to its script (folders of the resources with an __init__.py)."""
    return sorted(entry for entry in os.listdir(resources)
                  if os.path.isfile(os.path.join(resources, entry, "__init__.py")) and entry.isidentifier())


def _import_bundled(resources: str, packages: list) -> bool:
    """Import the bundled packages (resources on sys.path for this only) or, when they are imported already,
    repoint them at this FMU's resources if the folder they came from is gone.

    FMUs that bundle a package under the same (content-hashed) name share the imported modules; an importer
    may delete the extraction folder of one of them (fmpy.simulate_fmu does) while another instance lives on
    and imports submodules lazily through the package's __path__. A host may also drop the modules from
    sys.modules (a build in the same process does): then they are imported again from here, and True is
    returned (the slave script must then be executed again, against the new modules)."""
    fresh = False
    for package in packages:
        module = sys.modules.get(package)
        root = os.path.join(resources, package)
        if module is None:
            importlib.import_module(package)
            fresh = True
            continue
        path = getattr(module, "__path__", None)
        if path is None or all(os.path.isdir(p) for p in path):
            continue
        for name, mod in list(sys.modules.items()):
            if (name == package or name.startswith(package + ".")) and getattr(mod, "__path__", None) is not None:
                mod.__path__[:] = [os.path.join(root, *name.split(".")[1:])]
    return fresh


def _load_slave_class(resources: str, config: dict):
    """The slave class, from the script in the resources, imported under a name unique to its contents."""
    script = os.path.join(resources, config["slave_module"] + ".py")
    with open(script, "rb") as f:
        digest = hashlib.sha256(f.read()).hexdigest()[:16]
    name = f"{config['slave_module']}_{digest}"
    # the script imports what the FMU bundles next to it: resources on sys.path for the imports only
    sys.path.insert(0, resources)
    try:
        fresh = _import_bundled(resources, _bundled_packages(resources))
        module = None if fresh else sys.modules.get(name)
        if module is None:
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
