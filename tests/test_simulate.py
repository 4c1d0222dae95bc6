"""``double-pendulum simulate``: a case of one's own through the FMU, fmpy's numbers bit for bit, ``--set`` checked
against the modelDescription, misuse answered in one line, nothing lost or left behind."""

from __future__ import annotations

import json
import tempfile
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu

from double_pendulum import case as case_module
from double_pendulum.case import FILES, START_STATE, start_state, start_state_words
from double_pendulum.cli import main
from double_pendulum.fmu.running.runner import FmuRunner
from double_pendulum.fmu.running.start_values import StartValueError, closest_name, parse_start_values
from double_pendulum.model.outputs import OUTPUT_NAMES
from double_pendulum.model.parameters import InitialState
from double_pendulum.runs.results_io import read_results_csv


def _columns(result: np.ndarray) -> dict[str, np.ndarray]:
    return {name: np.asarray(result[name]) for name in result.dtype.names}


def _one_error_line(capsys) -> str:
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    return err


def test_a_case_writes_csv_figure_animation_and_summary_with_fmpy_s_numbers(fmu_path, tmp_path, capsys,
                                                                             monkeypatch):
    titles = []
    plot_case = case_module.plot_case
    monkeypatch.setattr(case_module, "plot_case", lambda *a, title: titles.append(title) or plot_case(*a, title=title))
    out = tmp_path / "case"
    argv = ["simulate", "--set", "phi1_0=2", "--set", "air_drag=true", "--stop", "3", "--step", "0.02",
            "--fmu", str(fmu_path), "--out", str(out)]
    assert main(argv) == 0
    assert sorted(p.name for p in out.iterdir()) == sorted(FILES)  # nothing else, no staging folder left
    line = capsys.readouterr().out.splitlines()[-1]
    assert line.startswith("wrote simulation.csv, simulation.png, simulation.gif, summary.json")
    summary = json.loads((out / "summary.json").read_text())
    assert summary["start_values"] == {"phi1_0": 2.0, "air_drag": True} and summary["status"] == "finished"
    # the start state it used, all four, the ones not set at the model's defaults: in the line, summary and title
    defaults = InitialState()
    state = ("phi1_0 = 2 rad (set), phi2_0 = 1 rad (default), omega1_0 = 0 rad/s (default), "
             "omega2_0 = 0 rad/s (default)")
    assert (defaults.phi2_0, defaults.omega1_0, defaults.omega2_0) == (1.0, 0.0, 0.0)
    assert line.endswith(f"; start state: {state}")
    assert summary["start_state"] == {
        "phi1_0": {"value": 2.0, "unit": "rad", "source": "set"},
        "phi2_0": {"value": defaults.phi2_0, "unit": "rad", "source": "default"},
        "omega1_0": {"value": defaults.omega1_0, "unit": "rad/s", "source": "default"},
        "omega2_0": {"value": defaults.omega2_0, "unit": "rad/s", "source": "default"}}
    assert len(titles) == 1 and f"start state: {state}" in titles[0].splitlines()
    written = read_results_csv(out / "simulation.csv")
    with open(out / "simulation.csv") as fh:
        assert '"time [s]","phi1 [rad]"' in fh.readline()  # units in the column names
    plain = simulate_fmu(str(fmu_path), start_values={"phi1_0": 2.0, "air_drag": True}, stop_time=3.0,
                         output_interval=0.02, output=list(OUTPUT_NAMES))  # the summary's fmpy call
    assert written.dtype.names == plain.dtype.names
    for name, column in _columns(plain).items():
        assert np.array_equal(written[name], column), name  # bit for bit
    assert summary["E_total_start_J"] > summary["E_total_end_J"]  # air drag takes energy
    assert summary["fmpy_call"].startswith("fmpy.simulate_fmu(") and "'air_drag': True" in summary["fmpy_call"]
    assert f"output={list(OUTPUT_NAMES)!r})" in summary["fmpy_call"]  # fmpy records only the outputs by default


