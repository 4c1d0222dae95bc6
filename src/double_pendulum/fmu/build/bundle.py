"""The Python code an FMU bundles, in one zip in ``resources/``, and the names it runs under.

Every module an FMU runs is imported under a private name (``fmu_src/slave_common.py`` says how),
so that FMUs of another author with the same model identifier, an older build of this one, or a
host that imports ``double_pendulum`` or ``pythonfmu`` itself never meet it in ``sys.modules``::

    resources/slavemodule.txt        _dp_fmu_<id>_<Model>: the entry module (pythonfmu's convention)
    resources/identity.cfg           the model, its GUID, the archive and the entry module (identity_record)
    resources/python_code.zip        every module, under its private name (ARCHIVE):
        _dp_fmu_<id>_<Model>.py          the entry module (ENTRY_FMI2 / ENTRY_FMI3 below): its
                                         ``fmi_bridge`` is what the FMU's binary calls
        _dp_fmu_<id>_adapters/           fmu_src's adapters, a package (ADAPTERS)
        _dp_fmu_<id>/                    the runtime (the package ``double_pendulum``'s runtime part)
        _dp_fmu_<id>_pythonfmu/          the FMI library's Python part (pythonfmu3 for FMI 3), its slave
                                         modules only: its builder is not bundled, and its ``__init__``,
                                         which would import the builder, is never run (FMI_LIBRARY_INIT)

Each source has its bytecode beside it (``mod.pyc``, where zipimport looks: hash-based, checked against the
source, PEP 552); a Python of another minor version compiles the source instead. One zip instead of a
hundred files: fmpy extracts an FMU anew for every ``simulate_fmu`` call, and it is the number of files that
costs (docs/performance.md).

The id is a hash of the bundled code (:func:`bundle_id`): FMUs built from the same sources
(DoublePendulum and Suspension) share it, and so share their privately imported modules. The FMI
library's builder is given a stub of the adapter under a build-only name (:func:`builder_script`);
:func:`bundled_entries` puts the layout above in its place.
"""

from __future__ import annotations

import hashlib
import importlib.util
import io
import marshal
import zipfile
from collections.abc import Mapping
from pathlib import Path

from ...component.variables import INTERFACES

PRIVATE_MARK = "_dp_fmu_"
BUILDER_ADAPTERS = "adapters"  # the adapters' folder as the builder writes it into resources/
ARCHIVE = "python_code.zip"  # in resources/: every module the FMU runs
FMI_LIBRARIES = ("pythonfmu", "pythonfmu3")
# The FMI libraries' modules that only build FMUs (their builder and command line): not bundled.
BUILD_ONLY = ("builder.py", "__main__.py", "csvbuilder.py", "deploy.py")
# fmu_src's modules each FMI version's FMUs bundle: every FMI 2 FMU carries all FMI 2 adapters, so
# that DoublePendulum and Suspension bundle the same code (one id, one private package).
ADAPTERS = {
    2: ("__init__.py", "fmi_bridge.py", "slave_common.py", "archive_import.py", "double_pendulum_slave.py",
        *(f"{name}.py" for name in INTERFACES)),
    3: ("__init__.py", "fmi_bridge.py", "slave_common.py", "archive_import.py", "DoublePendulumFmi3.py"),
}
ADAPTER_MODULES = {2: {name: name for name in INTERFACES}, 3: {"DoublePendulum": "DoublePendulumFmi3"}}

PACKAGE_INIT = '''"""The adapters of this bundle (written by the build: double_pendulum.fmu.build.bundle).

All are imported with the package: FMUs of one bundle (DoublePendulum, Suspension) share it, and
the archive it was first imported from may be gone by the time another FMU of the bundle, or
another extraction of the same FMU, is instantiated (fmpy extracts an FMU anew for each run).
"""

from . import {modules}  # noqa: F401
'''

