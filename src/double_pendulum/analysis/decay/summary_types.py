"""The ``energy_decay`` summary's shape: what ``summary.json`` holds and :mod:`.report` reads.

TypedDicts, so the summary stays a JSON object; ``tests/test_summary_types.py`` checks the quick run's summary
against :class:`DecaySummary` key by key. The exponential fit E = a exp(b t): a [J], b [1/s]; lengths [m];
the nested tables the report reads by their own keys stay ``dict[str, Any]``.
"""

from typing import Any, TypedDict


class ModelFit(TypedDict):
    """One decay law fitted to the energy (:func:`.fit.fit_model`): parameters with standard errors and units,
    chi2, AIC/BIC and the Akaike weight."""

    model: str
    params: dict[str, Any]
    stderr: dict[str, Any]
    units: dict[str, Any]
    n: int
    k: int
    chi2: float
    chi2_red: float
    absolute_sigma: bool
    aic: float
    bic: float
    delta_aic: float
    delta_bic: float
    akaike_weight: float


class DecaySummary(TypedDict):
    """``energy_decay``'s ``summary.json``: the record's geometry, the exponential fit, the other laws and
    weightings, the seed's fit, the error budget of b."""

    scenario: str
    source: str
    n_frames: int
    n_flagged: int
    release_frame: int
    release_time_s: float
    n_fit: int
    masses_kg: dict[str, Any]
    pivot_origin_m: dict[str, Any]
    l1_m: float
    l1_stderr_m: float
    circle_rms_residual_m: float
    l2_m: float
    l2_stderr_m: float
    l2_std_m: float
    position_noise_m: dict[str, Any]
    r1_drift_m_per_s: float
    derivative_filters: dict[str, Any]
    error_model: dict[str, Any]
    scatter: dict[str, Any]
    a_J: float
    a_J_stderr: float
    b_per_s: float
    b_per_s_stderr: float
    autocorrelation_factor: float
    a_J_stderr_autocorr: float
    b_per_s_stderr_autocorr: float
    chi2_red: float
    n_points: int
    model_comparison: list[ModelFit]
    weighting_variants: dict[str, Any]
    seed: dict[str, Any]
    null_means: dict[str, Any]
    error_budget: dict[str, Any]
    tilt: dict[str, Any]
    quick: bool