def test_model_exchange_through_the_fmi3_fmu_gives_fmpy_s_numbers(fmu3_path, tmp_path):
    out = tmp_path / "me"
    assert main(["simulate", "--fmi", "3", "--me", "--set", "phi2_0=0.5", "--stop", "1", "--fmu", str(fmu3_path),
                 "--out", str(out), "--no-animation"]) == 0
    assert not (out / "simulation.gif").exists()
    fmu3 = fmu3_path
    plain = simulate_fmu(str(fmu3), fmi_type="ModelExchange", start_values={"phi2_0": 0.5}, stop_time=1.0,
                         output_interval=0.01)
    written = read_results_csv(out / "simulation.csv")
    for name, column in _columns(plain).items():
        assert np.array_equal(written[name], column), name
    summary = json.loads((out / "summary.json").read_text())
    assert summary["fmi_version"] == "3.0" and summary["fmi_type"] == "ModelExchange"
    assert summary["relative_tolerance"] == float(read_model_description(str(fmu3)).defaultExperiment.tolerance)


@pytest.mark.parametrize("setting, words", [
    ("phi1_O=2", "no parameter phi1_O; the closest parameter is phi1_0"),
    ("airdrag=true", "the closest parameter is air_drag"),
    ("air_drag=maybe", "air_drag is a switch: true or false"),
    ("m1=heavy", "m1 is a real number [kg]"),
    ("m1=nan", "m1 must be a finite number [kg]"),
    ("pivot_x=0.1", "pivot_x is an input"),
    ("x2=0.1", "x2 is a local variable"),
    ("phi1=0.1", "phi1 is an output variable"),
    ("phi1_0", "write NAME=VALUE"),
])
def test_a_bad_set_is_refused_in_one_line_that_says_why(fmu_path, tmp_path, capsys, setting, words):
    assert main(["simulate", "--set", setting, "--fmu", str(fmu_path), "--out", str(tmp_path / "x")]) == 2
    err = _one_error_line(capsys)
    assert words in err
    assert list((tmp_path / "x").iterdir()) == []  # nothing written


@pytest.mark.parametrize("argv, words", [
    (["--me"], "--me needs an FMU with Model Exchange"),
    (["--fmi", "3"], "--fmi 3 does not match"),
    (["--stop", "-1"], "--stop must be a positive number"),
    (["--step", "0"], "--step must be a positive number"),
    (["--stop", "1", "--step", "2"], "longer than the run"),
])
def test_misuse_of_the_options_is_one_line(fmu_path, tmp_path, capsys, argv, words):
    assert main(["simulate", *argv, "--fmu", str(fmu_path), "--out", str(tmp_path / "out")]) == 2
    assert words in _one_error_line(capsys)
    assert list(tmp_path.iterdir()) == []  # checked before the output folder is made


@pytest.mark.parametrize("argv", [["--me"], ["--fmi", "2", "--me"]])
def test_model_exchange_of_the_project_s_fmu_needs_fmi_3_before_anything_is_built(tmp_path, capsys, argv):
    assert main(["simulate", *argv, "--build-dir", str(tmp_path / "fmus"), "--out", str(tmp_path / "out")]) == 2
    assert "--me needs --fmi 3: the project's FMI 2.0 FMU is co-simulation only" in _one_error_line(capsys)
    assert list(tmp_path.iterdir()) == []


def test_a_value_the_fmu_refuses_is_one_line_with_the_fmu_s_reason(fmu_path, tmp_path, capsys):
    out = tmp_path / "bad"
    assert main(["simulate", "--set", "l1=-1", "--fmu", str(fmu_path), "--out", str(out)]) == 1
    err = _one_error_line(capsys)
    assert "l1" in err and "must be > 0" in err
    assert "start state: phi1_0 = 1 rad (default), phi2_0 = 1 rad (default)" in err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "stopped by the FMU" and "l1" in summary["fmu_message"]
    assert [entry["source"] for entry in summary["start_state"].values()] == ["default"] * 4


