"""Figures of the loss identification: measured against simulated energy, loss shares, profiles."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import matplotlib.pyplot as plt
import numpy as np

from .style import legend_below, running_mean, save


def plot_energy_fit(
    t: np.ndarray, e_measured: np.ndarray, sigma: np.ndarray, e_sim: np.ndarray, model: str, path: str | Path,
    whose: str = "the seed's pendulum", swing_frames: int = 39,
) -> Path:
    """Measured energy [J] with errors and a model's simulated energy over time [s] (``model``: its label in words,
    ``whose``: the record's in words); below, the residual E_measured - E_simulated [mJ] per frame and its running
    mean over one swing (``swing_frames``: 39 at the seed's 29.97 fps)."""
    fig, (ax, ax_r) = plt.subplots(2, 1, figsize=(10, 6.5), sharex=True, height_ratios=(2, 1))
    ax.errorbar(t, e_measured, yerr=sigma, fmt=".", ms=2, lw=0.4, alpha=0.5, color="C0", label="measured (camera)")
    ax.plot(t, e_sim, color="C3", lw=1.6, label=f"simulated: {model}")
    ax.set(ylabel="pendulum energy E [J]", title=f"Energy of {whose}: measured and simulated (FMU)")
    ax.grid(alpha=0.3)
    d = (e_measured - e_sim) * 1e3
    ax_r.plot(t, d, ".", ms=2, color="C0", alpha=0.5, label="measured - simulated, per frame")
    ax_r.plot(t, running_mean(d, swing_frames), color="k", lw=1.2, label="its running mean over about one swing")
    ax_r.axhline(0.0, color="C3", lw=0.8)
    ax_r.set(xlabel="time after the start of the track t [s]", ylabel="measured - simulated [mJ]",
             title="Residuals: measured minus simulated energy")  # fmt: skip
    ax_r.grid(alpha=0.3)
    handles, labels = ax.get_legend_handles_labels()
    more = ax_r.get_legend_handles_labels()
    legend_below(fig, [*handles, *more[0]], [*labels, *more[1]], ncols=2)
    return save(fig, path)


def plot_loss_shares(rows: list[Mapping[str, Any]], path: str | Path, *, supported_daic: float = 2.0) -> Path:
    """Each model's shares of the dissipated work as stacked horizontal bars, the lowest AIC on top, each model
    named in words (``model_in_words``) with its dAIC; a dashed line under the models within ``supported_daic`` of
    the lowest (the record does not rank them). A model whose optimum is its nested limit (``delta_aic_at_best``)
    has no bar, only what it reaches at best; one that did not converge otherwise is marked "not ranked"."""
    labels = sorted({name for r in rows if "delta_aic_at_best" not in r for name in r["shares"]})
    fig, ax = plt.subplots(figsize=(10, 0.55 * len(rows) + 2.0))
    y = np.arange(len(rows))[::-1]
    left = np.zeros(len(rows))
    bars = [r if "delta_aic_at_best" not in r else {**r, "shares": {}} for r in rows]
    for k, label in enumerate(labels):
        vals = np.array([r["shares"].get(label, 0.0) for r in bars])
        ax.barh(y, vals, left=left, color=f"C{k}", label=label)
        for yi, li, v in zip(y, left, vals):
            if v > 0.06:
                ax.text(li + v / 2, yi, f"{v:.0%}", ha="center", va="center", fontsize=8, color="white")
        left += vals
    for yi, r in zip(y, rows):
        if "delta_aic_at_best" in r:
            ax.text(0.01, yi, f"no finite fit: at best as good as {r['best_is_limit_model_in_words']}",
                    ha="left", va="center", fontsize=8, color="0.25")

    def tick(r: Mapping[str, Any]) -> str:
        name = r.get("model_in_words", r["model"])
        if "delta_aic_at_best" in r:
            return f"{name}  (dAIC at best {r['delta_aic_at_best']:.0f})"
        if not r.get("converged", True):
            return f"{name}  (not ranked)"
        return f"{name}  (dAIC {r['delta_aic']:.1f})"

    ax.set_yticks(y, [tick(r) for r in rows])
    tied = sum(1 for r in rows if r.get("converged", True) and r["delta_aic"] < supported_daic)
    if 0 < tied < len(rows):
        ax.axhline(y[tied - 1] - 0.5, color="k", ls="--", lw=0.9)
    ax.set(xlim=(0, 1), xlabel="share of the energy dissipated over the record [1]",
           title=f"Share of each loss in each fitted model (lowest AIC on top; the {tied} above the dashed line\n"
                 f"lie within dAIC {supported_daic:g} of it: the record does not rank them)" if tied > 1 else
                 f"Share of each loss in each fitted model (lowest AIC on top;\n"
                 f"the others, below the dashed line, dAIC {supported_daic:g} or more behind it)")  # fmt: skip
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


def plot_out_of_sample(oos: Mapping[str, Any], titles: Mapping[str, str], path: str | Path) -> Path:
    """The out-of-sample test (``summary["out_of_sample"]``): per model (named by ``titles``, the best predictor
    over both directions on top) and direction, left the held-out half's chi2 per frame with the AR(1) noise model
    (bars) and without it (open circles); right the held-out mean residual simulated - measured [mJ] with its
    AR(1) standard error."""
    models = oos["both_directions"]["order"]
    dirs = list(oos["directions"].items())
    fig, (ax, ax_m) = plt.subplots(1, 2, figsize=(15, 0.6 * len(models) + 2.4), sharey=True, layout="constrained")
    y = np.arange(len(models))[::-1]
    h = 0.38
    for j, (name, d) in enumerate(dirs):
        s = [d["scores"][m] for m in models]
        yy = y + (0.5 - j) * h
        words = name.replace("_predicts_", " half fitted, predicting the ") + " half"
        ax.barh(yy, [x["ar1_chi2_per_frame"] for x in s], height=h, color=f"C{j}", label=f"{words}: AR(1)")
        ax.plot([x["chi2_per_frame"] for x in s], yy, "o", mfc="none", color="k", ms=5,
                label="plain chi2 per frame (no noise model)" if j == 0 else None)
        ax_m.errorbar([1e3 * x["mean_residual_J"] for x in s], yy, xerr=[1e3 * x["mean_residual_stderr_J"] for x in s],
                      fmt="o", color=f"C{j}", capsize=3, label=words)  # fmt: skip
    ax.axvline(1.0, color="0.4", lw=0.8, ls="--")
    ax_m.axvline(0.0, color="0.4", lw=0.8, ls="--")
    ax.set_yticks(y, [titles.get(m, m) for m in models])
    ax.set(xlabel="held-out chi2 per frame [1]\n(1: as good as the frames' errors)",
           title="Each loss model fitted to one half:\nhow well it predicts the other half's energy")  # fmt: skip
    ax_m.set(xlabel="held-out mean residual [mJ]\n(simulated - measured energy)",
             title="Bias on the held-out half\n(error bars: one standard error, AR(1) noise)")
    for a in (ax, ax_m):
        a.grid(alpha=0.3, axis="x")
    handles, labels = ax.get_legend_handles_labels()
    legend_below(fig, handles, labels, ncols=2, fontsize=8)
    return save(fig, path)
