"""The FMUs a test session runs: which ones (:class:`FmuTarget`), each opened once (:class:`Fmu`: its model
description, its variables with units, its extracted folder) and its runs through fmpy, kept per argument set.

An FMU named with ``--fmu PATH`` is only read; without one the tests run the project's ``DoublePendulum.fmu``,
built first where it is missing or older than the sources, as a script does
(:func:`double_pendulum.fmu.running.choice.fmu_to_run`). Runs go through :func:`fmpy.simulate_fmu` by the project's
:class:`~double_pendulum.fmu.running.runner.FmuRunner`, which extracts the FMU once and collects what it logs: a run
that fails raises :class:`SimulationFailed` with the FMU's messages.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ..fmu.running.choice import fmu_to_run, read_fmu_description
from ..fmu.running.runner import FmuRunError, FmuRunner
from .results import MissingReference, Result, reference_in_folder

INTERFACES = {"CS": "CoSimulation", "ME": "ModelExchange"}
"""The interfaces an FMU may have, by the short name the marker and ``--fmu-interface`` use, as fmpy names them."""


class SimulationFailed(RuntimeError):
    """A run of an FMU failed: the message says which FMU, with which arguments, and what the FMU logged."""


@dataclasses.dataclass(frozen=True)
class FmuTarget:
    """One FMU file and one of its interfaces, a parameter of the ``fmu`` fixture: ``path`` (``None``: the
    project's DoublePendulum.fmu, built when first used), ``interface`` (``"CS"`` or ``"ME"``), ``fmi_version``
    (``"2.0"``, ``"3.0"``) and ``model`` (the model name)."""

    path: Path | None
    interface: str
    fmi_version: str
    model: str
    stem: str | None = None

    @property
    def id(self) -> str:
        """The test id: the file's stem (or ``stem``), the FMI version's major and the interface
        (``DoublePendulum-fmi2-CS``)."""
        stem = self.stem or (self.path.stem if self.path is not None else self.model)
        return f"{stem}-fmi{self.fmi_version.split('.')[0]}-{self.interface}"


def targets_of(path: Path) -> list[FmuTarget]:
    """Every interface of the FMU file ``path`` as a target (its model description read, nothing extracted);
    ``ValueError`` (:class:`~double_pendulum.fmu.running.choice.FmuPathError`) saying why where it is not a usable
    FMU."""
    md = read_fmu_description(path)
    return [FmuTarget(path, short, md.fmiVersion, md.modelName)
            for short, attribute in (("CS", "coSimulation"), ("ME", "modelExchange"))
            if getattr(md, attribute) is not None]


PROJECT_TARGET = FmuTarget(None, "CS", "2.0", "DoublePendulum")
"""The project's DoublePendulum.fmu (FMI 2.0, Co-Simulation), the target without ``--fmu``."""


class Fmu:
    """An FMU opened for the session: ``path``, ``interface`` and ``fmi_version`` of its target,
    ``model_description`` (:func:`fmpy.read_model_description`), ``variables`` (fmpy's variables by name),
    ``units`` (each variable's unit, ``""`` where it has none), ``folder`` (where it is extracted, removed at the
    end of the session) and :attr:`experiment` (its default experiment)."""

    def __init__(self, target: FmuTarget, path: Path) -> None:
        self.target = target
        self.path = path
        self.interface = target.interface
        self.fmi_version = target.fmi_version
        self._runner = FmuRunner(path)
        self.model_description = self._runner.model_description
        self.variables = {v.name: v for v in self.model_description.modelVariables}
        self.units: dict[str, str] = dict(self._runner.units)
        self.folder = Path(self._runner.unzipdir)
        self._runs: dict[str, Result] = {}

    @property
    def name(self) -> str:
        """The model's name (``DoublePendulum``)."""
        return str(self.model_description.modelName)

    @property
    def outputs(self) -> list[str]:
        """The names of the variables of causality output."""
        return [name for name, v in self.variables.items() if v.causality == "output"]

    @property
    def experiment(self) -> dict[str, float | None]:
        """The FMU's default experiment: start and stop time, step size [s] and tolerance (``None`` where unset)."""
        experiment = self.model_description.defaultExperiment

        def value(name: str) -> float | None:
            text = getattr(experiment, name, None) if experiment is not None else None
            return float(text) if text not in (None, "") else None

        return {"start_time": value("startTime"), "stop_time": value("stopTime"), "step_size": value("stepSize"),
                "tolerance": value("tolerance")}

    def start_value(self, name: str) -> Any:
        """The start value the FMU declares for variable ``name`` (as fmpy reads it: a string)."""
        return self.variables[name].start

    def __repr__(self) -> str:
        return f"<Fmu {self.path} {self.interface} FMI {self.fmi_version}>"

    def simulate(self, start_values: Mapping[str, Any] | None = None, stop_time: float | None = None,
                 output_interval: float | None = None, inputs: np.ndarray | None = None,
                 outputs: Sequence[str] | None = None, start_time: float | None = None,
                 **fmpy_options: Any) -> Result:
        """Run the FMU through :func:`fmpy.simulate_fmu` under its target's interface and return the columns
        ``time`` and ``outputs`` (default: every output) with their units; the same arguments within a session
        give the same :class:`Result`, run once. ``stop_time`` and ``output_interval`` [s] default to the default
        experiment's stop time and step size (10 s and stop/500 where it has none); ``inputs``: fmpy's structured
        input array. A failed run raises :class:`SimulationFailed` with the FMU's messages."""
        __tracebackhide__ = True  # pytest shows the test's line
        experiment = self.experiment
        start = float(start_time if start_time is not None else experiment["start_time"] or 0.0)
        stop = float(stop_time if stop_time is not None else experiment["stop_time"] or start + 10.0)
        interval = float(output_interval if output_interval is not None
                         else experiment["step_size"] or (stop - start) / 500)
        names = list(outputs) if outputs is not None else self.outputs
        unknown = [name for name in [*names, *(start_values or {})] if name not in self.variables]
        if unknown:
            raise KeyError(f"{self.path.name} has no variable {', '.join(map(repr, unknown))}")
        arguments = {"start_values": dict(start_values or {}), "stop_time": stop, "output_interval": interval,
                     "outputs": names, "start_time": start, **fmpy_options}
        key = _key(arguments, inputs)
        if key not in self._runs:
            options = dict(fmpy_options)
            if inputs is not None:
                options["input"] = inputs
            try:
                data = self._runner.simulate(dict(start_values or {}), stop_time=stop, output_interval=interval,
                                             start_time=start, outputs=names,
                                             fmi_type=INTERFACES[self.interface], **options)
            except FmuRunError as error:
                raise SimulationFailed(f"{self.path.name} ({self.interface}, FMI {self.fmi_version}): simulate("
                                       f"{_shown(arguments)}) failed: {error}") from None
            data.flags.writeable = False  # shared by every test that asks for this run: none may change it
            units = {name: self.units.get(name, "") for name in ("time", *names)}
            units["time"] = units["time"] or "s"
            self._runs[key] = Result(data, units, f"{self.path.name} {self.interface}",
                                     experiment={"start_time": start, "stop_time": stop, "output_interval": interval,
                                                 "start_values": dict(start_values or {})})
        return self._runs[key]

    def reference(self) -> Result:
        """The FMU's own reference result (``extra/org.fmi-standard.fmi-ls-ref/``) with the units of its columns
        and the default experiment; :class:`~.results.MissingReference` where it carries none."""
        try:
            result = reference_in_folder(self.folder, self.units, label=f"{self.path.name}'s reference")
        except MissingReference as error:
            raise MissingReference(f"{self.path.name} carries no reference result: {error}") from None
        return dataclasses.replace(result, experiment={**self.experiment, **result.experiment})

    def close(self) -> None:
        """Remove the extracted folder (and free the instance runs reuse)."""
        self._runner.close()


def _key(arguments: Mapping[str, Any], inputs: np.ndarray | None) -> str:
    """The cache key of a run: its arguments as JSON, and a hash of the input signals."""
    text = json.dumps(arguments, sort_keys=True, default=repr)
    if inputs is not None:
        text += hashlib.sha256(repr(inputs.dtype.descr).encode() + inputs.tobytes()).hexdigest()
    return text


def _shown(arguments: Mapping[str, Any]) -> str:
    return ", ".join(f"{name}={value!r}" for name, value in arguments.items() if value not in ({}, None))


class FmuSession:
    """The FMUs of one test session, each file opened once (:meth:`open`) and closed by :meth:`close`;
    ``project_fmu`` says where the project's FMU is kept (called when first needed)."""

    def __init__(self, project_fmu: Callable[[], Path]) -> None:
        self._project_fmu = project_fmu
        self._open: dict[FmuTarget, Fmu] = {}

    def open(self, target: FmuTarget) -> Fmu:
        """The opened FMU of ``target`` (the project's built first where it is missing or stale)."""
        if target not in self._open:
            path = target.path if target.path is not None else fmu_to_run(None, self._project_fmu())
            self._open[target] = Fmu(target, Path(path))
        return self._open[target]

    def close(self) -> None:
        """Close every FMU opened: their extracted folders are removed."""
        for fmu in self._open.values():
            fmu.close()
        self._open.clear()
