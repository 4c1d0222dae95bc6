"""A student's own camera track through the project's analysis (``run --track FILE.csv --pendulum FILE.toml``).

The records are made by the model (:mod:`double_pendulum.analysis.track.synthetic`): a pendulum of known masses,
lengths, pivot and viscous joint damping, simulated by the FMU's own component, sampled at a camera's rate for 20 s,
with 1 mm of white noise on each coordinate (the seed's measured position noise is 0.5 to 1 mm: tests of
``estimate_position_noise``). The run must give back what made them, within its stated errors: 3 standard errors,
a band a correct analysis leaves with probability 0.3 % (the records' noise is seeded, so each test is
deterministic). Bad files get one line each, exit status 2, and no results folder.
"""

from __future__ import annotations

import csv
import json
import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from double_pendulum.analysis.decay.fit import fit_model
from double_pendulum.analysis.losses import claims
from double_pendulum.analysis.losses.comparison import common_factor, comparison_rows
from double_pendulum.analysis.losses.fitting import fit_models, problem_from_track
from double_pendulum.analysis.losses.identification import measured, seed_reconstruction
from double_pendulum.analysis.track.measurement import load_track
from double_pendulum.analysis.track.synthetic import MadeTrack, write_pendulum, write_track
from double_pendulum.analysis.track.user_track import TrackFileError, parse_columns, read_record, read_track
from double_pendulum.cli import main

PENDULUM = {"m1": 0.25, "m2": 0.20, "l1": 0.30, "l2": 0.22}
B_V = 4e-4
"""The viscous joint damping [N m s/rad] the records are made with (loss model ``viscous``)."""
MADE = MadeTrack({**PENDULUM, "bearing_friction": True, "c_R1": 0.0, "c_R2": 0.0, "b_v1": B_V, "b_v2": B_V},
                 start=(1.0, 0.4, 0.0, 0.0), pivot=(0.12, 0.45), fps=29.97, duration_s=20.0, noise_m=1e-3, seed=3)
RENAMED = {"t": "time", "x1": "xA", "y1": "yA", "x2": "xB", "y2": "yB"}
AT_25_FPS = MadeTrack(MADE.pendulum, start=MADE.start, pivot=(-4.0, 1.5), fps=25.0, duration_s=20.0, noise_m=1e-3,
                      seed=4)
SEED_FIGURES = ("0.0252", "0.301", "0.297", "0.813", "-0.024 ", "Table 1", "seed_table1")
"""The seed's figures (its b, masses, fit, table) that a user's results must not show."""


@pytest.fixture(scope="session")
def records(tmp_path_factory: pytest.TempPathFactory, runner) -> Path:
    """The records, made once: ``my_track.csv`` (made by the FMU through fmpy; seed's column names, metres,
    29.97 fps) with ``my_pendulum.toml`` (the masses); ``cm_track.csv`` (made by the FMU's component in this process;
    renamed columns, cm to 0.1 mm, 25 fps, three frames without the lower bob, the pivot far from the origin) with
    ``cm_pendulum.toml`` (the masses and l1)."""
    folder = tmp_path_factory.mktemp("own_track")
    write_track(folder / "my_track.csv", MADE.positions(runner), frame_column=True)
    write_pendulum(folder / "my_pendulum.toml", {"m1": PENDULUM["m1"], "m2": PENDULUM["m2"]})
    table = AT_25_FPS.positions()
    table[[100, 101, 300], 3:5] = np.nan  # the tracker lost the lower bob
    path = write_track(folder / "cm_track.csv", table, columns=RENAMED, unit_per_m=100.0, decimals=2)
    path.write_text(path.read_text().replace("nan", ""))  # empty cells, as Tracker leaves them
    write_pendulum(folder / "cm_pendulum.toml", {"m1": PENDULUM["m1"], "m2": PENDULUM["m2"], "l1": PENDULUM["l1"]})
    return folder


def _run(args: list[str], fmu_path: Path, out: Path) -> int:
    return main(["run", *args, "--fmu", str(fmu_path), "--out", str(out)])


