"""A user's FMU is only read (issue 52): ``run``, ``simulate``, ``app`` and the examples run an FMU given by ``--fmu``
as it is, never build over it or beside it, and refuse a missing or foreign one in one line naming it, leaving the
file system as it was (every entry of the user's folder, its size and its mtime, before and after); the project's
FMUs are built in the build folder, ``--build-dir``."""

from __future__ import annotations

import importlib.util
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from conftest import BUILT_FMUS, REPO, folder_state, users_folder
from fmpy import read_model_description

from double_pendulum.cli import main
from double_pendulum.fmu.running.choice import FmuPathError, read_pendulum_fmu


def _one_error_line(capsys) -> str:
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    return err


@pytest.fixture
def home(tmp_path: Path, built_fmus: list[Path], monkeypatch) -> Path:
    """A user's folder (:func:`conftest.users_folder`), the current folder of the test."""
    folder = users_folder(tmp_path / "home", built_fmus)
    monkeypatch.chdir(folder)
    return folder


def test_a_given_fmu_older_than_the_sources_runs_as_it_is_and_nothing_beside_it_changes(home, tmp_path, capsys):
    """``run`` through the user's old FMU, with cosimulation, which needs a Suspension FMU the user did not give (the
    old one beside it is not current): it builds one in the run's temporary folder, not beside the user's."""
    before = folder_state(home)
    out = tmp_path / "out"
    argv = ["run", "free_swing", "cosimulation", "--quick", "--jobs", "1", "--fmu", "models/Other.fmu", "--out",
            str(out)]
    assert main(argv) == 0
    printed = capsys.readouterr().out
    assert "building" not in printed and "2 of 2 scenarios wrote" in printed
    assert folder_state(home) == before
    assert (out / "free_swing" / "summary.json").is_file() and (out / "cosimulation" / "summary.json").is_file()


def test_simulate_runs_a_given_fmu_as_it_is_in_its_own_fmi_version(home, tmp_path, capsys):
    before = folder_state(home)
    for fmu, version, extra in (("models/Other.fmu", "2.0", []), ("models/Other3.fmu", "3.0", ["--me"])):
        out = tmp_path / f"out{version}"
        argv = ["simulate", "--fmu", fmu, *extra, "--stop", "0.2", "--no-animation", "--out", str(out)]
        assert main(argv) == 0
        assert "building" not in capsys.readouterr().out
        summary = (out / "summary.json").read_text()
        assert f'"fmi_version": "{version}"' in summary
    assert folder_state(home) == before


@pytest.mark.parametrize("command", [["run", "free_swing"], ["simulate"]])
@pytest.mark.parametrize("given", ["models/nonexistent.fmu", "models/nowhere/DoublePendulum.fmu", "models"])
def test_a_missing_fmu_is_one_line_naming_it_and_changes_nothing(home, capsys, command, given):
    """Run in the user's folder with the default ``--out``: not even the output folder is made."""
    before = folder_state(home)
    assert main([*command, "--fmu", given]) == 2
    err = _one_error_line(capsys)
    assert f"--fmu {given}" in err and ("no such file" in err or "a folder, not an FMU file" in err)
    assert "--build-dir DIR" in err  # where the project's FMUs can be built instead
    assert folder_state(home) == before


@pytest.mark.parametrize("command", [["run", "free_swing"], ["simulate"]])
def test_an_fmu_that_is_not_the_pendulum_s_is_one_line_naming_it_and_changes_nothing(home, capsys, command):
    before = folder_state(home)
    assert main([*command, "--fmu", "models/Container.fmu"]) == 2
    err = _one_error_line(capsys)
    assert "models/Container.fmu is not an FMU of the double pendulum" in err and "'PendulumOnSuspension'" in err
    assert folder_state(home) == before


@pytest.mark.parametrize(("argv", "words"), [
    (["run", "free_swing", "--rebuild"], "--rebuild and --fmu exclude each other"),
    (["simulate", "--rebuild"], "--rebuild and --fmu exclude each other"),
    (["run", "free_swing", "--build-dir", "models"], "--fmu and --build-dir exclude each other"),
    (["simulate", "--build-dir", "build"], "--fmu and --build-dir exclude each other"),
    (["simulate", "--fmi", "3"], "--fmi 3 does not match models/Other.fmu: it is an FMI 2.0 FMU"),
    (["simulate", "--me"], "--me needs an FMU with Model Exchange: models/Other.fmu (FMI 2.0) is co-simulation only"),
])  # fmt: skip
def test_what_would_build_over_a_given_fmu_or_contradict_it_is_one_line(home, capsys, argv, words):
    before = folder_state(home)
    assert main([*argv, "--fmu", "models/Other.fmu"]) == 2
    assert words in _one_error_line(capsys)
    assert folder_state(home) == before


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


