"""The pytest plugin for FMU outputs (double_pendulum.testing, docs/testing.md), run as a user runs it: pytest
sessions in this process (pytester) on the session's built FMUs, given with --fmu, their outcomes and failure
messages asserted; and the tube comparison on signals whose answer is known."""

from __future__ import annotations

import os
import re
from pathlib import Path

import fmpy.util  # noqa: F401 (below)
import matplotlib.figure  # noqa: F401
import numpy as np
import pytest
import scipy.interpolate  # noqa: F401
import scipy.ndimage  # noqa: F401

import double_pendulum.testing.cases  # noqa: F401
import double_pendulum.testing.physics  # noqa: F401
from double_pendulum.testing import Result, Tolerance, assert_matches_reference

# pytester's in-process runs forget the modules a run imported, and an extension module cannot be loaded twice in a
# process (numpy.fft's): what the plugin's runs import is imported here once, before them.

pytest_plugins = ["pytester"]

# the inner runs: no plugin they need not load (each run imports them anew: about 2 s; dash's warns), no cache written
# beside the test files
QUIET = ("-p", "no:dash", "-p", "no:hypothesispytest", "-p", "no:xdist", "-p", "no:xdist.looponfail",
         "-p", "no:cacheprovider")


# --- the tube ------------------------------------------------------------------------------------------------


def _signal(t: np.ndarray, y: np.ndarray, label: str) -> Result:
    data = np.zeros(len(t), dtype=[("time", float), ("x", float)])
    data["time"], data["x"] = t, y
    return Result(data, {"time": "s", "x": "m"}, label)


REFERENCE = _signal(np.linspace(0, 4, 401), np.sin(2 * np.pi * np.linspace(0, 4, 401)), "reference")
STILL = _signal(np.linspace(0, 4, 401), np.cos(2 * np.pi * np.linspace(0, 4, 401)), "reference")  # starts at rest


def test_a_signal_late_by_less_than_the_time_tolerance_passes_and_one_later_fails():
    t = np.linspace(0, 4, 401)
    late = _signal(t, np.cos(2 * np.pi * (t - 0.015)), "late")  # 0.094 m off at the steepest, far above atol
    checks = assert_matches_reference(late, STILL, time=0.02, atol=1e-3, rtol=0)
    assert checks["x"].deviation == pytest.approx(2 * np.sin(np.pi * 0.015), rel=0.01)
    with pytest.raises(AssertionError, match=r"x: left the tube first at t = 0.02 s \(3\d\d of 399 points outside\)"):
        assert_matches_reference(late, STILL, time=0.01, atol=1e-3, rtol=0)


def test_a_spike_just_outside_the_value_tolerance_fails_at_its_time(tmp_path):
    t = np.linspace(0, 4, 801)
    y = np.sin(2 * np.pi * t)
    k = int(np.searchsorted(t, 2.5))
    spiked, inside = y.copy(), y.copy()
    spiked[k] += 0.0105  # the tube: +-0.01 m
    inside[k] += 0.0095
    assert_matches_reference(_signal(t, inside, "inside"), REFERENCE, atol=0.01, rtol=0)
    with pytest.raises(AssertionError) as failed:
        assert_matches_reference(_signal(t, spiked, "spiked"), REFERENCE, atol=0.01, rtol=0, plot_dir=tmp_path)
    message = str(failed.value)
    assert "1 of 1 variables left the tube" in message
    assert "x: left the tube first at t = 2.5 s (1 of 799 points outside)" in message
    assert re.search(r"largest deviation 0.010[45]\d* m at t = 2.5 s, 0.000[45]\d* m beyond the tube", message)
    assert f"plot: {tmp_path / 'tube-x.png'}" in message and (tmp_path / "tube-x.png").stat().st_size > 10_000