def _true_b(made: MadeTrack, folder: Path) -> float:
    """b of E = a exp(b t) fitted to the simulation's own energy on the run's fitted frames with the run's weights
    (``track.csv``'s in_fit and sigma_E_fit): the b the run would find without the noise."""
    with (folder / "track.csv").open() as fh:
        rows = list(csv.DictReader(fh))
    used = np.array([float(r["in_fit"]) == 1 for r in rows])
    t = np.array([float(r["time [s]"]) for r in rows])[used]
    sigma = np.array([float(r["sigma_E_fit [J]"]) for r in rows])[used]
    energy = np.asarray(made.run(outputs=("E_pendulum",))["E_pendulum"])[used]
    return fit_model("exponential", t, energy, sigma).value("b")


def _outputs_text(out: Path) -> str:
    return "\n".join(p.read_text() for p in [out / "index.html", *out.glob("*/summary.json"), *out.glob("*/report.md")])


def test_the_run_gives_back_the_pendulum_that_made_the_track(records, fmu_path, tmp_path, capsys):
    out = tmp_path / "results"
    assert _run(["energy_decay", "loss_identification", "--track", str(records / "my_track.csv"), "--pendulum",
                 str(records / "my_pendulum.toml"), "--quick"], fmu_path, out) == 0  # fmt: skip
    said = capsys.readouterr().out
    assert "your record: my_track.csv, 600 frames" in said and "29.97 fps" in said
    s = json.loads((out / "energy_decay" / "summary.json").read_text())
    assert s["record"]["file"] == "my_track.csv" and s["source"].startswith("my_track.csv")
    assert abs(s["record"]["frame_interval_s"] - 1 / 29.97) < 1e-6
    # the decay rate: within 3 of its statistical errors of the noiseless record's, fitted the same way
    b_true = _true_b(MADE, out / "energy_decay")
    stat = s["error_budget"]["b_statement"]["statistical_per_s"]
    assert abs(s["b_per_s"] - b_true) < 3 * stat, (s["b_per_s"], b_true, stat)
    assert stat < 0.05 * abs(b_true)  # a measurement, not a bound: 20 s at 1 mm give b to a few per cent
    # the lengths and the pivot within 3 of their standard errors
    fitted = s["lengths_fitted_m"]
    for k in ("l1", "l2"):
        assert abs(fitted[k] - PENDULUM[k]) < 3 * fitted[f"{k}_stderr"], (k, fitted)
    pivot = s["pivot_origin_m"]
    assert abs(pivot["x"] - 0.12) < 3 * pivot["sigma_x"] and abs(pivot["y"] - 0.45) < 3 * pivot["sigma_y"]
    assert s["masses_kg"] == {"m1": 0.25, "m2": 0.20}
    # the noise estimate finds the 1 mm put in (within 15 %: a robust estimate from 600 frames)
    assert s["position_noise_m"]["upper_bob"] == pytest.approx(1e-3, rel=0.15)
    losses = json.loads((out / "loss_identification" / "summary.json").read_text())
    assert losses["record"]["file"] == "my_track.csv" and losses["load_proportional_friction_against_seed"] is None
    assert losses["b_measured_per_s"] == pytest.approx(s["b_per_s"], rel=0.02)  # the same record's energy
    # whose record it is, everywhere; none of the seed's figures
    page = (out / "index.html").read_text()
    assert "Record analysed: <strong>my_track.csv</strong>" in page
    assert "energy decay of your pendulum from your camera track my_track.csv" in page
    text = _outputs_text(out)
    assert "Energy decay of your pendulum (my_track.csv)" in text
    assert [f for f in SEED_FIGURES if f in text] == []
    assert "seed" not in s and "seed" not in s["error_budget"]


