"""Results and references as the plugin's fixtures hand them to a test: named columns with units.

A :class:`Result` is fmpy's structured array (``time`` first, then a column a variable) with the unit of each
column and where it came from: a run of the FMU (:mod:`.running`), the FMU's own reference result, or a CSV file
of the user's. The reference result is laid out as the layered standard ``fmi-ls-ref`` says and the project's FMUs
carry it (:mod:`double_pendulum.fmu.carries.reference_result`)::

    extra/org.fmi-standard.fmi-ls-ref/fmi-ls-manifest.xml   a <Related role="result" source="..."/> names the CSV
    extra/org.fmi-standard.fmi-ls-ref/<model>_out.csv       time and the outputs of the default experiment

:func:`write_reference` writes a result in that layout into a folder the user names (``--regen-references DIR``),
never into an FMU.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any
from xml.etree import ElementTree as ET

import numpy as np

from ..fmu.carries.reference_result import FOLDER, MANIFEST, csv_text, manifest


class MissingReference(LookupError):
    """No reference result where one was looked for; the message names the place and says how to make one."""


@dataclasses.dataclass(frozen=True, repr=False)
class Result:
    """Columns of a run or a reference: ``data`` (a structured array, ``time`` [s] first), ``units`` by column
    name, ``label`` (what it is, for messages and plots) and ``experiment`` (start time, stop time and output
    interval [s], and the start values, where known). ``artefacts`` gives the folder where an assertion keeps
    what it saves for the test that holds this result (pytest's tmp path of that test), ``None`` outside one."""

    data: np.ndarray
    units: Mapping[str, str]
    label: str
    experiment: Mapping[str, Any] = dataclasses.field(default_factory=dict)
    artefacts: Callable[[], Path] | None = None

    def __repr__(self) -> str:
        columns = ", ".join(f"{n} [{self.unit(n)}]" if self.unit(n) else n for n in self.names[:6])
        more = f" and {len(self.names) - 6} more" if len(self.names) > 6 else ""
        span = f"t = {self.time[0]:g} to {self.time[-1]:g} s" if len(self) else "no rows"
        return f"<Result {self.label}: {len(self)} rows, {span}; {columns}{more}>"

    @property
    def time(self) -> np.ndarray:
        """The time column [s]."""
        return self.data["time"]

    @property
    def names(self) -> tuple[str, ...]:
        """The variables' columns, ``time`` left out."""
        return tuple(name for name in self.data.dtype.names if name != "time")

    def __getitem__(self, name: str) -> np.ndarray:
        if name not in self.data.dtype.names:
            raise KeyError(f"{self.label} has no column {name!r}; it has {', '.join(self.data.dtype.names)}")
        return self.data[name]

    def __contains__(self, name: object) -> bool:
        return name in self.data.dtype.names

    def __len__(self) -> int:
        return len(self.data)

    def unit(self, name: str) -> str:
        """The unit of column ``name`` (``""`` where none is known)."""
        return self.units.get(name, "")

    def for_test(self, artefacts: Callable[[], Path] | None) -> Result:
        """The same columns (not copied) with the artefact folder of another test."""
        return dataclasses.replace(self, artefacts=artefacts)


def read_csv_result(path: str | Path, units: Mapping[str, str] | None = None, label: str | None = None) -> Result:
    """A CSV file as the FMI Cross-Check and fmpy write it (a header ``time,<names>``, then numbers), read by
    :func:`fmpy.util.read_csv`; ``units`` by column where the file's reader knows them."""
    from fmpy.util import read_csv

    path = Path(path)
    if not path.is_file():
        raise MissingReference(f"{path}: no such file")
    try:
        data = read_csv(str(path))
    except (ValueError, IndexError) as error:
        raise MissingReference(f"{path} is not a CSV file of numbers under a header time,<names> ({error})") from None
    if data.dtype.names is None or data.dtype.names[0] != "time":
        raise MissingReference(f"{path}: the first column must be time, not {data.dtype.names[0]!r}")
    return Result(data, dict(units or {}), label or path.name, experiment=_experiment_of(data))


def _experiment_of(data: np.ndarray, **more: Any) -> dict[str, Any]:
    """Start and stop time and output interval [s] of a result's time column (and ``more``)."""
    time = data["time"]
    interval = float(time[1] - time[0]) if len(time) > 1 else 0.0
    return {"start_time": float(time[0]), "stop_time": float(time[-1]), "output_interval": interval, **more}


def reference_in_folder(folder: str | Path, units: Mapping[str, str] | None = None,
                        label: str | None = None) -> Result:
    """The reference result under ``folder`` (an extracted FMU, or a folder :func:`write_reference` wrote): the CSV
    that ``extra/org.fmi-standard.fmi-ls-ref/fmi-ls-manifest.xml`` names as its result, with the manifest's
    description in the experiment. :class:`MissingReference` where there is none."""
    folder = Path(folder)
    path = folder / MANIFEST
    if not path.is_file():
        raise MissingReference(f"{folder} holds no reference result ({MANIFEST} is missing)")
    root = ET.parse(path).getroot()
    related = [r for r in root.iter("Related") if r.get("role") == "result" and r.get("type") == "text/csv"]
    if not related:
        raise MissingReference(f"{path} names no result (no <Related role=\"result\" type=\"text/csv\">)")
    csv = folder / FOLDER / related[0].get("source", "")
    result = read_csv_result(csv, units, label or f"reference {related[0].get('source')}")
    experiment = {**result.experiment, "description": related[0].get("description", "")}
    return dataclasses.replace(result, experiment=experiment)


def write_reference(result: Result, folder: str | Path, model: str, description: str) -> Path:
    """Write ``result`` into ``folder`` as an FMU carries its reference (``extra/org.fmi-standard.fmi-ls-ref/``:
    the manifest and ``<model>_out.csv``, 17 significant digits); returns the CSV's path. Only ``folder`` is
    written, each file replaced whole."""
    target = Path(folder) / FOLDER
    target.mkdir(parents=True, exist_ok=True)
    rows = {name: [float(v) for v in result.data[name]] for name in ("time", *result.names)}
    step = float(result.experiment.get("output_interval") or 0.0)
    files = {Path(folder) / MANIFEST: manifest(model, step, description),
             target / f"{model}_out.csv": csv_text(rows).encode()}
    for path, content in files.items():
        partial = path.with_name(path.name + ".partial")
        partial.write_bytes(content)
        partial.replace(path)
    return target / f"{model}_out.csv"
