"""Figures of the ``cosimulation`` scenario: coupling error, cost, energy, stability map."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import matplotlib.pyplot as plt
import numpy as np

from .style import legend_below, plain_log_numbers, save

MARKERS = {"jacobi": "o", "jacobi_sequential": "v", "extrapolation": "s", "iterative": "^", "libcosim": "x",
           "container": "+"}


def _cases(rows: list[dict[str, Any]]) -> list[tuple[str, str]]:
    return sorted({(r["start"], r["suspension"]) for r in rows})


def plot_against(rows: list[dict[str, Any]], x: str, y: str, path: str | Path, *, xlabel: str, ylabel: str,
                 title: str) -> Path:
    """One panel per case: ``y`` over ``x`` (log-log) for every method, stable runs only; every panel labels both
    axes (their ranges differ), one legend under the panels."""
    cases = _cases(rows)
    ncols = min(2, len(cases))
    nrows = (len(cases) + ncols - 1) // ncols
    fig, axes = plt.subplots(nrows, ncols, figsize=(5.0 * ncols + 2.0, 3.8 * nrows + 0.6), squeeze=False)
    axes = [list(axes.flat)]
    for ax, case in zip(axes[0], cases):
        for method, marker in MARKERS.items():
            sel = sorted((r[x], abs(r[y])) for r in rows if (r["start"], r["suspension"]) == case
                         and r["method"] == method and r["stable"] and abs(r[y]) > 0)
            if sel:
                ax.loglog(*zip(*sel), marker=marker, label=method)
        ax.set_title(f"{case[0]} start, {case[1]} suspension", fontsize=9)
        ax.set_xlabel(xlabel)
        ax.grid(True, which="both", alpha=0.3)
        ax.set_ylabel(ylabel)
    handles: dict[str, Any] = {}
    for ax in axes[0]:
        for handle, label in zip(*ax.get_legend_handles_labels()):
            handles.setdefault(label, handle)
    legend_below(fig, list(handles.values()), list(handles), ncols=len(handles))
    fig.suptitle(title, fontsize=11)
    return save(fig, path)


def plot_stability_map(points: list[dict[str, Any]], curves: dict[str, tuple[np.ndarray, np.ndarray]],
                       path: str | Path) -> Path:
    """Per scheme: stable (dots) and unstable (crosses) runs over h omega and mass ratio, judged by the spectral
    radius of the step map fitted to each run, with the derived limit."""
    fig, axes = plt.subplots(1, len(curves), figsize=(5.0 * len(curves) + 1.5, 4.5), squeeze=False, sharey=True)
    for ax, (scheme, curve) in zip(axes[0], curves.items()):
        for stable, marker, color, label in ((True, "o", "tab:green", "stable, fitted growth per step <= 1"),
                                                   (False, "x", "tab:red", "unstable, fitted growth per step > 1")):
            sel = [(p["h_omega"], p["mass_ratio"]) for p in points if p["stable"] == stable and p["scheme"] == scheme]
            if sel:
                ax.scatter(*zip(*sel), marker=marker, color=color, label=f"run: {label}")
        ax.plot(*curve, color="k", label="derived limit (rigid vertical load)")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("macro step times suspension frequency, h omega [1]")
        ax.set_title(f"{scheme} (zero-order hold)", fontsize=10)
        ax.grid(True, which="both", alpha=0.3)
    axes[0][0].set_ylabel("mass ratio (m1 + m2) / M_s [1]")
    for ax in axes[0]:
        plain_log_numbers(ax, "x")
        plain_log_numbers(ax, "y")
    legend_below(fig, *axes[0][-1].get_legend_handles_labels(), ncols=3)
    fig.suptitle("Added-mass stability of explicit coupling (damping ratio 0.05)")
    return save(fig, path)
