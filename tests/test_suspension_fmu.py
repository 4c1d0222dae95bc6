"""The Suspension FMU on its own, and DoublePendulum + Suspension coupled against the monolith."""

from __future__ import annotations

import math
import zipfile
from pathlib import Path
from xml.etree import ElementTree as ET

import numpy as np
import pytest

from double_pendulum.component.cosimulation import DoublePendulumCoSimulation
from double_pendulum.component.suspension import SuspensionCoSimulation
from double_pendulum.fmu.build.fmi2 import build_fmu
from double_pendulum.fmu.masters.coupling import FmuSlave, run_jacobi
from double_pendulum.fmu.running.runner import FmuRunError, FmuRunner
from double_pendulum.model.parameters import ParameterError, PendulumParameters, SuspensionLoad
from double_pendulum.model.suspension import OUTPUT_NAMES, PORT_NAMES

START = {"phi1_0": 1.0, "phi2_0": 1.0}


@pytest.fixture(scope="module")
def suspension_fmu(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return build_fmu(tmp_path_factory.mktemp("suspension") / "Suspension.fmu", "Suspension")


@pytest.fixture(scope="module")
def suspension_runner(suspension_fmu: Path):
    with FmuRunner(suspension_fmu) as r:
        yield r


def force_table(stop_time: float, dt: float, f_x, f_y) -> np.ndarray:
    t = np.arange(int(round(stop_time / dt)) + 2) * dt
    table = np.zeros(len(t), dtype=[("time", np.float64), ("F_x", np.float64), ("F_y", np.float64)])
    table["time"], table["F_x"], table["F_y"] = t, [f_x(v) for v in t], [f_y(v) for v in t]
    return table


def test_suspension_fmu_validates_and_states_its_interface(suspension_fmu):
    from fmpy.validation import validate_fmu

    assert validate_fmu(str(suspension_fmu)) == []
    with zipfile.ZipFile(suspension_fmu) as fmu:
        root = ET.fromstring(fmu.read("modelDescription.xml"))
    assert root.find("CoSimulation").get("modelIdentifier") == "Suspension"
    variables = list(root.find("ModelVariables"))
    by_name = {sv.get("name"): sv for sv in variables}
    assert {"M_s", "k_x", "k_y", "c_x", "c_y", "F_static_y"} <= set(by_name)
    for name in ("F_x", "F_y"):
        assert by_name[name].get("causality") == "input" and by_name[name].find("Real").get("unit") == "N"
    deps = {
        variables[int(u.get("index")) - 1].get("name"): u.get("dependencies")
        for u in root.find("ModelStructure/Outputs")
    }
    assert deps["ay"] == str(variables.index(by_name["F_y"]) + 1)
    assert deps["y"] == "" and deps["vx"] == ""
    assert set(deps) == set(PORT_NAMES)  # energies, works and power are locals
    assert by_name["E_suspension"].get("causality") == "local"


def test_static_load_leaves_the_mass_at_rest(suspension_runner):
    result = suspension_runner.simulate({}, stop_time=1.0, output_interval=1e-2, outputs=OUTPUT_NAMES)
    for name in OUTPUT_NAMES:
        assert not np.any(result[name]), name


def test_static_load_default_is_the_default_pendulums_weight():
    p = PendulumParameters()
    assert SuspensionLoad().F_static_y == -(p.m1 + p.m2) * p.g


def test_extra_load_settles_at_the_spring_deflection_and_the_energy_budget_closes(suspension_runner):
    extra = 10.0
    table = force_table(3.0, 1e-2, lambda t: 2.0 * math.sin(30 * t), lambda t: SuspensionLoad().F_static_y + extra)
    result = suspension_runner.simulate({}, stop_time=3.0, output_interval=1e-2, outputs=OUTPUT_NAMES, input=table)
    assert result["y"][-1] == pytest.approx(extra / 2e4, rel=1e-4)
    assert result["W_in"][-1] > 0 and result["W_suspension"][-1] > 0
    assert abs(result["energy_residual"]).max() < 1e-9 * result["W_in"].max()


def test_suspension_fmu_matches_its_in_process_component(suspension_runner):
    table = force_table(0.5, 1e-3, lambda t: 3.0 * math.sin(50 * t), lambda t: -5.0 + math.cos(70 * t))
    fmu = suspension_runner.simulate(
        {"M_s": 0.5}, stop_time=0.5, output_interval=1e-3, outputs=OUTPUT_NAMES, input=table
    )
    sim = SuspensionCoSimulation()
    sim.set("M_s", 0.5)
    sim.initialise()
    for n in range(500):
        t = n * 1e-3
        sim.set_input("F_x", 3.0 * math.sin(50 * t))
        sim.set_input("F_y", -5.0 + math.cos(70 * t))
        sim.do_step(t, 1e-3)
    for name in OUTPUT_NAMES:
        assert fmu[name][-1] == pytest.approx(sim.outputs[name], rel=1e-12, abs=1e-15), name


def test_non_finite_force_is_refused_naming_it(suspension_runner):
    table = force_table(0.2, 1e-2, lambda t: math.nan if t > 0.1 else 0.0, lambda t: -5.0)
    with pytest.raises(FmuRunError, match="invalid input F_x = nan N") as info:
        suspension_runner.simulate({}, stop_time=0.2, output_interval=1e-2, input=table)
    assert info.value.partial_result is not None and len(info.value.partial_result) > 5
    with pytest.raises(ParameterError, match="invalid input F_y = inf N"):
        SuspensionCoSimulation().set_input("F_y", math.inf)


def _monolith(start: dict, stop_time: float) -> DoublePendulumCoSimulation:
    sim = DoublePendulumCoSimulation()
    for name, value in {**start, "suspension": True}.items():
        sim.set(name, value)
    sim.initialise()
    n = 100
    for k in range(n):
        sim.do_step(k * stop_time / n, stop_time / n)
    return sim


def _split(start: dict, stop_time: float, macro_step: float) -> np.ndarray:
    pendulum, suspension = DoublePendulumCoSimulation(), SuspensionCoSimulation()
    for name, value in start.items():
        pendulum.set(name, value)
    pendulum.initialise()
    suspension.initialise()
    return run_jacobi(pendulum, suspension, stop_time=stop_time, macro_step=macro_step)


def test_pendulum_hanging_at_rest_leaves_the_coupled_suspension_at_rest():
    rows = _split({"phi1_0": 0.0, "phi2_0": 0.0}, 0.2, 1e-3)
    for name in ("phi1", "phi2", "x", "y", "W_input", "W_in"):
        assert abs(rows[name]).max() < 1e-14, name


def test_split_system_converges_to_the_monolith_at_first_order():
    """Jacobi coupling (explicit, outputs of the last communication point) is first order in the macro step."""
    stop = 1.0
    ref = _monolith(START, stop)
    errors = []
    for macro_step in (4e-3, 2e-3, 1e-3):
        last = _split(START, stop, macro_step)[-1]
        errors.append(max(abs(last["phi1"] - ref.outputs["phi1"]), abs(last["phi2"] - ref.outputs["phi2"])))
        energy = last["E_pendulum"] + last["E_suspension"]
        assert energy == pytest.approx(ref.outputs["E_total"], abs=30 * macro_step)
    orders = [math.log2(a / b) for a, b in zip(errors, errors[1:])]
    assert all(0.8 < q < 1.3 for q in orders), (errors, orders)
    assert errors[-1] < 3e-3


def test_the_two_fmus_couple_like_the_in_process_components(fmu_path, suspension_fmu, tmp_path):
    from fmpy import extract, read_model_description

    slaves = []
    dirs = []
    try:
        for path, start in ((fmu_path, START), (suspension_fmu, {})):
            dirs.append(extract(str(path), unzipdir=str(tmp_path / path.stem)))  # under tmp_path, not loose in $TMPDIR
            slaves.append(FmuSlave(dirs[-1], read_model_description(str(path)), start))
        through_fmus = run_jacobi(*slaves, stop_time=0.1, macro_step=1e-3)
    finally:
        for slave in slaves:
            slave.close()
    in_process = _split(START, 0.1, 1e-3)
    for name in through_fmus.dtype.names:
        np.testing.assert_allclose(through_fmus[name], in_process[name], rtol=1e-12, atol=1e-15, err_msg=name)
