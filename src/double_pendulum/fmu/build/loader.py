"""The FMU's binaries: a small C loader for each platform, compiled from source when the FMU is built.

The loader (``fmu_src/loader/``) is the FMU's whole native side: ``fmi2_guard.c`` and ``fmi3_guard.c``
give the FMI functions with the standard's state machine and checks, sharing ``guard.c`` (instances,
instantiation, logging), ``fmu_state.c`` (FMU states) and ``pointer_set.c``; ``bridge.c`` calls the
FMU's Python side (``fmu_src/fmi_bridge.py``) through CPython's C API; ``python_runtime.c`` chooses the
CPython that runs it and ``python_start.c`` starts one where the host has none; ``platform.c`` is everything
that differs between Linux and Windows. No FMI library's binary is involved (docs/architecture.md says why
pythonfmu's C++ layer was replaced). The loader becomes the FMU's ``binaries/<platform>/<model identifier>.so``
(``.dll`` on Windows), compiled with the FMU's GUID (``FMU_GUID``, in ``identity.c``, the one source compiled for
each FMU; the others once per process and platform).

Which Python runs the FMU, one per process: in a Python host, the host's own interpreter (CPython >= 3.11; an
older one is refused in one line, and no second Python is ever loaded beside it); in a process where an earlier
FMU started one, that one; else the one named by ``DOUBLE_PENDULUM_FMU_PYTHON`` (a python3 interpreter, a
``libpython3.X.so`` or a ``python3X.dll``), if set; else the CPython the FMU carries beside the loader
(``binaries/<platform>/``: its shared library, the standard library it needs zipped, its extension modules;
:mod:`double_pendulum.fmu.build.carried_python`). A lean FMU (``double-pendulum build --lean``) carries none and
looks for the CPython it was built with (``resources/python.cfg``, :func:`python_record`), then ``python3`` on
PATH. Whichever it is needs nothing installed: it is started isolated (no ``site``, no environment variables,
no signal handlers, the host's locale left alone, no bytecode written), through the configuration API that
returns a status, so a Python that cannot start gives one line and no running FMU, never an ended host; and
everything the FMU runs in it (the model code and pythonfmu's Python part) is bundled in
``resources/python_code.zip`` and imports only the standard library. With debug logging on, an instantiation
logs which Python runs and why (docs/fmu.md, "What a target machine needs").

The loader is compiled with the system C compiler (``$CC``, else ``cc``, ``gcc`` or ``clang``; where there is
none, Zig's C compiler, which the ``ziglang`` package brings with pip)
against the FMI 2 and FMI 3 headers fmpy ships (``fmpy/c-code``), with every warning an error;
nothing compiled is committed. The Windows loader is cross-compiled by Zig (``x86_64-windows-gnu``).
Building the FMUs needs Linux and a compiler: elsewhere the build stops with one line saying so
(:class:`LoaderUnavailable`).

``DOUBLE_PENDULUM_LOADER_CFLAGS`` (:data:`EXTRA_CFLAGS_VARIABLE`), if set, holds more compiler flags
(split as a shell would): they go at the end of each command that compiles a source and of the one that links
the loader, so they reach the linker too, and they are part of the compile cache's key. The memory check
(``scripts/check_memory.sh``) builds a sanitized loader this way, e.g.
``DOUBLE_PENDULUM_LOADER_CFLAGS="-fsanitize=address,undefined -fno-omit-frame-pointer -g -O1"``.
"""

from __future__ import annotations

import ast
import functools
import importlib.util
import os
import re
import shlex
import shutil
import subprocess
import sys
import sysconfig
import tempfile
from dataclasses import dataclass
from pathlib import Path

LOADER_FOLDER = "loader"  # in fmu_src/ (installed as double_pendulum.adapters)
_SHARED_SOURCES = ("text.c", "platform.c", "python_start.c", "python_runtime.c", "pointer_set.c", "guard_base.c",
                   "guard.c", "fmu_state.c", "bridge.c")
LOADER_SOURCES = {version: (*_SHARED_SOURCES, f"fmi{version}_guard.c", "identity.c") for version in (2, 3)}
LOADER_HEADERS = ("text.h", "platform.h", "python_config.h", "python_start.h", "python_runtime.h", "pointer_set.h",
                  "guard_base.h", "guard.h", "fmu_state.h", "bridge.h", "identity.h", "glibc_compat.h")