def test_the_right_signal_sampled_differently_passes_and_a_short_one_does_not():
    t = np.concatenate([[0.0], np.sort(np.random.default_rng(5).uniform(0, 4, 1234)), [4.0]])  # uneven steps
    assert_matches_reference(_signal(t, np.sin(2 * np.pi * t), "resampled"), REFERENCE, atol=1e-3, rtol=0)
    short = _signal(t[t < 3], np.sin(2 * np.pi * t[t < 3]), "short")
    with pytest.raises(AssertionError, match="the result ends at t = 2.99[0-9]* s, the reference runs to 4 s"):
        assert_matches_reference(short, REFERENCE, atol=1e-3, rtol=0)


def test_a_constant_zero_reference_gets_the_tolerance_asked_for():
    """fmpy's band gives a reference of zeros a fixed width of 0.5: the tolerance asked for holds all the same."""
    t = np.linspace(0, 1, 101)
    zero = _signal(t, np.zeros_like(t), "rest")
    assert_matches_reference(_signal(t, np.full_like(t, 0.009), "near"), zero, atol=0.01, rtol=0)
    with pytest.raises(AssertionError, match="x: left the tube first at t = 0.01 s"):
        assert_matches_reference(_signal(t, np.full_like(t, 0.011), "off"), zero, atol=0.01, rtol=0)
    with pytest.raises(ValueError, match="tolerance time = -1"):
        Tolerance(time=-1)


# --- the plugin in a user's session ---------------------------------------------------------------------------

USERS_TESTS = '''
import pytest
from double_pendulum.testing import (ENERGY_COLUMNS, SimulationFailed, assert_conserved, assert_energy_budget_closes,
                                     assert_energy_never_rises, assert_matches_reference, assert_normal_mode_periods,
                                     normal_mode_start, pendulum_parameters)

MOVED = {"DoublePendulum": ({"phi1_0": 1.02}, "phi1"), "Suspension": ({"F_static_y": -50.0}, "y")}


def test_own_reference(fmu, simulate, reference):
    assert_matches_reference(simulate.like(reference), reference, time=0.002, rtol=1e-6)


def test_moved_start(fmu, simulate, reference):
    start, name = MOVED[fmu.name]
    assert_matches_reference(simulate.like(reference, start_values=start), reference, [name], time=0.01, rtol=1e-3)


def test_runs_are_kept_with_units(fmu, simulate):
    first, again = simulate(stop_time=0.2), simulate(stop_time=0.2)
    assert first.data is again.data and first.unit("time") == "s" and not first.data.flags.writeable
    assert {name: first.unit(name) for name in first.names} == {name: fmu.units[name] for name in fmu.outputs}


def test_failed_run(fmu, simulate):
    bad = {"DoublePendulum": {"l1": -1.0}, "Suspension": {"M_s": -1.0}}[fmu.name]
    simulate(start_values=bad, stop_time=0.1)


def test_physics_holds(fmu, simulate):
    if fmu.name != "DoublePendulum":
        pytest.skip("the pendulum's physics")
    lossy = simulate(start_values={"air_drag": True, "bearing_friction": True}, stop_time=3, output_interval=0.01,
                     outputs=list(ENERGY_COLUMNS))
    assert_energy_budget_closes(lossy, rtol=1e-6)
    assert_energy_never_rises(lossy)
    assert_conserved(simulate(stop_time=3, outputs=["E_total"]), rtol=1e-6)
    parameters = pendulum_parameters(fmu.variables)
    for mode in ("slow", "fast"):
        swing = simulate(start_values=normal_mode_start(parameters, mode), stop_time=4, output_interval=0.002,
                         outputs=["phi1", "phi2"])
        assert_normal_mode_periods(swing, parameters, mode, rtol=1e-3)


def test_physics_broken(fmu, simulate):
    if fmu.name != "DoublePendulum":
        pytest.skip("the pendulum's physics")
    parameters = pendulum_parameters(fmu.variables)
    swing = simulate(start_values=normal_mode_start(parameters, "slow"), stop_time=4, output_interval=0.002,
                     outputs=["phi1", "phi2"])
    assert_normal_mode_periods(swing, parameters, "fast")
'''


