"""A user's FMU is only read (issue 52): ``run``, ``simulate``, ``app`` and the examples run an FMU given by ``--fmu``
as it is, never build over it or beside it, and refuse a missing or foreign one in one line naming it, leaving the
file system as it was (every entry of the user's folder, its size and its mtime, before and after); the project's
FMUs are built in the build folder, ``--build-dir``."""

from __future__ import annotations

import pytest
from fmpy import read_model_description

from double_pendulum.fmu.running.choice import FmuPathError, read_pendulum_fmu


def test_the_check_of_a_given_fmu_reads_its_model_description(built_fmus, tmp_path):
    assert read_pendulum_fmu(built_fmus[0]).fmiVersion == "2.0"
    assert read_pendulum_fmu(built_fmus[-1]).fmiVersion == "3.0"
    suspension = built_fmus[1]
    assert read_model_description(str(suspension)).modelName == "Suspension"
    with pytest.raises(FmuPathError, match=r"Suspension\.fmu is not an FMU of the double pendulum: its model "
                                           r"'Suspension' has no phi1_0, phi2_0, omega1_0, omega2_0 and \d+ more"):
        read_pendulum_fmu(suspension)
    broken = tmp_path / "broken.fmu"
    broken.write_bytes(b"not a zip file")
    with pytest.raises(FmuPathError, match="broken.fmu is not a usable FMU \\(BadZipFile: "):
        read_pendulum_fmu(broken)
    with pytest.raises(FmuPathError, match="nowhere.fmu: no such file"):
        read_pendulum_fmu(tmp_path / "nowhere.fmu")
    with pytest.raises(FmuPathError, match="is a folder, not an FMU file"):
        read_pendulum_fmu(tmp_path)
    assert list(tmp_path.iterdir()) == [broken]  # nothing written
