"""The README stays true: its test command is what CI runs, its variable table matches the FMU."""

from __future__ import annotations

import re

from conftest import REPO

from double_pendulum.component.variables import fmu_variables

README = (REPO / "README.md").read_text()


def _bash_blocks() -> list[str]:
    return re.findall(r"```bash\n(.*?)```", README, flags=re.S)


def test_readme_starts_with_the_two_commands_and_ci_runs_the_test_command():
    main_cmd, test_cmd = (block.strip() for block in _bash_blocks()[:2])
    assert "double-pendulum run all" in main_cmd
    assert "pytest" in test_cmd
    assert test_cmd in (REPO / ".ci" / "run").read_text()


def test_readme_variable_table_lists_every_variable_with_its_unit():
    for var in fmu_variables():
        row = next((line for line in README.splitlines() if line.startswith(f"| `{var.name}` |")), None)
        assert row is not None, f"{var.name} missing from the README table"
        cells = [c.strip() for c in row.strip("|").split("|")]
        assert cells[1] == var.causality and cells[2] == var.fmi_type
        assert cells[3] == (var.unit or "-")
