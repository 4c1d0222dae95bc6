"""Solver comparisons: error against CPU time."""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt

from .style import legend_outside, save


def plot_work_precision(rows: list[dict], path: str | Path, *, title: str = "") -> Path:
    """Max error over the horizon against CPU time [s], log-log, one line per method (ok runs only).

    The error is max over t and over the states (phi1, phi2 [rad], omega1, omega2 [rad/s]) of |x - x_ref|,
    numerically mixing angles and angular velocities; the label says so.
    """
    fig, ax = plt.subplots(figsize=(8, 6))
    for solver in sorted({r["solver"] for r in rows}):
        pts = sorted((r["cpu_time_s"], r["max_error"]) for r in rows if r["solver"] == solver and r["status"] == "ok")
        if pts:
            ax.loglog(*zip(*pts), "o-", label=solver)
        failed = [r for r in rows if r["solver"] == solver and r["status"] != "ok"]
        if failed:
            ax.plot([], [], "x", label=f"{solver}: {len(failed)} failed/unstable")
    ax.set(xlabel="CPU time per run [s]",
           ylabel="max state error over the horizon\n(largest of the angle [rad] and rate [rad/s] errors)",
           title=f"error against CPU time: {title}" if title else "error against CPU time")
    legend_outside(ax)
    ax.grid(alpha=0.3, which="both")
    return save(fig, path)
