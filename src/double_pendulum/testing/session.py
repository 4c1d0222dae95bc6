"""What the plugin's hooks, fixtures and case items share: the session's FMU targets and opened FMUs (kept in
pytest's stash of the session's config), where the project's FMU is kept, and the tests' artefact folders."""

from __future__ import annotations

import re
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

import pytest

if TYPE_CHECKING:
    from .running import FmuSession, FmuTarget

TARGETS: pytest.StashKey[list[FmuTarget]] = pytest.StashKey()
SESSION: pytest.StashKey[FmuSession] = pytest.StashKey()
WRITTEN: pytest.StashKey[list[Path]] = pytest.StashKey()
"""The references ``--regen-references`` wrote in this session, for the summary at its end."""


def project_fmu(config: pytest.Config) -> Path:
    """Where the project's DoublePendulum.fmu is kept for the tests: ``build/`` in the project's own folder (as
    the README's commands keep it), elsewhere pytest's cache folder."""
    from ..fmu.build.fmi2 import DEFAULT_FMU_PATH
    from ..fmu.running.choice import is_project_folder

    if is_project_folder(config.rootpath):
        return config.rootpath / DEFAULT_FMU_PATH
    if config.cache is None:
        raise pytest.UsageError("the project's FMU is built into pytest's cache folder, which is switched off "
                                "(-p no:cacheprovider): pass --fmu PATH")
    return config.cache.mkdir("double_pendulum_fmu") / DEFAULT_FMU_PATH.name


def fmu_session(config: pytest.Config) -> FmuSession:
    """The session's opened FMUs (made when first asked for; closed when the session ends)."""
    from .running import FmuSession

    if SESSION not in config.stash:
        config.stash[SESSION] = FmuSession(lambda: project_fmu(config))
    return config.stash[SESSION]


def artefact_folder(factory: pytest.TempPathFactory, name: str) -> Callable[[], Path]:
    """A folder for a test's artefacts (plots of failed comparisons), made in pytest's temporary folder when
    first asked for."""
    made: list[Path] = []

    def folder() -> Path:
        if not made:
            made.append(factory.mktemp(re.sub(r"[^A-Za-z0-9_.-]+", "_", name)[:60] or "test", numbered=True))
        return made[0]

    return folder
