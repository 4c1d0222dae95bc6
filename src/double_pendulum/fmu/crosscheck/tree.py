"""The FMI Cross-Check tree of this tool: its FMUs with their reference results, and the checks importers face.

The FMI Cross-Check (modelica/fmi-cross-check, rules v4.1) asks an exporting tool for, per FMU,
``fmus/<fmi_version>/<cs|me>/<platform>/<tool>/<version>/<Model>/`` holding ``<Model>.fmu``,
``<Model>_ref.csv``, ``<Model>_ref.opt``, ``<Model>_in.csv`` where it has inputs and a ReadMe.
:func:`write_tree` writes it for this platform (:data:`PLATFORM`) from freshly built case FMUs
(:func:`double_pendulum.fmu.crosscheck.reference_runs.build_case_fmus`) and the committed reference files
(``data/reference/fmu/``, :mod:`double_pendulum.fmu.crosscheck.reference_cases`).

The checks, as the Cross-Check runs them:

* :func:`validate_tree`: fmpy's validator of vendor repositories
  (``fmpy.cross_check.validate_vendor_repo``: its ``validate_test_fmu`` on each of this tool's folders,
  as its ``validate_repo`` runs it on every FMI 1.0 and 2.0 folder, the rules' versions; the FMI 3.0
  folders too);
* :func:`import_with_fmpy`: fmpy as an importer, run from the options and inputs as
  ``python -m fmpy.cross_check --simulate`` runs it, its result judged by
  ``fmpy.cross_check.validate_result`` (at most 10 % of the samples outside the reference's band);
* the FMI Compliance Checker with the input file: :mod:`double_pendulum.fmu.crosscheck.compliance_checker`.
"""

from __future__ import annotations

import json
import shutil
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from ... import __version__
from .reference_cases import CASES, ReferenceCase, fmu_file, input_names

TOOL = "double-pendulum-fmu"
PLATFORM = "linux64"
INTERFACE = {"cs": "CoSimulation", "me": "ModelExchange"}


def model_dir(root: str | Path, case: ReferenceCase) -> Path:
    """The case's folder in the tree under ``root``."""
    return Path(root, "fmus", case.fmi_version, case.fmi_type, PLATFORM, TOOL, __version__, case.model)


def checker_command(case: ReferenceCase, checker: str = "fmuCheck.linux64") -> str:
    """How the FMI Compliance Checker runs the case (from the model's folder; the rules' section 9.1.2). ``-f``
    prints every variable: the reference holds local diagnostics too (W_air, E_kin), which the checker's
    default, the outputs only, would leave out."""
    inputs = f" -i {case.model}_in.csv" if input_names(case) else ""
    return (f"{checker} -e {case.model}_cc.log{inputs} -o {case.model}_cc.csv -c , -f -n 0 -s {case.stop_time:g} "
            f"-h {case.step_size:g} {case.model}.fmu")


def readme(case: ReferenceCase, record: Mapping[str, Any]) -> str:
    """``ReadMe.md`` of the case's folder: what it tests, how the reference was made, how to run it."""
    made = record.get("made_with", {})
    start = ", ".join(f"{k} = {v}" for k, v in record.get("run_start_values", {}).items()) or "none (its defaults)"
    baked = ", ".join(f"{k} = {v}" for k, v in case.baked.items())
    difference = record.get("max_abs_difference_to_cs_at_rtol_1e-12")
    floor = (f" CVode's largest difference to the FMU's own integrator at rtol 1e-12 (Co-Simulation): "
             f"{difference:.2g}." if difference is not None else "")
    files = [f"`{case.model}.fmu`", f"`{case.model}_ref.csv`", f"`{case.model}_ref.opt`"]
    if input_names(case):
        files.append(f"`{case.model}_in.csv` (every input of the FMU; linear between its rows)")
    checker = (f"```\n{checker_command(case)}\n```\n\nreports `0 Warning(s)` and `0 Error(s)`: the input file holds "
               "inputs only (the FMU refuses a fixed parameter set after initialisation, which is what the checker "
               "does with every column of its input file before every step)."
               if case.fmi_version == "2.0" else
               "The FMI Compliance Checker supports FMI 1.0 and 2.0; this FMU is checked by fmpy and by the "
               "project's own C host (`tests/c_host/fmi3_host.c`).")
    return f"""# Export of {case.model}

## What it tests

{case.description[0].upper() + case.description[1:]}.

## Export tool

| | |
|--:|:--|
| tool | {TOOL} {__version__} (pythonfmu/pythonfmu3 with the project's C loader and guard) |
| FMI version | {case.fmi_version} |
| FMI variant | {INTERFACE[case.fmi_type]} |
| platform | {PLATFORM} (x86-64 Linux; the FMU needs a CPython >= 3.11 with a shared libpython) |
| start values baked into this FMU | {baked or "none: the FMU as `double-pendulum build` writes it"} |

Files: {", ".join(files)}.

## Reference result

Run in fmpy, {record.get("solver", "")}; start values set for the run: {start}.{floor}
Made with double-pendulum-fmu {made.get("double-pendulum-fmu", "")}, fmpy
{made.get("fmpy", "")}, Python {made.get("python", "")} on {made.get("platform", "")} by
`{record.get("script", "data/reference/fmu/make_fmu_references.py")}`. Columns: the time and {len(case.outputs)}
outputs. fmpy's `fmpy.cross_check.validate_result` judges an import against it.

## Compliance Checker

{checker}

## Contact

The double-pendulum-fmu project; `double-pendulum cross-check DIR` writes this folder.
"""


