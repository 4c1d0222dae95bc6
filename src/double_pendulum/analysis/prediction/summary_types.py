"""The ``measured_vs_sim`` summary's shape: what ``summary.json`` holds and :mod:`.report` reads.

TypedDicts, so the summary stays a JSON object; ``tests/test_summary_types.py`` checks the quick run's summary
against :class:`PredictionSummary` key by key. Times [s] after t0 = the start frame, distances [m], angles [rad],
rates [rad/s]; a horizon is the first time the lower bob's (or either bob's) position error exceeds a threshold
(2 cm, 5 cm), None where it never does within the prediction.
"""

from typing import Any, NotRequired, TypedDict

from ..losses.summary_types import ParameterEntry


class StartState(TypedDict):
    """A start state (or its standard error, or its change): angles [rad] and rates [rad/s] at t0."""

    phi1_0: float
    phi2_0: float
    omega1_0: float
    omega2_0: float


class StartFit(TypedDict):
    """A least-squares start (:meth:`~..track.start_state.StartStateFit.as_dict`): state, standard errors scaled by
    sqrt(chi2_red), correlation matrix, rms position residual [m]; the geometry keys only where it is fitted
    (``view_rotation`` [rad], ``pivot_offset_x``/``_y`` [m], ``l2`` [m])."""

    t0_s: float
    state: StartState
    stderr: StartState
    geometry: NotRequired[dict[str, float]]
    geometry_stderr: NotRequired[dict[str, float]]
    geometry_units: NotRequired[dict[str, str]]
    parameters: NotRequired[list[str]]
    correlation: list[list[float]]
    chi2: float
    chi2_red: float
    n_frames: int
    rms_residual: float
    n_fmu_runs: int
    change_from_reconstruction: StartState


class Starts(TypedDict):
    """The seed's reconstructed start and the four least-squares starts."""

    seed_reconstruction: StartState
    least_squares: StartFit
    least_squares_geometry: StartFit
    least_squares_fixed_geometry: StartFit
    least_squares_pivot_shift: StartFit


class PredictingModel(TypedDict):
    """The model predicting: rod lengths [m], bob masses [kg], the rods' plates, the fitted losses."""

    lengths_m: dict[str, float]
    bob_masses_kg: float
    rods: dict[str, float]
    loss_model: str
    loss_parameters: dict[str, ParameterEntry]
    loss_fit_record_s: float
    loss_fit_runs: int


class HeadlineHorizon(TypedDict):
    """The lower bob's smoothed 5 cm horizon as a claim (:func:`~.comparison.headline_horizon`): the record's
    length if censored, the largest smoothed error [m] and when [s], the margin below 5 cm [m], the first
    crossing of the per-frame error [s] (None: never)."""

    horizon_s: float
    censored: bool
    smoothed_error_peak_m: float
    smoothed_error_peak_at_s: float
    margin_below_threshold_m: float
    raw_horizon_s: float | None


class Horizons(TypedDict):
    """First times [s] the lower bob's and the worse bob's error exceed 2 cm and 5 cm (None: never)."""

    lower_bob_2cm_s: float | None
    both_bobs_2cm_s: float | None
    lower_bob_5cm_s: float | None
    both_bobs_5cm_s: float | None


class LossModelSensitivity(TypedDict):
    """The main start under each supported loss model: its headline horizons and their ranges [s]."""

    models: dict[str, HeadlineHorizon]
    n_models: int
    smoothed_5cm_range_s: list[float]
    smoothed_censored_models: list[str]
    smoothed_5cm_claim: str
    raw_5cm_range_s: list[float]
    raw_censored_models: list[str]
    raw_5cm_claim: str
    margin_range_m: list[float]
    statement: str


class DampingLevel(TypedDict):
    """The 5 cm horizons [s] at one damping level (every loss coefficient times 1 + ``damping_change``)."""

    damping_change: float
    horizon_s: float
    censored: bool
    raw_horizon_s: float
    raw_censored: bool


class DampingSensitivity(TypedDict):
    """A model's horizons at 1 -+ ``step`` damping and their change [s] per 1 % more damping."""

    levels: dict[str, DampingLevel]
    smoothed_s_per_percent: float
    raw_s_per_percent: float
    slope_is_lower_bound: bool
    step: float


class HorizonStats(TypedDict):
    """Median and 16-84 % range [s] of an ensemble's horizons (:func:`~.loss_uncertainty.horizon_stats`)."""

    median_s: float
    range_16_84_s: list[float]
    n: int
    censored_fraction: float
    median_censored: bool
    top_censored: bool


class HorizonEnsemble(TypedDict):
    """A model's ensemble over the losses' and the start's covariance (``--thorough``)."""

    smoothed_5cm: HorizonStats
    raw_5cm: HorizonStats
    width: float
    members_smoothed_5cm_s: list[float]
    members_raw_5cm_s: list[float]


class LossUncertainty(TypedDict):
    """The horizons' sensitivity to the damping level and, with ``--thorough``, the ensemble."""

    damping_sensitivity: dict[str, DampingSensitivity]
    damping_definition: str
    damping_slope_range_s_per_percent: dict[str, Any] | None
    ensemble: NotRequired[dict[str, HorizonEnsemble]]
    ensemble_definition: NotRequired[str]


class Goal(TypedDict):
    """Issue 12's goal: the lower bob's smoothed error below 5 cm for ``required_s`` [s]."""

    statement: str
    required_s: float
    reached_s: float
    reached_is_lower_bound: bool
    met: bool


