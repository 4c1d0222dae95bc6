"""Bad input through the FMU: an error status naming the variable and value, never a crash or hang."""

from __future__ import annotations

import math
import subprocess
import sys
import textwrap
from dataclasses import fields

import pytest

from double_pendulum.component.cosimulation import PARAMETER_GROUPS
from double_pendulum.fmu.running.runner import FmuRunError

INVALID_VALUES = {
    "positive": [-1.0, 0.0, math.nan, math.inf, -math.inf],
    "nonnegative": [-1.0, -1e-300, math.nan, math.inf],
    "finite": [math.nan, math.inf, -math.inf],
    "angle": [math.nan, math.inf, -math.inf, 1e300, -1.0001e4],  # a start angle: at most 1e4 rad in size
    "count": [0, -5],  # an Integer (max_steps)
}


def _bad_real_inputs() -> list[tuple[str, float]]:
    cases = []
    for group in PARAMETER_GROUPS:
        for f in fields(group):
            cases += [(f.name, v) for v in INVALID_VALUES.get(f.metadata["rule"], [])]
    return cases


BAD_REAL_INPUTS = _bad_real_inputs()


def test_every_real_parameter_has_invalid_values_to_try():
    names = {name for name, _ in BAD_REAL_INPUTS}
    assert {"m1", "l2", "g", "phi1_0", "omega2_0", "rtol", "atol", "fixed_step", "k_x", "M_s", "omega_reg"} <= names
    assert len(BAD_REAL_INPUTS) > 100


@pytest.mark.parametrize(("name", "value"), BAD_REAL_INPUTS, ids=[f"{n}={v}" for n, v in BAD_REAL_INPUTS])
def test_invalid_real_parameter_is_an_error_naming_variable_and_value(runner, name, value):
    with pytest.raises(FmuRunError, match="failed with status") as info:
        runner.simulate({name: value}, stop_time=0.1)
    assert f"invalid {name} = {value!r}" in str(info.value)


@pytest.mark.parametrize("solver", ["", "RK4", "dop 853", "radau"])
def test_unknown_solver_names_are_errors(runner, solver):
    if solver == "radau" and solver in _known_solvers():
        pytest.skip("radau is a known solver in this build")
    with pytest.raises(FmuRunError, match=f"invalid solver = {solver!r}"):
        runner.simulate({"solver": solver}, stop_time=0.1)


def _known_solvers() -> set[str]:
    from double_pendulum.solvers import METHODS

    return set(METHODS)


def _slave(runner, name):
    from fmpy.fmi2 import FMU2Slave

    md = runner.model_description
    fmu = FMU2Slave(
        guid=md.guid, unzipDirectory=runner.unzipdir, modelIdentifier=md.coSimulation.modelIdentifier, instanceName=name
    )
    fmu.instantiate()
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    return fmu, {v.name: v.valueReference for v in md.modelVariables}


@pytest.mark.parametrize("step", [0.0, -0.01, math.nan])
def test_a_non_positive_communication_step_is_an_error_and_reset_recovers(runner, step):
    """Misuse is fmi2Error (fmi2Discard means a step done in part); the instance is then in the Error
    state (only get, FMU states, reset and free), and fmi2Reset brings it back."""
    from fmpy.fmi1 import FMICallException

    fmu, vrs = _slave(runner, "step")
    with pytest.raises(FMICallException) as info:
        fmu.doStep(currentCommunicationPoint=0.0, communicationStepSize=step)
    assert info.value.status == 3  # fmi2Error
    with pytest.raises(FMICallException) as info:
        fmu.doStep(currentCommunicationPoint=0.0, communicationStepSize=0.01)  # not in the Error state
    assert info.value.status == 3
    assert fmu.getReal([vrs["phi1"]])[0] == pytest.approx(1.0)  # values can still be read
    fmu.reset()
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    fmu.doStep(currentCommunicationPoint=0.0, communicationStepSize=0.01)
    assert fmu.getReal([vrs["phi1"]])[0] != 1.0
    fmu.terminate()
    fmu.freeInstance()


def test_do_step_out_of_order_is_an_error(runner):
    from fmpy.fmi1 import FMICallException

    fmu, _ = _slave(runner, "order")
    with pytest.raises(FMICallException) as info:
        fmu.doStep(currentCommunicationPoint=5.0, communicationStepSize=0.01)
    assert info.value.status == 3
    with pytest.raises(FMICallException):
        fmu.terminate()  # terminate is not allowed in the Error state
    fmu.freeInstance()


