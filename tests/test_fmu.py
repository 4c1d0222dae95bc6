"""The FMU through fmpy: validity, units, physics on its outputs, agreement with in-process runs."""

from __future__ import annotations

import io
import math
import os
import re
import subprocess
import sys
import sysconfig
import textwrap
import zipfile
from pathlib import Path
from xml.etree import ElementTree as ET

import numpy as np
import pytest
from conftest import DATA
from scipy.special import ellipk

from double_pendulum.fmu.build import loader
from double_pendulum.fmu.masters.simulate import simulate
from double_pendulum.fmu.running.runner import FmuRunError
from double_pendulum.model.dynamics import linearised_normal_modes
from double_pendulum.model.outputs import OUTPUT_NAMES
from double_pendulum.model.parameters import PendulumParameters
from double_pendulum.runs.results_io import read_results_csv


def _model_description(fmu_path) -> ET.Element:
    with zipfile.ZipFile(fmu_path) as z:
        return ET.fromstring(z.read("modelDescription.xml"))


def test_validate_fmu_reports_no_problems(fmu_path):
    from fmpy.validation import validate_fmu

    assert validate_fmu(str(fmu_path)) == []


def test_physical_variables_carry_fmi_units_and_descriptions(fmu_path):
    root = _model_description(fmu_path)
    defined = {u.get("name") for u in root.find("UnitDefinitions")}
    units = {}
    for sv in root.find("ModelVariables"):
        real = sv.find("Real")
        if real is not None and real.get("unit"):
            units[sv.get("name")] = real.get("unit")
            assert f"[{real.get('unit')}]" in sv.get("description")
    assert set(units.values()) <= defined
    assert units["l1"] == "m" and units["m2"] == "kg" and units["phi1"] == "rad"
    assert units["omega2"] == "rad/s" and units["E_total"] == "J" and units["g"] == "m/s2"
    assert root.find("DefaultExperiment") is not None
    assert set(OUTPUT_NAMES) <= {sv.get("name") for sv in root.find("ModelVariables")}


def test_fmu_bundles_its_code_in_one_archive_its_loaders_and_the_pythons_it_carries(fmu_path):
    from double_pendulum.fmu.build import carried_python

    with zipfile.ZipFile(fmu_path) as z:
        names = z.namelist()
        identity = dict(line.split("=", 1) for line in z.read("resources/identity.cfg").decode().splitlines()
                        if "=" in line and not line.startswith("#"))
        code = zipfile.ZipFile(io.BytesIO(z.read(f"resources/{identity['archive']}")))
        modules = code.namelist()
        slavemodule = z.read("resources/slavemodule.txt").decode()
    assert identity["model"] == "DoublePendulum" and identity["archive"] == "python_code.zip"
    entry, package = identity["entry"], identity["package"]
    prefix = package.removesuffix("_adapters")
    assert re.fullmatch(r"_dp_fmu_[0-9a-f]{16}", prefix) and entry == f"{prefix}_DoublePendulum"
    assert slavemodule == entry  # pythonfmu's convention, for tools that read it
    assert f"{entry}.py" in modules and f"{package}/DoublePendulum.py" in modules
    assert f"{prefix}/model/dynamics.py" in modules and f"{prefix}_pythonfmu/fmi2slave.py" in modules
    assert not [n for n in modules if not n.startswith("_dp_fmu_")]  # nothing importable under a public name
    assert not [n for n in modules if n.rpartition("/")[2] in ("builder.py", "__main__.py")]  # no builder
    assert not [n for n in names if n.startswith("resources/") and n.endswith((".py", ".pyc"))]  # one archive
    assert "resources/requirements.txt" not in names  # it needs nothing installed
    assert "resources/python.cfg" not in names  # a self-contained FMU records no Python of the build machine
    for python in carried_python.PLATFORMS:
        folder = f"binaries/{loader.TARGETS[python].folder(2)}/"
        binary = f"{folder}DoublePendulum{loader.TARGETS[python].suffix}"
        assert binary in names, binary
        minor = sys.version_info[1]
        library = f"libpython3.{minor}.so.1.0" if python == "x86_64-linux" else f"python3{minor}.dll"
        assert f"{folder}{library}" in names and f"{folder}python3{minor}.zip" in names
    assert {n.split("/")[1] for n in names if n.startswith("binaries/")} == {"linux64", "win64"}


