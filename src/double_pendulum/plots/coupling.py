"""Figures of the ``cosimulation`` scenario: coupling error, cost, energy, stability map."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import matplotlib.pyplot as plt
import numpy as np

from .style import save

MARKERS = {"jacobi": "o", "extrapolation": "s", "iterative": "^", "libcosim": "x", "container": "+"}


def _cases(rows: list[dict[str, Any]]) -> list[tuple[str, str]]:
    return sorted({(r["start"], r["suspension"]) for r in rows})


def plot_against(rows: list[dict[str, Any]], x: str, y: str, path: str | Path, *, xlabel: str, ylabel: str,
                 title: str) -> Path:
    """One panel per case: ``y`` over ``x`` (log-log) for every method, stable runs only."""
    cases = _cases(rows)
    fig, axes = plt.subplots(1, len(cases), figsize=(4.5 * len(cases), 4.0), squeeze=False)
    for ax, case in zip(axes[0], cases):
        for method, marker in MARKERS.items():
            sel = sorted((r[x], abs(r[y])) for r in rows if (r["start"], r["suspension"]) == case
                         and r["method"] == method and r["stable"] and abs(r[y]) > 0)
            if sel:
                ax.loglog(*zip(*sel), marker=marker, label=method)
        ax.set_title(f"{case[0]} start, {case[1]} suspension", fontsize=9)
        ax.set_xlabel(xlabel)
        ax.grid(True, which="both", alpha=0.3)
    axes[0][0].set_ylabel(ylabel)
    axes[0][-1].legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.02, 1.0))
    fig.suptitle(title)
    return save(fig, path)


def plot_stability_map(points: list[dict[str, Any]], curve: tuple[np.ndarray, np.ndarray], path: str | Path) -> Path:
    """Bounded (dots) and blown-up (crosses) Jacobi runs over h omega and mass ratio, with the derived limit."""
    fig, ax = plt.subplots(figsize=(6.5, 4.5))
    for stable, marker, color, label in ((True, "o", "tab:green", "bounded"), (False, "x", "tab:red", "blows up")):
        sel = [(p["h_omega"], p["mass_ratio"]) for p in points if p["stable"] == stable]
        if sel:
            ax.scatter(*zip(*sel), marker=marker, color=color, label=f"measured: {label}")
    ax.plot(*curve, color="k", label="derived limit (rigid vertical load, zeta = 0.05)")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("macro step times suspension frequency h omega [1]")
    ax.set_ylabel("mass ratio (m1 + m2) / M_s [1]")
    ax.set_title("Jacobi coupling with zero-order hold: added-mass stability")
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.02, 1.0))
    return save(fig, path)
