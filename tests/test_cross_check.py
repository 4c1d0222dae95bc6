"""``double-pendulum cross-check DIR``: the FMI Cross-Check tree (rules v4.1) of the project's FMUs, valid for
fmpy's validator, passing as fmpy imports it (fmpy.cross_check.validate_result) and, where the FMI
Compliance Checker is installed ($DOUBLE_PENDULUM_FMU_CHECKER or fmuCheck.linux64 on PATH; it is
built from modelica/FMUComplianceChecker's sources, which CI cannot fetch), running in the checker with
its input file without warning or error. The C hosts run the same cases in tests/test_reference_results.py."""

from __future__ import annotations

import zipfile
from pathlib import Path

import numpy as np
import pytest

from double_pendulum import __version__
from double_pendulum.cli import main
from double_pendulum.fmu.crosscheck.compliance_checker import find_checker, run_checker
from double_pendulum.fmu.crosscheck.reference_cases import CASES, input_names
from double_pendulum.fmu.crosscheck.tree import PLATFORM, TOOL, case_of, import_with_fmpy, model_dir, validate_tree

pytestmark = pytest.mark.filterwarnings("ignore:Please import:DeprecationWarning")  # fmpy's scipy.ndimage.filters
CHECKER = find_checker()
needs_checker = pytest.mark.skipif(CHECKER is None, reason="the FMI Compliance Checker is not installed (set "
                                   "DOUBLE_PENDULUM_FMU_CHECKER to fmuCheck.linux64, built from "
                                   "modelica/FMUComplianceChecker)")


@pytest.fixture(scope="module")
def tree(cross_check_tree: tuple[Path, int, str]) -> tuple[Path, int, str]:
    """The tree as the command writes it (into a folder that already holds another vendor's files): the session's
    run of the command (conftest.py's ``cross_check_tree``, whose FMUs tests/test_reference_results.py runs too)."""
    return cross_check_tree


def test_the_command_writes_every_case_and_fmpys_validator_finds_no_problem(tree):
    root, code, out = tree
    assert code == 0, out
    assert f"{len(CASES)} FMU folders written; fmpy's cross-check validator checked {len(CASES)}: 0 problems" in out
    assert validate_tree(root) == (len(CASES), [])
    from fmpy.cross_check.validate_vendor_repo import validate_repo

    count, results, problems = validate_repo(str(root))  # fmpy's own walk: the FMI 2.0 folders
    assert problems == [] and results == 0 and count >= sum(c.fmi_version == "2.0" for c in CASES)
    assert (root / "fmus/2.0/cs" / PLATFORM / "OtherTool/1.0/Model/keep.txt").is_file()  # others' files stay
    assert not (root / "fmus/2.0/cs" / PLATFORM / TOOL / __version__ / "Removed").exists()  # ours are anew


@pytest.mark.parametrize("case", CASES, ids=lambda c: c.folder.as_posix())
def test_each_folder_holds_what_the_rules_ask(tree, case):
    root = tree[0]
    folder = model_dir(root, case)
    assert folder == root / "fmus" / case.fmi_version / case.fmi_type / PLATFORM / TOOL / __version__ / case.model
    expected = {f"{case.model}.fmu", f"{case.model}_ref.csv", f"{case.model}_ref.opt", "ReadMe.md"}
    if input_names(case):
        expected.add(f"{case.model}_in.csv")
    assert {p.name for p in folder.iterdir()} == expected
    assert all(p.stat().st_size < (10e6 if p.suffix == ".fmu" else 1e6) for p in folder.iterdir())
    header = (folder / f"{case.model}_ref.csv").read_text().splitlines()[0]
    assert header == ",".join(f'"{n}"' for n in ("time", *case.outputs))
    with zipfile.ZipFile(folder / f"{case.model}.fmu") as z:
        assert "documentation/index.html" in z.namelist()  # the cross-check table's "Doc" column
    readme = (folder / "ReadMe.md").read_text()
    assert case.description[1:] in readme
    if case.fmi_version == "2.0":
        assert f"-n 0 -s {case.stop_time:g} -h {case.step_size:g} {case.model}.fmu" in readme
    assert case_of(folder) == case


CLOSE = 1e-7
"""How close a co-simulation import at the FMU's defaults (rtol 1e-9 where not baked in) comes to the
reference (rtol 1e-12), relative to each column's scale: measured 2.1e-12 at most for the pendulum,
3.5e-8 (fmpy) and 1.4e-8 (the checker) for the Suspension."""
ME_CLOSE = 1e-4
"""The same for a Model Exchange import: fmpy's CVode at the options' RelTol, the one that made the reference
(1e-12); CVode's own error path differs from the FMU's integrator by 1.5e-5 on the chaotic case."""


