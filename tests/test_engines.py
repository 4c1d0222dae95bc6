"""The coupled system on real co-simulation engines: the SSP file on libcosim, fmpy's container FMU.

Both engines step the two FMUs side by side with the inputs held over a macro step (Jacobi), so
they converge to the monolith (DoublePendulum with ``suspension`` on) at first order in the macro
step, like :func:`double_pendulum.fmu.masters.coupling.run_jacobi`.
"""

from __future__ import annotations

import shutil
import zipfile
from pathlib import Path

import numpy as np
import pytest

from double_pendulum.component.cosimulation import DoublePendulumCoSimulation
from double_pendulum.fmu.build.container import write_container
from double_pendulum.fmu.build.ssp import write_ssp
from double_pendulum.fmu.build.systems import build_systems
from double_pendulum.fmu.masters.coupling import FmuSlave, run_coupled, split_values
from double_pendulum.fmu.running.hosts import simulate_container, simulate_ssp_with_libcosim

START = {"phi1_0": 1.2, "phi2_0": 0.8}
STOP = 0.2
STEPS = (4e-3, 2e-3, 1e-3)


@pytest.fixture(scope="module")
def fmus(fmu_path: Path) -> tuple[Path, Path]:
    """The session's DoublePendulum.fmu and the Suspension.fmu built beside it."""
    return fmu_path, fmu_path.parent / "Suspension.fmu"


@pytest.fixture(scope="module")
def reference() -> dict[str, float]:
    sim = DoublePendulumCoSimulation()
    for name, value in {**START, "suspension": True}.items():
        sim.set(name, value)
    sim.initialise()
    for k in range(100):
        sim.do_step(k * STOP / 100, STOP / 100)
    return {n: sim.get(n) for n in ("phi1", "phi2", "ys")}


def _fitted_order(errors: list[float]) -> float:
    slope = np.polyfit(np.log(STEPS), np.log(errors), 1)[0]
    return float(slope)


def _angle_error(last: np.void, reference: dict[str, float]) -> float:
    return max(abs(last["phi1"] - reference["phi1"]), abs(last["phi2"] - reference["phi2"]))


def test_build_systems_writes_an_ssp_and_a_container_that_validates(fmus, tmp_path):
    from fmpy.validation import validate_fmu

    for fmu in fmus:
        assert validate_fmu(str(fmu)) == []
        shutil.copy(fmu, tmp_path)  # written beside copies: the session's build folder is only read
    ssp, container = build_systems(tmp_path / fmus[0].name)
    assert validate_fmu(str(container)) == []
    with zipfile.ZipFile(ssp) as archive:
        names = set(archive.namelist())
        ssd = archive.read("SystemStructure.ssd").decode()
    assert {"SystemStructure.ssd", "resources/DoublePendulum.fmu", "resources/Suspension.fmu"} <= names
    assert 'startConnector="F_pivot_y"' in ssd and 'endConnector="pivot_ay"' in ssd
    assert 'name="F_static_y"' in ssd
    with zipfile.ZipFile(container) as archive:
        md = archive.read("modelDescription.xml").decode()
    assert 'fmiVersion="2.0"' in md and "binaries/linux64/container_fmu.so" in archive.namelist()


def test_libcosim_runs_the_ssp_and_converges_at_first_order(fmus, reference, tmp_path):
    errors = []
    for h in STEPS:
        ssp = write_ssp(tmp_path / "system.ssp", *fmus, START, macro_step=h)
        rows = simulate_ssp_with_libcosim(ssp, stop_time=STOP, macro_step=h)
        assert rows["time"][-1] == pytest.approx(STOP)
        errors.append(_angle_error(rows[-1], reference))
    order = _fitted_order(errors)
    assert 0.8 < order < 1.3, (errors, order)
    assert errors[-1] < 2e-3


def test_container_fmu_runs_in_fmpy_and_converges_at_first_order(fmus, reference, tmp_path):
    errors = []
    for h in STEPS:
        container = write_container(tmp_path / f"c{h:g}.fmu", *fmus, START, macro_step=h)
        rows = simulate_container(container, stop_time=STOP, macro_step=h)
        errors.append(_angle_error(rows[-1], reference))
    order = _fitted_order(errors)
    assert 0.8 < order < 1.3, (errors, order)
    assert errors[-1] < 2e-3


