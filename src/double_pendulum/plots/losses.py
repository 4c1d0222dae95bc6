"""Figures of the loss identification: measured against simulated energy, loss shares, profiles."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import matplotlib.pyplot as plt
import numpy as np

from .style import running_mean, save


def plot_energy_fit(
    t: np.ndarray, e_measured: np.ndarray, sigma: np.ndarray, e_sim: np.ndarray, model: str, path: str | Path
) -> Path:
    """Measured energy [J] with errors and the best model's simulated energy over time [s]; below, the
    residual E_measured - E_simulated [mJ] per frame and its running mean over one swing (39 frames)."""
    fig, (ax, ax_r) = plt.subplots(2, 1, figsize=(10, 6.5), sharex=True, height_ratios=(2, 1))
    ax.errorbar(t, e_measured, yerr=sigma, fmt=".", ms=2, lw=0.4, alpha=0.5, color="C0", label="measured (camera)")
    ax.plot(t, e_sim, color="C3", lw=1.6, label=f"simulated, best model: {model}")
    ax.set(ylabel="pendulum energy E [J]", title="Energy of the seed's pendulum: measured and simulated (FMU)")
    ax.legend(loc="upper right", fontsize=9)
    ax.grid(alpha=0.3)
    d = (e_measured - e_sim) * 1e3
    ax_r.plot(t, d, ".", ms=2, color="C0", alpha=0.5, label="per frame")
    ax_r.plot(t, running_mean(d, 39), color="k", lw=1.2, label="running mean over one swing (1.3 s)")
    ax_r.axhline(0.0, color="C3", lw=0.8)
    ax_r.set(xlabel="time after the start of the track t [s]", ylabel="measured - simulated [mJ]",
             title="Residuals")  # fmt: skip
    ax_r.legend(loc="lower right", fontsize=8, ncol=2)
    ax_r.grid(alpha=0.3)
    return save(fig, path)


def plot_loss_shares(rows: list[Mapping[str, Any]], path: str | Path) -> Path:
    """Each model's shares of the dissipated work as stacked horizontal bars (best model on top), with dAIC
    (and "not ranked" where its fit ended above a model nested in it)."""
    labels = sorted({name for r in rows for name in r["shares"]})
    fig, ax = plt.subplots(figsize=(10, 0.55 * len(rows) + 1.8))
    y = np.arange(len(rows))[::-1]
    left = np.zeros(len(rows))
    for k, label in enumerate(labels):
        vals = np.array([r["shares"].get(label, 0.0) for r in rows])
        ax.barh(y, vals, left=left, color=f"C{k}", label=label)
        for yi, li, v in zip(y, left, vals):
            if v > 0.06:
                ax.text(li + v / 2, yi, f"{v:.0%}", ha="center", va="center", fontsize=8, color="white")
        left += vals
    ax.set_yticks(y, [f"{r['model']}  (dAIC {r['delta_aic']:.0f}{'' if r.get('converged', True) else ', not ranked'})"
                      for r in rows])
    ax.set(xlim=(0, 1), xlabel="share of the energy dissipated over the record [1]",
           title="Loss shares per model (best model on top)")  # fmt: skip
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.1 - 0.6 / len(rows)), ncol=3, fontsize=8)
    return save(fig, path)


def plot_profiles(profile: Mapping[str, Mapping[str, Any]], labels: Mapping[str, str], path: str | Path) -> Path:
    """Profile likelihood delta chi2 / F against each parameter of the best model, the others re-fitted
    (1: one standard error); ``labels`` maps a parameter to its axis label in words with the unit."""
    names = list(profile)
    fig, axes = plt.subplots(1, len(names), figsize=(5.5 * len(names), 4.2), squeeze=False)
    for ax, name in zip(axes[0], names):
        p = profile[name]
        ax.plot(p["values"], p["delta_chi2_over_F"], "o-", color="C0", label="others re-fitted")
        ax.axhline(1.0, color="k", lw=0.8, ls="--", label="one standard error")
        ax.set(xlabel=labels.get(name, name), ylabel="rise of chi2 / F [1]", title=f"Profile likelihood: {name}")
        ax.legend(loc="upper center", fontsize=8)
        ax.grid(alpha=0.3)
    return save(fig, path)
