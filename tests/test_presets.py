"""Start values baked into a build (double_pendulum.fmu.presets): the FMU's defaults are the scene, in its
modelDescription and in every instance, at instantiation and after a reset, FMI 2 and FMI 3."""

from __future__ import annotations

import zipfile
from pathlib import Path

import pytest
from fmpy import read_model_description, simulate_fmu

from double_pendulum.fmu.build.fmi2 import build_fmu
from double_pendulum.fmu.build.fmi3 import build_fmu3
from double_pendulum.fmu.presets import PRESET_FILE
from double_pendulum.model.parameters import ParameterError

SCENE = {"phi1_0": 2.0, "phi2_0": 1.5, "air_drag": True, "solver": "dopri5", "rtol": 1e-10}
OUTPUTS = ["phi1", "phi2", "W_air", "solver_steps"]


@pytest.fixture(scope="module")
def baked(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    folder = tmp_path_factory.mktemp("presets")
    return {"fmi2": build_fmu(folder / "Scene.fmu", "DoublePendulum", SCENE),
            "fmi3": build_fmu3(folder / "fmi3" / "Scene.fmu", SCENE),
            "suspension": build_fmu(folder / "Loaded.fmu", "Suspension", {"k_x": 5e3, "F_static_y": -3.0})}


def starts(fmu: Path) -> dict[str, str]:
    return {v.name: v.start for v in read_model_description(str(fmu)).modelVariables}


@pytest.mark.parametrize("kind", ["fmi2", "fmi3"])
def test_the_model_description_holds_the_baked_start_values_and_says_so(baked, kind):
    got = starts(baked[kind])
    assert {name: got[name] for name in SCENE} == {"phi1_0": "2.0", "phi2_0": "1.5", "air_drag": "true",
                                                   "solver": "dopri5", "rtol": "1e-10"}
    assert got["l1"] == "0.2964"  # the others stay the defaults
    description = read_model_description(str(baked[kind])).description
    assert description.endswith("Start values of this build: phi1_0 = 2.0, phi2_0 = 1.5, air_drag = true, "
                                "solver = dopri5, rtol = 1e-10.")


def test_a_run_without_start_values_is_the_plain_fmu_run_with_them(baked, fmu_path):
    plain = simulate_fmu(str(fmu_path), start_values=SCENE, stop_time=0.5, output_interval=0.01, output=OUTPUTS)
    scene = simulate_fmu(str(baked["fmi2"]), stop_time=0.5, output_interval=0.01, output=OUTPUTS)
    assert scene.tolist() == plain.tolist()  # bit for bit


@pytest.mark.parametrize("fmi_type", ["CoSimulation", "ModelExchange"])
def test_the_fmi3_build_runs_its_scene_in_both_interfaces(baked, fmu_path, fmi_type):
    plain = simulate_fmu(str(fmu_path), start_values=SCENE, stop_time=0.5, output_interval=0.01, output=OUTPUTS)
    scene = simulate_fmu(str(baked["fmi3"]), stop_time=0.5, output_interval=0.01, output=OUTPUTS[:2],
                         fmi_type=fmi_type, relative_tolerance=1e-10)
    assert scene["phi1"][0] == 2.0 and scene["phi2"][0] == 1.5
    tolerance = 0.0 if fmi_type == "CoSimulation" else 1e-6  # CS: the same component; ME: CVode at 1e-10
    assert max(abs(scene["phi1"] - plain["phi1"])) <= tolerance


def test_a_reset_brings_back_the_baked_values_not_the_packages_defaults(baked, tmp_path):
    from fmpy import extract
    from fmpy.fmi2 import FMU2Slave

    md = read_model_description(str(baked["fmi2"]))
    refs = {v.name: v.valueReference for v in md.modelVariables}
    slave = FMU2Slave(guid=md.guid, unzipDirectory=extract(str(baked["fmi2"]), str(tmp_path / "x")),
                      modelIdentifier=md.coSimulation.modelIdentifier, instanceName="reset")
    slave.instantiate()
    try:
        slave.setReal([refs["phi1_0"]], [0.3])
        slave.setupExperiment(startTime=0.0)
        slave.enterInitializationMode()
        slave.exitInitializationMode()
        assert slave.getReal([refs["phi1"]]) == [0.3]
        slave.reset()
        slave.setupExperiment(startTime=0.0)
        slave.enterInitializationMode()
        slave.exitInitializationMode()
        assert slave.getReal([refs["phi1"], refs["phi2"]]) == [2.0, 1.5]
        assert slave.getBoolean([refs["air_drag"]]) == [True]
        slave.terminate()
    finally:
        slave.freeInstance()


def test_the_suspension_takes_its_own_parameters(baked):
    got = starts(baked["suspension"])
    assert got["k_x"] == "5000.0" and got["F_static_y"] == "-3.0"
    with zipfile.ZipFile(baked["suspension"]) as z:
        assert z.read(PRESET_FILE).decode().split() == ['{', '"k_x":', '5000.0,', '"F_static_y":', '-3.0', '}']


def test_the_plain_build_has_no_baked_values(fmu_path):
    with zipfile.ZipFile(fmu_path) as z:
        assert PRESET_FILE not in z.namelist()
    assert "Start values of this build" not in read_model_description(str(fmu_path)).description


@pytest.mark.parametrize(("values", "error", "message"), [
    ({"l1": -0.3}, ParameterError, "invalid l1 = -0.3 m: must be > 0"),
    ({"phi1": 1.0}, ValueError, "DoublePendulum has no parameter phi1"),
    ({"tau1": 1.0}, ValueError, "DoublePendulum has no parameter tau1"),
    ({"solver": "ode45"}, ValueError, "invalid solver = .ode45.: must be one of dop853"),
])
def test_bad_start_values_stop_the_build_before_anything_is_written(tmp_path, values, error, message):
    with pytest.raises(error, match=message):
        build_fmu(tmp_path / "bad.fmu", "DoublePendulum", values)
    assert not (tmp_path / "bad.fmu").exists()
