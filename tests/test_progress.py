"""Progress display: plain lines when stderr is not a terminal, the --thorough option of the CLI."""

from __future__ import annotations

import types

import pytest

from double_pendulum import cli
from double_pendulum.cli.run import accepts_thorough
from double_pendulum.runs import progress


def test_plain_lines_every_tenth_of_a_long_loop(capsys, monkeypatch):
    monkeypatch.setattr(progress, "QUIET_SECONDS", 0.0)
    monkeypatch.delenv(progress.ENV, raising=False)
    with progress.progress_bar(50, "demo", unit="case") as bar:  # stderr is captured: not a terminal
        for _ in range(50):
            bar.update(1)
    lines = capsys.readouterr().err.splitlines()
    assert len(lines) == 10  # 10 %, ..., 90 %, then the closing line
    assert lines[0].startswith("demo: 5/50 (10 %)") and "left" in lines[0] and "case/s" in lines[0]
    assert lines[-1].startswith("demo: 50/50 done in")


def test_short_loops_stay_silent_and_off_means_off(capsys, monkeypatch):
    monkeypatch.delenv(progress.ENV, raising=False)
    assert list(progress.track(range(3), "short")) == [0, 1, 2]
    assert capsys.readouterr().err == ""
    monkeypatch.setenv(progress.ENV, "off")
    monkeypatch.setattr(progress, "QUIET_SECONDS", 0.0)
    assert list(progress.track(range(3), "off")) == [0, 1, 2]
    assert capsys.readouterr().err == ""


def test_step_says_what_the_scenario_does(capsys):
    progress.step("fitting c")
    assert capsys.readouterr().out == "  - fitting c\n"


def test_thorough_goes_only_to_scenarios_that_take_it_and_excludes_quick(capsys):
    def with_option(runner, out, *, quick=False, thorough=False):
        return None

    def without(runner, out, *, quick=False):
        return None

    assert accepts_thorough(types.SimpleNamespace(run=with_option))
    assert not accepts_thorough(types.SimpleNamespace(run=without))
    assert cli.main(["run", "free_swing", "--quick", "--thorough"]) == 2
    assert "exclude each other" in capsys.readouterr().err


@pytest.mark.parametrize("name", ["chaos", "work_precision"])
def test_the_heavy_scenarios_have_a_thorough_setting(name):
    import importlib

    assert accepts_thorough(importlib.import_module(f"double_pendulum.scenarios.{name}"))


def test_a_loop_cut_short_by_ctrl_c_says_interrupted_not_done(capsys, monkeypatch):
    monkeypatch.setattr(progress, "QUIET_SECONDS", 0.0)
    monkeypatch.delenv(progress.ENV, raising=False)
    with pytest.raises(KeyboardInterrupt), progress.progress_bar(56, "11 scenarios", unit="CPU s") as bar:
        bar.update(40)
        raise KeyboardInterrupt
    last = capsys.readouterr().err.splitlines()[-1]
    assert last.startswith("11 scenarios: interrupted at 40/56 after") and "done" not in last


def test_a_bar_cut_short_says_so_in_its_description(monkeypatch):
    monkeypatch.setenv(progress.ENV, "bar")
    with pytest.raises(KeyboardInterrupt), progress.progress_bar(56, "run", unit="CPU s") as bar:
        bar.update(40)
        raise KeyboardInterrupt
    assert bar.desc == "run: interrupted at 40/56"
    with progress.progress_bar(3, "fine") as ok:
        ok.update(3)
    assert ok.desc == "fine" and ok.n == 3
