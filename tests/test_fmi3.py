"""The FMI 3.0 DoublePendulum.fmu: Model Exchange and Co-Simulation from the same runtime as the FMI 2 FMU.

Through fmpy (a Python host): the modelDescription is valid and offers the FMI 2 FMU's variables; Co-
Simulation gives the FMI 2 FMU's numbers; Model Exchange integrated by CVode follows them within 1e-6
rad from the chaotic start; the right-hand side is smooth where friction changes sign (no event
indicators); an input jump in Event Mode is booked into W_input; the FMU state round-trips; bad input
is an error naming the variable and value. Our C host runs it in tests/test_c_host.py.
"""

from __future__ import annotations

import math
from ctypes import POINTER, c_double
from pathlib import Path

import numpy as np
import pytest
from fmpy import extract, read_model_description, simulate_fmu
from fmpy.fmi1 import FMICallException

CHAOTIC = {"phi1_0": 2.0, "phi2_0": 2.0}
TIGHT = {"solver": "dop853", "rtol": 1e-12, "atol": 1e-14}  # the co-simulation's integrator, tight
ANGLES = ["phi1", "phi2"]


@pytest.fixture(scope="module")
def fmu3(fmu3_path: Path, tmp_path_factory: pytest.TempPathFactory) -> tuple[str, object]:
    """The FMI 3 FMU extracted once, with its model description."""
    return extract(str(fmu3_path), str(tmp_path_factory.mktemp("fmu3_x"))), read_model_description(str(fmu3_path))


class ModelExchange:
    """One Model Exchange instance through fmpy's FMU3Model, its log collected, initialised with ``start``."""

    def __init__(self, fmu3: tuple[str, object], start: dict | None = None, name: str = "me",
                 log: list[str] | None = None) -> None:
        from fmpy.fmi3 import FMU3Model

        unzipdir, md = fmu3
        self.refs = {v.name: v for v in md.modelVariables}
        self.n = md.numberOfContinuousStates
        self.log: list[str] = [] if log is None else log
        self.fmu = FMU3Model(guid=md.guid, unzipDirectory=unzipdir, modelIdentifier=md.modelExchange.modelIdentifier,
                             instanceName=name)
        self.fmu.instantiate(logMessage=lambda env, status, category, message: self.log.append(message.decode()))
        self.start = start or {}
        self.initialise()

    def initialise(self) -> None:
        """From Instantiated (a new or reset instance) to Continuous-Time Mode at t = 0 with the start values."""
        self.fmu.enterInitializationMode(startTime=0.0)
        for variable, value in self.start.items():
            self.set(variable, value)
        self.fmu.exitInitializationMode()
        self.fmu.updateDiscreteStates()
        self.fmu.enterContinuousTimeMode()

    def set(self, name: str, value) -> None:
        variable = self.refs[name]
        setter = {"Float64": self.fmu.setFloat64, "Boolean": self.fmu.setBoolean, "String": self.fmu.setString}
        setter[variable.type]([variable.valueReference], [value])

    def get(self, name: str) -> float:
        return self.fmu.getFloat64([self.refs[name].valueReference])[0]

    def states(self) -> np.ndarray:
        x = np.zeros(self.n)
        self.fmu.getContinuousStates(x.ctypes.data_as(POINTER(c_double)), self.n)
        return x

    def derivatives(self, t: float, x: np.ndarray) -> np.ndarray:
        x = np.ascontiguousarray(x, dtype=float)
        dx = np.zeros(self.n)
        self.fmu.setTime(t)
        self.fmu.setContinuousStates(x.ctypes.data_as(POINTER(c_double)), self.n)
        self.fmu.getContinuousStateDerivatives(dx.ctypes.data_as(POINTER(c_double)), self.n)
        return dx

    def rk4(self, t: float, x: np.ndarray, h: float, steps: int) -> tuple[float, np.ndarray]:
        for _ in range(steps):
            k1 = self.derivatives(t, x)
            k2 = self.derivatives(t + h / 2, x + h / 2 * k1)
            k3 = self.derivatives(t + h / 2, x + h / 2 * k2)
            k4 = self.derivatives(t + h, x + h * k3)
            t, x = t + h, x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        self.fmu.setTime(t)
        self.fmu.setContinuousStates(x.ctypes.data_as(POINTER(c_double)), self.n)
        return t, x

    def close(self) -> None:
        self.fmu.terminate()
        self.fmu.freeInstance()