def test_the_build_folder_is_where_the_project_s_fmus_are_built_and_kept(tmp_path, capsys, monkeypatch):
    """``--build-dir DIR`` builds every FMU in DIR when they are missing, and a later command keeps them there
    (``--fmi 3`` takes DIR/fmi3/); nothing goes to the current folder or beside the output."""
    elsewhere, build = tmp_path / "elsewhere", tmp_path / "fmus"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)
    assert main(["simulate", "--build-dir", str(build), "--stop", "0.2", "--no-animation",
                 "--out", str(tmp_path / "a")]) == 0
    assert f"building the FMUs in {build} (missing or older than the sources) ..." in capsys.readouterr().out
    assert sorted(p.relative_to(build).as_posix() for p in build.rglob("*") if p.is_file()) == sorted(BUILT_FMUS)
    kept = folder_state(build)
    assert main(["simulate", "--build-dir", str(build), "--fmi", "3", "--me", "--stop", "0.2", "--no-animation",
                 "--out", str(tmp_path / "b")]) == 0
    printed = capsys.readouterr().out
    assert "building" not in printed and f"through {build / 'fmi3' / 'DoublePendulum.fmu'}" in printed
    assert folder_state(build) == kept
    assert list(elsewhere.iterdir()) == [] and not (tmp_path / "a" / "fmu").exists()


def test_rebuild_rebuilds_in_the_build_folder(tmp_path, built_fmus, capsys, monkeypatch):
    """``--build-dir DIR --rebuild``, the FMUs there and current: they are built again, there (the build recorded
    and done by copying the session's FMUs, which a real build would write)."""
    build = tmp_path / "fmus"
    for name, path in zip(BUILT_FMUS, built_fmus):
        (build / name).parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(path, build / name)
    built: list[Path] = []

    def build_all(dest: Path) -> list[Path]:
        built.append(Path(dest))
        for name, path in zip(BUILT_FMUS, built_fmus):
            shutil.copyfile(path, Path(dest).parent / name)
        return []

    monkeypatch.setattr("double_pendulum.cli.fmus.build_all", build_all)
    argv = ["simulate", "--build-dir", str(build), "--stop", "0.2", "--no-animation", "--out", str(tmp_path / "out")]
    assert main(argv) == 0
    assert built == []  # current: kept
    assert main([*argv, "--rebuild"]) == 0
    assert built == [build / "DoublePendulum.fmu"]
    assert f"building the FMUs in {build} (--rebuild) ..." in capsys.readouterr().out


needs_dash = pytest.mark.skipif(importlib.util.find_spec("dash") is None,
                                reason="Dash is not installed (pip install -e \".[app]\")")


@needs_dash
@pytest.mark.parametrize(("argv", "words"), [
    (["--fmu", "models/nonexistent.fmu"], "--fmu models/nonexistent.fmu: no such file"),
    (["--fmu", "models/Container.fmu"], "models/Container.fmu is not an FMU of the double pendulum"),
    (["--fmu", "models/Other.fmu", "--build-dir", "models"], "--fmu and --build-dir exclude each other"),
])  # fmt: skip
def test_the_app_refuses_a_missing_or_foreign_fmu_in_one_line_and_changes_nothing(home, capsys, argv, words):
    before = folder_state(home)
    assert main(["app", *argv]) == 2
    err = _one_error_line(capsys)
    assert err.startswith("double-pendulum app: ") and words in err
    assert folder_state(home) == before


def test_an_example_refuses_a_missing_fmu_in_one_line_and_changes_nothing(home):
    before = folder_state(home)
    env = {**os.environ, "MPLBACKEND": "Agg", "DOUBLE_PENDULUM_PROGRESS": "off"}
    done = subprocess.run([sys.executable, str(REPO / "examples" / "drive_inputs.py"), "--fmu",
                           "models/nonexistent.fmu", "--out", "driven.png"], cwd=home, env=env, capture_output=True,
                          text=True)  # fmt: skip
    assert done.returncode == 2 and done.stdout == ""
    assert done.stderr == "drive_inputs.py: error: --fmu models/nonexistent.fmu: no such file\n"
    assert folder_state(home) == before
