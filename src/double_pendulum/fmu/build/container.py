"""The pendulum on its suspension as one FMU: fmpy's container FMU ``PendulumOnSuspension.fmu``.

fmpy 0.3.32 (``fmpy.container_fmu``) ships a prebuilt container binary (``container_fmu``, written
in Rust) that exports both the FMI 2.0 and the FMI 3.0 API; which one the container *exposes* is
the FMI version of the modelDescription written next to it. Here it is **FMI 2.0 co-simulation**
(``fmiVersion="2.0"``, ``binaries/linux64`` etc.), holding the two FMI 2.0 FMUs extracted under
``resources/DoublePendulum`` and ``resources/Suspension`` and described by
``resources/container.json`` (components, connections, the container's variables mapped onto
the components' value references, ``fixedStepSize`` and ``parallelDoStep``).

How it steps: ``fmi2DoStep(h)`` must be a multiple of ``fixedStepSize`` (the macro step of the
coupling, fixed when the container is written); for each of these steps it passes every
connection's source value to its destination and then steps every component (one after the
other, or on threads with ``parallelDoStep``): inputs held over the step, Jacobi.

The container exposes, as flat variables named ``<component>.<variable>``, parameters (the
pendulum's initial state, the suspension's ``M_s, k, c, F_static_y``, and whatever else the
monolith's start values split by :func:`~double_pendulum.fmu.masters.coupling.split_values` set; their
start values are those values) and the coupling and energy outputs of both components.

fmpy 0.3.32 writes a connection's ``variableType`` as the FMI 2 type name ("Real") where the
binary expects FMI 3 names ("Float64", as it writes for variables); :func:`write_container`
corrects that in ``container.json``.
"""

from __future__ import annotations

import json
import shutil
import tempfile
import uuid
import zipfile
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from ..masters.coupling import FORCE_CONNECTIONS, MOTION_CONNECTIONS, PENDULUM_OUTPUTS, SUSPENSION_OUTPUTS, split_values
from ..presets import literal

SYSTEM_NAME = "PendulumOnSuspension"
PENDULUM, SUSPENSION = "DoublePendulum", "Suspension"
FMI3_TYPES = {"Real": "Float64", "Integer": "Int32"}
PORTS = ("DoublePendulum.phi1", "DoublePendulum.phi2", "Suspension.x", "Suspension.y")
"""The container's outputs: both angles and the suspension mass's position (its documentation plot's)."""
EXPOSED_PARAMETERS = {
    PENDULUM: ("phi1_0", "phi2_0", "omega1_0", "omega2_0"),
    SUSPENSION: ("M_s", "k_x", "k_y", "c_x", "c_y", "F_static_y"),
}
"""Parameters the container always exposes (start: the value given, else the component's own start)."""
CONTAINER_BINARIES = (("x86_64-linux", "linux64", "container_fmu.so"),)
"""fmpy's container binaries the container may carry: (fmpy's folder, the FMI 2 platform, the file). Not its
Windows one: it links bcryptprimitives.dll (Rust's random numbers, Windows 10 and newer), which Wine 8 lacks, so
it could not be run here, and a platform ships only after it ran (its members carry their Windows binaries)."""


def _component(fmu: Path) -> Any:
    from fmpy import read_model_description
    from fmpy.container_fmu.config import Component

    md = read_model_description(str(fmu))
    return Component(name=md.coSimulation.modelIdentifier, filename=fmu, modelDescription=md)


def _variables(component: Any) -> dict[str, Any]:
    return {v.name: v for v in component.modelDescription.modelVariables}


def _description(macro_step: float, stop_time: float) -> Any:
    from fmpy.model_description import CoSimulation, DefaultExperiment, ModelDescription

    return ModelDescription(
        fmiVersion="2.0",
        modelName=SYSTEM_NAME,
        instantiationToken=f"{{{uuid.uuid4()}}}",
        description="DoublePendulum hanging from the Suspension mass, coupled with a fixed macro step "
        f"of {macro_step:g} s (Jacobi, inputs held over the step)",
        generationTool="double-pendulum-fmu with fmpy.container_fmu",
        coSimulation=CoSimulation(modelIdentifier="container_fmu", fixedInternalStepSize=macro_step,
                                  canHandleVariableCommunicationStepSize=True),
        defaultExperiment=DefaultExperiment(startTime="0.0", stopTime=repr(float(stop_time)),
                                            stepSize=repr(float(macro_step))),
    )


def _expose(md: Any, mappings: dict, component: Any, name: str, start: Any = None) -> None:
    """Add ``<component>.<name>`` to the container, mapped onto the component's variable."""
    from fmpy.model_description import ModelVariable, Unknown

    source = _variables(component)[name]
    is_parameter = start is not None
    # the container is a closed system: no master couples to it, so its outputs are what a user plots first
    # (CONTAINER_PORTS); whatever else it exposes is a local, recorded by name
    causality = "parameter" if is_parameter else "output" if f"{component.name}.{name}" in PORTS else "local"
    variable = ModelVariable(
        name=f"{component.name}.{name}", type=source.type, description=source.description,
        causality=causality,
        variability="fixed" if is_parameter else "continuous",
        initial="exact" if is_parameter else None, start=None if start is None else literal(start),
    )
    variable.unit = source.unit
    variable.canHandleMultipleSetPerTimeInstant = False
    md.modelVariables.append(variable)
    mappings[variable] = [(component, source)]
    if causality == "output":
        md.outputs.append(Unknown(variable=variable, dependencies=[]))
        md.initialUnknowns.append(Unknown(variable=variable, dependencies=[]))