def deviation(result, reference) -> float:
    """The largest difference over the reference's columns at its times, relative to each column's scale."""
    return max(float(np.max(np.abs(np.interp(reference["time"], result["time"], result[n]) - reference[n]))
                     / max(1.0, np.max(np.abs(reference[n])))) for n in reference.dtype.names[1:])


@pytest.mark.parametrize("case", CASES, ids=lambda c: c.folder.as_posix())
def test_fmpy_as_the_importer_passes_the_cross_check_comparison(tree, case):
    from fmpy.cross_check.validate_vendor_repo import read_csv

    folder = model_dir(tree[0], case)
    result, problem = import_with_fmpy(folder)
    assert problem is None
    assert result["time"][-1] == pytest.approx(case.stop_time)
    got = deviation(result, read_csv(str(folder / f"{case.model}_ref.csv")))
    print(f"fmpy as importer, {case.folder.as_posix()}: {got:.2g} of the scale off the reference")
    # under ME CVode runs at the RelTol that made the reference (1e-12), its own error path all the same
    assert got <= (CLOSE if case.fmi_type == "cs" else ME_CLOSE)


def test_the_baked_scenes_need_no_start_value(tree):
    """fmpy's importer sets no start value: the chaotic folder's FMU starts at 2 rad by itself."""
    from fmpy.cross_check.validate_vendor_repo import read_csv

    case = next(c for c in CASES if c.model == "DoublePendulumChaotic" and c.fmi_version == "2.0")
    result, _ = import_with_fmpy(model_dir(tree[0], case))
    assert result["phi1"][0] == 2.0 and result["phi2"][0] == 2.0
    reference = read_csv(str(model_dir(tree[0], case) / f"{case.model}_ref.csv"))
    assert np.max(np.abs(result["phi1"] - reference["phi1"])) < 1e-6  # rtol 1e-12 baked in: near the reference


@needs_checker
@pytest.mark.parametrize("case", [c for c in CASES if c.fmi_version == "2.0"], ids=lambda c: c.model)
def test_the_compliance_checker_runs_every_fmi2_fmu_with_its_input_file_cleanly(tree, case, tmp_path):
    from fmpy.cross_check import validate_result
    from fmpy.cross_check.validate_vendor_repo import read_csv

    folder = model_dir(tree[0], case)
    report = run_checker(CHECKER, folder, case, tmp_path)
    assert (report.returncode, report.fmu_messages, report.warnings, report.errors, report.fatal) == (0, 0, 0, 0, 0), \
        report.log
    reference = read_csv(str(folder / f"{case.model}_ref.csv"))
    assert validate_result(report.result, reference, 0.0, case.stop_time) is None
    assert report.result.size == reference.size  # -n 0: a row at every step
    assert deviation(report.result, reference) <= CLOSE


@needs_checker
def test_a_start_value_in_the_checkers_input_file_is_refused_with_an_error_naming_it(tree, tmp_path):
    """What the FMU does with what the checker does to a fixed parameter in its input file: fmi2Error
    at the first step, naming it (the checker then ends its loop); no crash."""
    case = next(c for c in CASES if c.model == "DoublePendulum" and c.fmi_version == "2.0")
    folder = tmp_path / case.model
    folder.mkdir()
    (folder / f"{case.model}.fmu").write_bytes((model_dir(tree[0], case) / f"{case.model}.fmu").read_bytes())
    (folder / f"{case.model}_in.csv").write_text('"time","phi1_0","tau1"\n0.0,2.0,0.0\n1.0,2.0,0.0\n')
    report = run_checker(CHECKER, folder, case, tmp_path / "out")
    assert report.returncode == 1 and report.errors >= 1
    assert "fmi2SetReal: CoSimulationError: cannot set parameter phi1_0 = 2.0 after initialisation" in report.log
    assert "FMU status:Fatal" not in report.log


def test_misuse_is_one_line_and_exit_status_2(tmp_path, capsys):
    afile = tmp_path / "a_file"
    afile.write_text("")
    assert main(["cross-check", str(afile)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("double-pendulum: error: cannot write results to")
    assert main(["cross-check", str(tmp_path / "x"), "--checker", str(tmp_path / "nowhere")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--checker" in err[0] and "not an executable file" in err[0]
