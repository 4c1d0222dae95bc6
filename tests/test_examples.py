"""The examples a user copies run as the README shows them, in a quick form: each writes its figure into a folder of
its own and says what it found, and writes nothing else in the folder it runs in. They run as scripts, in processes of
their own (the sweep's workers import the script again)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

from conftest import REPO, folder_state, users_folder

EXAMPLES = REPO / "examples"


def _run(script: str, *args: str, cwd: Path) -> str:
    env = {**os.environ, "MPLBACKEND": "Agg", "DOUBLE_PENDULUM_PROGRESS": "off"}
    done = subprocess.run([sys.executable, str(EXAMPLES / script), *args], cwd=cwd, env=env, capture_output=True,
                          text=True)
    assert done.returncode == 0, done.stderr
    return done.stdout


def test_every_example_is_linked_from_the_readme_and_guards_its_top_level():
    """A script guards its top level (the sweep's workers import it again); a test file (test_*.py) is pytest's."""
    readme = (REPO / "README.md").read_text()
    for script in sorted(EXAMPLES.glob("*.py")):
        assert f"](examples/{script.name})" in readme, f"README does not link examples/{script.name}"
        if not script.name.startswith("test_"):
            assert 'if __name__ == "__main__":' in script.read_text(), script.name


def _users_cwd(folder: Path) -> Path:
    """A folder a user runs the example in, holding a file of theirs."""
    folder.mkdir()
    (folder / "notes.txt").write_text("the user's own file\n")
    return folder


def test_the_flip_time_sweep_runs_on_worker_processes(fmu_path, tmp_path):
    """With no --out, the figure goes into examples_output/ under the current folder, and nothing else is written."""
    cwd = _users_cwd(tmp_path / "work")
    before = folder_state(cwd)
    out = _run("flip_time_sweep.py", "--grid", "3", "--stop", "1.5", "--workers", "2", "--fmu", str(fmu_path),
               cwd=cwd)
    assert "of 9 starts flip the lower rod within 1.5 s; wrote examples_output/flip_times.png" in out
    after = folder_state(cwd)
    assert sorted(set(after) - set(before)) == ["examples_output", "examples_output/flip_times.png"]
    assert {name: after[name] for name in before if name != "."} == {n: v for n, v in before.items() if n != "."}
    assert (cwd / "examples_output" / "flip_times.png").stat().st_size > 10_000


def test_the_driven_pendulum_takes_energy_from_the_motor_at_resonance(built_fmus, tmp_path):
    """Through a user's FMU dated 2020 (older than the sources), which the example reads and never builds over."""
    home = users_folder(tmp_path / "home", built_fmus)
    cwd = _users_cwd(tmp_path / "work")
    before, before_cwd = folder_state(home), folder_state(cwd)
    out = _run("drive_inputs.py", "--stop", "4", "--fmu", str(home / "models" / "Other.fmu"), "--out", "figures/driven",
               cwd=cwd)
    assert folder_state(home) == before
    after_cwd = folder_state(cwd)  # only the folder asked for is new; the user's file is untouched
    assert sorted(set(after_cwd) - set(before_cwd)) == ["figures", "figures/driven", "figures/driven/drive_inputs.png"]
    assert after_cwd["notes.txt"] == before_cwd["notes.txt"]
    lines = {line.split(":")[0]: line for line in out.splitlines()}
    fed = {name: float(line.split("work fed in ")[1].split()[0]) for name, line in lines.items() if "work" in line}
    at, off = fed["torque at 4.81 rad/s"], fed["torque at 2.89 rad/s"]
    assert at > 10 * abs(off)  # in resonance the motor does the work
    assert "wrote figures/driven/drive_inputs.png" in out
    assert (cwd / "figures" / "driven" / "drive_inputs.png").stat().st_size > 10_000


def _pytest(*args: str, cwd: Path) -> str:
    """pytest run as a user runs it, in a process of its own: the project's addopts (xdist's workers) left out."""
    done = subprocess.run([sys.executable, "-m", "pytest", "-o", "addopts=", "-p", "no:dash", "-p", "no:cacheprovider",
                           *args], cwd=cwd, env={**os.environ, "MPLBACKEND": "Agg"}, capture_output=True, text=True)
    assert done.returncode == 0, done.stdout + done.stderr
    return done.stdout


def test_the_pytest_example_and_its_cases_pass_on_an_fmu_of_ones_own(built_fmus, tmp_path):
    """examples/test_my_pendulum.py and examples/cases.toml through the plugin, on a user's FMU dated 2020 (read, never
    built over); the cases' references written into the folder named (tests/test_testing_plugin.py compares with
    such), nothing else written."""
    home = users_folder(tmp_path / "home", built_fmus)
    cwd = _users_cwd(tmp_path / "work")
    before, before_cwd = folder_state(home), folder_state(cwd)
    fmu = f"--fmu={home / 'models' / 'Other.fmu'}"
    out = _pytest(str(EXAMPLES / "test_my_pendulum.py"), str(EXAMPLES / "cases.toml"), fmu, "--regen-references=refs",
                  "-v", cwd=cwd)
    for test in ("test_the_fmu_reproduces_the_reference_it_carries[Other-fmi2-CS]",
                 "test_my_pendulum_loses_energy_only_to_friction[Other-fmi2-CS]",
                 "test_my_pendulum_swings_at_its_normal_modes[Other-fmi2-CS-slow]",
                 "test_my_pendulum_swings_at_its_normal_modes[Other-fmi2-CS-fast]"):
        assert f"test_my_pendulum.py::{test} PASSED" in out, out
    assert "--regen-references wrote 2 reference results in the fmi-ls-ref layout into refs" in out
    assert "cases.toml::small_swing[Other-fmi2-CS] PASSED" in out and "6 passed" in out, out
    assert folder_state(home) == before
    after_cwd = folder_state(cwd)
    assert sorted(set(after_cwd) - set(before_cwd)) == sorted(
        ["refs", *(f"refs/{case}{tail}" for case in ("small_swing", "longer_rod_with_friction") for tail in (
            "", "/Other-fmi2-CS", "/Other-fmi2-CS/extra", "/Other-fmi2-CS/extra/org.fmi-standard.fmi-ls-ref",
            "/Other-fmi2-CS/extra/org.fmi-standard.fmi-ls-ref/fmi-ls-manifest.xml",
            "/Other-fmi2-CS/extra/org.fmi-standard.fmi-ls-ref/DoublePendulum_out.csv"))])
