"""The Python code an FMU bundles in ``resources/``, and the names it runs under.

Every module an FMU runs is imported under a private name (``fmu_src/slave_common.py`` says how),
so that FMUs of another author with the same model identifier, an older build of this one, or a
host that imports ``double_pendulum`` or ``pythonfmu`` itself never meet it in ``sys.modules``::

    resources/slavemodule.txt              _dp_fmu_<id>_<Model>: the entry module (pythonfmu's convention)
    resources/_dp_fmu_<id>_<Model>.py      the entry module (ENTRY_FMI2 / ENTRY_FMI3 below): its
                                           ``fmi_bridge`` is what the FMU's binary calls
    resources/identity.cfg                 the model, its GUID and the entry module (identity_record)
    resources/_dp_fmu_<id>_adapters/       fmu_src's adapters, a package (ADAPTERS)
    resources/double_pendulum/             the runtime, imported as _dp_fmu_<id>
    resources/pythonfmu/ or pythonfmu3/    the FMI library's Python part

The id is a hash of the bundled code (:func:`bundle_id`): FMUs built from the same sources
(DoublePendulum and Suspension) share it, and so share their privately imported modules. The FMI
library's builder is given a stub of the adapter under a build-only name (:func:`builder_script`);
:func:`bundled_entries` puts the layout above in its place.
"""

from __future__ import annotations

import hashlib
from pathlib import Path

from ...component.variables import INTERFACES

PRIVATE_MARK = "_dp_fmu_"
BUILDER_ADAPTERS = "adapters"  # the adapters' folder as the builder writes it into resources/
# fmu_src's modules each FMI version's FMUs bundle: every FMI 2 FMU carries all FMI 2 adapters, so
# that DoublePendulum and Suspension bundle the same code (one id, one private package).
ADAPTERS = {
    2: ("__init__.py", "fmi_bridge.py", "slave_common.py", "double_pendulum_slave.py",
        *(f"{name}.py" for name in INTERFACES)),
    3: ("__init__.py", "fmi_bridge.py", "slave_common.py", "DoublePendulumFmi3.py"),
}
ADAPTER_MODULES = {2: {name: name for name in INTERFACES}, 3: {"DoublePendulum": "DoublePendulumFmi3"}}

PACKAGE_INIT = '''"""The adapters of this bundle (written by the build: double_pendulum.fmu.build.bundle).

All are imported with the package: FMUs of one bundle (DoublePendulum, Suspension) share it, and
the folder it was first imported from may be gone by the time another FMU of the bundle, or
another extraction of the same FMU, is instantiated (fmpy extracts an FMU anew for each run).
"""

from . import {modules}  # noqa: F401
'''

ENTRY_FMI2 = '''"""Entry module of {model}.fmu, imported by its binary (written by double_pendulum.fmu.build.bundle)."""

from {package}.{adapter} import {model}
from {package}.fmi_bridge import Bridge

fmi_bridge = Bridge({model}, fmi_version=2)
'''

ENTRY_FMI3 = '''"""Entry module of {model}.fmu, imported by its binary (written by double_pendulum.fmu.build.bundle)."""

from {package} import {adapter} as _adapter
from {package}.fmi_bridge import Bridge


class {model}(_adapter.{model}, _adapter.Fmi3SlaveBase):
    """The adapter's class. pythonfmu3's builder finds an FMU's class by a line like the one above."""


fmi_bridge = Bridge({model}, fmi_version=3)
'''

IDENTITY_FILE = "resources/identity.cfg"


def builder_stem(model_identifier: str) -> str:
    """The module name of the stub the FMI library's builder imports (not a public name)."""
    return f"{PRIVATE_MARK}build_{model_identifier}"


def builder_script(folder: Path, model_identifier: str, fmi_version: int) -> Path:
    """Write the stub the builder imports to find the model's class: the entry module, importing the
    installed adapters (``double_pendulum.adapters``)."""
    path = folder / f"{builder_stem(model_identifier)}.py"
    path.write_text(entry_source(model_identifier, fmi_version, "double_pendulum.adapters"))
    return path


def entry_source(model_identifier: str, fmi_version: int, package: str) -> str:
    """The entry module's source, importing the adapters from ``package``."""
    template = ENTRY_FMI2 if fmi_version == 2 else ENTRY_FMI3
    return template.format(model=model_identifier, package=package,
                           adapter=ADAPTER_MODULES[fmi_version][model_identifier])


def bundle_id(files: dict[str, bytes], model_identifier: str) -> str:
    """A hash of the Python code the FMU bundles (every ``resources/**.py`` but the builder's stub)."""
    digest = hashlib.sha256()
    stub = f"resources/{builder_stem(model_identifier)}.py"
    for name in sorted(files):
        if name.startswith("resources/") and name.endswith(".py") and name != stub:
            digest.update(name.encode() + b"\0" + files[name] + b"\0")
    return digest.hexdigest()[:16]


def bundled_entries(files: dict[str, bytes], model_identifier: str,
                    fmi_version: int) -> tuple[dict[str, bytes], str]:
    """The FMU's files with the builder's layout turned into the private one (see the top of this module),
    and the bundle's id."""
    identity = bundle_id(files, model_identifier)
    package, entry = package_name(identity), entry_name(identity, model_identifier)
    adapters_folder = f"resources/{BUILDER_ADAPTERS}/"
    out: dict[str, bytes] = {}
    for name, data in files.items():
        if name == f"resources/{builder_stem(model_identifier)}.py":
            continue
        if name == f"{adapters_folder}__init__.py":
            data = PACKAGE_INIT.format(modules=", ".join(sorted(set(ADAPTER_MODULES[fmi_version].values())))).encode()
        if name.startswith(adapters_folder):
            name = f"resources/{package}/" + name[len(adapters_folder):]
        elif name == "resources/slavemodule.txt":
            data = entry.encode()
        out[name] = data
    out[f"resources/{entry}.py"] = entry_source(model_identifier, fmi_version, package).encode()
    return out, identity


def package_name(identity: str) -> str:
    """The private name of the adapters' package of the bundle ``identity``."""
    return f"{PRIVATE_MARK}{identity}_adapters"


def entry_name(identity: str, model_identifier: str) -> str:
    """The private name of the entry module of ``model_identifier`` in the bundle ``identity``."""
    return f"{PRIVATE_MARK}{identity}_{model_identifier}"


def identity_record(model_identifier: str, token: str, identity: str) -> bytes:
    """``resources/identity.cfg``: whose resources these are, read by the FMU's binary, which refuses
    another FMU's resources folder (fmu_src/loader/guard.c), and what it imports: the adapters' package
    (``resources/<package>/``) and the entry module (``resources/<entry>.py``)."""
    package, entry = package_name(identity), entry_name(identity, model_identifier)
    return (f"# The FMU these resources belong to (written by double_pendulum.fmu.build.bundle).\n"
            f"model={model_identifier}\ntoken={token}\npackage={package}\nentry={entry}\n").encode()
