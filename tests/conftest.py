"""Shared fixtures: the FMU is built once per test session into a temporary folder."""

from __future__ import annotations

from pathlib import Path

import pytest

from double_pendulum.fmu.build import build_fmu
from double_pendulum.fmu.runner import FmuRunner

REPO = Path(__file__).resolve().parents[1]
DATA = REPO / "data"


@pytest.fixture(scope="session")
def fmu_path(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A freshly built DoublePendulum.fmu (built once per session)."""
    return build_fmu(tmp_path_factory.mktemp("fmu") / "DoublePendulum.fmu")


@pytest.fixture(scope="session")
def runner(fmu_path: Path):
    """An fmpy runner for the session's FMU."""
    with FmuRunner(fmu_path) as r:
        yield r


# pythonfmu (<= 0.7.0, upstream issue NTNU-IHB/PythonFMU#228) can corrupt the heap while the
# process tears down after its FMUs were used, aborting *after* every test has finished and
# turning a green run into exit code 134. Leave the finished session without the teardown.
_exit_status: list[int] = []


def pytest_sessionfinish(session: pytest.Session, exitstatus: int) -> None:
    _exit_status.append(int(exitstatus))


@pytest.hookimpl(trylast=True)
def pytest_unconfigure(config: pytest.Config) -> None:
    import os
    import sys

    if _exit_status:
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(_exit_status[-1])
