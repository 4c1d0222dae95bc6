"""Sanitized builds for the memory check (``scripts/check_memory.sh``).

With ``DOUBLE_PENDULUM_SANITIZE=1`` the test session (tests/conftest.py) builds the FMUs' loader with
AddressSanitizer and UndefinedBehaviorSanitizer (through ``DOUBLE_PENDULUM_LOADER_CFLAGS``, read by
:mod:`double_pendulum.fmu.build.loader`), tests/test_guard.py compiles its C torture hosts with the same flags
and runs them with :func:`environment` added to their bare environment: any finding ends the host
with a report on stderr and a non-zero exit, which fails the test with the report in its message.
Without the variable nothing changes.
"""

from __future__ import annotations

import os
import shlex
from pathlib import Path

VARIABLE = "DOUBLE_PENDULUM_SANITIZE"
ENABLED = os.environ.get(VARIABLE) == "1"
# The hosts' and the loader's: -O1 and frame pointers for reports with whole stacks.
FLAGS = ("-fsanitize=address,undefined", "-fno-omit-frame-pointer", "-g", "-O1")
# The loader also with -z nodelete: the hosts dlclose it before exit, and LeakSanitizer, which runs at
# exit, neither scans the globals of an unloaded library (what they hold looks leaked) nor names its
# functions in a report.
LOADER_FLAGS = (*FLAGS, "-Wl,-z,nodelete")
LEAK_SUPPRESSIONS = Path(__file__).resolve().parents[1] / "scripts" / "lsan-python.supp"


def host_flags() -> list[str]:
    """Compiler flags for a C test host: the sanitizers' when enabled, else plain -O2."""
    return list(FLAGS) if ENABLED else ["-O2"]


def options() -> dict[str, str]:
    """The sanitizers' run-time options: stop at the first finding; leaks checked at exit, except what
    the embedded CPython allocated (it is never finalised, and its small-object arenas, which hold
    pointers to much of the rest, are memory LeakSanitizer does not scan): LEAK_SUPPRESSIONS."""
    return {
        "ASAN_OPTIONS": "halt_on_error=1:detect_leaks=1:detect_stack_use_after_return=1:strict_string_checks=1",
        "LSAN_OPTIONS": f"suppressions={LEAK_SUPPRESSIONS}:print_suppressions=0",
        "UBSAN_OPTIONS": "print_stacktrace=1:halt_on_error=1",
    }


def environment() -> dict[str, str]:
    """What a host's bare environment gets added: :func:`options` when enabled, else nothing."""
    return options() if ENABLED else {}


def configure() -> None:
    """In a sanitized session, have the loader built with LOADER_FLAGS (unless the variable is set already)."""
    if ENABLED:
        from double_pendulum.fmu.build import loader

        os.environ.setdefault(loader.EXTRA_CFLAGS_VARIABLE, shlex.join(LOADER_FLAGS))
