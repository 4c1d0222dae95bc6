"""The ``cosimulation`` scenario's report.md: orders, stability limit (with its derivation), remedies."""

from __future__ import annotations

import math
from typing import Any

from .coupling_stability import __doc__ as DERIVATION


def _fmt(value: float) -> str:
    return "-" if value is None or (isinstance(value, float) and not math.isfinite(value)) else f"{value:.3g}"


def _orders_table(summary: dict[str, Any]) -> list[str]:
    lines = ["| case / method | angles | pivot | energy | coupling energy |", "|---|---|---|---|---|"]
    for key, value in summary["order_angles"].items():
        lines.append(f"| {key} | {_fmt(value)} | {_fmt(summary['order_pivot'][key])} | "
                     f"{_fmt(summary['order_energy'][key])} | {_fmt(summary['order_coupling_energy'][key])} |")
    return lines


def _remedy_table(rows: list[dict[str, Any]]) -> list[str]:
    lines = ["| case | h [s] | method | angle error [rad] | coupling energy [J] | CPU [s] |",
             "|---|---|---|---|---|---|"]
    for r in sorted(rows, key=lambda r: (r["start"], r["suspension"], r["macro_step_s"], r["method"])):
        if r["macro_step_s"] in (1e-3, 2e-3, 4e-3, 1e-2):
            err = _fmt(r["angle_error_rad"]) if r["stable"] else "unstable"
            lines.append(f"| {r['start']} / {r['suspension']} | {r['macro_step_s']:g} | {r['method']} | {err} | "
                         f"{_fmt(r['coupling_energy_J'])} | {r['cpu_s']:.2f} |")
    return lines


def report_text(summary: dict[str, Any], rows: list[dict[str, Any]]) -> str:
    """Markdown report of one run of the scenario."""
    limit = ["| scheme | h omega | derived mu_c | measured mu_c (between last bounded and first unbounded) |",
             "|---|---|---|---|"]
    for scheme, st in summary["stability"].items():
        for key, mu_c in st["derived_limit"].items():  # keys "h_omega_<value>"
            bracket = st["measured_limit"].get(key)
            measured = f"{bracket[0]:g} - {bracket[1]:g}" if bracket else "-"
            limit.append(f"| {scheme} | {key.removeprefix('h_omega_')} | {_fmt(mu_c)} | {measured} |")
    parts = [
        "# Co-simulation of the pendulum on its suspension",
        "",
        f"Stop time {summary['stop_time_s']} s; reference: the monolithic model (suspension on). "
        "Errors at the stop time. Quick run: " + str(summary["quick"]) + ".",
        "",
        "## Fitted order of convergence (slope of log error over log h, h <= 5 ms)",
        "",
        *_orders_table(summary),
        "",
        "## Remedies against plain zero-order hold (Jacobi)",
        "",
        *_remedy_table(rows),
        "",
        "Cheapest stable run reaching an angle error of 1e-4 rad, per case (the recommendation "
        "follows the numbers):",
        "",
        *[f"- {case}: {b['method']} at h = {b['macro_step_s']:g} s, error {b['angle_error_rad']:.2g} rad, "
          f"{b['cpu_s']:.2f} s CPU" for case, b in summary["cheapest_to_1e-4_rad"].items()],
        "",
        "## Added-mass stability of Jacobi coupling",
        "",
        *limit,
        "",
        "### Derivation",
        "",
        "```text",
        (DERIVATION or "").strip(),
        "```",
        "",
        "Unstable runs (each ended with this message and kept its rows so far):",
        "",
        *[f"- {m}" for m in summary["unstable_runs"]],
        "",
    ]
    return "\n".join(parts)
