"""The scenarios by name: each one's description, read from its source without importing it, the listing that
``list`` and ``run --help`` print, and the names a command line gives checked."""

from __future__ import annotations

import ast
import importlib.util
from pathlib import Path

from ..scenarios import SCENARIOS
from .common import CliError


def scenario_description(name: str) -> str:
    """The scenario's one-line ``DESCRIPTION``, read from its source without importing it (fast)."""
    spec = importlib.util.find_spec(f"double_pendulum.scenarios.{name}")
    tree = ast.parse(Path(spec.origin).read_text(encoding="utf-8"))
    for node in tree.body:
        if isinstance(node, ast.Assign) and any(getattr(t, "id", None) == "DESCRIPTION" for t in node.targets):
            return ast.literal_eval(node.value)
    return ""


def scenario_listing() -> str:
    """One line per scenario: name and description."""
    return "\n".join(f"  {name:22s} {scenario_description(name)}" for name in SCENARIOS)


def check_scenarios(names: list[str]) -> tuple[str, ...]:
    """The scenarios the command line names (``all``: every one), each once, in the order given."""
    if "all" in names:
        if len(names) > 1:
            raise CliError("'all' runs every scenario: give it alone, not with other scenario names")
        return SCENARIOS
    for name in names:
        if name not in SCENARIOS:
            raise CliError(f"unknown scenario {name!r}; choose one of: {', '.join(SCENARIOS)} (or 'all')")
    return tuple(dict.fromkeys(names))