def test_renamed_columns_in_cm_at_25_fps_with_lost_frames(records, fmu_path, tmp_path, capsys):
    out = tmp_path / "results"
    assert _run(["energy_decay", "--track", str(records / "cm_track.csv"), "--pendulum",
                 str(records / "cm_pendulum.toml"), "--columns", "t=time,x1=xA,y1=yA,x2=xB,y2=yB", "--scale", "0.01"],
                fmu_path, out) == 0  # fmt: skip
    said = capsys.readouterr().out
    assert "3 frame(s) without a bob's position" in said
    s = json.loads((out / "energy_decay" / "summary.json").read_text())
    assert abs(s["record"]["frame_interval_s"] - 0.04) < 1e-7 and s["record"]["frames_missing_in_file"] == 3
    assert s["l1_m"] == PENDULUM["l1"]  # given in the pendulum file
    fitted = s["lengths_fitted_m"]
    for k in ("l1", "l2"):  # the track's own lengths: cm to 0.1 mm adds 0.03 mm of rounding, within the noise
        assert abs(fitted[k] - PENDULUM[k]) < 3 * fitted[f"{k}_stderr"], (k, fitted)
    pivot = s["pivot_origin_m"]
    assert abs(pivot["x"] + 4.0) < 3 * pivot["sigma_x"] and abs(pivot["y"] - 1.5) < 3 * pivot["sigma_y"]
    b_true = _true_b(AT_25_FPS, out / "energy_decay")
    stat = s["error_budget"]["b_statement"]["statistical_per_s"]
    assert abs(s["b_per_s"] - b_true) < 3 * stat, (s["b_per_s"], b_true, stat)
    text = _outputs_text(out)
    assert [f for f in (*SEED_FIGURES, "29.97") if f in text] == []
    assert "cm_track.csv" in (out / "index.html").read_text()


def test_measured_vs_sim_predicts_the_users_track_at_its_own_frame_rate(records, fmu_path, tmp_path, capsys):
    """measured_vs_sim on the 25 fps record in cm (quick): t0 at the end of its release, the start and geometry fitted
    to the seed's windows in seconds (0.5 s: 13 frames at 25 fps), the losses fitted to its energy. The model of the
    pendulum that made the record follows it to within a few times the 1 mm noise; run on the seed's 29.97 fps grid
    it would be centimetres off within a swing."""
    out = tmp_path / "results"
    assert _run(["measured_vs_sim", "--track", str(records / "cm_track.csv"), "--pendulum",
                 str(records / "cm_pendulum.toml"), "--columns", "t=time,x1=xA,y1=yA,x2=xB,y2=yB", "--scale", "0.01",
                 "--quick"], fmu_path, out) == 0  # fmt: skip
    s = json.loads((out / "measured_vs_sim" / "summary.json").read_text())
    assert s["record"]["file"] == "cm_track.csv" and s["source"].startswith("cm_track.csv")
    assert s["start_frame"] == 3 and s["t0_s"] == pytest.approx(3 * 0.04)  # the release: the energy's first maximum
    with (out / "measured_vs_sim" / "paths.csv").open() as fh:
        since_t0 = [float(r["t_since_t0 [s]"]) for r in csv.DictReader(fh)]
    assert np.diff(since_t0).min() == pytest.approx(0.04) and since_t0[-1] == pytest.approx(s["prediction_s"])
    geo = s["starts"]["least_squares_geometry"]
    assert geo["n_frames"] == 13 and s["starts"]["least_squares"]["n_frames"] == 8  # 0.5 s and 1/3 s at 25 fps
    assert abs(geo["geometry"]["view_rotation"]) < 3 * geo["geometry_stderr"]["view_rotation"]  # made level
    assert abs(geo["geometry"]["l2"] - PENDULUM["l2"]) < 1e-3
    assert s["model"]["lengths_m"]["l1"] == PENDULUM["l1"] and s["model"]["bob_masses_kg"] == pytest.approx(0.45)
    for label in ("lsq_start_identified", "lsq_geometry_identified"):  # within 2.5 mm rms of the 1 mm noise
        assert s["rms_error_first_second_m"][label]["lower_bob"] < 2.5e-3, s["rms_error_first_second_m"]
    main = s["horizon_5cm_details"]["lsq_geometry_identified"]
    assert main["censored"] and main["smoothed_error_peak_m"] < 0.01  # never near 5 cm in the 3 s
    text = (out / "measured_vs_sim" / "report.md").read_text() + json.dumps(s)
    assert "FMU prediction of your pendulum's track (cm_track.csv)" in text
    assert [f for f in (*SEED_FIGURES, "29.97", "0.8 s", "t0 = 0.80") if f in text] == []
    assert "FMU prediction of your camera track cm_track.csv" in (out / "index.html").read_text()


