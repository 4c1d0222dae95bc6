"""The ``cosimulation`` scenario's report.md: orders, stability limit (with its derivation), remedies."""

from __future__ import annotations

import math
from typing import Any

from ...runs.results_io import report_opening
from .stability import __doc__ as DERIVATION
from .summary_types import CouplingSummary


def _fmt(value: float) -> str:
    return "-" if value is None or (isinstance(value, float) and not math.isfinite(value)) else f"{value:.3g}"


def _orders_table(summary: CouplingSummary) -> list[str]:
    """Fitted orders per case and method; an order whose errors follow no power of h is marked "(no order)"."""
    unresolved = summary["orders_unresolved"]

    def cell(quantity: str, order_key: str, key: str) -> str:
        value = _fmt(summary[order_key][key])
        return f"{value} (no order)" if key in unresolved.get(quantity, []) and value != "-" else value

    lines = ["| case / method | angles | pivot | energy | coupling energy |", "|---|---|---|---|---|"]
    for key in summary["order_angles"]:
        lines.append(f"| {key} | {cell('angle', 'order_angles', key)} | {cell('pivot', 'order_pivot', key)} | "
                     f"{cell('energy', 'order_energy', key)} | {_fmt(summary['order_coupling_energy'][key])} |")
    return lines


def _order_note(summary: CouplingSummary) -> list[str]:
    """What the orders mean: the iterative scheme's order is the angles'; the range of its other slopes."""
    iterative = [k for k in summary["order_angles"] if k.endswith("/ iterative")]
    angles = [summary["order_angles"][k] for k in iterative if summary["order_angles"][k] is not None]
    others = [summary[q][k] for q in ("order_pivot", "order_energy") for k in iterative
              if summary[q][k] is not None and math.isfinite(summary[q][k])]
    text = (f"(no order): {summary['orders_unresolved_means']}. A negative slope (the error growing as h shrinks"
            " over the steps tried) is no order of convergence either; the coupling-energy column is fitted like the"
            " others but not checked for linearity.")
    if angles and others:
        text += (f" The iterative scheme's second order is its angles' ({min(angles):.2f} to {max(angles):.2f}):"
                 f" its pivot and energy slopes range from {min(others):.2f} to {max(others):.2f} and are not the"
                 " scheme's order. Those errors are small (pivot 1e-8 to 1e-5 m) and do not fall steadily with h;"
                 " the cause was not isolated: candidates are the fixed point's tolerance (relative 1e-8 a step),"
                 " the monolithic reference's own error, and an error taken at one instant passing through zero"
                 " between two macro steps.")
    return [text]


def _damping_lines(summary: CouplingSummary) -> list[str]:
    """The derived limit at other damping ratios (``derived_limit_by_damping``), where the map has none."""
    lines = []
    for scheme, st in summary["stability"].items():
        table = st.get("derived_limit_by_damping")
        if not table:
            continue
        keys = list(next(iter(table.values())))
        if not lines:
            lines = ["Derived limit at other damping ratios zeta of the suspension (no map runs):", "",
                     "| scheme | zeta | " + " | ".join(f"h omega {k.removeprefix('h_omega_')}" for k in keys) + " |",
                     "|---|---|" + "---|" * len(keys)]
        for zeta, row in table.items():
            cells = " | ".join(_fmt(row[k]) for k in keys)
            lines.append(f"| {scheme} | {zeta.removeprefix('zeta_')} | {cells} |")
    return [*lines, ""] if lines else []


