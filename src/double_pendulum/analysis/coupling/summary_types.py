"""The ``cosimulation`` summary's shape: what ``summary.json`` holds and :mod:`.report` reads.

TypedDicts, so the summary stays a JSON object; ``tests/test_summary_types.py`` checks the quick run's summary
against :data:`CouplingSummary` key by key. Fitted orders of convergence (slope of log error over log macro step
h, None where not fitted), errors at the stop time [s], CPU times [s].
"""

from typing import Any, NotRequired, TypedDict


class CheapestRun(TypedDict):
    """The cheapest stable run of a case reaching an angle error of 1e-4 rad: method, macro step [s], error [rad],
    CPU time [s]."""

    method: str
    macro_step_s: float
    angle_error_rad: float
    cpu_s: float


CouplingSummary = TypedDict(
    "CouplingSummary",
    {
        "scenario": str,
        "quick": bool,
        "stop_time_s": float,
        "workers": int,
        "skipped_methods": dict[str, Any],
        "order_angles": dict[str, float | None],
        "order_pivot": dict[str, float | None],
        "order_energy": dict[str, float | None],
        "order_coupling_energy": dict[str, float | None],
        "orders_unresolved": dict[str, Any],
        "orders_unresolved_means": str,
        "cheapest_to_1e-4_rad": dict[str, CheapestRun],
        "unstable_runs": list[str],
        "stability": dict[str, Any],
        "cpu_s_by_method": NotRequired[dict[str, Any]],
        "wall_s": NotRequired[float],
    },
)
"""``cosimulation``'s ``summary.json``: orders by case and method, the cheapest runs, the stability limits by
scheme (a key with a '-' in it: the functional form)."""
