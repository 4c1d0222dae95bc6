"""The commands that print: ``double-pendulum list`` (the scenarios) and ``double-pendulum variables`` (the FMU's
variables as a Markdown table)."""

from __future__ import annotations

import argparse

from .catalogue import scenario_listing


def cmd_list(args: argparse.Namespace) -> int:
    print(scenario_listing())
    return 0


def cmd_variables(args: argparse.Namespace) -> int:
    """Print the FMU's variables as the Markdown table in docs/fmu.md."""
    from ..component.variables import fmu_variables

    print("| name | causality | type | unit | start | description |")
    print("|---|---|---|---|---|---|")
    for v in fmu_variables():
        text = v.description.rsplit(" [", 1)[0] if v.unit else v.description
        start = "" if v.start is None else v.start
        print(f"| `{v.name}` | {v.causality} | {v.fmi_type} | {v.unit or '-'} | {start} | {text} |")
    return 0


def add_list_parser(sub: argparse._SubParsersAction) -> None:
    """``list``, which takes no options."""
    p_list = sub.add_parser("list", help="list the scenarios", description="List the scenarios.")
    p_list.set_defaults(func=cmd_list)


def add_variables_parser(sub: argparse._SubParsersAction) -> None:
    """``variables``, which takes no options."""
    p_vars = sub.add_parser("variables", help="print the FMU's variables (Markdown table)",
                            description="Print the FMU's variables as a Markdown table.")
    p_vars.set_defaults(func=cmd_variables)
