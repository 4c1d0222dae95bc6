"""The reference cases' FMUs, their reference runs in fmpy and their files (_ref.csv, _in.csv, _ref.opt).

:func:`build_case_fmus` builds every FMU the cases run (:mod:`double_pendulum.fmu.crosscheck.reference_cases`):
the FMUs as ``double-pendulum build`` writes them, the ones with a scene baked in, the container.
:func:`reference_run` is a case's run in fmpy at tight tolerance (the FMU's integrator at
:data:`~double_pendulum.fmu.crosscheck.reference_cases.TIGHT`, or CVode at
:data:`~double_pendulum.fmu.crosscheck.reference_cases.ME_REFERENCE_TOLERANCE`); :func:`write_case_files` writes
it in the FMI Cross-Check's formats (rules v4.1, appendix B: a header of quoted names, time first,
numbers as C literals, no units). ``data/reference/fmu/make_fmu_references.py`` writes the committed set
and its record ``references.json`` (:func:`provenance`).
"""

from __future__ import annotations

import json
import platform
import sys
from collections.abc import Mapping, Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from ... import __version__
from .reference_cases import (
    CASES,
    CONTAINER_VALUES,
    ME_REFERENCE_TOLERANCE,
    TIGHT,
    ReferenceCase,
    fmu_file,
    input_names,
)
from .reference_cases import input_table as case_input_table

RECORD = "references.json"


TREE_PLATFORMS = ("x86_64-linux",)
"""The cross-check tree's FMUs carry the CPython of the platform whose folder they lie in (``linux64``, where their
reference results were made): one FMU for both platforms would exceed the rules' 10 MB."""


def build_case_fmus(folder: str | Path) -> dict[str, Path]:
    """Build every FMU the cases run into ``folder``, as
    :func:`~double_pendulum.fmu.crosscheck.reference_cases.fmu_file` names them (``2.0/DoublePendulum.fmu``,
    ``3.0/DoublePendulumChaotic.fmu``, ...), self-contained for Linux (:data:`TREE_PLATFORMS`); return them by
    that name."""
    from ..build.container import write_container
    from ..build.fmi2 import build_fmu
    from ..build.fmi3 import build_fmu3

    folder = Path(folder)
    built: dict[str, Path] = {}
    for case in CASES:
        name = fmu_file(case)
        if name in built:
            continue
        path = folder / name
        if case.source == "PendulumOnSuspension":
            continue  # below, from the two FMUs as built
        if case.fmi_version == "2.0":
            built[name] = build_fmu(path, case.source, case.baked, platforms=TREE_PLATFORMS)
        else:
            built[name] = build_fmu3(path, case.baked, platforms=TREE_PLATFORMS)
    for case in CASES:
        if case.source == "PendulumOnSuspension":
            built[fmu_file(case)] = write_container(folder / fmu_file(case), built["2.0/DoublePendulum.fmu"],
                                                    built["2.0/Suspension.fmu"], CONTAINER_VALUES, documented=True)
    return built


def input_signals(case: ReferenceCase) -> np.ndarray | None:
    """The case's inputs as fmpy's ``simulate_fmu(input=...)`` takes them (a structured array), or None."""
    rows = case_input_table(case)
    if rows is None:
        return None
    dtype = [("time", np.float64)] + [(name, np.float64) for name in input_names(case)]
    return np.array(rows, dtype=dtype)


def reference_run(case: ReferenceCase, fmu: str | Path, start_values: Mapping[str, Any] | None = None) -> np.ndarray:
    """The case's reference: its FMU in fmpy with the case's inputs, a row every ``step_size`` from 0 to the
    stop time; under Co-Simulation the FMU's integrator at tight tolerance (``reference_start``), under
    Model Exchange fmpy's CVode at :data:`ME_REFERENCE_TOLERANCE`. ``start_values`` replace
    ``reference_start``."""
    from fmpy import simulate_fmu

    me = case.fmi_type == "me"
    values = dict(case.reference_start if start_values is None else start_values)
    return simulate_fmu(str(fmu), start_values=values, stop_time=case.stop_time, output_interval=case.step_size,
                        step_size=case.step_size if me else None, input=input_signals(case), output=list(case.outputs),
                        fmi_type="ModelExchange" if me else "CoSimulation", solver="CVode",
                        relative_tolerance=ME_REFERENCE_TOLERANCE if me else None, validate=False)