def test_a_users_tests_pass_and_fail_with_their_reasons(pytester, built_fmus):
    pendulum, suspension = built_fmus[0], built_fmus[1]
    pytester.makepyfile(test_mine=USERS_TESTS)
    run = pytester.runpytest_inprocess(*QUIET, f"--fmu={pendulum}", f"--fmu={suspension}", "-v")
    outcomes = dict(re.findall(r"^test_mine.py::(\S+) (PASSED|FAILED|SKIPPED)", run.stdout.str(), re.MULTILINE))
    assert outcomes == {
        "test_own_reference[DoublePendulum-fmi2-CS]": "PASSED", "test_own_reference[Suspension-fmi2-CS]": "PASSED",
        "test_moved_start[DoublePendulum-fmi2-CS]": "FAILED", "test_moved_start[Suspension-fmi2-CS]": "FAILED",
        "test_runs_are_kept_with_units[DoublePendulum-fmi2-CS]": "PASSED",
        "test_runs_are_kept_with_units[Suspension-fmi2-CS]": "PASSED",
        "test_failed_run[DoublePendulum-fmi2-CS]": "FAILED", "test_failed_run[Suspension-fmi2-CS]": "FAILED",
        "test_physics_holds[DoublePendulum-fmi2-CS]": "PASSED", "test_physics_broken[DoublePendulum-fmi2-CS]": "FAILED",
        "test_physics_holds[Suspension-fmi2-CS]": "SKIPPED", "test_physics_broken[Suspension-fmi2-CS]": "SKIPPED",
    }, run.outlines
    text = run.stdout.str()
    # the tube: which variable, when it first left, how far, and the plot
    assert "DoublePendulum.fmu CS does not match DoublePendulum.fmu's reference:" in text
    assert "phi1: left the tube first at t = " in text
    assert "Suspension.fmu CS does not match Suspension.fmu's reference:" in text and "y: left the tube first" in text
    plots = sorted(Path(p) for p in re.findall(r"^E +plot: (\S+)$", run.stdout.str(), re.MULTILINE))
    assert [p.name for p in plots] == ["tube-phi1.png", "tube-y.png"]
    assert all(p.stat().st_size > 10_000 and p.is_relative_to(pytester.path.parent) for p in plots)  # pytest's tmp
    # a failed run: the FMU's own message
    assert "invalid l1 = -1.0 m: must be > 0" in text and "invalid M_s = -1.0 kg" in text
    assert "the slow normal mode" not in text and "phi1 swings with a period of 1.30" in text
    assert "the fast normal mode's is 0.528" in text
    assert sorted(p.name for p in pytester.path.iterdir()) == ["test_mine.py"]


def test_misuse_is_a_usage_error_naming_it_and_two_fmus_of_one_name_keep_apart(pytester, fmu_path):
    pytester.makepyfile(test_mine="import pytest\n\ndef test_one(fmu):\n    pass\n")
    for options, message in ((["--fmu=models/Mine.fmu"], "--fmu models/Mine.fmu: no such file"),
                             ([f"--fmu={fmu_path}", f"--fmu={fmu_path}"], f"--fmu {fmu_path}: given twice"),
                             (["--fmu=test_mine.py"], "--fmu test_mine.py is not a usable FMU (BadZipFile")):
        run = pytester.runpytest_inprocess(*QUIET, *options)
        assert run.ret == pytest.ExitCode.USAGE_ERROR and message in run.stderr.str(), (options, run.stderr.str())
    for folder in ("a", "b"):  # the same file under one name in two folders (hard links: not resolved as one)
        (pytester.path / folder).mkdir()
        os.link(fmu_path, pytester.path / folder / fmu_path.name)
    run = pytester.runpytest_inprocess(*QUIET, "--fmu=a/DoublePendulum.fmu", "--fmu=b/DoublePendulum.fmu",
                                       "--collect-only", "-q")
    assert run.outlines[:2] == ["test_mine.py::test_one[a-DoublePendulum-fmi2-CS]",
                                "test_mine.py::test_one[b-DoublePendulum-fmi2-CS]"], run.outlines
    pytester.makepyfile(test_mine="import pytest\n\n@pytest.mark.fmu(interface='me')\ndef test_one(fmu):\n    pass\n")
    run = pytester.runpytest_inprocess(*QUIET, f"--fmu={fmu_path}")
    assert run.ret == pytest.ExitCode.USAGE_ERROR
    assert "@pytest.mark.fmu(interface='me', fmi_version=None): the interface is ME or CS" in run.stderr.str()


