"""The measured track against the simulation: coordinates and prediction errors."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from .style import legend_below, legend_outside, save


def plot_track_comparison(
    t: np.ndarray,
    measured: Mapping[str, np.ndarray],
    runs: Mapping[str, tuple[np.ndarray, Mapping[str, np.ndarray]]],
    path: str | Path,
    *,
    starts: Mapping[str, float] | None = None,
) -> Path:
    """Measured coordinates (dots) and simulated ones (lines) over time [s], one panel per coordinate [m]
    (the seed's figs. 11-14); ``starts`` marks start times [s] by label. One legend under the panels."""
    names = list(measured)
    fig, axes = plt.subplots(len(names), 1, figsize=(11, 2.6 * len(names)), sharex=True, squeeze=False)
    for ax, name in zip(axes[:, 0], names):
        ax.plot(t, measured[name], ".", color="k", ms=3, label="measured track")
        for label, (ts, coords) in runs.items():
            ax.plot(ts, coords[name], lw=1.2, label=f"simulated: {label}")
        for label, t0 in (starts or {}).items():
            ax.axvline(t0, color="0.5", ls=":", lw=0.8, label=label)
        bob = {"1": "upper", "2": "lower"}.get(name[-1:])
        ax.set(ylabel=f"{bob} bob {name} [m]" if bob else f"{name} [m]")
        ax.grid(alpha=0.3)
    axes[0, 0].set_title("bob coordinates: measured track and FMU predictions from the same start time")
    axes[-1, 0].set_xlabel("t [s]")
    legend_below(fig, *axes[0, 0].get_legend_handles_labels(), ncols=2)
    return save(fig, path)


def plot_prediction_errors(
    curves: Mapping[str, tuple[np.ndarray, np.ndarray]],
    thresholds: tuple[float, ...] | list[float],
    path: str | Path,
    *,
    floor: tuple[np.ndarray, np.ndarray] | None = None,
    title: str = "distance between the simulated and the measured bob position",
) -> Path:
    """Position error [m] over time since the start [s], log scale, with horizontal ``thresholds`` [m];
    ``floor`` (t, error) is drawn grey (e.g. the track's own deviation from a rigid rod)."""
    fig, ax = plt.subplots(figsize=(11, 5.5))
    for label, (t, err) in curves.items():
        ax.semilogy(t, np.maximum(err, 1e-5), lw=1.1, label=label)
    if floor is not None:
        label = "track: | |r2 - r1| - l2 | (rod-length error)"
        ax.semilogy(floor[0], np.maximum(floor[1], 1e-5), ".", color="0.6", ms=2, label=label)
    for th, ls in zip(thresholds, ("--", "-.", ":")):
        ax.axhline(th, color="k", ls=ls, lw=0.9, label=f"{100 * th:g} cm")
    ax.set(xlabel="time since the start t - t0 [s]", ylabel="position error [m]", title=title)
    legend_outside(ax)
    ax.grid(alpha=0.3, which="both")
    return save(fig, path)
