"""FMU state for co-simulation masters: get/set and serialise, continuing bit-identically."""

from __future__ import annotations

import zipfile
from xml.etree import ElementTree as ET

import numpy as np
import pytest

START = {"phi1_0": 2.0, "phi2_0": 2.0, "air_drag": True, "bearing_friction": True, "suspension": True}
OUTPUTS = ("phi1", "phi2", "omega1", "omega2", "xs", "ys", "W_air", "W_bearing", "W_suspension", "E_total")


class Slave:
    """A minimal co-simulation master around fmpy's FMU2Slave."""

    def __init__(self, runner, name: str) -> None:
        from fmpy.fmi2 import FMU2Slave

        md = runner.model_description
        self.vrs = {v.name: v.valueReference for v in md.modelVariables}
        self.types = {v.name: v.type for v in md.modelVariables}
        self.fmu = FMU2Slave(
            guid=md.guid, unzipDirectory=runner.unzipdir, modelIdentifier=md.coSimulation.modelIdentifier,
            instanceName=name,
        )
        self.fmu.instantiate()
        self.time = 0.0

    def initialise(self, start: dict) -> None:
        self.fmu.setupExperiment(startTime=0.0)
        self.fmu.enterInitializationMode()
        for name, value in start.items():
            vr = [self.vrs[name]]
            if self.types[name] == "Boolean":
                self.fmu.setBoolean(vr, [value])
            else:
                self.fmu.setReal(vr, [value])
        self.fmu.exitInitializationMode()

    def run_to(self, t_end: float, step: float = 0.05) -> np.ndarray:
        rows = []
        n = round((t_end - self.time) / step)
        t0 = self.time
        for i in range(n):
            t = t0 + i * step
            self.fmu.doStep(currentCommunicationPoint=t, communicationStepSize=step)
            rows.append(self.fmu.getReal([self.vrs[o] for o in OUTPUTS]))
        self.time = t0 + n * step
        return np.array(rows)

    def close(self) -> None:
        self.fmu.terminate()
        self.fmu.freeInstance()


def test_model_description_declares_state_capabilities(fmu_path):
    with zipfile.ZipFile(fmu_path) as z:
        cs = ET.fromstring(z.read("modelDescription.xml")).find("CoSimulation")
    assert cs.get("canGetAndSetFMUstate") == "true"
    assert cs.get("canSerializeFMUstate") == "true"


def test_restored_state_continues_bit_identically(runner):
    a = Slave(runner, "a")
    a.initialise(START)
    a.run_to(5.0)
    state = a.fmu.getFMUstate()
    serialized = a.fmu.serializeFMUstate(state)
    reference = a.run_to(8.0)

    # 1) roll back the same instance
    a.fmu.setFMUstate(state)
    a.time = 5.0
    again = a.run_to(8.0)
    np.testing.assert_array_equal(again, reference)

    # 2) serialise to bytes and back, into the same instance
    a.fmu.setFMUstate(a.fmu.deSerializeFMUstate(serialized))
    a.time = 5.0
    np.testing.assert_array_equal(a.run_to(8.0), reference)
    a.fmu.freeFMUstate(state)
    a.close()

    # 3) into a fresh instance that never ran
    b = Slave(runner, "b")
    b.fmu.setFMUstate(b.fmu.deSerializeFMUstate(serialized))
    b.time = 5.0
    np.testing.assert_array_equal(b.run_to(8.0), reference)
    b.close()


def test_state_restores_the_parameters_too(runner):
    a = Slave(runner, "p")
    a.initialise({"phi1_0": 0.5, "suspension": True, "k_x": 1234.0})
    a.run_to(1.0)
    blob = a.fmu.serializeFMUstate(a.fmu.getFMUstate())
    a.close()
    b = Slave(runner, "q")  # default parameters until the state is set
    b.fmu.setFMUstate(b.fmu.deSerializeFMUstate(blob))
    assert b.fmu.getReal([b.vrs["k_x"]]) == [pytest.approx(1234.0)]
    b.close()
