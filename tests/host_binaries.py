"""The tests' C hosts (tests/c_host/*.c), each compiled once per test session instead of once per module that
runs it: the torture hosts serve tests/test_guard.py and tests/test_state_matrix.py, fmi2_host and fmi3_host
tests/test_c_host.py and tests/test_reference_results.py. A host is compiled by the first module that asks for
it into a folder of the session (conftest's ``session_shared``, which the xdist workers share under a file
lock); the others read it. What is tested is the FMUs in the hosts, not the compile.

The torture hosts get :func:`sanitize.host_flags` (AddressSanitizer and UndefinedBehaviorSanitizer with
DOUBLE_PENDULUM_SANITIZE=1, else -O2), the plain hosts -O2."""

from __future__ import annotations

import subprocess
from pathlib import Path

import pytest
import sanitize
from conftest import session_shared

from double_pendulum.fmu.build import loader

SOURCES = Path(__file__).parent / "c_host"
TORTURE = ("fmi2_torture", "fmi3_torture")


def compile_host(name: str, folder: Path) -> Path:
    """Compile ``tests/c_host/<name>.c`` into ``folder/<name>``."""
    path = folder / name
    flags = sanitize.host_flags() if name in TORTURE else ["-O2"]
    command = [*loader.c_compiler(), *flags, f"-I{loader.fmi_headers()}", "-o", str(path), str(SOURCES / f"{name}.c"),
               "-ldl", "-lpthread", "-lm"]
    subprocess.run(command, check=True, capture_output=True)
    return path


def compiled_host(tmp_path_factory: pytest.TempPathFactory, name: str) -> Path:
    """The host ``name`` (``fmi2_torture``, ``fmi3_torture``, ``fmi2_host``, ``fmi3_host``), compiled once for
    the session."""
    def make(folder: Path) -> None:
        folder.mkdir()
        compile_host(name, folder)

    return session_shared(tmp_path_factory, f"c_host_{name}", make) / name