def test_the_interface_and_version_select_the_tests(pytester, fmu_path, fmu3_path):
    pytester.makepyfile(test_mine='''
import pytest

def test_any(fmu):
    assert fmu.interface in ("ME", "CS")

@pytest.mark.fmu(interface="ME")
def test_model_exchange(fmu, simulate):
    assert fmu.fmi_version == "3.0" and simulate(stop_time=0.5, outputs=["phi1"])["phi1"][-1] != 1.0
''')
    run = pytester.runpytest_inprocess(*QUIET, f"--fmu={fmu_path}", f"--fmu={fmu3_path}", "-v")
    run.assert_outcomes(passed=4, deselected=2)
    assert "test_model_exchange[DoublePendulum-fmi3-ME] PASSED" in run.stdout.str()
    run = pytester.runpytest_inprocess(*QUIET, f"--fmu={fmu_path}", f"--fmu={fmu3_path}", "--fmi-version=3",
                                       "--fmu-interface=CS", "-v")
    run.assert_outcomes(passed=1, deselected=5)
    assert "test_any[DoublePendulum-fmi3-CS] PASSED" in run.stdout.str()


CASES = '''
references = "references"

[defaults]
stop_time = 2.0
output_interval = 0.01
tolerance = { time = 0.005, rtol = 1e-4 }

[cases.small_swing]
start_values = { phi1_0 = 0.1, phi2_0 = 0.1 }
compare = ["phi1", "phi2"]
checks = ["energy_budget", "conserved"]

[cases.with_friction]
start_values = { phi1_0 = 1.5, air_drag = true }
compare = ["phi2"]
checks = ["energy_never_rises"]
'''


