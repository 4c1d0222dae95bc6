"""The pytest plugin (entry point ``pytest11``: ``double_pendulum_fmu``): options, marker and fixtures.

Options:

* ``--fmu PATH`` (repeatable): the FMUs the tests that take the ``fmu`` fixture run on, each interface it has (Model
  Exchange, Co-Simulation) one parameter; without it, the project's DoublePendulum.fmu (FMI 2.0, Co-Simulation),
  built when missing or older than the sources (in ``build/`` of the project's folder, elsewhere in pytest's cache
  folder). A path that is not there is a usage error naming it.
* ``--fmu-interface ME|CS`` and ``--fmi-version 2|3``: only those; per test the marker
  ``@pytest.mark.fmu(interface="ME", fmi_version="3")`` says the same. The others are deselected.
* ``--fmu-cases``: collect the files ``*cases*.toml`` in the folders given (a file named on the command line is
  collected without it); ``--regen-references DIR`` makes their cases write their references into DIR,
  ``--fmu-references DIR`` compare with those in DIR.

Fixtures: ``fmu`` (:class:`~.running.Fmu`), ``simulate`` (a run of it through fmpy, a :class:`~.results.Result`),
``reference`` (its own reference result, or the CSV file ``@pytest.mark.fmu_reference(PATH)`` names). Nothing of it
runs, reads or builds an FMU unless a test asks for one of them or a cases file is collected.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

import pytest

from .session import SESSION, TARGETS, WRITTEN, artefact_folder, fmu_session

if TYPE_CHECKING:
    from .results import Result
    from .running import Fmu, FmuTarget

CASES_PATTERN = "*cases*.toml"


def pytest_addoption(parser: pytest.Parser) -> None:
    group = parser.getgroup("fmu", "FMU outputs (double_pendulum.testing, docs/testing.md)")
    group.addoption("--fmu", action="append", default=[], metavar="PATH",
                    help="an FMU file to run the tests that take the fmu fixture on (repeatable; default: the "
                         "project's DoublePendulum.fmu, built when missing or stale)")
    group.addoption("--fmu-interface", choices=("ME", "CS"), default=None,
                    help="test only this interface of the FMUs: ME (Model Exchange) or CS (Co-Simulation)")
    group.addoption("--fmi-version", choices=("2", "3"), default=None, help="test only FMUs of this FMI version")
    group.addoption("--fmu-cases", action="store_true",
                    help=f"collect the cases files ({CASES_PATTERN}) in the folders given, not only those named")
    group.addoption("--regen-references", default=None, metavar="DIR",
                    help="the cases write their references (fmi-ls-ref layout) into DIR instead of comparing")
    group.addoption("--fmu-references", default=None, metavar="DIR",
                    help="the cases compare with the references in DIR (default: the folder their file names)")


def pytest_configure(config: pytest.Config) -> None:
    config.addinivalue_line("markers", "fmu(interface=None, fmi_version=None): run this test only on the FMUs of "
                                       "this interface (ME, CS) and FMI version (2, 3)")
    config.addinivalue_line("markers", "fmu_reference(path): the reference fixture reads this CSV file (relative "
                                       "to the test's file) instead of the FMU's own reference result")
    targets = _targets(config.getoption("fmu"))
    config.stash[TARGETS] = targets
    config.pluginmanager.register(_fixtures(targets), "double_pendulum_fmu_fixtures")


def _targets(paths: list[str]) -> list[FmuTarget]:
    """The targets of the ``--fmu`` paths (every interface of each), else the project's FMU; a usage error names
    a path that is not an FMU file."""
    from .running import PROJECT_TARGET, targets_of

    if not paths:
        return [PROJECT_TARGET]
    targets = []
    for given in paths:
        path = Path(given)
        if not path.is_file():
            why = "a folder, not an FMU file" if path.is_dir() else "no such file"
            raise pytest.UsageError(f"--fmu {given}: {why}")
        if any(target.path == path.resolve() for target in targets):
            raise pytest.UsageError(f"--fmu {given}: given twice")
        try:
            targets += [dataclasses.replace(target, path=path.resolve()) for target in targets_of(path)]
        except ValueError as error:
            raise pytest.UsageError(f"--fmu {error}") from None
    ids = [target.id for target in targets]
    # two files of one name (in two folders): their folder tells them apart in the ids and the references' folders
    return [dataclasses.replace(target, stem=f"{target.path.parent.name}-{target.path.stem}")
            if ids.count(target.id) > 1 and target.path is not None else target for target in targets]


def pytest_sessionfinish(session: pytest.Session) -> None:
    opened = session.config.stash.get(SESSION, None)
    if opened is not None:
        opened.close()


def pytest_terminal_summary(terminalreporter: Any, config: pytest.Config) -> None:
    written = config.stash.get(WRITTEN, [])
    if written:
        terminalreporter.write_line(f"--regen-references wrote {len(written)} reference results in the fmi-ls-ref "
                                    f"layout into {config.getoption('regen_references')}:")
        for path in written:
            terminalreporter.write_line(f"  {path}")


def _major(version: Any) -> str:
    return str(version).split(".")[0]


def selected(config: pytest.Config, target: FmuTarget, marker: pytest.Mark | None) -> bool:
    """Whether ``target`` is one the options and the test's ``fmu`` marker ask for (a marker asking for an
    interface or version there is none of is a usage error)."""
    interfaces = [config.getoption("fmu_interface")]
    versions = [config.getoption("fmi_version")]
    if marker is not None:
        interface, version = marker.kwargs.get("interface"), marker.kwargs.get("fmi_version")
        if interface not in (None, "ME", "CS") or (version is not None and _major(version) not in ("2", "3")):
            raise pytest.UsageError(f"@pytest.mark.fmu(interface={interface!r}, fmi_version={version!r}): the "
                                    "interface is ME or CS, the FMI version 2 or 3")
        interfaces.append(interface)
        versions.append(version)
    return (all(i is None or target.interface == i for i in interfaces)
            and all(v is None or _major(target.fmi_version) == _major(v) for v in versions))


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    from .running import FmuTarget

    keep, drop = [], []
    for item in items:
        callspec = getattr(item, "callspec", None)
        target = callspec.params.get("fmu") if callspec is not None else getattr(item, "fmu_target", None)
        if isinstance(target, FmuTarget) and not selected(config, target, item.get_closest_marker("fmu")):
            drop.append(item)
        else:
            keep.append(item)
    if drop:
        config.hook.pytest_deselected(items=drop)
        items[:] = keep


def pytest_collect_file(file_path: Path, parent: pytest.Collector) -> pytest.Collector | None:
    if file_path.suffix != ".toml" or not file_path.match(CASES_PATTERN):
        return None
    if not (parent.session.isinitpath(file_path) or parent.config.getoption("fmu_cases")):
        return None
    from .cases import CasesFile

    return CasesFile.from_parent(parent, path=file_path)


class Simulate:
    """The ``simulate`` fixture: ``simulate(start_values=..., stop_time=..., output_interval=..., inputs=...,
    outputs=...)`` runs the test's FMU (:meth:`~.running.Fmu.simulate`, kept per argument set for the session);
    ``simulate.like(reference, ...)`` runs the experiment of a reference: its start and stop time, its output
    interval, its columns."""

    def __init__(self, fmu: Fmu, artefacts: Callable[[], Path]) -> None:
        self.fmu = fmu
        self._artefacts = artefacts

    def __repr__(self) -> str:
        return f"<simulate {self.fmu.path.name} {self.fmu.interface}>"

    def __call__(self, **arguments: Any) -> Result:
        __tracebackhide__ = True  # a failed run: pytest shows the test's line
        return self.fmu.simulate(**arguments).for_test(self._artefacts)

    def like(self, reference: Result, **arguments: Any) -> Result:
        __tracebackhide__ = True
        experiment = reference.experiment
        settings = {"start_time": experiment.get("start_time"), "stop_time": float(reference.time[-1]),
                    "output_interval": experiment.get("output_interval"),
                    "outputs": [name for name in reference.names if name in self.fmu.variables]}
        return self(**{**settings, **arguments})


def _fixtures(targets: list[FmuTarget]) -> object:
    """The fixtures, as a plugin object made once the ``--fmu`` options are read: ``fmu`` is parametrised over
    ``targets``. A test module's or conftest's own ``fmu``, ``simulate`` or ``reference`` fixture overrides
    these, as any fixture of a plugin."""

    class FmuFixtures:
        @pytest.fixture(scope="session", params=targets, ids=[t.id for t in targets])
        @classmethod
        def fmu(cls, request: pytest.FixtureRequest) -> Fmu:
            """The FMU under test (each ``--fmu`` file and interface in turn): its model description, variables
            with units and extracted folder (removed when the session ends)."""
            return fmu_session(request.config).open(request.param)

        @pytest.fixture
        def simulate(self, fmu: Fmu, request: pytest.FixtureRequest,
                     tmp_path_factory: pytest.TempPathFactory) -> Simulate:
            """Run the test's FMU through fmpy: a result with named columns and units, kept per argument set."""
            return Simulate(fmu, artefact_folder(tmp_path_factory, request.node.name))

        @pytest.fixture
        def reference(self, fmu: Fmu, request: pytest.FixtureRequest,
                      tmp_path_factory: pytest.TempPathFactory) -> Result:
            """The FMU's own reference result and its experiment, or the CSV ``@pytest.mark.fmu_reference``
            names."""
            from .results import read_csv_result

            artefacts = artefact_folder(tmp_path_factory, request.node.name)
            marker = request.node.get_closest_marker("fmu_reference")
            if marker is None:
                return fmu.reference().for_test(artefacts)
            path = Path(request.node.path).parent / marker.args[0]
            return read_csv_result(path, fmu.units, label=f"reference {marker.args[0]}").for_test(artefacts)

    return FmuFixtures()