def test_the_model_description_is_valid_and_offers_both_interfaces(fmu3_path):
    from fmpy.validation import validate_fmu

    assert validate_fmu(str(fmu3_path)) == []
    md = read_model_description(str(fmu3_path))
    assert md.fmiVersion == "3.0" and md.modelExchange and md.coSimulation
    assert md.modelExchange.canGetAndSetFMUstate and md.modelExchange.canSerializeFMUstate
    assert md.numberOfEventIndicators == 0  # a smooth right-hand side
    states = [d.variable.derivative.name for d in md.derivatives]
    assert states == ["phi1", "phi2", "omega1", "omega2", "suspension.x", "suspension.vx", "suspension.y",
                      "suspension.vy", "W_air", "W_bearing", "W_bearing_drag", "W_suspension", "W_input"]
    units = {d.variable.derivative.name: (d.variable.derivative.unit, d.variable.unit) for d in md.derivatives}
    assert units["omega1"] == ("rad/s", "rad/s2") and units["W_air"] == ("J", "W")


def test_the_variables_are_the_fmi2_fmus(fmu_path, fmu3_path):
    """Names, causality, descriptions, units and start values: as in the FMI 2 FMU."""
    fmi2 = {v.name: v for v in read_model_description(str(fmu_path)).modelVariables}
    fmi3 = {v.name: v for v in read_model_description(str(fmu3_path)).modelVariables}
    assert set(fmi2) <= set(fmi3)
    for name, v2 in fmi2.items():
        v3 = fmi3[name]
        assert (v3.causality, v3.description, v3.unit) == (v2.causality, v2.description, v2.unit), name
        assert v3.type == {"Real": "Float64", "Integer": "Int32"}.get(v2.type, v2.type)
        if v2.start is not None:
            assert type(v2.start)(v3.start) == v2.start, name


def test_both_interfaces_follow_the_fmi2_fmu_from_the_chaotic_start(fmu_path, fmu3_path):
    """Co-Simulation is the FMI 2 FMU's component (the same numbers); Model Exchange integrated by CVode
    at rtol 1e-12 stays within 1e-6 rad of it after 2 s from (2, 2) rad, energy budget closed."""
    options = {"stop_time": 2.0, "output_interval": 0.01, "start_values": {**CHAOTIC, **TIGHT}}
    fmi2 = simulate_fmu(str(fmu_path), output=ANGLES, **options)
    cs = simulate_fmu(str(fmu3_path), fmi_type="CoSimulation", output=ANGLES, **options)
    me = simulate_fmu(str(fmu3_path), fmi_type="ModelExchange", relative_tolerance=1e-12,
                      output=[*ANGLES, "energy_residual"], **options)
    for name in ANGLES:
        assert np.array_equal(cs[name], fmi2[name])
        assert abs(me[name][-1] - fmi2[name][-1]) < 1e-6
    assert np.max(np.abs(me["energy_residual"])) < 1e-8


def test_co_simulation_starts_at_the_start_time_it_is_given(fmu3_path):
    """pythonfmu3 drops fmi3EnterInitializationMode's start time; the loader passes it on, so a run from
    t = 1 s steps from there (the motion does not depend on the time origin)."""
    runs = [simulate_fmu(str(fmu3_path), fmi_type="CoSimulation", start_time=t0, stop_time=t0 + 0.5,
                         output_interval=0.01, start_values=CHAOTIC, output=ANGLES) for t0 in (0.0, 1.0)]
    assert runs[1]["time"][0] == 1.0
    for name in ANGLES:
        assert runs[1][name] == pytest.approx(runs[0][name], abs=1e-12)


FRICTION = {"bearing_friction": True, "c_R1": 0.05, "c_R2": 0.05, "bearing_drag": True, "tau_b1": 2e-3,
            "tau_b2": 1e-3, "b_v1": 1e-4, "air_drag": True, "rod_drag": True, "suspension": True}