def test_the_loss_model_that_made_the_track_is_among_those_that_fit(records):
    """The one-mechanism models of loss_identification fitted to the record (as its default run fits them, in this
    process): viscous damping, which made it, is the one the energy supports, at the damping put in."""
    rec = read_record(records / "my_track.csv", records / "my_pendulum.toml").reconstruction()
    problem = problem_from_track(rec, measured(rec))
    fits, _ = fit_models(("air", "drag", "viscous", "bearing"), problem, max_workers=1)
    rows = comparison_rows(fits, common_factor(problem))
    supported = claims.supported_models(rows)["models"]
    assert "viscous" in supported, [(r["model"], r["delta_aic"]) for r in rows]
    b_v = next(r for r in rows if r["model"] == "viscous")["parameters"]["b_v"]
    assert abs(b_v["value"] - B_V) < 3 * b_v["stderr"], b_v
    assert set(supported) == {"viscous"}  # the others miss by far: delta AIC above 10
    assert min(r["delta_aic"] for r in rows if r["model"] != "viscous") > 10
    # the fits' cache (runs.result_cache) keys on the record: its energies and its frame interval
    seed_rec = seed_reconstruction()
    assert problem.digest() != problem_from_track(seed_rec, measured(seed_rec), quick=True).digest()
    assert replace(problem, dt=0.04).digest() != problem.digest()


def test_the_seed_table_read_as_a_users_track_is_the_seeds_track():
    """The seed's Table 1 through the user's reader (its times are cut to 2 or 3 decimals, so --fps) is the track
    the seed's loader reads: the same frames, positions, flags and times."""
    seed = load_track()
    user = read_track(Path(__file__).resolve().parents[1] / "data" / "seed_table1.csv", fps=29.97).track
    for k in ("x1", "y1", "x2", "y2", "valid"):
        assert np.array_equal(getattr(user, k), getattr(seed, k)), k
    assert np.allclose(user.t, seed.t, rtol=0, atol=1e-12) and user.dt == seed.dt


def _lines(path: Path, edit) -> list[str]:
    return edit((path).read_text().splitlines())


def _swap_times(lines: list[str]) -> list[str]:
    lines[40], lines[41] = lines[41], lines[40]
    return lines


def _blank_lower_bob(lines: list[str]) -> list[str]:
    return [",".join(line.split(",")[:4] + ["", ""]) if 1 <= i <= 90 else line for i, line in enumerate(lines)]


def _swap_lower_bob_axes(lines: list[str]) -> list[str]:
    out = lines[:1]
    for line in lines[1:]:
        cells = line.split(",")
        cells[4], cells[5] = cells[5], cells[4]  # x2 and y2 swapped: the lower bob no longer a rod's length away
        out.append(",".join(cells))
    return out


def _round_times(lines: list[str]) -> list[str]:
    out = lines[:1]
    for line in lines[1:]:
        cells = line.split(",")
        cells[1] = f"{math.floor(float(cells[1]) * 100) / 100:.2f}"  # cut to 2 decimals, as the seed's table
        out.append(",".join(cells))
    return out


def _y_down(lines: list[str]) -> list[str]:
    out = lines[:1]
    for line in lines[1:]:
        cells = line.split(",")
        cells[3], cells[5] = (f"{-float(cells[k]):.4f}" for k in (3, 5))  # image coordinates: y down
        out.append(",".join(cells))
    return out


BAD_TRACKS = {
    "missing column": (lambda ls: [ls[0].replace("x2_m", "x2"), *ls[1:]],
                       "column 'x2_m' (x2) is missing; columns present: frame, t_s, x1_m, y1_m, x2, y2_m"),
    "time not increasing": (_swap_times, "the time does not increase at row 42"),
    "too many lost frames": (_blank_lower_bob, "90 of 600 frames lack a bob's position"),
    "too few frames": (lambda ls: ls[:60], "59 frames over 1.94 s; at least 100 frames over 8 s are needed"),
    "not a rigid rod": (_swap_lower_bob_axes, "the distance between the bobs scatters by"),
    "y pointing down": (_y_down, "the upper bob is above the fitted pivot in 100% of the frames: y points down"),
    "uneven times": (_round_times, "the time steps are uneven: 0.03 to 0.04 s"),
    "semicolons": (lambda ls: [line.replace(",", ";") for line in ls],
                   "its columns are separated by semicolons; export with commas"),
    "not a number": (lambda ls: [*ls[:5], ",".join([*ls[5].split(",")[:2], "abc", *ls[5].split(",")[3:]]), *ls[6:]],
                     "row 6: x1_m = 'abc' is not a number"),
}