FMI_LIBRARY_INIT = '''"""{library}'s slave modules, bundled under a private name (double_pendulum.fmu.build.bundle).

The package is registered without running this file (fmu_src/slave_common.py, fmi_library): {library}'s own
__init__ imports its builder, which the FMU does not bundle.
"""
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


def bundle_id(files: Mapping[str, bytes], model_identifier: str) -> str:
    """A hash of the Python code the FMU bundles (every ``resources/**.py`` but the builder's stub)."""
    digest = hashlib.sha256()
    stub = f"resources/{builder_stem(model_identifier)}.py"
    for name in sorted(files):
        if name.startswith("resources/") and name.endswith(".py") and name != stub:
            digest.update(name.encode() + b"\0" + files[name] + b"\0")
    return digest.hexdigest()[:16]


def _private_path(name: str, identity: str) -> str | None:
    """Where the builder's ``resources/<name>`` lies in the archive, or None if it is not bundled."""
    top, _, rest = name.partition("/")
    if top == BUILDER_ADAPTERS:
        return f"{package_name(identity)}/{rest}"
    if top == "double_pendulum":
        return f"{PRIVATE_MARK}{identity}/{rest}"
    if top in FMI_LIBRARIES:
        return None if rest in BUILD_ONLY else f"{PRIVATE_MARK}{identity}_{top}/{rest}"
    return None


def code_files(files: Mapping[str, bytes], model_identifier: str, fmi_version: int) -> tuple[dict[str, bytes], str]:
    """The Python sources the FMU bundles, by their path in the archive (the private layout), and the bundle's id.

    ``files`` is the FMI library builder's FMU (its ``resources/`` holds the runtime, the adapters and the
    library's Python part)."""
    identity = bundle_id(files, model_identifier)
    code: dict[str, bytes] = {}
    for name, data in files.items():
        if not (name.startswith("resources/") and name.endswith(".py")):
            continue
        path = _private_path(name[len("resources/"):], identity)
        if path is None:
            continue
        top, _, rest = path.partition("/")
        if rest == "__init__.py" and top == package_name(identity):
            data = PACKAGE_INIT.format(modules=", ".join(sorted(set(ADAPTER_MODULES[fmi_version].values())))).encode()
        elif rest == "__init__.py" and top.endswith(FMI_LIBRARIES):
            data = FMI_LIBRARY_INIT.format(library=top.rsplit("_", 1)[1]).encode()
        code[path] = data
    code[f"{entry_name(identity, model_identifier)}.py"] = entry_source(model_identifier, fmi_version,
                                                                        package_name(identity)).encode()
    return code, identity


def pyc(source: bytes, filename: str, checked: bool) -> bytes:
    """``source`` compiled (by this CPython, as ``filename``) into a hash-based .pyc (PEP 552): checked against the
    source beside it (``checked``), or read as it is. File times do not count: hosts extract FMUs without them."""
    code = compile(source, filename, "exec", dont_inherit=True)
    flags = 0b11 if checked else 0b01
    return importlib.util.MAGIC_NUMBER + flags.to_bytes(4, "little") + importlib.util.source_hash(source) + \
        marshal.dumps(code)


def archive(code: Mapping[str, bytes]) -> bytes:
    """The zip of the FMU's code: each source with its checked bytecode beside it (``mod.pyc``), stored
    uncompressed (a carried Linux CPython has no zlib until an extension module loads; the FMU's own zip
    compresses it)."""
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w", zipfile.ZIP_STORED) as out:
        for name in sorted(code):
            for member, data in ((name, code[name]), (name + "c", pyc(code[name], f"{ARCHIVE}/{name}", True))):
                out.writestr(zipfile.ZipInfo(member, (2020, 1, 1, 0, 0, 0)), data)
    return buffer.getvalue()


def bundled_entries(files: Mapping[str, bytes], model_identifier: str,
                    fmi_version: int) -> tuple[dict[str, bytes], dict[str, bytes], str]:
    """The FMU's files with the builder's Python sources replaced by ``resources/python_code.zip`` (see the top
    of this module), the code itself by its path in that archive, and the bundle's id."""
    code, identity = code_files(files, model_identifier, fmi_version)
    out = {name: data for name, data in files.items() if not (name.startswith("resources/") and name.endswith(".py"))}
    out["resources/slavemodule.txt"] = entry_name(identity, model_identifier).encode()
    out[f"resources/{ARCHIVE}"] = archive(code)
    return out, code, identity


def package_name(identity: str) -> str:
    """The private name of the adapters' package of the bundle ``identity``."""
    return f"{PRIVATE_MARK}{identity}_adapters"


def entry_name(identity: str, model_identifier: str) -> str:
    """The private name of the entry module of ``model_identifier`` in the bundle ``identity``."""
    return f"{PRIVATE_MARK}{identity}_{model_identifier}"


def identity_record(model_identifier: str, token: str, identity: str) -> bytes:
    """``resources/identity.cfg``: whose resources these are, read by the FMU's binary, which refuses
    another FMU's resources folder (fmu_src/loader/guard.c), and what it imports: the archive of the FMU's code
    (``resources/python_code.zip``), the adapters' package and the entry module in it."""
    package, entry = package_name(identity), entry_name(identity, model_identifier)
    return (f"# The FMU these resources belong to (written by double_pendulum.fmu.build.bundle).\n"
            f"model={model_identifier}\ntoken={token}\narchive={ARCHIVE}\npackage={package}\nentry={entry}\n").encode()