def write_tree(root: str | Path, fmus: Mapping[str, Path], references: str | Path) -> list[Path]:
    """Write every case's folder under ``root``: the FMU from ``fmus`` (by
    :func:`~double_pendulum.fmu.crosscheck.reference_cases.fmu_file`), the files from ``references`` (the committed
    ``data/reference/fmu``) and a ReadMe. The tool's folders are written anew; return the case folders."""
    references = Path(references)
    record = json.loads((references / "references.json").read_text(encoding="utf-8"))
    for version in {case.fmi_version for case in CASES}:
        for kind in {case.fmi_type for case in CASES}:
            shutil.rmtree(Path(root, "fmus", version, kind, PLATFORM, TOOL, __version__), ignore_errors=True)
    folders = []
    for case in CASES:
        folder = model_dir(root, case)
        folder.mkdir(parents=True)
        shutil.copyfile(fmus[fmu_file(case)], folder / f"{case.model}.fmu")
        for source in sorted((references / case.folder).glob(f"{case.model}_*")):
            shutil.copyfile(source, folder / source.name)
        (folder / "ReadMe.md").write_text(readme(case, record["cases"][case.folder.as_posix()]), encoding="utf-8")
        folders.append(folder)
    return folders


def validate_tree(root: str | Path) -> tuple[int, list[str]]:
    """fmpy's validation of this tool's folders of the tree (``validate_test_fmu``, what ``validate_repo``
    runs on each FMU folder; other vendors' folders are theirs): the number of folders and the problems."""
    from fmpy.cross_check.validate_vendor_repo import validate_test_fmu

    folders = sorted(Path(root, "fmus").glob(f"*/*/{PLATFORM}/{TOOL}/{__version__}/*"))
    problems = [problem for folder in folders for problem in validate_test_fmu(str(folder))]
    return len(folders), problems


def case_of(folder: Path) -> ReferenceCase:
    """The case of a model folder of the tree."""
    model, kind, version = folder.name, folder.parents[3].name, folder.parents[4].name
    return next(c for c in CASES if (c.fmi_version, c.fmi_type, c.model) == (version, kind, model))


def import_with_fmpy(folder: str | Path) -> tuple[Any, str | None]:
    """Run the folder's FMU in fmpy as the cross-check's importer runs it (options and inputs from the
    folder; under Model Exchange CVode at the options' RelTol) and judge it with
    ``fmpy.cross_check.validate_result``: the result and the problem (None if it passes)."""
    from fmpy import simulate_fmu
    from fmpy.cross_check import validate_result
    from fmpy.cross_check.validate_vendor_repo import read_csv
    from fmpy.util import read_ref_opt_file

    folder = Path(folder)
    model = folder.name
    options = read_ref_opt_file(str(folder / f"{model}_ref.opt"))
    reference = read_csv(str(folder / f"{model}_ref.csv"))
    inputs = folder / f"{model}_in.csv"
    me = folder.parents[3].name == "me"
    result = simulate_fmu(str(folder / f"{model}.fmu"), validate=False, step_size=options["StepSize"] or None,
                          stop_time=options["StopTime"], input=read_csv(str(inputs)) if inputs.is_file() else None,
                          output=list(reference.dtype.names[1:]), fmi_type=INTERFACE["me" if me else "cs"],
                          relative_tolerance=options["RelTol"] if me else None)
    return result, validate_result(result, reference, options["StartTime"], options["StopTime"])
