"""Solver comparisons: error against CPU time."""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
from matplotlib import ticker

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
    # CPU times span one to four decades: label 1, 2, 5 of each decade in plain numbers (matplotlib's default
    # labels the minor ticks of a narrow range as "3x10^-1 4x10^-1 ...", which run into each other)
    ax.xaxis.set_major_locator(ticker.LogLocator(subs=(1.0, 2.0, 5.0)))
    ax.xaxis.set_major_formatter(ticker.FuncFormatter(lambda v, _: f"{v:g}"))
    ax.xaxis.set_minor_formatter(ticker.NullFormatter())
    legend_outside(ax)
    ax.grid(alpha=0.3, which="both")
    return save(fig, path)