def test_the_right_hand_side_is_smooth_where_friction_changes_sign(fmu3):
    """Friction torques change sign through tanh(omega / omega_reg): across omega1 = 0 (pivot) and
    omega2 = omega1 (elbow) the derivatives change in proportion to the step in omega, with no jump,
    so the FMU needs no event indicators."""
    instance = ModelExchange(fmu3, {**FRICTION, "phi1_0": 0.4, "phi2_0": -0.3})
    try:
        assert instance.fmu.getNumberOfEventIndicators() == 0
        x0 = instance.states()
        omega_reg = 1e-3  # the default regularisation speed [rad/s]
        for crossing in ({2: 1.0}, {3: 1.0}):  # omega1 through 0; omega2 through omega1 (= 0)
            differences = []
            for eps in (1e-2 * omega_reg, 1e-3 * omega_reg, 1e-4 * omega_reg):
                below, above = x0.copy(), x0.copy()
                for k, sign in crossing.items():
                    below[k], above[k] = -sign * eps, sign * eps
                differences.append(np.max(np.abs(instance.derivatives(0.0, above) - instance.derivatives(0.0, below))))
            assert differences[0] > 0  # friction acts there
            # linear in the step: a tenth of the step, a tenth of the change (a sign function would stay)
            assert differences[1] == pytest.approx(differences[0] / 10, rel=0.05)
            assert differences[2] == pytest.approx(differences[0] / 100, rel=0.05)
    finally:
        instance.close()


def test_model_exchange_follows_the_co_simulation_through_friction_sign_changes(fmu3_path):
    """Swinging down with strong friction, the rates change sign several times in 3 s: CVode over the
    smooth right-hand side gives the co-simulation's motion to 1e-6 rad."""
    options = {"stop_time": 3.0, "output_interval": 0.01, "start_values": {**FRICTION, **TIGHT, "phi1_0": 0.4,
                                                                          "phi2_0": -0.3}}
    cs = simulate_fmu(str(fmu3_path), fmi_type="CoSimulation", output=[*ANGLES, "omega1"], **options)
    me = simulate_fmu(str(fmu3_path), fmi_type="ModelExchange", relative_tolerance=1e-11, output=ANGLES, **options)
    assert np.sum(np.diff(np.sign(cs["omega1"])) != 0) >= 3  # the pivot bearing reverses
    for name in ANGLES:
        assert np.max(np.abs(me[name] - cs[name])) < 1e-6


def test_an_input_jump_in_event_mode_books_its_energy(fmu3_path):
    """fmpy sets the pivot velocity's jump at 0.5 s in Event Mode: W_input takes the energy it changes,
    energy_residual stays at the integration error."""
    signal = np.array([(0.0, 0.0), (0.5, 0.0), (0.5, 0.5), (1.0, 0.5)], dtype=[("time", float), ("pivot_vx", float)])
    result = simulate_fmu(str(fmu3_path), fmi_type="ModelExchange", relative_tolerance=1e-10, stop_time=1.0,
                          output_interval=0.01, start_values=CHAOTIC, input=signal,
                          output=["E_total", "W_input", "energy_residual"])
    jump = np.searchsorted(result["time"], 0.5, side="right")
    assert abs(result["W_input"][jump] - result["W_input"][jump - 2]) > 0.05  # the jump's energy [J]
    assert np.max(np.abs(result["energy_residual"])) < 1e-6


def test_the_fmu_state_round_trips_under_model_exchange(fmu3):
    """Saved mid-run and serialised, the state restores into a fresh instance that continues bit-identically."""
    first = ModelExchange(fmu3, CHAOTIC, "first")
    second = ModelExchange(fmu3, CHAOTIC, "second")
    try:
        t, x = first.rk4(0.0, first.states(), 1e-3, 200)
        state = first.fmu.getFMUState()
        saved = first.fmu.serializeFMUState(state)
        first.fmu.freeFMUState(state)
        _, x_first = first.rk4(t, x, 1e-3, 100)
        second.fmu.setFMUState(second.fmu.deserializeFMUState(saved))
        assert np.array_equal(second.states(), x)
        _, x_second = second.rk4(t, second.states(), 1e-3, 100)
        assert np.array_equal(x_first, x_second)
        assert second.get("phi1") == first.get("phi1") == x_first[0]
    finally:
        first.close()
        second.close()


