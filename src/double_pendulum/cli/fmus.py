"""The FMUs a command uses and the options that choose them: an FMU the user names (``--fmu``: read, never built
or written) or the project's, kept together in a build folder (``--build-dir``, else ``build/`` in the project's
folder, else ``OUT/fmu/``) and built there when missing or stale; which files ``build`` writes with them, whether
they are current, and opening them."""

from __future__ import annotations

import argparse
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..component.variables import INTERFACES
from ..fmu.build.carried_python import CarriedPythonUnavailable
from ..fmu.build.fmi2 import DEFAULT_FMU_PATH
from ..fmu.build.loader import LoaderUnavailable
from ..fmu.build.systems import build_all
from ..fmu.running.choice import FmuPathError, is_project_folder, option_fmu
from .common import CliError

BUILD_DIR_HELP = (f"the folder the project's FMUs are built and kept in, all of them, built there when one is "
                  f"missing or older than the sources (default: {DEFAULT_FMU_PATH.parent}/ in the project's folder, "
                  "elsewhere OUT/fmu/); not with --fmu")


@dataclass(frozen=True)
class FmuChoice:
    """The FMU a command runs: ``path``, and whether the user ``given`` it (``--fmu``: it is read, never built or
    written; ``description`` is its fmpy model description, checked to be the double pendulum's) or it is the
    project's, kept with the other FMUs in its folder and built there when missing or stale."""

    path: Path
    given: bool
    description: Any = None

    @property
    def folder(self) -> Path:
        """The folder of the FMU (for the project's: the build folder)."""
        return self.path.parent


def add_fmu_options(parser: argparse.ArgumentParser, fmu_help: str) -> None:
    """Add ``--fmu PATH`` (help ``fmu_help``), ``--build-dir DIR`` and ``--rebuild`` to a command's parser."""
    parser.add_argument("--fmu", default=None, metavar="PATH", help=fmu_help)
    parser.add_argument("--build-dir", default=None, metavar="DIR", help=BUILD_DIR_HELP)
    parser.add_argument("--rebuild", action="store_true",
                        help="rebuild the project's FMUs first, in the build folder (not with --fmu)")


def default_fmu_path(out: Path) -> Path:
    """Where a command keeps the FMUs unless ``--build-dir`` says: ``build/DoublePendulum.fmu`` in the project's own
    folder, elsewhere ``OUT/fmu/DoublePendulum.fmu``, so that a run from any other folder writes only into
    its ``--out`` folder."""
    if is_project_folder(Path.cwd()):
        return DEFAULT_FMU_PATH
    return out / "fmu" / DEFAULT_FMU_PATH.name


def choose_fmu(args: argparse.Namespace) -> FmuChoice:
    """The FMU the command's options name (``--fmu``, ``--build-dir``, ``--rebuild``, ``--out``), checked before
    anything is written: a given FMU must be there and be a usable FMU of the double pendulum; ``--fmu`` excludes
    ``--build-dir`` and ``--rebuild``, which would build over it. Misuse is a CliError naming the path."""
    if args.fmu is None:
        if args.build_dir is None:
            return FmuChoice(default_fmu_path(Path(args.out)), given=False)
        if not args.build_dir.strip():
            raise CliError("--build-dir needs a folder name (got an empty one); use --build-dir . for the current "
                           "folder")
        return FmuChoice(Path(args.build_dir) / DEFAULT_FMU_PATH.name, given=False)
    if args.rebuild and args.build_dir is None:
        raise CliError("--rebuild and --fmu exclude each other: --fmu runs an FMU file you have and never builds "
                       "over it (--build-dir DIR --rebuild rebuilds the project's FMUs in DIR)")
    try:
        path, description = option_fmu(args.fmu, args.build_dir)
        return FmuChoice(path, given=True, description=description)
    except FmuPathError as error:
        raise CliError(str(error)) from None


def fmu_set(fmu: Path) -> list[Path]:
    """The files ``build`` writes with the DoublePendulum FMU ``fmu``: the other FMUs next to it, the coupled
    system (SSP and container FMU) and the FMI 3.0 FMU in ``fmi3/``."""
    others = [fmu.parent / f"{name}.fmu" for name in INTERFACES if f"{name}.fmu" != fmu.name]
    systems = [fmu.parent / "PendulumOnSuspension.ssp", fmu.parent / "PendulumOnSuspension.fmu"]
    return [fmu, *others, *systems, fmu.parent / "fmi3" / fmu.name]


def fmu_set_is_current(fmu: Path) -> bool:
    """Whether ``fmu`` is newer than its sources and, for an FMU named as ``build`` names it, the rest of
    :func:`fmu_set` is there and current too (an FMU of another name is checked alone)."""
    from ..fmu.build.fmi2 import fmu_is_current

    if not fmu_is_current(fmu):
        return False
    if fmu.name != DEFAULT_FMU_PATH.name:
        return True
    from ..fmu.build.fmi3 import adapter_sources as fmi3_sources

    built = fmu.stat().st_mtime
    others = fmu_set(fmu)[1:]
    interfaces = [path for path in others if path.stem in INTERFACES and path.parent == fmu.parent]
    fmi3 = fmu.parent / "fmi3" / fmu.name  # also built from its own adapter
    return all(fmu_is_current(path, path.stem) for path in interfaces) and all(
        path.is_file() and path.stat().st_mtime >= built for path in others if path not in interfaces
    ) and all(source.stat().st_mtime <= fmi3.stat().st_mtime for source in fmi3_sources())


def build_fmus(folder: Path, rebuild: bool) -> None:
    """Build the project's FMUs (:func:`fmu_set`) in the build folder ``folder``; a failure is a CliError."""
    why = "--rebuild" if rebuild else "missing or older than the sources"
    print(f"building the FMUs in {folder} ({why}) ...", flush=True)
    try:
        build_all(folder / DEFAULT_FMU_PATH.name)
    except (LoaderUnavailable, CarriedPythonUnavailable) as error:
        raise CliError(f"cannot build the FMUs: {error}") from None
    except OSError as error:
        raise CliError(f"cannot build the FMUs in {folder}: {error.strerror or error} "
                       "(pass --build-dir DIR to build them elsewhere)") from None


def load_fmu(choice: FmuChoice, rebuild: bool):
    """Open the chosen FMU with fmpy: a given one as it is; the project's after building the FMUs in its folder if
    ``rebuild`` or if one of them is missing or stale (:func:`fmu_set_is_current`). Unusable files become a
    CliError."""
    import zipfile

    from ..fmu.running.runner import FmuRunner

    if not choice.given and (rebuild or not fmu_set_is_current(choice.path)):
        build_fmus(choice.folder, rebuild)
    hint = "" if choice.given else "; delete it or pass --rebuild"
    try:
        return FmuRunner(choice.path)
    except (zipfile.BadZipFile, KeyError, OSError) as error:
        raise CliError(f"{choice.path} is not a usable FMU ({type(error).__name__}: {error}){hint}") from None
    except Exception as error:  # fmpy's own validation errors
        raise CliError(f"{choice.path} is not a usable FMU: {error}{hint}") from None
