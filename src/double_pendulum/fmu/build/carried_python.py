"""The CPython a self-contained FMU carries beside its binary, for each platform it ships.

A self-contained FMU runs where no Python is installed: its ``binaries/<platform>/`` folder holds, beside the FMU's
binary (the loader), a CPython of the building interpreter's minor version, which the loader starts in a host that
has no Python of its own (a Python host's interpreter is used instead: ``fmu_src/loader/python_runtime.h``):

* **x86_64-linux**: the building CPython's own shared ``libpython3.X.so`` (stripped), the extension modules of its
  ``lib-dynload`` that the FMU's code imports, and the shared libraries those need beyond the C library
  (``libffi.so.8`` for ``ctypes``), which the loader loads before Python starts (:attr:`CarriedPython.preload`);
  it needs the glibc its files ask for (:func:`glibc_floor`);
* **x86_64-windows**: python.org's embeddable CPython of the same minor version (:mod:`.python_embed`):
  ``python3X.dll``, the C runtime it needs (``vcruntime140.dll``) and the extension modules (``*.pyd``) the FMU's
  code imports, with the DLLs they need.

Both carry only the part of the standard library the FMU's code imports, as bytecode in one zip
(``python3X.zip``): :func:`stdlib_modules` follows every import of the FMU's own code (its functions included),
the imports in the functions of the standard-library modules it imports itself (it calls them: ``uuid.uuid1``
imports ``random`` where the C library gives no time-based UUID), and from there what runs when a module is
imported (module and class bodies), not what a standard-library function it never calls would import. Both
Linux zip is stored uncompressed, read as it is when the CPython starts (its ``zlib`` is an extension module, and
inflating the modules made the start 17 % slower), and deflated in the FMU's zip instead; the Windows one is
deflated (its ``zlib`` is built into the DLL). The loader's bootstrap reads both zips once
(``fmu_src/archive_import.py``). The FMU's own code is compiled by the building CPython, whose minor version both
carried Pythons share, so its bytecode is the one they run.
"""

from __future__ import annotations

import dis
import functools
import inspect
import io
import modulefinder
import os
import re
import shutil
import struct
import subprocess
import sys
import sysconfig
import tempfile
import zipfile
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

from ..carries import elf_needs
from . import bundle, loader, python_embed

# Modules CPython looks up by name (codecs), which no import statement names.
LOOKED_UP = ("encodings.utf_8", "encodings.utf_8_sig", "encodings.ascii", "encodings.latin_1",
             "encodings.raw_unicode_escape", "encodings.unicode_escape", "encodings.utf_16", "encodings.utf_16_le",
             "encodings.utf_32", "encodings.mbcs", "encodings.cp1252")
# What every Linux system has: the C library's parts and the dynamic loader (never carried).
SYSTEM_LIBRARIES = frozenset({"libc.so.6", "libm.so.6", "libpthread.so.0", "libdl.so.2", "librt.so.1",
                              "libutil.so.1", "ld-linux-x86-64.so.2"})
# Libraries too large to carry for what they give: the modules that need them are left out (hashlib falls back to
# the hashes built into CPython, and nothing the FMU runs needs TLS).
NOT_CARRIED = ("libssl", "libcrypto")
# Extension modules the standard library imports only inside ``try: ... except ImportError``, for what the FMU
# never does: shutil's and zipfile's bz2 and lzma archives. Left out, with the libraries they need (on Linux
# preloaded at every start otherwise).
OPTIONAL = ("_bz2", "_lzma")
LINUX_LIBRARY_FOLDERS = ("/lib/x86_64-linux-gnu", "/usr/lib/x86_64-linux-gnu", "/lib64", "/usr/lib64", "/lib",
                         "/usr/lib")


class CarriedPythonUnavailable(RuntimeError):
    """No CPython can be carried for a platform: the message says why and what to do, in one line."""


@dataclass(frozen=True)
class CarriedPython:
    """What an FMU carries in ``binaries/<platform>/`` to run without a Python installed."""

    platform: str  # "x86_64-linux", "x86_64-windows"
    version: str  # "3.11.7"
    library: str  # the shared library's file name: libpython3.11.so.1.0, python311.dll
    stdlib: str  # the zipped standard library's file name: python311.zip
    files: Mapping[str, bytes] = field(repr=False)  # every file, by name, the above included
    preload: tuple[str, ...] = ()  # libraries the loader loads before Python starts (Linux: the modules' needs)
    left_out: tuple[str, ...] = ()  # extension modules not carried, each with why

    @property
    def minor(self) -> int:
        return int(self.version.split(".")[1])

    @property
    def size(self) -> int:
        return sum(len(data) for data in self.files.values())