@pytest.mark.parametrize("case", BAD_TRACKS)
def test_a_bad_track_is_one_line_and_nothing_is_written(case, records, tmp_path, capsys):
    edit, expected = BAD_TRACKS[case]
    bad = tmp_path / "bad.csv"
    bad.write_text("\n".join(_lines(records / "my_track.csv", edit)) + "\n")
    out = tmp_path / "results"
    code = main(["run", "energy_decay", "--track", str(bad), "--pendulum", str(records / "my_pendulum.toml"),
                 "--out", str(out)])  # fmt: skip
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and err.startswith("double-pendulum: error: "), err
    assert expected in err, err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.csv"]  # no results folder, no FMU built


BAD_RUNS = {
    "masses missing": (["--pendulum", "{folder}/bad.toml"], "l1 = 0.3\n", "m1 and m2 [kg] missing"),
    "negative mass": (["--pendulum", "{folder}/bad.toml"], "m1 = -0.3\nm2 = 0.2\n",
                      "invalid m1 = -0.3 kg: must be > 0"),
    "unknown key": (["--pendulum", "{folder}/bad.toml"], "m1 = 0.3\nm2 = 0.2\nmass3 = 1\n", "unknown key(s) mass3"),
    "no pendulum": ([], "", "--track needs --pendulum FILE.toml"),
    "a length in cm": (["--pendulum", "{folder}/bad.toml"], "m1 = 0.3\nm2 = 0.2\nl1 = 30\n",
                       "l1 = 30 m, but the track gives 0.3"),
    "a scenario without a track": (["--pendulum", "{folder}/bad.toml", "chaos"], "m1 = 0.3\nm2 = 0.2\n",
                                   "--track: chaos does not analyse a camera track"),
    "all": (["--pendulum", "{folder}/bad.toml", "all"], "m1 = 0.3\nm2 = 0.2\n",
            "--track: 'all' runs every scenario; the ones that analyse a camera track: energy_decay, "
            "loss_identification, measured_vs_sim"),
    "columns without a track": (["--no-track", "--columns", "t=time"], "", "--columns describe(s) your own track"),
}


@pytest.mark.parametrize("case", BAD_RUNS)
def test_a_bad_pendulum_or_option_is_one_line_and_nothing_is_written(case, records, tmp_path, capsys):
    extra, toml, expected = BAD_RUNS[case]
    (tmp_path / "bad.toml").write_text(toml)
    extra = [a.format(folder=tmp_path) for a in extra]
    scenarios = [a for a in extra if a in ("chaos", "all")] or ["energy_decay"]
    options = [a for a in extra if a not in scenarios and a != "--no-track"]
    track = [] if "--no-track" in extra else ["--track", str(records / "my_track.csv")]
    out = tmp_path / "results"
    code = main(["run", *scenarios, *track, *options, "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and err.startswith("double-pendulum: error: "), err
    assert expected in err, err
    assert not out.exists()


def test_a_tracker_export_with_its_two_header_rows_reads_by_position(records, tmp_path):
    """Tracker's export of two point masses: their names in a row above ``t,x,y,x,y``; the names repeat, so the
    columns are given by position. The same track as the file it was made from."""
    rows = (records / "my_track.csv").read_text().splitlines()[1:]
    lines = [",mass A,,mass B,", "t,x,y,x,y", *(",".join(r.split(",")[1:]) for r in rows)]
    (tmp_path / "tracker.csv").write_text("\n".join(lines) + "\n")
    tracker = read_track(tmp_path / "tracker.csv", columns=parse_columns("t=1,x1=2,y1=3,x2=4,y2=5")).track
    plain = read_track(records / "my_track.csv").track
    for k in ("t", "x1", "y1", "x2", "y2", "valid"):
        assert np.array_equal(getattr(tracker, k), getattr(plain, k)), k
    with pytest.raises(TrackFileError, match=r"column 'x' \(x1\) appears more than once \(give its position"):
        read_track(tmp_path / "tracker.csv", columns=parse_columns("t=t,x1=x"))
