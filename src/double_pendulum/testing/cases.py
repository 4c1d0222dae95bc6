"""Cases as data: a TOML file of cases becomes one test item per case and FMU (``<case>[<FMU id>]``).

The file (``*cases*.toml``; ``examples/cases.toml`` is one)::

    references = "references"      # folder of the cases' references, relative to this file

    [defaults]                     # what every case takes unless it says otherwise (all optional)
    stop_time = 4.0                # [s]
    output_interval = 0.01         # [s]
    tolerance = { time = 0.01, rtol = 0.01 }   # the tube (double_pendulum.testing.tube.Tolerance)

    [cases.small_swing]
    start_values = { phi1_0 = 0.1, phi2_0 = 0.1 }
    compare = ["phi1", "phi2"]     # the variables compared with the reference, in the tube
    tolerances = { phi2 = { atol = 0.002 } }   # per variable, over the case's tolerance
    checks = ["energy_budget"]     # physics: energy_budget, energy_never_rises, conserved (E_total)

Each case runs the FMU and compares the variables of ``compare`` with the case's reference,
``<references>/<case>/<FMU id>/extra/org.fmi-standard.fmi-ls-ref/`` (the layout an FMU carries; ``<references>``:
``--fmu-references DIR``, else the file's ``references``). With
``--regen-references DIR`` it writes that reference into ``DIR`` instead (the folder the user names; nothing else
is written) and passes, saying where.
"""

from __future__ import annotations

import dataclasses
import tomllib
from collections.abc import Iterator, Mapping
from pathlib import Path
from typing import Any

import pytest

from .running import FmuTarget
from .session import TARGETS, WRITTEN, artefact_folder, fmu_session

CASE_KEYS = {"start_values", "stop_time", "output_interval", "compare", "tolerance", "tolerances", "checks"}
FILE_KEYS = {"references", "defaults", "cases"}
CHECKS = ("energy_budget", "energy_never_rises", "conserved")


class CaseError(Exception):
    """A cases file that cannot be read as cases; the message names the file, the case and the key."""


@dataclasses.dataclass(frozen=True)
class Case:
    """One case of a cases file, its defaults applied."""

    name: str
    start_values: Mapping[str, Any]
    stop_time: float | None
    output_interval: float | None
    compare: tuple[str, ...]
    tolerance: Mapping[str, float]
    tolerances: Mapping[str, Mapping[str, float]]
    checks: tuple[str, ...]


def read_cases(path: Path) -> tuple[Path | None, list[Case]]:
    """The references folder (``None`` where the file names none) and the cases of the file ``path``;
    :class:`CaseError` naming what is wrong."""
    try:
        content = tomllib.loads(path.read_text(encoding="utf-8"))
    except tomllib.TOMLDecodeError as error:
        raise CaseError(f"{path}: not TOML: {error}") from None
    unknown = sorted(set(content) - FILE_KEYS)
    if unknown:
        raise CaseError(f"{path}: unknown key {', '.join(unknown)} (known: {', '.join(sorted(FILE_KEYS))})")
    defaults = content.get("defaults", {})
    cases = content.get("cases", {})
    if not isinstance(cases, dict) or not cases:
        raise CaseError(f"{path}: no cases (a table [cases.NAME] each)")
    out = []
    for name, given in cases.items():
        for where, table in (("[defaults]", defaults), (f"case {name!r}", given)):
            wrong = sorted(set(table) - CASE_KEYS) if isinstance(table, dict) else ["(not a table)"]
            if wrong:
                raise CaseError(f"{path}, {where}: unknown key {', '.join(wrong)} (known: "
                                f"{', '.join(sorted(CASE_KEYS))})")
        case = {**defaults, **given}
        checks = tuple(case.get("checks", ()))
        bad = [check for check in checks if check not in CHECKS]
        if bad:
            raise CaseError(f"{path}, case {name!r}: unknown check {', '.join(bad)} (known: {', '.join(CHECKS)})")
        if not case.get("compare") and not checks:
            raise CaseError(f"{path}, case {name!r}: nothing to test (give compare = [names] or checks)")
        out.append(Case(name, dict(case.get("start_values", {})), case.get("stop_time"), case.get("output_interval"),
                        tuple(case.get("compare", ())), dict(case.get("tolerance", {})),
                        dict(case.get("tolerances", {})), checks))
    references = content.get("references")
    return (path.parent / references if references is not None else None), out


