"""The examples a user copies run as the README shows them, in a quick form: each writes its figure and says what
it found. They run as scripts, in processes of their own (the sweep's workers import the script again)."""

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
    readme = (REPO / "README.md").read_text()
    for script in sorted(EXAMPLES.glob("*.py")):
        assert f"](examples/{script.name})" in readme, f"README does not link examples/{script.name}"
        assert 'if __name__ == "__main__":' in script.read_text(), script.name


def test_the_flip_time_sweep_runs_on_worker_processes(fmu_path, tmp_path):
    out = _run("flip_time_sweep.py", "--grid", "3", "--stop", "1.5", "--workers", "2", "--fmu", str(fmu_path),
               "--out", "flips.png", cwd=tmp_path)
    assert "of 9 starts flip the lower rod within 1.5 s; wrote flips.png" in out
    assert (tmp_path / "flips.png").stat().st_size > 10_000


def test_the_driven_pendulum_takes_energy_from_the_motor_at_resonance(built_fmus, tmp_path):
    """Through a user's FMU dated 2020 (older than the sources), which the example reads and never builds over."""
    home = users_folder(tmp_path / "home", built_fmus)
    before = folder_state(home)
    out = _run("drive_inputs.py", "--stop", "4", "--fmu", str(home / "models" / "Other.fmu"), "--out", "driven.png",
               cwd=tmp_path)
    assert folder_state(home) == before
    lines = {line.split(":")[0]: line for line in out.splitlines()}
    fed = {name: float(line.split("work fed in ")[1].split()[0]) for name, line in lines.items() if "work" in line}
    at, off = fed["torque at 4.81 rad/s"], fed["torque at 2.89 rad/s"]
    assert at > 10 * abs(off)  # in resonance the motor does the work
    assert (tmp_path / "driven.png").stat().st_size > 10_000