# ------------------------------------------------------------------------------------------ the standard library

class _ImportTimeFinder(modulefinder.ModuleFinder):
    """modulefinder that follows, in the FMU's own code (under ``own``) every import, and in the standard library
    the imports that run when a module is imported (a module's and its classes' bodies), plus those in the
    functions of the modules the FMU's code imports itself (``direct``: it calls them)."""

    def __init__(self, path: list[str], own: str, direct: frozenset[str] = frozenset()) -> None:
        super().__init__(path=path)
        self.own, self.direct = own, direct

    def scan_code(self, co, m) -> None:  # noqa: ANN001 (modulefinder's signature)
        in_function = co.co_flags & inspect.CO_OPTIMIZED
        if in_function and not (m.__file__ or "").startswith(self.own) and m.__name__ not in self.direct:
            return  # a function of the standard library the FMU's code does not call: its imports never run
        super().scan_code(co, m)

    def scan_opcodes(self, co):  # noqa: ANN001, ANN201 (modulefinder's signature)
        """modulefinder's, without the imports under ``if __name__ == "__main__":`` (a module run as a script:
        ``calendar``, ``platform``, ``tokenize`` import argparse, doctest there). Only a code object that holds the
        constant ``"__main__"`` can have that block: the others take modulefinder's own scan, which is many times
        faster than :func:`dis.get_instructions` (most of the closure's time before)."""
        if "__main__" not in co.co_consts:
            yield from super().scan_opcodes(co)
            return
        guarded = _main_guarded(co)
        instructions = list(dis.get_instructions(co))
        for what, args in super().scan_opcodes(co):
            if what == "store":
                yield what, args
        for k, instruction in enumerate(instructions):
            if instruction.opname != "IMPORT_NAME" or any(instruction.offset in block for block in guarded):
                continue
            level, fromlist = instructions[k - 2].argval, instructions[k - 1].argval
            if level == 0:
                yield "absolute_import", (fromlist, instruction.argval)
            else:
                yield "relative_import", (level, fromlist, instruction.argval)


def _main_guarded(co: object) -> list[range]:
    """The offsets of ``co``'s instructions under ``if __name__ == "__main__":``."""
    instructions = list(dis.get_instructions(co))
    blocks = []
    for k in range(len(instructions) - 3):
        name, main, compare, jump = instructions[k:k + 4]
        if (name.opname == "LOAD_NAME" and name.argval == "__name__" and main.argval == "__main__"
                and compare.opname == "COMPARE_OP" and "IF_FALSE" in jump.opname):
            blocks.append(range(jump.offset, jump.argval))
    return blocks


def _imported_by(code: object) -> set[str]:
    """Every name an ``import`` statement anywhere in ``code`` (a code object) names."""
    names = set()
    for instruction in dis.get_instructions(code):
        if instruction.opname == "IMPORT_NAME":
            names.add(instruction.argval)
    for constant in code.co_consts:
        if isinstance(constant, type(code)):
            names |= _imported_by(constant)
    return names


def _module_name(path: str) -> str | None:
    """``pkg/sub/__init__.py`` -> ``pkg.sub``, ``pkg/mod.py`` -> ``pkg.mod``; None for other files."""
    if not path.endswith(".py"):
        return None
    parts = path[:-3].split("/")
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _stdlib_folders() -> tuple[Path, Path]:
    stdlib = Path(sysconfig.get_paths()["stdlib"])
    return stdlib, Path(sysconfig.get_config_var("DESTSHARED") or stdlib / "lib-dynload")


BOOTSTRAP_MODULE = "_dp_fmu_bootstrap.py"  # the loader's own first Python (bridge.c), followed like the FMU's code


def _find(code: tuple[tuple[str, bytes], ...], folder: str, direct: frozenset[str]) -> _ImportTimeFinder:
    stdlib, dynload = _stdlib_folders()
    finder = _ImportTimeFinder([folder, str(stdlib), str(dynload)], own=folder, direct=direct)
    for name, _ in code:
        module = _module_name(name)
        if module:
            finder.import_hook(module)
    for name in LOOKED_UP:
        try:
            finder.import_hook(name)
        except ImportError:
            pass  # another platform's codec (encodings.mbcs): the Windows package has it
    return finder