def test_the_fmu_state_round_trips_under_co_simulation(fmu3):
    """The same for Co-Simulation: the component's state, integrator included, through fmi3SerializeFMUState."""
    from fmpy.fmi3 import FMU3Slave

    unzipdir, md = fmu3
    refs = {v.name: v.valueReference for v in md.modelVariables}
    instances = []
    for name in ("first", "second"):
        fmu = FMU3Slave(guid=md.guid, unzipDirectory=unzipdir, modelIdentifier="DoublePendulum", instanceName=name)
        fmu.instantiate()
        fmu.enterInitializationMode()
        fmu.setFloat64([refs["phi1_0"], refs["phi2_0"]], [2.0, 2.0])
        fmu.exitInitializationMode()
        instances.append(fmu)
    first, second = instances
    for k in range(20):
        first.doStep(k * 0.01, 0.01)
    state = first.getFMUState()
    saved = first.serializeFMUState(state)
    first.freeFMUState(state)
    for k in range(20, 40):
        first.doStep(k * 0.01, 0.01)
    second.setFMUState(second.deserializeFMUState(saved))
    for k in range(20, 40):
        second.doStep(k * 0.01, 0.01)
    angles = [refs["phi1"], refs["phi2"], refs["omega1"]]
    assert second.getFloat64(angles) == first.getFloat64(angles)
    for fmu in instances:
        fmu.terminate()
        fmu.freeInstance()


@pytest.mark.parametrize(("name", "value", "message"), [
    ("l1", -0.3, "invalid l1 = -0.3 m: must be > 0"),
    ("omega_reg", 0.0, "invalid omega_reg = 0.0 rad/s: must be > 0"),
    ("phi1_0", math.nan, "invalid phi1_0 = nan rad: must be finite"),
    ("solver", "radau5", "invalid solver = 'radau5'"),
])
def test_a_bad_parameter_is_an_error_naming_the_variable_and_value(fmu3, name, value, message):
    log: list[str] = []
    with pytest.raises(FMICallException) as info:
        ModelExchange(fmu3, {name: value}, log=log)
    assert info.value.status == 3  # fmi3Error: an exception is an error of this instance only
    assert message in "\n".join(log)


def test_bad_input_reaches_the_log_and_many_failures_leave_the_host_running(fmu3, monkeypatch):
    """Each failed call is fmi3Error with its message logged, and leaves the instance in the Error state,
    from which fmi3Reset brings it back; a hundred of them on one instance (bad values, unknown
    references, wrong types, types the FMU does not have) leave it and the host running."""
    monkeypatch.setenv("DOUBLE_PENDULUM_FMU_STDERR", "0")
    instance = ModelExchange(fmu3, CHAOTIC)
    fmu, phi1 = instance.fmu, instance.refs["phi1"].valueReference
    calls = [lambda: instance.set("pivot_ay", math.nan), lambda: fmu.getFloat64([10**6]),
             lambda: fmu.getInt32([phi1]), lambda: fmu.getFloat32([phi1])]
    try:
        for k in range(100):
            with pytest.raises(FMICallException) as info:
                calls[k % len(calls)]()
            assert info.value.status == 3  # fmi3Error, not fmi3Fatal
            with pytest.raises(FMICallException):
                fmu.setTime(0.0)  # not allowed in the Error state
            fmu.reset()
            instance.initialise()
        log = "\n".join(instance.log)
        assert "invalid input pivot_ay = nan m/s2: must be finite" in log
        assert "fmi3GetFloat32: not supported by this FMU" in log  # the guard's answer, not pythonfmu3's throw
        assert "fmi3SetTime: illegal call sequence: not allowed in state Error" in log
        with pytest.raises(FMICallException):
            instance.set("l1", 0.5)  # a parameter after initialisation
        assert "cannot set parameter l1 = 0.5 after initialisation" in instance.log[-1]
        fmu.reset()
        instance.initialise()
        assert instance.derivatives(0.0, instance.states())[0] == pytest.approx(0.0)  # still answers
    finally:
        instance.close()


