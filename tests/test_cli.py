"""The command line: list, build, run a scenario through the FMU."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
from conftest import BUILT_FMUS, folder_state, quick_run_leftovers, quick_scenario
from double_pendulum.scenarios import SCENARIOS

import double_pendulum
from double_pendulum.cli import main
from double_pendulum.cli.fmus import default_fmu_path, fmu_set, fmu_set_is_current
from double_pendulum.cli.run import run_scenario
from double_pendulum.runs.results_io import read_results_csv


def test_list_names_the_scenarios(capsys):
    assert main(["list"]) == 0
    assert "free_swing" in capsys.readouterr().out


def test_build_writes_the_fmu(built_by_the_command):
    """``double-pendulum build -o FOLDER/DoublePendulum.fmu`` into a folder not there before (the session's build,
    tests/conftest.py) exits 0, says what it writes, and writes every FMU there, each one it names."""
    folder, code, out = built_by_the_command
    assert code == 0, out
    target = folder / "DoublePendulum.fmu"
    assert target.is_file()
    assert (target.parent / "Suspension.fmu").is_file()  # every FMU, next to DoublePendulum
    assert (target.parent / "PendulumOnSuspension.ssp").is_file()  # and the coupled system
    assert (target.parent / "PendulumOnSuspension.fmu").is_file()
    named = [Path(line.removeprefix("built ")) for line in out.splitlines() if line.startswith("built ")]
    assert out.startswith(f"building the FMUs next to {target} (each carries its own CPython for Linux and "
                          "Windows) ...")
    assert [path.relative_to(folder).as_posix() for path in named] == list(BUILT_FMUS)
    assert all(path.is_file() for path in named)


def test_build_refuses_lean_with_linux_only_in_one_line(tmp_path, capsys):
    """A lean FMU carries no CPython at all: --lean with --linux-only (which CPython to carry) is one line, exit 2,
    nothing written."""
    assert main(["build", "--lean", "--linux-only", "-o", str(tmp_path / "out" / "DoublePendulum.fmu")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--lean and --linux-only exclude each other" in err
    assert not (tmp_path / "out").exists()


def test_run_free_swing_writes_csv_plots_and_summary(fmu_path, tmp_path):
    assert main(["run", "free_swing", "--quick", "--fmu", str(fmu_path), "--out", str(tmp_path)]) == 0
    out = tmp_path / "free_swing"
    summary = json.loads((out / "summary.json").read_text())
    assert set(summary["runs"]) == {"regular", "chaotic", "chaotic_nudged"}
    assert summary["runs"]["regular"]["max_relative_energy_drift"] < 1e-8
    for name in ("angles", "traces", "energy", "phase_portraits"):
        assert (out / f"{name}.png").stat().st_size > 10_000
    chaotic, nudged = (read_results_csv(out / f"{name}.csv") for name in ("chaotic", "chaotic_nudged"))
    assert chaotic["time"][-1] == summary["stop_time_s"]
    assert chaotic["phi1"][0] == 2.0 and nudged["phi1"][0] == 2.0 + summary["twin_starts"]["phi1_0_difference_rad"]
    assert (out / "twin_starts.gif").is_file() and summary["in_short"]
    assert (tmp_path / "index.html").is_file()  # the page of the run, beside the scenario's folder


def test_unknown_scenario_is_one_clear_line(capsys):
    assert main(["run", "nope"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "unknown scenario 'nope'" in err and "free_swing" in err


def test_run_friction_budget_accounts_for_the_loss(quick_results):
    out, summary = quick_scenario(quick_results, "friction_budget")
    shares = summary["share_of_loss_all_on"]
    assert sum(shares.values()) == pytest.approx(1.0, abs=1e-6)  # every joule accounted for
    assert all(v > 0 for v in shares.values())
    assert all(b < 0 for b in summary["decay_rate_b_per_s"].values())
    for name in ("energy_per_mechanism", "energy_budget_stacked"):
        assert (out / f"{name}.png").is_file()


def test_variables_prints_the_table_in_the_fmu_docs(capsys):
    from conftest import REPO

    assert main(["variables"]) == 0
    table = capsys.readouterr().out.strip()
    assert table in (REPO / "docs" / "fmu.md").read_text()


def test_version_and_plain_help(capsys):
    with pytest.raises(SystemExit) as exit_info:
        main(["--version"])
    assert exit_info.value.code == 0
    assert capsys.readouterr().out.strip() == f"double-pendulum {double_pendulum.__version__}"
    with pytest.raises(SystemExit):
        main(["run", "--help"])
    shown = capsys.readouterr().out
    assert "`" not in shown
    for name in SCENARIOS:  # every scenario listed with its one-line description
        assert any(line.split()[:1] == [name] and len(line.split()) > 3 for line in shown.splitlines()), name


def test_list_imports_no_scenario_and_no_numpy():
    """``list`` reads the descriptions from the sources: it stays fast (no NumPy, SciPy, Matplotlib)."""
    code = ("import sys; from double_pendulum.cli import main; main(['list']); "
            "heavy = [m for m in ('numpy', 'scipy', 'matplotlib', 'fmpy') if m in sys.modules]; "
            "assert not heavy, heavy")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert len(done.stdout.splitlines()) == len(SCENARIOS)


@pytest.mark.parametrize("kind", ["file", "proc", "readonly"])
def test_unusable_output_folder_is_one_clear_line(tmp_path, capsys, kind):
    if kind == "file":
        out = tmp_path / "a_file"
        out.write_text("x")
    elif kind == "proc":
        out = Path("/proc/x/y")
    else:
        if os.geteuid() == 0:
            pytest.skip("root can write to read-only folders")
        out = tmp_path / "ro"
        out.mkdir()
        out.chmod(0o500)
    assert main(["run", "free_swing", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "cannot write results to" in err and "Traceback" not in err
    assert "--out" in err  # how to write elsewhere
    if kind == "file":
        assert "it is a file, not a folder" in err and "File exists" not in err


def test_an_empty_output_name_is_refused_not_taken_for_the_current_folder(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(["run", "free_swing", "--out", ""]) == 2
    assert "--out needs a folder name" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []  # nothing written here


def test_an_unknown_option_shows_the_usage_of_its_command(capsys):
    with pytest.raises(SystemExit) as stop:
        main(["run", "free_swing", "--frobnicate"])
    assert stop.value.code == 2
    err = capsys.readouterr().err
    assert err.startswith("usage: double-pendulum run ") and "unrecognized arguments: --frobnicate" in err


def test_corrupt_fmu_is_one_clear_line(tmp_path, capsys):
    fmu = tmp_path / "broken.fmu"
    fmu.write_bytes(b"not a zip file")
    before = folder_state(tmp_path)
    assert main(["run", "free_swing", "--fmu", str(fmu), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"{fmu} is not a usable FMU" in err and "BadZipFile" in err
    assert folder_state(tmp_path) == before  # neither rebuilt nor any output folder made


class _Scenario:
    """A stand-in scenario module that writes one file, then fails or is interrupted if told to."""

    def __init__(self, file_name: str, error: BaseException | None = None) -> None:
        self.file_name, self.error = file_name, error

    def run(self, runner, out_dir, *, quick=False):
        (out_dir / self.file_name).write_text("data")
        (out_dir / "summary.json").write_text("{}")
        if self.error is not None:
            raise self.error
        return {}


def test_scenario_folder_is_replaced_only_when_the_run_finishes(tmp_path):
    run_scenario(_Scenario("first.csv"), "demo", None, tmp_path, quick=False)
    run_scenario(_Scenario("second.csv"), "demo", None, tmp_path, quick=True)
    assert sorted(p.name for p in (tmp_path / "demo").iterdir()) == ["second.csv", "summary.json"]  # no stale file
    assert json.loads((tmp_path / "demo" / "summary.json").read_text()) == {"quick": True}
    with pytest.raises(KeyboardInterrupt):
        run_scenario(_Scenario("third.csv", KeyboardInterrupt()), "demo", None, tmp_path, quick=False)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["demo"]  # nothing half-written left
    assert (tmp_path / "demo" / "second.csv").is_file()  # earlier results intact
    with pytest.raises(RuntimeError):
        run_scenario(_Scenario("fourth.csv", RuntimeError("boom")), "demo", None, tmp_path, quick=False)
    assert (tmp_path / "demo" / "second.csv").is_file()
    assert (tmp_path / "demo.failed" / "fourth.csv").is_file()  # what the failed run wrote is kept apart


def test_ctrl_c_exits_130_with_one_line(tmp_path, capsys, monkeypatch, fmu_path):
    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr("double_pendulum.cli.run.run_scenario", interrupted)
    assert main(["run", "free_swing", "--fmu", str(fmu_path), "--out", str(tmp_path)]) == 130
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "interrupted" in err


def _recorded_runs(monkeypatch) -> list[str]:
    """The scenarios ``run --jobs 1`` runs from now on, recorded instead of run (and no FMU opened)."""
    import contextlib

    runs: list[str] = []
    monkeypatch.setattr("double_pendulum.cli.run.load_fmu", lambda fmu, rebuild: contextlib.nullcontext())
    monkeypatch.setattr("double_pendulum.cli.run.run_scenario", lambda module, name, *args: runs.append(name))
    return runs


def test_several_scenarios_run_once_each_in_the_order_given_in_one_process(tmp_path, capsys, monkeypatch):
    runs = _recorded_runs(monkeypatch)
    assert main(["run", "free_swing", "cosimulation", "free_swing", "--jobs", "1", "--out", str(tmp_path)]) == 0
    assert runs == ["free_swing", "cosimulation"]  # duplicates dropped; libcosim and the container run after fmpy
    out = capsys.readouterr().out
    assert "[1/2] free_swing:" in out and "[2/2] cosimulation:" in out and "2 of 2 scenarios wrote" in out


def test_a_child_numbers_its_scenarios_as_its_parent_says_and_leaves_the_sum_to_it(tmp_path, capsys, monkeypatch):
    runs = _recorded_runs(monkeypatch)
    command = ["run", "cosimulation", "chaos", "--jobs", "1", "--out", str(tmp_path)]
    assert main([*command, "--index", "1/11,10/11"]) == 0
    assert runs == ["cosimulation", "chaos"]
    out = capsys.readouterr().out
    assert "[1/11] cosimulation:" in out and "[10/11] chaos:" in out and "scenarios wrote" not in out
    assert main([*command, "--index", "1/11"]) == 2
    assert "--index needs one k/N per scenario (2)" in capsys.readouterr().err


@pytest.mark.parametrize(("names", "message"), [
    (["all", "free_swing"], "'all' runs every scenario: give it alone"),
    (["free_swing", "all"], "'all' runs every scenario: give it alone"),
    (["free_swing", "nope"], "unknown scenario 'nope'"),
])  # fmt: skip
def test_bad_scenario_lists_are_one_clear_line(tmp_path, capsys, names, message):
    assert main(["run", *names, "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and message in err
    assert list(tmp_path.iterdir()) == []  # nothing ran


def test_a_finished_run_leaves_nothing_in_the_temporary_folder(quick_results):
    # every scenario ran (in child processes, their sweeps on workers); the FMUs they extracted are gone
    assert quick_run_leftovers(quick_results) == []


@pytest.mark.parametrize("command", ["variables", "list"])
def test_a_reader_that_stops_early_gets_no_traceback(command):
    process = subprocess.Popen([sys.executable, "-m", "double_pendulum.cli", command], stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE)  # fmt: skip
    process.stdout.close()  # as `| head -1` does, before the command has written its lines
    stderr = process.stderr.read().decode()
    assert process.wait(timeout=60) == 141, stderr  # 128 + SIGPIPE, as a shell tool ended by the pipe
    assert stderr == ""


def test_run_from_another_folder_keeps_every_fmu_in_the_out_folder(tmp_path, monkeypatch, capsys):
    elsewhere, out = tmp_path / "elsewhere", tmp_path / "results"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)
    assert main(["run", "free_swing", "--quick", "--out", str(out)]) == 0
    assert list(elsewhere.iterdir()) == []  # no build/ where the command was given
    fmu = out / "fmu" / "DoublePendulum.fmu"
    assert default_fmu_path(out) == fmu
    names = sorted(str(path.relative_to(fmu.parent)) for path in fmu_set(fmu))
    assert names == ["DoublePendulum.fmu", "PendulumOnSuspension.fmu", "PendulumOnSuspension.ssp", "Suspension.fmu",
                     "fmi3/DoublePendulum.fmu"]  # fmt: skip
    assert all(path.is_file() for path in fmu_set(fmu)) and fmu_set_is_current(fmu)
    newer = tmp_path / "DoublePendulumFmi3.py"  # an FMI 3 adapter source changed since: the set is stale
    newer.write_text("")
    os.utime(newer, (fmu.stat().st_mtime + 60,) * 2)
    monkeypatch.setattr("double_pendulum.fmu.build.fmi3.adapter_sources", lambda: [newer])
    assert not fmu_set_is_current(fmu)
    monkeypatch.undo()
    (out / "fmu" / "PendulumOnSuspension.ssp").unlink()  # one missing: the next run builds the set again
    assert not fmu_set_is_current(fmu)


def test_in_the_project_folder_the_fmus_stay_in_build(tmp_path, monkeypatch):
    (tmp_path / "pyproject.toml").write_text('[project]\nname = "double-pendulum-fmu"\n')
    monkeypatch.chdir(tmp_path)
    assert default_fmu_path(Path("results")) == Path("build") / "DoublePendulum.fmu"


def test_fmus_that_cannot_be_built_name_the_option_to_build_them_elsewhere(tmp_path, capsys):
    blocker = tmp_path / "a_file"
    blocker.write_text("x")  # a file where the build folder should be
    assert main(["run", "free_swing", "--build-dir", str(blocker), "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"cannot build the FMUs in {blocker}" in err and "--build-dir DIR" in err
    assert blocker.read_text() == "x"