@dataclass(frozen=True)
class Target:
    """A platform the FMUs ship a binary for: its name, each FMI version's name of its binaries folder, the
    binary's file suffix, and Zig's target (Zig cross-compiles for it; the Linux loader is built with the system's
    compiler where there is one)."""

    name: str
    folders: tuple[tuple[int, str], ...]
    suffix: str
    zig_target: str

    def folder(self, fmi_version: int) -> str:
        """``binaries/<this>/``: linux64 / win64 (FMI 2), x86_64-linux / x86_64-windows (FMI 3)."""
        return dict(self.folders)[fmi_version]

    @property
    def windows(self) -> bool:
        return self.suffix == ".dll"


# Zig links the Linux loader against the glibc it bundles, of the version its target names: the loader's floor.
LINUX = Target("x86_64-linux", ((2, "linux64"), (3, "x86_64-linux")), ".so", "x86_64-linux-gnu.2.17")
WINDOWS = Target("x86_64-windows", ((2, "win64"), (3, "x86_64-windows")), ".dll", "x86_64-windows-gnu")
TARGETS = {target.name: target for target in (LINUX, WINDOWS)}
# The platform of the Linux loader, as each FMI version names its binaries folder.
PLATFORMS = dict(LINUX.folders)
PLATFORM = PLATFORMS[2]
CONFIG_NAME = "python.cfg"  # in resources/: the CPython the FMU was built with
OVERRIDE_VARIABLE = "DOUBLE_PENDULUM_FMU_PYTHON"
EXTRA_CFLAGS_VARIABLE = "DOUBLE_PENDULUM_LOADER_CFLAGS"  # more flags for the loader's compile (and link) command
CFLAGS = ("-shared", "-fPIC", "-O2", "-std=gnu11", "-fvisibility=hidden", "-Wall", "-Wextra", "-Werror")
GCC_CFLAGS = ("-Wformat-truncation=2",)  # gcc's: a path or message that snprintf could cut is a warning too
# libdl and libpthread by file name and as needed: where the old glibc versions the loader binds
# (glibc_compat.h) live on systems older than glibc 2.34 (there -ldl would find an empty libdl.a).
LIBS = ("-Wl,--no-as-needed", "-l:libdl.so.2", "-l:libpthread.so.0", "-l:libm.so.6")
ZIG_LIBS = ("-Wl,--no-as-needed", "-ldl", "-lpthread", "-lm")
WINDOWS_LINK = ("-s",)  # no symbol table in the DLL (its exports stay)


class LoaderUnavailable(RuntimeError):
    """The loader cannot be built here (no C compiler, or not Linux): the FMUs cannot be built; the message
    says why in one line."""


def loader_sources(fmi_version: int = 2) -> list[Path]:
    """The C sources and headers of the FMI ``fmi_version`` loader (in the installed ``double_pendulum.adapters``)."""
    spec = importlib.util.find_spec("double_pendulum.adapters")
    if spec is None or not spec.submodule_search_locations:
        raise FileNotFoundError("cannot find double_pendulum.adapters: is double-pendulum-fmu installed?")
    folder = Path(next(iter(spec.submodule_search_locations))) / LOADER_FOLDER
    return [folder / name for name in (*LOADER_SOURCES[fmi_version], *LOADER_HEADERS)]


def bootstrap_source() -> str:
    """The Python the loader runs first in a process to import the FMU's code (``BOOTSTRAP`` in ``bridge.c``):
    what it imports is part of what a carried CPython must have."""
    text = next(path for path in loader_sources() if path.name == "bridge.c").read_text()
    literal = text[text.index("BOOTSTRAP[] ="):].split(";\n", 1)[0]
    return "".join(ast.literal_eval(f'"{line}"') for line in re.findall(r'^\s*"(.*)"\s*$', literal, re.M))


def fmi_headers() -> Path:
    """The folder of the official FMI 2 and FMI 3 C headers that fmpy ships."""
    import fmpy

    return Path(fmpy.__file__).resolve().parent / "c-code"


