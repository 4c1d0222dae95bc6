"""The ``chaos`` summary's shape: what ``summary.json`` holds and :mod:`.in_short` reads.

TypedDicts, so the summary stays a JSON object; ``tests/test_summary_types.py`` checks the quick run's summary
against :class:`ChaosSummary` key by key. Exponents [1/s], times [s], distances [m], energies [J]; the nested
parts nothing reads by key stay ``dict[str, Any]``.
"""

from typing import Any, TypedDict


class DefaultStart(TypedDict):
    """The seed's start: angles [rad], rates [rad/s]."""

    phi1_0: float
    phi2_0: float
    omega1_0: float
    omega2_0: float


class StepHalving(TypedDict):
    """The exponent [1/s] at one step size against the DOP853 cloud's."""

    default_start: float
    cloud_mean: float
    cloud_sem: float
    relative_to_dop853_cloud_mean: float
    wall_time_s: float


class Lyapunov(TypedDict):
    """The largest Lyapunov exponent [1/s]: the cloud's mean and standard error, its checks."""

    lyapunov_per_s: float
    lyapunov_sem_per_s: float
    method: str
    default_start_alone_per_s: float
    convergence_default_start: dict[str, Any]
    convergence_cloud_mean: dict[str, Any]
    step_halving: dict[str, StepHalving]
    cloud_members: int
    two_trajectory_rk4_default_start: float
    two_trajectory_rk4_cloud_mean: float
    spectrum: dict[str, Any]
    energy_scan: dict[str, Any]
    with_friction: dict[str, Any]


class FmuRuns(TypedDict):
    """The hand-release runs through the FMU and when their lower bobs part by 1 cm [s] (None: never)."""

    releases: dict[str, Any]
    settings: dict[str, Any]
    stop_time_s: float
    releases_part_by_1cm_at_s: float | None
    wall_time_s: float


class Predictability(TypedDict):
    """Ensembles of releases within sigma [m]: when their spread exceeds 1 cm and 10 cm [s] (None: never)."""

    members_per_ensemble: int
    sigmas_m: list[float]
    horizon_1cm_s: list[float | None]
    horizon_10cm_s: list[float | None]
    horizon_1cm_at_5mm_s: float | None
    horizon_10cm_at_5mm_s: float | None
    horizon_slope_per_ln_sigma_s: dict[str, float]
    one_over_lyapunov_s: float
    wall_time_s: float
    null_means: dict[str, Any]


class FlipMap(TypedDict):
    """The map of start angles from which a rod flips within t_max_s [s], against the energy bound [J]."""

    grid: list[int]
    t_max_s: float
    rk4_step_s: float
    wall_time_s: float
    workers: int
    fraction_flipped: float
    energy_bound: str
    E_flip_rod1_J: float
    E_flip_rod2_J: float
    starts_below_bound: int
    bound_violations: int


class PoincareSection(TypedDict):
    """A Poincare section at one energy [J]: starts and points."""

    energy_J: float
    starts: int
    points: int
    start_energy_relative_error: float


class ChaosSummary(TypedDict):
    """``chaos``'s ``summary.json``: exponents, releases, predictability, flips, sections; ``in_short`` is
    written from it (:func:`.in_short.in_short`)."""

    scenario: str
    quick: bool
    thorough: bool
    default_start: DefaultStart
    start_uncertainty_m: float
    lyapunov_per_s: float
    lyapunov: Lyapunov
    fmu_runs: FmuRuns
    fmu_vs_batch_dop853_max_angle_difference_rad_first_2s: float
    predictability: Predictability
    flip_map: FlipMap
    poincare: dict[str, PoincareSection]
    precision: dict[str, Any]
    in_short: str
    wall_time_s: float