def test_an_interrupted_case_changes_nothing_and_leaves_nothing(fmu_path, tmp_path, capsys, monkeypatch):
    out = tmp_path / "case"
    out.mkdir()
    (out / "simulation.csv").write_text("an earlier run's\n")

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(FmuRunner, "simulate", interrupted)
    assert main(["simulate", "--fmu", str(fmu_path), "--out", str(out)]) == 130
    assert "interrupted; nothing was written" in _one_error_line(capsys)
    assert [p.name for p in out.iterdir()] == ["simulation.csv"]  # no staging folder, the earlier file intact
    assert (out / "simulation.csv").read_text() == "an earlier run's\n"


def _description(*variables: SimpleNamespace) -> SimpleNamespace:
    return SimpleNamespace(modelVariables=list(variables))


def _variable(name: str, kind: str = "Real", **extra) -> SimpleNamespace:
    fields = {"causality": "parameter", "variability": "fixed", "min": None, "max": None, "unit": None,
              "declaredType": None}
    return SimpleNamespace(name=name, type=kind, **{**fields, **extra})


def test_set_checks_range_variability_and_type_of_any_fmu():
    md = _description(_variable("k", min="0", max="10", unit="N/m"), _variable("n", "Int32"),
                      _variable("c", variability="constant"), _variable("d", causality="calculatedParameter"),
                      _variable("s", "String"), _variable("on", "Boolean"))
    assert parse_start_values(["k=10", "n=3", "s=rk4", "on=FALSE"], md) == {"k": 10.0, "n": 3, "s": "rk4", "on": False}
    for setting, words in (("k=10.5", "outside the range 0 .. 10 [N/m]"), ("n=1.5", "whole number"),
                           ("c=1", "constant parameter, which a master cannot set"),
                           ("d=1", "fixed calculatedParameter"), ("k=1", "set twice")):
        with pytest.raises(StartValueError, match=words.replace(".", r"\.").replace("[", r"\[")):
            parse_start_values(["k=1", setting] if setting == "k=1" else [setting], md)


def test_the_start_state_takes_what_was_set_and_the_rest_from_the_model_description():
    md = _description(_variable("phi1_0", start="0.3", unit="rad"), _variable("omega1_0", start="0", unit="rad/s"),
                      _variable("phi2_0", start="1.5", declaredType=SimpleNamespace(unit="rad")),
                      _variable("omega2_0", start="-2", unit="rad/s"), _variable("air_drag", "Boolean", start="false"))
    state = start_state({"omega1_0": 4, "air_drag": True}, md)
    assert tuple(value.name for value in state) == START_STATE == ("phi1_0", "phi2_0", "omega1_0", "omega2_0")
    assert [(value.value, value.unit, value.given) for value in state] == [
        (0.3, "rad", False), (1.5, "rad", False), (4.0, "rad/s", True), (-2.0, "rad/s", False)]
    assert start_state_words(state) == ("phi1_0 = 0.3 rad (default), phi2_0 = 1.5 rad (default), "
                                        "omega1_0 = 4 rad/s (set), omega2_0 = -2 rad/s (default)")


def test_the_closest_parameter_is_named_whatever_the_case_of_the_letters():
    assert closest_name("PHI2_0", ["phi1_0", "phi2_0", "omega2_0"]) == "phi2_0"
    assert closest_name("anything", []) is None


def test_the_example_in_the_help_runs_as_written(fmu_path, tmp_path, capsys):
    from double_pendulum.cli import build_parser

    example = build_parser().command_parsers["simulate"].epilog.splitlines()[1].split()
    assert example[:2] == ["double-pendulum", "simulate"]
    argv = [*example[1:-2], "--stop", "0.5", "--fmu", str(fmu_path), "--out", str(tmp_path / "my_case")]
    assert main(argv) == 0
    assert Path(tmp_path / "my_case" / "simulation.png").stat().st_size > 10_000