@functools.cache
def _stdlib_modules(code: tuple[tuple[str, bytes], ...]) -> tuple[tuple[tuple[str, str | None], ...], frozenset]:
    code = (*code, (BOOTSTRAP_MODULE, loader.bootstrap_source().encode()))
    with tempfile.TemporaryDirectory(prefix="dp_closure_") as tmp:
        for name, data in code:
            path = Path(tmp, name)
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_bytes(data)
        first = _find(code, tmp, frozenset())
        own = [module for module in first.modules.values() if (module.__file__ or "").startswith(tmp)]
        direct = frozenset().union(*(_imported_by(module.__code__) for module in own if module.__code__))
        finder = _find(code, tmp, direct)
        found = tuple(sorted((name, module.__file__) for name, module in finder.modules.items()
                             if not (module.__file__ or "").startswith(tmp)))
        missing = frozenset(name for name in [*finder.badmodules, *LOOKED_UP] if name not in finder.modules)
    return found, missing


def stdlib_modules(code: Mapping[str, bytes]) -> tuple[dict[str, str | None], frozenset[str]]:
    """The standard library the FMU's ``code`` (its files by path: ``pkg/mod.py``) and the loader's bootstrap
    (:func:`~.loader.bootstrap_source`) import, as this CPython has it:
    ``{module: its file, or None where it is built in}``, and the names imported that this CPython lacks (another
    platform's modules: ``winreg``, ``nt``, ``_winapi``; or names imported from a module, not modules)."""
    found, missing = _stdlib_modules(tuple(sorted(code.items())))
    return dict(found), missing


def _zip(members: Mapping[str, bytes], method: int, version: str, platform: str) -> bytes:
    """The zipped standard library; its comment says whose (``CPython 3.11.7 x86_64-linux``, for the FMU's page)."""
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w", method) as archive:
        archive.comment = f"CPython {version} {platform}: the part of its standard library the FMU imports".encode()
        for name in sorted(members):
            archive.writestr(zipfile.ZipInfo(name, (2020, 1, 1, 0, 0, 0)), members[name], compress_type=method)
    return buffer.getvalue()


def _archive_name(module: str, package: bool) -> str:
    return module.replace(".", "/") + ("/__init__.pyc" if package else ".pyc")


# ----------------------------------------------------------------------------------------------------- Linux

def _strip(data: bytes) -> bytes:
    """``data`` (an ELF shared library) without its symbol table and debug sections, where binutils' strip is here."""
    tool = shutil.which("strip")
    if tool is None:
        return data
    with tempfile.TemporaryDirectory(prefix="dp_strip_") as tmp:
        source, stripped = Path(tmp, "in.so"), Path(tmp, "out.so")
        source.write_bytes(data)
        done = subprocess.run([tool, "--strip-unneeded", "-o", str(stripped), str(source)], capture_output=True)
        return stripped.read_bytes() if done.returncode == 0 else data


def _find_library(name: str, near: Path) -> Path | None:
    """Where the dynamic loader would find ``name`` for a module in ``near`` (its folder, then the system's)."""
    for folder in (near, *map(Path, LINUX_LIBRARY_FOLDERS)):
        if (folder / name).is_file():
            return (folder / name).resolve()
    return None


