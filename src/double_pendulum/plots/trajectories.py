"""Time series of single runs: angles, bob traces, energies, phase portraits, budgets."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from .style import legend_below, legend_outside, plain_log_numbers, save


def plot_angles(runs: Mapping[str, np.ndarray], path: str | Path) -> Path:
    """Angles phi1, phi2 [rad] over time, one panel per run; unwrapped (a rod that turns over keeps counting)."""
    fig, axes = plt.subplots(len(runs), 1, figsize=(9, 3 * len(runs)), squeeze=False)
    for ax, (label, r) in zip(axes[:, 0], runs.items()):
        ax.plot(r["time"], r["phi1"], label="phi1 (upper rod)")
        ax.plot(r["time"], r["phi2"], label="phi2 (lower rod)")
        ax.set(title=f"{label}: rod angles from the vertical, unwrapped (each full turn adds 2 pi)",
               xlabel="time t [s]", ylabel="angle, unwrapped [rad]")
        legend_outside(ax)
        ax.grid(alpha=0.3)
    return save(fig, path)


def plot_traces(runs: Mapping[str, np.ndarray], path: str | Path) -> Path:
    """Paths of both bobs in the x-y plane (like the seed's long-exposure photographs)."""
    fig, axes = plt.subplots(1, len(runs), figsize=(5 * len(runs), 5), squeeze=False)
    for ax, (label, r) in zip(axes[0], runs.items()):
        ax.plot(r["x2"], r["y2"], lw=0.6, label="lower bob")
        ax.plot(r["x1"], r["y1"], lw=0.8, label="upper bob")
        ax.plot([0], [0], "k+", ms=10, label="pivot")
        ax.set(title=f"{label}: paths of the bobs", xlabel="x [m]", ylabel="y [m]", aspect="equal")
        ax.grid(alpha=0.3)
    legend_below(fig, *axes[0, 0].get_legend_handles_labels())
    return save(fig, path)


def plot_energy(runs: Mapping[str, np.ndarray], path: str | Path) -> Path:
    """Energies [J] over time and the relative drift of the total energy."""
    fig, axes = plt.subplots(len(runs), 2, figsize=(12, 3 * len(runs)), squeeze=False)
    for (ax_e, ax_d), (label, r) in zip(axes, runs.items()):
        for name, word in (("E_kin", "kinetic"), ("E_pot", "potential"), ("E_total", "total")):
            ax_e.plot(r["time"], r[name], label=f"{word} ({name})")
        ax_e.set(title=f"{label}: energies", xlabel="t [s]", ylabel="energy [J]")
        legend_outside(ax_e)
        ax_e.grid(alpha=0.3)
        e0 = r["E_total"][0]
        ax_d.plot(r["time"], (r["E_total"] - e0) / abs(e0))
        ax_d.set(title=f"{label}: drift of the total energy", xlabel="t [s]",
                 ylabel="relative drift (E_total - E0) / E0 [-]")
        ax_d.grid(alpha=0.3)
    return save(fig, path)


def plot_phase_portraits(runs: Mapping[str, np.ndarray], path: str | Path) -> Path:
    """Phase portraits omega over phi for both rods (the seed's figs. 15/16)."""
    fig, axes = plt.subplots(len(runs), 2, figsize=(11, 4 * len(runs)), squeeze=False)
    for (ax1, ax2), (label, r) in zip(axes, runs.items()):
        for ax, k in ((ax1, "1"), (ax2, "2")):
            phi = np.angle(np.exp(1j * r[f"phi{k}"]))  # wrapped to (-pi, pi]
            ax.plot(phi, r[f"omega{k}"], ",", alpha=0.6)
            ax.set(title=f"{label}: phase portrait of rod {k}", xlabel=f"angle phi{k} [rad] (wrapped)",
                   ylabel=f"angular velocity omega{k} [rad/s]")
            ax.grid(alpha=0.3)
    return save(fig, path)


def plot_residuals(runs: Mapping[str, np.ndarray], path: str | Path) -> Path:
    """|energy_residual| / E_total(0) over time [s], log scale, one panel per run (each on its own time axis:
    the runs last from a fraction of a second to 1000 s), on one shared residual axis.

    The axis spans the nonzero values only; samples that are exactly zero (no residual to display on a
    log scale) are marked on the bottom edge, so a zero does not stretch the axis over empty decades.
    """
    fig, axes = plt.subplots(len(runs), 1, figsize=(10, 1.0 + 2.0 * len(runs)), sharey=True, squeeze=False,
                             layout="constrained")  # fmt: skip
    nonzero, marked = [], False
    for ax, (label, r) in zip(axes[:, 0], runs.items()):
        e0 = abs(r["E_total"][0]) or 1.0
        rel = np.abs(np.asarray(r["energy_residual"], dtype=float)) / e0
        zero = rel == 0.0
        ax.semilogy(r["time"], np.where(zero, np.nan, rel), color="C0")
        nonzero.append(rel[np.isfinite(rel) & ~zero])
        zeros = np.asarray(r["time"])[zero]
        if zeros.size:
            ax.plot(zeros, np.zeros(zeros.size), "|", color="k", ms=10, mew=1.5, transform=ax.get_xaxis_transform(),
                    clip_on=False, label=None if marked else "residual exactly 0 (off the log scale)")
            marked = True
        ax.set_xlabel("time t [s]")
        ax.set_title(f"case: {label}", loc="left", fontsize=10)
        ax.grid(alpha=0.3, which="both")
    values = np.concatenate(nonzero) if nonzero else np.empty(0)
    if values.size:
        axes[0, 0].set_ylim(values.min() / 2.0, values.max() * 2.0)
    fig.supylabel("relative energy residual |energy_residual| / E_total(0) [1]")
    fig.suptitle(f"Energy balance error of the {len(runs)} worst passing cases", fontsize=13)
    fig.get_layout_engine().set(h_pad=0.12)  # room between the figure's title and the first case's
    if marked:
        legend_outside(next(ax for ax in axes[:, 0] if ax.get_legend_handles_labels()[0]))
    return save(fig, path)


def plot_energy_per_mechanism(runs: Mapping[str, np.ndarray], path: str | Path, *, note: str = "") -> Path:
    """E_total [J] over time [s] for each run, log scale (straight lines mean exponential decay), numbered in plain
    decimals; ``note`` (e.g. which coefficients) goes under the title."""
    fig, ax = plt.subplots(figsize=(9, 5))
    for label, r in runs.items():
        ax.semilogy(r["time"], r["E_total"], label=label.replace("_", " "))
    title = "energy of the pendulum and its suspension: each loss mechanism alone, and all together"
    ax.set(xlabel="time t [s]", ylabel="total energy E_total [J] (log scale)",
           title=title + (f"\n{note}" if note else ""))  # fmt: skip
    plain_log_numbers(ax, "y")
    legend_outside(ax)
    ax.grid(alpha=0.3, which="both")
    return save(fig, path)


STACK_VISIBLE = 0.005
"""A band of the stacked budget narrower than this fraction of E_total(0) all the time is left out (and named in
the figure as negligible)."""


def plot_energy_budget_stacked(result: np.ndarray, path: str | Path, *, note: str = "") -> Path:
    """Where the energy went [J] over time [s]: the energy stored in the pendulum and its suspension (one band: they
    exchange energy at the suspension's frequency, faster than the output grid resolves, which drew a sawtooth
    between two bands) and each mechanism's dissipated work W_* stacked on it, adding up to E_total(0). Bands that
    stay below :data:`STACK_VISIBLE` of E_total(0) are not drawn and are named in the title's last line; ``note``
    (e.g. which coefficients) goes under the title."""
    words = {"W_air": "dissipated by air drag", "W_bearing": "dissipated in the bearings",
             "W_bearing_drag": "dissipated by the bearing drag torque",
             "W_suspension": "dissipated in the suspension's damper"}
    fields = result.dtype.names or ()
    e0 = float(result["E_total"][0])
    stored = np.asarray(result["E_pendulum"]) + (np.asarray(result["E_suspension"]) if "E_suspension" in fields else 0)
    bands = {"stored in the pendulum and its suspension (E_pendulum + E_suspension)": stored}
    small = []
    for name, word in words.items():
        if name not in fields:
            continue
        if float(np.max(np.abs(result[name]))) < STACK_VISIBLE * e0:
            small.append(name)
        else:
            bands[f"{word} ({name})"] = np.asarray(result[name])
    fig, ax = plt.subplots(figsize=(10, 5))
    ax.stackplot(result["time"], *bands.values(), labels=list(bands), alpha=0.85)
    ax.axhline(e0, color="k", lw=0.8, ls="--", label="E_total(0), the start energy")
    lines = ["where the energy went: stored and dissipated, all mechanisms on"]
    if note:
        lines.append(note)
    if small:
        lines.append(f"not drawn (below {STACK_VISIBLE:.1%} of the start energy): " + ", ".join(small))
    ax.set(xlabel="time t [s]", ylabel="energy [J]", title="\n".join(lines))
    ax.set_ylim(0.0, 1.08 * e0)
    legend_below(fig, *ax.get_legend_handles_labels(), ncols=2)
    ax.grid(alpha=0.3)
    return save(fig, path)
