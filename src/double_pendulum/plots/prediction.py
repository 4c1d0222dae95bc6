"""The measured track against the simulation: coordinates and prediction errors, one colour per run in both."""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from .animation import animate_swings, swing
from .style import legend_below, plain_log_numbers, save

ERROR_FLOOR_M = 1e-5
"""Errors [m] below this are drawn at it (the log axis has no zero)."""


def run_colours(titles: Sequence[str]) -> dict[str, str]:
    """One colour a run (``C0``, ``C1``, ... in the order of ``titles``), to pass to both figures of a scenario so
    that a run has the same colour in each."""
    return {title: f"C{i}" for i, title in enumerate(titles)}


def plot_track_comparison(
    t: np.ndarray,
    measured: Mapping[str, np.ndarray],
    runs: Mapping[str, tuple[np.ndarray, Mapping[str, np.ndarray]]],
    path: str | Path,
    *,
    starts: Mapping[str, float] | None = None,
    colours: Mapping[str, str] | None = None,
    title: str = "bob coordinates: measured track and FMU predictions from the same start time",
) -> Path:
    """Measured coordinates (dots) and simulated ones (lines, ``colours`` by run title) over time [s], one panel
    per coordinate [m] (the seed's figs. 11-14); ``starts`` marks start times [s] by label. One legend under the
    panels."""
    names = list(measured)
    colours = colours or run_colours(list(runs))
    fig, axes = plt.subplots(len(names), 1, figsize=(14, 2.6 * len(names)), sharex=True, squeeze=False)
    for ax, name in zip(axes[:, 0], names):
        ax.plot(t, measured[name], ".", color="k", ms=3, label="measured track")
        for label, (ts, coords) in runs.items():
            ax.plot(ts, coords[name], lw=1.1, color=colours[label], label=f"simulated: {label}")
        for label, t0 in (starts or {}).items():
            ax.axvline(t0, color="0.5", ls=":", lw=0.8, label=label)
        bob = {"1": "upper", "2": "lower"}.get(name[-1:])
        ax.set(ylabel=f"{bob} bob {name} [m]" if bob else f"{name} [m]")
        ax.grid(alpha=0.3)
    axes[0, 0].set_title(title)
    axes[-1, 0].set_xlabel("time t [s]")
    axes[-1, 0].set_xlim(float(np.min(t)) - 0.2, float(np.max(t)) + 0.2)
    legend_below(fig, *axes[0, 0].get_legend_handles_labels(), ncols=2)
    return save(fig, path)


def plot_prediction_errors(
    smoothed: Mapping[str, tuple[np.ndarray, np.ndarray]],
    thresholds: Sequence[float],
    path: str | Path,
    *,
    per_frame: tuple[str, np.ndarray, np.ndarray] | None = None,
    spread: tuple[np.ndarray, np.ndarray] | None = None,
    floor: tuple[np.ndarray, np.ndarray] | None = None,
    band: tuple[str, str, np.ndarray, np.ndarray, np.ndarray] | None = None,
    colours: Mapping[str, str] | None = None,
    dashed: Sequence[str] = (),
    title: str = "distance between the simulated and the measured lower bob",
) -> Path:
    """Position error [m] over time since the start [s], log scale: each run's smoothed error (``smoothed``, a line
    in its colour of ``colours``, dashed for the runs named in ``dashed`` where runs lie on top of each other), one
    run's per-frame error (``per_frame``: title, t, error; thin and pale, in that run's colour), the fit's
    uncertainty ``spread`` (t, error) as a shaded band up to it, the track's own rod-length error ``floor``
    (t, error) as grey dots, a ``band`` of smoothed errors (label, the run whose colour it takes, t, lowest,
    highest: e.g. one start under several equally supported models) and the ``thresholds`` [m] as black lines.
    The legend goes under the axes."""
    colours = colours or run_colours(list(smoothed))
    fig, ax = plt.subplots(figsize=(11, 5.5))
    if band is not None:
        text, run, t, low, high = band
        ax.fill_between(t, np.maximum(low, ERROR_FLOOR_M), np.maximum(high, ERROR_FLOOR_M), color=colours[run],
                        alpha=0.4, lw=0, label=text)
    if spread is not None:
        ax.fill_between(spread[0], ERROR_FLOOR_M, np.maximum(spread[1], ERROR_FLOOR_M), color="tab:olive", alpha=0.3,
                        lw=0, label="fit's own uncertainty: median spread of runs drawn from its covariance")
    if floor is not None:
        ax.semilogy(floor[0], np.maximum(floor[1], ERROR_FLOOR_M), ".", color="0.45", ms=2,
                    label="track's own error: | |r2 - r1| - l2 | (a rigid rod has none)")
    if per_frame is not None:
        name, t, err = per_frame
        ax.semilogy(t, np.maximum(err, ERROR_FLOOR_M), lw=0.7, color=colours[name], alpha=0.5,
                    label=f"{name}, per frame")
    for label, (t, err) in smoothed.items():
        ax.semilogy(t, np.maximum(err, ERROR_FLOOR_M), lw=1.4, color=colours[label], label=f"{label}, smoothed",
                    ls="--" if label in dashed else "-")
    for th, ls in zip(thresholds, ("--", "-.", ":")):
        ax.axhline(th, color="k", ls=ls, lw=0.9, label=f"threshold {100 * th:g} cm")
    ax.set_yscale("log")
    ax.set(xlabel="time since the start t - t0 [s]", ylabel="position error of the lower bob [m]", title=title)
    ax.grid(alpha=0.3, which="both")
    legend_below(fig, *ax.get_legend_handles_labels(), ncols=2, fontsize=8)
    return save(fig, path)