def test_setting_a_parameter_after_initialisation_is_an_error(runner):
    from fmpy.fmi1 import FMICallException

    fmu, vrs = _slave(runner, "late")
    with pytest.raises(FMICallException) as info:
        fmu.setReal([vrs["l1"]], [0.5])
    assert info.value.status == 3  # an error of this instance, not fmi2Fatal
    fmu.freeInstance()
    # a new instance works
    assert runner.simulate({"l1": 0.5}, stop_time=0.1)["time"][-1] == pytest.approx(0.1)


def test_many_failed_calls_on_one_instance_leave_it_and_the_host_running(runner):
    """pythonfmu's C++ layer released the slave's references once more for every exception that reached it
    (the fourth refused value on one instance crashed the host); the loader calls the slave itself. Each
    refused call here reaches the Python side: the slave's reference count is the same after 100 of them
    (nothing leaks, nothing is released twice), and resets leave no old slave alive."""
    import gc
    import sys

    from fmpy.fmi1 import FMICallException

    def slaves():
        return [o for o in gc.get_objects() if type(o).__name__ == "DoublePendulum" and hasattr(o, "_sim")]

    gc.collect()
    alive = len(slaves())
    fmu, vrs = _slave(runner, "many")
    (slave,) = [o for o in slaves() if o.instance_name == "many"]
    references = sys.getrefcount(slave)
    for k in range(100):  # the first puts the instance into its Error state, where getReal still reaches Python
        with pytest.raises(FMICallException) as info:
            if k == 0:
                fmu.setReal([vrs["pivot_ay"]], [math.nan])
            else:
                fmu.getReal([10**6 + k])
        assert info.value.status == 3
    assert sys.getrefcount(slave) == references
    del slave
    for _ in range(20):
        fmu.reset()
    gc.collect()
    assert len(slaves()) == alive + 1  # this instance's one slave: every reset freed the one before
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    fmu.doStep(currentCommunicationPoint=0.0, communicationStepSize=0.01)
    assert fmu.getReal([vrs["phi1"]])[0] == pytest.approx(1.0, abs=1e-2)  # it swings on from phi1_0 = 1 rad
    fmu.terminate()
    fmu.freeInstance()
    gc.collect()
    assert len(slaves()) == alive  # freed with its instance


def test_with_logging_off_the_message_still_reaches_the_hosts_logger(fmu_path, tmp_path):
    """Errors reach the host's logger from instantiation on, debug logging on or off (fmpy's default logger
    prints them); the FMU does not repeat them on stderr."""
    script = textwrap.dedent(f"""
        import os
        from fmpy import extract, simulate_fmu
        # extracted here: fmpy removes its own extraction only when the run returns, not when it raises
        unzipped = extract({str(fmu_path)!r}, unzipdir={str(tmp_path / "fmu")!r})
        try:
            simulate_fmu(unzipped, stop_time=1.0, start_values={{"l2": -0.2}})
        except Exception as error:
            print("raised", type(error).__name__, flush=True)
        os._exit(0)
    """)
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, cwd=tmp_path, timeout=120)
    assert "raised FMICallException" in out.stdout
    assert "[ERROR] fmi2SetReal: ParameterError: invalid l2 = -0.2 m: must be > 0" in out.stdout
    assert "invalid l2" not in out.stderr


def test_solver_failure_is_reported_with_the_time_and_the_run_stops_cleanly(runner):
    with pytest.raises(FmuRunError, match="numerical instability at t = ") as info:
        runner.simulate(
            {"solver": "euler", "fixed_step": 0.2, "phi1_0": 3.0, "omega2_0": 30.0}, stop_time=50.0, output_interval=0.2
        )
    assert info.value.partial_result is not None



def test_through_the_runner_errors_reach_the_caller_not_stderr(fmu_path, tmp_path):
    """FmuRunner collects the FMU's log and raises it; the FMU then leaves stderr alone (no alarm lines)."""
    script = textwrap.dedent(f"""
        import os
        from double_pendulum.fmu.running.runner import FmuRunError, FmuRunner
        with FmuRunner({str(fmu_path)!r}) as runner:
            try:
                runner.simulate({{"solver": "rk4", "fixed_step": 0.5, "phi1_0": 3.0, "omega2_0": 30.0}}, stop_time=20.0)
            except FmuRunError as error:
                print("raised:", error, flush=True)
        os._exit(0)
    """)
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, cwd=tmp_path, timeout=120)
    assert "raised:" in out.stdout and "rk4" in out.stdout
    assert "DoublePendulum:" not in out.stderr