def configuration(
    pendulum_fmu: Path, suspension_fmu: Path, values: Mapping[str, Any], macro_step: float, stop_time: float,
    pendulum_outputs: Sequence[str], suspension_outputs: Sequence[str], parallel: bool = False,
) -> Any:
    """fmpy's container :class:`~fmpy.container_fmu.config.Configuration` of the coupled system."""
    from fmpy.container_fmu.config import Configuration, Connection

    pendulum, suspension = _component(Path(pendulum_fmu)), _component(Path(suspension_fmu))
    md = _description(macro_step, stop_time)
    md.unitDefinitions = list({u.name: u for c in (pendulum, suspension)
                               for u in c.modelDescription.unitDefinitions}.values())
    mappings: dict = {}
    pendulum_values, suspension_values = split_values(values)
    for component, start, outputs in ((pendulum, pendulum_values, pendulum_outputs),
                                      (suspension, suspension_values, suspension_outputs)):
        own = _variables(component)
        for name in dict.fromkeys([*EXPOSED_PARAMETERS[component.name], *start]):
            _expose(md, mappings, component, name, start.get(name, own[name].start))
        for name in outputs:
            _expose(md, mappings, component, name)
    p_vars, s_vars = _variables(pendulum), _variables(suspension)
    connections = [Connection(pendulum, [p_vars[a]], suspension, [s_vars[b]]) for a, b in FORCE_CONNECTIONS]
    connections += [Connection(suspension, [s_vars[a]], pendulum, [p_vars[b]]) for a, b in MOTION_CONNECTIONS]
    return Configuration(parallelDoStep=parallel, modelDescription=md, components=[pendulum, suspension],
                         connections=connections, variableMappings=mappings)


def write_container(
    dest: str | Path, pendulum_fmu: str | Path, suspension_fmu: str | Path, values: Mapping[str, Any] | None = None,
    *, macro_step: float = 1e-3, stop_time: float = 10.0, pendulum_outputs: Sequence[str] = PENDULUM_OUTPUTS,
    suspension_outputs: Sequence[str] = SUSPENSION_OUTPUTS, parallel: bool = False,
    compression: int = zipfile.ZIP_DEFLATED, documented: bool = False,
) -> Path:
    """Write the container FMU at ``dest`` (FMI 2.0 co-simulation, fixed macro step ``macro_step`` [s]).

    ``compression`` is the zip method of the archive: ``zipfile.ZIP_STORED`` writes a container meant to be
    run once and removed about twice as fast (compressing the two bundled FMUs takes ~0.3 s).
    ``documented=True`` (the build's container) adds the documentation, icon and terminals
    (:mod:`double_pendulum.fmu.carries.presentation`; its result plot runs the coupled scene for 2 s in-process).
    """
    from fmpy.container_fmu import write_configuration
    from fmpy.model_description import write_model_description

    dest = Path(dest)
    dest.parent.mkdir(parents=True, exist_ok=True)
    config = configuration(Path(pendulum_fmu), Path(suspension_fmu), values or {}, macro_step, stop_time,
                           pendulum_outputs, suspension_outputs, parallel)
    for index, variable in enumerate(config.modelDescription.modelVariables):
        variable.valueReference = index + 1  # the binary reserves 0 (time, as in FMI 3)
    binaries = Path(__import__("fmpy.container_fmu", fromlist=["x"]).__file__).parent / "binaries"
    with tempfile.TemporaryDirectory(prefix="dp_container_") as tmp:
        root = Path(tmp)
        for component in config.components:
            with zipfile.ZipFile(component.filename) as archive:
                archive.extractall(root / "resources" / Path(component.filename).stem)
        write_model_description(config.modelDescription, root / "modelDescription.xml")
        write_configuration(config, root / "resources" / "container.json")
        _fix_connection_types(root / "resources" / "container.json")
        # fmpy's container binary only for the platforms every member has a binary for (never macOS), and where it
        # ran (CONTAINER_BINARIES): a container claims to run only where all of it can
        for platform_tuple, fmi2_platform, library in CONTAINER_BINARIES:
            if all((root / "resources" / Path(component.filename).stem / "binaries" / fmi2_platform).is_dir()
                   for component in config.components):
                (root / "binaries" / fmi2_platform).mkdir(parents=True, exist_ok=True)
                shutil.copyfile(binaries / platform_tuple / library, root / "binaries" / fmi2_platform / library)
        if documented:
            _add_presentation(root)
        tmp_fmu = dest.with_suffix(".fmu.tmp")
        with zipfile.ZipFile(tmp_fmu, "w", compression) as archive:
            for path in sorted(root.rglob("*")):
                if path.is_file():
                    archive.write(path, path.relative_to(root).as_posix())
        tmp_fmu.replace(dest)
    return dest


def _add_presentation(root: Path) -> None:
    """Write the container's documentation, icon and terminals into the folder ``root`` it is zipped from."""
    from ..carries.presentation import CONTAINER, presentation_files

    files = {path.relative_to(root).as_posix(): path.read_bytes() for path in root.rglob("*")
             if path.is_file() and (path.name in ("modelDescription.xml", "python.cfg", "bundle.json")
                                   or "binaries" in path.parts)}
    for name, data in presentation_files(CONTAINER, 2, files).items():
        (root / name).parent.mkdir(parents=True, exist_ok=True)
        (root / name).write_bytes(data)


def _fix_connection_types(path: Path) -> None:
    """Write the connections' FMI 2 type names as the container binary's FMI 3 names (Real -> Float64)."""
    data = json.loads(path.read_text(encoding="utf-8"))
    for connection in data["connections"]:
        connection["variableType"] = FMI3_TYPES.get(connection["variableType"], connection["variableType"])
    path.write_text(json.dumps(data, indent=2), encoding="utf-8")