def _opening(summary: CouplingSummary) -> str:
    """Title, plain summary and the words used."""
    cheapest = summary["cheapest_to_1e-4_rad"]
    methods = sorted({b["method"] for b in cheapest.values()})
    jacobi = [v for k, v in summary["order_angles"].items() if k.endswith("/ jacobi") and v is not None]
    holds = all(st["brackets_hold_derived_limit"] for st in summary["stability"].values())
    quick = " (quick run)" if summary["quick"] else ""
    return report_opening(f"Co-simulation of the pendulum on its suspension{quick}", [
        "The pendulum on its springy pivot was split into two FMUs, the pendulum and the suspension, coupled by "
        "several co-simulation masters, and each run was compared with the one FMU that integrates both together "
        f"(errors at {summary['stop_time_s']:g} s after a regular and a chaotic start).",
        "Plain exchange of values once per macro step (Jacobi, what libcosim and fmpy's container FMU do) has an "
        + (f"error proportional to the step (fitted orders {min(jacobi):.3f} to {max(jacobi):.3f})" if jacobi else
           "error that falls with the step") + " and creates or destroys a little energy.",
        "Repeating each step with the FMUs' saved and restored states until the exchanged values agree (the "
        "iterative master) is second order, and "
        + (f"{'it' if methods == ['iterative'] else ', '.join(methods)} was the cheapest way to an angle error of "
           f"1e-4 rad in every case run." if cheapest else "no run reached an angle error of 1e-4 rad."),
        "A suspension much lighter than the pendulum makes plain exchange blow up: the measured stability limits "
        + ("agree with the derived ones" if holds else "do NOT all agree with the derived ones")
        + " (the report's stability section); the CPU times are from a shared machine and rank only runs that "
        "differ clearly.",
    ], {
        "macro step h": "the interval at which the master exchanges values between the FMUs",
        "monolithic": "the pendulum and its suspension integrated as one system in one FMU: the reference",
        "Jacobi": "both FMUs step side by side with their inputs held over the step, then exchange outputs "
                  "(jacobi: read both, then write both; jacobi_sequential: the force passed first, as the container "
                  "does)",
        "order of convergence": "the slope of log error over log h: 1 means halving h halves the error, 2 quarters it",
        "mass ratio mu": "(m1 + m2) / M_s, the pendulum's mass over the suspension's",
        "spectral radius": "the largest size of the eigenvalues of the map from one step's exchanged values to the "
                           "next: above 1 the run grows without bound",
        "zero-order hold": "an input held constant over the macro step",
    })


def _run_kind(summary: CouplingSummary) -> str:
    """Which run this is, in words."""
    if summary["quick"]:
        return ("This is a quick run: a smoke test with a short stop time and few step sizes, whose numbers are not"
                " the default run's.")
    return "This is the default run."


def _remedy_table(rows: list[dict[str, Any]]) -> list[str]:
    lines = ["| case | h [s] | method | angle error [rad] | coupling energy [J] | CPU [s] |",
             "|---|---|---|---|---|---|"]
    for r in sorted(rows, key=lambda r: (r["start"], r["suspension"], r["macro_step_s"], r["method"])):
        if r["macro_step_s"] in (1e-3, 2e-3, 4e-3, 1e-2):
            err = _fmt(r["angle_error_rad"]) if r["stable"] else "unstable"
            lines.append(f"| {r['start']} / {r['suspension']} | {r['macro_step_s']:g} | {r['method']} | {err} | "
                         f"{_fmt(r['coupling_energy_J'])} | {r['cpu_s']:.2f} |")
    return lines


def report_text(summary: CouplingSummary, rows: list[dict[str, Any]]) -> str:
    """Markdown report of one run of the scenario."""
    limit = ["| scheme | h omega | derived mu_c | measured mu_c (between the last stable and the first unstable run) |",
             "|---|---|---|---|"]
    for scheme, st in summary["stability"].items():
        for key, mu_c in st["derived_limit"].items():  # keys "h_omega_<value>"
            bracket = st["measured_limit"].get(key)
            measured = f"{bracket[0]:g} - {bracket[1]:g}" if bracket else "-"
            limit.append(f"| {scheme} | {key.removeprefix('h_omega_')} | {_fmt(mu_c)} | {measured} |")
    parts = [
        _opening(summary).rstrip("\n"),
        "",
        f"Stop time {summary['stop_time_s']} s; reference: the monolithic model (suspension on). "
        f"Errors at the stop time. {_run_kind(summary)}",
        "",
        "## Fitted order of convergence (slope of log error over log h, h <= 5 ms)",
        "",
        *_orders_table(summary),
        "",
        *_order_note(summary),
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
        "Each map point runs the split system with the pendulum hanging straight, set moving by a 1 % step of"
        " the suspension's static load; its stability is the spectral radius of the step map fitted to the run"
        " (least squares X_{n+1} = G X_n + b on the exchanged values, X as in the derivation below), stable if"
        " at most 1 + 1e-6. Not a run that merely has not blown up yet: one growing by 4 % a step passes a"
        " tenfold test over 60 steps.",
        "",
        *limit,
        "",
        *_damping_lines(summary),
        *[f"- {scheme}: largest |fitted - derived| spectral radius"
          f" {_fmt(st['max_abs_fitted_minus_derived_spectral_radius'])}; every measured bracket holds the derived"
          f" limit: {st['brackets_hold_derived_limit']}; runs too short to fit: {st['points_too_short_to_fit']}"
          for scheme, st in summary["stability"].items()],
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