def test_cases_as_data_write_their_references_then_compare_with_them(pytester, fmu_path, fmu3_path, tmp_path):
    pytester.makefile(".toml", my_cases=CASES)
    pytester.makepyfile(test_other="def test_other():\n    pass\n")
    fmus = (f"--fmu={fmu_path}", f"--fmu={fmu3_path}", "--fmu-interface=CS")
    run = pytester.runpytest_inprocess(*QUIET, *fmus, "--collect-only", "-q")  # not named: not collected
    assert run.outlines[0] == "test_other.py::test_other" and "1 test collected" in run.stdout.str()
    run = pytester.runpytest_inprocess(*QUIET, *fmus, "--fmu-cases", "--collect-only", "-q")  # asked for: collected
    assert "my_cases.toml::small_swing[DoublePendulum-fmi3-CS]" in run.outlines
    assert "5/7 tests collected (2 deselected)" in run.stdout.str()  # the cases on Model Exchange: not asked for

    refs = tmp_path / "refs"  # the folder the user names
    run = pytester.runpytest_inprocess(*QUIET, "my_cases.toml", *fmus, f"--regen-references={refs}")
    run.assert_outcomes(passed=4)
    assert "--regen-references wrote 4 reference results in the fmi-ls-ref layout" in run.stdout.str()
    written = sorted(p.relative_to(refs).as_posix() for p in refs.rglob("*.csv"))
    layout = "extra/org.fmi-standard.fmi-ls-ref/DoublePendulum_out.csv"
    assert written == [f"{case}/DoublePendulum-{fmi}-CS/{layout}" for case in ("small_swing", "with_friction")
                       for fmi in ("fmi2", "fmi3")]
    assert sorted(p.name for p in pytester.path.iterdir()) == ["my_cases.toml", "test_other.py"]

    run = pytester.runpytest_inprocess(*QUIET, "my_cases.toml", *fmus, f"--fmu-references={refs}", "-v")
    run.assert_outcomes(passed=4)
    assert "my_cases.toml::small_swing[DoublePendulum-fmi3-CS] PASSED" in run.stdout.str()

    pytester.makefile(".toml", my_cases=CASES.replace("phi1_0 = 0.1,", "phi1_0 = 0.1005,"))  # the case changed
    run = pytester.runpytest_inprocess(*QUIET, "my_cases.toml", *fmus, f"--fmu-references={refs}")
    run.assert_outcomes(passed=2, failed=2)
    text = run.stdout.str()
    assert "FAILED my_cases.toml::small_swing[DoublePendulum-fmi2-CS]" in text
    assert re.search(r"phi1: left the tube first at t = 0.01 s \(\d+ of 199 points outside\); largest deviation "
                     r"0.000[45]\d* rad", text), text

    run = pytester.runpytest_inprocess(*QUIET, "my_cases.toml", *fmus)  # the file's references folder: empty
    run.assert_outcomes(failed=4)
    assert (f"{pytester.path / 'references' / 'small_swing' / 'DoublePendulum-fmi2-CS'} holds no reference result"
            in run.stdout.str() and "write it with pytest my_cases.toml --regen-references=" in run.stdout.str())

    pytester.makefile(".toml", bad_cases="[cases.x]\nstop = 1.0\ncompare = ['phi1']\n")
    run = pytester.runpytest_inprocess(*QUIET, "bad_cases.toml", *fmus)
    assert run.ret == pytest.ExitCode.INTERRUPTED  # a collection error
    assert "bad_cases.toml, case 'x': unknown key stop" in run.stdout.str()


def test_without_fmu_the_projects_fmu_is_used_and_a_csv_of_ones_own_is_a_reference(pytester, fmu_path):
    """Outside the project's folder the project's FMU is kept in pytest's cache folder: one there and newer than the
    sources is used as it is (an older one would be built anew there)."""
    import shutil
    import zipfile

    from double_pendulum.fmu.carries.reference_result import FOLDER

    kept = pytester.path / ".pytest_cache" / "d" / "double_pendulum_fmu" / "DoublePendulum.fmu"
    kept.parent.mkdir(parents=True)
    shutil.copyfile(fmu_path, kept)
    with zipfile.ZipFile(fmu_path) as archive:
        rows = archive.read(f"{FOLDER}/DoublePendulum_out.csv").decode().splitlines()
    pytester.path.joinpath("my_reference.csv").write_text("".join(",".join(row.split(",")[:2]) + "\n" for row in rows))
    pytester.makepyfile(test_mine='''
import pytest
from double_pendulum.testing import assert_matches_reference

@pytest.mark.fmu_reference("my_reference.csv")
def test_my_csv(fmu, simulate, reference):
    assert fmu.path.name == "DoublePendulum.fmu" and fmu.path.parent.name == "double_pendulum_fmu"
    assert reference.names == ("phi1",) and reference.unit("phi1") == "rad"
    assert_matches_reference(simulate.like(reference), reference, rtol=1e-9)
''')
    before = kept.stat().st_mtime_ns
    run = pytester.runpytest_inprocess(*QUIET[:-2], "-v")  # pytest's cache folder on
    assert "test_mine.py::test_my_csv[DoublePendulum-fmi2-CS] PASSED" in run.stdout.str(), run.stdout.str()
    assert kept.stat().st_mtime_ns == before