def test_a_lean_fmu_carries_no_python_and_records_the_builds(tmp_path):
    """``build --lean``: the Linux loader alone, and the CPython of the build recorded for it to find."""
    from double_pendulum.fmu.build.fmi2 import build_fmu

    lean = build_fmu(tmp_path / "DoublePendulum.fmu", lean=True)
    with zipfile.ZipFile(lean) as z:
        names = z.namelist()
        record = z.read("resources/python.cfg").decode()
        tool = ET.fromstring(z.read("modelDescription.xml")).find("CoSimulation").get("needsExecutionTool")
    assert [n for n in names if n.startswith("binaries/")] == ["binaries/linux64/DoublePendulum.so"]
    assert f"version={sys.version_info[0]}.{sys.version_info[1]}" in record and f"home={sys.base_prefix}" in record
    assert tool == "true"  # it needs a CPython where it runs
    assert lean.stat().st_size < 1e6


def test_fmu_runs_without_the_project_installed(fmu_path, tmp_path):
    """In a Python that cannot import double_pendulum, the FMU still runs from its resources."""
    site_packages = sysconfig.get_paths()["purelib"]
    script = textwrap.dedent(f"""
        import sys
        sys.path.append({site_packages!r})  # fmpy, numpy; no .pth files, so no editable project
        try:
            import double_pendulum
        except ImportError:
            pass
        else:
            raise SystemExit("double_pendulum is importable: the test would prove nothing")
        from fmpy import simulate_fmu
        r = simulate_fmu({str(fmu_path)!r}, stop_time=1.0, output_interval=0.1,
                         start_values={{"phi1_0": 1.5}}, output=["phi1"])
        print(repr(float(r["phi1"][-1])), flush=True)
        import os
        os._exit(0)  # skip interpreter teardown: pythonfmu 0.7 may abort there (upstream issue #228)
    """)
    out = subprocess.run(
        [sys.executable, "-S", "-c", script], capture_output=True, text=True, cwd=tmp_path, timeout=120
    )
    assert out.returncode == 0, out.stderr
    expected = simulate({"phi1_0": 1.5}, stop_time=1.0, output_interval=0.1, outputs=["phi1"])["phi1"][-1]
    assert float(out.stdout.strip()) == expected


def test_frictionless_energy_drift_below_1e9_over_30s(runner):
    r = runner.simulate(
        {"phi1_0": 2.0, "phi2_0": 2.0, "rtol": 1e-12, "atol": 1e-14}, stop_time=30.0, output_interval=0.01
    )
    e = r["E_total"]
    drift = np.max(np.abs(e - e[0])) / abs(e[0])
    assert drift < 1e-9
    assert np.max(np.abs(r["phi2"])) > math.pi  # the chaotic start really flips over


def _zero_crossing_times(t: np.ndarray, x: np.ndarray) -> np.ndarray:
    i = np.nonzero(np.sign(x[:-1]) * np.sign(x[1:]) < 0)[0]
    return t[i] - x[i] * (t[i + 1] - t[i]) / (x[i + 1] - x[i])


@pytest.mark.parametrize("mode", [0, 1])
def test_small_angle_motion_has_the_analytic_normal_mode_frequencies(runner, mode):
    """Started in a pure linear mode with 1e-4 rad amplitude, the FMU oscillates at omega_k: over 20 periods,
    sampled 100 times a period (the zero crossings interpolated linearly, exact to third order where the
    curvature vanishes), the measured frequency is 7e-10 (mode 0) and 3.5e-8 (mode 1) from omega_k and the
    mode shape's ratio 1e-10 and 1e-9 from the linear one, the same to two digits as at 1,000 samples a
    period (what the test took before, 5 times the CPU); the test allows 1e-4 and 1e-3."""
    omegas, shapes = linearised_normal_modes(PendulumParameters())
    amp = 1e-4
    start = {"phi1_0": amp, "phi2_0": amp * shapes[mode][1], "rtol": 1e-12, "atol": 1e-16}
    periods = 20
    stop = periods * 2 * math.pi / omegas[mode]
    r = runner.simulate(start, stop_time=stop, output_interval=stop / (100 * periods))
    crossings = _zero_crossing_times(r["time"], r["phi1"])
    measured = math.pi * (len(crossings) - 1) / (crossings[-1] - crossings[0])
    assert measured == pytest.approx(omegas[mode], rel=1e-4)
    # The other mode is not excited: phi2/phi1 stays at the mode shape.
    big = np.abs(r["phi1"]) > 0.5 * amp
    assert np.median(r["phi2"][big] / r["phi1"][big]) == pytest.approx(shapes[mode][1], rel=1e-3)