def test_the_summary_s_fmpy_call_works_from_any_folder_and_null_means_only_explains_nulls(tmp_path, fmu_path,
                                                                                       monkeypatch):
    """The summary's fmpy call names the FMU by its absolute path (run from another folder it gives the same
    numbers as the case's CSV); ``null_means`` explains only the values that are null."""
    import ast
    import os

    from double_pendulum.case import Case, run_case

    monkeypatch.chdir(fmu_path.parent)
    (tmp_path / "case").mkdir()
    outcome = run_case(Case(fmu=Path(fmu_path.name), start_values={"phi1_0": 1.0}, stop_time=0.2),
                       tmp_path / "case", animate=False)
    summary = json.loads((tmp_path / "case" / "summary.json").read_text())
    call = ast.parse(summary["fmpy_call"], mode="eval").body
    path = ast.literal_eval(call.args[0])
    assert os.path.isabs(path)
    monkeypatch.chdir(tmp_path)  # another folder
    again = simulate_fmu(path, **{k.arg: ast.literal_eval(k.value) for k in call.keywords})
    written = read_results_csv(tmp_path / "case" / "simulation.csv")
    assert float(again["phi1"][-1]) == float(written["phi1"][-1])
    for key in summary["null_means"]:
        assert summary.get(key) is None, (key, summary.get(key))
    assert outcome.message is None and "fmu_message" in summary["null_means"]


def test_one_rule_for_start_angles_in_the_model_the_component_and_the_cli(fmu_path, tmp_path, capsys):
    """A start angle is any number within +-1e4 rad, used as given: phi1_0 = 9 rad is the state 9 - 2 pi rad, and
    its run is that one's shifted by a turn. The component (the FMU) and the CLI refuse 2e4 rad in the same words,
    naming the angle and its value; the CLI before it writes anything."""
    from double_pendulum.component.cosimulation import DoublePendulumCoSimulation
    from double_pendulum.model.parameters import MAX_START_ANGLE, ParameterError, check_start_angle

    for value in (9.0, -MAX_START_ANGLE, MAX_START_ANGLE, np.pi + 0.05):
        check_start_angle("phi2_0", value)
    for value in (2e4, -1.0001e4, float("nan"), float("inf")):
        with pytest.raises(ParameterError, match=rf"phi2_0 = {value!r} rad: a start angle must be a finite number "
                                                 r"from -10000 to 10000 rad"):
            check_start_angle("phi2_0", value)
    with pytest.raises(ParameterError, match=r"phi1_0 = 20000.0 rad: a start angle must be"):
        DoublePendulumCoSimulation().set("phi1_0", 2e4)

    assert main(["simulate", "--set", "phi1_0=2e4", "--fmu", str(fmu_path), "--out", str(tmp_path / "x")]) == 2
    err = _one_error_line(capsys)
    assert "--set phi1_0=2e4: invalid phi1_0 = 20000.0 rad: a start angle must be a finite number" in err
    assert list(tmp_path.iterdir()) == []

    out = tmp_path / "nine"
    assert main(["simulate", "--set", "phi1_0=9", "--stop", "0.5", "--no-animation", "--fmu", str(fmu_path),
                 "--out", str(out)]) == 0
    nine = read_results_csv(out / "simulation.csv")
    wrapped = simulate_fmu(str(fmu_path), start_values={"phi1_0": 9.0 - 2 * np.pi}, stop_time=0.5,
                           output_interval=0.01, output=["phi1", "phi2"])
    assert nine["phi1"][0] == 9.0  # not wrapped: the output counts the turn
    np.testing.assert_allclose(nine["phi1"] - 2 * np.pi, wrapped["phi1"], atol=1e-6)
    np.testing.assert_allclose(nine["phi2"], wrapped["phi2"], atol=1e-6)