def c_compiler() -> list[str] | None:
    """The C compiler command: ``$CC`` if set, else the first of cc, gcc, clang on PATH, else Zig's C compiler
    from the ``ziglang`` package (a dependency on Linux: a machine with only Python and pip builds the FMUs
    too); None if none."""
    if os.environ.get("CC"):
        command = shlex.split(os.environ["CC"])
        return command if shutil.which(command[0]) else None
    found = next((shutil.which(name) for name in ("cc", "gcc", "clang") if shutil.which(name)), None)
    if found:
        return [found]
    if importlib.util.find_spec("ziglang") is not None:
        return [sys.executable, "-m", "ziglang", "cc"]
    return None


@functools.cache
def _is_gcc(compiler: tuple[str, ...]) -> bool:
    """Whether ``compiler`` is gcc (which takes :data:`GCC_CFLAGS`; clang and Zig's compiler do not)."""
    try:
        version = subprocess.run([*compiler, "--version"], capture_output=True, text=True, timeout=60).stdout.lower()
    except (OSError, subprocess.SubprocessError):
        return False
    return "clang" not in version and ("gcc" in version or "free software foundation" in version)


IDENTITY_SOURCES = ("identity.c",)
IDENTITY_MACROS = ("MODEL_IDENTIFIER", "FMU_GUID", "N_VARIABLES", "N_CONTINUOUS_STATES", "BUNDLED_PYTHON_LIBRARY",
                   "BUNDLED_PYTHON_STDLIB", "BUNDLED_PYTHON_MINOR", "BUNDLED_PYTHON_PRELOAD")
"""Only ``identity.c`` takes one FMU's macros (:data:`IDENTITY_MACROS`) and is compiled for each FMU. The others
take only the other macros (none in a build; the tests shorten ``QUERY_TIMEOUT_MS``) and are compiled once per
process and set of those (:func:`_object`): a build writes three loaders, the cross-check tree a dozen."""


def _flags(compiler: tuple[str, ...], target: Target = LINUX) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """The compiler's own flags (Zig's target, gcc's warnings) and the libraries the link needs."""
    if target.windows:
        return ("-target", target.zig_target), WINDOWS_LINK
    zig = "ziglang" in compiler
    own = ("-target", target.zig_target) if zig else GCC_CFLAGS if _is_gcc(compiler) else ()
    return own, ZIG_LIBS if zig else LIBS


def _cflags(target: Target) -> tuple[str, ...]:
    return tuple(flag for flag in CFLAGS if not (target.windows and flag == "-fPIC"))


def _run_compiler(command: list[str]) -> None:
    done = subprocess.run(command, capture_output=True, text=True)
    if done.returncode != 0:
        raise RuntimeError(f"compiling the FMU's loader failed: {shlex.join(command)}\n{done.stderr}")


def _compile_object(compiler: tuple[str, ...], target: Target, source: Path, macros: tuple[str, ...],
                    extra_flags: tuple[str, ...], folder: Path) -> Path:
    """``source`` compiled (not linked) into ``folder``, with :data:`CFLAGS` but ``-shared``."""
    output = folder / f"{source.stem}.o"
    flags = [flag for flag in _cflags(target) if flag != "-shared"]
    _run_compiler([*compiler, *flags, *_flags(compiler, target)[0], *macros, f"-I{fmi_headers()}", "-c", "-o",
                   str(output), str(source), *extra_flags])
    return output


@functools.cache
def _object(compiler: tuple[str, ...], target: Target, source: Path, stamp: tuple[float, tuple[float, ...]],
            macros: tuple[str, ...], extra_flags: tuple[str, ...]) -> bytes:
    """The object file of ``source``, one that takes no FMU's macros, kept for the process (``stamp``: the mtimes
    of ``source`` and of every header, part of the key; not the other sources', so that the FMI 2 and FMI 3 loaders
    share the objects)."""
    with tempfile.TemporaryDirectory(prefix="dp_loader_") as tmp:
        return _compile_object(compiler, target, source, macros, extra_flags, Path(tmp)).read_bytes()