def test_vanishing_lower_mass_reduces_to_the_single_pendulum(runner):
    """m2 -> 0: phi1 swings with the exact large-amplitude period 4 sqrt(l/g) K(sin^2(theta/2)). Sampled every
    5 ms over 10 s (the zero crossings interpolated linearly): the period 1.1e-8 from the exact one (every 1 ms:
    9.5e-10, at 4 times the CPU), the test allows 1e-6; the amplitude is the start's, sampled at t = 0."""
    p = PendulumParameters()
    theta = 1.0
    r = runner.simulate(
        {"m2": 1e-9, "phi1_0": theta, "phi2_0": theta, "rtol": 1e-12, "atol": 1e-14},
        stop_time=10.0,
        output_interval=5e-3,
    )
    crossings = _zero_crossing_times(r["time"], r["phi1"])
    period = 2 * (crossings[-1] - crossings[0]) / (len(crossings) - 1)
    exact = 4 * math.sqrt(p.l1 / p.g) * ellipk(math.sin(theta / 2) ** 2)
    assert period == pytest.approx(exact, rel=1e-6)
    assert np.max(np.abs(r["phi1"])) == pytest.approx(theta, rel=1e-6)


@pytest.mark.parametrize("solver", ["dop853", "dopri5", "rk4", "euler"])
def test_fmu_equals_in_process_results_of_the_same_solver(runner, solver):
    start = {
        "phi1_0": 2.0,
        "phi2_0": 1.0,
        "omega2_0": 1.0,
        "solver": solver,
        "rtol": 1e-8,
        "fixed_step": 1e-3,
    }
    a = runner.simulate(start, stop_time=2.0, output_interval=0.02)
    b = simulate(start, stop_time=2.0, output_interval=0.02)
    for name in a.dtype.names:
        np.testing.assert_array_equal(a[name], b[name])


@pytest.mark.parametrize("solver", ["dop853", "dopri5", "rk4"])
def test_result_does_not_depend_on_the_communication_step(runner, solver):
    start = {"phi1_0": 2.0, "phi2_0": 2.0, "solver": solver, "rtol": 1e-10, "atol": 1e-12, "fixed_step": 1e-3}
    fine = runner.simulate(start, stop_time=3.0, output_interval=1e-3)
    coarse = runner.simulate(start, stop_time=3.0, output_interval=0.05)
    for name in ("phi1", "phi2", "omega1", "omega2"):
        assert fine[name][-1] == pytest.approx(coarse[name][-1], abs=1e-8)
        # also at every coarse point (dense output on both grids)
        np.testing.assert_allclose(fine[name][::50], coarse[name], atol=1e-8, rtol=0)


@pytest.mark.parametrize("case", ["regular", "chaotic"])
def test_agrees_with_the_committed_reference_trajectory(runner, case):
    """data/reference/*.csv: Hamilton's equations, independent of our accelerations (make_reference.py)."""
    ref = read_results_csv(DATA / "reference" / f"{case}.csv")
    start = {"phi1_0": ref["phi1"][0], "phi2_0": ref["phi2"][0], "rtol": 1e-12, "atol": 1e-14}
    r = runner.simulate(start, stop_time=float(ref["time"][-1]), output_interval=0.01)
    tol = 1e-9 if case == "regular" else 1e-7
    for name in ("phi1", "phi2", "omega1", "omega2"):
        np.testing.assert_allclose(r[name], ref[name], atol=tol, rtol=0)


@pytest.mark.parametrize(
    ("start", "names"),
    [
        ({"l1": -0.3}, "l1 = -0.3 m"),
        ({"l2": 0.0}, "l2 = 0.0 m"),
        ({"m1": -1.0}, "m1 = -1.0 kg"),
        ({"phi1_0": math.nan}, "phi1_0 = nan rad"),
        ({"omega2_0": math.inf}, "omega2_0 = inf rad/s"),
        ({"solver": "leapfrog"}, "solver = 'leapfrog'"),
        ({"rtol": 0.0}, "rtol = 0.0"),
        ({"fixed_step": -1e-3}, "fixed_step = -0.001 s"),
    ],
)
def test_bad_parameters_give_an_error_status_naming_the_variable(runner, start, names):
    with pytest.raises(FmuRunError, match="status") as info:
        runner.simulate(start, stop_time=1.0)
    assert names in str(info.value)
    # and the runner still works afterwards, with a new instance
    assert runner.simulate({}, stop_time=0.1)["time"][-1] == pytest.approx(0.1)