def plot_lower_bob_paths(
    paths: np.ndarray,
    path: str | Path,
    *,
    run: str,
    colour: str = "C0",
    window_s: float = 2.0,
    title: str = "path of the lower bob in the x-y plane: measured track and FMU prediction",
) -> Path:
    """The lower bob's measured positions (dots) and the simulated run's (line, ``colour``; ``run``: its title) in
    the x-y plane [m], relative to the measured pivot, in three windows of ``window_s`` seconds (at most a third
    of the comparison each): at its start, in its middle and at its end. ``paths``: the table of
    :func:`~double_pendulum.analysis.prediction.paths.paths_table`, as read back from ``paths.csv``."""
    t = np.asarray(paths["t_since_t0"])
    span = float(t[-1])
    width = min(window_s, span / 3)
    starts = (0.0, (span - width) / 2, span - width)
    fig, axes = plt.subplots(1, 3, figsize=(15, 5.6), sharex=True, sharey=True)
    for ax, start in zip(axes, starts):
        rows = (t >= start - 1e-9) & (t <= start + width + 1e-9)
        ax.plot(paths["x2_simulated"][rows], paths["y2_simulated"][rows], "-", color=colour, lw=1.2,
                label=f"simulated lower bob (FMU, at the camera's frames): {run}")
        ax.plot(paths["x2_measured"][rows], paths["y2_measured"][rows], ".", color="k", ms=4,
                label="measured lower bob (camera track, one dot a frame)")
        ax.set(title=f"t - t0 = {t[rows][0]:.2f} to {t[rows][-1]:.2f} s", aspect="equal",
               xlabel="horizontal position x [m], from the pivot")
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("vertical position y [m], up from the pivot")
    fig.suptitle(f"{title}, at the start, in the middle and at the end of the {span:.2f} s compared")
    legend_below(fig, *axes[0].get_legend_handles_labels(), ncols=2)
    return save(fig, path)


def animate_prediction(paths: np.ndarray, path: str | Path, *, colour: str = "C0") -> Path:
    """The camera's two markers (black rings) and the simulated pendulum (rods and bobs, ``colour``) overlaid as a
    real-time GIF (:func:`~double_pendulum.plots.animation.animate_swings`), relative to the measured pivot, from
    the table of :func:`~double_pendulum.analysis.prediction.paths.paths_table` as read back from ``paths.csv``."""
    pivot = (float(paths["pivot_x_simulated"][0]), float(paths["pivot_y_simulated"][0]))
    swings = [swing(paths, "camera", "k", suffix="_measured", links=False),
              swing(paths, "FMU", colour, suffix="_simulated", pivot=pivot)]
    title = f"measured (camera) and simulated (FMU) pendulum from t0 = {float(paths['time'][0]):.2f} s"
    return animate_swings(paths["t_since_t0"], swings, path, title=title, time_label="t - t0")