def linux_python(code: Mapping[str, bytes]) -> CarriedPython:
    """The building CPython, carried for x86_64-linux (see the module's docstring)."""
    if not sys.platform.startswith("linux") or os.uname().machine != "x86_64":
        raise CarriedPythonUnavailable(f"the FMU can carry this machine's CPython only on x86_64 Linux, not on "
                                       f"{sys.platform} {os.uname().machine}: build with --lean")
    minor = sys.version_info[1]
    libdir, soname = sysconfig.get_config_var("LIBDIR") or "", sysconfig.get_config_var("INSTSONAME") or ""
    library = Path(libdir, soname)
    if not sysconfig.get_config_var("Py_ENABLE_SHARED") or not library.is_file():
        raise CarriedPythonUnavailable(f"this CPython ({sys.executable}) has no shared libpython, which the FMU "
                                       "would carry: build with one that has (Debian's python3, pyenv with "
                                       "--enable-shared), or with --lean")
    found, _ = stdlib_modules(code)
    stdlib_name = f"python3{minor}.zip"
    members, files, preload, left_out = {}, {library.name: _strip(library.read_bytes())}, [], []
    for module, path in found.items():
        if path is None or module == "__main__" or module in OPTIONAL:
            continue  # built into libpython, or not needed
        if path.endswith(".py"):
            source = Path(path).read_bytes()
            arcname = _archive_name(module, Path(path).name == "__init__.py")
            members[arcname] = bundle.pyc(source, f"{stdlib_name}/{arcname[:-1]}", checked=False)
            continue
        data = Path(path).read_bytes()
        extra = [name for name in elf_needs.needed_libraries(data)
                 if name not in SYSTEM_LIBRARIES and not name.startswith("libpython")]
        located = {name: _find_library(name, Path(path).parent) for name in extra}
        refused = [name for name in extra if name.startswith(NOT_CARRIED) or located[name] is None]
        if refused:
            left_out.append(f"{module} (needs {', '.join(refused)})")
            continue
        files[Path(path).name] = _strip(data)
        for name, located_path in located.items():
            if name not in files:
                files[name] = _strip(located_path.read_bytes())
                preload.append(name)
    # stored: read as it is at start-up (zlib is an extension module here; inflating the modules cost the start 17 %)
    version = ".".join(map(str, sys.version_info[:3]))
    files[stdlib_name] = _zip(members, zipfile.ZIP_STORED, version, "x86_64-linux")
    return CarriedPython("x86_64-linux", version, library.name, stdlib_name, files, tuple(preload), tuple(left_out))


def glibc_floor(python: CarriedPython) -> str | None:
    """The newest glibc symbol version the carried Linux files ask for (``GLIBC_2.35``), or None."""
    versions = [elf_needs.newest(elf_needs.version_needs(data), "GLIBC") for name, data in python.files.items()
                if data[:4] == b"\x7fELF"]
    versions = [v for v in versions if v]
    return max(versions, key=elf_needs.version_key) if versions else None


# --------------------------------------------------------------------------------------------------- Windows

_PE_VERSION = re.compile(rb"P\x00r\x00o\x00d\x00u\x00c\x00t\x00V\x00e\x00r\x00s\x00i\x00o\x00n\x00\x00\x00"
                         rb"((?:[0-9.]\x00)+)")


def _dll_version(data: bytes) -> str | None:
    """The ProductVersion in a DLL's version resource ("3.11.9"), read from its UTF-16 text."""
    match = _PE_VERSION.search(data)
    return match.group(1).decode("utf-16-le") if match else None


def _imported_dlls(data: bytes) -> list[str]:
    """The DLLs a PE file (a 64-bit DLL or .pyd) imports by name, from its import table."""
    pe = struct.unpack_from("<I", data, 0x3C)[0]
    if data[pe:pe + 4] != b"PE\0\0":
        raise ValueError("not a PE file")
    n_sections, = struct.unpack_from("<H", data, pe + 6)
    optional_size, = struct.unpack_from("<H", data, pe + 20)
    optional = pe + 24
    if struct.unpack_from("<H", data, optional)[0] != 0x20B:
        raise ValueError("not a 64-bit PE file")
    import_rva, _ = struct.unpack_from("<II", data, optional + 112 + 8)  # data directory 1: the import table
    sections = [struct.unpack_from("<IIII", data, optional + optional_size + 40 * k + 8) for k in range(n_sections)]

    def offset(rva: int) -> int:
        for size, address, raw_size, raw in sections:
            if address <= rva < address + max(size, raw_size):
                return rva - address + raw
        raise ValueError(f"RVA {rva:#x} is in no section")

    names, at = [], offset(import_rva) if import_rva else None
    while at is not None:
        name_rva = struct.unpack_from("<IIIII", data, at)[3]
        if name_rva == 0:
            break
        start = offset(name_rva)
        names.append(data[start:data.index(b"\0", start)].decode("ascii"))
        at += 20
    return names


def _needed_dlls(data: bytes, available: Mapping[str, bytes]) -> list[str]:
    """Which of the ``available`` DLLs a PE file imports."""
    imported = {name.lower() for name in _imported_dlls(data)}
    return [name for name in available if name.lower() in imported]


