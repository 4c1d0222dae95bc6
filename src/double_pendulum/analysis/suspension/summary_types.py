"""The ``suspension_transfer`` summary's shape: what ``summary.json`` holds and :mod:`.report` reads.

TypedDicts, so the summary stays a JSON object; ``tests/test_summary_types.py`` checks the quick run's summary
against :class:`SuspensionSummary` key by key. Suspension stiffness k [N/m], damping c [N s/m], mass M_s [kg],
decay rates b [1/s] of the pendulum's energy; the nested parts the report reads by their own keys stay
``dict[str, Any]``.
"""

from typing import Any, NotRequired, TypedDict


class Refit(TypedDict):
    """The measured decay refitted with the suspension identified: b of the pendulum's and of the total energy
    [1/s] against the measured, the exponent p, chi2."""

    b_E_pendulum_per_s: float
    b_E_total_per_s: float
    relative_difference_to_measured: float
    difference_in_measured_sigma: float
    difference_in_total_sigma: float
    p: float
    chi2: float
    delta_chi2: float


class IsoPoint(TypedDict):
    """A point (k [N/m], c [N s/m]) of a line of equal decay rate and the branch it lies on."""

    k: float
    c: float
    branch: str


class DecayMap(TypedDict):
    """The decay-rate map over (k, c) at one suspension mass M_s (:mod:`.decay_map`)."""

    M_s_kg: float
    k_N_per_m: list[float]
    c_N_s_per_m: list[float]
    b_base_no_suspension_per_s: float
    b_E_pendulum: list[list[float]]
    max_abs_b_E_pendulum_minus_b_E_total: float
    iso_b_measured: list[IsoPoint]
    iso_b_seed: list[IsoPoint]
    reach_measured_b: dict[str, Any]
    monotonic_in_c: dict[str, Any]
    linear_response: dict[str, Any]
    stiff_region: dict[str, Any]
    quasi_static_c_over_k2: dict[str, Any]


class SuspensionSummary(TypedDict):
    """``suspension_transfer``'s ``summary.json``: the measured decay, the identified suspension, the maps, the
    energy flow."""

    scenario: str
    quick: bool
    thorough: bool
    energy_fitted: str
    settings: dict[str, Any]
    measured: dict[str, Any]
    start_state: dict[str, Any]
    identified: dict[str, Any]
    refit: dict[str, Refit]
    valley: dict[str, Any]
    window_checks: list[Any]
    spectrum: dict[str, Any]
    maps: list[DecayMap]
    energy_flow: dict[str, Any]
    map_runs: int
    null_means: dict[str, Any]
    map_wall_time_s: NotRequired[float]
    wall_time_s: NotRequired[float]