def test_bad_parameters_raise_in_plain_fmpy_too(fmu_path, tmp_path):
    from fmpy import extract, simulate_fmu
    from fmpy.fmi1 import FMICallException

    # extracted here: fmpy removes the folder it extracts into only when the run returns, not when it raises
    unzipped = extract(str(fmu_path), unzipdir=str(tmp_path / "fmu"))
    with pytest.raises(FMICallException):
        simulate_fmu(unzipped, stop_time=1.0, start_values={"l1": -1.0})


def test_numerical_blow_up_is_reported_not_returned(runner):
    with pytest.raises(FmuRunError, match="numerical instability") as info:
        runner.simulate(
            {"solver": "euler", "fixed_step": 0.5, "phi1_0": 3.0, "omega2_0": 40.0},
            stop_time=100.0,
            output_interval=1.0,
        )
    partial = info.value.partial_result
    assert partial is not None and np.all(np.isfinite(partial["E_total"]))


def test_repeated_plain_fmpy_runs_with_fresh_extractions_work(fmu_path):
    """fmpy extracts the FMU anew for every call and deletes it afterwards; the bundled package
    stays imported from the first extraction, so nothing may be imported lazily from it later."""
    from fmpy import simulate_fmu

    for solver in ("dop853", "rodas4", "gauss4", "rk4"):
        r = simulate_fmu(str(fmu_path), stop_time=0.2, start_values={"solver": solver, "fixed_step": 1e-3})
        assert r["time"][-1] == pytest.approx(0.2)


def test_fmu_ships_hash_checked_bytecode_beside_each_source(fmu_path):
    import importlib.util

    with zipfile.ZipFile(fmu_path) as z, zipfile.ZipFile(io.BytesIO(z.read("resources/python_code.zip"))) as code:
        names = set(code.namelist())
        sources = [n for n in names if n.endswith(".py")]
        assert sources and all(f"{n}c" in names for n in sources)  # mod.pyc beside mod.py, where zipimport looks
        dynamics = next(n for n in sources if n.endswith("/model/dynamics.py"))
        compiled = code.read(f"{dynamics}c")
        assert compiled[:4] == importlib.util.MAGIC_NUMBER
        assert int.from_bytes(compiled[4:8], "little") == 0b11  # PEP 552: hash-based, checked against the source
        assert compiled[8:16] == importlib.util.source_hash(code.read(dynamics))
        assert all(info.compress_type == zipfile.ZIP_STORED for info in code.infolist())  # no zlib needed to read


def test_fmu_bundles_only_the_runtime(fmu_path):
    """The archive holds the adapters, pythonfmu's slave modules and the runtime subpackages: no analysis, plots
    or CLI."""
    from double_pendulum.fmu.build.staging import RUNTIME_SUBPACKAGES

    with zipfile.ZipFile(fmu_path) as z, zipfile.ZipFile(io.BytesIO(z.read("resources/python_code.zip"))) as code:
        identity = z.read("resources/identity.cfg").decode()
        runtime = re.search(r"package=(_dp_fmu_[0-9a-f]+)_adapters", identity).group(1) + "/"
        sources = [n for n in code.namelist() if n.startswith(runtime) and n.endswith(".py")]
    parts = {n.split("/")[1] for n in sources}
    assert parts == {"__init__.py", *RUNTIME_SUBPACKAGES}
    assert not any(word in n for n in sources for word in ("analysis", "plots", "cli", "scenarios", "fmu/"))


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="the C loader is for Linux")
def test_without_a_c_compiler_the_build_stops_with_one_line_and_leaves_no_fmu(tmp_path, monkeypatch):
    """The FMU's binary is compiled from source: without a compiler there is no FMU to write, and the CLI
    says why in one line (no traceback, nothing half-written)."""
    from double_pendulum.fmu.build import fmi2, loader

    monkeypatch.setenv("CC", "/nonexistent/cc")
    with pytest.raises(loader.LoaderUnavailable, match="no C compiler found"):
        fmi2.build_fmu(tmp_path / "DoublePendulum.fmu")
    assert not list(tmp_path.iterdir())
    done = subprocess.run([sys.executable, "-m", "double_pendulum.cli", "build", "-o", str(tmp_path / "out")],
                          capture_output=True, text=True, env={**os.environ, "CC": "/nonexistent/cc"})
    assert done.returncode != 0 and "Traceback" not in done.stderr, done.stderr
    assert len(done.stderr.strip().splitlines()) == 1 and "no C compiler found" in done.stderr, done.stderr


