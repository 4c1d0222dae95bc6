"""The FMU in a Python host: it runs on the host's own interpreter and leaves it as it found it.

One fresh process runs the FMU through fmpy (and the FMI 3.0 FMU both ways), then builds FMUs
(ours, and a user's own with pythonfmu), then runs the coupled system on libcosim and as fmpy's
container FMU. Before, the FMU's bundled ``pythonfmu`` stayed on ``sys.path`` and in
``sys.modules``, and every FMU built after it had no binary (libcosim: "no binary for this
platform"; the container aborted).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

pytest.importorskip("libcosimpy", reason="libcosimpy (the test extra) is not installed")

SCRIPT = textwrap.dedent("""
    import json, os, sys, zipfile
    from pathlib import Path

    out = {}
    path_before, modules_before = list(sys.path), set(sys.modules)
    from fmpy import simulate_fmu
    result = simulate_fmu(sys.argv[1], stop_time=0.5, output_interval=0.01, start_values={"phi1_0": 2.0})
    out["phi1"] = float(result["phi1"][-1])
    for interface in ("ModelExchange", "CoSimulation"):  # the FMI 3.0 FMU, both ways
        result = simulate_fmu(sys.argv[3], fmi_type=interface, stop_time=0.5, output_interval=0.01,
                              start_values={"phi1_0": 2.0})
        out["phi1_fmi3_" + interface] = float(result["phi1"][-1])
    out["sys_path_unchanged"] = sys.path == path_before
    added = set(sys.modules) - modules_before
    out["public_fmu_modules"] = sorted(name for name in added if not name.startswith("_dp_fmu_") and any(
        name == p or name.startswith(p + ".") for p in ("pythonfmu", "pythonfmu3", "double_pendulum", "DoublePendulum",
                                                         "double_pendulum_slave", "slave_common",
                                                         "DoublePendulumFmi3")))
    maps = Path("/proc/self/maps").read_text() if Path("/proc/self/maps").exists() else ""
    out["libpythons"] = sorted({line.split()[-1] for line in maps.splitlines() if "libpython3" in line})

    # a build after the run: ours, and a user's own slave with pythonfmu's builder
    from double_pendulum.fmu.build.systems import build_all
    folder = Path(sys.argv[2])
    built = build_all(folder / "DoublePendulum.fmu")
    user = folder / "user_slave.py"
    user.write_text("from pythonfmu import Fmi2Slave, Fmi2Causality, Real\\n"
                    "class UserSlave(Fmi2Slave):\\n"
                    "    def __init__(self, **kwargs):\\n"
                    "        super().__init__(**kwargs)\\n"
                    "        self.y = 1.0\\n"
                    "        self.register_variable(Real('y', causality=Fmi2Causality.output))\\n"
                    "    def do_step(self, t, h):\\n"
                    "        return True\\n")
    from pythonfmu.builder import FmuBuilder
    built.append(FmuBuilder.build_FMU(user, dest=folder))
    fmus = [Path(p) for p in built if str(p).endswith(".fmu")]
    linux = ("binaries/linux64/", "binaries/x86_64-linux/")  # FMI 2, FMI 3
    out["binaries"] = {str(p.relative_to(folder)): sorted(n for n in zipfile.ZipFile(p).namelist()
                                                          if n.startswith(linux)) for p in fmus}

    # the coupled system on libcosim and as the container FMU, in this same process
    from double_pendulum.fmu.running.hosts import simulate_container, simulate_ssp_with_libcosim
    ssp = simulate_ssp_with_libcosim(folder / "PendulumOnSuspension.ssp", stop_time=0.05, macro_step=1e-3)
    container = simulate_container(folder / "PendulumOnSuspension.fmu", stop_time=0.05, macro_step=1e-3)
    out["ssp_phi1"], out["container_phi1"] = float(ssp["phi1"][-1]), float(container["phi1"][-1])
    print(json.dumps(out), flush=True)
    os._exit(0)  # skip the teardown, see docs/fmu.md (pythonfmu issue #228)
""")


@pytest.fixture(scope="module")
def session(fmu_path: Path, fmu3_path: Path, tmp_path_factory: pytest.TempPathFactory) -> dict:
    """The script's findings; the override points nowhere: a Python host must not need it."""
    folder = tmp_path_factory.mktemp("python_host")
    env = {**os.environ, "DOUBLE_PENDULUM_FMU_PYTHON": "/nonexistent/python3"}
    done = subprocess.run([sys.executable, "-c", SCRIPT, str(fmu_path), str(folder), str(fmu3_path)],
                          capture_output=True, text=True, cwd=folder, env=env, timeout=600)
    assert done.returncode == 0, done.stderr[-3000:]
    return json.loads(done.stdout.strip().splitlines()[-1])


def test_the_fmu_runs_on_the_hosts_own_python_and_loads_no_second_one(session):
    assert abs(session["phi1"]) < 4  # it ran (the override, pointing nowhere, was not needed)
    # the FMI 3.0 FMU too, both interfaces: the same motion (CS: the same component as FMI 2, bit for bit)
    assert session["phi1_fmi3_CoSimulation"] == session["phi1"]
    assert session["phi1_fmi3_ModelExchange"] == pytest.approx(session["phi1"], abs=1e-6)
    assert len(session["libpythons"]) <= 1  # the host's libpython (or none: a static python), no second copy


def test_the_fmu_leaves_sys_path_and_the_public_modules_as_they_were(session):
    assert session["sys_path_unchanged"]
    assert session["public_fmu_modules"] == []


def test_fmus_built_after_running_one_hold_their_binaries(session):
    binaries = session["binaries"]
    assert set(binaries) == {"DoublePendulum.fmu", "Suspension.fmu", "PendulumOnSuspension.fmu", "UserSlave.fmu",
                             "fmi3/DoublePendulum.fmu"}
    library = f"libpython3.{sys.version_info[1]}.so.1.0"
    for name, folder in (("DoublePendulum", "linux64"), ("Suspension", "linux64"),
                         ("fmi3/DoublePendulum", "x86_64-linux")):
        found = binaries[f"{name}.fmu"]
        loader = f"binaries/{folder}/{name.rpartition('/')[2]}.so"
        assert loader in found and f"binaries/{folder}/{library}" in found, found  # the loader and the Python
        assert not [n for n in found if "pythonfmu" in n], found  # no FMI library's binary
    assert binaries["UserSlave.fmu"] == ["binaries/linux64/UserSlave.so"]  # the user's build: pythonfmu's own


def test_libcosim_and_the_container_run_after_fmpy_in_the_same_process(session):
    # both Jacobi at the same macro step; they start the coupling differently (libcosim exchanges twice
    # while initialising), which moves phi1 by some 3e-6 rad after 50 steps
    assert session["ssp_phi1"] == pytest.approx(session["container_phi1"], abs=1e-5)
