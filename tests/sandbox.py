"""A machine with no Python at all, for the tests' C hosts: a bubblewrap sandbox whose root holds only the C libraries
the host and the FMU's binaries load (the dynamic loader, libc, libm, libdl, libpthread, libgcc_s), the host and the
extracted FMU (read-only: the FMU may write nothing into its folder), with an empty environment but a PATH that
names nothing and a private /tmp. What a tool's machine without Python looks like to the FMU; its own CPython is
all there is (tests/test_self_contained.py).

:func:`unavailable` says why a test must skip (no ``bwrap``, or no user namespaces for it here).
"""

from __future__ import annotations

import functools
import os
import re
import shutil
import subprocess
from collections.abc import Sequence
from pathlib import Path

C_LIBRARIES = ("libc.so.6", "libm.so.6", "libdl.so.2", "libpthread.so.0", "libgcc_s.so.1")
"""What the FMUs' binaries may ask of a Linux system beyond the dynamic loader: the C library's parts
(tests/test_loader_symbols.py), and GCC's runtime, which fmpy's container binary links (every Linux system with
a C library has it)."""
BWRAP_MISSING = "bubblewrap is not installed (apt-get install bubblewrap)"


def bwrap() -> str | None:
    return shutil.which("bwrap")


@functools.cache
def unavailable() -> str | None:
    """Why no sandbox can be made here (None if one can)."""
    if bwrap() is None:
        return BWRAP_MISSING
    done = subprocess.run([bwrap(), "--unshare-all", "--ro-bind", "/", "/", "true"], capture_output=True, text=True)
    return None if done.returncode == 0 else f"bwrap cannot make a sandbox here: {done.stderr.strip()[:200]}"


@functools.cache
def system_files() -> tuple[str, ...]:
    """The paths of the dynamic loader and :data:`C_LIBRARIES`, as this system's dynamic loader finds them (``ldd``
    of /bin/true, then the folder of its libc for the others)."""
    out = subprocess.run(["ldd", "/bin/true"], capture_output=True, text=True, check=True).stdout
    loader = next(m for m in re.findall(r"(/\S*ld-linux\S*\.so\.\d)", out))
    libc = Path(re.search(r"libc\.so\.6 => (\S+)", out).group(1))
    return (loader, *(str(libc.parent / name) for name in C_LIBRARIES))


def command(host: Path, fmu_folder: Path, arguments: Sequence[str], extra: Sequence[Path] = ()) -> list[str]:
    """The bwrap command that runs ``host`` with ``arguments`` in the sandbox, the extracted FMU ``fmu_folder`` at
    /fmu (read-only; an argument that is the folder's path becomes /fmu) and ``extra`` files bound read-only at
    their own paths."""
    binds = []
    for path in (*system_files(), *map(str, extra)):
        binds += ["--ro-bind", path, path]
        real = os.path.realpath(path)
        if real != path:  # a symbolic link: bind what it names where it names it
            binds += ["--ro-bind", real, real]
    given = [a.replace(str(fmu_folder), "/fmu") for a in arguments]
    return [bwrap(), "--unshare-all", "--die-with-parent", "--tmpfs", "/", *binds,
            "--ro-bind", str(host), "/host", "--ro-bind", str(fmu_folder), "/fmu", "--tmpfs", "/tmp",
            "--proc", "/proc", "--dev", "/dev", "--clearenv", "--setenv", "PATH", "/nowhere", "--chdir", "/tmp",
            "/host", *given]


def run(host: Path, fmu_folder: Path, arguments: Sequence[str], timeout: float = 300) -> subprocess.CompletedProcess:
    """Run :func:`command` and return its exit status, stdout and stderr."""
    return subprocess.run(command(host, fmu_folder, arguments), capture_output=True, text=True, timeout=timeout)