def plot_out_of_sample_motion(
    curves: Mapping[str, Mapping[str, tuple[np.ndarray, np.ndarray]]],
    split_s: float,
    threshold: float,
    smoothing_s: float,
    path: str | Path,
    *,
    titles: Callable[[str], str] = str,
    whole: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None,
) -> Path:
    """The lower bob's position error [cm], smoothed over ``smoothing_s`` [s], over time since t0 [s] with each loss
    model's losses fitted to one half of the energy record (``curves``: half fitted to -> model -> (t, error [m]);
    one panel per half, a colour and line style per model named by ``titles(model)``, so that models ending at the same
    losses show as overlapping lines), the held-out half shaded, the split ``split_s`` [s after t0], the
    ``threshold`` [m] and, as a grey band, the lowest and highest error of the whole-record fits (``whole``: t,
    low, high [m])."""
    styles = (("-", 2.4), ("--", 1.7), (":", 1.9), ("-.", 1.4), ((0, (5, 1, 1, 1)), 1.2))
    floor_cm = 100 * ERROR_FLOOR_M
    halves = list(curves)
    fig, axes = plt.subplots(1, len(halves), figsize=(15, 5.4), sharey=True, squeeze=False, layout="constrained")
    for ax, half in zip(axes[0], halves):
        t_end = max(float(t[-1]) for t, _ in curves[half].values())
        lo, hi = (split_s, t_end) if half == "first" else (0.0, split_s)
        ax.axvspan(lo, hi, color="tab:orange", alpha=0.08, lw=0, label="held-out half (the loss fit never saw it)")
        if whole is not None:
            ax.fill_between(whole[0], np.maximum(100 * whole[1], floor_cm), np.maximum(100 * whole[2], floor_cm),
                            color="0.6", alpha=0.35, lw=0, label="range of the same models fitted to the whole record")
        for i, (model, (t, err)) in enumerate(curves[half].items()):
            ls, lw = styles[i % len(styles)]
            ax.semilogy(t, np.maximum(100 * err, floor_cm), ls=ls, lw=lw, color=f"C{i}",
                        label=f"fitted to one half: {titles(model)}")
        ax.axvline(split_s, color="0.3", lw=0.9, ls=":", label=f"split of the record ({split_s:.1f} s after t0)")
        ax.axhline(100 * threshold, color="k", lw=0.9, ls="--", label=f"threshold {100 * threshold:g} cm")
        other = "second" if half == "first" else "first"
        ax.set(xlabel="time since the start t - t0 [s]",
               title=f"losses fitted to the {half} half of the energy record,\npredicting the {other} half's motion")
        ax.grid(alpha=0.3, which="both")
        plain_log_numbers(ax)
    axes[0, 0].set_ylabel(f"position error of the lower bob [cm]\n(moving median over {smoothing_s:g} s)")
    legend_below(fig, *axes[0, 0].get_legend_handles_labels(), ncols=3, fontsize=8)
    return save(fig, path)


def plot_horizon_budget(rows: Sequence[Mapping[str, object]], distribution: Mapping[str, object], base_s: float,
                        span_s: float, path: str | Path, *, title: str = "") -> Path:  # fmt: skip
    """What moves the prediction horizon: a bar per input (``rows``: ``input``, ``low``/``high`` and ``kind`` as
    text, ``low_s``/``high_s`` the horizons [s] at the input's two values), from the main run's horizon ``base_s``
    [s], largest first; behind them the horizon's distribution over every input (``distribution``: ``median_s``,
    ``range_16_84_s``, ``range_2_97_s``) and the end of the record ``span_s`` [s], where horizons are censored."""
    n = len(rows)
    fig, ax = plt.subplots(figsize=(11, 1.6 + 0.62 * n), layout="constrained")
    lo2, hi2 = distribution["range_2_97_s"]
    lo, hi = distribution["range_16_84_s"]
    ax.axvspan(lo2, hi2, color="0.88", lw=0, label=f"every input drawn: 2.5-97.5 % ({lo2:.1f} to {hi2:.1f} s)")
    ax.axvspan(lo, hi, color="0.72", lw=0, label=f"every input drawn: 16-84 % ({lo:.1f} to {hi:.1f} s), "
               f"{distribution['n']} runs")
    ax.axvline(distribution["median_s"], color="0.35", lw=1.2, ls="-.",
               label=f"their median ({distribution['median_s']:.1f} s)")
    for i, r in enumerate(rows):
        for key, colour, dy in (("low", "tab:blue", 0.19), ("high", "tab:red", -0.19)):
            y, end = n - 1 - i + dy, float(r[f"{key}_s"])
            ax.barh(y, end - base_s, left=base_s, height=0.34, color=colour, alpha=0.8,
                    label=("the input's low value" if key == "low" else "the input's high value") if i == 0 else None)
            right = end >= base_s
            ax.text(end + (0.15 if right else -0.15), y, f"{r[key]}: "
                    + ("beyond the record" if end >= span_s else f"{end:.1f} s"), va="center",
                    ha="left" if right else "right", fontsize=8)  # fmt: skip
    ax.axvline(base_s, color="k", lw=1.2, label=f"the main run ({base_s:.1f} s)")
    ax.axvline(span_s, color="k", lw=0.9, ls="--",
               label=f"end of the record ({span_s:.1f} s): a horizon here is censored")
    ax.set_yticks(range(n)[::-1], [f"{r['input']}\n({r['kind']})" for r in rows], fontsize=8)
    ax.set_xlim(0, span_s * 1.25)
    ax.set_xlabel("horizon: lower bob within 5 cm of the track, smoothed [s after t0]")
    ax.set_title(title or "what moves the prediction horizon: bars, each input at two values with the others held;"
                          "\ngrey, the horizons with every input drawn at once")
    ax.grid(alpha=0.3, axis="x")
    legend_below(fig, *ax.get_legend_handles_labels(), ncols=3, fontsize=8)
    return save(fig, path)
