"""The ``base_excitation`` summary's shape: what ``summary.json`` holds and :mod:`.report` reads.

TypedDicts, so the summary stays a JSON object; ``tests/test_summary_types.py`` checks the quick run's summary
against :class:`ExcitationSummary` key by key. Each key names its unit: amplitudes and lengths [m], frequencies
[rad/s], relative errors as fractions.
"""

from typing import TypedDict


class KapitzaSummary(TypedDict):
    """Kapitza's pendulum (:func:`.report.kapitza_summary`): the simulated threshold amplitude [m] against the exact
    bounds of the held input and of the continuous sinusoid and against a^2 omega^2 = 2 g l1."""

    kapitza_frequency_rad_per_s: float
    kapitza_steps_per_period: int
    kapitza_mass_ratio_m2_over_m1: float
    kapitza_rod_length_m: float
    kapitza_criterion: str
    kapitza_threshold_amplitude_m: float
    kapitza_threshold_uncertainty_m: float
    kapitza_held_exact_amplitude_m: float
    kapitza_relative_error_vs_held_exact: float
    kapitza_mathieu_exact_amplitude_m: float
    kapitza_held_over_continuous: float
    kapitza_theory_amplitude_m: float
    kapitza_relative_error: float
    kapitza_effective_length_m: float
    kapitza_single_pendulum_limit_length_error: float
    kapitza_theory_effective_length_amplitude_m: float
    kapitza_probes: int


class AchesonSummary(TypedDict):
    """Acheson's map (:func:`.report.acheson_summary`): stable points simulated and by the linear theory, where
    the stable band begins [rad/s]."""

    acheson_map_points: int
    acheson_criterion: str
    acheson_stable_points: int
    acheson_theory_stable_points: int
    acheson_agreement_fraction: float
    acheson_theory_continuous_stable_points: int
    acheson_agreement_fraction_continuous: float
    acheson_continuous_disagreements_max_relative_distance_to_bound: float
    acheson_equivalent_length_slow_mode_m: float
    acheson_equivalent_length_fast_mode_m: float
    acheson_theory_lowest_stable_frequency_rad_per_s: float
    acheson_measured_lowest_stable_frequency_rad_per_s: float
    acheson_theory_flutter_amplitude_high_frequency_m: float


class ResonanceSummary(TypedDict):
    """Resonance under a pivot torque (:func:`.report.resonance_summary`): each mode's peak for each angle
    [rad/s] against the damped linear response's, the normal modes [rad/s], the largest errors and drift."""

    resonance_drive_frequencies: int
    resonance_normal_mode_slow_rad_per_s: float
    resonance_normal_mode_fast_rad_per_s: float
    resonance_peak_slow_phi1_rad_per_s: float
    resonance_damped_linear_peak_slow_phi1_rad_per_s: float
    resonance_peak_slow_phi1_relative_error: float
    resonance_peak_slow_phi2_rad_per_s: float
    resonance_damped_linear_peak_slow_phi2_rad_per_s: float
    resonance_peak_slow_phi2_relative_error: float
    resonance_peak_fast_phi1_rad_per_s: float
    resonance_damped_linear_peak_fast_phi1_rad_per_s: float
    resonance_peak_fast_phi1_relative_error: float
    resonance_peak_fast_phi2_rad_per_s: float
    resonance_damped_linear_peak_fast_phi2_rad_per_s: float
    resonance_peak_fast_phi2_relative_error: float
    resonance_max_abs_relative_error: float
    resonance_max_abs_damping_shift: float
    resonance_max_steady_state_drift: float
    resonance_max_amplitude_rad: float


class ExcitationSummary(KapitzaSummary, AchesonSummary, ResonanceSummary):
    """``base_excitation``'s ``summary.json``: the three studies' figures side by side."""

    scenario: str
    quick: bool