class CasesFile(pytest.File):
    """A cases file: one :class:`CaseItem` per case and FMU target."""

    def collect(self) -> Iterator[pytest.Item]:
        try:
            references, cases = read_cases(self.path)
        except CaseError as error:
            raise self.CollectError(str(error)) from None
        given = self.config.getoption("fmu_references")
        references = Path(given) if given is not None else references
        for case in cases:
            for target in self.config.stash[TARGETS]:
                yield CaseItem.from_parent(self, name=f"{case.name}[{target.id}]", case=case, target=target,
                                           references=references)


class CaseItem(pytest.Item):
    """One case on one FMU: run it, compare it with its reference (or write the reference), check its physics."""

    def __init__(self, *, case: Case, target: FmuTarget, references: Path | None, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self.case, self.fmu_target, self.references = case, target, references

    def reference_folder(self, root: Path) -> Path:
        return root / self.case.name / self.fmu_target.id

    def runtest(self) -> None:
        from . import physics
        from .results import MissingReference, reference_in_folder, write_reference
        from .tube import assert_matches_reference

        case = self.case
        fmu = fmu_session(self.config).open(self.fmu_target)
        needs = {"energy_budget": physics.ENERGY_COLUMNS, "energy_never_rises": ("E_total", "W_input"),
                 "conserved": ("E_total",)}
        outputs = list(dict.fromkeys([*case.compare, *(n for check in case.checks for n in needs[check])]))
        factory = getattr(self.config, "_tmp_path_factory", None)  # pytest's own, as its tmp_path fixture uses
        artefacts = artefact_folder(factory, self.name) if factory is not None else None
        result = fmu.simulate(case.start_values, case.stop_time, case.output_interval, outputs=outputs)
        result = result.for_test(artefacts)
        regen = self.config.getoption("regen_references")
        if regen is not None and case.compare:
            columns = result.data[["time", *case.compare]]
            values = ", ".join(f"{k} = {v!r}" for k, v in case.start_values.items()) or "its defaults"
            written = write_reference(
                dataclasses.replace(result, data=columns), self.reference_folder(Path(regen)), fmu.name,
                f"case {case.name} of {self.path.name}: {values}, to {result.time[-1]:g} s every "
                f"{result.experiment['output_interval']:g} s (written by pytest --regen-references)")
            self.user_properties.append(("reference", str(written)))
            self.config.stash.setdefault(WRITTEN, []).append(written)
        elif case.compare:
            if self.references is None:
                raise CaseError(f"{self.path.name} names no references folder (references = \"DIR\"); write them "
                                f"with pytest {self.path.name} --regen-references=DIR")
            folder = self.reference_folder(self.references)
            try:
                reference = reference_in_folder(folder, fmu.units, label=f"reference of {case.name}")
            except MissingReference as error:
                raise CaseError(f"{error}; write it with pytest {self.path.name} --regen-references="
                                f"{self.references}") from None
            assert_matches_reference(result, reference, case.compare, **case.tolerance, tolerances=case.tolerances)
        if "energy_budget" in case.checks:
            physics.assert_energy_budget_closes(result)
        if "energy_never_rises" in case.checks:
            physics.assert_energy_never_rises(result)
        if "conserved" in case.checks:
            physics.assert_conserved(result, "E_total")

    def repr_failure(self, excinfo: pytest.ExceptionInfo[BaseException], style: Any = None) -> str:
        if isinstance(excinfo.value, AssertionError | CaseError):
            return str(excinfo.value)
        return str(super().repr_failure(excinfo))

    def reportinfo(self) -> tuple[Path, int, str]:
        return self.path, 0, f"case {self.case.name} on {self.fmu_target.id}"
