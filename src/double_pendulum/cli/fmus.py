"""The FMUs a command uses: where they are kept unless ``--fmu`` says, which files ``build`` writes with them,
whether they are current, and opening them (built first if missing or stale)."""

from __future__ import annotations

from pathlib import Path

from ..component.variables import INTERFACES
from ..fmu.build.fmi2 import DEFAULT_FMU_PATH
from ..fmu.build.loader import LoaderUnavailable
from ..fmu.build.systems import build_all
from .common import CliError


def is_project_folder(folder: Path) -> bool:
    """Whether ``folder`` is this project's own source folder (its pyproject.toml names the project), where
    the README's commands keep the FMUs in ``build/``."""
    pyproject = folder / "pyproject.toml"
    try:
        return 'name = "double-pendulum-fmu"' in pyproject.read_text(encoding="utf-8")
    except OSError:
        return False


def default_fmu_path(out: Path) -> Path:
    """Where ``run`` keeps the FMUs unless ``--fmu`` says: ``build/DoublePendulum.fmu`` in the project's own
    folder, elsewhere ``OUT/fmu/DoublePendulum.fmu``, so that a run from any other folder writes only into
    its ``--out`` folder."""
    if is_project_folder(Path.cwd()):
        return DEFAULT_FMU_PATH
    return out / "fmu" / DEFAULT_FMU_PATH.name


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


def load_fmu(path: str, rebuild: bool):
    """Build the FMUs if the FMU or the rest of its set is missing or stale (:func:`fmu_set_is_current`), then
    open the FMU with fmpy; unusable files become a CliError."""
    import zipfile

    from ..fmu.running.runner import FmuRunner

    fmu = Path(path)
    if rebuild or not fmu_set_is_current(fmu):
        print(f"building the FMUs next to {fmu} (missing or older than the sources) ...", flush=True)
        try:
            build_all(fmu)
        except LoaderUnavailable as error:
            raise CliError(f"cannot build the FMUs: {error}") from None
        except OSError as error:
            raise CliError(f"cannot build the FMU at {fmu}: {error.strerror or error} "
                           "(pass --fmu PATH to build it elsewhere)") from None
    try:
        return FmuRunner(fmu)
    except (zipfile.BadZipFile, KeyError, OSError) as error:
        raise CliError(f"{fmu} is not a usable FMU ({type(error).__name__}: {error}); "
                       "delete it or pass --rebuild") from None
    except Exception as error:  # fmpy's own validation errors
        raise CliError(f"{fmu} is not a usable FMU: {error}") from None
