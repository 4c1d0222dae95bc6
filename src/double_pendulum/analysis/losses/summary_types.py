"""The ``loss_identification`` summary's shape: what ``summary.json`` holds and :mod:`.report` reads.

TypedDicts, so the summary stays a JSON object; ``tests/test_summary_types.py`` checks the quick run's summary
against :class:`LossesSummary` key by key. Decay rate b [1/s] and exponent p of the energy's decay law, energies
[J], loss shares of the work per mechanism (fractions of the loss), AIC/BIC of the energy fit; parts the report
does not read stay ``dict[str, Any]``.
"""

from typing import Any, NotRequired, TypedDict


class ParameterEntry(TypedDict):
    """A fitted loss parameter: value and standard error in ``unit`` (None where not identified)."""

    value: float
    stderr: float | None
    relative_error: float | None
    unit: str
    description: str
    at_bound: bool


class Identifiability(TypedDict):
    """The top model's parameter correlations, which parameters are identified and their strong partners."""

    parameters: list[str]
    correlation: list[list[float]]
    identified: dict[str, bool]
    strongly_correlated: dict[str, list[str]]


class NoiseModel(TypedDict):
    """The loss fits under AR(1) residuals (:mod:`.noise`): criteria by model (from the AR(1) re-fits where
    ``refitted``, :mod:`.ar1_refit`), the ties (and the ties at the least-squares optimum beside them), the air
    share's range."""

    model: str
    refitted: bool
    criteria: dict[str, dict[str, Any]]
    rho_range: list[float]
    rho_of_lowest_aic: float
    equivalent_factor: float
    common_factor_F: float
    ties: dict[str, list[str]]
    air_share_range: dict[str, Any]
    ties_at_least_squares: NotRequired[dict[str, list[str]]]
    text: str


class ResidualHalves(TypedDict):
    """Mean energy residual [J] of each half of the record and the difference's size against its error."""

    first_half: dict[str, float]
    second_half: dict[str, float]
    difference_J: float
    difference_stderr_J: float
    trend: bool


class Goal(TypedDict):
    """Issue goal: the simulated b and p within 2 % and 2 standard errors of the measured, no trend."""

    b_relative_deviation: float
    b_within_2_percent: bool
    p_deviation_in_stderr: float
    p_within_2_stderr: bool
    no_trend_between_halves: bool
    met: bool


class SupportedModel(TypedDict):
    """A model within ``daic`` of the lowest AIC: its weight, loss shares, simulated b [1/s] and p."""

    delta_aic: float
    akaike_weight: float
    shares: dict[str, float]
    b_sim_per_s: float
    p_sim: float


class SupportedModels(TypedDict):
    """The models the record supports equally (delta AIC < ``daic``)."""

    daic: float
    models: dict[str, SupportedModel]
    n_models: int
    reduced: dict[str, Any]
    air_share_range: list[float]
    text: str


class DragTorqueAgainstSeed(TypedDict):
    """The fitted bearing drag torque [N m] against the seed's rolling friction c_R times the pivot load [N]."""

    c_R: list[float]
    r_b_m: float
    pivot_load_N: float
    torque_N_m: list[float]
    fitted_tau_b_N_m: float
    fitted_over_seed: list[float]


class AirDragAtDefaults(TypedDict):
    """The air drag's work [J] at the FMU's default drag and its share of the measured loss."""

    W_air_J: float
    share_of_measured_loss: float
    cw_rod: float
    W_air_on_measured_decay_J: float
    share_on_measured_decay: float
    measured_decay_model: str
    definitions: str


class ModelRow(TypedDict):
    """One fitted loss model (:func:`.comparison.comparison_rows`): parameters, chi2, AIC/BIC and weights, the
    energy scale kappa, loss shares, simulated b [1/s] and p; the last keys only for unranked or bounded fits."""

    model: str
    model_in_words: str
    parameters: dict[str, ParameterEntry]
    chi2: float
    chi2_red: float
    n_frames: int
    k: int
    aic: float
    bic: float
    delta_aic: float
    delta_bic: float
    akaike_weight: float
    converged: bool
    reduces_to: str | None
    parameter_correlation: list[list[float]] | None
    energy_scale_kappa: float
    shares: dict[str, float]
    b_sim_per_s: float
    p_sim: float
    n_runs: int
    fit_stopped: str
    ar1: dict[str, float] | None
    not_ranked_because: NotRequired[str]
    best_is_limit_model: NotRequired[str]
    best_is_limit_model_in_words: NotRequired[str]
    delta_aic_at_best: NotRequired[float]
    bound: NotRequired[str]


class LossesSummary(TypedDict):
    """``loss_identification``'s ``summary.json``: the fitted models, the top one, what the record supports."""

    scenario: str
    source: str
    pendulum: dict[str, float]
    t0_s: float
    record_s: float
    n_frames: int
    quick: bool
    thorough: bool
    models_fitted: list[str]
    workers: int
    top_model: str
    top_model_means: str
    b_measured_per_s: float
    b_measured_stderr: float
    b_sim_per_s: float
    p_measured: float
    p_measured_stderr: float
    p_sim: float
    top_model_shares: dict[str, float]
    top_model_shares_stderr: dict[str, float]
    parameters: dict[str, ParameterEntry]
    identifiability: Identifiability
    profile_likelihood: dict[str, Any] | None
    energy_scale_kappa: float
    correlation_factor_F: float
    correlation_factor_from: str
    supported_from_factor: dict[str, float | None]
    noise_model: NoiseModel | None
    out_of_sample: dict[str, Any] | None
    air_share_profile: dict[str, Any] | None
    untilted_track: dict[str, Any] | None
    residual_halves: ResidualHalves
    goal: Goal
    measured_loss_J: float
    simulated_loss_J: float
    suspension_verdict: dict[str, Any] | None
    answer: str
    suspension_share_by_model: dict[str, Any]
    suspension_as_main_loss: dict[str, Any] | None
    supported_models: SupportedModels
    b_sim_range_all_models_per_s: list[float]
    load_proportional_friction_against_seed: dict[str, dict[str, Any]]
    drag_torque_against_seed_rolling_friction: DragTorqueAgainstSeed | None
    air_drag_at_defaults: AirDragAtDefaults
    models: list[ModelRow]
    suspension_fixed: dict[str, float]
    omega_reg_rad_per_s: float
    regularisation: dict[str, Any] | None
    null_means: dict[str, str]
    start_state: dict[str, float]