class Regime(TypedDict):
    """Regular or chaotic at the fitted start's energy [J]: the largest Lyapunov exponent [1/s] over
    ``averaging_time_s`` [s], its running value at checkpoints and at T/4, the lower rod's flip energy [J]."""

    verdict: str
    largest_lyapunov_exponent_per_s: float
    averaging_time_s: float
    exponent_at_quarter_time_per_s: float
    checkpoints: dict[str, float]
    energy_J: float
    lower_rod_flip_energy_J: float
    energy_over_flip_energy: float
    method: str


class RodLengthFloor(TypedDict):
    """The track's rod-length error |r2 - r1| - l2 [m] over the prediction and its correlation with omega2^2."""

    rms_m: float
    max_m: float
    fraction_above_1cm: float
    correlation_with_omega2_squared: float


class WindowFit(Horizons):
    """The start and geometry fitted to another window (``--thorough``) and its smoothed horizons [s]."""

    fit_frames: int
    fit_window_s: float
    chi2_red: float
    rms_residual_m: float
    geometry: dict[str, float]
    geometry_units: dict[str, str]


class MotionScore(TypedDict):
    """A prediction scored on the half of the record its losses were not fitted to: RMS and median smoothed
    error of the lower bob [m], the 5 cm horizon [s]."""

    fitted_on: str
    predicts: str
    n_frames: int
    rms_error_m: float
    median_smoothed_error_m: float
    horizon_5cm_s: float
    horizon_5cm_censored: bool
    same_as_whole_record: NotRequired[bool]


class MotionDirection(TypedDict):
    """One direction of the out-of-sample test: half-fitted and whole-record scores by model, the ranking."""

    scores: dict[str, MotionScore]
    whole_record_scores: dict[str, MotionScore]
    order: list[str]
    tie: list[str]
    energy_test_best: NotRequired[list[str]]


class MotionOutOfSample(TypedDict):
    """The out-of-sample test of the motion (``--thorough``, :mod:`.out_of_sample`)."""

    split_after_t0_s: float
    tie_within_m: float
    directions: dict[str, MotionDirection]
    text: str


class BudgetRow(TypedDict):
    """One input of :func:`~.horizon_budget.one_at_a_time`: its two values (text), what they are, the horizons [s]
    there and the main run's, and the larger change [s]."""

    input: str
    low: str
    high: str
    kind: str
    low_s: float
    high_s: float
    base_s: float
    largest_change_s: float


class ProfileRow(TypedDict):
    """The start and geometry fitted with one rods' member mass [kg]: chi2, its prediction's horizon [s] and RMS
    error over the whole prediction [m]."""

    member_kg: float
    chi2: float
    chi2_red: float
    rms_residual_m: float
    geometry: dict[str, float]
    horizon_s: float
    censored: bool
    rms_error_m: float


class RodProfile(TypedDict):
    """The profile over the rods' member mass (:func:`~.horizon_budget.rod_profile`)."""

    rows: list[ProfileRow]
    lowest_at: float
    at_edge: bool
    delta_chi2_over_chi2_red: list[float]
    best: float | None
    stderr: float | None
    record_rms_lowest_at_kg: float
    record_rms_best_kg: float | None


class HorizonDistribution(TypedDict):
    """The horizons [s] of the Monte Carlo over every input, their median and ranges (:func:`~.horizon_budget.
    horizon_interval`)."""

    median_s: float
    range_16_84_s: list[float]
    range_2_97_s: list[float]
    width_16_84_s: float
    n: int
    censored_fraction: float
    top_censored: bool
    range_16_84_claim: str
    members_s: list[float]


class HorizonBudget(TypedDict):
    """The horizon over every uncertain input (:mod:`.horizon_budget`)."""

    main_horizon_s: float
    span_s: float
    one_at_a_time: list[BudgetRow]
    rod_profile: RodProfile | None
    rods_stderr_kg: float | None
    rods_stderr_from: str | None
    l1_stderr_m: float
    distribution: HorizonDistribution
    inputs_drawn: list[str]
    dominant_input: str | None
    statement: str
    null_means: dict[str, str]


class PredictionSummary(TypedDict):
    """``measured_vs_sim``'s ``summary.json``: the runs from t0, their horizons, the floors, the regime."""

    scenario: str
    source: str
    record: NotRequired[dict[str, Any]]
    lengths_fitted_m: NotRequired[dict[str, float]]
    quick: bool
    thorough: bool
    t0_s: float
    start_frame: int
    prediction_s: float
    pivot_origin_m: dict[str, float]
    model: PredictingModel
    starts: Starts
    horizon_5cm_s: float
    horizon_5cm_censored: bool
    horizon_5cm_s_fixed_geometry: float
    horizon_5cm_censored_fixed_geometry: bool
    horizon_5cm_s_pivot_shift: float
    horizon_5cm_censored_pivot_shift: bool
    horizon_5cm_details: dict[str, HeadlineHorizon]
    horizon_statement: str
    smoothing: dict[str, Any]
    horizons_smoothed_s: dict[str, Horizons]
    horizons_raw_s: dict[str, Horizons]
    loss_model_sensitivity: LossModelSensitivity
    loss_uncertainty: LossUncertainty
    horizon_budget: HorizonBudget
    goal: Goal
    regime: Regime
    chaos_horizons_s: dict[str, float | None]
    ensemble_size: int
    track_rod_length_floor: RodLengthFloor
    rms_error_first_second_m: dict[str, dict[str, float]]
    null_means: dict[str, str]
    fit_window_sensitivity: NotRequired[list[WindowFit]]
    out_of_sample_motion: NotRequired[MotionOutOfSample]
    wall_time_s: float