def test_a_newer_build_module_makes_the_fmu_stale(fmu_path, tmp_path, monkeypatch):
    """The FMU holds what the build's own modules write (documentation, icon, terminals): a change to one
    of them, not only to the bundled code, means the FMU must be built again."""
    from double_pendulum.fmu.build import fmi2

    assert fmi2.fmu_is_current(fmu_path)
    newer = tmp_path / "documentation.py"
    newer.write_text("")
    os.utime(newer, (fmu_path.stat().st_mtime + 60,) * 2)
    monkeypatch.setattr(fmi2, "build_sources", lambda: [newer])
    assert not fmi2.fmu_is_current(fmu_path)


def test_every_fmu_claims_only_the_platforms_it_ran_on_and_no_sources_that_do_not_build_it(fmu_path):
    """Each FMU's binaries are the loaders for x86_64 Linux and Windows with the CPython each carries, where both
    are run in the tests (tests/test_self_contained.py: Linux without any Python, Windows under Wine); no
    pythonfmu binary, no macOS; the container carries fmpy's Linux binary (its Windows one could not be run here:
    fmu/build/container.py), its members both; and no
    FMU ships sources/ (pythonfmu3's sources build its own C++ library, not the FMU's binary)."""
    folder = fmu_path.parent
    for fmu, platforms in ((fmu_path, {"linux64", "win64"}), (folder / "Suspension.fmu", {"linux64", "win64"}),
                           (folder / "fmi3" / "DoublePendulum.fmu", {"x86_64-linux", "x86_64-windows"}),
                           (folder / "PendulumOnSuspension.fmu", {"linux64"})):  # container.CONTAINER_BINARIES
        with zipfile.ZipFile(fmu) as z:
            names = z.namelist()
        found = {n.split("/")[1] for n in names if n.startswith("binaries/") and n.count("/") >= 2}
        assert found == platforms, (fmu.name, found)
        assert not [n for n in names if n.startswith("sources/")], fmu.name
        assert not [n for n in names if "pythonfmu-export" in n or n.endswith(".dylib")], fmu.name
        members = {n.split("/")[3] for n in names if n.startswith("resources/") and "/binaries/" in n}
        assert members <= {"linux64", "win64"}, (fmu.name, members)


CARRIED_LIBRARY_LICENCES = {"libffi.txt", "libz.txt", "libbz2.txt", "liblzma.txt", "libuuid.txt"}
"""The system libraries a carried Linux CPython's extension modules need (their Debian copyright files, where the
build machine has them)."""


def test_every_fmu_carries_the_licences_of_what_it_bundles(fmu_path):
    """documentation/licenses/: the project's MIT licence and those of pythonfmu (FMI 2) or pythonfmu3 (FMI 3),
    and for the container fmpy's (its container binary), each the text the distribution ships; and CPython's
    for each platform's carried CPython (python.org's Windows text covers the libraries its build carries)."""
    from double_pendulum.fmu.carries.presentation import distribution_licence

    project = (Path(__file__).resolve().parents[1] / "LICENSE").read_bytes()
    folder = fmu_path.parent
    for fmu, bundled in ((fmu_path, ("double-pendulum-fmu", "pythonfmu")),
                         (folder / "Suspension.fmu", ("double-pendulum-fmu", "pythonfmu")),
                         (folder / "fmi3" / "DoublePendulum.fmu", ("double-pendulum-fmu", "pythonfmu3")),
                         (folder / "PendulumOnSuspension.fmu", ("double-pendulum-fmu", "fmpy"))):
        with zipfile.ZipFile(fmu) as z:
            licences = {n.rpartition("/")[2]: z.read(n) for n in z.namelist()
                        if n.startswith("documentation/licenses/")}
        carried = {n for n in licences if n.startswith("CPython-")}  # the CPython each platform's binaries carry
        assert set(licences) - carried - {f"{name}.txt" for name in bundled} <= CARRIED_LIBRARY_LICENCES, \
            (fmu.name, sorted(licences))
        assert {f"{name}.txt" for name in bundled} <= set(licences), (fmu.name, sorted(licences))
        assert licences["double-pendulum-fmu.txt"].strip() == project.strip()
        for name in bundled:
            assert licences[f"{name}.txt"] == distribution_licence(name) and len(licences[f"{name}.txt"]) > 200
        if fmu.name != "PendulumOnSuspension.fmu":  # the container's members carry their own
            assert {re.sub(r"CPython-3\.\d+\.\d+-", "", n) for n in carried} == {"linux.txt", "windows.txt"}
            assert all(b"PYTHON SOFTWARE FOUNDATION LICENSE" in licences[n] for n in carried)
