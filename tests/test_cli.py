"""The command line: list, build, run a scenario through the FMU."""

from __future__ import annotations

import json

import pytest

from double_pendulum.cli import main
from double_pendulum.results_io import read_results_csv


def test_list_names_the_scenarios(capsys):
    assert main(["list"]) == 0
    assert "free_swing" in capsys.readouterr().out


def test_build_writes_the_fmu(tmp_path):
    target = tmp_path / "out" / "X.fmu"
    assert main(["build", "-o", str(target)]) == 0
    assert target.is_file()
    assert (target.parent / "Suspension.fmu").is_file()  # every FMU, next to DoublePendulum


def test_run_free_swing_writes_csv_plots_and_summary(fmu_path, tmp_path):
    assert main(["run", "free_swing", "--quick", "--fmu", str(fmu_path), "--out", str(tmp_path)]) == 0
    out = tmp_path / "free_swing"
    summary = json.loads((out / "summary.json").read_text())
    assert set(summary["runs"]) == {"regular", "chaotic"}
    assert summary["runs"]["regular"]["max_relative_energy_drift"] < 1e-8
    for name in ("angles", "traces", "energy", "phase_portraits"):
        assert (out / f"{name}.png").stat().st_size > 10_000
    chaotic = read_results_csv(out / "chaotic.csv")
    assert chaotic["time"][-1] == summary["stop_time_s"]
    assert chaotic["phi1"][0] == 2.0


def test_unknown_scenario_is_a_clear_error(capsys):
    try:
        main(["run", "nope"])
    except SystemExit as exc:
        assert "unknown scenario 'nope'" in str(exc)
    else:
        raise AssertionError("expected SystemExit")


def test_run_friction_budget_accounts_for_the_loss(fmu_path, tmp_path):
    assert main(["run", "friction_budget", "--quick", "--fmu", str(fmu_path), "--out", str(tmp_path)]) == 0
    summary = json.loads((tmp_path / "friction_budget" / "summary.json").read_text())
    shares = summary["share_of_loss_all_on"]
    assert sum(shares.values()) == pytest.approx(1.0, abs=1e-6)  # every joule accounted for
    assert all(v > 0 for v in shares.values())
    assert all(b < 0 for b in summary["decay_rate_b_per_s"].values())
    for name in ("energy_per_mechanism", "energy_budget_stacked"):
        assert (tmp_path / "friction_budget" / f"{name}.png").is_file()


def test_variables_prints_the_readme_table(capsys):
    from conftest import REPO

    assert main(["variables"]) == 0
    table = capsys.readouterr().out.strip()
    assert table in (REPO / "README.md").read_text()
