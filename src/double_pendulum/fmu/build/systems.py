"""Build every FMU of the project and the coupled system written from them.

:func:`build_all` builds ``DoublePendulum`` and ``Suspension`` (FMI 2.0, :mod:`double_pendulum.fmu.build.fmi2`), the
FMI 3.0 ``DoublePendulum`` (:mod:`double_pendulum.fmu.build.fmi3`) and, from the first two,
``PendulumOnSuspension`` as an SSP (:mod:`double_pendulum.fmu.build.ssp`) and as fmpy's container FMU
(:mod:`double_pendulum.fmu.build.container`).
"""

from __future__ import annotations

from pathlib import Path

from ...component.variables import INTERFACES, MODEL_IDENTIFIER
from .carried_python import PLATFORMS
from .fmi2 import DEFAULT_FMU_PATH, build_fmu


def build_all(dest: str | Path = DEFAULT_FMU_PATH, lean: bool = False,
              platforms: tuple[str, ...] = PLATFORMS) -> list[Path]:
    """Build every FMU: ``DoublePendulum`` at ``dest`` (a ``.fmu`` path or a folder), the others next to it,
    then the coupled system (:func:`build_systems`), then the FMI 3.0 ``DoublePendulum`` in the
    subfolder ``fmi3/`` (:func:`double_pendulum.fmu.build.fmi3.build_fmu3`). Self-contained (each carries a CPython
    for each of ``platforms``: Linux and Windows), or ``lean`` (Linux only, a CPython needed where they run)."""
    from .fmi3 import build_fmu3

    dest = Path(dest)
    first = build_fmu(dest, MODEL_IDENTIFIER, lean=lean, platforms=platforms)
    others = [build_fmu(first.parent / f"{name}.fmu", name, lean=lean, platforms=platforms) for name in INTERFACES
              if name != MODEL_IDENTIFIER]
    fmi3 = build_fmu3(first.parent / "fmi3" / f"{MODEL_IDENTIFIER}.fmu", lean=lean, platforms=platforms)
    return [first, *others, *build_systems(first), fmi3]


def build_systems(
    pendulum_fmu: str | Path, values: dict | None = None, macro_step: float = 1e-3
) -> list[Path]:
    """Write the coupled system next to the built FMUs: ``PendulumOnSuspension.ssp`` (SSP, for libcosim)
    and ``PendulumOnSuspension.fmu`` (fmpy's container FMU, FMI 2.0), macro step ``macro_step`` [s].

    ``pendulum_fmu``: the DoublePendulum FMU; ``Suspension.fmu`` is expected next to it.
    """
    from .container import write_container
    from .ssp import write_ssp

    folder = Path(pendulum_fmu).parent
    fmus = (Path(pendulum_fmu), folder / "Suspension.fmu")
    return [
        write_ssp(folder / "PendulumOnSuspension.ssp", *fmus, values, macro_step=macro_step, reference=True),
        write_container(folder / "PendulumOnSuspension.fmu", *fmus, values, macro_step=macro_step, documented=True),
    ]
