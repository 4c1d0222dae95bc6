"""Matplotlib figures for scenario results (PNG files, headless), one module a topic."""

from .animation import Swing, animate_swings, swing
from .chaos import (
    plot_ensemble_clouds,
    plot_ensemble_spread,
    plot_flip_map,
    plot_lower_mass_traces,
    plot_lyapunov_convergence,
    plot_lyapunov_spectrum,
    plot_lyapunov_vs_energy,
    plot_lyapunov_with_friction,
    plot_poincare_sections,
    plot_predictability,
)
from .decay import plot_circle_fit, plot_energy_decay
from .losses import plot_energy_fit, plot_loss_shares, plot_out_of_sample, plot_profiles
from .prediction import (
    animate_prediction,
    plot_horizon_budget,
    plot_lower_bob_paths,
    plot_out_of_sample_motion,
    plot_prediction_errors,
    plot_track_comparison,
    run_colours,
)
from .solvers import plot_work_precision
from .suspension import plot_decay_rate_cuts, plot_decay_rate_map, plot_energy_flow, plot_force_spectrum
from .trajectories import (
    plot_angles,
    plot_energy,
    plot_energy_budget_stacked,
    plot_energy_per_mechanism,
    plot_phase_portraits,
    plot_residuals,
    plot_traces,
)

__all__ = [
    "plot_angles",
    "plot_traces",
    "plot_energy",
    "plot_phase_portraits",
    "plot_residuals",
    "plot_energy_per_mechanism",
    "plot_energy_budget_stacked",
    "plot_energy_decay",
    "plot_circle_fit",
    "plot_decay_rate_map",
    "plot_decay_rate_cuts",
    "plot_force_spectrum",
    "plot_energy_flow",
    "plot_lower_mass_traces",
    "plot_ensemble_clouds",
    "plot_ensemble_spread",
    "plot_predictability",
    "plot_lyapunov_convergence",
    "plot_lyapunov_vs_energy",
    "plot_lyapunov_spectrum",
    "plot_flip_map",
    "plot_poincare_sections",
    "plot_lyapunov_with_friction",
    "plot_work_precision",
    "plot_track_comparison",
    "plot_prediction_errors",
    "plot_horizon_budget",
    "run_colours",
    "plot_lower_bob_paths",
    "Swing",
    "animate_swings",
    "animate_prediction",
    "swing",
    "plot_energy_fit",
    "plot_loss_shares",
    "plot_out_of_sample",
    "plot_out_of_sample_motion",
    "plot_profiles",
]