def csv_text(names: Sequence[str], rows: Sequence[Sequence[float]]) -> str:
    """The Cross-Check's CSV: quoted names, then one row per line, shortest exact literals (``repr``)."""
    header = ",".join(f'"{name}"' for name in names)
    return header + "\n" + "".join(",".join(repr(float(v)) for v in row) + "\n" for row in rows)


def opt_text(case: ReferenceCase) -> str:
    """``_ref.opt``: StartTime, StopTime, StepSize, RelTol (the rules' required elements)."""
    return (f"StartTime,0.0\nStopTime,{case.stop_time!r}\nStepSize,{case.step_size!r}\nRelTol,{case.rel_tol!r}\n")


def input_csv(case: ReferenceCase) -> str | None:
    """``_in.csv`` of the case, or None (an FMU without inputs)."""
    rows = case_input_table(case)
    return None if rows is None else csv_text(["time", *input_names(case)], rows)


def write_case_files(folder: str | Path, case: ReferenceCase, result: np.ndarray) -> list[Path]:
    """Write ``<model>_ref.csv`` (from ``result``), ``<model>_ref.opt`` and ``<model>_in.csv`` into ``folder``."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    names = ["time", *case.outputs]
    files = {f"{case.model}_ref.csv": csv_text(names, [[row[n] for n in names] for row in result]),
             f"{case.model}_ref.opt": opt_text(case)}
    inputs = input_csv(case)
    if inputs is not None:
        files[f"{case.model}_in.csv"] = inputs
    for name, text in files.items():
        (folder / name).write_text(text, encoding="utf-8")
    return [folder / name for name in files]


def provenance(case: ReferenceCase) -> dict[str, Any]:
    """What produced a case's reference: the FMU, the start values of the run, the solver, the versions."""
    import fmpy

    me = case.fmi_type == "me"
    return {
        "fmu": f"{case.model}.fmu, {'built as' if case.source != 'PendulumOnSuspension' else 'the container of'} "
               f"{case.source} (FMI {case.fmi_version})",
        "baked_start_values": dict(case.baked),
        "run_start_values": dict(case.reference_start),
        "solver": (f"fmpy's CVode, relative tolerance {ME_REFERENCE_TOLERANCE:g}, output every {case.step_size:g} s"
                   if me else f"the FMU's own integrator, a doStep every {case.step_size:g} s"),
        "inputs": f"{case.model}_in.csv" if input_names(case) else None,
        "description": case.description,
        "made_with": {"double-pendulum-fmu": __version__, "fmpy": fmpy.__version__, "numpy": np.__version__,
                      "python": platform.python_version(), "platform": f"{sys.platform} {platform.machine()}"},
    }


def write_references(out: str | Path, fmus: Mapping[str, Path]) -> dict[str, Any]:
    """Run every case on the built ``fmus`` (:func:`build_case_fmus`) and write its files under
    ``out/<fmi_version>/<fmi_type>/<model>/``, and the record :data:`RECORD`; return the record."""
    out = Path(out)
    record = {"script": "data/reference/fmu/make_fmu_references.py", "cases": {}}
    for case in CASES:
        result = reference_run(case, fmus[fmu_file(case)])
        write_case_files(out / case.folder, case, result)
        record["cases"][case.folder.as_posix()] = provenance(case)
        if case.fmi_type == "me":  # CVode's own error: against the FMU's integrator at rtol 1e-12 (CS)
            own = reference_run(replace(case, fmi_type="cs"), fmus[fmu_file(case)], {**case.reference_start, **TIGHT})
            record["cases"][case.folder.as_posix()]["max_abs_difference_to_cs_at_rtol_1e-12"] = max(
                float(np.max(np.abs(result[name] - own[name]))) for name in case.outputs)
    (out / RECORD).write_text(json.dumps(record, indent=2) + "\n", encoding="utf-8")
    return record


def read_reference(folder: str | Path, case: ReferenceCase) -> np.ndarray:
    """A committed ``_ref.csv`` as a structured array (fmpy's cross-check reader, which checks the format)."""
    from fmpy.cross_check.validate_vendor_repo import read_csv

    return read_csv(str(Path(folder) / case.folder / f"{case.model}_ref.csv"))
