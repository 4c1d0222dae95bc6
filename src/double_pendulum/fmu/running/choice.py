"""Which FMU a command or a script runs: one the user names, which is read and never built or written, or the
project's own, built where the project keeps its FMUs when it is missing or older than the sources.

A path a user gives (``--fmu PATH``) is theirs: :func:`given_fmu` checks that it is there and
:func:`read_pendulum_fmu` that it is a usable FMU of the double pendulum, each raising :class:`FmuPathError` with
a one-line reason that names the path; nothing here writes beside it. The project's FMUs go to a folder of the
project's (:func:`is_project_folder`: ``build/`` in its own source folder) or to one the user names as a place to
build in; :func:`fmu_to_run` is the choice a script makes between the two.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any

from ...model.outputs import OUTPUT_NAMES
from ...model.parameters import InitialState
from ..build.fmi2 import DEFAULT_FMU_PATH

PENDULUM_VARIABLES = (*(spec.name for spec in dataclasses.fields(InitialState)), *OUTPUT_NAMES)
"""The variables an FMU needs for the commands to run it as the double pendulum: the start state they set and
report, and the outputs they record."""


class FmuPathError(ValueError):
    """A path given for an FMU names no usable FMU of the double pendulum; the message, one line, names the path."""


def is_project_folder(folder: Path) -> bool:
    """Whether ``folder`` is this project's own source folder (its pyproject.toml names the project), where
    the README's commands keep the FMUs in ``build/``."""
    pyproject = folder / "pyproject.toml"
    try:
        return 'name = "double-pendulum-fmu"' in pyproject.read_text(encoding="utf-8")
    except OSError:
        return False


def given_fmu(path: str | Path) -> Path:
    """``path``, an FMU file a user named, if it is there (else :class:`FmuPathError`: no such file, or a folder);
    it is only looked at, never built or written."""
    path = Path(path)
    if path.is_dir():
        raise FmuPathError(f"{path} is a folder, not an FMU file")
    if not path.is_file():
        raise FmuPathError(f"{path}: no such file")
    return path


def read_fmu_description(path: str | Path) -> Any:
    """fmpy's model description of the FMU file ``path``, any FMU's; :class:`FmuPathError` naming the path and why
    where it is not a usable FMU (not a zip, no modelDescription.xml, fmpy's validation fails)."""
    import zipfile

    from fmpy import read_model_description

    try:
        return read_model_description(str(path))
    except (zipfile.BadZipFile, KeyError, OSError) as error:
        raise FmuPathError(f"{path} is not a usable FMU ({type(error).__name__}: {error})") from None
    except Exception as error:  # fmpy's own validation errors
        raise FmuPathError(f"{path} is not a usable FMU: {' '.join(str(error).split())}") from None


def read_pendulum_fmu(path: str | Path) -> Any:
    """fmpy's model description of the FMU file ``path`` (:func:`given_fmu`), which must be usable and carry
    :data:`PENDULUM_VARIABLES` (else :class:`FmuPathError` saying why)."""
    path = given_fmu(path)
    md = read_fmu_description(path)
    names = {variable.name for variable in md.modelVariables}
    missing = [name for name in PENDULUM_VARIABLES if name not in names]
    if missing:
        shown = ", ".join(missing[:4]) + (f" and {len(missing) - 4} more" if len(missing) > 4 else "")
        raise FmuPathError(f"{path} is not an FMU of the double pendulum: its model {md.modelName!r} has no "
                           f"{shown}")
    return md


def option_fmu(fmu: str, build_dir: str | None, builds: str = "FMUs") -> tuple[Path, Any]:
    """The FMU a command's ``--fmu`` names and its model description (:func:`read_pendulum_fmu`), checked against
    ``--build-dir`` (``build_dir``), which it excludes; every refusal is a :class:`FmuPathError` of one line that
    says what each option does (``builds``: what ``--build-dir`` builds, "FMUs" or "FMU")."""
    if build_dir is not None:
        raise FmuPathError(f"--fmu and --build-dir exclude each other: --fmu runs an FMU file you have, as it is; "
                           f"--build-dir DIR builds the project's {builds} in DIR")
    try:
        path = given_fmu(fmu)
    except FmuPathError as error:
        raise FmuPathError(f"--fmu {error} (--fmu reads an FMU you have and never builds one; --build-dir DIR "
                           f"builds the project's {builds} in DIR)") from None
    return path, read_pendulum_fmu(path)


def fmu_to_run(given: str | Path | None, default: str | Path = DEFAULT_FMU_PATH) -> Path:
    """The FMU a script runs: ``given`` if the user named one (:func:`read_pendulum_fmu`: read, never built or
    written), else ``default``, a place of the project's, built there first when missing or older than the
    sources (:func:`~.runner.ensure_fmu`)."""
    from .runner import ensure_fmu

    if given is not None:
        read_pendulum_fmu(given)
        return Path(given)
    return ensure_fmu(default)
