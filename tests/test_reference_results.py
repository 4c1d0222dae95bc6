"""The committed reference results (data/reference/fmu/, double_pendulum.fmu.crosscheck.reference_cases): freshly built
FMUs (those of the session's ``double-pendulum cross-check`` tree, tests/conftest.py) reproduce them in fmpy and in
the project's C hosts (tests/c_host, no Python in them), and the committed inputs and options are what the case
definitions write.

Stated tolerances, per output column, relative to the column's largest magnitude (at least 1):
fmpy and the C hosts under Co-Simulation run the same FMU code on the same communication grid,
REPRODUCE = 1e-9 (they agree to rounding; the margin covers another machine's libm through 3 s of
chaos); the C host's Model Exchange integrates with its own RK4 against CVode at rtol 1e-12 (RK4_ME):
1e-6 for the free swing, 1e-4 for the chaotic case, at a millisecond (ME_SUBSTEPS; measured 1.5e-9 and
3.9e-6, at a quarter of a millisecond 4.5e-10 and 1.6e-7: CVode's own error and RK4's h^4), and 3e-3
with friction at a quarter of a millisecond, where the regularised friction torque switches within about
omega_reg / (angular acceleration), 1e-4 s, as the pendulum leaves rest: a fixed-step RK4 steps over it
(1e-6 rad/s after 10 ms, grown to 4.6e-4 relative over 5 s in the angles and rates, the same at 0.125 ms
steps; 1.3e-3 in the pivot force, which carries the accelerations the switch acts on), CVode resolves
it; how far it lands depends on where the steps fall, not monotonically on their size (0.5 ms and 1 ms:
1.9e-2 and 5.5e-3, over the tolerance), so that case keeps its 0.25 ms. Each test prints what it measured.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from double_pendulum.data import data_path
from host_binaries import compiled_host

from double_pendulum.fmu.build import loader
from double_pendulum.fmu.crosscheck.reference_cases import CASES, ReferenceCase, fmu_file, input_names
from double_pendulum.fmu.crosscheck.reference_runs import (
    RECORD,
    input_csv,
    opt_text,
    read_reference,
    reference_run,
)
from double_pendulum.fmu.crosscheck.tree import model_dir

pytestmark = pytest.mark.filterwarnings("ignore:Please import:DeprecationWarning")  # fmpy's scipy.ndimage.filters
REFERENCES = Path(str(data_path("reference/fmu")))
REPRODUCE = 1e-9
RK4_ME = {"DoublePendulumChaotic": 1e-4, "DoublePendulumFriction": 3e-3}
RK4_ME_DEFAULT = 1e-6
# RK4 steps of the C host per output interval (10 ms) under Model Exchange, by model: 1 ms; 0.25 ms with friction
ME_SUBSTEPS = {"DoublePendulumFriction": 40}
ME_SUBSTEPS_DEFAULT = 10
HOST_SOURCES = {"2.0": "fmi2_host.c", "3.0": "fmi3_host.c"}


def case_id(case: ReferenceCase) -> str:
    return case.folder.as_posix()


@pytest.fixture(scope="module")
def fmus(cross_check_tree: tuple[Path, int, str]) -> dict[str, Path]:
    """The cases' FMUs (by :func:`fmu_file`), freshly built by the session's ``double-pendulum cross-check`` run
    (conftest.py's ``cross_check_tree``: ``build_case_fmus``, one build for both modules), as its tree holds them."""
    root, code, out = cross_check_tree
    assert code == 0, out
    return {fmu_file(case): model_dir(root, case) / f"{case.model}.fmu" for case in CASES}


def deviation(result, reference, names) -> float:
    """The largest difference over ``names``, each relative to its column's largest magnitude (at least 1)."""
    return max(float(np.max(np.abs(np.asarray(result[n]) - reference[n])) / max(1.0, np.max(np.abs(reference[n]))))
               for n in names)


@pytest.mark.parametrize("case", CASES, ids=case_id)
def test_the_committed_inputs_and_options_are_the_cases(case):
    folder = REFERENCES / case.folder
    assert (folder / f"{case.model}_ref.opt").read_text() == opt_text(case)
    inputs = folder / f"{case.model}_in.csv"
    assert (inputs.read_text() if inputs.is_file() else None) == input_csv(case)
    reference = read_reference(REFERENCES, case)
    assert reference.dtype.names == ("time", *case.outputs) and len(case.outputs) <= 10
    assert reference["time"][0] == 0.0 and reference["time"][-1] == pytest.approx(case.stop_time)
    record = json.loads((REFERENCES / RECORD).read_text())["cases"][case_id(case)]
    assert record["baked_start_values"] == dict(case.baked) and record["run_start_values"] == dict(case.reference_start)


def test_every_variant_has_at_least_three_models():
    """The Cross-Check asks for three FMUs per platform and FMI variant."""
    variants = {}
    for case in CASES:
        variants.setdefault((case.fmi_version, case.fmi_type), []).append(case.model)
    assert set(variants) == {("2.0", "cs"), ("3.0", "cs"), ("3.0", "me")}
    assert all(len(models) >= 3 for models in variants.values())


@pytest.mark.parametrize("case", CASES, ids=case_id)
def test_fmpy_reproduces_the_reference(fmus, case):
    reference = read_reference(REFERENCES, case)
    result = reference_run(case, fmus[fmu_file(case)])
    assert result["time"].tolist() == pytest.approx(reference["time"].tolist(), abs=1e-12)
    got = deviation(result, reference, case.outputs)
    print(f"fmpy {case_id(case)}: largest relative difference {got:.2g}")
    assert got <= REPRODUCE


# ------------------------------------------------------------------------------------------- the C hosts
def _shared_libpython_here() -> bool:
    record = dict(line.split("=", 1) for line in loader.python_record().splitlines() if "=" in line)
    return bool(record["library"]) and Path(record["library"]).is_file()


needs_c_host = [
    pytest.mark.skipif(not sys.platform.startswith("linux"), reason="the C loader and the C hosts are for Linux"),
    pytest.mark.skipif(loader.c_compiler() is None, reason="no C compiler ($CC, cc, gcc or clang) for the C hosts"),
    pytest.mark.skipif(not _shared_libpython_here(), reason="this Python has no shared libpython, which the FMU "
                       "needs in a host without Python"),
]


@pytest.fixture(scope="module")
def hosts(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """The C hosts by FMI version, compiled once for the test session (host_binaries)."""
    return {version: compiled_host(tmp_path_factory, source.removesuffix(".c"))
            for version, source in HOST_SOURCES.items()}


def host_run(host: Path, case: ReferenceCase, fmu: Path, tmp_path: Path) -> np.ndarray:
    """Run ``case`` in the C host: its FMU extracted, the reference run's start values, the case's inputs as an
    input table by value reference, every output recorded at every output interval's end (under Model
    Exchange ME_SUBSTEPS RK4 steps an interval)."""
    from fmpy import extract, read_model_description

    folder = Path(extract(str(fmu), str(tmp_path / "fmu")))
    md = read_model_description(str(fmu))
    variables = {v.name: v for v in md.modelVariables}
    args = []
    for name, value in case.reference_start.items():
        kind = {"Boolean": "b", "String": "s"}.get(variables[name].type, "r")
        args.append(f"{kind}:{variables[name].valueReference}={int(value) if kind == 'b' else value}")
    text = input_csv(case)
    if text is not None:
        header, _, rows = text.partition("\n")
        table = tmp_path / "inputs.csv"
        vrs = [str(variables[n].valueReference) for n in input_names(case)]
        table.write_text(",".join(["time", *vrs]) + "\n" + rows)
        args.append(f"f:{table}")
    args += [f"O:{variables[n].valueReference}" for n in case.outputs]
    me = case.fmi_type == "me"
    substeps = ME_SUBSTEPS.get(case.model, ME_SUBSTEPS_DEFAULT) if me else 1
    if me:
        args.append(f"e:{substeps}")  # a row per output interval
    steps = round(case.stop_time / case.step_size) * substeps
    h = repr(case.step_size / substeps)
    identifier = (md.coSimulation or md.modelExchange).modelIdentifier
    if case.fmi_version == "2.0":
        command = [str(host), str(folder), identifier, md.guid, str(steps), h, *args]
    else:
        command = [str(host), str(folder), identifier, md.guid, "rk4" if me else "cs", str(steps), h, *args]
    done = subprocess.run(command, capture_output=True, text=True, env={"PATH": "/usr/bin:/bin", "HOME": str(tmp_path)},
                          cwd=tmp_path, timeout=600)
    assert done.returncode == 0, f"exit {done.returncode}\n{done.stdout[-2000:]}\n{done.stderr[-2000:]}"
    rows = np.array([[float(v) for v in line.split()[1:]] for line in done.stdout.splitlines()
                     if line.startswith("row ")])
    return np.rec.fromarrays(rows.T, names=["time", *case.outputs])


@needs_c_host[0]
@needs_c_host[1]
@needs_c_host[2]
@pytest.mark.parametrize("case", CASES, ids=case_id)
def test_the_c_host_reproduces_the_reference(hosts, fmus, case, tmp_path):
    reference = read_reference(REFERENCES, case)
    result = host_run(hosts[case.fmi_version], case, fmus[fmu_file(case)], tmp_path)
    assert result["time"].tolist() == pytest.approx(reference["time"].tolist(), abs=1e-9)
    tolerance = RK4_ME.get(case.model, RK4_ME_DEFAULT) if case.fmi_type == "me" else REPRODUCE
    got = deviation(result, reference, case.outputs)
    print(f"C host {case_id(case)}: largest relative difference {got:.2g} (allowed {tolerance:g})")
    assert got <= tolerance
    from fmpy.cross_check import validate_result

    assert validate_result(result, reference, 0.0, case.stop_time) is None  # the cross-check's comparison