def windows_python(code: Mapping[str, bytes], minor: int | None = None) -> CarriedPython:
    """python.org's embeddable CPython 3.``minor`` (the building Python's minor version by default), carried for
    x86_64-windows (see the module's docstring)."""
    minor = sys.version_info[1] if minor is None else minor
    try:
        package = python_embed.embeddable_package(minor)
    except python_embed.WindowsPythonUnavailable as error:
        raise CarriedPythonUnavailable(str(error)) from None
    found, missing = stdlib_modules(code)
    library, stdlib_name = f"python3{minor}.dll", f"python3{minor}.zip"
    with zipfile.ZipFile(io.BytesIO(package[stdlib_name])) as stdlib:
        available = set(stdlib.namelist())
        members = {}
        for module in sorted({*found, *missing}):
            for arcname in (_archive_name(module, True), _archive_name(module, False)):
                if arcname in available:
                    members[arcname] = stdlib.read(arcname)
                    break
    dlls = {name: data for name, data in package.items() if name.lower().endswith(".dll") and name != library}
    version = _dll_version(package[library]) or f"3.{minor}"
    files = {library: package[library], stdlib_name: _zip(members, zipfile.ZIP_DEFLATED, version, "x86_64-windows")}
    left_out = []
    for module in sorted({*found, *missing}):
        pyd = f"{module}.pyd"
        if pyd not in package or module in OPTIONAL:
            continue
        needed = _needed_dlls(package[pyd], dlls)
        refused = [name for name in needed if name.lower().startswith(NOT_CARRIED)]
        if refused:
            left_out.append(f"{module} (needs {', '.join(refused)})")
            continue
        files[pyd] = package[pyd]
        for name in needed:
            files[name] = dlls[name]
    for name in _needed_dlls(package[library], dlls):  # the C runtime
        files[name] = dlls[name]
    return CarriedPython("x86_64-windows", version, library, stdlib_name, files, (), tuple(left_out))


@functools.cache
def _debian_copyright(library: str) -> bytes | None:
    """The Debian copyright file (its licence) of the package that installed the system library ``library`` (asked
    of dpkg once per process: some 0.1 s a library, for each FMU of a build otherwise)."""
    located = _find_library(library, Path("/nonexistent"))
    if located is None or shutil.which("dpkg-query") is None:
        return None
    for path in {str(located), *(str(Path(folder, library)) for folder in LINUX_LIBRARY_FOLDERS)}:
        done = subprocess.run(["dpkg-query", "-S", path], capture_output=True, text=True)
        if done.returncode == 0:
            package = done.stdout.split(":", 1)[0]
            copyright_file = Path("/usr/share/doc", package, "copyright")
            if copyright_file.is_file():
                return copyright_file.read_bytes()
    return None


def licenses(python: CarriedPython) -> dict[str, bytes]:
    """The licence texts of what ``python`` carries, by file name (for ``documentation/licenses/``): CPython's
    (python.org's Windows text covers the libraries its build carries: bzip2, libffi, zlib, ...), and on Linux
    those of the system libraries carried beside it, where the build machine has them (Debian's copyright files)."""
    if python.platform == "x86_64-windows":
        package = python_embed.embeddable_package(python.minor)
        return {f"CPython-{python.version}-windows.txt": package["LICENSE.txt"]} if "LICENSE.txt" in package else {}
    stdlib, _ = _stdlib_folders()
    found = {f"CPython-{python.version}-linux.txt": (stdlib / "LICENSE.txt").read_bytes()} \
        if (stdlib / "LICENSE.txt").is_file() else {}
    for library in python.preload:
        text = _debian_copyright(library)
        if text:
            found[f"{library.split('.so')[0]}.txt"] = text
    return found


PLATFORMS = ("x86_64-linux", "x86_64-windows")  # what a self-contained FMU carries a CPython for, by default


@functools.cache
def _carried(code: tuple[tuple[str, bytes], ...], platform: str) -> CarriedPython:
    return linux_python(dict(code)) if platform == "x86_64-linux" else windows_python(dict(code))


def carried_pythons(code: Mapping[str, bytes], platforms: tuple[str, ...] = PLATFORMS) -> tuple[CarriedPython, ...]:
    """The CPython a self-contained FMU with this ``code`` carries for each of ``platforms``, kept for the process
    (DoublePendulum and Suspension share their code). Raises :class:`CarriedPythonUnavailable`."""
    unknown = [name for name in platforms if name not in PLATFORMS]
    if unknown or not platforms:
        raise CarriedPythonUnavailable(f"cannot carry a CPython for {', '.join(unknown) or 'no platform'} (known: "
                                       f"{', '.join(PLATFORMS)})")
    key = tuple(sorted(code.items()))
    return tuple(_carried(key, name) for name in platforms)
