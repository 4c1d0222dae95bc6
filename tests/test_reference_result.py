"""The reference result inside every FMU (``extra/org.fmi-standard.fmi-ls-ref/``, Reference-FMUs' layout): the
manifest names it, it holds every output of the default experiment, and fmpy re-simulating the FMU with its
defaults gets it back: to rounding under Co-Simulation, within the tolerance under Model Exchange."""

from __future__ import annotations

import zipfile
from pathlib import Path
from xml.etree import ElementTree as ET

import numpy as np
import pytest

from double_pendulum.fmu.carries.reference_result import FOLDER, MANIFEST, MOST_ROWS, interval

LS = "{http://fmi-standard.org/fmi-ls-manifest}"
CASES = {  # FMU, model, interface, |difference| bound relative to each output's range (or size, if larger)
    "fmi2": ("fmi2", "DoublePendulum", "CoSimulation", 1e-12),
    "fmi3-cs": ("fmi3", "DoublePendulum", "CoSimulation", 1e-12),
    # CVode at the FMU's default tolerance (1e-9): 6e-8 of the range at most here
    "fmi3-me": ("fmi3", "DoublePendulum", "ModelExchange", 1e-5),
    "suspension": ("suspension", "Suspension", "CoSimulation", 1e-12),
    # the container's own time grid sums its macro steps: 1e-13 of the range
    "container": ("container", "PendulumOnSuspension", "CoSimulation", 1e-11),
}


@pytest.fixture(scope="module")
def fmus(fmu_path: Path, fmu3_path: Path) -> dict[str, Path]:
    folder = fmu_path.parent
    return {"fmi2": fmu_path, "fmi3": fmu3_path, "suspension": folder / "Suspension.fmu",
            "container": folder / "PendulumOnSuspension.fmu"}


def _reference(fmu: Path, model: str, tmp_path: Path) -> tuple[ET.Element, np.ndarray]:
    from fmpy.util import read_csv

    with zipfile.ZipFile(fmu) as archive:
        manifest = ET.fromstring(archive.read(MANIFEST))
        related = manifest.find("Related")
        csv = tmp_path / related.get("source")
        csv.write_bytes(archive.read(f"{FOLDER}/{related.get('source')}"))
    return manifest, read_csv(csv)


@pytest.mark.parametrize("case", list(CASES))
def test_the_fmus_reference_result_is_what_fmpy_gets_from_its_default_experiment(fmus, case, tmp_path):
    from fmpy import read_model_description, simulate_fmu

    which, model, interface, bound = CASES[case]
    fmu = fmus[which]
    manifest, reference = _reference(fmu, model, tmp_path)
    assert manifest.get(f"{LS}fmi-ls-name") == "org.fmi-standard.fmi-ls-ref"
    related = manifest.find("Related")
    assert (related.get("role"), related.get("type"), related.get("source")) == ("result", "text/csv",
                                                                                   f"{model}_out.csv")
    md = read_model_description(fmu)
    outputs = [v.name for v in md.modelVariables if v.causality == "output"]
    assert list(reference.dtype.names) == ["time", *outputs]
    experiment = md.defaultExperiment
    step = reference["time"][1] - reference["time"][0]
    assert step == pytest.approx(interval(0.0, float(experiment.stopTime), float(experiment.stepSize)), rel=1e-12)
    assert reference["time"][0] == 0.0 and reference["time"][-1] == pytest.approx(float(experiment.stopTime))
    assert len(reference) <= MOST_ROWS + 1

    result = simulate_fmu(fmu, fmi_type=interface, output_interval=step)  # the defaults, that output interval
    np.testing.assert_allclose(result["time"], reference["time"], rtol=0, atol=1e-12)
    for name in outputs:
        scale = max(float(np.ptp(reference[name])), float(np.max(np.abs(reference[name]))), 1e-300)
        difference = float(np.max(np.abs(result[name] - reference[name])))
        assert difference <= bound * scale, f"{case} {name}: {difference:.3g} > {bound:g} x range {scale:.3g}"


def test_a_moving_reference_is_not_a_constant_one(fmus, tmp_path):
    """The pendulum's and the coupled system's references move (a reference of zeros proves nothing); the
    unloaded Suspension at rest is the one that stays still, as its default experiment says."""
    for which, model in (("fmi2", "DoublePendulum"), ("container", "PendulumOnSuspension")):
        _, reference = _reference(fmus[which], model, tmp_path)
        assert all(np.ptp(reference[n]) > 0 for n in reference.dtype.names[1:]), model
    _, rest = _reference(fmus["suspension"], "Suspension", tmp_path)
    assert all(np.ptp(rest[n]) == 0 for n in rest.dtype.names[1:])


def test_the_reference_interval_keeps_a_result_small():
    assert interval(0.0, 10.0, 0.01) == 0.01
    assert interval(0.0, 10.0, 1e-3, 1e-3) == pytest.approx(0.01)  # the container: 10 macro steps a row
    assert interval(0.0, 1.0, 1e-3) == 1e-3


def _fmusim() -> str | None:
    """Reference-FMUs' fmusim: ``$DOUBLE_PENDULUM_FMUSIM``, else ``fmusim`` on PATH (built from modelica/Reference-FMUs
    v0.0.39 or modelica/fmusim; CI cannot fetch it, so these tests skip there)."""
    import os
    import shutil

    return os.environ.get("DOUBLE_PENDULUM_FMUSIM") or shutil.which("fmusim")


@pytest.mark.skipif(_fmusim() is None, reason="fmusim is not installed (set DOUBLE_PENDULUM_FMUSIM to the fmusim "
                    "executable built from modelica/Reference-FMUs or modelica/fmusim)")
@pytest.mark.parametrize("case", list(CASES))
def test_fmusim_gets_each_fmus_reference_result_too(fmus, case, tmp_path):
    """Reference-FMUs' own simulator, a C host, on the FMU's default experiment at the reference's interval (under
    Model Exchange its CVode at the default experiment's tolerance: its own default is Euler)."""
    import subprocess

    from fmpy import read_model_description
    from fmpy.util import read_csv

    which, model, interface, bound = CASES[case]
    fmu = fmus[which]
    _, reference = _reference(fmu, model, tmp_path)
    step = reference["time"][1] - reference["time"][0]
    out = tmp_path / "fmusim.csv"
    command = [_fmusim(), "--interface-type", "me" if interface == "ModelExchange" else "cs",
               "--output-interval", repr(float(step)), "--output-file", str(out)]
    if interface == "ModelExchange":
        tolerance = read_model_description(fmu).defaultExperiment.tolerance
        command += ["--solver", "cvode", "--tolerance", str(tolerance)]
    done = subprocess.run([*command, str(fmu)], capture_output=True, text=True, timeout=300, cwd=tmp_path)
    assert done.returncode == 0, done.stdout + done.stderr
    result = read_csv(str(out))
    assert len(result) == len(reference)
    for name in reference.dtype.names[1:]:
        scale = max(float(np.ptp(reference[name])), float(np.max(np.abs(reference[name]))), 1e-300)
        difference = float(np.max(np.abs(result[name] - reference[name])))
        # fmusim writes 16 significant digits: a few units of 1e-16 of the scale at least
        assert difference <= max(bound, 1e-15) * scale, f"{case} {name}: {difference:.3g}"