@functools.cache
def _compiled(compiler: tuple[str, ...], target: Target, sources: tuple[Path, ...], mtimes: tuple[float, ...],
              defines: tuple[tuple[str, str], ...], extra_flags: tuple[str, ...] = ()) -> bytes:
    def macros(pairs: tuple[tuple[str, str], ...]) -> tuple[str, ...]:
        return tuple(f"-D{name}={value}" if value.isdigit() else f'-D{name}="{value}"' for name, value in pairs)

    shared = macros(tuple((name, value) for name, value in defines if name not in IDENTITY_MACROS))
    headers = tuple(mtime for path, mtime in zip(sources, mtimes) if path.suffix == ".h")
    with tempfile.TemporaryDirectory(prefix="dp_loader_") as tmp:
        folder = Path(tmp)
        objects = []
        for source, mtime in ((path, mtime) for path, mtime in zip(sources, mtimes) if path.suffix == ".c"):
            if source.name in IDENTITY_SOURCES:
                objects.append(_compile_object(compiler, target, source, macros(defines), extra_flags, folder))
            else:
                objects.append(folder / f"{source.stem}.o")
                objects[-1].write_bytes(_object(compiler, target, source, (mtime, headers), shared, extra_flags))
        output = folder / f"loader{target.suffix}"
        _run_compiler([*compiler, *_cflags(target), *_flags(compiler, target)[0], "-o", str(output),
                       *map(str, objects), *_flags(compiler, target)[1], *extra_flags])
        return output.read_bytes()


def zig_compiler() -> list[str] | None:
    """Zig's C compiler from the ``ziglang`` package, which cross-compiles the Windows loader; None without it."""
    return [sys.executable, "-m", "ziglang", "cc"] if importlib.util.find_spec("ziglang") is not None else None


def compiled_loader(fmi_version: int, defines: dict[str, str], target: Target = LINUX) -> bytes:
    """The FMI ``fmi_version`` loader's shared library for ``target`` and one FMU (compiled once per process,
    compiler, source version and ``defines``: the C string macros ``MODEL_IDENTIFIER`` and ``FMU_GUID``, the number
    ``N_VARIABLES`` of the model description's variables, for FMI 3 the number ``N_CONTINUOUS_STATES``, and for a
    self-contained FMU the ``BUNDLED_PYTHON_*`` names of the CPython it carries).
    The Linux loader is built with the system's C compiler (else Zig's), the Windows one always with
    Zig's (``x86_64-windows-gnu``: the Universal C Runtime of Windows 10 and newer).

    Raises :class:`LoaderUnavailable` where it cannot be built (no C compiler; not Linux), and
    ``RuntimeError`` with the compiler's output if compiling fails.
    """
    if not sys.platform.startswith("linux"):
        raise LoaderUnavailable(f"the FMUs' binary (a C loader) is for Linux; they cannot be built on {sys.platform}")
    compiler = zig_compiler() if target.windows else c_compiler()
    if compiler is None and target.windows:
        raise LoaderUnavailable("no Zig to compile the FMUs' Windows binary (pip install ziglang), or build with "
                                "--lean (Linux only)")
    if compiler is None:
        raise LoaderUnavailable(
            "no C compiler found ($CC, cc, gcc, clang, or the ziglang package): building the FMUs compiles their "
            "binary from source (fmu_src/loader/); install one (pip install ziglang, or apt-get install gcc) and "
            "build again"
        )
    bad = {name: value for name, value in defines.items() if any(c in str(value) for c in '"\\\n')}
    if bad:
        raise ValueError(f"loader macros must be plain text: {bad}")
    sources = tuple(loader_sources(fmi_version))
    # the sanitizers of the memory check are for the Linux loader, which the Linux hosts run
    extra = () if target.windows else tuple(shlex.split(os.environ.get(EXTRA_CFLAGS_VARIABLE, "")))
    return _compiled(tuple(compiler), target, sources, tuple(path.stat().st_mtime for path in sources),
                     tuple(sorted(defines.items())), extra)


def python_record() -> str:
    """``resources/python.cfg``: the CPython running this build, for the loader in a host without Python.

    ``executable`` and ``home`` are the base interpreter's (not a virtual environment's: the FMU
    needs only the standard library), ``library`` its shared libpython (empty if it has none).
    """
    library = ""
    if sysconfig.get_config_var("Py_ENABLE_SHARED"):
        library = os.path.join(sysconfig.get_config_var("LIBDIR") or "", sysconfig.get_config_var("INSTSONAME") or "")
    executable = getattr(sys, "_base_executable", "") or sys.executable
    return (
        "# The CPython this FMU was built with. Its binary loads it in a host that has no Python of its\n"
        f"# own, unless {OVERRIDE_VARIABLE} names another one (docs/fmu.md).\n"
        f"version={sys.version_info[0]}.{sys.version_info[1]}\n"
        f"executable={executable}\nlibrary={library}\nhome={sys.base_prefix}\n"
    )
