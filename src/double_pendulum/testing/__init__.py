"""pytest on FMU outputs: a pytest plugin, its fixtures and assertions, for anyone who tests an FMU (docs/testing.md).

Installing the package registers the plugin (:mod:`.plugin`, the ``pytest11`` entry point ``double_pendulum_fmu``);
it stays out of the way of a test suite that asks for none of its fixtures. Its parts:

* :mod:`.running` -- the FMUs a session tests (``--fmu PATH``, else the project's DoublePendulum.fmu) and their
  runs through fmpy, kept per argument set;
* :mod:`.results` -- results and references as named columns with units, the ``fmi-ls-ref`` layout read and written;
* :mod:`.tube` -- :func:`assert_matches_reference`, the tube comparison of fmpy's ``validate_signal``;
* :mod:`.physics` -- the pendulum's energy budget, energy loss, conserved quantities and normal modes;
* :mod:`.cases` -- cases as data: a TOML file, one test item per case and FMU.

Importing the package is cheap (the names below are loaded when first used): pytest imports the plugin in every
session.
"""

from __future__ import annotations

import importlib
from typing import Any

_EXPORTS = {
    "Result": "results", "read_csv_result": "results", "MissingReference": "results",
    "Tolerance": "tube", "assert_matches_reference": "tube",
    "ENERGY_COLUMNS": "physics", "assert_energy_budget_closes": "physics", "assert_energy_never_rises": "physics",
    "assert_conserved": "physics", "assert_normal_mode_periods": "physics", "normal_mode_start": "physics",
    "pendulum_parameters": "physics",
    "SimulationFailed": "running",
}

__all__ = sorted(_EXPORTS)


def __getattr__(name: str) -> Any:
    if name not in _EXPORTS:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(importlib.import_module(f".{_EXPORTS[name]}", __name__), name)