def test_parameters_reach_the_components_on_both_engines(fmus, tmp_path):
    values = {"phi1_0": 0.3, "phi2_0": -0.2, "M_s": 1.5}
    ssp = write_ssp(tmp_path / "p.ssp", *fmus, values, macro_step=1e-3)
    container = write_container(tmp_path / "p.fmu", *fmus, values, macro_step=1e-3)
    for rows in (simulate_ssp_with_libcosim(ssp, stop_time=2e-3, macro_step=1e-3),
                 simulate_container(container, stop_time=2e-3, macro_step=1e-3)):
        assert rows["phi1"][-1] == pytest.approx(0.3, abs=1e-3)
        assert rows["phi2"][-1] == pytest.approx(-0.2, abs=1e-3)


def test_engines_step_like_run_coupled_with_the_same_macro_step(fmus, tmp_path):
    """Same macro step, same stepping scheme, same numbers. libcosim: textbook Jacobi (outputs read
    after the step, then inputs set) with two more exchanges while initialising; the container:
    the force passed first, the motion read after it (``jacobi_sequential``). Compared: states
    (angles, suspension position); direct-feedthrough outputs are read at other moments."""
    from fmpy import extract, read_model_description

    h, stop, values = 1e-3, 0.1, {"phi1_0": 2.0, "phi2_0": 2.5}
    pv, sv = split_values(values)
    expected = {}
    for scheme, initial in (("jacobi", 2), ("jacobi_sequential", 0)):
        slaves = [FmuSlave(extract(str(f), unzipdir=str(tmp_path / scheme / f.stem)), read_model_description(str(f)), v)
                  for f, v in zip(fmus, (pv, sv))]  # extracted under tmp_path, not left in $TMPDIR
        try:
            expected[scheme] = run_coupled(*slaves, stop_time=stop, macro_step=h, scheme=scheme,
                                           initial_exchanges=initial)
        finally:
            for slave in slaves:
                slave.close()
    container = write_container(tmp_path / "j.fmu", *fmus, values, macro_step=h)
    in_container = simulate_container(container, stop_time=stop, macro_step=h)
    libcosim = simulate_ssp_with_libcosim(write_ssp(tmp_path / "j.ssp", *fmus, values, macro_step=h),
                                          stop_time=stop, macro_step=h)
    for name in ("phi1", "phi2", "x", "y"):
        np.testing.assert_allclose(in_container[name], expected["jacobi_sequential"][name], rtol=0, atol=1e-11,
                                   err_msg=name)
        np.testing.assert_allclose(libcosim[name], expected["jacobi"][name][1:], rtol=0, atol=1e-11, err_msg=name)


def test_container_parameters_can_be_changed_by_the_host(fmus, tmp_path):
    from fmpy import simulate_fmu

    container = write_container(tmp_path / "d.fmu", *fmus, macro_step=1e-3)
    rows = simulate_fmu(str(container), stop_time=2e-3, output_interval=1e-3,
                        start_values={"DoublePendulum.phi1_0": 2.0, "Suspension.M_s": 3.0})
    assert rows["DoublePendulum.phi1"][0] == 2.0


def test_an_unstable_split_system_ends_with_a_message_and_its_rows_on_both_engines(fmus, tmp_path):
    """A suspension lighter than the pendulum ((m1 + m2) / M_s = 2) blows up under Jacobi coupling."""
    from double_pendulum.fmu.masters.coupling import CouplingError

    light = {"phi1_0": 0.2, "phi2_0": 0.0, "M_s": 0.3, "k_x": 3e3, "k_y": 3e3, "c_x": 0.0, "c_y": 0.0}
    runs = (
        lambda: simulate_ssp_with_libcosim(write_ssp(tmp_path / "u.ssp", *fmus, light, macro_step=1e-3),
                                           stop_time=1.0, macro_step=1e-3),
        lambda: simulate_container(write_container(tmp_path / "u.fmu", *fmus, light, macro_step=1e-3),
                                   stop_time=1.0, macro_step=1e-3),
    )
    for run in runs:
        with pytest.raises(CouplingError, match="unstable") as info:
            run()
        rows = info.value.rows
        assert 5 < len(rows) < 1000 and np.isfinite(rows["phi1"]).all()
