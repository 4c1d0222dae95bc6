"""``run all`` in child processes: order, relayed lines, failures, Ctrl-C."""

from __future__ import annotations

import sys

import pytest
from double_pendulum.scenarios import EXPECTED_CPU_S, SCENARIOS

from double_pendulum import scenario_pool
from double_pendulum.analysis.progress import ENV
from double_pendulum.cli import main


def test_every_scenario_has_an_expected_cost_and_the_longest_start_first():
    assert set(EXPECTED_CPU_S) == set(SCENARIOS)
    order = scenario_pool.longest_first(SCENARIOS)
    costs = [EXPECTED_CPU_S[name] for name in order]
    assert costs == sorted(costs, reverse=True)
    assert sorted(order) == sorted(SCENARIOS)


def test_child_lines_are_marked_with_their_scenario():
    assert scenario_pool.marked("chaos", "  - flip map: 24 x 24 releases\n") == "  chaos: - flip map: 24 x 24 releases"
    assert scenario_pool.marked("chaos", "sweep (5 runs): 5/5 done") == "  chaos: sweep (5 runs): 5/5 done"
    # the child's own header and result lines already name it
    assert scenario_pool.marked("chaos", "[10/11] chaos: sensitivity ...\n") == "[10/11] chaos: sensitivity ..."
    assert scenario_pool.marked("chaos", "chaos: wrote results/chaos in 1 s") == "chaos: wrote results/chaos in 1 s"


@pytest.mark.parametrize(("parent", "child"), [("", "lines"), ("bar", "lines"), ("off", "off")])
def test_children_count_progress_in_plain_lines_unless_it_is_off(monkeypatch, parent, child):
    monkeypatch.setenv(ENV, parent)
    assert scenario_pool.child_environment()[ENV] == child


def _fake_children(monkeypatch, scripts: dict[str, str]) -> None:
    """Children that run a small Python script per scenario name instead of the scenario."""
    monkeypatch.setattr(scenario_pool, "child_command",
                        lambda name, *args: [sys.executable, "-c", scripts[name]])  # fmt: skip


def test_failed_children_are_named_and_the_others_finish(monkeypatch, tmp_path, capsys):
    _fake_children(monkeypatch, {
        "a": "print('working'); import sys; sys.exit(3)",
        "b": "import sys; print('b: FAILED: bad input', file=sys.stderr); sys.exit(1)",
        "c": "print('c: wrote it')",
    })  # fmt: skip
    failed = scenario_pool.run_in_children(["a", "b", "c"], tmp_path, tmp_path / "x.fmu", quick=True,
                                           thorough=False, jobs=2)  # fmt: skip
    assert failed == ["a", "b"]
    out, err = capsys.readouterr()
    assert "  a: working" in out and "c: wrote it" in out
    assert "a: FAILED: its process ended with code 3" in err
    assert "b: FAILED: bad input" in err and "b: FAILED: its process" not in err  # the child said why


def test_ctrl_c_stops_every_child(monkeypatch, tmp_path):
    _fake_children(monkeypatch, {"a": "import time; time.sleep(60)", "b": "import time; time.sleep(60)"})
    started = []
    real_start = scenario_pool.start_child

    def start(*args):
        started.append(real_start(*args))
        return started[-1]

    def interrupt(seconds):
        raise KeyboardInterrupt

    monkeypatch.setattr(scenario_pool, "start_child", start)
    monkeypatch.setattr(scenario_pool, "_pause", interrupt)
    monkeypatch.setattr(scenario_pool, "STOP_GRACE_S", 0.2)
    with pytest.raises(KeyboardInterrupt):
        scenario_pool.run_in_children(["a", "b"], tmp_path, tmp_path / "x.fmu", quick=True, thorough=False, jobs=2)
    assert len(started) == 2
    assert all(child.process.poll() is not None for child in started)  # none left running


def test_run_all_in_children_writes_every_folder(tmp_path, capsys, fmu_path, monkeypatch):
    monkeypatch.setattr("double_pendulum.cli._check_scenario", lambda name: ("energy_decay", "free_swing"))
    assert main(["run", "all", "--quick", "--jobs", "2", "--fmu", str(fmu_path), "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert sorted(p.name for p in tmp_path.iterdir()) == ["energy_decay", "free_swing"]
    assert "2 at a time in their own processes" in out
    assert "[1/2] energy_decay:" in out and "[2/2] free_swing:" in out
    assert "2 of 2 scenarios wrote" in out


def test_jobs_below_one_is_refused_in_one_line(tmp_path, capsys):
    assert main(["run", "all", "--jobs", "0", "--out", str(tmp_path)]) == 2
    assert capsys.readouterr().err.strip() == "double-pendulum: error: --jobs must be at least 1, got 0"
