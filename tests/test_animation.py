"""The animations: real time, small, drawn from the CSV files the scenarios wrote; the x-y overlay's table."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import quick_scenario
from PIL import Image

from double_pendulum.analysis.track.measurement import untilt
from double_pendulum.analysis.track.tilt import seed_record_geometry
from double_pendulum.plots.animation import (
    MAX_FRAME_RATE,
    Swing,
    animate_swings,
    frame_rows,
    palette_image,
    real_time_durations_ms,
)
from double_pendulum.runs.results_io import read_results_csv

GIF_LIMIT_BYTES = 3_000_000
"""The issue's bound on a GIF's size (about 3 MB)."""


def _durations(path) -> list[int]:
    with Image.open(path) as gif:
        durations = []
        for k in range(gif.n_frames):
            gif.seek(k)
            durations.append(gif.info["duration"])
    return durations


@pytest.mark.parametrize("step", [0.005, 1 / 29.97, 0.01, 0.05, 0.2])
def test_frames_come_at_most_twenty_a_second_and_their_durations_keep_real_time(step):
    times = np.arange(0, 400) * step
    rows = frame_rows(times)
    assert np.all(np.diff(times[rows]) >= 1 / MAX_FRAME_RATE - 1e-9)
    assert np.diff(rows).max() == np.diff(rows).min()  # every k-th row
    durations = real_time_durations_ms(times[rows], hold_last_ms=700)
    assert durations[-1] == 700 and min(durations) >= 20  # browsers slow down shorter frames
    assert all(d % 10 == 0 for d in durations)  # GIF counts in 10 ms
    assert abs(sum(durations[:-1]) - 1000 * (times[rows][-1] - times[0])) <= 5  # no drift over the whole GIF


def test_the_palette_holds_each_colour_drawn_and_its_shades_to_white():
    palette = palette_image(["C0", "C3"]).getpalette()[:3 * 40]
    colours = {tuple(palette[i:i + 3]) for i in range(0, len(palette), 3)}
    assert (255, 255, 255) in colours and (0, 0, 0) in colours
    assert (31, 119, 180) in colours and (214, 39, 40) in colours  # Matplotlib's C0 and C3 themselves


def test_an_animation_shows_what_it_is_given_frame_by_frame(tmp_path):
    t = np.arange(0.0, 2.0, 0.01)
    angle = 0.5 * np.sin(2 * np.pi * t)
    x1, y1 = 0.3 * np.sin(angle), -0.3 * np.cos(angle)
    swing = Swing("a test", x1, y1, x1 + 0.2 * np.sin(2 * angle), y1 - 0.2 * np.cos(2 * angle), "C0")
    path = animate_swings(t, [swing], tmp_path / "test.gif", title="a test")
    with Image.open(path) as gif:
        assert gif.n_frames == len(frame_rows(t)) == 40
        gif.seek(0)
        first = np.asarray(gif.convert("RGB")).copy()
        gif.seek(10)
        later = np.asarray(gif.convert("RGB"))
    assert (first != later).any()  # the pendulum moved
    assert sum(_durations(path)[:-1]) == pytest.approx(1000 * t[frame_rows(t)][-1], abs=5)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["test.gif"]  # no partial file left


@pytest.mark.parametrize("scenario, gif, csv", [("free_swing", "twin_starts.gif", "chaotic.csv"),
                                                ("measured_vs_sim", "measured_vs_sim.gif", "paths.csv")])
def test_a_scenario_s_animation_is_small_and_plays_its_csv_in_real_time(quick_results, scenario, gif, csv):
    folder, summary = quick_scenario(quick_results, scenario)
    path = folder / gif
    assert 0 < path.stat().st_size <= GIF_LIMIT_BYTES
    table = read_results_csv(folder / csv)
    t = table["t_since_t0"] if "t_since_t0" in table.dtype.names else table["time"]
    with Image.open(path) as image:
        assert image.n_frames == len(frame_rows(t)) > 10
    assert sum(_durations(path)[:-1]) == pytest.approx(1000 * (t[frame_rows(t)][-1] - t[0]), abs=5)


def test_the_paths_table_holds_the_track_and_a_rigid_simulated_pendulum(quick_results):
    folder, summary = quick_scenario(quick_results, "measured_vs_sim")
    paths, errors = read_results_csv(folder / "paths.csv"), read_results_csv(folder / "errors.csv")
    pivot = summary["pivot_origin_m"]
    np.testing.assert_allclose(paths["time"], errors["time"])
    tilt = seed_record_geometry().geometry.tilt  # the track relative to its circle-fit pivot, in gravity's frame
    assert tilt > 0.03
    for bob in ("1", "2"):
        x, y = untilt(errors[f"x{bob}"] - pivot["x"], errors[f"y{bob}"] - pivot["y"], tilt)
        np.testing.assert_allclose(paths[f"x{bob}_measured"], x, atol=1e-12)
        np.testing.assert_allclose(paths[f"y{bob}_measured"], y, atol=1e-12)
    px, py = paths["pivot_x_simulated"], paths["pivot_y_simulated"]
    upper = np.hypot(paths["x1_simulated"] - px, paths["y1_simulated"] - py)
    lower = np.hypot(paths["x2_simulated"] - paths["x1_simulated"], paths["y2_simulated"] - paths["y1_simulated"])
    model = summary["model"]["lengths_m"]
    l2 = summary["starts"]["least_squares_geometry"].get("geometry", {}).get("l2", model["l2"])
    np.testing.assert_allclose(upper, model["l1"], rtol=1e-9)  # turned and shifted, not stretched
    np.testing.assert_allclose(lower, l2, rtol=1e-9)
    # the main run's error per frame is the distance between the two lower bobs
    main = np.hypot(paths["x2_simulated"] - paths["x2_measured"], paths["y2_simulated"] - paths["y2_measured"])
    np.testing.assert_allclose(main, errors["e2_lsq_geometry_identified"], rtol=1e-9, atol=1e-12)


def test_the_twin_starts_part_as_the_summary_says(quick_results):
    folder, summary = quick_scenario(quick_results, "free_swing")
    a, b = (read_results_csv(folder / f"{name}.csv") for name in ("chaotic", "chaotic_nudged"))
    distance = np.hypot(a["x2"] - b["x2"], a["y2"] - b["y2"])
    twins = summary["twin_starts"]
    parted = twins["lower_bobs_1cm_apart_at_s"]
    if parted is None:
        assert distance.max() <= 0.01
    else:
        assert a["time"][np.argmax(distance > 0.01)] == parted
    assert twins["lower_bob_distance_at_end_m"] == pytest.approx(distance[-1])
    said = f"for {parted:.1f} s, then went its own way" if parted is not None else f"for the whole {a['time'][-1]:g} s"
    assert said in summary["in_short"]  # the plain summary says what the numbers say