def _growth(fmu_path: Path, tmp_path: Path, monkeypatch, stop: float, batch: int) -> int:
    """How many memory blocks Python's heap (``sys.getallocatedblocks``) gained over the second half of a run of
    ``stop`` s at 5 ms, its rows streamed to the CSV file every ``batch`` rows: the most it held then, less what it
    held at half time (a run's fixed costs, the FMU's instance and the like, come before)."""
    import sys

    from double_pendulum.runs import row_stream

    monkeypatch.setattr(row_stream, "BATCH_ROWS", batch)
    held = []
    take = row_stream.RowStream.take

    def sampled(self, recorder, keep=1):
        take(self, recorder, keep)
        if recorder.rows[-1][0] >= stop / 2:
            held.append(sys.getallocatedblocks())

    monkeypatch.setattr(row_stream.RowStream, "take", sampled)
    out = Path(tempfile.mkdtemp(dir=tmp_path))
    outcome = case_module.run_case(case_module.Case(fmu_path, {}, stop, 0.005), out, animate=False)
    assert outcome.summary["rows"] == round(stop / 0.005) + 1
    return max(held) - held[0]


def test_memory_stays_flat_however_long_the_run(fmu_path, tmp_path, monkeypatch):
    """Over the second half of a run of N = 2000 steps and of 4N, Python's heap grows by no more than a batch of
    rows (512 rows, 31 blocks each: 16,000): the rows go to the file as they come. Kept in memory, as fmpy keeps them
    (a batch larger than the run), the 4N run's second half, 4000 rows, adds 124,000 blocks."""
    for stop in (10.0, 40.0):
        assert _growth(fmu_path, tmp_path, monkeypatch, stop, 512) < 20_000
    assert _growth(fmu_path, tmp_path, monkeypatch, 10.0, 10**9) > 25_000  # the measure sees rows that are kept
    assert _growth(fmu_path, tmp_path, monkeypatch, 40.0, 10**9) > 100_000


def test_the_streamed_csv_holds_fmpy_s_numbers_bit_for_bit(fmu_path, tmp_path, monkeypatch):
    """Streamed in batches of 64 rows, the file is the one fmpy's whole result gives."""
    from double_pendulum.runs import row_stream

    monkeypatch.setattr(row_stream, "BATCH_ROWS", 64)
    out = tmp_path / "streamed"
    out.mkdir()
    values = {"phi1_0": 2.0, "air_drag": True}
    case_module.run_case(case_module.Case(fmu_path, values, 3.0, 0.01), out, animate=False)
    plain = simulate_fmu(str(fmu_path), start_values=values, stop_time=3.0, output_interval=0.01,
                         output=list(OUTPUT_NAMES))
    streamed = read_results_csv(out / "simulation.csv")
    assert len(streamed) == len(plain) == 301
    for name in plain.dtype.names:
        np.testing.assert_array_equal(streamed[name], plain[name], err_msg=name)


def test_a_long_run_is_estimated_and_refused_beyond_max_wall(fmu_path, tmp_path, capsys):
    out = tmp_path / "long"
    assert main(["simulate", "--stop", "1e9", "--max-wall", "60", "--fmu", str(fmu_path), "--out", str(out)]) == 2
    captured = capsys.readouterr()
    estimate = captured.out.splitlines()[-1]
    assert estimate.startswith("this run takes about ") and "100,000,000,001 rows, about" in estimate
    err = captured.err
    assert err.count("\n") == 1 and "Traceback" not in err
    assert err.startswith("double-pendulum: error: --stop 1e+09 s would take about ")
    assert "more than --max-wall 60 s" in err and "nothing written (to run it all: --max-wall " in err
    assert list(out.iterdir()) == []  # the probe's rows are not kept


def test_the_estimate_is_near_the_run_s_time(fmu_path, tmp_path, capsys):
    """The first second of a 200 s run estimates its wall time to within a factor of 2 (the machine's load moves
    it)."""
    assert main(["simulate", "--stop", "200", "--no-animation", "--fmu", str(fmu_path), "--out",
                 str(tmp_path / "o")]) == 0
    lines = capsys.readouterr().out.splitlines()
    estimated = lines[1].removeprefix("this run takes about ").split()
    took = float(lines[2].split(" rows, ")[1].split(" s)")[0])
    estimated_s = float(estimated[0]) * {"s": 1, "min": 60}[estimated[1]]
    assert took / 2 < estimated_s < 2 * took, (lines[1], lines[2])
