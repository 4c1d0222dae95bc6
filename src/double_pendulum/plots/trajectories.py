"""Time series of single runs: angles, bob traces, energies, phase portraits, budgets."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from .style import save


def plot_angles(runs: Mapping[str, np.ndarray], path: str | Path) -> Path:
    """Angles phi1, phi2 [rad] over time, one panel per run."""
    fig, axes = plt.subplots(len(runs), 1, figsize=(9, 3 * len(runs)), squeeze=False)
    for ax, (label, r) in zip(axes[:, 0], runs.items()):
        ax.plot(r["time"], r["phi1"], label="phi1")
        ax.plot(r["time"], r["phi2"], label="phi2")
        ax.set(title=label, xlabel="t [s]", ylabel="angle [rad]")
        ax.legend(loc="upper right")
        ax.grid(alpha=0.3)
    return save(fig, path)


def plot_traces(runs: Mapping[str, np.ndarray], path: str | Path) -> Path:
    """Paths of both bobs in the x-y plane (like the seed's long-exposure photographs)."""
    fig, axes = plt.subplots(1, len(runs), figsize=(5 * len(runs), 5), squeeze=False)
    for ax, (label, r) in zip(axes[0], runs.items()):
        ax.plot(r["x2"], r["y2"], lw=0.6, label="lower bob")
        ax.plot(r["x1"], r["y1"], lw=0.8, label="upper bob")
        ax.plot([0], [0], "k+", ms=10)
        ax.set(title=label, xlabel="x [m]", ylabel="y [m]", aspect="equal")
        ax.legend(loc="lower right", fontsize=8)
        ax.grid(alpha=0.3)
    return save(fig, path)


def plot_energy(runs: Mapping[str, np.ndarray], path: str | Path) -> Path:
    """Energies [J] over time and the relative drift of the total energy."""
    fig, axes = plt.subplots(len(runs), 2, figsize=(12, 3 * len(runs)), squeeze=False)
    for (ax_e, ax_d), (label, r) in zip(axes, runs.items()):
        for name in ("E_kin", "E_pot", "E_total"):
            ax_e.plot(r["time"], r[name], label=name)
        ax_e.set(title=label, xlabel="t [s]", ylabel="energy [J]")
        ax_e.legend(loc="upper right", fontsize=8)
        ax_e.grid(alpha=0.3)
        e0 = r["E_total"][0]
        ax_d.plot(r["time"], (r["E_total"] - e0) / abs(e0))
        ax_d.set(title=f"{label}: (E_total - E0) / E0", xlabel="t [s]", ylabel="relative drift")
        ax_d.grid(alpha=0.3)
    return save(fig, path)


def plot_phase_portraits(runs: Mapping[str, np.ndarray], path: str | Path) -> Path:
    """Phase portraits omega over phi for both rods (the seed's figs. 15/16)."""
    fig, axes = plt.subplots(len(runs), 2, figsize=(11, 4 * len(runs)), squeeze=False)
    for (ax1, ax2), (label, r) in zip(axes, runs.items()):
        for ax, k in ((ax1, "1"), (ax2, "2")):
            phi = np.angle(np.exp(1j * r[f"phi{k}"]))  # wrapped to (-pi, pi]
            ax.plot(phi, r[f"omega{k}"], ",", alpha=0.6)
            ax.set(title=f"{label}: rod {k}", xlabel=f"phi{k} [rad] (wrapped)", ylabel=f"omega{k} [rad/s]")
            ax.grid(alpha=0.3)
    return save(fig, path)


def plot_residuals(runs: Mapping[str, np.ndarray], path: str | Path) -> Path:
    """|energy_residual| / E_total(0) over time [s], log scale, one line per run."""
    fig, ax = plt.subplots(figsize=(9, 5))
    for label, r in runs.items():
        e0 = abs(r["E_total"][0]) or 1.0
        ax.semilogy(r["time"], np.abs(r["energy_residual"]) / e0 + 1e-18, label=label)
    ax.set(xlabel="t [s]", ylabel="|energy_residual| / E_total(0)", title="Energy residual of the worst cases")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3, which="both")
    return save(fig, path)


def plot_energy_per_mechanism(runs: Mapping[str, np.ndarray], path: str | Path) -> Path:
    """E_total [J] over time [s] for each run, log scale (straight lines mean exponential decay)."""
    fig, ax = plt.subplots(figsize=(9, 5))
    for label, r in runs.items():
        ax.semilogy(r["time"], r["E_total"], label=label)
    ax.set(xlabel="t [s]", ylabel="E_total [J]", title="Energy of the pendulum and its suspension")
    ax.legend()
    ax.grid(alpha=0.3, which="both")
    return save(fig, path)


def plot_energy_budget_stacked(result: np.ndarray, path: str | Path) -> Path:
    """Where the energy went: stacked E_pendulum, E_suspension and each W_* [J] over time [s]."""
    names = tuple(
        n
        for n in ("E_pendulum", "E_suspension", "W_air", "W_bearing", "W_bearing_drag", "W_suspension")
        if n in (result.dtype.names or ())
    )
    fig, ax = plt.subplots(figsize=(9, 5))
    ax.stackplot(result["time"], *(result[n] for n in names), labels=names, alpha=0.85)
    ax.axhline(result["E_total"][0], color="k", lw=0.8, ls="--", label="E_total(0)")
    ax.set(xlabel="t [s]", ylabel="energy [J]", title="Energy budget, all mechanisms on")
    ax.legend(loc="lower left", fontsize=8)
    ax.grid(alpha=0.3)
    return save(fig, path)
