"""The figure of a case of one's own (``double-pendulum simulate``): angles, energies, the energy budget and
the lower bob's path, from the CSV file the command wrote."""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from .style import legend_outside, save

DISSIPATED = {"W_air": "air drag", "W_bearing": "bearing friction", "W_bearing_drag": "bearing drag torque",
              "W_suspension": "suspension damper"}
"""The FMU's dissipated works, in words."""


def plot_case(result: np.ndarray, path: str | Path, *, title: str) -> Path:
    """Four panels of one run of the FMU (``result``: its outputs, as read back from its CSV file): the rod angles
    [rad] over time, the energies [J] (stored, and each mechanism's dissipated work that is not zero), the energy
    budget's residual [J] (E_total + dissipated - fed in - E_total(0), the FMU's ``energy_residual``: zero up to
    the integration error) and the lower bob's path in the x-y plane [m]; ``title`` above them."""
    t = result["time"]
    fig, axes = plt.subplots(2, 2, figsize=(14, 9.5), layout="constrained")
    (ax_angles, ax_energy), (ax_budget, ax_path) = axes
    ax_angles.plot(t, result["phi1"], label="phi1 (upper rod)")
    ax_angles.plot(t, result["phi2"], label="phi2 (lower rod)")
    ax_angles.set(title="rod angles from the downward vertical (unwrapped: a full turn adds 2 pi)",
                  xlabel="time t [s]", ylabel="angle [rad]")
    legend_outside(ax_angles)
    ax_energy.plot(t, result["E_total"], color="k", label="total (E_total)")
    ax_energy.plot(t, result["E_kin"], lw=0.8, label="kinetic (E_kin)")
    ax_energy.plot(t, result["E_pot"], lw=0.8, label="potential (E_pot)")
    for name, words in DISSIPATED.items():
        if name in result.dtype.names and np.any(result[name] != 0.0):
            ax_energy.plot(t, result[name], ls="--", label=f"dissipated by {words} ({name})")
    if "W_input" in result.dtype.names and np.any(result["W_input"] != 0.0):
        ax_energy.plot(t, result["W_input"], ls=":", label="fed in through the inputs (W_input)")
    ax_energy.set(title="energies: stored in the pendulum and dissipated so far", xlabel="time t [s]",
                  ylabel="energy [J]")
    legend_outside(ax_energy)
    ax_budget.plot(t, result["energy_residual"], color="C3")
    ax_budget.set(title="energy budget: E_total + dissipated - fed in - E_total(0)", xlabel="time t [s]",
                  ylabel="residual [J] (zero but for the integration error)")
    ax_budget.ticklabel_format(axis="y", style="sci", scilimits=(-3, 3))
    ax_path.plot(result["x2"], result["y2"], lw=0.6, label="lower bob")
    ax_path.plot(result["x1"], result["y1"], lw=0.8, alpha=0.7, label="upper bob")
    ax_path.plot([0.0], [0.0], "k+", ms=10, label="pivot")
    ax_path.set(title="paths of the bobs in the x-y plane", xlabel="horizontal position x [m]",
                ylabel="vertical position y [m] (up)", aspect="equal")
    legend_outside(ax_path)
    for ax in axes.flat:
        ax.grid(alpha=0.3)
    fig.suptitle(title)
    return save(fig, path)
